//! The error model of a GPU evaluation of a technique against the exact (f64) CPU
//! reference: for one query, the interval its visibility must lie in, derived from the
//! storage precision and Vulkan's precision rules (see the list below), or a tie to skip.
//! Used to compare both the hand-written WGSL and the shaders sshc generates with the CPU.

use super::Query;
use super::cpu::{self, Chain, Footprint, LevelLookup, Lookup, Prefiltered};
use super::{Kind, Storage};

// ---------------------------------------------------------------------------------------
// Error model of the GPU reference against exact arithmetic
//
// Sources, per the Vulkan specification and the GPU reference's own arithmetic:
// - storing to a unorm format rounds to one of the two nearest steps: < 1 step of
//   (hi - lo) / (2^b - 1) in value units; to a float format, to one of the two nearest
//   values: < 1 ulp, 2^-10 |v| for F16 (plus 2^-24 below its normal range), 2^-23 |v| for F32;
// - the Map pass stores once, the separable blur once more (its horizontal half is kept in
//   f32), and every mip level once more; a mean or a convex filter does not grow the error
//   it receives;
// - sin and cos: 2^-11 absolute on [-pi, pi] (the shaders reduce their arguments to it, at
//   a phase error of pi (2k - 1) 2^-24 for order k); exp: 3 + 2|x| ulp;
// - filtering: each bilinear weight carries 8 bits of sub-texel precision (lavapipe's
//   subTexelPrecisionBits), an error below 2^-8 per axis, i.e. 2^-8 times the spread of the
//   texels it blends per axis; the weight between two mip levels likewise 8 bits (measured
//   on lavapipe; Vulkan only promises mipmapPrecisionBits >= 4, so another device may need
//   2^-4 here); lavapipe filters rgba8unorm in 8-bit fixed point and returns the result at
//   the format's precision (measured: outputs are multiples of 1/255), one more step;
// - f32 arithmetic of the shaders: a few units of 2^-24 relative, counted generously.

pub const EPS32: f64 = 1.0 / (1u64 << 24) as f64;
/// Error of one filtering weight (8 bits of sub-texel or mip-level precision).
pub const WEIGHT: f64 = 1.0 / 256.0;
/// Perturbation of the tie guard: four times the f32 rounding of values in [0, 1].
pub const NUDGE: f32 = 1.0 / (1u32 << 22) as f32;

/// What the GPU reference does to one stored channel.
struct Model {
    storage: Storage,
    /// `value = stored * span + lo`
    lo: f64,
    span: f64,
    /// width of the channel's range of values (1 where unknown)
    range: f64,
    /// Rounds at level 0: the Map pass, plus the blur's vertical pass.
    level0_roundings: u32,
    /// Taps of the blur (1 without blur).
    taps: usize,
    /// Error of the Map pass's function: absolute, and relative to the value.
    map_abs: f64,
    map_rel: f64,
    /// `Some(bound of |v|)` for a channel of either sign (errors of float rounding relative
    /// to that bound); `None` for a non-negative channel, whose float rounding errors stay
    /// relative to the local values through every mean.
    signed: Option<f64>,
}

impl Model {
    fn new(pre: &Prefiltered, channel: &str, map_abs: f64, map_rel: f64, signed: Option<f64>) -> Model {
        let t = &pre.technique;
        let c = pre.stored.iter().find(|c| c.name == channel);
        let storage = t.channel_storage(channel);
        let (lo, span) = c.as_ref().map_or((0.0, 1.0), |c| c.encoding(storage));
        let range = c.map_or(1.0, |c| c.hi - c.lo);
        let taps = t.int("K").max(1) as usize;
        Model {
            storage,
            lo,
            span,
            range,
            level0_roundings: if taps > 1 { 2 } else { 1 },
            taps,
            map_abs,
            map_rel,
            signed,
        }
    }

    /// One rounding to the storage precision of a value of magnitude up to `mag`.
    fn rounding(&self, mag: f64) -> f64 {
        match self.storage {
            Storage::Unorm8 => self.span / 255.0,
            Storage::Unorm16 => self.span / 65535.0,
            Storage::F16 => mag / 1024.0 + EPS32,
            Storage::F32 => 2.0 * EPS32 * mag,
        }
    }

    /// Error of a texel of `level` whose neighbourhood has magnitude `mag`.
    fn level(&self, level: usize, mag: f64) -> f64 {
        let roundings = (self.level0_roundings + level as u32) as f64;
        let arithmetic = (4 * self.taps + 4 * level + 4) as f64 * EPS32 * mag;
        self.map_abs + self.map_rel * mag + roundings * self.rounding(mag) + arithmetic
    }

    fn magnitude(&self, l: &LevelLookup) -> f64 {
        self.signed.unwrap_or(l.max.abs().max(l.min.abs()))
    }

    /// Error of a filtered lookup (bilinear within a level, linear between two).
    fn lookup(&self, l: &Lookup) -> f64 {
        let in_level = |level: usize, ll: &LevelLookup| self.level(level, self.magnitude(ll)) + 2.0 * WEIGHT * (ll.max - ll.min);
        let lower = in_level(l.level, &l.lower);
        let (e, mag) = match &l.upper {
            None => (lower, self.magnitude(&l.lower)),
            Some((lambda, up)) => {
                let upper = in_level(l.level + 1, up);
                let blend = (1.0 - lambda) * lower + lambda * upper;
                let between = WEIGHT * ((up.value - l.lower.value).abs() + lower + upper);
                (blend + between, self.magnitude(&l.lower).max(self.magnitude(up)))
            }
        };
        e + self.output(mag) + self.decoding(mag)
    }

    /// [`Model::lookup`] without the error of the filtering weights: for channels filtered
    /// through one sampler with the same weights, whose weight error the caller models
    /// jointly (MSM).
    fn lookup_unweighted(&self, l: &Lookup) -> f64 {
        let lower = self.level(l.level, self.magnitude(&l.lower));
        let (e, mag) = match &l.upper {
            None => (lower, self.magnitude(&l.lower)),
            Some((lambda, up)) => {
                let upper = self.level(l.level + 1, self.magnitude(up));
                (
                    (1.0 - lambda) * lower + lambda * upper + WEIGHT * (lower + upper),
                    self.magnitude(&l.lower).max(self.magnitude(up)),
                )
            }
        };
        e + self.output(mag) + self.decoding(mag)
    }

    /// Error of one texel read without filtering (`fetch`).
    fn texel(&self, v: f64) -> f64 {
        let mag = self.signed.unwrap_or(v.abs());
        self.level(0, mag) + self.decoding(mag)
    }

    /// The filtered result at the format's precision (rgba8unorm on lavapipe), or the f32
    /// arithmetic of the filter.
    fn output(&self, mag: f64) -> f64 {
        match self.storage {
            Storage::Unorm8 | Storage::Unorm16 => self.rounding(mag),
            Storage::F16 | Storage::F32 => 4.0 * EPS32 * mag,
        }
    }

    /// `stored * span + lo` in f32.
    fn decoding(&self, mag: f64) -> f64 {
        2.0 * EPS32 * (mag + self.lo.abs())
    }

    /// Error of a box mean from a summed-area table of this (unorm) channel, `sample_box` on
    /// a map of `size` texels over a box `w` (uv) wide:
    /// - the level-0 texels' error (Map and blur roundings): a mean does not grow it; the
    ///   table sums their unorm codes exactly (u32);
    /// - f32 arithmetic of the box: nine products of run sums (exact integers below 2^24)
    ///   by covered fractions, their sum and the division by the area: a few roundings of
    ///   values up to the largest code, 16 EPS32 of the range;
    /// - the box's edges in f32: the centre uv n rounds by (n + 2) 2^-24 texels, the width
    ///   carries the relative error of the kernel (32 EPS32); the mean moves by at most
    ///   (spread of the texels) / (clipped length >= 1/2 texel) per texel an edge moves,
    ///   four edges.
    fn boxed(&self, size: usize, w: [f64; 2]) -> f64 {
        let n = size as f64;
        let mag = self.signed.unwrap_or(self.range);
        let edges: f64 = w
            .iter()
            .map(|w| {
                let wt = (w * n).max(1.0);
                let edge = (n + 2.0) * 2.0 * EPS32 + wt * 32.0 * EPS32;
                2.0 * 2.0 * self.range * edge
            })
            .sum();
        self.level(0, mag) + 16.0 * EPS32 * self.range + edges + self.decoding(mag)
    }
}

/// Where the GPU's visibility may lie, or a tie to skip.
pub enum Allowed {
    Tie,
    Within(f64, f64),
}

pub(super) fn clamp_interval(lo: f64, hi: f64) -> Allowed {
    Allowed::Within(lo.clamp(0.0, 1.0), hi.clamp(0.0, 1.0))
}

pub fn nudged(q: &Query, dd: f32, du: f32, dv: f32) -> Query {
    Query {
        uv: [q.uv[0] + du, q.uv[1] + dv],
        d: q.d + dd,
        lod: q.lod,
    }
}

/// Whether `f` changes when d (and, with `uv`, each uv coordinate) moves by [`NUDGE`].
pub fn sensitive<T: PartialEq>(q: &Query, uv: bool, f: impl Fn(&Query) -> T) -> bool {
    let at = f(q);
    let mut moves = vec![nudged(q, -NUDGE, 0.0, 0.0), nudged(q, NUDGE, 0.0, 0.0)];
    if uv {
        moves.extend([
            nudged(q, 0.0, -NUDGE, 0.0),
            nudged(q, 0.0, NUDGE, 0.0),
            nudged(q, 0.0, 0.0, -NUDGE),
            nudged(q, 0.0, 0.0, NUDGE),
        ]);
    }
    moves.iter().any(|m| f(m) != at)
}

/// The interval the GPU reference's visibility must lie in for this query.
pub fn allowed(pre: &Prefiltered, q: &Query) -> Allowed {
    let t = &pre.technique;
    let uv = [q.uv[0] as f64, q.uv[1] as f64];
    let (d, lod) = (q.d as f64, q.lod as f64);
    let d_biased = d - t.bias();
    let size = pre.depth.base().size as f64;
    // tf = fract(uv N - 0.5) in f32: uv N rounds by at most N 2^-24, the rest is exact
    let tf_error = (size + 1.0) * EPS32;
    match t.kind {
        Kind::Hard => {
            // a binary test of f32 values: exact once ties are excluded
            let v = cpu::evaluate(pre, q);
            if sensitive(q, true, |q| cpu::evaluate(pre, q)) {
                Allowed::Tie
            } else {
                Allowed::Within(v, v)
            }
        }
        Kind::Pcf => {
            // Tests flip only with d; the weights (1 - tf, 1, ..., tf) carry tf's error, and
            // their products and the sum a few f32 roundings each, over (N + 1)^2 taps / N^2.
            if sensitive(q, false, |q| {
                let lit = |z: f64| q.d as f64 - t.get("bias") <= z;
                let n = t.int("N");
                let r = n / 2;
                let uv = [q.uv[0] as f64, q.uv[1] as f64];
                (0..=n)
                    .flat_map(|j| (0..=n).map(move |i| (i, j)))
                    .map(|(i, j)| lit(pre.depth.fetch(uv, i - r, j - r)))
                    .collect::<Vec<_>>()
            }) {
                return Allowed::Tie;
            }
            let v = cpu::evaluate(pre, q);
            let n = t.int("N") as f64;
            let b = (n + 1.0).powi(2) / (n * n) * (2.0 * tf_error + 4.0 * EPS32);
            clamp_interval(v - b, v + b)
        }
        Kind::Vsm => {
            // Chebyshev's bound is ill-conditioned where the variance is small: propagate the
            // lookups' error bounds through it in interval arithmetic rather than linearly.
            let m1 = pre.channel("m1").map(|c| c.lookup(uv, lod));
            let m2 = pre.channel("m2").map(|c| c.lookup(uv, lod));
            let (Some(m1), Some(m2)) = (m1, m2) else {
                return Allowed::Within(0.0, 1.0);
            };
            let e1 = Model::new(pre, "m1", 0.0, 0.0, None).lookup(&m1);
            // z * z in f32: one rounding
            let e2 = Model::new(pre, "m2", 0.0, EPS32, None).lookup(&m2);
            vsm_interval(
                (m1.value - e1, m1.value + e1),
                (m2.value - e2, m2.value + e2),
                (d_biased - 2.0 * EPS32, d_biased + 2.0 * EPS32),
                t.get("min_variance"),
                t.get("bleed"),
            )
        }
        Kind::Evsm => evsm_allowed(pre, q),
        Kind::Msm => msm_allowed(pre, q),
        Kind::Esm => {
            let c = t.get("c");
            let Some(e) = pre.channel("e_t0_k1") else {
                return Allowed::Within(0.0, 1.0);
            };
            // exp(c z): 3 + 2|cz| ulp, plus the rounding of c z and of the unorm encoding
            let model = Model::new(pre, "e_t0_k1", 0.0, (3.0 + 3.0 * c) * 2.0 * EPS32 + 4.0 * EPS32, None);
            let lookup = e.lookup(uv, 0.0);
            let decay = (-c * d_biased).exp();
            // e^{-c d} on the GPU: 3 + 2|x| ulp, plus the rounding of d - bias and of c d
            let decay_rel = (3.0 + 3.0 * c * d_biased.abs()) * 2.0 * EPS32 + 2.0 * c * EPS32;
            let s = decay * lookup.value;
            let ds = decay * model.lookup(&lookup) + (decay_rel + 2.0 * EPS32) * s.abs();
            let fails = match t.int("classify") {
                1 => {
                    let threshold = 1.0 + t.get("eps");
                    if (s - threshold).abs() <= ds {
                        return Allowed::Tie;
                    }
                    s > threshold
                }
                2 => {
                    let zm = pre.channel("zm");
                    let by_zmax =
                        |q: &Query| zm.is_some_and(|zm| q.d as f64 + t.get("zmax_offset") < zm.nearest([q.uv[0] as f64, q.uv[1] as f64]));
                    if sensitive(q, true, by_zmax) {
                        return Allowed::Tie;
                    }
                    by_zmax(q)
                }
                _ => false,
            };
            if !fails {
                return clamp_interval(s - ds, s + ds);
            }
            // the 2 x 2 fallback: each texel clamped, then blended with tf
            let f = |dx, dy| {
                let texel = e.fetch(uv, dx, dy);
                let x = decay * texel;
                let dx = decay * model.texel(texel) + (decay_rel + 2.0 * EPS32) * x.abs();
                ((x - dx).clamp(0.0, 1.0), (x + dx).clamp(0.0, 1.0))
            };
            let texels = [f(0, 0), f(1, 0), f(0, 1), f(1, 1)];
            let (sx, sy) = (uv[0] * size - 0.5, uv[1] * size - 0.5);
            let (fx, fy) = (sx - sx.floor(), sy - sy.floor());
            let blend = |i: usize| {
                let pick = |t: (f64, f64)| if i == 0 { t.0 } else { t.1 };
                let top = pick(texels[0]) + fx * (pick(texels[1]) - pick(texels[0]));
                let bottom = pick(texels[2]) + fx * (pick(texels[3]) - pick(texels[2]));
                top + fy * (bottom - top)
            };
            // tf's error moves the blend by at most twice its error (spread <= 1), and mix
            // rounds a few times
            let slack = 2.0 * tf_error + 8.0 * EPS32;
            clamp_interval(blend(0) - slack, blend(1) + slack)
        }
        Kind::Csm => {
            // s = 1/2 + sum_k (2 a_k / c_k) (cos(c_k d) S_k - sin(c_k d) C_k) is linear in
            // the lookups S_k, C_k; the shade's own sin and cos add 2^-11 each.
            let m = t.int("M");
            let fix = t.int("fix");
            let dr = d_biased - if fix == 1 { 0.5 / m as f64 } else { 0.0 };
            let alpha = t.get("alpha");
            let phase = |k: i64| std::f64::consts::PI * (2 * k - 1) as f64 * EPS32 * (2.0 * dr.abs() + 2.0);
            let model = Model::new(pre, "f_t0_k1", 1.0 / 2048.0 + phase(m), 0.0, Some(1.0));
            let mut s = 0.5;
            let mut b = 0.0;
            let mut magnitude = 0.5;
            for k in 1..=m {
                let ck = std::f64::consts::PI * (2 * k - 1) as f64;
                let amp = 2.0 * (-alpha * (k as f64 / m as f64).powi(2)).exp() / ck;
                let (Some(sin_z), Some(cos_z)) = (pre.channel(&format!("f_t0_k{k}")), pre.channel(&format!("f_t1_k{k}"))) else {
                    return Allowed::Within(0.0, 1.0);
                };
                let (sz, cz) = (sin_z.lookup(uv, lod), cos_z.lookup(uv, lod));
                let (cos_d, sin_d) = ((ck * dr).cos(), (ck * dr).sin());
                s += amp * (cos_d * sz.value - sin_d * cz.value);
                let trig = 1.0 / 2048.0 + phase(k);
                b += amp * (cos_d.abs() * model.lookup(&sz) + sin_d.abs() * model.lookup(&cz));
                b += amp * (sz.value.abs() + cz.value.abs() + 2.0 * (model.lookup(&sz) + model.lookup(&cz))) * trig;
                magnitude += amp * (sz.value.abs() + cz.value.abs());
            }
            // amplitudes rounded to f32, and the sum of 2M terms in f32
            b += (2 * m + 2) as f64 * 2.0 * EPS32 * magnitude;
            let scale = if fix == 2 { 2.0 } else { 1.0 };
            clamp_interval(scale * (s - b), scale * (s + b))
        }
        Kind::Cssm => cssm_allowed(pre, q),
        Kind::Pcss => pcss_allowed(pre, q),
        Kind::Vssm => super::moments_tolerance::vssm_allowed(pre, q),
        Kind::Mssm => super::moments_tolerance::mssm_allowed(pre, q),
        Kind::MsmHausdorff => super::moments_tolerance::hausdorff_allowed(pre, q),
    }
}

// ---------------------------------------------------------------------------------------
// CSSM (Annen 2008, chapter 8)
//
// The visibility is a chain of nonlinear steps over filtered lookups, so the bounds are
// propagated as intervals, each step evaluated with the CPU formulas at the ends of its
// inputs' intervals (every step is monotone in each input, or is bounded over its inputs'
// range as noted):
// 1. the initial kernel u0 (f32: d_world = near + d (far - near) and (dist - near) / dist,
//    a few roundings of values up to dist: 32 EPS32 of u0 plus of light_width in uv);
// 2. s_f and the numerator of eq. 8.8 at u0: value +- the series' error (below), taken
//    over the kernel's interval;
// 3. the blocker branch: where the interval of 1 - s_f straddles min_blocker either branch
//    may be taken and the allowed interval is the union of both;
// 4. z_avg = clamp(num / (1 - s_f), 0, d): monotone in num and in 1 - s_f > 0, so its
//    interval comes from the four corners (plus 4 roundings and d - bias's);
// 5. the final kernel u1, decreasing in z_avg: the kernels of the ends of z_avg's interval,
//    widened like u0;
// 6. s_1: the series bounded over the whole interval of kernels (mipmaps: it is piecewise
//    linear in the level of detail between whole levels, so the ends and the whole levels
//    between bound it; tables: 9 kernels along the segment of kernels plus the series'
//    Lipschitz bound between them, |d mean / d width| <= spread / clipped length);
// 7. ringing suppression, monotone in s; p of eq. 8.9, increasing in z_avg (exp: 3 + 2|x|
//    ulp); v^p, increasing in v and decreasing in p for v in [0, 1], with pow's error as
//    exp2(p log2 v): log2 2^-21 absolute near 1 or 3 ulp, exp2 3 + 2|x| ulp.
//
// The series' error at one footprint is the CSM model's: per basis image its stored and
// filtered error ([`Model`]: Map rounding, blur rounding, one per mip level, 8-bit filter
// weights, the rgba8unorm filter output; for tables [`Model::boxed`]), times |cos| and
// |sin| of the coefficient, plus the coefficients' own sin/cos error 2^-11 (and the phase
// rounding of the argument) times the lookup, and the f32 sum of 2M terms. The mip path's
// level of detail log2(max(w n, 1)) carries log2's error and the kernel's (2^-19 of a level
// in all), which moves a lookup by at most that times the range of its channel.

/// Error of a level of detail computed on the GPU (log2, the kernel's f32 arithmetic).
const LOD_ERR: f64 = 1.0 / (1u64 << 19) as f64;

/// The value and error bound of one CSSM channel at a footprint.
fn cssm_channel(pre: &Prefiltered, model: &Model, name: &str, uv: [f64; 2], at: Footprint) -> (f64, f64) {
    match at {
        Footprint::Lod(lod) => match pre.channel(name) {
            Some(c) => {
                let l = c.lookup(uv, lod);
                (l.value, model.lookup(&l) + LOD_ERR * model.range)
            }
            None => (f64::NAN, f64::INFINITY),
        },
        Footprint::Box(w) => match pre.table(name) {
            Some(t) => (t.box_mean(uv, w), model.boxed(t.size, w)),
            None => (f64::NAN, f64::INFINITY),
        },
    }
}

/// The CSM series s_f (`weighted` false) or the numerator of eq. 8.8 (true) at one
/// footprint: its value, its error bound, and the sum over its terms of |coefficient| times
/// the range of the channel (the Lipschitz factor of the box path).
fn cssm_series_bound(pre: &Prefiltered, uv: [f64; 2], at: Footprint, dr: f64, weighted: bool) -> (f64, f64, f64) {
    let t = &pre.technique;
    let m = t.int("M");
    let (f, g, zh) = cpu::cssm_sets(t);
    let set = if weighted { g } else { f };
    let phase = |k: i64| std::f64::consts::PI * (2 * k - 1) as f64 * EPS32 * (2.0 * dr.abs() + 2.0);
    // the Map pass's sin/cos (2^-11 and the phase of its argument); times z for the
    // weighted set (z <= 1), one more rounding
    let model = |name: &str| Model::new(pre, name, 1.0 / 2048.0 + phase(m), if weighted { EPS32 } else { 0.0 }, Some(1.0));
    let (mut s, mut b, mut lipschitz, mut magnitude) = (if weighted { 0.0 } else { 0.5 }, 0.0, 0.0, 0.5);
    for k in 1..=m {
        let ck = std::f64::consts::PI * (2 * k - 1) as f64;
        let amp = cpu::cssm_amplitude(t, k);
        let (sin_name, cos_name) = (format!("{set}_t0_k{k}"), format!("{set}_t1_k{k}"));
        let (ms, mc) = (model(&sin_name), model(&cos_name));
        let (sv, se) = cssm_channel(pre, &ms, &sin_name, uv, at);
        let (cv, ce) = cssm_channel(pre, &mc, &cos_name, uv, at);
        let (cos_d, sin_d) = ((ck * dr).cos(), (ck * dr).sin());
        // CSM: cos S - sin C; weighted: sin Zc - cos Zs (same magnitudes)
        s += if weighted {
            amp * (sin_d * cv - cos_d * sv)
        } else {
            amp * (cos_d * sv - sin_d * cv)
        };
        b += amp * (cos_d.abs() * se + sin_d.abs() * ce);
        b += amp * (sv.abs() + cv.abs() + 2.0 * (se + ce)) * (1.0 / 2048.0 + phase(k));
        lipschitz += amp * (cos_d.abs() * ms.range + sin_d.abs() * mc.range);
        magnitude += amp * (sv.abs() + cv.abs());
    }
    if weighted {
        // z / 2 exactly (no Map error), non-negative
        let mz = Model::new(pre, zh, 0.0, 0.0, Some(0.5));
        let (zv, ze) = cssm_channel(pre, &mz, zh, uv, at);
        s += zv;
        b += ze;
        lipschitz += mz.range;
    }
    // amplitudes rounded to f32, and the sum of 2M + 1 terms in f32
    b += (2 * m + 3) as f64 * 2.0 * EPS32 * magnitude;
    (s, b, lipschitz)
}

/// Bounds of the series over every kernel between `lo` and `hi` (uv, per axis).
fn cssm_series_range(pre: &Prefiltered, uv: [f64; 2], lo: [f64; 2], hi: [f64; 2], dr: f64, weighted: bool) -> (f64, f64) {
    let size = pre.depth.base().size;
    let mut out = (f64::INFINITY, f64::NEG_INFINITY);
    let mut include = |(v, e, _): (f64, f64, f64), extra: f64| {
        out = (out.0.min(v - e - extra), out.1.max(v + e + extra));
    };
    if pre.technique.int("filter") == 1 {
        // Both kernels scale light_width by one ratio, so the kernels between `lo` and `hi`
        // lie on the segment between them (off it only by the per-axis f32 roundings that
        // widened its ends, 1e-5 of a texel here): 65 points along it, and between two
        // points the box mean moves by at most (spread) / (clipped length) per texel of width,
        // the clipped length at least that of the narrower box. That term charges every
        // channel's full range, so it is the bound's width unless the points are close: with
        // 9 points, 10.8 % of the queries of the widest light got all of [0, 1] (the blocker
        // branch's final lookup, its kernel interval wide where z_avg = num / (1 - s_f)
        // divides the basis's Unorm8 rounding by a small 1 - s_f); with 65 none do, and the
        // median allowance falls from 1.9e-2 to 5.5e-5 (docs/agreement.md, issue 52).
        let steps = if lo == hi { 1 } else { 65 };
        let n = size as f64;
        for i in 0..steps {
            let f = if steps == 1 { 0.0 } else { i as f64 / (steps - 1) as f64 };
            let w = [lo[0] + (hi[0] - lo[0]) * f, lo[1] + (hi[1] - lo[1]) * f];
            let bound = cssm_series_bound(pre, uv, Footprint::Box(w), dr, weighted);
            let between: f64 = (0..2)
                .map(|a| {
                    let h = if steps == 1 {
                        0.0
                    } else {
                        (hi[a] - lo[a]) * n / (steps - 1) as f64
                    };
                    let len = cpu::box_runs(size, uv[a], w[a]).1;
                    bound.2 * (h + 1e-5) / len
                })
                .sum();
            include(bound, between);
        }
    } else {
        // piecewise linear in the level of detail: the ends and the whole levels between
        // (just above each too, where the blend with the next level starts)
        let lod = |u: [f64; 2]| cpu::lod_of_width(size, cpu::INV_SQRT3 * u[0].max(u[1]));
        let last = (pre.depth.levels.len().max(1) - 1) as f64;
        let chain_last = pre
            .channel(&format!("{}_t0_k1", cpu::cssm_sets(&pre.technique).0))
            .map_or(last, |c| (c.levels.len() - 1) as f64);
        let (a, b) = ((lod(lo) - LOD_ERR).max(0.0), lod(hi) + LOD_ERR);
        let mut candidates = vec![a, b];
        let mut l = a.ceil();
        while l < b && l <= chain_last {
            candidates.push(l);
            l += 1.0;
        }
        for c in candidates {
            let c = c.min(chain_last);
            for at in [c, (c + 1e-9).min(chain_last)] {
                include(cssm_series_bound(pre, uv, Footprint::Lod(at), dr, weighted), 0.0);
            }
        }
    }
    out
}

/// A kernel (uv per axis) widened by the f32 error of its computation.
fn cssm_widen(u: [f64; 2], light_uv: [f64; 2]) -> ([f64; 2], [f64; 2]) {
    let e = |a: usize| 32.0 * EPS32 * (u[a] + light_uv[a]);
    ([(u[0] - e(0)).max(0.0), (u[1] - e(1)).max(0.0)], [u[0] + e(0), u[1] + e(1)])
}

/// Bound on |pow(v, p) - v^p| on the GPU: exp2(p log2 v), log2 2^-21 absolute (v in
/// [1/2, 2]) or 3 ulp, the product one rounding, exp2 3 + 2|x| ulp.
fn pow_error(v: f64, p: f64) -> f64 {
    if v <= 0.0 {
        return 0.0;
    }
    let l = v.log2();
    let x = p * l;
    let dx = p * (1.0 / (1u64 << 21) as f64 + 3.0 * 2.0 * EPS32 * l.abs()) + 2.0 * EPS32 * x.abs();
    v.powf(p) * (std::f64::consts::LN_2 * dx + (3.0 + 2.0 * x.abs()) * 2.0 * EPS32) * 1.01
}

fn cssm_allowed(pre: &Prefiltered, q: &Query) -> Allowed {
    let t = &pre.technique;
    let light = t.light();
    let uv = [q.uv[0] as f64, q.uv[1] as f64];
    let tr = cpu::cssm_trace(pre, q);
    let light_uv = light.width.map(|w| light.uv_width(w, light.near));
    // d - bias rounds once in f32
    let db_err = 2.0 * EPS32 * (tr.db.abs() + 1.0);
    let (u0_lo, u0_hi) = cssm_widen(tr.u0, light_uv);
    let sf = cssm_series_range(pre, uv, u0_lo, u0_hi, tr.dr, false);
    let num = cssm_series_range(pre, uv, u0_lo, u0_hi, tr.dr, true);
    // 1 - s_f in f32
    let blockers = (1.0 - sf.1 - EPS32, 1.0 - sf.0 + EPS32);
    let min_blocker = t.get("min_blocker");
    // ringing suppression: (scale s - ring) / (1 - 2 ring) in f32, a few roundings
    let ring_slack = 8.0 * EPS32 / (1.0 - 2.0 * t.get("ring"));
    let ringing = |s: (f64, f64)| (cpu::cssm_ringing(t, s.0) - ring_slack, cpu::cssm_ringing(t, s.1) + ring_slack);
    let mut out = (f64::INFINITY, f64::NEG_INFINITY);
    let mut include = |(lo, hi): (f64, f64)| {
        out = (out.0.min(lo), out.1.max(hi));
    };
    // no blocker: the ringing-suppressed series at the initial kernel
    if blockers.0 < min_blocker {
        include(ringing(sf));
    }
    if blockers.1 >= min_blocker {
        // in this branch the GPU's 1 - s_f is at least min_blocker: the division happens
        let den = (blockers.0.max(min_blocker), blockers.1);
        let top = tr.db.max(0.0) + db_err;
        let (za_lo, za_hi) = if den.0 <= 0.0 {
            (0.0, top)
        } else {
            let corners = [num.0 / den.0, num.0 / den.1, num.1 / den.0, num.1 / den.1];
            let lo = corners.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = corners.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            // the quotient rounds (2.5 ulp), the clamp's bound d - bias rounds
            let e = |z: f64| 4.0 * EPS32 * z.abs();
            ((lo - e(lo)).clamp(0.0, top), (hi + e(hi)).clamp(0.0, top))
        };
        // the final kernel decreases with z_avg
        let (u1_lo, _) = cssm_widen(cpu::cssm_final_width(&light, tr.dist, za_hi), light_uv);
        let (_, u1_hi) = cssm_widen(cpu::cssm_final_width(&light, tr.dist, za_lo), light_uv);
        let s1 = cssm_series_range(pre, uv, u1_lo, u1_hi, tr.dr, false);
        let v1 = ringing(s1);
        let v1 = (v1.0.clamp(0.0, 1.0), v1.1.clamp(0.0, 1.0));
        // p = 1 + A exp(-B x), x = max(d - z_avg, 0), decreasing in x
        let (a, b) = (t.get("A"), t.get("B"));
        let x_lo = (tr.db - db_err - za_hi).max(0.0);
        let x_hi = (tr.db + db_err - za_lo).max(0.0);
        let sharpen = |x: f64, sign: f64| {
            let e = a * (-b * x).exp();
            1.0 + e * (1.0 + sign * ((3.0 + 2.0 * b * x) * 2.0 * EPS32 + 8.0 * EPS32))
        };
        let (p_lo, p_hi) = (sharpen(x_hi, -1.0), sharpen(x_lo, 1.0));
        let lo = v1.0.powf(p_hi) - pow_error(v1.0, p_hi);
        let hi = v1.1.powf(p_lo) + pow_error(v1.1, p_lo);
        include((lo, hi));
    }
    clamp_interval(out.0, out.1)
}

// ---------------------------------------------------------------------------------------
// PCSS (Fernando 2005)
//
// Every read is a binary choice: which texel `nearest_at` reads, and each depth test. The
// f32 positions (uv + o) n on the GPU differ from the exact ones by the error of the
// region's width (search: 16 EPS32 of it plus 16 EPS32 of light_width in uv, for the
// cancellation in d_world - near; filter: the blocker depth's error propagated through
// (dist - zb) / zb, the mean of up to N^2 f32 values carrying (N^2 + 2) EPS32), the lattice
// constants (2 EPS32), and the products and sums (2 EPS32 of each operand), doubled. A query
// is a tie where any read could land on a texel of another depth within that error (in the
// search a different depth changes the blocker mean; in the filter only a different test
// result matters), or where a depth test compares values within 2 EPS32 (d - bias rounds).
// Otherwise the GPU reads the same texels and decides the same tests, and the result is
// the same count over M^2 (one rounding).

/// Whether a `nearest_at` read at texel position `p` (+- `e` texels per axis) may read a
/// texel whose value `differs` from the exact one's.
fn read_is_open(pre: &Prefiltered, p: [f64; 2], e: [f64; 2], differs: impl Fn(f64, f64) -> bool) -> bool {
    let base = pre.depth.base();
    let cell = |x: f64| x.floor() as i64;
    let exact = base.at(cell(p[0]), cell(p[1]));
    [-1.0, 1.0]
        .iter()
        .flat_map(|sx| [-1.0, 1.0].map(|sy| (*sx, sy)))
        .any(|(sx, sy)| differs(exact, base.at(cell(p[0] + sx * e[0]), cell(p[1] + sy * e[1]))))
}

fn pcss_allowed(pre: &Prefiltered, q: &Query) -> Allowed {
    let t = &pre.technique;
    let light = t.light();
    let tr = cpu::pcss_trace(pre, q);
    let n = pre.depth.base().size as f64;
    let uv = [q.uv[0] as f64, q.uv[1] as f64];
    let light_uv = light.width.map(|w| light.uv_width(w, light.near));
    let test_err = 2.0 * EPS32 * (tr.db.abs() + 1.0);
    let position_err = |s: &cpu::PcssSample, region: [f64; 2], region_err: [f64; 2]| -> [f64; 2] {
        [0, 1].map(|a| {
            let c = if region[a] > 0.0 { (s.offset[a] / region[a]).abs() } else { 0.5 };
            let o = s.offset[a].abs();
            2.0 * n * (c * region_err[a] + 2.0 * EPS32 * region[a] + 2.0 * EPS32 * (uv[a].abs() + o + 1.0))
        })
    };
    let near_test = |z: f64| (z - tr.db).abs() <= test_err;
    // 1. the search
    let su_err = [0, 1].map(|a| 16.0 * EPS32 * (tr.su[a] + light_uv[a]));
    for s in &tr.search {
        let e = position_err(s, tr.su, su_err);
        if near_test(s.z) || read_is_open(pre, s.position, e, |a, b| a != b || near_test(b)) {
            return Allowed::Tie;
        }
    }
    if tr.count == 0 {
        return Allowed::Within(1.0, 1.0);
    }
    // 2. the filter region's error through the blocker mean
    let nn = (t.int("N") * t.int("N")) as f64;
    let span = light.far - light.near;
    let zbw = light.near + tr.zb * span;
    let e_zbw = span * (nn + 2.0) * EPS32 * tr.zb.abs() + 4.0 * EPS32 * zbw;
    let e_dist = 4.0 * EPS32 * tr.dist;
    let gap = (tr.dist - zbw).max(0.0);
    let pu_err = [0, 1].map(|a| {
        light_uv[a] * light.near / tr.dist * ((e_dist + e_zbw) / zbw + gap / (zbw * zbw) * e_zbw + gap / zbw * e_dist / tr.dist)
            + 16.0 * EPS32 * tr.pu[a]
    });
    for s in &tr.filter {
        let e = position_err(s, tr.pu, pu_err);
        let lit = |z: f64| tr.db <= z;
        if near_test(s.z) || read_is_open(pre, s.position, e, |a, b| lit(a) != lit(b) || near_test(b)) {
            return Allowed::Tie;
        }
    }
    let v = tr.value;
    clamp_interval(v - 2.0 * EPS32, v + 2.0 * EPS32)
}

/// Chebyshev's one-sided bound ([`cpu::chebyshev`]) over boxes of its inputs: mean, second
/// moment, receiver and least variance; the bound before any clamp or bleeding reduction.
pub(super) fn chebyshev_interval(mean: (f64, f64), m2: (f64, f64), d: (f64, f64), least: (f64, f64)) -> (f64, f64) {
    let sq = |(lo, hi): (f64, f64)| {
        let (a, b) = (lo * lo, hi * hi);
        if lo <= 0.0 && hi >= 0.0 {
            (0.0, a.max(b))
        } else {
            (a.min(b), a.max(b))
        }
    };
    let mean_sq = sq(mean);
    // m2 - mean^2 in f32 loses up to 2^-23 of each operand
    let slop = 2.0 * EPS32 * (m2.1.abs().max(m2.0.abs()) + mean_sq.1);
    let variance = ((m2.0 - mean_sq.1 - slop).max(least.0), (m2.1 - mean_sq.0 + slop).max(least.1));
    let delta = (d.0 - mean.1, d.1 - mean.0);
    let mut p = (f64::INFINITY, f64::NEG_INFINITY);
    let mut include = |v: f64| {
        p = (p.0.min(v), p.1.max(v));
    };
    // in front of (or at) the mean: lit
    if delta.0 <= 0.0 {
        include(1.0);
    }
    // behind it: p_max = var / (var + delta^2), increasing in var, decreasing in delta^2
    if delta.1 > 0.0 {
        let delta_sq = (delta.0.max(0.0).powi(2), delta.1.powi(2));
        let p_max = |v: f64, dsq: f64| if v + dsq > 0.0 { v / (v + dsq) } else { 1.0 };
        include(p_max(variance.0, delta_sq.1));
        include(p_max(variance.1, delta_sq.0));
    }
    p
}

/// VSM's visibility over boxes of its inputs: mean, second moment and biased depth.
fn vsm_interval(mean: (f64, f64), m2: (f64, f64), d: (f64, f64), min_variance: f64, bleed: f64) -> Allowed {
    let p = chebyshev_interval(mean, m2, d, (min_variance, min_variance));
    let linstep = |x: f64| cpu::linstep(bleed, 1.0, x);
    // the f32 division and linstep: a few roundings, magnified by 1 / (1 - bleed)
    let slack = 8.0 * EPS32 / (1.0 - bleed);
    clamp_interval(linstep(p.0) - slack, linstep(p.1) + slack)
}

// ---------------------------------------------------------------------------------------
// EVSM (Lauritzen & McCool 2008)
//
// Each warp is VSM in the warped space, so its bound is propagated as VSM's is, in interval
// arithmetic over the lookups' error bounds (Chebyshev's bound is monotone in the variance
// and in the distance to the mean), with these sources on top of the lookups' [`Model`]:
// - the Map pass's exp(k c t), k = 1 for a warp and 2 for its square, |k c t| <= k c: exp's
//   3 + 2|x| ulp, plus the argument's own error: 2z - 1 rounds by 2^-24, times k c, and
//   the product k c t rounds once (relative 2^-24 of x), so the relative error of the value
//   is at most (3 + 4 k c) 2^-23 + 2^-22 (the f32 values of the warps are what the lookups
//   blend; their storage rounding, relative for floats, is in the Model);
// - the receiver's warp exp(c t_r) the same way (t_r = 2 d - 1, d - bias exact for EVSM);
// - the least variance min_variance (c w)^2: monotone in |w|, evaluated at the ends of w's
//   interval, plus four roundings;
// - m2 - mean^2 in f32 (as for VSM); with c = 40 the warps span e^{+-40} and the squares
//   e^{+-80}, so this cancellation is the error that matters where the filter region is
//   almost flat: 2^-23 of the second moment against a least variance of
//   min_variance c^2 w^2 (3 % of w^2 at the defaults), small where w is near the mean;
// - the minimum of the two bounds is monotone in each, the final linstep likewise.
// For F16 the Model's rounding is 2^-11 relative: the variance is then meaningful only
// above about 2^-9 of the second moment, so F16 needs a larger minimum variance (or the
// allowance is wide, as it says).

fn evsm_allowed(pre: &Prefiltered, q: &Query) -> Allowed {
    let t = &pre.technique;
    let uv = [q.uv[0] as f64, q.uv[1] as f64];
    let lod = q.lod as f64;
    let d = q.d as f64 - t.bias();
    let tr = 2.0 * d - 1.0;
    let tr_err = 2.0 * EPS32;
    let min_variance = t.get("min_variance");
    let bound = |c: f64, sign: f64, first: &str, second: &str| -> Option<(f64, f64)> {
        let exp_rel = |kc: f64| (3.0 + 4.0 * kc) * 2.0 * EPS32 + 4.0 * EPS32;
        let l1 = pre.channel(first)?.lookup(uv, lod);
        let l2 = pre.channel(second)?.lookup(uv, lod);
        let e1 = Model::new(pre, first, 0.0, exp_rel(c), None).lookup(&l1);
        let e2 = Model::new(pre, second, 0.0, exp_rel(2.0 * c), None).lookup(&l2);
        // the receiver's warp: w = sign exp(sign c t_r), sign = +1 or -1
        let x = sign * c * tr;
        let w = sign * x.exp();
        let w_err = w.abs() * ((3.0 + 2.0 * x.abs()) * 2.0 * EPS32 + c * tr_err + 2.0 * EPS32 * x.abs());
        let ws = (w - w_err, w + w_err);
        // min_variance (c w)^2 over that interval
        let mag = |v: f64| c * v.abs();
        let (small, large) = if ws.0 <= 0.0 && ws.1 >= 0.0 {
            (0.0, mag(ws.0).max(mag(ws.1)))
        } else {
            (mag(ws.0).min(mag(ws.1)), mag(ws.0).max(mag(ws.1)))
        };
        let least = (
            min_variance * small * small * (1.0 - 8.0 * EPS32),
            min_variance * large * large * (1.0 + 8.0 * EPS32),
        );
        Some(chebyshev_interval(
            (l1.value - e1, l1.value + e1),
            (l2.value - e2, l2.value + e2),
            ws,
            least,
        ))
    };
    let (Some(vp), Some(vn)) = (bound(t.get("c_pos"), 1.0, "p1", "p2"), bound(t.get("c_neg"), -1.0, "n1", "n2")) else {
        return Allowed::Within(0.0, 1.0);
    };
    let bleed = t.get("bleed");
    let linstep = |x: f64| cpu::linstep(bleed, 1.0, x);
    // the f32 divisions, the minimum and linstep: a few roundings, magnified by 1 / (1 - bleed)
    let slack = 8.0 * EPS32 / (1.0 - bleed);
    clamp_interval(linstep(vp.0.min(vn.0)) - slack, linstep(vp.1.min(vn.1)) + slack)
}

// ---------------------------------------------------------------------------------------
// MSM (Peters & Klein 2015, Algorithm 2)
//
// The bound is a smooth but far from monotone function of the four moments, and badly
// conditioned where the Hankel matrix is nearly singular (a flat filter region: the bias
// alone keeps it positive definite, its last pivot of the order of alpha). So the error
// bounds are propagated by perturbing the inputs and evaluating the CPU formulas there:
// - the filtering weights: the four moments share one texture, one sampler and so the same
//   bilinear weights and the same weight between levels; each carries 8 bits (see the top
//   of this module), so the GPU's moments are those of the exact filter with each weight
//   moved by up to 2^-8. They are taken at the exact weights and at every corner (each
//   fraction of each level, and the weight between levels where the lookup blends two,
//   moved by -2^-8 or +2^-8): the moments stay those of a convex combination of texels (a valid moment
//   vector), which independent intervals per moment would not;
// - per moment, everything else the [`Model`] counts (storage roundings at each level, the
//   mean and filter arithmetic, the Map pass's powers: z^k in f32 rounds k - 1 times) and
//   the bias's f32 mix (a few roundings);
// - the backward error of the f32 Cholesky solve: the computed factor is the exact one of
//   the matrix perturbed by at most gamma_4 sqrt(a_ii a_jj) <= 4 2^-23 per entry (Higham,
//   Accuracy and Stability of Numerical Algorithms, theorem 10.3; the entries are moments
//   in [0, 1]) and the two triangular solves are backward stable likewise: 16 2^-24 per
//   entry in all. This perturbation need not keep the matrix a Hankel matrix, and where
//   the matrix is nearly singular that matters: so the five entries of the matrix
//   (a12 = b1, a13 = a22 = b2, a23 = b3, a33 = b4) each move by their moment's error plus
//   this, independently, and the b1, b2 of the last step by their moments' errors
//   ([`cpu::msm_bound`]); the bound is evaluated at the 128 corners of that box (for a
//   function linear over a box this small, its extremes);
// - the receiver's depth d - bias rounds once: +-2^-23 (d + 1), taken at both ends;
// - the steps after the solve (the quadratic's roots and the three cases) in f32: their
//   forward error is measured by running the same algorithm in f32 on the CPU
//   ([`cpu::msm_intensity_f32`]) at the query's moments, and allowed twice over (the GPU
//   rounds in another order and may contract products into fused multiply-adds), plus a
//   few roundings of the result.
// Where the matrix is nearly singular the allowance is wide, and it says so.

/// One bilinear lookup of `level` at uv with both fractions moved by `shift` (clamped to
/// [0, 1]).
fn shifted_bilinear(level: &cpu::Level, uv: [f64; 2], shift: [f64; 2]) -> f64 {
    let n = level.size as f64;
    let (sx, sy) = (uv[0] * n - 0.5, uv[1] * n - 0.5);
    let (x0, y0) = (sx.floor(), sy.floor());
    let fx = (sx - x0 + shift[0]).clamp(0.0, 1.0);
    let fy = (sy - y0 + shift[1]).clamp(0.0, 1.0);
    let (x0, y0) = (x0 as i64, y0 as i64);
    let top = level.at(x0, y0) + fx * (level.at(x0 + 1, y0) - level.at(x0, y0));
    let bottom = level.at(x0, y0 + 1) + fx * (level.at(x0 + 1, y0 + 1) - level.at(x0, y0 + 1));
    top + fy * (bottom - top)
}

/// [`Chain::lookup`] with the filtering weights moved: the bilinear fractions of the lower
/// level by `shift[0..2]`, of the upper level by `shift[2..4]`, the weight of the upper level
/// by `shift[4]` (each clamped to [0, 1]).
fn shifted_lookup(chain: &Chain, uv: [f64; 2], lod: f64, shift: [f64; 5]) -> f64 {
    let l = chain.lookup(uv, lod);
    let lower = shifted_bilinear(&chain.levels[l.level], uv, [shift[0], shift[1]]);
    match l.upper {
        None => lower,
        Some((lambda, _)) => {
            let upper = shifted_bilinear(&chain.levels[l.level + 1], uv, [shift[2], shift[3]]);
            let lambda = (lambda + shift[4]).clamp(0.0, 1.0);
            lower + lambda * (upper - lower)
        }
    }
}

/// The backward error of MSM's f32 Cholesky solve per matrix entry (see above).
pub(super) const BACKWARD: f64 = 16.0 * EPS32;

fn msm_allowed(pre: &Prefiltered, q: &Query) -> Allowed {
    msm_family_allowed(
        pre,
        q,
        &|v, zf| cpu::msm_bound([v[0], v[1], v[2], v[3], v[4]], v[5], v[6], zf),
        &cpu::msm_intensity_f32,
        &|_, _, _, _| None,
    )
}

/// An enclosure of a moment bound over a box (see [`msm_family_allowed`]).
pub(super) type Enclosure<'a> = dyn Fn([f64; 4], [f64; 4], f64, f64) -> Option<(f64, f64)> + 'a;

/// The model above for a bound of MSM's moments: `bound(v, zf)` with
/// `v = (a12, a13, a22, a23, a33, b1, b2)` (the matrix entries and the moments of the last
/// step), `bound32` the same algorithm in f32 at the moments. Hausdorff MSM shares it.
/// `enclose(b, e, zf, zf_err)`, called once per set of weights after `bound`'s corners,
/// may add an enclosure of the bound over the whole box `b +- e` (each moment), `zf +-
/// zf_err`, for a bound the corners do not enclose (Hausdorff MSM's four-point branch); an
/// infinite end leaves the query undetermined, [0, 1].
pub(super) fn msm_family_allowed(
    pre: &Prefiltered,
    q: &Query,
    bound: &dyn Fn([f64; 7], f64) -> f64,
    bound32: &dyn Fn([f32; 4], f32) -> f32,
    enclose: &Enclosure,
) -> Allowed {
    let t = &pre.technique;
    let uv = [q.uv[0] as f64, q.uv[1] as f64];
    let lod = q.lod as f64;
    let zf = q.d as f64 - t.bias();
    let zf_err = 2.0 * EPS32 * (zf.abs() + 1.0);
    let names = ["b1", "b2", "b3", "b4"];
    let mut chains = Vec::new();
    for name in names {
        match pre.channel(name) {
            Some(c) => chains.push(c),
            None => return Allowed::Within(0.0, 1.0),
        }
    }
    let alpha = t.get("alpha");
    // per-moment errors besides the weights', in the biased moments' units
    let errors: Vec<f64> = chains
        .iter()
        .enumerate()
        .map(|(k, c)| {
            let l = c.lookup(uv, lod);
            let model = Model::new(pre, names[k], 0.0, k as f64 * EPS32, None);
            (1.0 - alpha) * model.lookup_unweighted(&l) + 4.0 * EPS32
        })
        .collect();
    let blends = chains[0].lookup(uv, lod).upper.is_some();
    // the exact weights and the weights' corners (each weight at either end of its error;
    // the two levels' fractions are rounded independently)
    let dims = if blends { 5 } else { 2 };
    let mut shifts = vec![[0.0; 5]];
    for corner in 0..1u32 << dims {
        shifts.push(std::array::from_fn(|i| {
            if i >= dims {
                0.0
            } else if (corner >> i) & 1 == 1 {
                WEIGHT
            } else {
                -WEIGHT
            }
        }));
    }
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for shift in shifts {
        let b: [f64; 4] = std::array::from_fn(|k| shifted_lookup(chains[k], uv, lod, shift));
        let b = cpu::msm_biased(t, b);
        let hankel = [b[0], b[1], b[1], b[2], b[3], b[0], b[1]];
        let centre = bound(hankel, zf);
        // the receiver's rounding, linear over its interval
        let by_zf = [-zf_err, zf_err]
            .iter()
            .map(|e| (bound(hankel, zf + e) - centre).abs())
            .fold(0.0, f64::max);
        // (value, half-width) of a12, a13, a22, a23, a33, then b1 and b2 of the last step
        let inputs = [
            (b[0], errors[0] + BACKWARD),
            (b[1], errors[1] + BACKWARD),
            (b[1], errors[1] + BACKWARD),
            (b[2], errors[2] + BACKWARD),
            (b[3], errors[3] + BACKWARD),
            (b[0], errors[0]),
            (b[1], errors[1]),
        ];
        for corner in 0..1u32 << inputs.len() {
            let v: [f64; 7] = std::array::from_fn(|k| {
                let (x, e) = inputs[k];
                if (corner >> k) & 1 == 1 { x + e } else { x - e }
            });
            let g = bound(v, zf);
            lo = lo.min(g - by_zf);
            hi = hi.max(g + by_zf);
        }
        lo = lo.min(centre - by_zf);
        hi = hi.max(centre + by_zf);
        if let Some((a, b)) = enclose(b, std::array::from_fn(|k| errors[k]), zf, zf_err) {
            lo = lo.min(a);
            hi = hi.max(b);
        }
    }
    // the f32 steps after the solve, measured at the query's moments
    let b = cpu::msm_biased(t, cpu::msm_moments(pre, uv, lod));
    let g64 = bound([b[0], b[1], b[1], b[2], b[3], b[0], b[1]], zf);
    let g32 = bound32(b.map(|v| v as f32), zf as f32) as f64;
    let forward = if g32.is_finite() && g64.is_finite() {
        2.0 * (g32 - g64).abs()
    } else {
        1.0
    };
    let slack = forward + 8.0 * EPS32;
    if !(lo.is_finite() && hi.is_finite()) {
        return Allowed::Within(0.0, 1.0);
    }
    // visibility 1 - G
    clamp_interval(1.0 - hi - slack, 1.0 - lo + slack)
}
