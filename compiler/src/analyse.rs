//! Phase `analyse`: the range of every channel in every resource (the range analysis of
//! `ranges.rs`), and the precision fit. A float precision must hold the range (f16 up to
//! 65504, f32 up to 3.4e38); a unorm precision needs a finite range, which it stores with
//! an affine encode `(v - lo) / (hi - lo)` (identity when the range is already [0, 1];
//! affine maps commute with the linear filters that follow). When a channel does not fit,
//! the diagnostic states the largest safe value of each parameter it depends on, found by
//! bisection (`probe`; e.g. ESM with c = 80 at f16: c must stay at or below ln 65504 =
//! 11.09 for z in [0, 1]).

use crate::check::Checked;
use crate::diag::{Diagnostic, Diagnostics, Phase};
use crate::front::ast::{ConstValue, Precision};
use crate::ir::*;
use crate::lower::lower_with_value;
use crate::ranges::{F16_MIN_NORMAL, fits, scene_slot_ranges, slot_ranges, value_slot_ranges};
use crate::resolve::Symbols;
use std::collections::HashMap;

/// Below this magnitude a value stored at `p` becomes 0: half the smallest subnormal
/// (2^-24 for F16, 2^-149 for F32), which rounds to even, to 0. `None` for the unorm
/// precisions, whose smallest step is a fraction of the encoded range instead.
pub fn flushes_below(p: Precision) -> Option<f64> {
    match p {
        Precision::F16 => Some(2f64.powi(-25)),
        Precision::F32 => Some(2f64.powi(-150)),
        Precision::Unorm8 | Precision::Unorm16 => None,
    }
}

pub fn encode_for(p: Precision, r: Interval) -> Encode {
    // Ranges computed through f32 constants can stray below 0 or above 1 by rounding
    // (sin(f32(pi)) = -8.7e-8); within 1e-6 the unorm clamp is the right encode.
    const SLACK: f64 = 1e-6;
    if !p.is_unorm() || (r.lo >= -SLACK && r.hi <= 1.0 + SLACK) {
        return Encode::IDENTITY;
    }
    let w = r.hi - r.lo;
    Encode {
        bias: r.lo,
        scale: if w > 0.0 { 1.0 / w } else { 1.0 },
    }
}

/// The range of slot `slot` of resource `res` with param `param` at `value`, for the
/// largest safe value a diagnostic states. A runtime param is a `Param` node of `ir`: the
/// same IR is evaluated with its range widened to `value`. A fixed param is no node of
/// the IR: `lower` substituted its value, folded the constants it reaches and unrolled the
/// series and expansions it bounds, so the technique is lowered again with the other
/// value (`lower::lower_with_value`) and that IR's range read. Analyse calls the earlier
/// phase; `lower` imports nothing of analyse.
fn probe(ir: &Ir, sym: &Symbols, checked: &Checked, param: ParamId, value: f64, res: ResId, slot: usize) -> Option<Interval> {
    let p = &ir.params[param];
    let ranges = if p.uniform {
        let lo = p.range.map(|r| r.0).unwrap_or(value).min(value);
        slot_ranges(ir, Some((param, Interval { lo, hi: value })))
    } else {
        slot_ranges(&lower_with_value(sym, checked, param, value)?, None)
    };
    ranges.get(res.index())?.get(slot).copied()
}

/// Ranges and encodings of every slot (a side table: the IR is only read), and the
/// warnings. `sym` and `checked` are what `ir` was lowered from: a channel that does not
/// fit its precision is lowered again with other values of a fixed param (`probe`).
pub fn analyse(ir: &Ir, sym: &Symbols, checked: &Checked) -> Result<(Analysis, Vec<Diagnostic>), Diagnostics> {
    // channels left to the compiler were chosen on the scene's ranges (`lower`)
    let generic = slot_ranges(ir, None);
    let scene = scene_slot_ranges(ir);
    let ranges: Vec<Vec<Interval>> = ir
        .resources
        .iter()
        .enumerate()
        .map(|(ri, res)| {
            res.slots
                .iter()
                .enumerate()
                .map(|(si, slot)| {
                    if ir.channels[slot.channel].precision_auto {
                        scene[ri][si]
                    } else {
                        generic[ri][si]
                    }
                })
                .collect()
        })
        .collect();
    let mut diags = Diagnostics::default();
    let mut warnings = Vec::new();
    // a declared range the value cannot reach: every texel would be clamped to its edge
    let analysed = value_slot_ranges(ir);
    for (ri, res) in ir.resources.with_handles() {
        if !ir.passes[res.writer].kind.kind().is_map() {
            continue;
        }
        for (si, slot) in res.slots.iter().enumerate() {
            let ch = &ir.channels[slot.channel];
            let (Some((lo, hi)), Some(_)) = (ch.range, ch.value) else {
                continue;
            };
            let r = analysed[ri.index()][si];
            if r.hi < lo || r.lo > hi {
                diags.push(
                    Diagnostic::error(
                        Phase::Analyse,
                        format!(
                            "the value of `{}` lies in [{}, {}], outside its declared range ({lo}, {hi}): every texel would be clamped to an end of it",
                            ch.name,
                            short(r.lo),
                            short(r.hi)
                        ),
                    )
                    .at(ch.span, "declared here")
                    .help("declare the range the value takes, or fix the value"),
                );
            }
        }
    }
    for (ri, res) in ir.resources.with_handles() {
        // A resource repeats its source's complaint: report each channel once, where it is made.
        let own = ir.passes[res.writer].kind.reports_own_range();
        for (si, slot) in res.slots.iter().enumerate() {
            let r = ranges[ri.index()][si];
            if fits(slot.precision, r) {
                continue;
            }
            if !own {
                continue;
            }
            let ch = &ir.channels[slot.channel];
            let why = match slot.precision {
                Precision::F16 => "F16 holds at most 65504",
                Precision::F32 => "F32 holds at most 3.4e38",
                Precision::Unorm8 | Precision::Unorm16 => "a unorm channel stores a finite range scaled to [0, 1]",
            };
            let mut d = Diagnostic::error(
                Phase::Analyse,
                format!(
                    "channel `{}` in `{}` spans {r}, which {} cannot hold",
                    ch.name,
                    res.name,
                    slot.precision.name()
                ),
            )
            .at(
                ch.precision_span,
                if ch.precision_overridden {
                    format!("{why} (set by `--precision`)")
                } else {
                    why.to_string()
                },
            )
            .also(ch.span, "channel computed here");
            if let Some(v) = ch.value {
                d = d.note(format!(
                    "the channel's value is {} (for inputs in their ranges: depth z in [0, 1])",
                    ir.arena.display(v, Some(ir))
                ));
            }
            let mut suggested = false;
            for (pi, p) in ir.params.with_handles() {
                if matches!(p.value, ConstValue::Bool(_)) {
                    continue;
                }
                let now = if p.uniform {
                    p.range.map(|r| r.1).unwrap_or(p.value.as_f64())
                } else {
                    p.value.as_f64()
                };
                let lo = p.range.map(|r| r.0).unwrap_or(0.0).min(now);
                let range_at = |v: f64| probe(ir, sym, checked, pi, v, ri, si);
                let ok = |v: f64| range_at(v).is_some_and(|r| fits(slot.precision, r));
                let unchanged = range_at(lo) == range_at(now);
                if unchanged || !ok(lo) || ok(now) {
                    continue;
                }
                let (mut a, mut b) = (lo, now);
                for _ in 0..60 {
                    let m = 0.5 * (a + b);
                    if ok(m) { a = m } else { b = m }
                }
                let is_int = matches!(p.value, ConstValue::Int(_));
                let best = if is_int { a.floor() } else { a };
                // floored, so that the value shown fits
                let shown = if is_int {
                    format!("{}", best as i64)
                } else {
                    format!("{:.4}", (best * 1e4).floor() / 1e4)
                };
                let what = if p.uniform {
                    format!("narrow the range of `{}` to at most {shown}", p.name)
                } else {
                    format!(
                        "`{}` = {} is too large: it must stay at or below {shown} for {}",
                        p.name,
                        p.value,
                        slot.precision.name()
                    )
                };
                let help = if slot.precision.is_widest() {
                    what
                } else {
                    format!("{what}, or store `{}` at a wider precision", ch.name)
                };
                d = d.help(help).also(p.name_span, format!("`{}` declared here", p.name));
                suggested = true;
                break;
            }
            if !suggested {
                d = d.help(if r.is_finite() && !slot.precision.is_widest() {
                    "store the channel at F32".to_string()
                } else if r.is_finite() {
                    "F32 is the widest precision: shrink the value's range (a smaller exponent or scale), or clamp it".to_string()
                } else {
                    "bound the value: give the params it uses a `range`, or clamp it".to_string()
                });
            }
            diags.push(d);
        }
    }
    diags.check()?;
    let mut analysis = Analysis::default();
    for (ri, res) in ir.resources.with_handles() {
        for (si, slot) in res.slots.iter().enumerate() {
            let range = ranges[ri.index()][si];
            let encode = encode_for(slot.precision, range);
            analysis.slots.insert((ri, slot.channel), SlotInfo { range, encode });
        }
    }
    // Quantisation and underflow, reported once, where the channel is made.
    for (ri, res) in ir.resources.with_handles() {
        if ir.passes[res.writer].kind.copies_source() {
            continue;
        }
        for s in &res.slots {
            let Some(SlotInfo { range: r, .. }) = analysis.get(ri, s.channel) else {
                continue;
            };
            let ch = &ir.channels[s.channel];
            if s.precision == Precision::Unorm8 && r.hi - r.lo > 8.0 {
                warnings.push(
                    Diagnostic::warning(
                        Phase::Analyse,
                        format!(
                            "channel `{}` spans {r} at Unorm8: one step is {}",
                            ch.name,
                            short((r.hi - r.lo) / 255.0)
                        ),
                    )
                    .at(ch.precision_span, "coarse quantisation")
                    .help("use Unorm16 or F16 for this channel"),
                );
            }
            let min_normal = match s.precision {
                Precision::F16 => Some(F16_MIN_NORMAL),
                Precision::F32 => Some(f32::MIN_POSITIVE as f64),
                Precision::Unorm8 | Precision::Unorm16 => None,
            };
            if let Some(m) = min_normal {
                let smallest = if r.lo > 0.0 {
                    r.lo
                } else if r.hi < 0.0 {
                    -r.hi
                } else {
                    f64::INFINITY
                };
                // a range touching or straddling 0 says nothing of how small the nonzero
                // values get: sample the channel over the depths where its value is a
                // function of depth (a Map's channel; Geometry outputs are not), and warn
                // where a nonzero value is stored as 0 (issue 51: exp(-80 z) at F16 with
                // a range touching 0 was silent)
                let made_by_map = ir.passes[res.writer].kind.kind().is_map() && !ir.passes.iter().any(|p| p.kind.kind().is_geometry());
                if smallest.is_infinite()
                    && made_by_map
                    && let Some(zero) = flushes_below(s.precision)
                {
                    let mut memo = std::collections::HashMap::new();
                    let flushed: Vec<f64> = (0..=64)
                        .map(|k| k as f64 / 64.0)
                        .filter(|&z| {
                            let v = channel_value(ir, s.channel, z, &mut memo, 0);
                            v != 0.0 && v.abs() < zero
                        })
                        .collect();
                    if let (Some(first), Some(last)) = (flushed.first(), flushed.last()) {
                        let mut d = Diagnostic::warning(
                            Phase::Analyse,
                            format!(
                                "channel `{}` at {} underflows to 0 inside its analysed range {r}: at depths from {} to {} ({} of the 65 sampled) its nonzero value lies below {}, which is stored as 0",
                                ch.name,
                                s.precision.name(),
                                short(*first),
                                short(*last),
                                flushed.len(),
                                short(zero)
                            ),
                        )
                        .at(ch.precision_span, set_by(ch, "nonzero values stored as 0"))
                        .note("a quotient or a product with a large factor (an exponential warp undone in the Shade) reads 0 there")
                        .help("rescale the channel, or store it at F32");
                        if s.precision == Precision::F16 && !ch.precision_overridden {
                            d = d.fix(ch.precision_span, "F32");
                        }
                        warnings.push(d);
                    }
                }
                if smallest < m {
                    warnings.push(
                        Diagnostic::warning(
                            Phase::Analyse,
                            format!(
                                "channel `{}` reaches magnitudes down to {} at {}, below its smallest normal number {}",
                                ch.name,
                                short(smallest),
                                s.precision.name(),
                                short(m)
                            ),
                        )
                        .at(ch.precision_span, set_by(ch, "values underflow to subnormals or zero"))
                        .help(if s.precision.is_widest() {
                            "rescale the channel"
                        } else {
                            "rescale the channel, or store it at a wider precision"
                        }),
                    );
                }
            }
        }
    }
    Ok((analysis, warnings))
}

/// A label on a channel's precision, saying so where `--precision` set it (the caret is
/// on the file's precision, which the command line overrode).
fn set_by(ch: &IrChannel, label: &str) -> String {
    if ch.precision_overridden {
        format!("{label} (the precision set by `--precision`)")
    } else {
        label.to_string()
    }
}

/// The value of channel `c` at a texel of depth `z`: the depth itself for a Depth
/// channel, else its expression with the channels it reads at `z`.
pub(crate) fn channel_value(p: &Ir, c: ChannelId, z: f64, memo: &mut HashMap<(ChannelId, u64), f64>, depth: usize) -> f64 {
    let Some(h) = p.channels[c].value else {
        return z;
    };
    // each channel once per depth, however many channels read it
    if let Some(v) = memo.get(&(c, z.to_bits())) {
        return *v;
    }
    // the channels this value reads, computed first (a Map's value reads earlier
    // resources); a bound on the chain keeps a malformed one finite
    let mut known: HashMap<ChannelId, f64> = HashMap::new();
    for n in p.arena.postorder(&[h]) {
        if let Node::Channel(r, _) | Node::Sample { channel: r, .. } = p.arena.node(n)
            && !known.contains_key(r)
        {
            let v = if depth < 16 {
                channel_value(p, *r, z, memo, depth + 1)
            } else {
                f64::NAN
            };
            known.insert(*r, v);
        }
    }
    let v = p.arena.eval(h, &|n: &Node| match n {
        Node::Channel(r, _) | Node::Sample { channel: r, .. } => known.get(r).copied(),
        Node::Input(i, _) => Some(i.desc().typical),
        Node::Param(id) => Some(p.params[*id].value.as_f64()),
        Node::Swizzle(..) => None,
        Node::F32(_) | Node::I32(_) | Node::U32(_) | Node::Bool(_) | Node::Unary(..) | Node::Binary(..) | Node::Call(..) => None,
    });
    memo.insert((c, z.to_bits()), v);
    v
}
