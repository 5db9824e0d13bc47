//! The f64 reference of soft shadow maps for linear lights (`sshc_tests::reference::linear`,
//! Heidrich, Brabec & Seidel 2000) against closed forms, and the hand-written WGSL reference
//! (`sshc_tests::reference::linear_gpu`) against the f64 one channel by channel.
//!
//! The figure-2 scene (paper section 3.1, figure 2): world z up; a linear light from
//! `(-1, 0, H)` to `(1, 0, H)`, `H = 4` (length `L = 2`, along x); a receiver plane at `z = 0`
//! (parallel to the light); an occluder plane at `z = h = 2` covering `x <= e` (its edge runs
//! along y, perpendicular to the light). Every sample looks straight down with a 90-degree field
//! of view, near 1, far 6: the map covers 8 world units on the receiver (a texel is `8 / S`) and
//! 4 on the occluder. A receiver point `(x, y, 0)` sees the light point `x_l` iff the segment
//! between them crosses `z = h` at `x + (x_l - x) h / H >= e`, so its visible fraction is
//! `f(x) = clamp((L/2 - x - (e - x) H / h) / L, 0, 1)`: linear in `x`, eq. 1 with equal slopes
//! `m = n` of light and receiver.

use sshc_runtime::gpu::Gpu;
use sshc_tests::reference::linear::fixtures::{self, quad, segment_views};
use sshc_tests::reference::linear::*;
use sshc_tests::reference::linear_gpu::{GpuChannel, channels_gpu};
use sshc_tests::reference::penumbra::fixtures::cuboid;
use std::sync::OnceLock;

const H: f64 = 4.0;
const HO: f64 = 2.0;
const HALF_L: f64 = 1.0;
/// The occluder edge's x, off the texel grids so that no skin corner lands on a texel centre.
const E: f64 = 0.0137;
const NEAR: f64 = 1.0;
const FAR: f64 = 6.0;
/// Receiver and occluder linear depths from the light's height: 0.6 and 0.2, a jump of 0.4.
const TAU: f64 = 0.05;
const KEEP_BIAS: f64 = 1e-3;
/// The receiver and the occluder are perpendicular to every view's axis, so their depth is
/// constant across a texel: the shade's bias only has to absorb f64 rounding.
const BIAS: f64 = 1e-9;

fn setup(a: V3, b: V3, n: usize, size: usize, interpolation: Interpolation) -> LinearSetup {
    LinearSetup {
        views: segment_views(a, b, n, [0.0, 0.0, -1.0], [0.0, 1.0, 0.0], std::f64::consts::FRAC_PI_2, NEAR, FAR),
        closed: false,
        size,
        skin_threshold: TAU,
        keep_bias: KEEP_BIAS,
        bias: BIAS,
        interpolation,
    }
}

fn light(n: usize, size: usize, interpolation: Interpolation) -> LinearSetup {
    setup([-HALF_L, 0.0, H], [HALF_L, 0.0, H], n, size, interpolation)
}

fn receiver() -> Vec<[V3; 3]> {
    quad(-8.0, 8.0, -8.0, 8.0, 0.0)
}

/// The receiver and a half-plane occluder `{x cos(theta) + y sin(theta) <= e}` at `z = h`.
fn edge_scene(theta: f64, e: f64) -> Vec<[V3; 3]> {
    let (c, s) = (theta.cos(), theta.sin());
    let (n, t) = ([c, s], [-s, c]);
    let p = |a: f64, b: f64| [n[0] * a + t[0] * b, n[1] * a + t[1] * b, HO];
    let mut tris = receiver();
    tris.push([p(e - 16.0, -16.0), p(e, -16.0), p(e, 16.0)]);
    tris.push([p(e - 16.0, -16.0), p(e, 16.0), p(e - 16.0, 16.0)]);
    tris
}

/// The exact visible fraction of the segment light at receiver x (edge perpendicular to it).
fn exact_fraction(x: f64) -> f64 {
    ((HALF_L - x - (E - x) * H / HO) / (2.0 * HALF_L)).clamp(0.0, 1.0)
}

/// What the continuous algorithm gives with perspective-correct interpolation in the
/// penumbra seen by the right sample only: the skin of the left sample runs from the edge
/// `E = (e, h)` (value 0) to `P0`, where the left sample's ray through `E` meets the receiver
/// (value 1); the right sample's ray to the receiver point `(x, 0)` meets it at the affine
/// parameter `a`, the interpolated value.
fn perspective_prediction(x: f64) -> f64 {
    let (l0, l1) = ([-HALF_L, H], [HALF_L, H]);
    let edge = [E, HO];
    let p0 = [edge[0] + (edge[0] - l0[0]) * HO / (H - HO), 0.0];
    // solve edge + a (p0 - edge) = l1 + s ((x, 0) - l1)
    let (d1, d2) = ([p0[0] - edge[0], p0[1] - edge[1]], [x - l1[0], -l1[1]]);
    let rhs = [l1[0] - edge[0], l1[1] - edge[1]];
    let det = d1[0] * -d2[1] + d2[0] * d1[1];
    let a = (rhs[0] * -d2[1] + d2[0] * rhs[1]) / det;
    a.clamp(0.0, 1.0)
}

/// Receiver query points along the light's direction, off the texel grids.
fn receiver_line(x0: f64, x1: f64, count: usize) -> Vec<V3> {
    (0..count)
        .map(|i| [x0 + (x1 - x0) * (i as f64 + 0.37) / count as f64, 0.0213, 0.0])
        .collect()
}

/// Tolerance of the shaded visibility against the continuous algorithm in the figure-2 scene
/// at `S` texels: the visibility's slope across the penumbra is `1 / w`, `w` the penumbra's width
/// `L h / (H - h)` (= 2); (1) the shade reads the texel holding `p`, up to half a receiver texel
/// `t_r = 8 / S` from it; (2) the skin's ends are texel centres of the source view, within one
/// texel of the edge (`t_o = 4 / S` on the occluder, which the right sample projects onto the
/// receiver magnified `H / (H - h) = 2`: `t_r`) and of `P0` (`t_r`), shifting the ramp by at most
/// `t_r`. So `|V - V_continuous| <= (t_r / 2 + t_r) / w`.
fn ramp_tolerance(size: usize) -> f64 {
    let t_r = 8.0 / size as f64;
    let w = 2.0 * HALF_L * HO / (H - HO);
    1.5 * t_r / w
}

/// (a) Figure 2 with two samples: across the penumbra the shaded visibility rises from 0 to 1.
/// With the conventions' perspective-correct interpolation it follows the skin's affine
/// parameter seen from the other sample, which is a rational function of `x`, not the exact
/// linear `f`; interpolated affinely in the target view's screen (parallel to the receiver)
/// it is the exact linear fraction.
#[test]
fn figure_2_two_samples_ramp() {
    let size = 64;
    let tol = ramp_tolerance(size);
    let scene = edge_scene(0.0, E);
    let xs = receiver_line(-1.6, 1.6, 400);
    let mut worst = [0.0f64; 3];
    for interpolation in [Interpolation::Screen, Interpolation::Perspective] {
        let s = light(2, size, interpolation);
        let maps = linear_maps(&scene, &s).unwrap();
        assert!(!maps.skins[0].is_empty() && !maps.skins[1].is_empty(), "the edge makes skins");
        for p in &xs {
            let v = visibility_clamped(&s, &maps, *p);
            let f = exact_fraction(p[0]);
            match interpolation {
                Interpolation::Screen => {
                    let err = (v - f).abs();
                    worst[0] = worst[0].max(err);
                    assert!(
                        err <= tol,
                        "screen interpolation at x = {}: V = {v}, exact {f} (tolerance {tol})",
                        p[0]
                    );
                }
                Interpolation::Perspective => {
                    // inside the penumbra (sample 1 only) V follows the prediction; outside it is f
                    let pred = if f > 0.0 && f < 1.0 { perspective_prediction(p[0]) } else { f };
                    let err = (v - pred).abs();
                    worst[1] = worst[1].max(err);
                    worst[2] = worst[2].max((v - f).abs());
                    assert!(
                        err <= tol,
                        "perspective interpolation at x = {}: V = {v}, predicted {pred} (tolerance {tol})",
                        p[0]
                    );
                }
            }
        }
    }
    // the rational prediction departs from the linear fraction by up to
    // max (1 + u)(1 - u) / (2 (3 - u)) = 0.1716 (u = x - 2e, at u = 3 - 2 sqrt 2)
    let dev = (0..2000)
        .map(|i| -1.0 + 2.0 * i as f64 / 2000.0 + 2.0 * E)
        .map(|x| (perspective_prediction(x) - exact_fraction(x)).abs())
        .fold(0.0, f64::max);
    assert!((dev - 0.1716).abs() < 1e-3, "the prediction's departure is {dev}");
    assert!(worst[2] >= dev - tol, "perspective V departs from f by {} only", worst[2]);
    eprintln!(
        "figure 2, S = {size}: |V - f| <= {:.4} (screen), |V - prediction| <= {:.4}, |V - f| = {:.4} (perspective); tolerance {tol:.4}",
        worst[0], worst[1], worst[2]
    );
}

/// The point light's exact visibility at receiver x (occluder edge at `e`, light at height
/// `H` over `x_l`): the segment crosses `z = h` at `x + (x_l - x) h / H`.
fn point_visible(x: f64, x_l: f64) -> bool {
    x + (x_l - x) * HO / H >= E
}

fn receiver_grid(count: usize) -> Vec<V3> {
    let mut out = Vec::new();
    for j in 0..count {
        for i in 0..count {
            let f = |k: usize| -2.9 + 5.8 * (k as f64 + 0.31) / count as f64;
            out.push([f(i), f(j), 0.0]);
        }
    }
    out
}

/// (a, section 3.3) Figure 2 with three samples (ends and middle): each half of the light is a
/// linear light of half the weight; the middle sample sums both halves' channels. With screen
/// interpolation the shade is again the exact linear fraction: on `[2e - 1, 2e]` only the
/// right sample sees, `V = v_prev / 2` rising 0 -> 1/2; on `[2e, 2e + 1]` the middle and right
/// samples see, `V = 1/2 + v_prev / 2` of the middle sample, rising 1/2 -> 1. The tolerance is
/// figure 2's: the same slope (1/2 per world unit), texels and ends; except within one receiver
/// texel of `x = 2e`, the middle sample's shadow edge, where the texel of view 1 holding `p` can
/// see the receiver while `p` lies in its shadow (or the reverse) and the right sample's
/// `v_prev` (the middle sample's skin, near its receiver end: about 1) is summed with the middle
/// sample's `v_next` (0.5): `V` overshoots to about 0.8 where `f` is 0.5. Unlike the end
/// samples' edges (where `f` is 1 and the clamp hides the overshoot) this is visible; it is
/// bounded there by the weights: `V - f <= w_after_1 / 2 + (1 - f)`.
#[test]
fn figure_2_three_samples_ramp() {
    let size = 64;
    let tol = ramp_tolerance(size);
    let t_r = 8.0 / size as f64;
    let s = light(3, size, Interpolation::Screen);
    assert_eq!(s.views[1].weights, [0.5, 0.5]);
    let maps = linear_maps(&edge_scene(0.0, E), &s).unwrap();
    let (mut worst, mut overshoot) = (0.0f64, 0.0f64);
    for p in receiver_line(-1.6, 1.6, 400) {
        let v = visibility_clamped(&s, &maps, p);
        let f = exact_fraction(p[0]);
        if (p[0] - 2.0 * E).abs() < t_r {
            overshoot = overshoot.max(v - f);
            assert!(v - f <= 0.25 + (1.0 - f), "x = {}: V = {v}, exact {f}", p[0]);
            continue;
        }
        worst = worst.max((v - f).abs());
        assert!((v - f).abs() <= tol, "x = {}: V = {v}, exact {f} (tolerance {tol})", p[0]);
    }
    eprintln!(
        "figure 2, three samples, S = {size}: |V - f| <= {worst:.4} (tolerance {tol:.4}) away from the middle sample's shadow edge, V - f up to {overshoot:.4} within a texel of it"
    );
}

/// A closed chain (a triangle light's edges, paper section 4): three corner samples, each
/// edge a third of the perimeter, so every sample carries [1/3, 1/3]; sample 0's `v_prev` is
/// made of sample 2's skins; a receiver point every sample sees with no skin on it (beyond the
/// occluder's every shadow, inside every map) shades 1, one in the umbra 0.
#[test]
fn a_closed_chain_links_the_last_sample_to_the_first() {
    let size = 32;
    let corners = [[-1.0, -0.6, H], [1.0, -0.6, H], [0.0, 1.1, H]];
    let proj = fixtures::perspective(std::f64::consts::FRAC_PI_2, NEAR, FAR);
    let views = corners
        .iter()
        .map(|&eye| {
            let view = fixtures::look_at(eye, [eye[0], eye[1], 0.0], [0.0, 1.0, 0.0]);
            LinearView {
                view,
                view_proj: fixtures::mul(&proj, &view),
                near: NEAR,
                far: FAR,
                weights: [1.0 / 3.0; 2],
            }
        })
        .collect();
    let s = LinearSetup {
        views,
        closed: true,
        size,
        skin_threshold: TAU,
        keep_bias: KEEP_BIAS,
        bias: BIAS,
        interpolation: Interpolation::Perspective,
    };
    let mut scene = receiver();
    scene.extend(quad(-0.9, 0.9, -0.9, 0.9, HO));
    let maps = linear_maps(&scene, &s).unwrap();
    let direct = warp(&maps.skins[2], &maps.depth[0], &s, 0).unwrap();
    assert!(maps.v_prev[0].value == direct.value && maps.v_prev[0].winner == direct.winner);
    assert!(maps.v_prev[0].winner.iter().any(|w| w.is_some()));
    let lit = visibility(&s, &maps, [-2.6, 3.1, 0.0]);
    assert!((lit - 1.0).abs() < 1e-12, "lit receiver: {lit}");
    assert_eq!(visibility(&s, &maps, [0.013, 0.021, 0.0]), 0.0);
}

/// (b) One sample (the midpoint, weights [1, 1]): no channel is written (no neighbours), and
/// the shade is the hard shadow map: 0 or 1, the exact point-light visibility away from the
/// shadow's edge (more than one occluder texel, `4 / S`, from it).
#[test]
fn one_sample_is_the_hard_shadow_map() {
    let size = 64;
    let s = light(1, size, Interpolation::Perspective);
    assert_eq!(s.views[0].weights, [1.0, 1.0]);
    let maps = linear_maps(&edge_scene(0.0, E), &s).unwrap();
    assert!(maps.v_prev[0].value.iter().chain(&maps.v_next[0].value).all(|v| *v == 0.5));
    let t_o = 4.0 / size as f64;
    let mut compared = 0;
    for p in receiver_grid(60) {
        let v = visibility(&s, &maps, p);
        let hard = lit(&s, &maps, 0, p);
        assert_eq!(v, if hard { 1.0 } else { 0.0 }, "at {p:?}");
        if (p[0] * (1.0 - HO / H) - E).abs() > t_o {
            assert_eq!(hard, point_visible(p[0], 0.0), "at {p:?}");
            compared += 1;
        }
    }
    assert!(compared > 3000);
}

/// (c) A segment of length 0 with N = 2 and 3: every view is the same, so a skin warped into
/// its neighbour lands on the same texels it came from and meets texel centres only at its
/// corners. Every texel that is no skin corner keeps 0.5 in both channels, and there the shade
/// equals the hard shadow map; where it differs the texel is an occluder-side corner (value 0)
/// whose own skin covered it (the ray through a texel centre meets a corner on that ray only
/// up to rounding, so which of them are covered is not asserted).
#[test]
fn zero_length_segment_is_the_hard_shadow_map() {
    let size = 48;
    let scene = edge_scene(0.3, E);
    let hard = light(1, size, Interpolation::Perspective);
    let hard_maps = linear_maps(&scene, &hard).unwrap();
    for n in [2, 3] {
        let p0 = [0.0, 0.0, H];
        let s = setup(p0, p0, n, size, Interpolation::Perspective);
        let maps = linear_maps(&scene, &s).unwrap();
        let mut corner = vec![false; size * size];
        let mut occluder_corner = vec![false; size * size];
        for sk in &maps.skins[0] {
            for c in 0..3 {
                let (x, y) = sk.texels[c];
                corner[y * size + x] = true;
                occluder_corner[y * size + x] |= sk.value[c] == 0.0;
            }
        }
        assert!(corner.iter().any(|c| *c), "the edge makes skins");
        for k in 0..n {
            assert_eq!(maps.depth[k], hard_maps.depth[0], "N = {n}: view {k} is the midpoint's");
            for ch in [&maps.v_prev[k], &maps.v_next[k]] {
                for (t, (c, v)) in corner.iter().zip(&ch.value).enumerate() {
                    assert!(*c || *v == 0.5, "N = {n}, view {k}: texel {t} (no skin corner) holds {v}");
                }
            }
        }
        let mut differ = 0;
        for p in receiver_grid(60)
            .into_iter()
            .chain(receiver_grid(60).into_iter().map(|p| [p[0], p[1], HO]))
        {
            let v = visibility_clamped(&s, &maps, p);
            let want = if lit(&hard, &hard_maps, 0, p) { 1.0 } else { 0.0 };
            if v != want {
                let (x, y) = s.views[0].texel_of(p, size).unwrap();
                assert!(occluder_corner[y * size + x], "N = {n} at {p:?}: V = {v}, hard {want}");
                differ += 1;
            }
        }
        eprintln!("zero-length segment, N = {n}: {differ} of 7200 queries differ from hard, all at occluder-side skin corners");
    }
}

/// The exact visibility of sample `l` from world point `p` (a shadow ray against `scene`).
fn sees(scene: &[[V3; 3]], p: V3, l: V3) -> bool {
    let d = [l[0] - p[0], l[1] - p[1], l[2] - p[2]];
    !scene
        .iter()
        .any(|t| matches!(ray_hit(p, d, t), Some((s, _)) if s > 1e-9 && s < 1.0))
}

/// The receiver and a bar `{e0 <= x cos(theta) + y sin(theta) <= e1}` at `z = h`.
fn bar_scene(theta: f64, e0: f64, e1: f64) -> Vec<[V3; 3]> {
    let (c, s) = (theta.cos(), theta.sin());
    let (n, t) = ([c, s], [-s, c]);
    let p = |a: f64, b: f64| [n[0] * a + t[0] * b, n[1] * a + t[1] * b, HO];
    let mut tris = receiver();
    tris.push([p(e0, -16.0), p(e1, -16.0), p(e1, 16.0)]);
    tris.push([p(e0, -16.0), p(e1, 16.0), p(e0, 16.0)]);
    tris
}

/// (d) No cracks: a long bar whose edges lie at 20 degrees to the grid, two samples; every receiver
/// texel of view `j` strictly inside the band that sample `j` sees and the other does not
/// (the texel's receiver point and its four neighbours 1.5 receiver texels away all in it,
/// by exact shadow rays; where the other view's map holds the skin) is covered by a warped skin.
#[test]
fn no_cracks_along_a_long_edge() {
    let size = 48;
    let theta = 20f64.to_radians();
    let scene = bar_scene(theta, E - 0.6, E + 0.6);
    let s = light(2, size, Interpolation::Perspective);
    let maps = linear_maps(&scene, &s).unwrap();
    let pos = [[-HALF_L, 0.0, H], [HALF_L, 0.0, H]];
    let m = 1.5 * 8.0 / size as f64;
    for j in 0..2 {
        let other = 1 - j;
        let ch = if j == 1 { &maps.v_prev[1] } else { &maps.v_next[0] };
        let mut inside = 0;
        for y in 0..size {
            for x in 0..size {
                let z = maps.depth[j][y * size + x];
                let v = &s.views[j];
                let dist = v.near + z * (v.far - v.near);
                let p = v
                    .point_at((x as f64 + 0.5) / size as f64, (y as f64 + 0.5) / size as f64, dist)
                    .unwrap();
                // the receiver only, and only where the other view's map holds both p and the
                // occluder point on the ray from sample j through p (the skin's end), two texels
                // inside its border (it covers 4 world units at the occluder, 8 on the receiver)
                let q = [pos[j][0] + (p[0] - pos[j][0]) * (H - HO) / H, p[1] * (H - HO) / H];
                let inside_other = |x: f64, y: f64, half: f64| {
                    let m = half - 2.0 * 2.0 * half / size as f64;
                    (x - pos[other][0]).abs() <= m && y.abs() <= m
                };
                if p[2].abs() > 1e-9 || !inside_other(p[0], p[1], 4.0) || !inside_other(q[0], q[1], 2.0) {
                    continue;
                }
                let band = |q: V3| sees(&scene, q, pos[j]) && !sees(&scene, q, pos[other]);
                let around = [[0.0, 0.0], [m, 0.0], [-m, 0.0], [0.0, m], [0.0, -m]];
                if around.iter().all(|o| band([p[0] + o[0], p[1] + o[1], 0.0])) {
                    inside += 1;
                    assert!(ch.winner[y * size + x].is_some(), "view {j}: texel ({x}, {y}) at {p:?} is a crack");
                }
            }
        }
        assert!(inside > 100, "view {j}: only {inside} texels inside the band");
        eprintln!("no cracks, view {j}: {inside} texels strictly inside the penumbra band, all covered");
    }
}

fn assert_finite(name: &str, s: &LinearSetup, maps: &LinearMaps) {
    for k in 0..s.views.len() {
        assert!(maps.depth[k].iter().all(|z| (0.0..=1.0).contains(z)), "{name}: depth");
        for ch in [&maps.v_prev[k], &maps.v_next[k]] {
            if let Some(v) = ch.value.iter().find(|v| !(0.0..=1.0).contains(*v)) {
                panic!("{name}: channel value {v:e} ({:?}) leaves [0, 1] or is NaN", s.interpolation);
            }
            for (d, w) in ch.depth.iter().zip(&ch.winner) {
                assert_eq!(w.is_some(), d.is_finite(), "{name}: a winner without a finite depth");
            }
        }
    }
    for p in receiver_grid(40)
        .into_iter()
        .chain(receiver_grid(40).into_iter().map(|p| [p[0], p[1], HO]))
    {
        let v = visibility(s, maps, p);
        assert!(v.is_finite() && (0.0..=2.0).contains(&v), "{name}: V = {v} at {p:?}");
    }
}

/// (e) Degenerate skins: a discontinuity parallel to the segment (its skins lie in planes
/// through the light, edge-on in the neighbour's view), a one-texel occluder, occluders at the
/// map's border, and no caster at all: every channel finite in `[0, 1]`, every shade finite.
#[test]
fn degenerate_skins_give_no_nan() {
    let size = 32;
    let t_o = 4.0 / size as f64;
    let mut tiny = receiver();
    tiny.extend(quad(0.013, 0.013 + t_o, 0.021, 0.021 + t_o, HO));
    let mut border = receiver();
    // the middle sample's map covers x, y in [-2, 2] at the occluder's height
    border.extend(quad(1.9, 9.0, -9.0, 9.0, HO));
    border.extend(quad(-9.0, 9.0, 1.95, 9.0, HO + 0.5));
    border.extend(quad(-9.0, -2.0 + 0.01, -9.0, 9.0, HO));
    let cases: Vec<(&str, Vec<[V3; 3]>, bool)> = vec![
        ("edge parallel to the light", edge_scene(std::f64::consts::FRAC_PI_2, E), true),
        ("one-texel occluder", tiny, true),
        ("occluders at the border", border, true),
        ("receiver only", receiver(), false),
        ("nothing", Vec::new(), false),
    ];
    for (name, scene, has_skins) in cases {
        for n in [2, 3] {
            for interpolation in [Interpolation::Perspective, Interpolation::Screen] {
                let s = light(n, size, interpolation);
                let maps = linear_maps(&scene, &s).unwrap();
                assert_eq!(maps.skins.iter().any(|k| !k.is_empty()), has_skins, "{name}");
                assert_finite(name, &s, &maps);
            }
        }
    }
}

/// A closed chain links the last sample to the first; an open one does not; a lone sample has
/// no neighbour.
#[test]
fn chain_neighbours() {
    let mut s = light(3, 8, Interpolation::Perspective);
    assert_eq!(
        (s.prev_of(0), s.next_of(0), s.prev_of(2), s.next_of(2)),
        (None, Some(1), Some(1), None)
    );
    s.closed = true;
    assert_eq!((s.prev_of(0), s.next_of(2)), (Some(2), Some(0)));
    let one = light(1, 8, Interpolation::Perspective);
    assert_eq!((one.prev_of(0), one.next_of(0)), (None, None));
}

/// Bad set-ups are refused with a message, never a panic.
#[test]
fn bad_setups_are_refused() {
    let good = light(2, 8, Interpolation::Perspective);
    let mut cases: Vec<(LinearSetup, &str)> = Vec::new();
    let mut s = good.clone();
    s.views.clear();
    cases.push((s, "1 to 16"));
    let mut s = good.clone();
    s.size = 1;
    cases.push((s, "map size"));
    let mut s = good.clone();
    s.views[1].far = 0.5;
    cases.push((s, "near < far"));
    let mut s = good.clone();
    s.views[0].view[3] = f64::NAN;
    cases.push((s, "finite"));
    let mut s = good.clone();
    s.skin_threshold = -1.0;
    cases.push((s, "skin_threshold"));
    let mut s = good.clone();
    s.keep_bias = f64::INFINITY;
    cases.push((s, "keep_bias"));
    for (s, want) in cases {
        let e = linear_maps(&receiver(), &s).unwrap_err();
        assert!(e.contains(want), "{e}");
    }
    let e = linear_maps_from_depth(vec![vec![0.5; 64]; 1], &good).unwrap_err();
    assert!(e.contains("1 depth maps for 2 samples"), "{e}");
    let e = linear_maps_from_depth(vec![vec![0.5; 64], vec![1.5; 64]], &good).unwrap_err();
    assert!(e.contains("outside [0, 1]"), "{e}");
    let e = linear_maps_from_depth(vec![vec![0.5; 64], vec![0.5; 63]], &good).unwrap_err();
    assert!(e.contains("63 texels"), "{e}");
    // the parts refuse what does not fit too
    assert!(depth_map(&receiver(), &good, 2).unwrap_err().contains("no sample 2"));
    assert!(skins(&[0.5; 63], &good, 0).unwrap_err().contains("63 texels"));
    assert!(warp(&[], &[0.5; 64], &good, 5).unwrap_err().contains("no sample 5"));
    assert!(laplacian(&[0.5; 3], 2).is_err());
    let maps = linear_maps(&receiver(), &good).unwrap();
    let mut other = good.clone();
    other.views.push(other.views[0]);
    assert!(!lit(&other, &maps, 2, [0.0, 0.0, 0.0]));
    assert!(visibility(&other, &maps, [0.0, 0.0, 0.0]).is_finite());
}

fn gpu() -> &'static Gpu {
    static GPU: OnceLock<Gpu> = OnceLock::new();
    GPU.get_or_init(|| Gpu::new().unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}")))
}

/// How one channel's texels compare.
#[derive(Debug, Default)]
struct Agreement {
    /// Same winner (or none in both), value and depth within tolerance.
    same: usize,
    /// Different winners whose fragments have the same value and depth within tolerance (a
    /// texel centre on an edge two skins share, or two skins at equal depth).
    ties: usize,
    /// Different results where the texel centre lies within f32 rounding of an edge of either
    /// winner, or either winner's keep test or the depth test between them is within rounding.
    edge: usize,
    /// Anything else.
    failures: Vec<String>,
    worst_value: f64,
    covered: usize,
}

const EPS32: f64 = f32::EPSILON as f64;

/// Compare the WGSL channel of view `j` (skins of view `i`) with the f64 one.
///
/// Tolerances, from f32: the WGSL places a corner by a 3 x 3 solve whose terms are world
/// coordinates up to `R` (the largest coordinate of a skin corner or of the views'
/// translations) and projects it, each step a few roundings; we allow 32 roundings of `R`:
/// a world error `32 eps R`, which at view distance `>= near_j` is a screen error of
/// `dq = 32 eps (R / near_j) (S / 2)` texels (the map spans `2 dist / f` world units at `dist`,
/// `f >= 1` here). An edge function of an edge `L` texels long is then off by `2 L dq`, so a
/// texel centre's distance to an edge by `2 dq` (the edge margin), and a screen barycentric
/// (edge function over twice the area) by `2 dq / h`, `h` the triangle's smallest height in
/// texels; the perspective weights `l_k / w_k` over their sum multiply that by at most
/// `w_max / w_min` of the corners. Values are barycentric mixes of 0 and 1: `tol_v = 2 dq
/// (w_max / w_min) / h + 8 eps`. Depths mix the corners' depths (each off by `32 eps R /
/// (far - near)`): `tol_d = tol_v + 32 eps R / (far_j - near_j)`.
fn agree(setup: &LinearSetup, maps: &LinearMaps, i: usize, j: usize, cpu: &Channel, gpu: &GpuChannel) -> Agreement {
    let n = setup.size;
    let vj = &setup.views[j];
    let skins = &maps.skins[i];
    let mut r = 0.0f64;
    for sk in skins {
        for p in sk.world {
            r = r.max(p.iter().fold(0.0f64, |m, c| m.max(c.abs())));
        }
    }
    for v in &setup.views {
        r = r.max(v.view[12].abs()).max(v.view[13].abs()).max(v.view[14].abs());
    }
    let dq = 32.0 * EPS32 * (r / vj.near) * (n as f64 / 2.0);
    let margin = 2.0 * dq;
    let d_tol_extra = 32.0 * EPS32 * r / (vj.far - vj.near);
    let find = |idx: u32| skins.binary_search_by_key(&idx, |s| s.index).ok().map(|k| &skins[k]);
    let tol_v = |sk: &Skin| -> f64 {
        let Some(pr) = project(sk, vj, n) else { return f64::INFINITY };
        let len = |a: usize, b: usize| ((pr.q[b][0] - pr.q[a][0]).powi(2) + (pr.q[b][1] - pr.q[a][1]).powi(2)).sqrt();
        let area2 = ((pr.q[1][0] - pr.q[0][0]) * (pr.q[2][1] - pr.q[0][1]) - (pr.q[1][1] - pr.q[0][1]) * (pr.q[2][0] - pr.q[0][0])).abs();
        let h = [area2 / len(1, 2), area2 / len(2, 0), area2 / len(0, 1)]
            .into_iter()
            .fold(f64::INFINITY, f64::min);
        let wr = pr.w.iter().fold(0.0f64, |m, w| m.max(*w)) / pr.w.iter().fold(f64::INFINITY, |m, w| m.min(*w));
        2.0 * dq * wr / h + 8.0 * EPS32
    };
    let mut a = Agreement::default();
    for y in 0..n {
        for x in 0..n {
            let t = y * n + x;
            let (cw, gw) = (cpu.winner[t], gpu.winner[t]);
            a.covered += cw.is_some() as usize;
            let dv = (cpu.value[t] - gpu.value[t] as f64).abs();
            let dd = (cpu.depth[t] - gpu.depth[t] as f64).abs();
            if cw.is_some() && gw.is_some() {
                a.worst_value = a.worst_value.max(dv);
            }
            let tv = cw
                .and_then(find)
                .map(tol_v)
                .unwrap_or(8.0 * EPS32)
                .max(gw.and_then(find).map(tol_v).unwrap_or(8.0 * EPS32));
            let close = dv <= tv && (cw.is_none() || dd <= tv + d_tol_extra);
            if cw == gw {
                // one skin's fragment in both: its value and depth are continuous across the
                // texel, so no rounding of an edge or test excuses a difference
                if close {
                    a.same += 1;
                } else {
                    a.failures.push(format!(
                        "texel ({x}, {y}): skin {cw:?}: f64 value {} depth {}, WGSL value {} depth {} (tolerance {tv:e})",
                        cpu.value[t], cpu.depth[t], gpu.value[t], gpu.depth[t]
                    ));
                }
                continue;
            }
            if cw != gw && cw.is_some() && gw.is_some() && close {
                a.ties += 1;
                continue;
            }
            // within rounding of an edge, of the keep test or of the depth test?
            let mut borderline = false;
            let mut frags = Vec::new();
            for w in [cw, gw].into_iter().flatten() {
                let Some(sk) = find(w) else { continue };
                if let Some(e) = edge_distances(sk, setup, j, x, y)
                    && e.iter().any(|d| d.abs() <= margin)
                {
                    borderline = true;
                }
                if let Some(f) = fragment(sk, setup, j, x, y) {
                    let tol_d = tol_v(sk) + d_tol_extra;
                    if (f.depth - (maps.depth[j][t] + setup.keep_bias)).abs() <= tol_d {
                        borderline = true;
                    }
                    frags.push((f.depth, tol_d));
                }
            }
            if let [(d0, t0), (d1, t1)] = frags[..]
                && (d0 - d1).abs() <= t0.max(t1)
            {
                borderline = true;
            }
            if borderline {
                a.edge += 1;
            } else {
                a.failures.push(format!(
                    "texel ({x}, {y}): f64 {:?} value {} depth {}, WGSL {:?} value {} depth {} (tolerance {tv:e})",
                    cw, cpu.value[t], cpu.depth[t], gw, gpu.value[t], gpu.depth[t]
                ));
            }
        }
    }
    a
}

fn check_agreement(name: &str, setup: &LinearSetup, scene: &[[V3; 3]]) -> (usize, usize, usize) {
    let maps = linear_maps(scene, setup).unwrap();
    let g = channels_gpu(gpu(), setup, &maps.depth).unwrap_or_else(|e| panic!("{name}: {e}"));
    let (mut covered, mut ties, mut edge) = (0, 0, 0);
    for j in 0..setup.views.len() {
        for (src, cpu, gpu_ch, what) in [
            (setup.prev_of(j), &maps.v_prev[j], &g.v_prev[j], "v_prev"),
            (setup.next_of(j), &maps.v_next[j], &g.v_next[j], "v_next"),
        ] {
            let Some(i) = src else {
                assert!(gpu_ch.value.iter().all(|v| *v == 0.5) && cpu.value.iter().all(|v| *v == 0.5));
                continue;
            };
            let a = agree(setup, &maps, i, j, cpu, gpu_ch);
            assert!(
                a.failures.is_empty(),
                "{name}, {what} of view {j}: {} texels disagree:\n{}",
                a.failures.len(),
                a.failures.join("\n")
            );
            // texels decided within rounding lie within `margin` (1e-4 texels here) of an edge
            // or of a keep or depth test: at most a few per channel unless geometry puts
            // centres exactly on them
            assert!(
                a.edge <= 2 + a.covered / 100,
                "{name}, {what} of view {j}: {} of {} covered texels decided by rounding",
                a.edge,
                a.covered
            );
            eprintln!(
                "{name}, {what} of view {j}: {} covered, {} same, {} ties, {} edge cases, largest value difference {:.2e}",
                a.covered, a.same, a.ties, a.edge, a.worst_value
            );
            covered += a.covered;
            ties += a.ties;
            edge += a.edge;
        }
    }
    (covered, ties, edge)
}

/// The WGSL channels against the f64 ones: a tilted light, three samples, views turned off
/// the axes, a bar at 20 degrees and a box (both interpolations); and the figure-2 scene,
/// whose views share an orientation so that the mesh's rows land exactly on texel centres.
#[test]
fn the_wgsl_channels_agree_with_the_f64_reference() {
    let size = 32;
    let mut scene = bar_scene(20f64.to_radians(), E - 0.6, E + 0.6);
    scene.extend(cuboid([0.6, -1.3, 1.2], [1.3, -0.55, 2.4]));
    for interpolation in [Interpolation::Perspective, Interpolation::Screen] {
        let s = LinearSetup {
            views: segment_views(
                [-1.0, -0.3, 4.1],
                [1.0, 0.37, 3.9],
                3,
                [0.05, -0.03, -1.0],
                [0.1, 1.0, 0.0],
                std::f64::consts::FRAC_PI_2,
                NEAR,
                FAR,
            ),
            closed: false,
            size,
            skin_threshold: TAU,
            keep_bias: KEEP_BIAS,
            bias: BIAS,
            interpolation,
        };
        let (covered, _, edge) = check_agreement(&format!("tilted ({interpolation:?})"), &s, &scene);
        assert!(covered > 300, "only {covered} covered texels");
        eprintln!("tilted ({interpolation:?}): {edge} edge cases in {covered} covered texels");
    }
    let s = light(2, size, Interpolation::Perspective);
    let (covered, ties, edge) = check_agreement("figure 2", &s, &edge_scene(0.0, E));
    eprintln!("figure 2: {covered} covered texels, {ties} ties, {edge} edge cases");
}

/// The WGSL reference refuses what the f64 one refuses.
#[test]
fn the_wgsl_reference_refuses_bad_inputs() {
    let s = light(2, 8, Interpolation::Perspective);
    let e = channels_gpu(gpu(), &s, &[vec![0.5; 64]]).unwrap_err();
    assert!(e.contains("1 depth maps for 2 samples"), "{e}");
    let mut bad = s.clone();
    bad.size = 0;
    assert!(channels_gpu(gpu(), &bad, &[vec![0.5; 64], vec![0.5; 64]]).is_err());
}

/// A runtime sample view converts field by field.
#[test]
fn a_runtime_sample_view_converts() {
    let v = light(2, 8, Interpolation::Perspective).views[1];
    let f = |m: &[f64; 16]| m.map(|x| x as f32);
    let s = sshc_runtime::gpu::SampleView {
        light_view: f(&v.view),
        light_view_proj: f(&v.view_proj),
        position: [1.0, 0.0, 4.0],
        near: 1.0,
        far: 6.0,
        light_proj_y: 1.0,
        weights: [1.0, 0.0],
    };
    let w = LinearView::from_sample(&s);
    assert_eq!((w.near, w.far, w.weights), (1.0, 6.0, [1.0, 0.0]));
    for k in 0..16 {
        assert!((w.view[k] - v.view[k]).abs() < 1e-6 && (w.view_proj[k] - v.view_proj[k]).abs() < 1e-6);
    }
}
