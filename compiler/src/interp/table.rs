//! Summed-area tables as the GPU builds them (`Table`): prefix sums of a level's values and
//! allowances, and what each kind of table's storage adds (`TableModel`).

use super::texels::Level;
use super::{Model, Rounding};
use crate::ir::PlacedSlot;

/// A summed-area table as the GPU builds it: prefix sums of the texels' values and of their
/// allowances (on an `(n + 1)^2` grid, row and column 0 zero), and what its sums leave.
#[derive(Clone, Debug)]
pub(super) struct Table {
    pub(super) sums: Vec<f64>,
    pub(super) asums: Vec<f64>,
    pub(super) kind: TableModel,
}

/// What a table's storage adds to a lookup's allowance.
#[derive(Clone, Debug)]
pub(super) enum TableModel {
    /// Exact u32 sums of a unorm texture's own codes (the texels' allowances hold their
    /// rounding).
    Codes,
    /// Exact u32 sums of fixed-point codes over `[lo, hi]` (half a code step is in
    /// `asums`): the mean code `e` is weighed in f32 as a unorm's, relative to `e`, and the
    /// decode `lo + e * (hi - lo)` rounds too.
    Fixed { lo: f64 },
    /// f32 sums of the values less the channel's midpoint: `err` bounds each entry's
    /// rounding (rows summed first, then columns, as the GPU does) and `csums` holds the
    /// sums of `v - centre`, whose magnitudes the lookup's own f32 arithmetic rounds.
    Float { err: Vec<f64>, csums: Vec<f64> },
}

/// The table the GPU builds over `base` (a channel stored in `slot`) as `code` says: the
/// texels' values (clamped to the range a fixed-point code spans) and allowances (half a
/// code step more there; under [`Rounding::Stored`] rounded to the code, `round((v - lo)
/// / (hi - lo) (2^B - 1))`, as the GPU sums them), and for an f32 table each entry's
/// rounding bound.
pub(super) fn table(
    base: &Level,
    slot: &PlacedSlot,
    code: crate::back::summed_area::TableCode,
    rounding: Rounding,
    model: Model,
) -> (Level, Table) {
    use crate::back::summed_area::TableCode;
    let mut level = base.clone();
    let kind = match code {
        TableCode::Codes { fixed: false, .. } => TableModel::Codes,
        TableCode::Codes { fixed: true, scale } => {
            let (lo, hi) = (slot.range.lo, slot.range.hi);
            let step = if hi > lo { (hi - lo) / f64::from(scale) } else { 0.0 };
            for (v, a) in level.v.iter_mut().zip(level.a.iter_mut()) {
                *v = v.clamp(lo, hi.max(lo));
                if rounding == Rounding::Stored && step > 0.0 {
                    *v = lo + ((*v - lo) / step).round() * step;
                }
                *a += 0.5 * step;
            }
            TableModel::Fixed { lo }
        }
        TableCode::Float => {
            let centre = crate::back::summed_area::centre(slot);
            // the subtraction `v - centre` rounds in f32 too
            for (v, a) in level.v.iter().zip(level.a.iter_mut()) {
                *a += model.ulp(v - centre + a.abs());
            }
            let n = level.size;
            let row = n + 1;
            let (mut csums, mut err) = (vec![0.0; row * row], vec![0.0; row * row]);
            // rows: running sums, each addition rounding at the partial sum's magnitude
            for y in 0..n {
                let (mut acc, mut e) = (0.0f64, 0.0f64);
                for x in 0..n {
                    acc += level.v[y * n + x] - centre;
                    e += model.ulp(acc.abs() + e);
                    csums[(y + 1) * row + x + 1] = acc;
                    err[(y + 1) * row + x + 1] = e;
                }
            }
            // columns: running sums of the rounded row sums, in place
            for x in 1..=n {
                let (mut acc, mut e) = (0.0f64, 0.0f64);
                for y in 1..=n {
                    acc += csums[y * row + x];
                    e += err[y * row + x] + model.ulp(acc.abs() + e);
                    csums[y * row + x] = acc;
                    err[y * row + x] = e;
                }
            }
            TableModel::Float { err, csums }
        }
    };
    let sums = prefix_sums(&level, true);
    let asums = prefix_sums(&level, false);
    (level, Table { sums, asums, kind })
}

fn prefix_sums(l: &Level, values: bool) -> Vec<f64> {
    let n = l.size;
    let row = n + 1;
    let mut s = vec![0.0; row * row];
    for y in 0..n {
        for x in 0..n {
            let t = if values { l.v[y * n + x] } else { l.a[y * n + x] };
            s[(y + 1) * row + x + 1] = t + s[y * row + x + 1] + s[(y + 1) * row + x] - s[y * row + x];
        }
    }
    s
}
