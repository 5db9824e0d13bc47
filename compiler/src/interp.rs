//! A compiled technique evaluated on the CPU in f64 (`sshc verify`), with the
//! interval about each value that the GPU's f32 arithmetic, its storage rounding, its
//! filtering hardware and its built-in functions may move it by.
//!
//! Given the Depth pass's output (a square map of linear depths per view) and every
//! Geometry pass's ([`Given`]), [`Evaluation::new`] runs every other pass in execution
//! order: Map (the channel expressions per texel, `neighbour` offsets clamped to the edge), Filter (separable Box, Gaussian, Max and Min
//! kernels along x then y, the 3 x 3 Laplacian), Mipmap (levels down to 1 x 1, each texel
//! the mean, maximum or minimum of the 2 x 2 below it) and SummedArea (exact prefix sums).
//! [`Evaluation::visibility`] then evaluates the Shade's visibility for one receiver with
//! the eight lookups as the runtime performs them (texel `(i, j)` centred at uv `((i + 0.5)
//! / N, (j + 0.5) / N)`, clamp to edge, bilinear within a level and linear between levels,
//! `fetch` from `floor(uv N - 0.5)`, `sample_box` integrating the texels the box covers),
//! and clamps it as the runtime stores it (`[0, 1]`, NaN read as 1).
//!
//! Values are exact (f64, the built-in functions folded without rounding by
//! [`crate::builtins::fold_call_exact`]) unless [`Rounding::Stored`] asks for every stored texel to be
//! rounded to its channel's precision and encoding, as the GPU keeps it: the difference of
//! the two evaluations is what storage alone does to the visibility.
//!
//! **The allowance** (the tolerance model of `sshc verify`, a generic form of the agreement
//! tests' model) is a running error bound. Every texel of every stored channel carries one:
//! half its precision's rounding step ([`half_step`]), plus what the pass that wrote it
//! propagates (a filter's weights applied to its inputs' allowances, a maximum's largest, a
//! mip level's mean, a Map channel's bound below). An expression (a Map channel per texel,
//! the Shade's visibility per receiver) is bounded node by node in postorder
//! (`Evaluation::allowed`): a node's error is its own, under the [`Model`],
//!
//! - a lookup: the allowance of the texels it reads, weighted as it weighs them, and the
//!   jump to the neighbour texel where a `nearest` or `fetch` reads within the receiver's
//!   error of a texel boundary;
//! - an input: what the GPU's f32 transforms may leave in it ([`input_error`]: `d` and `uv`
//!   by 2^-20, the others by 2^-20 of their magnitude);
//! - a stored texel: half its rounding step, a whole one for F16 (a device may round F16
//!   stores toward zero, as lavapipe does), and a filtered unorm lookup one code more (a
//!   device may filter in fixed point); a read-back unorm texel an f32 ulp (its conversion);
//! - an arithmetic result: one f32 ulp (three for a division; none for an add, subtract or
//!   multiply of exact operands whose result f32 holds); a built-in: its WGSL accuracy
//!   ([`call_error`]: `sin`, `cos` 2^-11 absolute; `exp`, `exp2` (3 + 2|x|) ulp; `log`,
//!   `log2` 3 ulp or 2^-21 absolute; `pow` as `exp2(y log2 x)`; `sqrt`, `inverseSqrt` 2.5 ulp;
//!   the inverse trigonometric functions 4096 ulp) plus an ulp where it rounds,
//!
//! plus, for each operand and each of its components, the largest change of the node when
//! that component alone moves by its error either way (a bool operand flips). A clamp thus
//! passes on only what crosses it; a comparison or a `select` whose operands may cross passes
//! on the whole jump, so binary tests at exact ties need no separate rule; an operand that
//! may be anything (an unbounded error) makes the node unbounded. The Shade's interval is its
//! raw value (NaN read as 1) widened by the root's bound and then clamped to `[0, 1]`, widened
//! once more by what moving every filtered lookup together by the hardware's 8-bit texel
//! positions and level fractions (`FILTER_SHIFT`) changes: the GPU weighs every channel
//! of a texel with the same weights, so that error is coherent across the lookups of one
//! receiver, not independent per lookup.
//!
//! The bound is linear in each operand and sums over operands: it is not a proof where
//! errors interact beyond first order, and it is loose where an expression amplifies every
//! error (MSM's Cholesky on flat moments; `sshc verify` counts such receivers as loose).
//!
//! **Given texels.** What the GPU rasterises is not recomputed: the Depth pass's output
//! and every Geometry pass's (cones, sheets, ribbons, back faces and skins are drawn from
//! the scene's meshes) are [`Given`], one map per view, and the evaluation starts after them.
//! A depth map given from a synthetic field checks every pass after Depth; one read back
//! from the GPU (`given_slots` names the textures) checks the passes after it and the
//! Shade, not the rasterisation itself. Per-sample views (`Depth(view: PerSample)`, Skins)
//! take one map per light sample, and the Shade's `at_sample(k, ..)` reads the receiver as
//! light sample k sees it ([`Seen`]).

use crate::builtins::{Accuracy, Func, Input, InputError, SampleFn, Ty};
use crate::front::ast::{Precision, Reduce};
use crate::front::expr::BinOp;
use crate::ir::{ChannelId, ExprId, Hooks, IrKernel, IrPassKind, Node, PassId, PlacedSlot, Program, ResId};
use std::collections::HashMap;

/// The frame-wide inputs (docs/language.md section 8.5), as the runtime's `Frame` uniform
/// holds them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    pub shadow_size: u32,
    /// World distances of the fitted depth range.
    pub near: f64,
    pub far: f64,
    pub light_size: f64,
    pub light_width: [f64; 2],
    pub light_spread: f64,
    pub light_distant: bool,
    /// One texel at view distance D spans `texel_world[0] D + texel_world[1]` world units
    /// across the map (perspective: `[2 / (proj_y N), 0]`; orthographic: `[0, extent / N]`).
    pub texel_world: [f64; 2],
    /// Frames run since the scene was bound.
    pub frame: u32,
}

/// One receiver (a shaded point) as the Shade pass sees it.
#[derive(Clone, Debug, PartialEq)]
pub struct Receiver {
    /// Light-space uv.
    pub uv: [f64; 2],
    /// View distance from the light's centre (world units).
    pub d_world: f64,
    pub ndotl: f64,
    /// The receiver plane's depth slope per texel (`depth_slope`).
    pub depth_slope: f64,
    /// The level of detail of implicit `sample` lookups.
    pub lod: f64,
    /// The camera pixel.
    pub pixel: [f64; 2],
    /// The receiver as each light sample's view sees it, in sample order (empty without
    /// per-sample views).
    pub samples: Vec<Seen>,
}

/// A receiver seen from light sample k (the `in_*_v{k}` of the generated Shade): its
/// coordinates in the sample's view and the view's own depth range, texel size and weights.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Seen {
    pub uv: [f64; 2],
    pub d_world: f64,
    /// The view's fitted depth range (world distances).
    pub near: f64,
    pub far: f64,
    /// `dot(n, normalize(sample position - receiver))`.
    pub ndotl: f64,
    pub depth_slope: f64,
    pub lod: f64,
    /// World size of one texel per unit of view distance (`2 / (proj_y N)`).
    pub texel_world: f64,
    /// Weights of the segments before and after the sample (`segment_before`, `segment_after`).
    pub weights: [f64; 2],
}

impl Seen {
    fn d(&self) -> f64 {
        (self.d_world - self.near) / (self.far - self.near)
    }
}

/// Texels given to an evaluation instead of computed by it: the Depth pass's output and
/// every Geometry pass's, by resource and channel, one map per view (the centre's alone, or
/// one per light sample), decoded, row 0 first.
#[derive(Clone, Debug, Default)]
pub struct Given {
    maps: HashMap<(ResId, ChannelId), Vec<Vec<f64>>>,
}

impl Given {
    /// The Depth pass's output: one linear depth map per view.
    pub fn depth(p: &Program, views: Vec<Vec<f32>>) -> Given {
        let mut g = Given::default();
        for s in given_slots(p).into_iter().filter(|s| !s.geometry) {
            g.insert(
                s.resource,
                s.channel,
                views.iter().map(|v| v.iter().map(|&z| z as f64).collect()).collect(),
            );
        }
        g
    }

    /// One channel's maps, one per view.
    pub fn maps(&self, resource: ResId, channel: ChannelId) -> Option<&[Vec<f64>]> {
        self.maps.get(&(resource, channel)).map(Vec::as_slice)
    }

    /// Give one channel's maps, one per view.
    pub fn insert(&mut self, resource: ResId, channel: ChannelId, views: Vec<Vec<f64>>) {
        self.maps.insert((resource, channel), views);
    }
}

/// A channel an evaluation must be given, and where the compiled graph keeps it.
#[derive(Clone, Debug, PartialEq)]
pub struct GivenSlot {
    /// The pass that writes it.
    pub pass: String,
    /// Written by a Geometry pass (else by Depth).
    pub geometry: bool,
    pub resource: ResId,
    pub channel: ChannelId,
    /// The graph's texture, and the channel's layer within one view's block of `layers`.
    pub texture: String,
    pub layer: u32,
    pub layers: u32,
    pub component: u32,
    /// Views: 1, or one per light sample (view k's block starts at layer `k * layers`).
    pub views: u32,
    /// The stored value is `(v - bias) * scale`.
    pub bias: f64,
    pub scale: f64,
}

impl GivenSlot {
    /// A stored texel's value.
    pub fn decode(&self, stored: f32) -> f64 {
        stored as f64 / self.scale + self.bias
    }

    /// The array layer of view `k`.
    pub fn array_layer(&self, k: u32) -> u32 {
        k * self.layers + self.layer
    }
}

/// The channels written by the live Depth and Geometry passes of `p`: what an evaluation is
/// given rather than computes.
pub fn given_slots(p: &Program) -> Vec<GivenSlot> {
    let mut out = Vec::new();
    for pass in p.passes.iter().filter(|pass| pass.live) {
        let geometry = match pass.kind {
            IrPassKind::Depth { .. } => false,
            IrPassKind::Geometry { .. } => true,
            IrPassKind::Map
            | IrPassKind::Filter { .. }
            | IrPassKind::Mipmap { .. }
            | IrPassKind::SummedArea { .. }
            | IrPassKind::Shade { .. } => {
                continue;
            }
        };
        let Some(r) = pass.writes else { continue };
        let res = &p.resources[r];
        for s in &res.slots {
            let Some(t) = res.textures.get(s.texture) else { continue };
            out.push(GivenSlot {
                pass: pass.name.clone(),
                geometry,
                resource: r,
                channel: s.channel,
                texture: t.name.clone(),
                layer: s.layer,
                layers: t.layers,
                component: s.component,
                views: if p.per_sample(r) { p.samples } else { 1 },
                bias: s.encode.bias,
                scale: s.encode.scale,
            });
        }
    }
    out
}

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
    fn new(raw: f64, clamped: bool) -> Allowed {
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
    fn widen(&mut self, by: f64, clamped: bool) {
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

fn stored_at(precision: Precision, bias: f64, scale: f64, v: f64) -> f64 {
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

/// One level of one stored channel: values and their allowances, row-major.
#[derive(Clone, Debug)]
struct Level {
    size: usize,
    v: Vec<f64>,
    a: Vec<f64>,
}

impl Level {
    fn at(&self, x: i64, y: i64) -> (f64, f64) {
        let last = self.size as i64 - 1;
        let k = (y.clamp(0, last) * (last + 1) + x.clamp(0, last)) as usize;
        (self.v[k], self.a[k])
    }

    /// The texel containing texel-space point `p` (`floor(p)`, clamped to the edge), with its
    /// allowance; where `p` lies within `margin` (the GPU's coordinate error, in this
    /// level's texels) of a texel boundary the neighbour across it may be read instead,
    /// so the difference is allowed too.
    fn nearest(&self, p: [f64; 2], margin: f64) -> (f64, f64) {
        let (x, y) = (p[0].floor() as i64, p[1].floor() as i64);
        let (v, mut a) = self.at(x, y);
        for (axis, c) in p.into_iter().enumerate() {
            let f = c - c.floor();
            let across = if f < margin {
                Some(-1)
            } else if f > 1.0 - margin {
                Some(1)
            } else {
                None
            };
            if let Some(o) = across {
                let (dx, dy) = if axis == 0 { (o, 0) } else { (0, o) };
                a += (self.at(x + dx, y + dy).0 - v).abs();
            }
        }
        (v, a)
    }

    /// Bilinear at uv: the value and the allowance of the blend.
    fn bilinear(&self, uv: [f64; 2]) -> (f64, f64) {
        let n = self.size as f64;
        let (sx, sy) = (uv[0] * n - 0.5, uv[1] * n - 0.5);
        let (x0, y0) = (sx.floor(), sy.floor());
        let (fx, fy) = (sx - x0, sy - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let t = [self.at(x0, y0), self.at(x0 + 1, y0), self.at(x0, y0 + 1), self.at(x0 + 1, y0 + 1)];
        let w = [(1.0 - fx) * (1.0 - fy), fx * (1.0 - fy), (1.0 - fx) * fy, fx * fy];
        t.iter()
            .zip(w)
            .fold((0.0, 0.0), |(v, a), ((tv, ta), wk)| (v + wk * tv, a + wk * ta))
    }
}

/// A summed-area table as the GPU builds it: prefix sums of the texels' values and of their
/// allowances (on an `(n + 1)^2` grid, row and column 0 zero), and what its sums leave.
#[derive(Clone, Debug)]
struct Table {
    sums: Vec<f64>,
    asums: Vec<f64>,
    kind: TableModel,
}

/// What a table's storage adds to a lookup's allowance.
#[derive(Clone, Debug)]
enum TableModel {
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

/// A stored channel: its levels (one without mips) and, read by the box lookups and
/// `nearest` on a table, the table over level 0.
#[derive(Clone, Debug)]
struct Texels {
    levels: Vec<Level>,
    sat: Option<Table>,
    /// What a filtered lookup's result may be off by beyond its texels' allowance: one code
    /// of an 8- or 16-bit unorm format, which a device may filter in fixed point and round
    /// to a code (lavapipe filters 8-bit formats so: tests/tests/lookups.rs measures its
    /// bilinear result within 2^-8 + 1/255 of the exact blend); 0 for float formats.
    code: f64,
}

impl Texels {
    fn new(levels: Vec<Level>, slot: &PlacedSlot) -> Texels {
        Texels {
            levels,
            sat: None,
            code: match slot.precision {
                Precision::Unorm8 | Precision::Unorm16 => 2.0 * half_step(slot, 0.0),
                Precision::F16 | Precision::F32 => 0.0,
            },
        }
    }
}

/// Filtering hardware keeps the position within a texel and the fraction between mip
/// levels to 8 bits (lavapipe; Vulkan asks for at least 4): a filtered lookup reads as if
/// its texel-space position and level of detail were off by up to this much. The shift is
/// the same for every lookup at one position, so it is applied to the receiver as a whole
/// (all lookups move together, as the moments of one texel do on the GPU).
const FILTER_SHIFT: f64 = 1.0 / 256.0;

impl Texels {
    fn base(&self) -> &Level {
        &self.levels[0]
    }

    fn texel(&self, x: i64, y: i64) -> (f64, f64) {
        self.base().at(x, y)
    }

    /// The level-0 texel containing texel-space point `p` (`floor(p)`), with its
    /// allowance; where `p` lies within the GPU's coordinate error of a texel boundary the
    /// neighbour across it may be read instead, so the difference is allowed too.
    fn nearest(&self, p: [f64; 2], margin: f64) -> (f64, f64) {
        self.base().nearest(p, margin)
    }

    /// `nearest_level`: the texel of level `level` (truncated toward 0 as the GPU's i32 is,
    /// clamped to the chain) containing uv, with [`Texels::nearest`]'s allowance at a
    /// texel boundary (`margin` in level-0 texels, scaled to the level's).
    fn nearest_level(&self, uv: [f64; 2], level: f64, margin: f64) -> (f64, f64) {
        let last = self.levels.len() - 1;
        let l = if level.is_nan() {
            0
        } else {
            (level.trunc().max(0.0) as usize).min(last)
        };
        let lv = &self.levels[l];
        let size = lv.size as f64;
        lv.nearest([uv[0] * size, uv[1] * size], margin * size / self.base().size as f64)
    }

    /// Filtered at uv and level of detail `lod` (clamped to the chain): value and allowance.
    fn filtered(&self, uv: [f64; 2], lod: f64) -> (f64, f64) {
        let last = self.levels.len() - 1;
        let lod = if lod.is_nan() { 0.0 } else { lod.clamp(0.0, last as f64) };
        let level = (lod.floor() as usize).min(last);
        let lambda = lod - level as f64;
        let (v0, a0) = self.levels[level].bilinear(uv);
        if lambda > 0.0 && level < last {
            let (v1, a1) = self.levels[level + 1].bilinear(uv);
            // each level's blend and the blend between them may be rounded to a code
            (v0 + lambda * (v1 - v0), a0 + lambda * (a1 - a0) + 2.0 * self.code)
        } else {
            (v0, a0 + self.code)
        }
    }

    /// `sample_box`: the mean over a box `w` (uv units, at least a texel each way) centred
    /// at uv, clipped to the map (the centre clamped to it first).
    fn boxed(&self, uv: [f64; 2], w: [f64; 2], model: Model) -> (f64, f64) {
        let Some(Table { sums, asums, kind }) = &self.sat else {
            return (f64::NAN, 0.0);
        };
        let n = self.base().size;
        let runs = |c: f64, w: f64| {
            let nf = n as f64;
            let width = (w * nf).max(1.0);
            let centre = if c.is_nan() { 0.0 } else { (c * nf).clamp(0.0, nf) };
            ((centre - 0.5 * width).max(0.0), (centre + 0.5 * width).min(nf))
        };
        let ((x0, x1), (y0, y1)) = (runs(uv[0], w[0]), runs(uv[1], w[1]));
        // the integral of the piecewise-constant texels over [0, x] x [0, y]
        let integral = |s: &[f64], x: f64, y: f64| {
            let row = n + 1;
            let at = |i: usize, j: usize| s[j * row + i];
            let (i, j) = ((x.floor() as usize).min(n), (y.floor() as usize).min(n));
            let (fx, fy) = (x - i as f64, y - j as f64);
            let (i1, j1) = ((i + 1).min(n), (j + 1).min(n));
            // bilinear in the prefix sums is exact for piecewise-constant texels
            let a = at(i, j) + fx * (at(i1, j) - at(i, j));
            let b = at(i, j1) + fx * (at(i1, j1) - at(i, j1));
            a + fy * (b - a)
        };
        let area = (x1 - x0) * (y1 - y0);
        let mean = |s: &[f64]| (integral(s, x1, y1) - integral(s, x0, y1) - integral(s, x1, y0) + integral(s, x0, y0)) / area;
        let v = mean(sums);
        // the GPU weighs exact integer sums in f32
        let weighing = 32.0 * model.ulp(v);
        let corners = [(x0, y0), (x1, y0), (x0, y1), (x1, y1)];
        let table = match kind {
            TableModel::Codes => 0.0,
            // the mean code is weighed in f32 (relative to the codes' scale), then decoded
            TableModel::Fixed { lo } => 32.0 * model.ulp(v - lo) + 2.0 * model.ulp(v),
            // each corner's entries' rounding, and the lookup's f32 arithmetic on entries as
            // large as the largest it reads (nine rectangles of four entries, weighed and
            // added: 512 roundings of that magnitude bound it, docs/language.md)
            TableModel::Float { err, csums, .. } => {
                let row = n + 1;
                let near = |x: f64, y: f64, s: &[f64]| {
                    let (i, j) = ((x.floor() as usize).min(n), (y.floor() as usize).min(n));
                    let (i1, j1) = ((i + 1).min(n), (j + 1).min(n));
                    [(i, j), (i1, j), (i, j1), (i1, j1)]
                        .iter()
                        .map(|&(a, b)| s[b * row + a].abs())
                        .fold(0.0, f64::max)
                };
                let entries: f64 = corners.iter().map(|&(x, y)| near(x, y, err)).sum();
                let largest = corners.iter().map(|&(x, y)| near(x, y, csums)).fold(0.0, f64::max);
                (entries + 256.0 * model.ulp(largest)) / area + 4.0 * model.ulp(v)
            }
        };
        (v, mean(asums) + weighing + table)
    }

    /// `sample_mip_box`: the mean over the box `w` wide (uv units, a texel at least) centred
    /// at uv (clamped to the map), clipped to the map, of the piecewise-constant texels of
    /// the level where the box spans one to two texels, as WGSL's `mip_box`
    /// (`builtins::MIP_BOX_WGSL`) computes it, in f64. The allowance: the covered texels'
    /// allowances weighed as their values are; what the GPU's coordinate error can do, the
    /// box moved by `margin` (level-0 texels: the receiver's uv error, and a few f32
    /// roundings of coordinates as large as the map) either way along each axis and widened
    /// or narrowed by twice that (which takes a jump to the next level where the width
    /// crosses a power of two); and the f32 weighing of nine texels and the division, 16
    /// roundings of the largest texel read.
    fn mip_box(&self, uv: [f64; 2], w: f64, margin: f64, model: Model) -> (f64, f64) {
        let Some((v, a, big)) = self.mip_box_exact(uv, w) else {
            return (f64::NAN, 0.0);
        };
        let n = self.base().size as f64;
        let shift = margin + 4.0 * model.ulp(n);
        let mut moved = 0.0;
        if shift > 0.0 {
            let d = shift / n;
            for moves in [
                [([d, 0.0], 0.0), ([-d, 0.0], 0.0)],
                [([0.0, d], 0.0), ([0.0, -d], 0.0)],
                [([0.0, 0.0], 2.0 * d), ([0.0, 0.0], -2.0 * d)],
            ] {
                let mut worst = 0.0f64;
                for (duv, dw) in moves {
                    let m = self
                        .mip_box_exact([uv[0] + duv[0], uv[1] + duv[1]], w + dw)
                        .map_or(f64::INFINITY, |m| (m.0 - v).abs());
                    worst = worst.max(m);
                }
                moved += worst;
            }
        }
        (v, a + moved + 16.0 * model.ulp(big))
    }

    /// [`Texels::mip_box`]'s value, its texels' weighed allowance and the largest magnitude
    /// among the texels it read (`None` for a width or centre that is not a number).
    fn mip_box_exact(&self, uv: [f64; 2], w: f64) -> Option<(f64, f64, f64)> {
        let n = self.base().size as f64;
        let width = (w * n).clamp(1.0, 4294967040.0);
        if width.is_nan() || uv.iter().any(|c| c.is_nan()) {
            return None;
        }
        let level = ((width as u64).ilog2() as usize).min(self.levels.len() - 1);
        let s = (1u64 << level) as f64;
        let lv = &self.levels[level];
        let size = lv.size as f64;
        let c = [(uv[0] * n).clamp(0.0, n), (uv[1] * n).clamp(0.0, n)];
        let lo = [((c[0] - 0.5 * width) / s).max(0.0), ((c[1] - 0.5 * width) / s).max(0.0)];
        let hi = [((c[0] + 0.5 * width) / s).min(size), ((c[1] + 0.5 * width) / s).min(size)];
        let first = [lo[0].floor(), lo[1].floor()];
        let cover = |k: usize, t: f64| (hi[k].min(t + 1.0) - lo[k].max(t)).max(0.0);
        let (mut v, mut a, mut big) = (0.0, 0.0, 0.0f64);
        for j in 0..3 {
            let y = first[1] + j as f64;
            let wy = cover(1, y);
            for i in 0..3 {
                let x = first[0] + i as f64;
                let wxy = cover(0, x) * wy;
                let (tv, ta) = lv.at((x as i64).min(lv.size as i64 - 1), (y as i64).min(lv.size as i64 - 1));
                if wxy > 0.0 {
                    v += wxy * tv;
                    a += wxy * ta;
                    big = big.max(tv.abs());
                }
            }
        }
        let area = (hi[0] - lo[0]) * (hi[1] - lo[1]);
        Some((v / area, a / area, big))
    }

    /// `nearest` on a table: the texel's value from four entries, with what the table's
    /// storage adds (an f32 table's four entries' rounding and three f32 subtractions of
    /// entries that large; a fixed-point table's decode).
    fn table_texel(&self, p: [f64; 2], margin: f64, model: Model) -> (f64, f64) {
        let (v, a) = self.nearest(p, margin);
        let extra = match self.sat.as_ref().map(|t| &t.kind) {
            None | Some(TableModel::Codes) => 0.0,
            Some(TableModel::Fixed { lo }) => 4.0 * model.ulp(v - lo) + 2.0 * model.ulp(v),
            Some(TableModel::Float { err, csums, .. }) => {
                let n = self.base().size;
                let row = n + 1;
                // the texel (i, j) is entries (i + 1, j + 1) less its left and upper neighbours
                let (i, j) = (
                    p[0].floor().clamp(0.0, n as f64 - 1.0) as usize,
                    p[1].floor().clamp(0.0, n as f64 - 1.0) as usize,
                );
                // within `margin` of a boundary the neighbour may be read: take the worse
                let (i1, j1) = ((i + 2).min(n), (j + 2).min(n));
                let (mut e, mut big) = (0.0f64, 0.0f64);
                for b in j.saturating_sub(1)..=j1 {
                    for a in i.saturating_sub(1)..=i1 {
                        e = e.max(err[b * row + a]);
                        big = big.max(csums[b * row + a].abs());
                    }
                }
                4.0 * e + 8.0 * model.ulp(big) + 2.0 * model.ulp(v)
            }
        };
        (v, a + extra)
    }
}

/// The table the GPU builds over `base` (a channel stored in `slot`) as `code` says: the
/// texels' values (clamped to the range a fixed-point code spans) and allowances (half a
/// code step more there; under [`Rounding::Stored`] rounded to the code, `round((v - lo)
/// / (hi - lo) (2^B - 1))`, as the GPU sums them), and for an f32 table each entry's
/// rounding bound.
fn table(base: &Level, slot: &PlacedSlot, code: crate::back::summed_area::TableCode, rounding: Rounding, model: Model) -> (Level, Table) {
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

/// The value of input `i` in component `k`: a frame-wide one from the frame, a receiver's
/// as the view `at` sees it (`None`: no receiver, outside the Shade), a Geometry
/// fragment's never (`None`: the Geometry passes' outputs are given).
fn input_value(f: &Frame, i: Input, k: usize, at: Option<&At>) -> Option<f64> {
    let n = f.shadow_size as f64;
    let slope = |ndotl: f64| ((1.0 - ndotl * ndotl).max(0.0).sqrt() / ndotl.abs().max(0.01)).min(100.0);
    Some(match i {
        Input::TexelSize => 1.0 / n,
        Input::ShadowSize => n,
        Input::Near => f.near,
        Input::Far => f.far,
        Input::LightSize => f.light_size,
        Input::LightWidth => f.light_width[k.min(1)],
        Input::LightSpread => f.light_spread,
        Input::LightDistant => f.light_distant as i32 as f64,
        Input::Frame => f.frame as f64,
        Input::D => at?.seen.d(),
        Input::DWorld => at?.seen.d_world,
        Input::Uv => at?.seen.uv[k.min(1)],
        Input::Tf => {
            let t = at?.seen.uv[k.min(1)] * n - 0.5;
            t - t.floor()
        }
        Input::NdotL => at?.seen.ndotl,
        Input::Slope => slope(at?.seen.ndotl),
        // the centre's: (texel_world.x D + texel_world.y) / (far - near); a sample's view
        // is perspective: its texel_world.x D / (far - near)
        Input::TexelDepth => {
            let at = at?;
            let s = &at.seen;
            if at.centre {
                (f.texel_world[0] * s.d_world + f.texel_world[1]) / (f.far - f.near)
            } else {
                s.texel_world * s.d_world / (s.far - s.near)
            }
        }
        Input::DepthSlope => at?.seen.depth_slope,
        Input::SegmentBefore => at?.seen.weights[0],
        Input::SegmentAfter => at?.seen.weights[1],
        Input::Pixel => at?.pixel[k.min(1)],
        Input::ZFrag
        | Input::ZVertex
        | Input::ConeRadius
        | Input::ZSurface
        | Input::OccluderDepth
        | Input::PenumbraLimit
        | Input::LimitDepth
        | Input::Skin => return None,
    })
}

/// A receiver as one view sees it, for [`input_value`].
struct At {
    seen: Seen,
    /// The light's centre view (not a light sample's).
    centre: bool,
    pixel: [f64; 2],
}

/// `noise(x, y, k)`: PCG3D of the three integers (`builtins::NOISE_WGSL`), top 24 bits.
pub fn noise(x: f64, y: f64, k: f64) -> f64 {
    let u = |v: f64| v.floor() as i32 as u32;
    let mut v = [u(x), u(y), u(k)];
    for c in &mut v {
        *c = c.wrapping_mul(1664525).wrapping_add(1013904223);
    }
    let mix = |v: &mut [u32; 3]| {
        v[0] = v[0].wrapping_add(v[1].wrapping_mul(v[2]));
        v[1] = v[1].wrapping_add(v[2].wrapping_mul(v[0]));
        v[2] = v[2].wrapping_add(v[0].wrapping_mul(v[1]));
    };
    mix(&mut v);
    for c in &mut v {
        *c ^= *c >> 16;
    }
    mix(&mut v);
    (v[0] >> 8) as f64 / 16_777_216.0
}

/// The light-side function `uv_width(len, dist)`.
fn uv_width(f: &Frame, len: f64, dist: f64) -> f64 {
    len / ((f.texel_world[0] * dist + f.texel_world[1]) * f.shadow_size as f64)
}

/// A leaf's value and allowance in component `i`, given the values computed so far.
type LeafAllowed<'a> = dyn Fn(ExprId, usize, &[[f64; 4]]) -> Option<(f64, f64)> + 'a;

/// An expression prepared for repeated evaluation: its root and its nodes in postorder.
struct Prepared {
    root: ExprId,
    order: Vec<ExprId>,
}

impl Prepared {
    fn new(p: &Program, root: ExprId) -> Prepared {
        Prepared {
            root,
            order: p.arena.postorder(&[root]),
        }
    }
}

/// A technique's passes after Depth evaluated on one depth map.
pub struct Evaluation<'p> {
    p: Program<'p>,
    frame: Frame,
    /// Every stored channel, one entry per view (the centre's alone, or one per sample).
    texels: HashMap<(ResId, ChannelId), Vec<Texels>>,
    shade: Prepared,
    /// The views of the Shade's filtered lookups (`None`: the centre's): each is shifted by
    /// the filtering hardware's positions on its own.
    filtered: Vec<Option<u8>>,
    model: Model,
    /// Per Map channel with a declared range: the texels whose value it clamped.
    clamped: Vec<(ChannelId, usize)>,
    /// The Shade's debug outputs (where the build has them), each with the views of its
    /// filtered lookups.
    debug: Vec<(Prepared, Vec<Option<u8>>)>,
}

impl<'p> Evaluation<'p> {
    /// The channels whose declared range clamped some stored value: their names and how
    /// many texels (what `sshc verify` reports).
    pub fn clamped(&self) -> Vec<(String, usize)> {
        self.clamped.iter().map(|(c, n)| (self.p.channels[*c].name.clone(), *n)).collect()
    }

    /// Run every pass after Depth and Geometry, whose outputs are `given` (`size` x `size`
    /// texels per view, row 0 first).
    pub fn new(p: Program<'p>, given: &Given, frame: Frame, rounding: Rounding, model: Model) -> Result<Evaluation<'p>, String> {
        let shade = Prepared::new(&p, p.shade().ok_or("the technique has no live Shade pass")?);
        let filtered = filtered_views(&p, &shade.order);
        let debug = p
            .debug
            .iter()
            .map(|d| {
                let e = Prepared::new(&p, d.expr);
                let views = filtered_views(&p, &e.order);
                (e, views)
            })
            .collect();
        let mut ev = Evaluation {
            p,
            frame,
            texels: HashMap::new(),
            shade,
            filtered,
            model,
            clamped: Vec::new(),
            debug,
        };
        for (id, pass) in p.passes.with_handles() {
            if !pass.live {
                continue;
            }
            ev.run_pass(id, given, rounding)?;
        }
        Ok(ev)
    }

    fn slots(&self, r: ResId) -> Vec<PlacedSlot> {
        self.p.resources[r].slots.clone()
    }

    fn source(&self, pass: PassId) -> Result<ResId, String> {
        self.p.passes[pass]
            .reads
            .first()
            .copied()
            .ok_or_else(|| format!("pass `{}` reads nothing", self.p.passes[pass].name))
    }

    /// The maps given for channel `c` of `r`, checked: one per view, each `size` x `size`.
    fn given<'g>(&self, given: &'g Given, pass: PassId, r: ResId, c: ChannelId) -> Result<&'g [Vec<f64>], String> {
        let size = self.frame.shadow_size as usize;
        let views = if self.p.per_sample(r) { self.p.samples as usize } else { 1 };
        let what = || format!("channel `{}` of pass `{}`", self.p.channels[c].name, self.p.passes[pass].name);
        let maps = given.maps.get(&(r, c)).ok_or_else(|| format!("{} is not given", what()))?;
        if maps.len() != views {
            return Err(format!("{} is given {} view(s), not {views}", what(), maps.len()));
        }
        if let Some(m) = maps.iter().find(|m| size == 0 || m.len() != size * size) {
            return Err(format!("{} is given a map of {} values, not {size} x {size}", what(), m.len()));
        }
        Ok(maps)
    }

    fn run_pass(&mut self, id: PassId, given: &Given, rounding: Rounding) -> Result<(), String> {
        let pass = &self.p.passes[id];
        let Some(out) = pass.writes else { return Ok(()) };
        let size = self.frame.shadow_size as usize;
        let keep = |slot: &PlacedSlot, v: f64| match rounding {
            Rounding::Exact => v,
            Rounding::Stored => stored(slot, v),
        };
        match &pass.kind {
            // given: a Depth output as the caller gives it (a synthetic field is stored as
            // the slot stores it), a Geometry output read back as the GPU stored it (exact,
            // but for a unorm code's conversion to f32 in the shader: `k * (1 / 255)` on
            // lavapipe, an ulp from `k / 255`)
            IrPassKind::Depth { .. } | IrPassKind::Geometry { .. } => {
                let read_back = matches!(pass.kind, IrPassKind::Geometry { .. });
                for slot in self.slots(out) {
                    let unorm = matches!(slot.precision, Precision::Unorm8 | Precision::Unorm16);
                    let allow = |x: f64| match (read_back, unorm) {
                        (false, _) => self.model.storage(&slot, x),
                        (true, true) => self.model.ulp(x),
                        (true, false) => 0.0,
                    };
                    let views = self
                        .given(given, id, out, slot.channel)?
                        .iter()
                        .map(|map| {
                            let v: Vec<f64> = map.iter().map(|&x| if read_back { x } else { keep(&slot, x) }).collect();
                            let a = v.iter().map(|&x| allow(x)).collect();
                            Texels::new(vec![Level { size, v, a }], &slot)
                        })
                        .collect();
                    self.texels.insert((out, slot.channel), views);
                }
            }
            IrPassKind::Map => {
                for slot in self.slots(out) {
                    let (level, clamped) = self.map_channel(id, &slot, size, rounding)?;
                    if clamped > 0 {
                        self.clamped.push((slot.channel, clamped));
                    }
                    self.insert(out, &slot, vec![level]);
                }
            }
            IrPassKind::Filter { kernel } => {
                let src = self.source(id)?;
                for slot in self.slots(out) {
                    let base = self.read(src, slot.channel)?.base().clone();
                    let level = filter(&base, kernel, &slot, rounding, self.model);
                    self.insert(out, &slot, vec![level]);
                }
            }
            IrPassKind::Mipmap { reduce } => {
                let src = self.source(id)?;
                for slot in self.slots(out) {
                    let base = self.read(src, slot.channel)?.base().clone();
                    let levels = mip_chain(base, *reduce, &slot, rounding, self.model);
                    self.insert(out, &slot, levels);
                }
            }
            IrPassKind::SummedArea { .. } => {
                let src = self.source(id)?;
                for slot in self.slots(out) {
                    let base = self.read(src, slot.channel)?.base().clone();
                    let code = crate::back::summed_area::table_code(&self.p, out, slot.texture).map_err(|d| d.message.clone())?;
                    let (base, sat) = table(&base, &slot, code, rounding, self.model);
                    let texels = Texels {
                        sat: Some(sat),
                        ..Texels::new(vec![base], &slot)
                    };
                    self.texels.insert((out, slot.channel), vec![texels]);
                }
            }
            IrPassKind::Shade { .. } => {}
        }
        Ok(())
    }

    fn insert(&mut self, r: ResId, slot: &PlacedSlot, levels: Vec<Level>) {
        self.texels.insert((r, slot.channel), vec![Texels::new(levels, slot)]);
    }

    /// The centre's texels of a channel (Map, Filter, Mipmap and SummedArea passes read no
    /// per-sample resource).
    fn read(&self, r: ResId, c: ChannelId) -> Result<&Texels, String> {
        self.texels.get(&(r, c)).and_then(|v| v.first()).ok_or_else(|| {
            format!(
                "channel `{}` of `{}` is read before it is written",
                self.p.channels[c].name, self.p.resources[r].name
            )
        })
    }

    /// One Map channel at every texel: value and allowance (with its storage's rounding).
    /// A Map channel's texels, and how many were clamped to its declared range.
    fn map_channel(&self, pass: PassId, slot: &PlacedSlot, size: usize, rounding: Rounding) -> Result<(Level, usize), String> {
        let mut clamped = 0;
        let c = slot.channel;
        let h = self.p.channels[c]
            .value
            .ok_or_else(|| format!("channel `{}` has no value", self.p.channels[c].name))?;
        let prepared = Prepared::new(&self.p, h);
        // the resources this pass reads, by the channels they carry
        let mut from: HashMap<ChannelId, &Texels> = HashMap::new();
        for &r in &self.p.passes[pass].reads {
            for s in &self.p.resources[r].slots {
                if let Some(t) = self.texels.get(&(r, s.channel)).and_then(|v| v.first()) {
                    from.entry(s.channel).or_insert(t);
                }
            }
        }
        let mut scratch = Scratch::default();
        scratch.fit(self.p.arena.len());
        let (mut v, mut a) = (Vec::with_capacity(size * size), Vec::with_capacity(size * size));
        for y in 0..size as i64 {
            for x in 0..size as i64 {
                let leaf = |h: ExprId, k: usize, _: &[[f64; 4]]| -> Option<(f64, f64)> {
                    match self.p.arena.node(h) {
                        Node::Channel(ch, [dx, dy]) => from.get(ch).map(|t| t.texel(x + *dx as i64, y + *dy as i64)),
                        Node::Input(i, _) => input_value(&self.frame, *i, k, None).map(|v| (v, 0.0)),
                        Node::Param(id) => Some((self.p.params[*id].value.as_f64(), 0.0)),
                        Node::Sample { .. } => None,
                        Node::F32(_)
                        | Node::I32(_)
                        | Node::U32(_)
                        | Node::Bool(_)
                        | Node::Unary(..)
                        | Node::Binary(..)
                        | Node::Call(..)
                        | Node::Swizzle(..) => None,
                    }
                };
                let r = self.allowed(&prepared, &leaf, &mut scratch);
                // a declared range: clamped to it when stored (1-Lipschitz: the allowance holds)
                let value = match self.p.channels[c].range {
                    Some((lo, hi)) => {
                        let kept = r.value.clamp(lo, hi);
                        clamped += usize::from(kept != r.value);
                        kept
                    }
                    None => r.value,
                };
                v.push(match rounding {
                    Rounding::Exact => value,
                    Rounding::Stored => stored(slot, value),
                });
                a.push(r.allowance + self.model.storage(slot, value));
            }
        }
        Ok((Level { size, v, a }, clamped))
    }

    /// The clamped visibility at one receiver and the interval allowed about it.
    pub fn visibility(&self, r: &Receiver, scratch: &mut Scratch) -> Allowed {
        scratch.fit(self.p.arena.len());
        let mut out = self.allowed(&self.shade, &self.receiver_leaf(r, Shift::NONE), scratch);
        if self.model == Model::F64 {
            return out;
        }
        // the filtering hardware's 8-bit positions and level fractions, one axis at a time,
        // the lookups of each view together (each view reads its own positions)
        let texel = FILTER_SHIFT / self.frame.shadow_size as f64;
        let mut extra = 0.0;
        for &view in &self.filtered {
            for axis in 0..3 {
                let mut worst: f64 = 0.0;
                for sign in [1.0, -1.0] {
                    let mut by = [0.0; 3];
                    by[axis] = sign * if axis == 2 { FILTER_SHIFT } else { texel };
                    worst = worst.max(change(self.raw(r, Shift { view, by }, scratch), out.raw));
                }
                extra += worst;
            }
        }
        out.widen(extra, true);
        out
    }

    /// The raw visibility (NaN read as 1) at `r` with filtered lookups shifted by `shift`.
    fn raw(&self, r: &Receiver, shift: Shift, scratch: &mut Scratch) -> f64 {
        raw_visibility(self.shifted(&self.shade, r, shift, scratch)[0])
    }

    /// The value of `e` at `r` with filtered lookups shifted by `shift`.
    fn shifted(&self, e: &Prepared, r: &Receiver, shift: Shift, scratch: &mut Scratch) -> [f64; 4] {
        let leaf = self.receiver_leaf(r, shift);
        let plain = |h: ExprId, k: usize, vals: &[[f64; 4]]| leaf(h, k, vals).map(|(v, _)| v);
        self.p
            .arena
            .eval_span(&e.order, &Hooks { leaf: &plain, exact: true }, &mut scratch.vals);
        scratch.vals.get(e.root.index()).copied().unwrap_or([f64::NAN; 4])
    }

    /// Debug outputs this evaluation has (the build's, `CompileOptions::debug`): their names.
    pub fn debug_names(&self) -> Vec<&str> {
        self.p.debug.iter().map(|d| d.name.as_str()).collect()
    }

    /// Debug output `i` at one receiver: each component's value (unclamped, NaN kept) and
    /// the interval allowed about it, by the visibility's error model (a running bound
    /// node by node, widened by the filtering hardware's positions).
    pub fn debug(&self, i: usize, r: &Receiver, scratch: &mut Scratch) -> Vec<Allowed> {
        let Some((e, views)) = self.debug.get(i) else { return Vec::new() };
        scratch.fit(self.p.arena.len());
        self.allowed(e, &self.receiver_leaf(r, Shift::NONE), scratch);
        let width = match self.p.arena.ty(e.root) {
            Ty::Vec(n) => usize::from(n).clamp(1, 4),
            Ty::F32 | Ty::I32 | Ty::U32 | Ty::Bool | Ty::AbstractInt => 1,
        };
        let v = scratch.vals.get(e.root.index()).copied().unwrap_or([f64::NAN; 4]);
        let err = scratch.errors.get(e.root.index()).copied().unwrap_or([f64::INFINITY; 4]);
        let mut out: Vec<Allowed> = (0..width)
            .map(|k| {
                let mut a = Allowed::new(v[k], false);
                a.widen(err[k], false);
                a
            })
            .collect();
        if self.model == Model::F64 {
            return out;
        }
        let texel = FILTER_SHIFT / self.frame.shadow_size as f64;
        for &view in views {
            for axis in 0..3 {
                let mut worst = [0.0f64; 4];
                for sign in [1.0, -1.0] {
                    let mut by = [0.0; 3];
                    by[axis] = sign * if axis == 2 { FILTER_SHIFT } else { texel };
                    let moved = self.shifted(e, r, Shift { view, by }, scratch);
                    for k in 0..width {
                        worst[k] = worst[k].max(change(moved[k], v[k]));
                    }
                }
                for (a, w) in out.iter_mut().zip(worst) {
                    a.widen(w, false);
                }
            }
        }
        out
    }

    /// The clamped visibility at one receiver, without its allowance.
    pub fn value(&self, r: &Receiver, scratch: &mut Scratch) -> f64 {
        scratch.fit(self.p.arena.len());
        self.raw(r, Shift::NONE, scratch).clamp(0.0, 1.0)
    }

    /// The leaf values of the Shade at receiver `r`: inputs, params, the frame's functions,
    /// lookups (with their allowance); inside `at_sample(k, ..)`, as light sample k sees it.
    fn receiver_leaf<'a>(&'a self, r: &'a Receiver, shift: Shift) -> impl Fn(ExprId, usize, &[[f64; 4]]) -> Option<(f64, f64)> + 'a {
        let f = &self.frame;
        let n = f.shadow_size as f64;
        let centre = Seen {
            uv: r.uv,
            d_world: r.d_world,
            near: f.near,
            far: f.far,
            ndotl: r.ndotl,
            depth_slope: r.depth_slope,
            lod: r.lod,
            texel_world: f.texel_world[0],
            weights: [0.0; 2],
        };
        move |h: ExprId, k: usize, vals: &[[f64; 4]]| -> Option<(f64, f64)> {
            let arg = |h: &ExprId, c: usize| vals.get(h.index()).map_or(f64::NAN, |v| v[c]);
            let seen = |view: &Option<u8>| match view {
                Some(s) => r.samples.get(*s as usize).copied(),
                None => Some(centre),
            };
            match self.p.arena.node(h) {
                Node::Input(i, view) => {
                    let at = At {
                        seen: seen(view)?,
                        centre: view.is_none(),
                        pixel: r.pixel,
                    };
                    let v = input_value(f, *i, k, Some(&at))?;
                    Some((v, 0.0))
                }
                Node::Param(id) => Some((self.p.params[*id].value.as_f64(), 0.0)),
                Node::Call(Func::UvWidth, a) => Some((uv_width(f, arg(&a[0], 0), arg(&a[1], 0)), 0.0)),
                Node::Call(Func::Noise, a) => Some((noise(arg(&a[0], 0), arg(&a[1], 0), arg(&a[2], 0)), 0.0)),
                Node::Sample {
                    channel,
                    resource,
                    how,
                    args,
                    view,
                } => {
                    let t = self.texels.get(&(*resource, *channel))?.get(view.map_or(0, usize::from))?;
                    let s = seen(view)?;
                    let a = |i: usize| args.get(i).map_or(f64::NAN, |h| arg(h, 0));
                    let margin = match self.model {
                        Model::Gpu => n * 4.0 * input_error(Input::Uv, 0.0),
                        Model::F64 => 0.0,
                    };
                    let texel = |uv: [f64; 2]| t.table_texel([uv[0] * n, uv[1] * n], margin, self.model);
                    let by = if shift.view == *view { shift.by } else { [0.0; 3] };
                    let at = [s.uv[0] + by[0], s.uv[1] + by[1]];
                    Some(match how {
                        SampleFn::Sample => t.filtered(at, s.lod + by[2]),
                        SampleFn::SampleLod => t.filtered(at, a(0) + by[2]),
                        SampleFn::SampleWidth => t.filtered(at, (a(0) * n).max(1.0).log2() + by[2]),
                        SampleFn::SampleAt => t.filtered([at[0] + a(0), at[1] + a(1)], by[2]),
                        SampleFn::Nearest => texel(s.uv),
                        SampleFn::NearestAt => texel([s.uv[0] + a(0), s.uv[1] + a(1)]),
                        SampleFn::Fetch => t.nearest([s.uv[0] * n - 0.5 + a(0), s.uv[1] * n - 0.5 + a(1)], margin),
                        SampleFn::Box => t.boxed(s.uv, [a(0), a(1)], self.model),
                        SampleFn::BoxAt => t.boxed([s.uv[0] + a(0), s.uv[1] + a(1)], [a(2), a(3)], self.model),
                        SampleFn::SampleWidthAt => t.filtered([at[0] + a(0), at[1] + a(1)], (a(2) * n).max(1.0).log2() + by[2]),
                        SampleFn::NearestLevel => t.nearest_level(s.uv, a(0), margin),
                        SampleFn::NearestLevelAt => t.nearest_level([s.uv[0] + a(1), s.uv[1] + a(2)], a(0), margin),
                        SampleFn::MipBox => t.mip_box(s.uv, a(0), margin, self.model),
                        SampleFn::MipBoxAt => t.mip_box([s.uv[0] + a(0), s.uv[1] + a(1)], a(2), margin, self.model),
                    })
                }
                Node::Channel(..)
                | Node::F32(_)
                | Node::I32(_)
                | Node::U32(_)
                | Node::Bool(_)
                | Node::Unary(..)
                | Node::Binary(..)
                | Node::Call(..)
                | Node::Swizzle(..) => None,
            }
        }
    }

    /// Evaluate `e` with `leaf` (value and allowance of leaves), then bound its error
    /// node by node (a running error analysis, in postorder): a node's error is its own
    /// (the lookup's or input's allowance, f32 rounding, the built-in's bound) plus, for each
    /// operand, the largest change of the node when that operand alone moves by its error
    /// either way (a bool operand that may flip: flipped). A clamp, a `select` or a
    /// comparison therefore passes on exactly what its operands' errors can do to it. The
    /// Shade's interval is its raw value (NaN read as 1) widened by the root's error, then
    /// clamped.
    fn allowed(&self, e: &Prepared, leaf: &LeafAllowed, scratch: &mut Scratch) -> Allowed {
        let arena = &self.p.arena;
        // the visibility (a debug output may be the same node, and is not clamped)
        let shade = std::ptr::eq(e, &self.shade);
        let plain = |h: ExprId, k: usize, vals: &[[f64; 4]]| leaf(h, k, vals).map(|(v, _)| v);
        let Scratch { vals, errors } = scratch;
        let hooks = Hooks { leaf: &plain, exact: true };
        arena.eval_span(&e.order, &hooks, vals);
        let width = |h: ExprId| match arena.ty(h) {
            Ty::Vec(n) => (n as usize).clamp(1, 4),
            Ty::F32 | Ty::I32 | Ty::U32 | Ty::Bool | Ty::AbstractInt => 1,
        };
        let mut operands: Vec<ExprId> = Vec::new();
        for &h in &e.order {
            let v = vals.get(h.index()).copied().unwrap_or([f64::NAN; 4]);
            let w = width(h);
            let model = self.model;
            let ulp = |k: usize| model.ulp(v[k]);
            let float = matches!(arena.ty(h), Ty::F32 | Ty::Vec(_));
            // the node's own error, per component
            let mut err = [0.0f64; 4];
            for (k, x) in err.iter_mut().enumerate().take(w) {
                *x = match arena.node(h) {
                    Node::Input(..) | Node::Sample { .. } | Node::Channel(..) | Node::Param(_) => {
                        let own = leaf(h, k, vals).map_or(0.0, |(_, a)| a);
                        match arena.node(h) {
                            Node::Input(i, _) if model == Model::Gpu => own + input_error(*i, v[k]),
                            Node::Input(..) => own,
                            Node::F32(_)
                            | Node::I32(_)
                            | Node::U32(_)
                            | Node::Bool(_)
                            | Node::Param(_)
                            | Node::Channel(..)
                            | Node::Sample { .. }
                            | Node::Unary(..)
                            | Node::Binary(..)
                            | Node::Call(..)
                            | Node::Swizzle(..) => own,
                        }
                    }
                    // f32's add, subtract and multiply are correctly rounded: exact operands
                    // with a result f32 holds give that result exactly
                    Node::Binary(BinOp::Add | BinOp::Sub | BinOp::Mul, x, y)
                        if float
                            && v[k] as f32 as f64 == v[k]
                            && [x, y]
                                .iter()
                                .all(|o| errors.get(o.index()).is_some_and(|e| e.iter().all(|e| *e == 0.0))) =>
                    {
                        0.0
                    }
                    Node::Binary(BinOp::Add | BinOp::Sub | BinOp::Mul, ..) if float => ulp(k),
                    Node::Binary(BinOp::Div, ..) if float => 3.0 * ulp(k),
                    Node::Call(f, a) if float => {
                        let arg = |i: usize| a.get(i).and_then(|x| vals.get(x.index())).map_or(0.0, |x| x[k]);
                        match (model, call_error(*f, v[k], &[arg(0), arg(1)])) {
                            (_, None) => 0.0,
                            (Model::Gpu, Some(e)) => e + ulp(k),
                            (Model::F64, Some(_)) => 4.0 * ulp(k),
                        }
                    }
                    Node::F32(_)
                    | Node::I32(_)
                    | Node::U32(_)
                    | Node::Bool(_)
                    | Node::Unary(..)
                    | Node::Binary(..)
                    | Node::Call(..)
                    | Node::Swizzle(..) => 0.0,
                };
            }
            // a value that is not a number stays one whatever moves it; a number whose
            // own error is not a number may be anything
            for k in 0..w {
                if err[k].is_nan() {
                    err[k] = if v[k].is_nan() { 0.0 } else { f64::INFINITY };
                }
            }
            // what each operand's error can do to it
            operands.clear();
            match arena.node(h) {
                Node::Unary(_, x) | Node::Swizzle(x, _) => operands.push(*x),
                Node::Binary(_, x, y) => operands.extend([*x, *y]),
                Node::Call(_, a) | Node::Sample { args: a, .. } => operands.extend(a.iter().copied()),
                Node::F32(_) | Node::I32(_) | Node::U32(_) | Node::Bool(_) | Node::Param(_) | Node::Input(..) | Node::Channel(..) => {}
            }
            operands.dedup();
            for &x in &operands {
                let ex = errors.get(x.index()).copied().unwrap_or([0.0; 4]);
                if ex.iter().all(|e| *e == 0.0) {
                    continue;
                }
                // an operand that may be anything makes this node anything
                if ex.iter().take(width(x)).any(|e| e.is_infinite()) {
                    for e in err.iter_mut().take(w) {
                        *e = f64::INFINITY;
                    }
                    continue;
                }
                let keep = vals[x.index()];
                // a bool flips; a number moves one component at a time, both ways (moving
                // every component together would hide what cancels between them)
                let moves: Vec<[f64; 4]> = if arena.ty(x) == Ty::Bool {
                    vec![keep.map(|b| if b != 0.0 { 0.0 } else { 1.0 })]
                } else {
                    let wx = width(x);
                    let mut m = Vec::with_capacity(2 * wx);
                    for k in (0..wx).filter(|&k| ex[k] != 0.0) {
                        for by in [ex[k], -ex[k]] {
                            let mut moved = keep;
                            if wx == 1 {
                                // a scalar is held in every component
                                moved = [keep[0] + by; 4];
                            } else {
                                moved[k] += by;
                            }
                            m.push(moved);
                        }
                    }
                    m
                };
                // per moved component: the largest change of each of this node's components,
                // summed over the operand's components (first order in each)
                let mut total = [0.0f64; 4];
                for pair in moves.chunks(if arena.ty(x) == Ty::Bool { 1 } else { 2 }) {
                    let mut worst = [0.0f64; 4];
                    for m in pair {
                        vals[x.index()] = *m;
                        let moved = arena.eval_node(h, &hooks, vals);
                        for k in 0..w {
                            worst[k] = worst[k].max(change(moved[k], v[k]));
                        }
                    }
                    for k in 0..w {
                        total[k] += worst[k];
                    }
                }
                vals[x.index()] = keep;
                for k in 0..w {
                    err[k] += total[k];
                }
            }
            // a `select` whose condition may flip takes either branch with its own error
            if let Node::Call(Func::Select | Func::Branch, a) = arena.node(h)
                && let [f, t, c] = a.as_slice()
                && errors.get(c.index()).is_some_and(|e| e[0] > 0.0)
            {
                let (ef, et) = (errors[f.index()], errors[t.index()]);
                for k in 0..w {
                    err[k] += ef[k].max(et[k]);
                }
            }
            if w == 1 {
                err = [err[0]; 4];
            }
            if let Some(slot) = errors.get_mut(h.index()) {
                *slot = err;
            }
        }
        let root = vals.get(e.root.index()).map_or(f64::NAN, |v| v[0]);
        let error = errors.get(e.root.index()).map_or(f64::INFINITY, |v| v[0]);
        let mut out = Allowed::new(if shade { raw_visibility(root) } else { root }, shade);
        out.widen(error, shade);
        out
    }
}

/// The views (`None`: the centre's) of the filtered lookups among `order`'s nodes: each is
/// shifted by the filtering hardware's positions on its own.
fn filtered_views(p: &Program, order: &[ExprId]) -> Vec<Option<u8>> {
    let mut filtered: Vec<Option<u8>> = Vec::new();
    for &h in order {
        if let Node::Sample { how, view, .. } = p.arena.node(h)
            && matches!(
                how,
                SampleFn::Sample | SampleFn::SampleLod | SampleFn::SampleWidth | SampleFn::SampleAt | SampleFn::SampleWidthAt
            )
            && !filtered.contains(view)
        {
            filtered.push(*view);
        }
    }
    filtered
}

/// The filtering hardware's error as one shift of the filtered lookups of one view: uv by
/// `by[..2]`, the level of detail by `by[2]`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Shift {
    view: Option<u8>,
    by: [f64; 3],
}

impl Shift {
    const NONE: Shift = Shift { view: None, by: [0.0; 3] };
}

/// How far a value moved: 0 between two NaNs, infinite from a number to a NaN.
fn change(moved: f64, v: f64) -> f64 {
    if moved == v || (moved.is_nan() && v.is_nan()) {
        0.0
    } else {
        let c = (moved - v).abs();
        if c.is_nan() { f64::INFINITY } else { c }
    }
}

/// The Shade's raw visibility as the runtime reads it before clamping: NaN as 1.
fn raw_visibility(v: f64) -> f64 {
    if v.is_nan() { 1.0 } else { v }
}

/// Scratch space of [`Evaluation::visibility`], one per thread: values and errors by node.
#[derive(Default)]
pub struct Scratch {
    vals: Vec<[f64; 4]>,
    errors: Vec<[f64; 4]>,
}

impl Scratch {
    fn fit(&mut self, nodes: usize) {
        self.vals.resize(nodes, [f64::NAN; 4]);
        self.errors.resize(nodes, [0.0; 4]);
    }
}

/// A Filter pass over one level: separable kernels along x then y through an intermediate
/// at the scratch precision, the Laplacian in one step; allowances carried through.
fn filter(src: &Level, kernel: &IrKernel, slot: &PlacedSlot, rounding: Rounding, model: Model) -> Level {
    let n = src.size as i64;
    let scratch = crate::back::formats::scratch_precision(slot.precision);
    let keep = |v: f64, p: Precision| match rounding {
        Rounding::Exact => v,
        Rounding::Stored => stored_at(p, slot.encode.bias, slot.encode.scale, v),
    };
    let step_at = |v: f64, p: Precision| model.storage(&PlacedSlot { precision: p, ..*slot }, v);
    let out = |f: &dyn Fn(i64, i64) -> (f64, f64), p: Precision| -> Level {
        let mut l = Level {
            size: src.size,
            v: Vec::with_capacity(src.v.len()),
            a: Vec::with_capacity(src.v.len()),
        };
        for y in 0..n {
            for x in 0..n {
                let (v, a) = f(x, y);
                l.v.push(keep(v, p));
                l.a.push(a + step_at(v, p) + 4.0 * model.ulp(v));
            }
        }
        l
    };
    match kernel {
        IrKernel::LoG => out(
            &|x, y| {
                let (mut v, mut a) = (0.0, 0.0);
                for (k, w) in IrKernel::LOG_3X3.iter().enumerate() {
                    let (tv, ta) = src.at(x + k as i64 % 3 - 1, y + k as i64 / 3 - 1);
                    v += w * tv;
                    a += w.abs() * ta;
                }
                (v, a)
            },
            slot.precision,
        ),
        IrKernel::Box(_) | IrKernel::Gaussian(..) | IrKernel::Max(_) | IrKernel::Min(_) => {
            let r = (kernel.size() as i64 - 1) / 2;
            let weights = kernel.weights_1d();
            let axis = |l: &Level, dx: i64, dy: i64, p: Precision| {
                out(
                    &|x, y| match &weights {
                        Some(w) => {
                            let (mut v, mut a) = (0.0, 0.0);
                            for (k, wk) in w.iter().enumerate() {
                                let o = k as i64 - r;
                                let (tv, ta) = l.at(x + o * dx, y + o * dy);
                                v += wk * tv;
                                a += wk * ta;
                            }
                            (v, a)
                        }
                        None => {
                            let mut best: Option<(f64, f64)> = None;
                            for o in -r..=r {
                                let t = l.at(x + o * dx, y + o * dy);
                                let better = match (best, kernel) {
                                    (None, _) => true,
                                    (Some(b), IrKernel::Min(_)) => t.0 < b.0,
                                    (Some(b), IrKernel::Max(_) | IrKernel::Box(_) | IrKernel::Gaussian(..) | IrKernel::LoG) => t.0 > b.0,
                                };
                                if better {
                                    best = Some(t);
                                }
                            }
                            // the allowance of the window's largest, as any texel near the extreme may win
                            let amax = (-r..=r).map(|o| l.at(x + o * dx, y + o * dy).1).fold(0.0, f64::max);
                            best.map_or((f64::NAN, 0.0), |b| (b.0, amax))
                        }
                    },
                    p,
                )
            };
            let mid = axis(src, 1, 0, scratch);
            axis(&mid, 0, 1, slot.precision)
        }
    }
}

/// Levels down to 1 x 1, each texel reducing the 2 x 2 below it (clamped at an odd edge).
fn mip_chain(base: Level, reduce: Reduce, slot: &PlacedSlot, rounding: Rounding, model: Model) -> Vec<Level> {
    let mut levels = vec![base];
    while let Some(prev) = levels.last().filter(|l| l.size > 1) {
        let size = (prev.size / 2).max(1);
        let mut l = Level {
            size,
            v: Vec::with_capacity(size * size),
            a: Vec::with_capacity(size * size),
        };
        for y in 0..size as i64 {
            for x in 0..size as i64 {
                let t = [
                    prev.at(2 * x, 2 * y),
                    prev.at(2 * x + 1, 2 * y),
                    prev.at(2 * x, 2 * y + 1),
                    prev.at(2 * x + 1, 2 * y + 1),
                ];
                let amax = t.iter().map(|t| t.1).fold(0.0, f64::max);
                let (v, a) = match reduce {
                    Reduce::Mean => (t.iter().map(|t| t.0).sum::<f64>() * 0.25, t.iter().map(|t| t.1).sum::<f64>() * 0.25),
                    Reduce::Max => (t.iter().map(|t| t.0).fold(f64::NEG_INFINITY, f64::max), amax),
                    Reduce::Min => (t.iter().map(|t| t.0).fold(f64::INFINITY, f64::min), amax),
                };
                l.v.push(match rounding {
                    Rounding::Exact => v,
                    Rounding::Stored => stored(slot, v),
                });
                l.a.push(a + model.storage(slot, v) + 2.0 * model.ulp(v));
            }
        }
        levels.push(l);
    }
    levels
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ir::Program;

    fn compiled(src: &str) -> crate::Compiled {
        crate::compile_str(src, &crate::CompileOptions::default()).unwrap_or_else(|d| panic!("{}", d.render("t.ron", src)))
    }

    fn frame(n: u32) -> Frame {
        Frame {
            shadow_size: n,
            near: 8.0,
            far: 12.0,
            light_size: 0.0,
            light_width: [0.0; 2],
            light_spread: 0.0,
            light_distant: true,
            texel_world: [0.0, 2.0 / n as f64],
            frame: 0,
        }
    }

    /// A receiver at the centre of the map at normalised depth `d` (no slope).
    fn receiver(d: f64) -> Receiver {
        Receiver {
            uv: [0.5 + 1.0 / 64.0, 0.5 + 1.0 / 64.0],
            d_world: 8.0 + 4.0 * d,
            ndotl: 1.0,
            depth_slope: 0.0,
            lod: 0.0,
            pixel: [0.0, 0.0],
            samples: Vec::new(),
        }
    }

    fn depth(p: &Program, map: &[f32]) -> Given {
        Given::depth(p, vec![map.to_vec()])
    }

    #[test]
    fn halves_round_to_nearest_even_with_subnormals_and_overflow() {
        assert_eq!(round_f16(1.0), 1.0);
        // half way between 1 and the next half, 1 + 2^-10: to even (1)
        assert_eq!(round_f16(1.0 + 2f64.powi(-11)), 1.0);
        assert_eq!(round_f16(1.0 + 3.0 * 2f64.powi(-11)), 1.0 + 2.0 * 2f64.powi(-10));
        assert_eq!(round_f16(65504.0), 65504.0);
        assert_eq!(round_f16(70000.0), f64::INFINITY);
        // subnormals are multiples of 2^-24
        assert_eq!(round_f16(2f64.powi(-24)), 2f64.powi(-24));
        assert_eq!(round_f16(0.7 * 2f64.powi(-24)), 2f64.powi(-24));
        assert_eq!(round_f16(-0.3 * 2f64.powi(-24)), 0.0);
    }

    /// Debug outputs evaluate to their closed forms at a receiver: the receiver's depth,
    /// a vector of a lookup and a product, and the visibility's own expression unclamped
    /// (the same node as the visibility, which is clamped); a build without them has none.
    #[test]
    fn debug_outputs_evaluate_unclamped_to_their_closed_forms() {
        let src = r#"Technique(name: "t", channels: { "z": Channel(precision: F32) }, passes: [
            Depth(name: "depth", writes: "shadow", channel: "z"),
            Shade(name: "shade", reads: ["shadow"], visibility: "let k = 4.0; d * k", debug: {
                "depth": "d", "pair": "vec2(sample(z), d * 2.0)", "raw": "d * k",
            }),
        ])"#;
        let opts = crate::CompileOptions {
            debug: true,
            ..Default::default()
        };
        let c = crate::compile_str(src, &opts).unwrap_or_else(|d| panic!("{}", d.render("t.ron", src)));
        let p = Program::new(&c.ir, &c.layout);
        let n = 8;
        let map = vec![0.375f32; (n * n) as usize];
        let ev = Evaluation::new(p, &depth(&p, &map), frame(n), Rounding::Exact, Model::Gpu).unwrap();
        assert_eq!(ev.debug_names(), ["depth", "pair", "raw"]);
        let mut s = Scratch::default();
        let d = 0.75;
        let r = receiver(d);
        let one = |i: usize, s: &mut Scratch| ev.debug(i, &r, s);
        let depth_out = one(0, &mut s);
        assert_eq!(depth_out.len(), 1);
        // d from the receiver's view distance, (d_world - near) / (far - near), in f64
        assert!((depth_out[0].value - d).abs() < 1e-12 && depth_out[0].admits(d), "{depth_out:?}");
        let pair = one(1, &mut s);
        assert_eq!(pair.len(), 2);
        // a constant map filters to its value wherever it is read
        assert!(pair[0].admits(0.375) && (pair[1].value - 2.0 * d).abs() < 1e-12, "{pair:?}");
        let raw = one(2, &mut s);
        assert!((raw[0].value - 4.0 * d).abs() < 1e-12 && raw[0].value > 1.0, "{raw:?}");
        assert_eq!(ev.visibility(&r, &mut s).value, 1.0, "the visibility is clamped");
        // without the option the same source has none
        let plain = compiled(src);
        assert!(plain.ir.debug.is_empty() && plain.ir.debug_omitted == ["depth", "pair", "raw"]);
    }

    #[test]
    fn hard_shadows_evaluate_exactly_and_allow_both_sides_only_at_a_tie() {
        let c = compiled(include_str!("../../techniques/hard.ron"));
        let p = Program::new(&c.ir, &c.layout);
        let n = 8;
        let map = vec![0.5f32; (n * n) as usize];
        let ev = Evaluation::new(p, &depth(&p, &map), frame(n), Rounding::Exact, Model::Gpu).unwrap();
        let mut s = Scratch::default();
        // in front of the occluder: lit; behind it: shadowed; both within f32's reach
        let lit = ev.visibility(&receiver(0.25), &mut s);
        assert_eq!((lit.value, lit.lo, lit.hi), (1.0, 1.0, 1.0), "{lit:?}");
        let dark = ev.visibility(&receiver(0.75), &mut s);
        assert_eq!((dark.value, dark.lo, dark.hi), (0.0, 0.0, 0.0), "{dark:?}");
        // at the occluder's depth the comparison is a tie: either side is allowed
        let bias = c.ir.params.iter().find(|p| p.name == "bias").map_or(0.0, |p| p.value.as_f64());
        let tie = ev.visibility(&receiver(0.5 + bias), &mut s);
        assert_eq!((tie.lo, tie.hi), (0.0, 1.0), "{tie:?}");
    }

    #[test]
    fn storage_rounding_is_what_separates_the_two_evaluations() {
        // ESM's exp(c z) at Unorm8 over [1, e^c]: rounding moves the visibility a lot, and
        // the GPU model's allowance covers the rounded evaluation
        let src = include_str!("../../techniques/esm.ron");
        let opts = crate::CompileOptions {
            precision: vec![("e".into(), "unorm8".into())],
            ..Default::default()
        };
        let c = crate::compile_str(src, &opts).unwrap_or_else(|d| panic!("{}", d.render("esm.ron", src)));
        let p = Program::new(&c.ir, &c.layout);
        let n = 8;
        let map: Vec<f32> = (0..n * n).map(|k| 0.3 + 0.4 * (k % n) as f32 / n as f32).collect();
        let exact = Evaluation::new(p, &depth(&p, &map), frame(n), Rounding::Exact, Model::Gpu).unwrap();
        let rounded = Evaluation::new(p, &depth(&p, &map), frame(n), Rounding::Stored, Model::Gpu).unwrap();
        let mut s = Scratch::default();
        let r = receiver(0.55);
        let e = exact.visibility(&r, &mut s);
        let v = rounded.value(&r, &mut s);
        assert!((v - e.value).abs() > 0.05, "exact {e:?}, rounded {v}");
        assert!(e.admits(v), "exact {e:?}, rounded {v}");
    }

    #[test]
    fn an_f64_model_allows_only_f64_rounding_where_the_math_is_well_conditioned() {
        let c = compiled(include_str!("../../techniques/vsm.ron"));
        let p = Program::new(&c.ir, &c.layout);
        let n = 8;
        let map: Vec<f32> = (0..n * n).map(|k| 0.2 + 0.05 * (k % 7) as f32).collect();
        let gpu = Evaluation::new(p, &depth(&p, &map), frame(n), Rounding::Exact, Model::Gpu).unwrap();
        let f64m = Evaluation::new(p, &depth(&p, &map), frame(n), Rounding::Exact, Model::F64).unwrap();
        let mut s = Scratch::default();
        let r = receiver(0.4);
        let (a, b) = (gpu.visibility(&r, &mut s), f64m.visibility(&r, &mut s));
        assert_eq!(a.value, b.value);
        assert!(b.value > 0.0 && b.value < 1.0, "{b:?}");
        // f64's own rounding through a short expression, against the GPU's f32 and storage
        assert!(b.allowance < 1e-12, "{b:?}");
        assert!(a.allowance > 1e3 * b.allowance, "{a:?} {b:?}");
    }

    #[test]
    fn each_light_sample_reads_its_own_view_of_the_receiver_and_its_own_map() {
        let c = compiled(include_str!("../../techniques/point-samples.ron"));
        let p = Program::new(&c.ir, &c.layout);
        assert_eq!(p.samples, 2);
        let n = 8;
        // sample 0's map puts an occluder in front of the receiver, sample 1's does not
        let near = vec![0.2f32; (n * n) as usize];
        let far = vec![1.0f32; (n * n) as usize];
        let given = Given::depth(&p, vec![near, far]);
        let ev = Evaluation::new(p, &given, frame(n), Rounding::Exact, Model::Gpu).unwrap();
        let seen = |k: usize| Seen {
            uv: [0.3 + 0.25 * k as f64, 0.5 + 1.0 / 64.0],
            d_world: 10.0,
            near: 8.0,
            far: 12.0,
            ndotl: 1.0,
            depth_slope: 0.0,
            lod: 0.0,
            texel_world: 0.0,
            weights: [0.0, 1.0],
        };
        let mut r = receiver(0.5);
        r.samples = vec![seen(0), seen(1)];
        let mut s = Scratch::default();
        let v = ev.visibility(&r, &mut s);
        // the mean of a lit and a shadowed sample, within the f32 ulps of its sum and division
        // (one of 1, three of 0.5)
        assert_eq!(v.value, 0.5, "{v:?}");
        assert!(v.allowance <= 2.5 * 2f64.powi(-23), "{v:?}");
        // one map for two views is refused
        let one = Given::depth(&p, vec![vec![1.0; (n * n) as usize]]);
        let err = Evaluation::new(p, &one, frame(n), Rounding::Exact, Model::Gpu).err().unwrap();
        assert!(err.contains("given 1 view(s), not 2"), "{err}");
    }

    #[test]
    fn geometry_outputs_are_given_and_read_as_stored() {
        let c = compiled(include_str!("../../techniques/penumbra-maps.ron"));
        let p = Program::new(&c.ir, &c.layout);
        let slots = given_slots(&p);
        let geometry: Vec<_> = slots.iter().filter(|s| s.geometry).collect();
        assert!(!geometry.is_empty() && geometry.iter().all(|s| s.views == 1), "{slots:?}");
        let n = 8;
        let only_depth = Given::depth(&p, vec![vec![1.0; (n * n) as usize]]);
        let err = Evaluation::new(p, &only_depth, frame(n), Rounding::Exact, Model::Gpu)
            .err()
            .unwrap();
        assert!(err.contains("is not given"), "{err}");
        let mut given = only_depth;
        for s in &geometry {
            given.insert(s.resource, s.channel, vec![vec![s.decode(0.25); (n * n) as usize]]);
        }
        let ev = Evaluation::new(p, &given, frame(n), Rounding::Exact, Model::Gpu).unwrap();
        let v = ev.visibility(&receiver(0.5), &mut Scratch::default());
        // the depth map (all 1) lights the receiver at 0.5, so the visibility is the
        // penumbra map's intensity as given: 0.25, exact at its F16 (`select(0, p, lit)`,
        // techniques/penumbra-maps.ron)
        assert_eq!(v.value, 0.25, "{v:?}");
        // a depth map of 0.25 shadows it: the umbra, whatever the penumbra map holds
        let mut umbra = Given::depth(&p, vec![vec![0.25; (n * n) as usize]]);
        for s in &geometry {
            umbra.insert(s.resource, s.channel, vec![vec![s.decode(0.25); (n * n) as usize]]);
        }
        let ev = Evaluation::new(p, &umbra, frame(n), Rounding::Exact, Model::Gpu).unwrap();
        assert_eq!(ev.visibility(&receiver(0.5), &mut Scratch::default()).value, 0.0);
    }
}
