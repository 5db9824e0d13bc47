//! Phase `analyse`: interval (range) analysis of every channel in every resource, and the
//! precision fit. A float precision must hold the range (f16 up to 65504, f32 up to
//! 3.4e38); a unorm precision needs a finite range, which it stores with an affine encode
//! `(v - lo) / (hi - lo)` (identity when the range is already [0, 1]; affine maps commute
//! with the linear filters that follow). When a channel does not fit, the diagnostic
//! states the largest safe value of each parameter it depends on, found by bisection
//! (e.g. ESM with c = 80 at f16: c must stay at or below ln 65504 = 11.09 for z in [0, 1]).

use crate::builtins::Ty;
use crate::diag::{Diagnostic, Diagnostics, Phase};
use crate::front::ast::{ConstValue, LightView, Precision, Reduce};
use crate::front::expr::{BinOp, UnOp};
use crate::ir::*;
use std::collections::HashMap;

pub const F16_MAX: f64 = 65504.0;
pub const F32_MAX: f64 = f32::MAX as f64;
/// The smallest positive normal f16.
pub const F16_MIN_NORMAL: f64 = 6.103515625e-5;

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

/// Range of every expression node under given channel ranges.
pub struct RangeEval<'a> {
    ir: &'a Ir,
    /// Map side: the range of each channel as stored in the resources the pass reads.
    channels: HashMap<ChannelId, Interval>,
    /// One runtime param evaluated over another range than its declared one.
    pub param_range: Option<(ParamId, Interval)>,
    /// Inputs taken over another range than their descriptor's (`texel_size` at one map
    /// size, for `tables`).
    pub inputs: HashMap<crate::builtins::Input, Interval>,
    memo: HashMap<ExprId, Interval>,
}

impl<'a> RangeEval<'a> {
    pub fn new(ir: &'a Ir, channels: HashMap<ChannelId, Interval>) -> Self {
        RangeEval {
            ir,
            channels,
            param_range: None,
            inputs: HashMap::new(),
            memo: HashMap::new(),
        }
    }

    pub fn eval(&mut self, root: ExprId) -> Interval {
        for h in self.ir.arena.postorder(&[root]) {
            if !self.memo.contains_key(&h) {
                let r = self.node(h);
                self.memo.insert(h, r);
            }
        }
        self.memo[&root]
    }

    fn get(&self, h: ExprId) -> Interval {
        self.memo.get(&h).copied().unwrap_or(Interval::UNBOUNDED)
    }

    fn node(&self, h: ExprId) -> Interval {
        let r = self.node_exact(h);
        // u32 arithmetic wraps: a range that leaves [0, 2^32 - 1] may hold any u32
        if self.ir.arena.ty(h) == Ty::U32 && !(r.lo >= 0.0 && r.hi <= u32::MAX as f64) {
            Interval::U32
        } else {
            r
        }
    }

    /// The range of `h`'s value computed without wrapping.
    fn node_exact(&self, h: ExprId) -> Interval {
        let a = &self.ir.arena;
        let integers = || if a.ty(h) == Ty::U32 { Interval::U32 } else { Interval::I32 };
        match a.node(h) {
            Node::F32(b) => Interval::point(f32::from_bits(*b) as f64),
            Node::I32(v) => Interval::point(*v as f64),
            Node::U32(v) => Interval::point(*v as f64),
            Node::Bool(v) => Interval::point(*v as i32 as f64),
            Node::Param(p) if self.param_range.is_some_and(|(o, _)| o == *p) => {
                self.param_range.map(|(_, r)| r).unwrap_or(Interval::UNBOUNDED)
            }
            Node::Param(p) => {
                let p = &self.ir.params[*p];
                match (p.range, p.value) {
                    (Some((lo, hi)), _) => Interval { lo, hi },
                    (None, ConstValue::Bool(_)) => Interval::UNIT,
                    (None, _) => Interval::UNBOUNDED,
                }
            }
            Node::Input(i, _) => self.inputs.get(i).copied().unwrap_or_else(|| {
                let (lo, hi) = i.range();
                Interval { lo, hi }
            }),
            Node::Channel(c, _) => self.channels.get(c).copied().unwrap_or(Interval::UNBOUNDED),
            // Receiver side: a lookup's range is not known before the slot is laid out.
            Node::Sample { .. } => Interval::UNBOUNDED,
            Node::Unary(UnOp::Neg, x) => {
                let x = self.get(*x);
                Interval { lo: -x.hi, hi: -x.lo }
            }
            Node::Unary(UnOp::Not, _) => Interval::UNIT,
            // ~x is -x - 1 on i32, 2^32 - 1 - x on u32
            Node::Unary(UnOp::BitNot, x) => {
                let x = self.get(*x);
                let top = if a.ty(h) == Ty::U32 { u32::MAX as f64 } else { -1.0 };
                Interval {
                    lo: top - x.hi,
                    hi: top - x.lo,
                }
            }
            Node::Binary(op, x, y) => {
                let (x, y) = (self.get(*x), self.get(*y));
                match op {
                    BinOp::Add => Interval {
                        lo: x.lo + y.lo,
                        hi: x.hi + y.hi,
                    },
                    BinOp::Sub => Interval {
                        lo: x.lo - y.hi,
                        hi: x.hi - y.lo,
                    },
                    BinOp::Mul => Interval::of(&[mul(x.lo, y.lo), mul(x.lo, y.hi), mul(x.hi, y.lo), mul(x.hi, y.hi)]),
                    BinOp::Div => {
                        if y.lo <= 0.0 && y.hi >= 0.0 {
                            Interval::UNBOUNDED
                        } else {
                            Interval::of(&[x.lo / y.lo, x.lo / y.hi, x.hi / y.lo, x.hi / y.hi])
                        }
                    }
                    BinOp::Rem => {
                        let m = y.magnitude();
                        Interval {
                            lo: if x.lo < 0.0 { -m } else { 0.0 },
                            hi: if x.hi > 0.0 { m } else { 0.0 },
                        }
                    }
                    BinOp::Lt | BinOp::Le | BinOp::Gt | BinOp::Ge | BinOp::Eq | BinOp::Ne | BinOp::And | BinOp::Or => Interval::UNIT,
                    // of non-negative operands, `&` is at most the smaller one
                    BinOp::BitAnd if x.lo >= 0.0 && y.lo >= 0.0 => Interval {
                        lo: 0.0,
                        hi: x.hi.min(y.hi),
                    },
                    BinOp::BitAnd | BinOp::BitOr | BinOp::BitXor | BinOp::Shl => integers(),
                    // a right shift of a non-negative value only shrinks it
                    BinOp::Shr if x.lo >= 0.0 => Interval { lo: 0.0, hi: x.hi },
                    BinOp::Shr => integers(),
                }
            }
            Node::Swizzle(x, _) => self.get(*x),
            Node::Call(f, args) => {
                let v: Vec<Interval> = args.iter().map(|x| self.get(*x)).collect();
                (f.desc().range)(&v)
            }
        }
    }
}

/// 0 * inf is 0 here: a zero factor bounds the product whatever the other range.
fn mul(a: f64, b: f64) -> f64 {
    if a == 0.0 || b == 0.0 { 0.0 } else { a * b }
}

/// Ranges of every slot of every resource (indexed by resource, then slot), in pass order
/// (no diagnostics). `param_range` overrides the range of one runtime param: the probe
/// of the largest safe value evaluates the same IR under another environment.
pub fn slot_ranges(ir: &Ir, param_range: Option<(ParamId, Interval)>) -> Vec<Vec<Interval>> {
    ranges_from(ir, param_range, false)
}

/// [`slot_ranges`] with the Depth pass's output narrowed to the scene's depths where the
/// compilation is specialised for a scene (`SceneFacts::depth_floor`). Only the channels
/// left to the compiler (`Auto`) are judged on these: an explicit precision keeps the
/// generic ranges and so the generic encodes, and a specialised build stores what the
/// generic one stores.
pub fn scene_slot_ranges(ir: &Ir) -> Vec<Vec<Interval>> {
    ranges_from(ir, None, true)
}

fn ranges_from(ir: &Ir, param_range: Option<(ParamId, Interval)>, scene: bool) -> Vec<Vec<Interval>> {
    ranges_with(ir, param_range, scene, true)
}

/// [`ranges_from`], taking each channel's declared range (`declared`) or its value's
/// analysed interval.
fn ranges_with(ir: &Ir, param_range: Option<(ParamId, Interval)>, scene: bool, declared: bool) -> Vec<Vec<Interval>> {
    let mut out: Vec<Vec<Interval>> = ir.resources.iter().map(|r| vec![Interval::UNBOUNDED; r.slots.len()]).collect();
    for pass in &ir.passes {
        let Some(w) = pass.writes else { continue };
        let res = &ir.resources[w];
        let src = |ch: ChannelId| -> Option<Interval> {
            pass.reads.iter().find_map(|&r| {
                let i = ir.resources[r].slots.iter().position(|s| s.channel == ch)?;
                Some(out[r.index()][i])
            })
        };
        let mut ranges = Vec::with_capacity(res.slots.len());
        match &pass.kind {
            IrPassKind::Depth { view } => {
                // specialised for a scene: the centre view's casters lie at or beyond the
                // facts' least depth (what no caster covers stays at 1)
                let floor = match view {
                    LightView::Center if scene => ir
                        .specialised
                        .as_ref()
                        .and_then(|s| s.facts.depth_floor)
                        .map_or(0.0, |f| (f as f64).clamp(0.0, 1.0)),
                    LightView::Center | LightView::PerSample => 0.0,
                };
                ranges.extend(res.slots.iter().map(|_| Interval { lo: floor, hi: 1.0 }))
            }
            IrPassKind::Map | IrPassKind::Geometry { .. } => {
                let mut env = HashMap::new();
                for &r in &pass.reads {
                    for (i, s) in ir.resources[r].slots.iter().enumerate() {
                        env.insert(s.channel, out[r.index()][i]);
                    }
                }
                let mut ev = RangeEval::new(ir, env);
                ev.param_range = param_range;
                for s in &res.slots {
                    let ch = &ir.channels[s.channel];
                    ranges.push(match (ch.range, ch.value) {
                        // clamped to it when stored
                        (Some((lo, hi)), Some(_)) if declared => Interval { lo, hi },
                        (_, Some(v)) => ev.eval(v),
                        (_, None) => Interval::UNIT,
                    });
                }
            }
            IrPassKind::Filter { kernel: IrKernel::LoG } => {
                for s in &res.slots {
                    let r = src(s.channel).unwrap_or(Interval::UNBOUNDED);
                    // centre weight 4, four neighbours -1 (IrKernel::LOG_3X3)
                    let w = r.hi - r.lo;
                    ranges.push(Interval { lo: -4.0 * w, hi: 4.0 * w });
                }
            }
            IrPassKind::Filter { .. }
            | IrPassKind::Mipmap {
                reduce: Reduce::Mean | Reduce::Max | Reduce::Min,
            }
            | IrPassKind::SummedArea { .. } => {
                // convex combinations, maxima and minima stay within the source range
                for s in &res.slots {
                    ranges.push(src(s.channel).unwrap_or(Interval::UNBOUNDED));
                }
            }
            IrPassKind::Shade { .. } => {}
        }
        out[w.index()] = ranges;
    }
    out
}

/// The smallest magnitude other than 0 a range may hold (infinite when it straddles 0: its
/// values may come as near 0 as they like, which the underflow warning leaves alone).
fn smallest_magnitude(r: Interval) -> f64 {
    if r.lo > 0.0 {
        r.lo
    } else if r.hi < 0.0 {
        -r.hi
    } else {
        f64::INFINITY
    }
}

/// Choose the precision of every channel left to the compiler (`precision: Auto`, or
/// `--precision NAME=auto`): F16 where the channel's range, where it is made, fits F16
/// (at most 65504) and stays clear of F16's subnormals (at least 6.1e-5 in magnitude
/// when it does not straddle 0), else F32. The range is the one the analysis computes,
/// so a technique specialised for a scene (`--scene`) is judged on the scene's depths
/// (`SceneFacts::depth_floor`). The choice weighs range only: how finely a value must be
/// kept (a depth compared with a small bias) is the author's to state with an explicit
/// precision. Records one line per channel in `Ir::precision_choices`.
pub fn choose_precisions(ir: &mut Ir) {
    if !ir.channels.iter().any(|c| c.precision_auto) {
        return;
    }
    let ranges = scene_slot_ranges(ir);
    let mut chosen: Vec<(ChannelId, Precision, Interval)> = Vec::new();
    for (ri, res) in ir.resources.with_handles() {
        // where the channel is made: the Depth, Map or Geometry pass writing it
        if ir.passes[res.writer].kind.copies_source() {
            continue;
        }
        for (si, slot) in res.slots.iter().enumerate() {
            if !ir.channels[slot.channel].precision_auto || chosen.iter().any(|c| c.0 == slot.channel) {
                continue;
            }
            let r = ranges[ri.index()][si];
            let p = if fits(Precision::F16, r) && smallest_magnitude(r) >= F16_MIN_NORMAL {
                Precision::F16
            } else {
                Precision::F32
            };
            chosen.push((slot.channel, p, r));
        }
    }
    for &(c, p, r) in &chosen {
        ir.channels[c].precision = p;
        let why = match p {
            Precision::F16 => "within F16's 65504 and above its smallest normal 6.1e-5".to_string(),
            Precision::F32 | Precision::Unorm8 | Precision::Unorm16 if r.magnitude() > F16_MAX => "beyond F16's 65504".to_string(),
            Precision::F32 | Precision::Unorm8 | Precision::Unorm16 => {
                format!("down to {}, below F16's smallest normal 6.1e-5", short(smallest_magnitude(r)))
            }
        };
        let line = format!("channel `{}` (Auto): {}, spanning {r}, {why}", ir.channels[c].name, p.name());
        ir.precision_choices.push(line);
    }
    for res in ir.resources.iter_mut() {
        for slot in res.slots.iter_mut() {
            if let Some(&(_, p, _)) = chosen.iter().find(|c| c.0 == slot.channel) {
                slot.precision = p;
            }
        }
    }
}

/// Whether a precision can hold a range.
pub fn fits(p: Precision, r: Interval) -> bool {
    if r.lo.is_nan() || r.hi.is_nan() {
        return false;
    }
    match p {
        Precision::F32 => r.magnitude() <= F32_MAX,
        Precision::F16 => r.magnitude() <= F16_MAX,
        Precision::Unorm8 | Precision::Unorm16 => r.is_finite(),
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

/// Re-evaluates one slot's range with one parameter changed: `(param, value) -> range`.
pub type Probe<'p> = &'p dyn Fn(ParamId, f64, ResId, usize) -> Option<Interval>;

/// Ranges and encodings of every slot (a side table: the IR is only read, so the probe
/// may read it too), and the warnings.
pub fn analyse(ir: &Ir, probe: Probe) -> Result<(Analysis, Vec<Diagnostic>), Diagnostics> {
    // channels left to the compiler were chosen on the scene's ranges (`choose_precisions`)
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
    let analysed = ranges_with(ir, None, false, false);
    for (ri, res) in ir.resources.with_handles() {
        if !matches!(ir.passes[res.writer].kind, IrPassKind::Map) {
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
                let ok = |v: f64| probe(pi, v, ri, si).is_some_and(|r| fits(slot.precision, r));
                let unchanged = probe(pi, lo, ri, si) == probe(pi, now, ri, si);
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
                let made_by_map = matches!(ir.passes[res.writer].kind, IrPassKind::Map)
                    && !ir.passes.iter().any(|p| matches!(p.kind, IrPassKind::Geometry { .. }));
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
