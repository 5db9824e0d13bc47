//! The error models of VSSM, MSSM and Hausdorff MSM ([`super::moments`]) on the GPU
//! against the f64 CPU reference: for one query, the interval its visibility must lie in, or
//! a tie to skip. The sources, on top of those listed at the top of [`super::tolerance`]:
//!
//! - **f32 summed-area tables** (VSSM, docs/language.md 8.7 "Tables over float channels"):
//!   the stated bound there, `2^-23 m n^2 (n + 2)` per entry (`m = 1/2` for values in
//!   [0, 1] about their centre 1/2), is 2.1e-3 at 32 x 32 and `(4 that + 256 2^-23 m n^2) / A`
//!   = 0.024 / A for a box of A texels: as an allowance it would accept any visibility at
//!   the boxes VSSM reads (one to a few texels wide, whose moments feed an ill-conditioned
//!   Chebyshev bound). The docs also state how the GPU sums (rows, then columns, every
//!   addition rounded to f32) and that the GPU's table is that emulation bit for bit
//!   (measured on lavapipe at 2048 x 2048): so the model reads the table's actual rounding
//!   from the emulation ([`cpu::f32_table`], the Map pass's f32 values `z` and `z * z`) and
//!   takes, per box, |emulated mean - exact mean| (the entries' rounding and the Map's),
//!   plus the f32 arithmetic of the box (three roundings of each block's four entries, the
//!   products and sums of up to nine weighted blocks and the division: 8 2^-24 times the
//!   sum over the blocks of the magnitudes of their entries, over the area; the entries are
//!   large where the blocks are far into the map, which is the cancellation the stated
//!   bound is about);
//! - **16-bit fixed tables** (MSSM): the codes sum exactly in u32 (boxes stay far below
//!   65,537 texels here), so a box mean is within half a step, `1 / (2 65535)`, of the mean of
//!   the values the Map pass computed; those carry the f32 error of the transform (16 2^-24:
//!   a few products of values in [-1, 1] with constants up to 4); the weighted sum of
//!   at most nine exact block sums (integers below 2^24) and the division, 16 2^-24 of the
//!   mean;
//! - **the box's edges** in f32: the centre `c n` rounds by `(n + 2) 2^-24` texels, the width
//!   carries the relative error of its region (32 2^-24), and a region known only to an
//!   interval (the filter region after an uncertain blocker depth) moves each edge by its
//!   half-width plus its centre's uncertainty; the mean moves by at most (range of the
//!   channel) / (clipped length) per texel an edge moves, two edges per axis;
//! - **the regions** in f32: the search and filter widths a few roundings of values up to
//!   `dist` (32 2^-24 of the region plus of the light's width in uv, for the cancellation
//!   in dist - near); the blocker depth's interval propagated through the filter width,
//!   which decreases with it;
//! - **the bounds**: Chebyshev's (VSSM) in interval arithmetic over its inputs' intervals
//!   (as VSM's model); the Hamburger bound (MSSM's blocker search and intensity, Hausdorff
//!   MSM) evaluated at the corners of its inputs' error box with the backward error of the
//!   f32 Cholesky solve per matrix entry, and the forward error of the steps after the
//!   solve measured by running them in f32 at the query's moments, twice over (MSM's model,
//!   [`super::tolerance`]);
//! - **binary decisions**: VSSM's blocker test (P against 0.9999) and its subdivision test
//!   (the whole region's bound at 1) are ties where the inputs' intervals straddle them.

use super::cpu::{self, BoxRuns, Prefiltered, box_runs};
use super::moments::{self, VSSM_LIT};
use super::tolerance::{Allowed, BACKWARD, EPS32, chebyshev_interval, clamp_interval, msm_family_allowed};
use super::{LightFrame, Query};

/// A region (uv per axis) widened by the f32 error of its computation: the half-width of
/// its interval per axis.
fn region_err(u: [f64; 2], light_uv: [f64; 2]) -> [f64; 2] {
    [0, 1].map(|a| 32.0 * EPS32 * (u[a] + light_uv[a]))
}

fn light_uv(light: &LightFrame) -> [f64; 2] {
    light.width.map(|w| light.uv_width(w, light.near))
}

/// The mean moves by at most `range / len` per texel an edge moves: the edges' share of a
/// box's error, the box `w` wide centred at `c` (uv), its width known to `+- w_err` and its
/// centre to `+- c_err` (uv) per axis.
fn edges_err(n: usize, c: [f64; 2], w: [f64; 2], c_err: [f64; 2], w_err: [f64; 2], range: f64) -> f64 {
    let nf = n as f64;
    (0..2)
        .map(|a| {
            let wt = (w[a] * nf).max(1.0);
            let len = box_runs(n, c[a], w[a]).1.max(0.5);
            let edge = (nf + 2.0) * 2.0 * EPS32 + wt * 32.0 * EPS32 + (c_err[a] + 0.5 * w_err[a]) * nf;
            2.0 * range * edge / len
        })
        .sum()
}

/// VSSM: one box mean from an f32 table as the GPU computes it, against the exact one:
/// (exact, error bound) for the channel `name`.
fn vssm_box(pre: &Prefiltered, name: &str, c: [f64; 2], w: [f64; 2], c_err: [f64; 2], w_err: [f64; 2]) -> (f64, f64) {
    let n = pre.depth.base().size;
    let (Some(exact), Some((_, emu))) = (pre.table(name), pre.f32_tables.iter().find(|(t, _)| t == name)) else {
        return (f64::NAN, f64::INFINITY);
    };
    let value = exact.box_mean(c, w);
    let (rx, lx): (BoxRuns, f64) = box_runs(n, c[0], w[0]);
    let (ry, ly): (BoxRuns, f64) = box_runs(n, c[1], w[1]);
    let entry = |x: i64, y: i64| {
        if x < 0 || y < 0 {
            0.0
        } else {
            emu[y as usize * n + x as usize] as f64
        }
    };
    let (mut sum, mut magnitude) = (0.0, 0.0);
    for &(y0, y1, wy) in &ry {
        for &(x0, x1, wx) in &rx {
            if x1 <= x0 || y1 <= y0 || wx * wy <= 0.0 {
                continue;
            }
            let e = [
                entry(x1 - 1, y1 - 1),
                entry(x0 - 1, y1 - 1),
                entry(x1 - 1, y0 - 1),
                entry(x0 - 1, y0 - 1),
            ];
            sum += wx * wy * (e[0] - e[1] - e[2] + e[3]);
            magnitude += e.iter().map(|v| v.abs()).sum::<f64>();
        }
    }
    let emulated = sum / (lx * ly) + 0.5;
    let arithmetic = 8.0 * EPS32 * magnitude / (lx * ly) + 4.0 * EPS32 * (emulated.abs() + 0.5);
    let err = (emulated - value).abs() + arithmetic + edges_err(n, c, w, c_err, w_err, 1.0);
    (value, err)
}

/// VSSM's moments over a box, each as an interval.
fn vssm_moments(pre: &Prefiltered, c: [f64; 2], w: [f64; 2], c_err: [f64; 2], w_err: [f64; 2]) -> [(f64, f64); 2] {
    ["m1", "m2"].map(|name| {
        let (v, e) = vssm_box(pre, name, c, w, c_err, w_err);
        (v - e, v + e)
    })
}

pub fn vssm_allowed(pre: &Prefiltered, q: &Query) -> Allowed {
    let r = &pre.technique;
    let light = r.light();
    let luv = light_uv(&light);
    let tr = moments::vssm_trace(pre, q);
    let uv = [q.uv[0] as f64, q.uv[1] as f64];
    let texel = 1.0 / pre.depth.base().size as f64;
    let least = r.get("min_variance");
    let least = (least, least);
    // d - bias rounds once
    let t_err = 2.0 * EPS32 * (tr.t.abs() + 1.0);
    let t = (tr.t - t_err, tr.t + t_err);
    let zero = [0.0, 0.0];
    // 1-2. the search region's moments and bound; the blocker test
    let [m1, m2] = vssm_moments(pre, uv, tr.su, zero, region_err(tr.su, luv));
    let p = chebyshev_interval(m1, m2, t, least);
    // the division rounds: a few ulp of P
    let p = (p.0 - 4.0 * EPS32, p.1 + 4.0 * EPS32);
    if p.0 < VSSM_LIT && p.1 >= VSSM_LIT {
        return Allowed::Tie;
    }
    if !tr.blocker {
        return Allowed::Within(1.0, 1.0);
    }
    // 3. z_occ = (mu - P t) / (1 - P): increasing in mu, decreasing in P (t > mu) and in t;
    // its corners, plus the cancellation in mu - P t over 1 - P
    let (mut z_lo, mut z_hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for mu in [m1.0, m1.1] {
        for pp in [p.0.max(0.0), p.1.min(VSSM_LIT)] {
            for tt in [t.0, t.1] {
                // moments::vssm_blocker clamps to [0, 1], which keeps the order
                let z = moments::vssm_blocker(mu, pp, tt);
                let e = 4.0 * EPS32 * (mu.abs() + tt.abs()) / (1.0 - pp);
                z_lo = z_lo.min(z - e);
                z_hi = z_hi.max(z + e);
            }
        }
    }
    let (z_lo, z_hi) = (z_lo.clamp(0.0, 1.0), z_hi.clamp(0.0, 1.0));
    // the filter region decreases with z_occ
    let (pu_lo, pu_hi) = (
        moments::filter_region(&light, tr.dist, z_hi, texel),
        moments::filter_region(&light, tr.dist, z_lo, texel),
    );
    let f32_err = region_err(tr.pu, luv);
    let pu_err = [0, 1].map(|a| (tr.pu[a] - pu_lo[a]).max(pu_hi[a] - tr.pu[a]) + f32_err[a]);
    // 4. the whole region
    let [w1, w2] = vssm_moments(pre, uv, tr.pu, zero, pu_err);
    let whole = chebyshev_interval(w1, w2, t, least);
    // the division rounds: a few ulp, except where t is certainly at or in front of the
    // mean (then the bound is 1 by selection, no division: the subdivision is certain, not
    // a tie)
    let whole = (if whole.0 >= 1.0 { 1.0 } else { whole.0 - 4.0 * EPS32 }, whole.1 + 4.0 * EPS32);
    let subdivide = r.int("subdivide") != 0;
    if subdivide && whole.0 < 1.0 && whole.1 >= 1.0 {
        return Allowed::Tie;
    }
    if !(subdivide && tr.subdivided) {
        return clamp_interval(whole.0, whole.1);
    }
    // 5. the quadrants: offsets pu / 4 and widths pu / 2 carry a quarter and a half of the
    // region's error
    let half = [0.5 * tr.pu[0], 0.5 * tr.pu[1]];
    let (mut lo, mut hi) = (0.0, 0.0);
    for o in moments::quadrants(tr.pu) {
        let c = [uv[0] + o[0], uv[1] + o[1]];
        let c_err = [0, 1].map(|a| 0.25 * pu_err[a] + 2.0 * EPS32 * (c[a].abs() + 1.0));
        let w_err = [0.5 * pu_err[0], 0.5 * pu_err[1]];
        let [a1, a2] = vssm_moments(pre, c, half, c_err, w_err);
        let b = chebyshev_interval(a1, a2, t, least);
        lo += 0.25 * b.0;
        hi += 0.25 * b.1;
    }
    clamp_interval(lo - 8.0 * EPS32, hi + 8.0 * EPS32)
}

// ---------------------------------------------------------------------------------------
// Hausdorff MSM: MSM's model (its lookups, weights, the Cholesky solve's backward error,
// the f32 forward error after it) with the Hausdorff bound. The moments b3, b4 of the
// four-point branch are taken with the matrix's entries a23, a33 (the same moments).
//
// The corners of the moments' error box bound G where G is monotone over the box. The
// four-point branch is not: G = (g R - A) / (t g) + [B / A < 0] A / (g (B / A)(g - 1)),
// g = t + B / A, with the linear functionals R, A, B of `moments::hausdorff_functionals`,
// has a pole at B = 0 and a jump of wg where B / A changes sign; B = E[z (z - 1)(z - t)^2]
// is near 0 for depths near {0, t, 1} (a receiver on a surface before a far background),
// and there a change of 1e-7 in one moment (half an f32 step near 1) moves G by 0.05
// (bunny, uv (0.2578, 0.3047), d 0.742: G = 0.0486 at the f64 moments, 0.0626 exactly at
// their f32 roundings, a point inside the box, while the corners reached 0.0607). So
// wherever the exact moments take the four-point branch, G's range over the
// box is enclosed by interval arithmetic: R, A, B as intervals (the moments' errors through
// the nested differences, plus the shader's f32 roundings of them, 2^-24 of each operand
// and result), then G = R / t + A h(B / A) over them (see the enclosure), every operation
// outward by 2 2^-24 of its magnitude (its f32 rounding), a divisor's interval holding 0
// (a pole) or B / A of either sign (the jump) leaving G undetermined.

/// A closed interval.
#[derive(Clone, Copy, Debug)]
struct Iv(f64, f64);

impl Iv {
    fn about(v: f64, h: f64) -> Iv {
        Iv(v - h, v + h)
    }
    /// outward by the f32 rounding of the operation that gave it
    fn rounded(self) -> Iv {
        let m = self.0.abs().max(self.1.abs());
        Iv(self.0 - 2.0 * EPS32 * m, self.1 + 2.0 * EPS32 * m)
    }
    fn add(self, o: Iv) -> Iv {
        Iv(self.0 + o.0, self.1 + o.1).rounded()
    }
    fn sub(self, o: Iv) -> Iv {
        Iv(self.0 - o.1, self.1 - o.0).rounded()
    }
    fn mul(self, o: Iv) -> Iv {
        let p = [self.0 * o.0, self.0 * o.1, self.1 * o.0, self.1 * o.1];
        Iv(
            p.iter().copied().fold(f64::INFINITY, f64::min),
            p.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        )
        .rounded()
    }
    /// None where the divisor may vanish
    fn div(self, o: Iv) -> Option<Iv> {
        if o.0 <= 0.0 && o.1 >= 0.0 {
            return None;
        }
        Some(self.mul(Iv(1.0 / o.1, 1.0 / o.0)))
    }
    fn below(self, x: f64) -> bool {
        self.1 < x
    }
    fn at_least(self, x: f64) -> bool {
        self.0 >= x
    }
}

/// `(value, half-width)` of `x - t y` in f32: the inputs' half-widths through it, t's
/// error times |y|, and the roundings of `t y` and of the difference.
fn nested(x: (f64, f64), y: (f64, f64), t: f64, t_err: f64) -> (f64, f64) {
    let v = x.0 - t * y.0;
    let h = x.1 + t.abs() * y.1 + t_err * (y.0.abs() + y.1) + 2.0 * EPS32 * ((t * y.0).abs() + v.abs() + y.1 + x.1);
    (v, h)
}

/// The enclosure of the four-point branch's G over the moments `b +- e`, `t +- t_err`
/// (see above); None where the four-point branch does not apply at the centre's t, an
/// infinite interval where G is undetermined.
pub fn hausdorff_four_point_enclosure(b: [f64; 4], e: [f64; 4], t: f64, t_err: f64) -> (f64, f64) {
    const ANY: (f64, f64) = (f64::NEG_INFINITY, f64::INFINITY);
    if t + t_err <= 0.0 {
        return (0.0, 0.0);
    }
    if t - t_err <= 0.0 {
        return ANY;
    }
    // D_k = b_(k+1) - b_k (b0 = 1 exact), one rounding each
    let m = [(1.0, 0.0), (b[0], e[0]), (b[1], e[1]), (b[2], e[2]), (b[3], e[3])];
    let d: [(f64, f64); 4] = std::array::from_fn(|k| {
        let v = m[k + 1].0 - m[k].0;
        (v, m[k + 1].1 + m[k].1 + 2.0 * EPS32 * v.abs())
    });
    let r = nested(d[1], d[0], t, t_err);
    let a = nested(d[2], d[1], t, t_err);
    let c = nested(d[3], d[2], t, t_err);
    let bb = nested(c, a, t, t_err);
    let (r, a, bb) = (Iv::about(r.0, r.1), Iv::about(a.0, a.1), Iv::about(bb.0, bb.1));
    let ti = Iv::about(t, t_err);
    // |A| < 1e-12 takes the three points: undetermined where A's interval reaches it (its
    // G, R / t, is G's limit as A -> 0, but the enclosure below would not show it)
    if a.0 <= 1e-12 && a.1 >= -1e-12 {
        return ANY;
    }
    let Some(q) = bb.div(a) else { return ANY };
    if !(q.below(0.0) || q.at_least(0.0)) {
        return ANY;
    }
    // G = R / t + A h(q), h(q) = -1 / (t g) + [q < 0] / (g q (g - 1)), g = t + q: linear in
    // R and in A at a given q, so G lies in R / t + A h(Q) with Q the interval of B / A;
    // h's range over Q by interval arithmetic on 64 pieces of Q (the pieces keep the
    // dependency of g on q small)
    const PIECES: usize = 64;
    let (mut h_lo, mut h_hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for i in 0..PIECES {
        let x0 = q.0 + (q.1 - q.0) * i as f64 / PIECES as f64;
        let x1 = q.0 + (q.1 - q.0) * (i + 1) as f64 / PIECES as f64;
        let qi = Iv(x0, x1);
        let g = ti.add(qi);
        let Some(mut h) = Iv(-1.0, -1.0).div(ti.mul(g)) else {
            return ANY;
        };
        if q.below(0.0) {
            let Some(wg) = Iv(1.0, 1.0).div(g.mul(qi).mul(g.sub(Iv(1.0, 1.0)))) else {
                return ANY;
            };
            h = h.add(wg);
        }
        h_lo = h_lo.min(h.0);
        h_hi = h_hi.max(h.1);
    }
    let Some(rt) = r.div(ti) else { return ANY };
    let s = rt.add(a.mul(Iv(h_lo, h_hi)));
    // the shader's steps after R, A, B: a few roundings of w0's and wg's numerators and
    // denominators, relative to the terms' magnitudes
    let m = 16.0 * EPS32 * (rt.0.abs().max(rt.1.abs()) + a.0.abs().max(a.1.abs()) * h_lo.abs().max(h_hi.abs()));
    (s.0 - m, s.1 + m)
}

pub fn hausdorff_allowed(pre: &Prefiltered, q: &Query) -> Allowed {
    let bound = |v: [f64; 7], t: f64| moments::hausdorff_intensity([v[0], v[1], v[2], v[3], v[4]], [v[5], v[6], v[3], v[4]], t);
    // the enclosure where the exact moments take the four-point branch; where only corners
    // of the box take it (the Hamburger solve's backward error flips the branch test, as for
    // the moments of a constant region, exactly those of {0, t, 1} after the bias, A = B = 0)
    // the corners' values stand, as for MSM's own branches
    let enclose = |b: [f64; 4], e: [f64; 4], t: f64, t_err: f64| {
        let (_, four) = moments::hausdorff_branch([b[0], b[1], b[1], b[2], b[3]], b, t);
        four.then(|| hausdorff_four_point_enclosure(b, e, t, t_err))
    };
    msm_family_allowed(pre, q, &bound, &moments::hausdorff_intensity_f32, &enclose)
}

// ---------------------------------------------------------------------------------------
// MSSM

/// The half-width of a box mean's error from MSSM's fixed tables (every channel alike).
fn mssm_box_err(pre: &Prefiltered, c: [f64; 2], w: [f64; 2], c_err: [f64; 2], w_err: [f64; 2]) -> f64 {
    let n = pre.depth.base().size;
    0.5 / 65535.0 + 16.0 * EPS32 + 16.0 * EPS32 + edges_err(n, c, w, c_err, w_err, 1.0)
}

/// The signed moments' errors from the channels' error `e` (each channel alike) through
/// the decoding (`|coefficients|` of the inverse transform or of the binomial expansion),
/// plus its f32 arithmetic, then the bias's `(1 - alpha)`.
fn mssm_decode_err(quantise: bool, e: f64) -> [f64; 4] {
    let r3 = 3f64.sqrt();
    let coeffs: [f64; 4] = if quantise {
        [r3 + 1.0 / 3.0, 1.125, 0.75 * (r3 + 1.0), 1.125]
    } else {
        [2.0, 8.0, 26.0, 80.0]
    };
    // the decode's own f32 roundings: a few of values up to the coefficients' sums
    coeffs.map(|k| k * e + 8.0 * EPS32 * (k + 1.0))
}

/// The corners of MSSM's Hamburger inputs: `(a12, a13, a22, a23, a33, b1, b2)` at either
/// end of their errors (the matrix entries with the solve's backward error).
fn hamburger_corners(b: [f64; 4], e: [f64; 4], mut each: impl FnMut([f64; 7])) {
    let inputs = [
        (b[0], e[0] + BACKWARD),
        (b[1], e[1] + BACKWARD),
        (b[1], e[1] + BACKWARD),
        (b[2], e[2] + BACKWARD),
        (b[3], e[3] + BACKWARD),
        (b[0], e[0]),
        (b[1], e[1]),
    ];
    for corner in 0..1u32 << inputs.len() {
        each(std::array::from_fn(|k| {
            let (x, err) = inputs[k];
            if (corner >> k) & 1 == 1 { x + err } else { x - err }
        }));
    }
}

/// MSSM: the hull of the model about the exact trace and about the trace of the GPU's codes
/// (the tables of `round(q 65535)`, [`Prefiltered::fixed_tables`]): the 4MSM solve is so
/// badly conditioned near the boundary of the moment space that the half step of the codes
/// moves the bound further than its corners reach, so the codes' own trace is taken too.
pub fn mssm_allowed(pre: &Prefiltered, q: &Query) -> Allowed {
    let exact = mssm_interval(pre, q, &moments::mssm_trace(pre, q));
    let coded = mssm_interval(pre, q, &moments::mssm_trace_with(pre, q, &pre.fixed_tables));
    match (exact, coded) {
        (Some(a), Some(b)) => clamp_interval(a.0.min(b.0), a.1.max(b.1)),
        _ => Allowed::Within(0.0, 1.0),
    }
}

fn mssm_interval(pre: &Prefiltered, q: &Query, tr: &moments::MssmTrace) -> Option<(f64, f64)> {
    let r = &pre.technique;
    let light = r.light();
    let luv = light_uv(&light);
    let quantise = r.int("quantise") != 0;
    let lit_weight = r.get("lit_weight");
    let uv = [q.uv[0] as f64, q.uv[1] as f64];
    let texel = 1.0 / pre.depth.base().size as f64;
    let alpha = r.get("alpha");
    // ts = d - bias rounds once, sf = 2 ts - 1 once more
    let sf_err = 2.0 * (2.0 * EPS32 * (tr.ts.abs() + 1.0)) + 2.0 * EPS32;
    let zero = [0.0, 0.0];
    // 1-2. the search region's biased signed moments
    let e_s = mssm_box_err(pre, uv, tr.su, zero, region_err(tr.su, luv));
    let err_s = mssm_decode_err(quantise, e_s).map(|e| (1.0 - alpha) * e + 4.0 * EPS32);
    // 3. the blocker: the corners of the moments and of sf, and the f32 steps after the solve
    let (mut s_lo, mut s_hi) = (tr.s_occ, tr.s_occ);
    for sf in [tr.sf - sf_err, tr.sf + sf_err] {
        hamburger_corners(tr.search, err_s, |v| {
            let s = moments::mssm_blocker([v[0], v[1], v[2], v[3], v[4]], v[5], v[6], sf, lit_weight);
            s_lo = s_lo.min(s);
            s_hi = s_hi.max(s);
        });
    }
    let s32 = moments::mssm_blocker_f32(tr.search.map(|v| v as f32), tr.sf as f32, lit_weight as f32) as f64;
    let forward = if s32.is_finite() { 2.0 * (s32 - tr.s_occ).abs() } else { 2.0 };
    let (s_lo, s_hi) = ((s_lo - forward - 8.0 * EPS32).max(-1.0), (s_hi + forward + 8.0 * EPS32).min(1.0));
    // 4. the filter region decreases with z_occ = (s_occ + 1) / 2
    let (pu_lo, pu_hi) = (
        moments::filter_region(&light, tr.dist, 0.5 * (s_hi + 1.0), texel),
        moments::filter_region(&light, tr.dist, 0.5 * (s_lo + 1.0), texel),
    );
    let f32_err = region_err(tr.pu, luv);
    let pu_err = [0, 1].map(|a| (tr.pu[a] - pu_lo[a]).max(pu_hi[a] - tr.pu[a]) + f32_err[a]);
    let e_f = mssm_box_err(pre, uv, tr.pu, zero, pu_err);
    let err_f = mssm_decode_err(quantise, e_f).map(|e| (1.0 - alpha) * e + 4.0 * EPS32);
    // 5. the intensity at sf over the corners
    let (mut lo, mut hi) = (tr.g, tr.g);
    for sf in [tr.sf - sf_err, tr.sf + sf_err] {
        hamburger_corners(tr.filter, err_f, |v| {
            let (z2, z3) = moments::hamburger_roots([v[0], v[1], v[2], v[3], v[4]], sf);
            let g = moments::hamburger_intensity(z2, z3, v[5], v[6], sf);
            lo = lo.min(g);
            hi = hi.max(g);
        });
    }
    let g32 = cpu::msm_intensity_f32(tr.filter.map(|v| v as f32), tr.sf as f32) as f64;
    let forward = if g32.is_finite() && tr.g.is_finite() {
        2.0 * (g32 - tr.g).abs()
    } else {
        1.0
    };
    // the f32 forward error measured at one point may vanish by luck: at least 64 2^-24
    let slack = forward + 64.0 * EPS32;
    if !(lo.is_finite() && hi.is_finite()) {
        return None;
    }
    Some((1.0 - hi.clamp(0.0, 1.0) - slack, 1.0 - lo.clamp(0.0, 1.0) + slack))
}
