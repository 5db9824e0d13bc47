//! Closed intervals of real values: the domain of analyse's range analysis and of each
//! builtin's range rule. A module of its own so that the builtins (which state range rules)
//! and the IR (which prints ranges) both depend on it, and not on each other.

use std::fmt;

/// A closed interval of real values; infinite ends mean unbounded.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interval {
    pub lo: f64,
    pub hi: f64,
}

impl fmt::Display for Interval {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "[{}, {}]", short(self.lo), short(self.hi))
    }
}

/// A number in at most 4 significant digits.
pub fn short(v: f64) -> String {
    if v.is_infinite() {
        return if v > 0.0 { "inf".into() } else { "-inf".into() };
    }
    if v == 0.0 {
        return "0".into();
    }
    let a = v.abs();
    if (1e-3..1e5).contains(&a) {
        let s = format!("{v:.4}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        s.to_string()
    } else {
        format!("{v:.3e}")
    }
}

impl Interval {
    pub fn point(v: f64) -> Interval {
        Interval { lo: v, hi: v }
    }

    pub const UNBOUNDED: Interval = Interval {
        lo: f64::NEG_INFINITY,
        hi: f64::INFINITY,
    };
    pub const UNIT: Interval = Interval { lo: 0.0, hi: 1.0 };
    /// Every u32 value.
    pub const U32: Interval = Interval {
        lo: 0.0,
        hi: u32::MAX as f64,
    };
    /// Every i32 value.
    pub const I32: Interval = Interval {
        lo: i32::MIN as f64,
        hi: i32::MAX as f64,
    };

    /// The part of `self` inside `other` (`other` where they do not overlap: a value of
    /// the type lies in it whatever `self` said).
    pub(crate) fn meet(self, other: Interval) -> Interval {
        let (lo, hi) = (self.lo.max(other.lo), self.hi.min(other.hi));
        if lo <= hi { Interval { lo, hi } } else { other }
    }

    pub(crate) fn hull(a: Interval, b: Interval) -> Interval {
        Interval {
            lo: a.lo.min(b.lo),
            hi: a.hi.max(b.hi),
        }
    }

    pub(crate) fn of(vals: &[f64]) -> Interval {
        let lo = vals
            .iter()
            .copied()
            .fold(f64::INFINITY, |a, b| if b.is_nan() { f64::NEG_INFINITY } else { a.min(b) });
        let hi = vals
            .iter()
            .copied()
            .fold(f64::NEG_INFINITY, |a, b| if b.is_nan() { f64::INFINITY } else { a.max(b) });
        Interval { lo, hi }
    }

    pub fn is_finite(&self) -> bool {
        self.lo.is_finite() && self.hi.is_finite()
    }

    pub fn magnitude(&self) -> f64 {
        self.lo.abs().max(self.hi.abs())
    }

    pub(crate) fn monotone(self, f: impl Fn(f64) -> f64) -> Interval {
        Interval::of(&[f(self.lo), f(self.hi)])
    }
}
