//! What a summed-area table's storage leaves in its lookups, as docs/language.md
//! ("Summed-area tables") states it, and the warnings where that exceeds what the Shade
//! tolerates (judged by the rounding estimate, `rounding::estimate_with`).
//!
//! - **Unorm codes** (a Unorm8 or Unorm16 channel) and **fixed-point codes**
//!   (`sum: Fixed(bits: B)` over a float channel: `round((v - lo) / (hi - lo) (2^B - 1))`
//!   over the channel's range) are summed in wrapping u32 arithmetic. A box sum, a
//!   difference of four entries, is exact while the box's own sum of codes stays below
//!   2^32: for boxes of up to [`fixed_max_area`] texels, whatever the map's size. Beyond
//!   that it wraps and reads as nonsense. Within it the lookup is off by the codes'
//!   rounding alone: half a step, `(hi - lo) / (2 (2^B - 1))`.
//! - **f32 sums** (`sum: F32`, the default over a float channel) of the values less the
//!   midpoint `c` of the channel's range, so that `|v - c| <= m = (hi - lo) / 2`. Every
//!   addition of the row pass, then of the column pass, rounds at the running sum's
//!   magnitude (at most 2^-23 of it, as `interp` counts a rounding); summed over a
//!   running sum of up to `x m` the row pass leaves `2^-23 m x (x + 1) / 2` at column `x`,
//!   and the column pass adds its own, so an entry of an `n x n` table is within
//!   [`f32_entry_bound`] `= 2^-23 m n^2 (n + 2)` of the f64 sum (the centring subtraction
//!   included). A box of `A` texels combines entries near its four corners and computes
//!   nine rectangles of four entries in f32 (256 roundings at the largest entry's
//!   magnitude, `m n^2`, bound it): [`f32_box_bound`]. At 2048 x 2048 that is about
//!   `4228 m / A`: a bound, reached only by adversarial roundings, and what the warning
//!   uses; docs/language.md gives the error measured on depth maps beside it.

use crate::back::summed_area::{TableCode, table_code};
use crate::builtins::SampleFn;
use crate::diag::{Diagnostic, Phase};
use crate::front::ast::TableSum;
use crate::ir::{ChannelId, Node, Program, ResId};
use crate::ranges::RangeEval;
use std::collections::HashMap;

/// The map size the stated bounds and the warnings take (the runtime's size is the
/// scene's: tables are exact or bounded per box, whatever it is, but an f32 table's
/// entries grow with it).
pub const REFERENCE_SIZE: f64 = 2048.0;

/// One f32 rounding, relative to the value rounded (twice the unit roundoff, as `interp`).
const ROUND: f64 = 1.0 / 8_388_608.0;

/// The largest error of an entry of an `n x n` f32 table whose values lie within `m` of
/// the centre it subtracts.
pub fn f32_entry_bound(n: f64, m: f64) -> f64 {
    ROUND * m * n * n * (n + 2.0)
}

/// The largest error of the mean over a box of `area` texels (at least one) in an
/// `n x n` f32 table whose values lie within `m` of its centre.
pub fn f32_box_bound(n: f64, m: f64, area: f64) -> f64 {
    (4.0 * f32_entry_bound(n, m) + 256.0 * ROUND * m * n * n) / area.max(1.0)
}

/// The most texels a box of a `Fixed(bits)` table may cover and still sum exactly.
pub fn fixed_max_area(bits: u8) -> f64 {
    (f64::from(u32::MAX) / ((1u64 << bits) - 1) as f64).floor()
}

/// The most bits a fixed-point table may take for boxes of `area` texels to sum exactly.
pub fn fixed_bits_for(area: f64) -> u8 {
    (1..=TableSum::MAX_BITS).rev().find(|b| fixed_max_area(*b) >= area).unwrap_or(1)
}

/// A Shade lookup of a float channel through a table, with the box areas it may take at
/// [`REFERENCE_SIZE`] (texels; `nearest` is one texel).
struct Lookup {
    table: ResId,
    channel: ChannelId,
    /// The lookup's name, for the message.
    what: &'static str,
    area: (f64, f64),
}

fn lookups(p: &Program) -> Vec<Lookup> {
    let Some(shade) = p.shade() else {
        return vec![];
    };
    let n = REFERENCE_SIZE;
    let mut ranges = RangeEval::new(p.ir, HashMap::new());
    // a texel of the map at the reference size
    ranges
        .inputs
        .insert(crate::builtins::Input::TexelSize, crate::interval::Interval::point(1.0 / n));
    let mut out = Vec::new();
    for h in p.arena.postorder(&[shade]) {
        let Node::Sample {
            channel,
            resource,
            how,
            args,
            ..
        } = p.arena.node(h)
        else {
            continue;
        };
        if crate::pack::table_source(p.ir, *resource).is_none() {
            continue;
        }
        // the box's widths in uv units; a box is a texel at least and the map at most
        let widths = match how {
            SampleFn::Box => &args[..],
            SampleFn::BoxAt => &args[2..],
            SampleFn::Sample
            | SampleFn::SampleLod
            | SampleFn::SampleWidth
            | SampleFn::Nearest
            | SampleFn::Fetch
            | SampleFn::NearestAt
            | SampleFn::SampleAt
            | SampleFn::SampleWidthAt
            | SampleFn::NearestLevel
            | SampleFn::NearestLevelAt
            | SampleFn::MipBox
            | SampleFn::MipBoxAt => &[][..],
        };
        let area = if widths.len() == 2 {
            let side = |w: WidthRange| ((w.0 * n).clamp(1.0, n), (w.1 * n).clamp(1.0, n));
            let (x, y) = (side(range(&mut ranges, widths[0])), side(range(&mut ranges, widths[1])));
            (x.0 * y.0, x.1 * y.1)
        } else {
            (1.0, 1.0)
        };
        out.push(Lookup {
            table: *resource,
            channel: *channel,
            what: how.name(false),
            area,
        });
    }
    out
}

/// The range of a box's width in uv, `(lo, hi)`: an unknown low end is 0 (a texel, once
/// clamped), an unknown high end infinite (the whole map).
type WidthRange = (f64, f64);

fn range(ranges: &mut RangeEval, h: crate::ir::ExprId) -> WidthRange {
    let r = ranges.eval(h);
    (
        if r.lo.is_finite() { r.lo.max(0.0) } else { 0.0 },
        if r.hi.is_finite() { r.hi } else { f64::INFINITY },
    )
}

/// Where a table's `sum:` is written (the pass where it is not).
fn sum_span(pass: &crate::ir::IrPass) -> crate::span::Span {
    pass.kind.table_sum().map_or(pass.span, |s| s.1)
}

/// The edit that makes table `table`'s `sum:` read `sum`: its value replaced where it is
/// written, else the field added after the pass's `writes:`.
fn sum_fix(p: &Program, table: ResId, sum: TableSum) -> crate::diag::Edit {
    let text = match sum {
        TableSum::F32 => "F32".to_string(),
        TableSum::Fixed(bits) => format!("Fixed(bits: {bits})"),
    };
    match p.passes[p.resources[table].writer].kind.table_sum() {
        Some((_, span)) => crate::diag::Edit { span, text },
        None => {
            let at = p.resources[table].span.end as usize;
            crate::diag::Edit {
                span: crate::span::Span::new(at, at),
                text: format!(", sum: {text}"),
            }
        }
    }
}

/// The warnings of the tables over float channels: a fixed-point table whose boxes may
/// outgrow the area it sums exactly, and an f32 table whose stated bound at
/// [`REFERENCE_SIZE`] moves the visibility by more than `rounding::WARN_ABOVE`
/// (estimated as the rounding estimate does, each table lookup moved by its bound; only
/// where `estimate` is set).
pub fn warnings(p: &Program, estimate: bool) -> Vec<Diagnostic> {
    let mut out: Vec<Diagnostic> = Vec::new();
    let looks = lookups(p);
    let mut moved: HashMap<(ResId, ChannelId), f64> = HashMap::new();
    // the f32 tables' lookups and their bound, for the message
    let mut float_reads: Vec<(ResId, ChannelId, f64, f64)> = Vec::new();
    for l in &looks {
        let Some(slot) = p.resources[l.table].slot_of(l.channel) else {
            continue;
        };
        let Ok(code) = table_code(p, l.table, slot.texture) else {
            continue;
        };
        let pass = &p.passes[p.resources[l.table].writer];
        let span = sum_span(pass);
        let channel = &p.channels[l.channel].name;
        let width = slot.range.hi - slot.range.lo;
        match code {
            TableCode::Codes { fixed: false, .. } => {}
            TableCode::Codes { fixed: true, scale } => {
                let bits = (f64::from(scale) + 1.0).log2().round() as u8;
                let exact = fixed_max_area(bits);
                let table = format!("table `{}`", p.resources[l.table].name);
                if l.area.1 > exact && !out.iter().any(|d| d.message.starts_with(&table)) {
                    out.push(
                        Diagnostic::warning(
                            Phase::Analyse,
                            format!(
                                "table `{}` sums {bits}-bit codes of `{channel}`, exact for boxes of up to {exact} texels, but `{}` may cover {} at {n} x {n}: a larger box's sum wraps around 2^32",
                                p.resources[l.table].name,
                                l.what,
                                l.area.1,
                                n = REFERENCE_SIZE
                            ),
                        )
                        .at(span, "fixed-point codes")
                        .help(format!(
                            "`Fixed(bits: {})` sums such boxes exactly (half a step is then {:.3e} of the range), or bound the box's widths",
                            fixed_bits_for(l.area.1),
                            0.5 / ((1u64 << fixed_bits_for(l.area.1)) - 1) as f64
                        ))
                        .fix_edit(sum_fix(p, l.table, TableSum::Fixed(fixed_bits_for(l.area.1)))),
                    );
                }
                let step = if width.is_finite() { 0.5 * width / f64::from(scale) } else { 0.0 };
                let e = moved.entry((l.table, l.channel)).or_insert(0.0);
                *e = e.max(step);
            }
            TableCode::Float => {
                let m = 0.5 * width;
                let bound = if m.is_finite() {
                    f32_box_bound(REFERENCE_SIZE, m, l.area.0)
                } else {
                    f64::INFINITY
                };
                let e = moved.entry((l.table, l.channel)).or_insert(0.0);
                *e = e.max(bound);
                // each table channel once, at its smallest box (its largest bound)
                match float_reads.iter_mut().find(|r| (r.0, r.1) == (l.table, l.channel)) {
                    Some(r) if r.2 < bound => *r = (l.table, l.channel, bound, l.area.0),
                    Some(_) => {}
                    None => float_reads.push((l.table, l.channel, bound, l.area.0)),
                }
            }
        }
    }
    if moved.is_empty() || !estimate {
        return out;
    }
    let warn = crate::rounding::WARN_ABOVE;
    let estimate = crate::rounding::estimate_with(p, crate::rounding::Detail::Warn, &moved);
    let error_in = |e: &Option<crate::rounding::Estimate>, channel: ChannelId| {
        e.as_ref()
            .and_then(|e| e.channels.iter().find(|c| c.channel == channel).map(|c| c.error))
            .unwrap_or(f64::INFINITY)
    };
    let error_of = |channel: ChannelId| error_in(&estimate, channel);
    // a fixed-point table's codes: half a step of the range they span, judged as an f32
    // table's bound is (issue 51: `Fixed(bits: 10)` over exp(-80 z) passed unjudged)
    if estimate.is_some() {
        let mut fixed: Vec<ResId> = moved
            .keys()
            .map(|k| k.0)
            .filter(|t| !float_reads.iter().any(|r| r.0 == *t))
            .collect();
        fixed.sort_by_key(|t| t.index());
        fixed.dedup();
        for table in fixed {
            let mut over: Vec<(ChannelId, f64)> = moved
                .iter()
                .filter(|(k, _)| k.0 == table && error_of(k.1) > warn)
                .map(|(k, step)| (k.1, *step))
                .collect();
            over.sort_by_key(|o| o.0.index());
            let Some(&(_, step)) = over.iter().max_by(|a, b| a.1.total_cmp(&b.1)) else {
                continue;
            };
            let error = over.iter().map(|o| error_of(o.0)).fold(0.0, f64::max);
            let names: Vec<String> = over.iter().map(|o| format!("`{}`", p.channels[o.0].name)).collect();
            let bits = match p.passes[p.resources[table].writer].kind.table_sum() {
                Some((TableSum::Fixed(b), _)) => b,
                Some((TableSum::F32, _)) | None => continue,
            };
            out.push(
                Diagnostic::warning(
                    Phase::Analyse,
                    format!(
                        "table `{}` sums {bits}-bit codes of {}: half a code step, {step:.3e}, can move the visibility by up to {error:.3} (warned above {warn})",
                        p.resources[table].name,
                        names.join(", "),
                    ),
                )
                .at(sum_span(&p.passes[p.resources[table].writer]), "fixed-point codes")
                .note("a code step is a fixed fraction of the channel's range, so values small against the range (an exponential's tail) lose every digit")
                .help("store a channel of narrower range, or sum it in f32 (`sum: F32`) where its boxes are large enough for the f32 bound"),
            );
        }
    }
    if float_reads.is_empty() {
        return out;
    }
    // one warning per table, naming its channels above the threshold
    let mut tables: Vec<ResId> = float_reads.iter().map(|r| r.0).collect();
    tables.dedup();
    let bits = fixed_bits_for(REFERENCE_SIZE * REFERENCE_SIZE);
    for table in tables {
        let over: Vec<&(ResId, ChannelId, f64, f64)> = float_reads.iter().filter(|r| r.0 == table && error_of(r.1) > warn).collect();
        let Some(&&(_, _, bound, area)) = over.iter().max_by(|a, b| a.2.total_cmp(&b.2)) else {
            continue;
        };
        let error = over.iter().map(|r| error_of(r.1)).fold(0.0, f64::max);
        let names: Vec<String> = over.iter().map(|r| format!("`{}`", p.channels[r.1].name)).collect();
        // the fix offered is judged before it is offered: the same estimate with this
        // table's channels moved by half a code step of `bits` bits instead
        let mut codes = moved.clone();
        for r in float_reads.iter().filter(|r| r.0 == table) {
            let width = p.resources[table].slot_of(r.1).map_or(f64::INFINITY, |s| s.range.hi - s.range.lo);
            codes.insert((r.0, r.1), 0.5 * width / ((1u64 << bits) - 1) as f64);
        }
        let with_codes = crate::rounding::estimate_with(p, crate::rounding::Detail::Warn, &codes);
        let coded = over.iter().map(|r| error_in(&with_codes, r.1)).fold(0.0, f64::max);
        let d = Diagnostic::warning(
            Phase::Analyse,
            format!(
                "table `{}` sums {} in f32: at {n} x {n} its stated bound for a box of {area} texel(s) is {bound:.3e}, which can move the visibility by up to {error:.3} (warned above {warn})",
                p.resources[table].name,
                names.join(", "),
                n = REFERENCE_SIZE
            ),
        )
        .at(sum_span(&p.passes[p.resources[table].writer]), "f32 sums")
        .note("an f32 table's entries grow with the map (to m n^2, m half the channel's range): their rounding is divided among the box's texels, so small boxes read it whole");
        out.push(if coded <= warn {
            d.help(format!(
                "sum fixed-point codes, exact per box: `sum: Fixed(bits: {bits})` keeps boxes of up to the whole map exact (its half step moves the visibility by up to {coded:.3})"
            ))
            .fix_edit(sum_fix(p, table, TableSum::Fixed(bits)))
        } else {
            d.note(format!(
                "fixed-point codes would lose it too: half a step of `Fixed(bits: {bits})` (the most bits that sum the whole map exactly) can move the visibility by up to {coded:.3}"
            ))
            .help("read larger boxes (the f32 bound is divided by a box's area), or store a channel of narrower range")
        });
    }
    out
}

/// An f32 table as the GPU builds it from an `n x n` map of stored values (row-major):
/// `v - centre` rounded to f32, running sums along each row, then down each column, every
/// addition rounded to f32 in that order (WGSL's f32 addition is correctly rounded, so
/// this is the GPU's table bit for bit: lab/tests/gpu.rs compares them).
pub fn f32_table(values: &[f32], n: usize, centre: f32) -> Vec<f32> {
    let mut t = vec![0.0f32; n * n];
    for y in 0..n {
        let mut acc = 0.0f32;
        for x in 0..n {
            acc += values[y * n + x] - centre;
            t[y * n + x] = acc;
        }
    }
    for x in 0..n {
        let mut acc = 0.0f32;
        for y in 0..n {
            acc += t[y * n + x];
            t[y * n + x] = acc;
        }
    }
    t
}

/// The exact (f64) inclusive prefix sums of `values - centre` over an `n x n` map.
pub fn f64_table(values: &[f32], n: usize, centre: f32) -> Vec<f64> {
    let mut t = vec![0.0f64; n * n];
    for y in 0..n {
        let mut acc = 0.0f64;
        for x in 0..n {
            acc += f64::from(values[y * n + x]) - f64::from(centre);
            let above = if y > 0 { t[(y - 1) * n + x] } else { 0.0 };
            t[y * n + x] = acc + above;
        }
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_stated_bounds_hold_on_uniform_noise_and_a_map_at_one_end() {
        let n = 512;
        // a stated LCG's values in [0, 1), and a map at the top of [0, 1]
        let mut state = 12345u32;
        let noise: Vec<f32> = (0..n * n)
            .map(|_| {
                state = state.wrapping_mul(1664525).wrapping_add(1013904223);
                (state >> 8) as f32 / 16_777_216.0
            })
            .collect();
        for (what, values) in [("noise", noise), ("ones", vec![1.0f32; n * n])] {
            let (t, exact) = (f32_table(&values, n, 0.5), f64_table(&values, n, 0.5));
            let worst = t.iter().zip(&exact).map(|(a, b)| (f64::from(*a) - b).abs()).fold(0.0, f64::max);
            assert!(worst <= f32_entry_bound(n as f64, 0.5), "{what}: {worst} above the bound");
            if what == "noise" {
                // the entries round: the bound is not vacuous
                assert!(worst > 0.0);
            }
        }
    }

    #[test]
    fn fixed_point_areas_and_bits() {
        // 2^32 - 1 = (2^16 - 1)(2^16 + 1): 16-bit codes sum boxes of 65537 texels exactly
        assert_eq!(fixed_max_area(16), 65537.0);
        assert_eq!(fixed_max_area(8), 16843009.0);
        // the whole 2048^2 map (2^22 texels) takes 10 bits: (2^10 - 1) 2^22 < 2^32
        assert_eq!(fixed_bits_for(REFERENCE_SIZE * REFERENCE_SIZE), 10);
        assert!(fixed_max_area(11) < REFERENCE_SIZE * REFERENCE_SIZE);
    }
}
