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

use sshc_tests::reference::linear::fixtures::{quad, segment_views};
use sshc_tests::reference::linear::*;

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
}
