//! The hand-written WGSL penumbra map (`sshc_tests::reference::penumbra_gpu`, analytic cones
//! and sheets intersected in f32) agrees texel by texel with the f64 CPU reference
//! (`sshc_tests::reference::penumbra`) of Wyman & Hansen 2003, on a square over a floor
//! under a sphere light, two overlapping occluders under each resolve rule, a distant disk
//! light, an open quad and a three-fin mesh. A light of radius 0 gives a map of exactly 1.
//!
//! # Tolerance
//!
//! Both sides compute the same geometry; the GPU rounds its inputs (view-space coordinates,
//! `Z_v`, `Z_P`, `k`) to f32 and computes in f32, relative error `u = 2^-24` per operation.
//! Per kept fragment (the f64 reference's `Z_F`, `Z_v`, `Z_P`, `I`), with `N = Z_F - Z_v`
//! and `D = Z_P - Z_v` (equation 1: `I = N / D`):
//!
//! - the intersection: a lateral error `dl = C u Lambda` of the ray or the primitive
//!   (`Lambda` the largest lateral coordinate the computation touches: the ray's lateral
//!   position at the far plane plus the largest cone base radius) moves the intersection
//!   along the ray by `dl / sigma`, `sigma` the rate at which the surface separates from the
//!   ray per unit of depth (`Z_v k / Z_F` for a sphere light, `k` for a distant disk; a sheet
//!   is tangent to its cones, so it separates at the same rate); the depths themselves carry
//!   `C u (Z_F + Z_F^2 / Z_v)` (the rounding of `Z_v`, of `Z_F` and of `k`, whose relative
//!   error is amplified by `Z_F / Z_v` in `Z_v k / (k - g)`): `dN = C u (Lambda / sigma +
//!   Z_F + Z_F^2 / Z_v)`;
//! - equation 1's condition: `dD = C u (Z_P + Z_v)` and `dI = (dN + I dD) / D`;
//! - the Bernstein interpolant: `|ds/dI| = 6 I (1 - I) <= 3/2`, so `ds = 3/2 dI + C u`;
//! - the resolve: KeepMin and KeepMax pass the largest `ds` through, Add and Multiply
//!   (`s <= 1`) sum them, plus `C u` per fragment for the accumulation.
//!
//! `C = 16` counts the roundings along the longest chain (inputs, the quadratic's
//! coefficients, the root, the lateral offsets, the division of equation 1): about ten
//! operations, doubled. Texels with `D <= 0` reference `I = 0` exactly (contact) and use the
//! same bound with `D` replaced by `dD`.
//!
//! Texels where the GPU keeps a different number of fragments than the reference lie within
//! rounding of a primitive's boundary (a ruling `t = 0, 1`, the far plane, the discard
//! `Z_F = Z_P`): they are excluded, counted, bounded by 1% of the penumbra's texels (those
//! with a fragment on either side), and each must have a 4-neighbour whose reference
//! fragment count differs from its own (a boundary crosses within one texel).
//!
//! [`Target::F16`] adds one f16 ulp of the value (either rounding direction).

use sshc_runtime::gpu::Gpu;
use sshc_tests::reference::penumbra::fixtures::{quad, scene, sphere};
use sshc_tests::reference::penumbra::{
    AreaLight, LightProjection, PenumbraReference, PenumbraSetup, Primitives, Resolve, fragments, primitives, silhouettes,
};
use sshc_tests::reference::penumbra_gpu::{Target, penumbra_map_gpu, penumbra_map_gpu_at, penumbra_map_gpu_f16};
use std::ops::Range;
use std::sync::OnceLock;

type V3 = [f64; 3];

const IDENTITY: [f64; 16] = [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0];
/// f32's unit roundoff.
const U: f64 = 1.0 / (1u64 << 24) as f64;
/// Roundings counted along the longest chain (see the module documentation).
const C: f64 = 16.0;
/// The largest share of the penumbra's texels allowed to sit on a primitive's boundary.
const BOUNDARY_SHARE: f64 = 0.01;

fn gpu() -> &'static Gpu {
    static GPU: OnceLock<Gpu> = OnceLock::new();
    GPU.get_or_init(|| Gpu::new().unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}")))
}

/// Orthographic light down -z covering [-4, 4], a distant disk with tan(angle / 2) = tan_half.
fn disk(tan_half: f64, size: usize, resolve: Resolve) -> PenumbraSetup {
    PenumbraSetup {
        view: IDENTITY,
        projection: LightProjection::Orthographic { half_height: 4.0 },
        near: 1.0,
        far: 20.0,
        size,
        light: AreaLight::DistantDisk {
            angle: 2.0 * tan_half.atan(),
        },
        resolve,
    }
}

/// The allowed difference at texel (i, j) for the f32 map: f32's relative rounding `u`,
/// counted `C` times, amplified by the ray-surface intersection's condition
/// (`Lambda / sigma`) and equation 1's (`1 / D`), through `|ds/dI| <= 3/2` and the resolve
/// rule; derived in the module documentation.
fn tolerance(r: &PenumbraReference, setup: &PenumbraSetup, i: usize, j: usize) -> f64 {
    let frags = fragments(&r.primitives, &r.shadow, setup, i, j);
    let (o, d) = setup.texel_ray(i, j);
    let max_cr = r.primitives.cones.iter().map(|c| c.base_radius).fold(0.0, f64::max);
    let lambda = setup.far * d[0].hypot(d[1]) + o[0].hypot(o[1]) + max_cr;
    let per: Vec<f64> = frags
        .iter()
        .map(|f| {
            let k = setup.spread(f.z_v);
            let sigma = match setup.projection {
                LightProjection::Perspective { .. } => f.z_v * k / f.z_f,
                LightProjection::Orthographic { .. } => k,
            };
            let dn = C * U * (lambda / sigma + f.z_f + f.z_f * f.z_f / f.z_v);
            let dd = C * U * (f.z_p + f.z_v);
            let den = (f.z_p - f.z_v).max(dd);
            let di = (dn + f.intensity * dd) / den;
            1.5 * di + C * U
        })
        .collect();
    let rounding = C * U * (frags.len() as f64 + 1.0);
    match setup.resolve {
        Resolve::KeepMin | Resolve::KeepMax => per.iter().copied().fold(0.0, f64::max) + rounding,
        Resolve::Add | Resolve::Multiply => per.iter().sum::<f64>() + rounding,
    }
}

/// The spacing of f16 values around v (one ulp); below the smallest normal f16, 2^-14, the
/// whole subnormal range, since conversions may flush f16 subnormals to zero (lavapipe does).
fn ulp16(v: f64) -> f64 {
    let v = v.abs();
    if v < 2f64.powi(-14) {
        2f64.powi(-14)
    } else {
        2f64.powi(v.log2().floor() as i32 - 10)
    }
}

#[derive(Debug, Default)]
struct Stats {
    penumbra: usize,
    boundary: usize,
    compared: usize,
    /// Compared texels with two fragments or more (where the resolve rule matters).
    multi: usize,
    max_err: f64,
    max_ratio: f64,
    max_err16: f64,
}

/// Compare the GPU maps (f32 and f16) with the reference, texel by texel, within
/// [`tolerance`] (derived in the module documentation), texels on a primitive's boundary
/// excluded and bounded.
fn agree(name: &str, tris: &[[V3; 3]], meshes: &[Range<usize>], setup: &PenumbraSetup) -> Stats {
    let r = PenumbraReference::new(tris, meshes, setup).unwrap();
    let g = penumbra_map_gpu_at(gpu(), setup, &r.shadow, &r.primitives, Target::F32).unwrap();
    let h = penumbra_map_gpu_f16(gpu(), setup, &r.shadow, &r.primitives).unwrap();
    let n = setup.size;
    let mut st = Stats::default();
    let rc = &r.penumbra.fragments;
    for j in 0..n {
        for i in 0..n {
            let k = j * n + i;
            let (want, got, half) = (r.penumbra.value[k], g.value[k] as f64, h[k] as f64);
            assert!(
                (0.0..=1.0).contains(&got) && (0.0..=1.0).contains(&half),
                "{name} texel ({i}, {j}): {got}, {half}"
            );
            if rc[k] > 0 || g.fragments[k] > 0 {
                st.penumbra += 1;
            }
            if rc[k] != g.fragments[k] {
                st.boundary += 1;
                let neighbours = [(0, 1), (2, 1), (1, 0), (1, 2)]
                    .iter()
                    .filter_map(|&(a, b)| Some(((i + a).checked_sub(1)?, (j + b).checked_sub(1)?)))
                    .filter(|&(a, b)| a < n && b < n);
                assert!(
                    neighbours.into_iter().any(|(a, b)| rc[b * n + a] != rc[k]),
                    "{name} texel ({i}, {j}): {} fragments on the GPU, {} in the reference, away from any boundary",
                    g.fragments[k],
                    rc[k]
                );
                continue;
            }
            st.compared += 1;
            if rc[k] >= 2 {
                st.multi += 1;
            }
            let tol = tolerance(&r, setup, i, j);
            let err = (got - want).abs();
            assert!(
                err <= tol,
                "{name} texel ({i}, {j}): GPU {got} vs reference {want} (error {err:e} > tolerance {tol:e}, {} fragments)",
                rc[k]
            );
            st.max_err = st.max_err.max(err);
            st.max_ratio = st.max_ratio.max(err / tol);
            // f16: one ulp of the value from the f32 map, so the f32 bound plus one ulp
            let err16 = (half - want).abs();
            assert!(
                (half - got).abs() <= ulp16(got) && err16 <= tol + ulp16(want),
                "{name} texel ({i}, {j}): f16 {half} vs f32 {got} vs reference {want}"
            );
            assert_eq!(half as f32 as f64, half);
            st.max_err16 = st.max_err16.max(err16);
        }
    }
    assert!(st.penumbra > 0, "{name}: no penumbra");
    assert!(
        st.boundary as f64 <= BOUNDARY_SHARE * st.penumbra as f64,
        "{name}: {} of {} penumbra texels on a boundary",
        st.boundary,
        st.penumbra
    );
    eprintln!(
        "{name}: {} penumbra texels, {} compared ({} with 2+ fragments), {} on a boundary; max |error| {:.3e} (f16 {:.3e}), max error / tolerance {:.3}",
        st.penumbra, st.compared, st.multi, st.boundary, st.max_err, st.max_err16, st.max_ratio
    );
    st
}

#[test]
fn square_over_floor_under_a_sphere_light() {
    let (tris, meshes) = scene(&[quad(-6.0, 6.0, -6.0, 6.0, -10.0), quad(-1.0, 1.0, -1.0, 1.0, -5.0)]);
    agree("square", &tris, &meshes, &sphere(1.0, 128, Resolve::KeepMin));
    // a rotated, tilted square: oblique sheets, unequal Z_v along its edges
    let (s, c) = 0.4f64.sin_cos();
    let corner = |x: f64, y: f64| [c * x - s * y, s * x + c * y, -5.0 + 0.3 * x - 0.2 * y];
    let (a, b, cc, dd) = (corner(-1.2, -0.9), corner(1.1, -0.9), corner(1.1, 1.0), corner(-1.2, 1.0));
    let tilted = vec![[a, b, cc], [a, cc, dd]];
    let (tris, meshes) = scene(&[quad(-6.0, 6.0, -6.0, 6.0, -10.0), tilted]);
    for rule in [Resolve::KeepMin, Resolve::Add] {
        agree(&format!("tilted square {rule:?}"), &tris, &meshes, &sphere(0.7, 112, rule));
    }
}

#[test]
fn two_overlapping_occluders_under_each_resolve_rule() {
    // side by side at one depth, penumbrae overlapping between the hard shadows
    let side = scene(&[
        quad(-6.0, 6.0, -6.0, 6.0, -10.0),
        quad(-2.175, -0.175, -1.0, 1.0, -5.0),
        quad(0.175, 2.175, -1.0, 1.0, -5.0),
    ]);
    // stacked at two depths, overlapping as seen from the light
    let stacked = scene(&[
        quad(-6.0, 6.0, -6.0, 6.0, -10.0),
        quad(-1.5, 0.5, -1.0, 1.0, -4.0),
        quad(-0.5, 2.2, -0.6, 1.6, -6.5),
    ]);
    for rule in Resolve::ALL {
        let a = agree(&format!("side by side {rule:?}"), &side.0, &side.1, &sphere(0.5, 160, rule));
        let b = agree(&format!("stacked {rule:?}"), &stacked.0, &stacked.1, &sphere(0.6, 128, rule));
        // the resolve rule is exercised: many texels combine several fragments
        assert!(
            a.multi >= 100 && b.multi >= 100,
            "{} and {} texels with 2+ fragments",
            a.multi,
            b.multi
        );
    }
}

#[test]
fn distant_disk_light() {
    let (tris, meshes) = scene(&[quad(-6.0, 6.0, -6.0, 6.0, -13.0), quad(-1.0, 1.0, -1.0, 1.0, -5.0)]);
    agree("disk", &tris, &meshes, &disk(0.1, 128, Resolve::KeepMin));
    let (tris, meshes) = scene(&[
        quad(-6.0, 6.0, -6.0, 6.0, -13.0),
        quad(-2.0, 0.5, -1.0, 1.0, -5.0),
        quad(-0.3, 1.5, -1.5, 0.4, -8.0),
    ]);
    for rule in Resolve::ALL {
        agree(&format!("disk two occluders {rule:?}"), &tris, &meshes, &disk(0.15, 96, rule));
    }
}

#[test]
fn open_quad_and_three_fins() {
    let floor = quad(-6.0, 6.0, -6.0, 6.0, -10.0);
    let tilted: Vec<[V3; 3]> = vec![
        [[-1.0, -1.0, -4.0], [1.5, -0.5, -5.0], [1.0, 1.0, -6.0]],
        [[-1.0, -1.0, -4.0], [1.0, 1.0, -6.0], [-1.2, 0.8, -5.0]],
    ];
    // three fins sharing one edge (non-manifold), the first facing the light, the others not
    let (p, q) = ([-0.5, -1.5, -5.0], [0.5, 1.5, -5.5]);
    let fins: Vec<[V3; 3]> = vec![[q, p, [2.0, 0.0, -5.0]], [q, p, [-2.0, 0.3, -4.5]], [p, q, [0.2, -0.1, -7.0]]];
    let quad_scene = scene(&[floor.clone(), tilted]);
    let fin_scene = scene(&[floor, fins]);
    for rule in Resolve::ALL {
        agree(&format!("open quad {rule:?}"), &quad_scene.0, &quad_scene.1, &sphere(0.4, 96, rule));
        agree(&format!("fins {rule:?}"), &fin_scene.0, &fin_scene.1, &sphere(0.4, 96, rule));
    }
}

#[test]
fn radius_zero_is_exactly_one() {
    let (tris, meshes) = scene(&[quad(-6.0, 6.0, -6.0, 6.0, -10.0), quad(-1.0, 1.0, -1.0, 1.0, -5.0)]);
    for rule in Resolve::ALL {
        let setup = sphere(0.0, 64, rule);
        let r = PenumbraReference::new(&tris, &meshes, &setup).unwrap();
        assert!(r.primitives.cones.is_empty() && r.primitives.sheets.is_empty());
        let v = penumbra_map_gpu(gpu(), &setup, &r.shadow, &r.primitives).unwrap();
        assert!(v.iter().all(|&v| v == 1.0), "{rule:?}");
        // zero-width primitives handed over anyway (cones of spread 0, sheets of a radius-1
        // light read with radius 0) draw nothing either
        let wide = sphere(1.0, 64, rule);
        let sil = silhouettes(&tris, &meshes, &wide).unwrap();
        let mut prims: Primitives = primitives(&sil, &wide);
        assert!(!prims.cones.is_empty() && !prims.sheets.is_empty());
        for c in &mut prims.cones {
            c.spread = 0.0;
            c.base_radius = 0.0;
        }
        let m = penumbra_map_gpu_at(gpu(), &setup, &r.shadow, &prims, Target::F32).unwrap();
        assert!(m.value.iter().all(|&v| v == 1.0) && m.fragments.iter().all(|&c| c == 0), "{rule:?}");
        let h = penumbra_map_gpu_f16(gpu(), &setup, &r.shadow, &prims).unwrap();
        assert!(h.iter().all(|&v| v == 1.0), "{rule:?}");
    }
}
