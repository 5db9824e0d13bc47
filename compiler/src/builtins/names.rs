//! The names the language reserves without a declaration: `at_sample`, `neighbour` (and
//! how far it reads), the named constants, and the test every declaration's name must pass.

use super::{Func, Input, SampleFn};

/// The name of the per-sample lookup `at_sample(k, e)` (a Shade pass evaluating `e` in
/// light sample `k`'s view), which check types and lower unrolls.
pub const AT_SAMPLE: &str = "at_sample";

/// Named constants.
pub fn constant(name: &str) -> Option<f64> {
    match name {
        "PI" => Some(std::f64::consts::PI),
        "E" => Some(std::f64::consts::E),
        _ => None,
    }
}

/// Every name reserved by the language (declarations may not take them).
/// `neighbour(ch, dx, dy)`: on the map side, channel `ch` of the texel `(dx, dy)` texels
/// away, clamped to the map's edge; `dx`, `dy` integers known at compile time.
pub const NEIGHBOUR: &str = "neighbour";
/// The farthest a `neighbour` reads, in texels along each axis (the kernels' limit).
pub const MAX_NEIGHBOUR: i64 = 31;

pub fn is_reserved(name: &str) -> bool {
    Input::from_name(name).is_some()
        || constant(name).is_some()
        || Func::from_name(name).is_some()
        || SampleFn::from_name(name).is_some()
        || matches!(
            name,
            "let" | "sum" | "in" | "true" | "false" | "if" | "else" | "at_sample" | NEIGHBOUR
        )
        || name == crate::front::expr::COMPARE_AT
}
