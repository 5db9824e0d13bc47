//! Value-by-value comparison of an image or buffer under test against expected values,
//! each with the interval a tolerance model allows about it (`reference::tolerance`), or
//! skipped as a tie. Shared by the agreement tests (generated and hand-written shaders
//! against the CPU reference, per camera pixel) and the reference tests (the hand-written
//! WGSL against the CPU evaluator, per query).
//!
//! A [`Comparison`] gathers the figures the tests print (values checked, ties, largest and
//! mean difference, the allowances) and keeps the worst value (largest difference over its
//! allowance) with its coordinates and both values, so that a failure names it.

use crate::reference::tolerance::Allowed;
use std::fmt::Write;

/// How an index into the compared values maps to coordinates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layout {
    /// Row-major pixels of an image `width` wide, row 0 first: index i is (i % width, i / width).
    Image { width: usize },
    /// A plain buffer: index i.
    Buffer,
}

impl Layout {
    /// "pixel (x, y)" or "value i".
    pub fn at(self, index: usize) -> String {
        match self {
            Layout::Image { width } => format!("pixel ({}, {})", index % width.max(1), index / width.max(1)),
            Layout::Buffer => format!("value {index}"),
        }
    }
}

/// One compared value outside its interval, or the worst one.
#[derive(Clone, Debug, PartialEq)]
pub struct Sample {
    pub index: usize,
    pub got: f64,
    pub expected: f64,
    pub lo: f64,
    pub hi: f64,
}

impl Sample {
    /// |got - expected| over the half-width of the allowed interval on the side of `got`
    /// (infinite for a difference where nothing is allowed, 0 for none): above 1 is
    /// outside the interval.
    pub fn ratio(&self) -> f64 {
        let diff = self.got - self.expected;
        let allowance = if diff >= 0.0 {
            self.hi - self.expected
        } else {
            self.expected - self.lo
        };
        if diff == 0.0 {
            0.0
        } else if allowance > 0.0 {
            diff.abs() / allowance
        } else {
            f64::INFINITY
        }
    }

    pub fn inside(&self) -> bool {
        (self.lo..=self.hi).contains(&self.got)
    }
}

/// The comparison of one image or buffer (or several, pushed in turn).
#[derive(Clone, Debug)]
pub struct Comparison {
    pub label: String,
    pub layout: Layout,
    /// Values compared (ties excluded).
    pub checked: usize,
    /// Values skipped as ties.
    pub ties: usize,
    pub max_diff: f64,
    sum_diff: f64,
    /// The half-width of every allowed interval about the expected value (the larger side).
    pub allowances: Vec<f64>,
    /// The value with the largest [`Sample::ratio`] (then the largest difference).
    pub worst: Option<Sample>,
    /// Values outside their interval.
    pub outside: usize,
    /// The first few values outside their interval, each with its context.
    pub failures: Vec<(Sample, String)>,
}

/// How many failures a comparison keeps.
const KEPT: usize = 6;

impl Comparison {
    pub fn new(label: impl Into<String>, layout: Layout) -> Comparison {
        Comparison {
            label: label.into(),
            layout,
            checked: 0,
            ties: 0,
            max_diff: 0.0,
            sum_diff: 0.0,
            allowances: Vec::new(),
            worst: None,
            outside: 0,
            failures: Vec::new(),
        }
    }

    /// Compare `got` at `index` with `expected` under `allowed`; `context` (the query, the
    /// input's name) is evaluated only for a failure. Returns whether it was inside (ties
    /// count as inside).
    pub fn push(&mut self, index: usize, got: f64, expected: f64, allowed: &Allowed, context: impl FnOnce() -> String) -> bool {
        let (lo, hi) = match *allowed {
            Allowed::Tie => {
                self.ties += 1;
                return true;
            }
            Allowed::Within(lo, hi) => (lo, hi),
        };
        self.checked += 1;
        let diff = (got - expected).abs();
        // NaN differences are failures, never the maximum of a `max`
        self.max_diff = if diff.is_nan() { f64::NAN } else { self.max_diff.max(diff) };
        self.sum_diff += diff;
        self.allowances.push((expected - lo).max(hi - expected).max(0.0));
        let s = Sample {
            index,
            got,
            expected,
            lo,
            hi,
        };
        let worse = match &self.worst {
            None => true,
            Some(w) => {
                let (a, b) = (s.ratio(), w.ratio());
                a > b || (a == b && diff > (w.got - w.expected).abs()) || (got.is_nan() && !w.got.is_nan())
            }
        };
        let inside = s.inside();
        if worse {
            self.worst = Some(s.clone());
        }
        if !inside {
            self.outside += 1;
            if self.failures.len() < KEPT {
                self.failures.push((s, context()));
            }
        }
        inside
    }

    pub fn mean_diff(&self) -> f64 {
        self.sum_diff / self.checked.max(1) as f64
    }

    pub fn max_allowance(&self) -> f64 {
        self.allowances.iter().copied().fold(0.0, f64::max)
    }

    pub fn median_allowance(&self) -> f64 {
        let mut s = self.allowances.clone();
        s.sort_by(f64::total_cmp);
        s.get(s.len() / 2).copied().unwrap_or(0.0)
    }

    /// The worst value's difference over its allowance (0 when nothing differs).
    pub fn worst_ratio(&self) -> f64 {
        self.worst.as_ref().map_or(0.0, Sample::ratio)
    }

    /// Values whose allowance exceeds `width`.
    pub fn loose(&self, width: f64) -> usize {
        self.allowances.iter().filter(|a| **a > width).count()
    }

    /// The worst value, as a line: its coordinates and both values, and its interval.
    pub fn describe_worst(&self) -> String {
        match &self.worst {
            None => format!("{}: nothing compared", self.label),
            Some(w) => format!(
                "{}: worst at {}: got {:.7}, expected {:.7}, allowed [{:.7}, {:.7}] ({:.3} of the allowance)",
                self.label,
                self.layout.at(w.index),
                w.got,
                w.expected,
                w.lo,
                w.hi,
                w.ratio()
            ),
        }
    }

    /// Every value outside its interval (the first few, then a count), with the worst
    /// value; empty when all were inside.
    pub fn errors(&self) -> Vec<String> {
        if self.outside == 0 {
            return Vec::new();
        }
        let mut out: Vec<String> = self
            .failures
            .iter()
            .map(|(s, context)| {
                let mut l = format!(
                    "{}: at {}: got {:.7}, expected {:.7}, outside the allowed [{:.7}, {:.7}]",
                    self.label,
                    self.layout.at(s.index),
                    s.got,
                    s.expected,
                    s.lo,
                    s.hi
                );
                if !context.is_empty() {
                    let _ = write!(l, " ({context})");
                }
                l
            })
            .collect();
        if self.outside > self.failures.len() {
            out.push(format!("{}: {} more outside", self.label, self.outside - self.failures.len()));
        }
        out.push(self.describe_worst());
        out
    }
}

/// Compare two equally long images or buffers value by value: `allowed(i)` gives the
/// interval allowed about `expected[i]`, or a tie.
pub fn compare(label: &str, layout: Layout, got: &[f64], expected: &[f64], mut allowed: impl FnMut(usize) -> Allowed) -> Comparison {
    assert_eq!(
        got.len(),
        expected.len(),
        "{label}: {} values compared with {}",
        got.len(),
        expected.len()
    );
    let mut c = Comparison::new(label, layout);
    for (i, (&g, &e)) in got.iter().zip(expected).enumerate() {
        c.push(i, g, e, &allowed(i), String::new);
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_worst_pixel_is_named_with_its_coordinates_and_values() {
        // a 3-wide image; pixel (1, 1) = index 4 is 0.3 off with 0.1 allowed: ratio 3;
        // pixel (2, 0) is 0.05 off with 0.1 allowed: inside
        let expected = [0.5; 6];
        let got = [0.5, 0.5, 0.55, 0.5, 0.8, 0.5];
        let c = compare("img", Layout::Image { width: 3 }, &got, &expected, |i| {
            if i == 5 { Allowed::Tie } else { Allowed::Within(0.4, 0.6) }
        });
        assert_eq!((c.checked, c.ties, c.outside), (5, 1, 1));
        let w = c.worst.clone().unwrap();
        assert_eq!(w.index, 4);
        assert!((w.ratio() - 3.0).abs() < 1e-12);
        assert!((c.max_diff - 0.3).abs() < 1e-12);
        assert!((c.mean_diff() - 0.35 / 5.0).abs() < 1e-12);
        let errors = c.errors().join("\n");
        assert!(errors.contains("pixel (1, 1): got 0.8000000, expected 0.5000000"), "{errors}");
        assert!(errors.contains("worst at pixel (1, 1)"), "{errors}");
    }

    #[test]
    fn asymmetric_intervals_and_nan_fail() {
        let mut c = Comparison::new("buf", Layout::Buffer);
        // allowed [0.5, 0.9] about 0.5: 0.45 is below, 0.85 inside
        assert!(!c.push(0, 0.45, 0.5, &Allowed::Within(0.5, 0.9), String::new));
        assert!(c.push(1, 0.85, 0.5, &Allowed::Within(0.5, 0.9), String::new));
        assert!(!c.push(2, f64::NAN, 0.5, &Allowed::Within(0.0, 1.0), || "context".into()));
        assert_eq!(c.outside, 2);
        assert!(c.max_diff.is_nan());
        assert_eq!(c.worst.as_ref().unwrap().index, 2);
        assert!(c.errors().iter().any(|l| l.contains("value 2") && l.contains("(context)")));
    }
}
