//! The f64 CPU reference of three moment-based techniques read from summed-area tables or a
//! mip chain, written from the papers and the specification of their stated choices, not
//! from the technique files' expressions:
//!
//! - VSSM (Yang, Dong, Feng, Seidel and Kautz, "Variance Soft Shadow Mapping", Pacific
//!   Graphics 2010): Chebyshev's one-sided bound (section 3) over a search region for the
//!   blocker depth, then over the filter region, and the subdivision of a filter region
//!   whose whole bound reads lit into four quadrants (section 4). Read from memory of the
//!   paper (the paper itself was not available here); the blocker estimate
//!   `z_occ = (mu - P t) / (1 - P)` is the paper's, with the non-blockers taken at the
//!   receiver's depth t.
//! - Hausdorff MSM (Peters & Klein, "Moment Shadow Mapping", I3D 2015, the variant for
//!   depths known to lie in [0, 1]): the Hamburger 4MSM bound where its support lies in
//!   [0, 1], else the four-point distribution on {0, t, g, 1} derived in
//!   [`hausdorff_intensity`]. From memory of the paper (not available here); the derivation
//!   of g and the weights is this module's.
//! - MSSM (Peters, Münstermann, Wetzstein and Klein, "Improved Moment Shadow Maps for
//!   Translucent Occluders, Soft Shadows and Single Scattering", JCGT 6(1) 2017): signed
//!   depth (section 3.1), its sparse quantisation transform and inverse, the moment-based
//!   blocker search with Algorithm 1's Hamburger bounding distribution (m = 4), and the
//!   4MSM intensity over the filter region. Sections 1-3 and Algorithm 1 were read in a
//!   translation; the blocker search's weighting (`lit_weight`) is the specification's.
//!
//! The light geometry (search and filter regions) is the PCSS reference's
//! ([`super::cpu::pcss_trace`]), the light's angular spread 0 (rectangle lights).

use super::cpu::{MSM_PIVOT, Prefiltered, Table, chebyshev};
use super::{LightFrame, Query, Resolved};

// ---------------------------------------------------------------------------------------
// Shared light geometry

/// The search region (uv per axis): the pyramid from the receiver at `dist` to the light,
/// cut by the near plane, `uv_width(width (dist - near) / dist, near)` (+ the spread's
/// term, 0 here).
pub fn search_region(light: &LightFrame, dist: f64) -> [f64; 2] {
    light.width.map(|w| light.uv_width(w * (dist - light.near) / dist, light.near))
}

/// The filter region (uv per axis) from a blocker at normalised depth `z_occ`:
/// `wp = width max(dist - zbw, 0) / zbw` (0 for zbw <= 1e-30), projected to the near plane
/// `wn = wp near / dist`, in uv, at least one texel.
pub fn filter_region(light: &LightFrame, dist: f64, z_occ: f64, texel: f64) -> [f64; 2] {
    let zbw = light.near + z_occ * (light.far - light.near);
    let ratio = if zbw <= 1e-30 { 0.0 } else { (dist - zbw).max(0.0) / zbw };
    light
        .width
        .map(|w| light.uv_width(w * ratio * light.near / dist, light.near).max(texel))
}

/// `max(d_world(d), near)`
pub fn distance(light: &LightFrame, d: f64) -> f64 {
    light.d_world(d).max(light.near)
}

/// The box mean of a table centred at `uv + o` (`sample_box_at`).
pub fn box_at(table: &Table, uv: [f64; 2], o: [f64; 2], w: [f64; 2]) -> f64 {
    table.box_mean([uv[0] + o[0], uv[1] + o[1]], w)
}

/// The four quadrants of a region `pu`: offsets `(+-pu_x / 4, +-pu_y / 4)`, in the order
/// (-, -), (+, -), (-, +), (+, +); each box is `pu / 2`.
pub fn quadrants(pu: [f64; 2]) -> [[f64; 2]; 4] {
    let (x, y) = (0.25 * pu[0], 0.25 * pu[1]);
    [[-x, -y], [x, -y], [-x, y], [x, y]]
}

// ---------------------------------------------------------------------------------------
// VSSM

/// The largest lit fraction of the search region that still counts a blocker.
pub const VSSM_LIT: f64 = 0.9999;

/// The steps of VSSM's Shade for one receiver.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VssmTrace {
    /// d - bias
    pub t: f64,
    pub dist: f64,
    pub su: [f64; 2],
    /// the search region's (mean, second moment), and the bound there, at most VSSM_LIT
    pub search: [f64; 2],
    pub p: f64,
    pub blocker: bool,
    pub z_occ: f64,
    pub pu: [f64; 2],
    /// the filter region's moments and bound
    pub whole_m: [f64; 2],
    pub whole: f64,
    /// whether the quadrants were taken, and their bounds
    pub subdivided: bool,
    pub quads: [f64; 4],
    pub value: f64,
}

/// The moments (mean, second moment) over a box of the VSSM tables `m1`, `m2`.
pub fn vssm_moments(pre: &Prefiltered, uv: [f64; 2], o: [f64; 2], w: [f64; 2]) -> [f64; 2] {
    ["m1", "m2"].map(|name| pre.table(name).map_or(f64::NAN, |t| box_at(t, uv, o, w)))
}

/// VSSM's blocker estimate from the search region's mean and bound (Yang et al. 2010,
/// section 3: the region's mean is P t + (1 - P) z_occ with the lit part at the receiver).
pub fn vssm_blocker(mu: f64, p: f64, t: f64) -> f64 {
    ((mu - p * t) / (1.0 - p)).clamp(0.0, 1.0)
}

pub fn vssm_trace(pre: &Prefiltered, q: &Query) -> VssmTrace {
    let r = &pre.technique;
    let light = r.light();
    let uv = [q.uv[0] as f64, q.uv[1] as f64];
    let d = q.d as f64;
    let texel = 1.0 / pre.depth.base().size as f64;
    let min_variance = r.get("min_variance");
    let t = d - r.bias();
    let dist = distance(&light, d);
    let su = search_region(&light, dist);
    let search = vssm_moments(pre, uv, [0.0, 0.0], su);
    let p = chebyshev(search[0], search[1], t, min_variance).min(VSSM_LIT);
    let blocker = p < VSSM_LIT;
    let z_occ = vssm_blocker(search[0], p, t);
    let pu = filter_region(&light, dist, z_occ, texel);
    let whole_m = vssm_moments(pre, uv, [0.0, 0.0], pu);
    let whole = chebyshev(whole_m[0], whole_m[1], t, min_variance);
    let subdivided = blocker && r.int("subdivide") != 0 && whole >= 1.0;
    let half = [0.5 * pu[0], 0.5 * pu[1]];
    let quads = quadrants(pu).map(|o| {
        let m = vssm_moments(pre, uv, o, half);
        chebyshev(m[0], m[1], t, min_variance)
    });
    let value = if !blocker {
        1.0
    } else if subdivided {
        0.25 * quads.iter().sum::<f64>()
    } else {
        whole
    };
    VssmTrace {
        t,
        dist,
        su,
        search,
        p,
        blocker,
        z_occ,
        pu,
        whole_m,
        whole,
        subdivided,
        quads,
        value,
    }
}

// ---------------------------------------------------------------------------------------
// The Hamburger 4MSM bounding distribution (Peters & Klein 2015, Algorithm 2; Peters et al.
// 2017, Algorithm 1 with m = 4), with the matrix entries given apart from the moments

/// The Hamburger bounding distribution at `zf` for the Hankel matrix
/// `[1 a12 a13; a12 a22 a23; a13 a23 a33]` (`a = (a12, a13, a22, a23, a33)`; for moments b,
/// `(b1, b2, b2, b3, b4)`): the roots `z2 <= z3` of `c1 + c2 z + c3 z^2`, where
/// `M c = (1, zf, zf^2)`, by a Cholesky factorisation with pivots clamped at [`MSM_PIVOT`].
pub fn hamburger_roots(a: [f64; 5], zf: f64) -> (f64, f64) {
    let [a12, a13, a22, a23, a33] = a;
    let l22 = (a22 - a12 * a12).max(MSM_PIVOT).sqrt();
    let l32 = (a23 - a12 * a13) / l22;
    let l33 = (a33 - a13 * a13 - l32 * l32).max(MSM_PIVOT).sqrt();
    let y2 = (zf - a12) / l22;
    let y3 = (zf * zf - a13 - l32 * y2) / l33;
    let c3 = y3 / l33;
    let c2 = (y2 - l32 * c3) / l22;
    let c1 = 1.0 - a12 * c2 - a13 * c3;
    let (p, q) = (c2 / c3, c1 / c3);
    let r = (0.25 * p * p - q).max(0.0).sqrt();
    (-0.5 * p - r, -0.5 * p + r)
}

/// The weight of support point `x` of the three-point distribution on `{x, y, z}` with the
/// moments `(1, b1, b2)`: `E[(s - y)(s - z)] / ((x - y)(x - z))` (the Vandermonde system by
/// Lagrange's basis).
pub fn three_point_weight(b1: f64, b2: f64, x: f64, y: f64, z: f64) -> f64 {
    (b2 - (y + z) * b1 + y * z) / ((x - y) * (x - z))
}

/// The lower bound G of the shadow intensity (the weight below `zf`) of the Hamburger
/// bounding distribution, by Algorithm 2's three cases (b1, b2 the moments of its last step).
pub fn hamburger_intensity(z2: f64, z3: f64, b1: f64, b2: f64, zf: f64) -> f64 {
    if zf <= z2 {
        0.0
    } else if zf <= z3 {
        three_point_weight(b1, b2, z2, zf, z3)
    } else {
        1.0 - three_point_weight(b1, b2, zf, z2, z3)
    }
}

/// The three expectations the four-point distribution on `{0, t, g, 1}` is written in:
/// `R = E[(z - 1)(z - t)]`, `A = E[z (z - 1)(z - t)]`, `B = E[z (z - 1)(z - t)^2]`, from
/// the moments b1..b4 by nested differences (Newton's form): first `D_k = E[z^k (z - 1)]
/// = b_(k+1) - b_k` (b0 = 1), then `E[p (z - t)] = E[z p] - t E[p]` once for R and A (and
/// `C = E[z^2 (z - 1)(z - t)]`), once more for `B = C - t A`. Each subtraction cancels only
/// what the level before left (the moments of a distribution near {0, t, 1} differ in
/// their last digits), where the expanded polynomials `b3 - (1 + t) b2 + t b1` and
/// `b4 - (1 + 2t) b3 + (t^2 + 2t) b2 - t^2 b1` cancel values of the moments' size: in f32,
/// about 2^-24 |D| instead of 2^-24 |b| of absolute error.
pub fn hausdorff_functionals(b: [f64; 4], t: f64) -> [f64; 3] {
    let [b1, b2, b3, b4] = b;
    let d = [b1 - 1.0, b2 - b1, b3 - b2, b4 - b3];
    let r = d[1] - t * d[0];
    let a = d[2] - t * d[1];
    let c = d[3] - t * d[2];
    [r, a, c - t * a]
}

/// Hausdorff MSM's lower bound G of the shadow intensity at `t` (not clamped), the Hankel
/// matrix given by its entries `a` (see [`hamburger_roots`]) and the moments `b` for the
/// weights; and whether the four-point branch gave it.
///
/// Where the Hamburger solution's support `{t, z2, z3}` lies in [0, 1] it is a distribution
/// of depths in [0, 1] and its bound holds. Otherwise (Peters & Klein 2015, the Hausdorff
/// variant, as the specification states it): the distribution on `{0, t, g, 1}` with the
/// moments `b0..b4`. Derivation, with R, A, B of [`hausdorff_functionals`]: every such
/// distribution has `E[p(z)] = 0` for `p(z) = z (z - 1)(z - t)(z - g)`, and
/// `E[p] = E[z (z - 1)(z - t)^2] + (t - g) E[z (z - 1)(z - t)] = B + (t - g) A`, so
/// `g - t = B / A`. The weights by Lagrange's basis over the four points (moments b0..b3):
/// `w0 = E[(z - t)(z - g)(z - 1)] / (-t g) = (A - g R) / (-t g) = (g R - A) / (t g)`
/// (`E[(z - t)(z - 1)(z - g)] = E[z (z - t)(z - 1)] - g E[(z - t)(z - 1)]`),
/// `wg = E[z (z - t)(z - 1)] / (g (g - t)(g - 1)) = A / (g (B / A)(g - 1))`.
/// G is the weight strictly below t: `w0`, plus `wg` where `g < t` (`B / A < 0`).
/// Degenerate cases, as handled here:
/// - `t <= 0`: no depth in [0, 1] lies below t: G = 0;
/// - `t >= 1`: the points t and 1 coincide; the Hamburger bound is kept (the clamp follows);
/// - `|A| < 1e-12` (g undetermined: the moments are those of a distribution on {0, t, 1}
///   alone, wg = 0): `G = w0 = R / t` of the three points;
/// - a vanishing denominator of `w0` (g at 0) or of `wg` (g at t or 1): that weight is 0.
///
/// Near the boundary of the moment space (B near 0: the depths lie near {0, t, 1}) G is
/// a rational function with a pole at `B = 0` and a jump of `wg` where B / A changes sign:
/// the error model encloses it by interval arithmetic (`moments_tolerance`).
pub fn hausdorff_branch(a: [f64; 5], b: [f64; 4], t: f64) -> (f64, bool) {
    let (z2, z3) = hamburger_roots(a, t);
    if (z2 >= 0.0 && z3 <= 1.0) || t >= 1.0 {
        return (hamburger_intensity(z2, z3, b[0], b[1], t), false);
    }
    if t <= 0.0 {
        return (0.0, true);
    }
    let [r, a, bb] = hausdorff_functionals(b, t);
    if a.abs() < 1e-12 {
        return (r / t, true);
    }
    let q = bb / a;
    let g = t + q;
    let guarded = |num: f64, den: f64| if den.abs() < 1e-12 { 0.0 } else { num / den };
    let w0 = guarded(g * r - a, t * g);
    let wg = guarded(a, g * q * (g - 1.0));
    (if q < 0.0 { w0 + wg } else { w0 }, true)
}

/// [`hausdorff_branch`]'s G alone.
pub fn hausdorff_intensity(a: [f64; 5], b: [f64; 4], t: f64) -> f64 {
    hausdorff_branch(a, b, t).0
}

// ---------------------------------------------------------------------------------------
// MSSM

/// The moment bias of MSSM's quantised signed moments (JCGT 2017, section 3.1):
/// `b' = (1 - alpha) b + alpha (0, 0.628, 0, 0.628)`.
pub const MSSM_BIAS_TARGET: [f64; 4] = [0.0, 0.628, 0.0, 0.628];

/// The sparse quantisation transform (JCGT 2017, section 3.1) of the signed-depth powers
/// (s, s^2, s^3, s^4): each lies in [0, 1] for s in [-1, 1].
pub fn mssm_quantise(s: f64) -> [f64; 4] {
    let r3 = 3f64.sqrt();
    let (s2, s3) = (s * s, s * s * s);
    let s4 = s2 * s2;
    [
        1.5 * s - 2.0 * s3 + 0.5,
        4.0 * s2 - 4.0 * s4,
        0.5 * r3 * s - 2.0 * r3 / 9.0 * s3 + 0.5,
        0.5 * s2 + 0.5 * s4,
    ]
}

/// The channels the Map pass stores at depth z: the transform of s = 2z - 1, or z^k.
pub fn mssm_channels(quantise: bool, z: f64) -> [f64; 4] {
    if quantise {
        mssm_quantise(2.0 * z - 1.0)
    } else {
        [z, z * z, z * z * z, z * z * z * z]
    }
}

/// [`mssm_channels`] in f32, as the Map pass computes them (for the error model's codes).
pub fn mssm_channels_f32(quantise: bool, z: f32) -> [f32; 4] {
    if quantise {
        let r3 = 1.732_050_8f32;
        let s = 2.0 * z - 1.0;
        let (s2, s3) = (s * s, s * s * s);
        let s4 = s2 * s2;
        [
            1.5 * s - 2.0 * s3 + 0.5,
            4.0 * s2 - 4.0 * s4,
            0.5 * r3 * s - (2.0 * r3 / 9.0) * s3 + 0.5,
            0.5 * s2 + 0.5 * s4,
        ]
    } else {
        let z2 = z * z;
        [z, z2, z2 * z, z2 * z2]
    }
}

/// Filtered channels back to the signed-depth moments `E[s^k]`: the inverse of the
/// transform (odd: with u = q1 - 1/2, v = q3 - 1/2, b1 = sqrt(3) v - u / 3,
/// b3 = 3/4 (sqrt(3) v - u); even: b2 = q4 + q2 / 8, b4 = q4 - q2 / 8), or the binomial
/// expansion of (2z - 1)^k over the raw moments of z.
pub fn mssm_decode(quantise: bool, q: [f64; 4]) -> [f64; 4] {
    let [q1, q2, q3, q4] = q;
    if quantise {
        let r3 = 3f64.sqrt();
        let (u, v) = (q1 - 0.5, q3 - 0.5);
        [r3 * v - u / 3.0, q4 + 0.125 * q2, 0.75 * (r3 * v - u), q4 - 0.125 * q2]
    } else {
        [
            2.0 * q1 - 1.0,
            4.0 * q2 - 4.0 * q1 + 1.0,
            8.0 * q3 - 12.0 * q2 + 6.0 * q1 - 1.0,
            16.0 * q4 - 32.0 * q3 + 24.0 * q2 - 8.0 * q1 + 1.0,
        ]
    }
}

pub fn mssm_biased(r: &Resolved, b: [f64; 4]) -> [f64; 4] {
    let alpha = r.get("alpha");
    std::array::from_fn(|k| (1.0 - alpha) * b[k] + alpha * MSSM_BIAS_TARGET[k])
}

/// The moment-based blocker search (JCGT 2017; the specification's weighting): the
/// Hamburger bounding distribution at `sf` (matrix entries `a`, moments b1, b2 for the
/// weights), its roots' weights clamped to [0, 1], the mean signed depth of the roots in
/// front of sf with the receiver weighted by `lit_weight`, clamped to [-1, 1].
pub fn mssm_blocker(a: [f64; 5], b1: f64, b2: f64, sf: f64, lit_weight: f64) -> f64 {
    let (s1, s2) = hamburger_roots(a, sf);
    let weight = |x: f64, y: f64, z: f64| {
        let den = (x - y) * (x - z);
        if den.abs() < 1e-12 {
            0.0
        } else {
            ((b2 - (y + z) * b1 + y * z) / den).clamp(0.0, 1.0)
        }
    };
    let (mut w, mut s) = (0.0, 0.0);
    for (x, other) in [(s1, s2), (s2, s1)] {
        if x < sf {
            let wl = weight(x, sf, other);
            w += wl;
            s += wl * x;
        }
    }
    ((lit_weight * sf + s) / (lit_weight + w)).clamp(-1.0, 1.0)
}

/// The signed moments `(b1, b2, b2, b3, b4)` as the Hankel matrix's entries.
pub fn hankel(b: [f64; 4]) -> [f64; 5] {
    [b[0], b[1], b[1], b[2], b[3]]
}

/// The steps of MSSM's Shade for one receiver.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MssmTrace {
    /// d - bias, and 2 (d - bias) - 1
    pub ts: f64,
    pub sf: f64,
    pub dist: f64,
    pub su: [f64; 2],
    /// the biased signed moments over the search region
    pub search: [f64; 4],
    pub s_occ: f64,
    pub z_occ: f64,
    pub pu: [f64; 2],
    /// the biased signed moments over the filter region
    pub filter: [f64; 4],
    /// G before the clamp
    pub g: f64,
    pub value: f64,
}

/// MSSM's box means of q1..q4 from `tables`.
pub fn mssm_box(tables: &[(String, Table)], uv: [f64; 2], w: [f64; 2]) -> [f64; 4] {
    ["q1", "q2", "q3", "q4"].map(|name| tables.iter().find(|(n, _)| n == name).map_or(f64::NAN, |(_, t)| t.box_mean(uv, w)))
}

pub fn mssm_trace(pre: &Prefiltered, q: &Query) -> MssmTrace {
    mssm_trace_with(pre, q, &pre.tables)
}

/// [`mssm_trace`] reading the box means from `tables` (the exact ones, or the error
/// model's tables of the GPU's codes).
pub fn mssm_trace_with(pre: &Prefiltered, q: &Query, tables: &[(String, Table)]) -> MssmTrace {
    let r = &pre.technique;
    let light = r.light();
    let quantise = r.int("quantise") != 0;
    let uv = [q.uv[0] as f64, q.uv[1] as f64];
    let d = q.d as f64;
    let texel = 1.0 / pre.depth.base().size as f64;
    let ts = d - r.bias();
    let sf = 2.0 * ts - 1.0;
    let dist = distance(&light, d);
    let su = search_region(&light, dist);
    let search = mssm_biased(r, mssm_decode(quantise, mssm_box(tables, uv, su)));
    let s_occ = mssm_blocker(hankel(search), search[0], search[1], sf, r.get("lit_weight"));
    let z_occ = 0.5 * (s_occ + 1.0);
    let pu = filter_region(&light, dist, z_occ, texel);
    let filter = mssm_biased(r, mssm_decode(quantise, mssm_box(tables, uv, pu)));
    // tf = d - bias (depth_slope = 0): the same receiver as the search's
    let (z2, z3) = hamburger_roots(hankel(filter), sf);
    let g = hamburger_intensity(z2, z3, filter[0], filter[1], sf);
    MssmTrace {
        ts,
        sf,
        dist,
        su,
        search,
        s_occ,
        z_occ,
        pu,
        filter,
        g,
        value: 1.0 - g.clamp(0.0, 1.0),
    }
}

// ---------------------------------------------------------------------------------------
// The same steps in f32, for the error models' estimate of the forward error of what
// follows the Cholesky solve (as `cpu::msm_intensity_f32` does for MSM)

/// The roots `z2 <= z3` of the Hamburger system in f32 arithmetic, the steps of [`hamburger_roots`].
pub(crate) fn hamburger_roots_f32(b: [f32; 4], zf: f32) -> (f32, f32) {
    let [b1, b2, b3, b4] = b;
    let pivot = MSM_PIVOT as f32;
    let l22 = (b2 - b1 * b1).max(pivot).sqrt();
    let l32 = (b3 - b1 * b2) / l22;
    let l33 = (b4 - b2 * b2 - l32 * l32).max(pivot).sqrt();
    let y2 = (zf - b1) / l22;
    let y3 = (zf * zf - b2 - l32 * y2) / l33;
    let c3 = y3 / l33;
    let c2 = (y2 - l32 * c3) / l22;
    let c1 = 1.0 - b1 * c2 - b2 * c3;
    let (p, q) = (c2 / c3, c1 / c3);
    let r = (0.25 * p * p - q).max(0.0).sqrt();
    (-0.5 * p - r, -0.5 * p + r)
}

/// [`hausdorff_intensity`] in f32 at the moments `b` (the hand-written shader's steps).
pub fn hausdorff_intensity_f32(b: [f32; 4], t: f32) -> f32 {
    let (z2, z3) = hamburger_roots_f32(b, t);
    let [b1, b2, b3, b4] = b;
    let three = |x: f32, y: f32, z: f32| (b2 - (y + z) * b1 + y * z) / ((x - y) * (x - z));
    if (z2 >= 0.0 && z3 <= 1.0) || t >= 1.0 {
        return if t <= z2 {
            0.0
        } else if t <= z3 {
            three(z2, t, z3)
        } else {
            1.0 - three(t, z2, z3)
        };
    }
    if t <= 0.0 {
        return 0.0;
    }
    let d = [b1 - 1.0, b2 - b1, b3 - b2, b4 - b3];
    let r = d[1] - t * d[0];
    let a = d[2] - t * d[1];
    let bb = (d[3] - t * d[2]) - t * a;
    if a.abs() < 1e-12 {
        return r / t;
    }
    let q = bb / a;
    let g = t + q;
    let guarded = |num: f32, den: f32| if den.abs() < 1e-12 { 0.0 } else { num / den };
    let w0 = guarded(g * r - a, t * g);
    let wg = guarded(a, g * q * (g - 1.0));
    if q < 0.0 { w0 + wg } else { w0 }
}

/// [`mssm_blocker`] in f32 at the moments `b`.
pub fn mssm_blocker_f32(b: [f32; 4], sf: f32, lit_weight: f32) -> f32 {
    let (s1, s2) = hamburger_roots_f32(b, sf);
    let weight = |x: f32, y: f32, z: f32| {
        let den = (x - y) * (x - z);
        if den.abs() < 1e-12 {
            0.0
        } else {
            ((b[1] - (y + z) * b[0] + y * z) / den).clamp(0.0, 1.0)
        }
    };
    let (mut w, mut s) = (0.0, 0.0);
    for (x, other) in [(s1, s2), (s2, s1)] {
        if x < sf {
            let wl = weight(x, sf, other);
            w += wl;
            s += wl * x;
        }
    }
    ((lit_weight * sf + s) / (lit_weight + w)).clamp(-1.0, 1.0)
}
