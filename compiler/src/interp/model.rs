//! The precision and rounding model: whose errors an allowance bounds (`Model`), how a
//! stored texel is rounded (`stored`, `half_step`, `round_f16`), the GPU's error in built-in
//! calls and inputs (`call_error`, `input_error`) and filtering positions, and the interval
//! allowed about a value (`Allowed`).

use crate::builtins::{Accuracy, Func, Input, InputError};
use crate::front::ast::Precision;
use crate::ir::PlacedSlot;

/// Whose errors an allowance bounds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Model {
    /// The GPU's: storage rounding, f32 arithmetic, WGSL's built-in accuracy, the receiver's
    /// f32 transforms and the filtering hardware's 8-bit positions.
    Gpu,
    /// Another f64 evaluation's: only f64 rounding, so that two f64 evaluations of the same
    /// math (a technique and its reference) differ by no more than their conditioning allows.
    F64,
}

impl Model {
    /// One unit in the last place of `v` in the arithmetic modelled.
    pub fn ulp(self, v: f64) -> f64 {
        match self {
            Model::Gpu => v.abs() * 2f64.powi(-23),
            Model::F64 => v.abs() * 2f64.powi(-52),
        }
    }

    /// What storing `v` in `slot` may move it by: half a rounding step, but a whole one
    /// for F16, which Vulkan lets a device round toward zero when it converts a shader's
    /// f32 output (lavapipe does: `sshc verify` of penumbra-limit-maps at F16 found texels
    /// a whole step below the nearest half).
    pub fn storage(self, slot: &PlacedSlot, v: f64) -> f64 {
        match (self, slot.precision) {
            (Model::Gpu, Precision::F16) => 2.0 * half_step(slot, v),
            (Model::Gpu, Precision::Unorm8 | Precision::Unorm16 | Precision::F32) => half_step(slot, v),
            (Model::F64, _) => 0.0,
        }
    }
}

/// Whether stored texels keep their exact value or are rounded as the GPU stores them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rounding {
    Exact,
    Stored,
}

/// One evaluated value and the interval allowed about it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Allowed {
    /// The value (the Shade's: clamped to [0, 1], NaN read as 1).
    pub value: f64,
    /// The allowed interval `[lo, hi]` (the Shade's: `raw -+ allowance`, clamped).
    pub lo: f64,
    pub hi: f64,
    /// The value before the clamp, and the allowance about it.
    pub raw: f64,
    pub allowance: f64,
}

impl Allowed {
    pub(super) fn new(raw: f64, clamped: bool) -> Allowed {
        let value = if clamped { raw.clamp(0.0, 1.0) } else { raw };
        Allowed {
            value,
            lo: value,
            hi: value,
            raw,
            allowance: 0.0,
        }
    }

    /// Allow `by` more about the raw value.
    pub(super) fn widen(&mut self, by: f64, clamped: bool) {
        self.allowance += if by.is_nan() { f64::INFINITY } else { by };
        let (lo, hi) = (self.raw - self.allowance, self.raw + self.allowance);
        (self.lo, self.hi) = if clamped {
            (lo.clamp(0.0, 1.0), hi.clamp(0.0, 1.0))
        } else {
            (lo, hi)
        };
    }

    /// Whether `x` lies in the allowed interval.
    pub fn admits(&self, x: f64) -> bool {
        (self.lo..=self.hi).contains(&x)
    }

    /// The larger side of the interval about the value.
    pub fn half_width(&self) -> f64 {
        (self.hi - self.value).max(self.value - self.lo)
    }
}

/// Half the rounding step of `slot`'s storage at value `v`, in value units.
pub fn half_step(slot: &PlacedSlot, v: f64) -> f64 {
    let scale = slot.encode.scale.abs().max(f64::MIN_POSITIVE);
    match slot.precision {
        Precision::Unorm8 => 0.5 / (255.0 * scale),
        Precision::Unorm16 => 0.5 / (65535.0 * scale),
        Precision::F16 => (v.abs() * 2f64.powi(-11)).max(2f64.powi(-25)),
        Precision::F32 => v.abs() * 2f64.powi(-24),
    }
}

/// `v` as `slot` stores it: encoded, rounded to its precision, decoded.
pub fn stored(slot: &PlacedSlot, v: f64) -> f64 {
    stored_at(slot.precision, slot.encode.bias, slot.encode.scale, v)
}

pub(super) fn stored_at(precision: Precision, bias: f64, scale: f64, v: f64) -> f64 {
    let unorm = |levels: f64| {
        let e = ((v - bias) * scale).clamp(0.0, 1.0);
        (e * levels).round() / levels / scale + bias
    };
    match precision {
        Precision::Unorm8 => unorm(255.0),
        Precision::Unorm16 => unorm(65535.0),
        Precision::F16 => round_f16(v),
        Precision::F32 => v as f32 as f64,
    }
}

/// `v` rounded to the nearest IEEE half (11 significant bits, subnormals down to 2^-24,
/// infinity past 65504).
pub fn round_f16(v: f64) -> f64 {
    if !v.is_finite() || v == 0.0 {
        return v;
    }
    let e = v.abs().log2().floor().max(-14.0);
    let ulp = 2f64.powf(e - 10.0);
    let r = (v / ulp).round_ties_even() * ulp;
    if r.abs() > 65504.0 { v.signum() * f64::INFINITY } else { r }
}

/// Filtering hardware keeps the position within a texel and the fraction between mip
/// levels to 8 bits (lavapipe; Vulkan asks for at least 4): a filtered lookup reads as if
/// its texel-space position and level of detail were off by up to this much. The shift is
/// the same for every lookup at one position, so it is applied to the receiver as a whole
/// (all lookups move together, as the moments of one texel do on the GPU).
pub(super) const FILTER_SHIFT: f64 = 1.0 / 256.0;

/// The accuracy of a built-in call with value `v` and arguments `x` (WGSL's accuracy of
/// built-in functions): `None` where the result is exact (one of its arguments, or an exact
/// function of them), else its error beyond the f32 rounding of the result.
pub fn call_error(f: Func, v: f64, x: &[f64]) -> Option<f64> {
    match f.desc().accuracy {
        Accuracy::Exact => None,
        Accuracy::Rounded => Some(0.0),
        Accuracy::Bound(error) => Some(error(v, x)),
    }
}

/// What the GPU's f32 transforms may leave in a receiver input of value `v`.
pub fn input_error(i: Input, v: f64) -> f64 {
    match i.desc().error {
        InputError::Exact => 0.0,
        InputError::Absolute(e) => e,
        InputError::Relative(e) => v.abs() * e,
        InputError::TanHalfAngle if v != 0.0 => {
            let t = 0.5 * v;
            2.0 * call_error(Func::Tan, t, &[t.atan()]).unwrap_or(0.0)
        }
        InputError::TanHalfAngle => 0.0,
    }
}
