//! The error model of a GPU evaluation of a technique against the exact (f64) CPU
//! reference: for one query, the interval its visibility must lie in, derived from the
//! storage precision and Vulkan's precision rules (see the list below), or a tie to skip.
//! Used to compare both the hand-written WGSL and the shaders sshc generates with the CPU.

use super::Query;
use super::cpu::{self, LevelLookup, Lookup, Prefiltered};
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
        let c = t.stored_channels().into_iter().find(|c| c.name == channel);
        let (lo, span) = c.map_or((0.0, 1.0), |c| c.encoding(t.storage));
        let taps = t.int("K").max(1) as usize;
        Model {
            storage: t.storage,
            lo,
            span,
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
}

/// Where the GPU's visibility may lie, or a tie to skip.
pub enum Allowed {
    Tie,
    Within(f64, f64),
}

fn clamp_interval(lo: f64, hi: f64) -> Allowed {
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
    let d_biased = d - t.get("bias");
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
    }
}

/// VSM's visibility over boxes of its inputs: mean, second moment and biased depth.
fn vsm_interval(mean: (f64, f64), m2: (f64, f64), d: (f64, f64), min_variance: f64, bleed: f64) -> Allowed {
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
    let slop = 2.0 * EPS32 * (m2.1.abs() + mean_sq.1);
    let variance = (
        (m2.0 - mean_sq.1 - slop).max(min_variance),
        (m2.1 - mean_sq.0 + slop).max(min_variance),
    );
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
    let linstep = |x: f64| cpu::linstep(bleed, 1.0, x);
    // the f32 division and linstep: a few roundings, magnified by 1 / (1 - bleed)
    let slack = 8.0 * EPS32 / (1.0 - bleed);
    clamp_interval(linstep(p.0) - slack, linstep(p.1) + slack)
}
