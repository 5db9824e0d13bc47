//! The f64 penumbra-limit-map reference (`sshc_tests::reference::plm`, Lawlor 2006) against
//! closed forms, and the hand-written WGSL reference (`sshc_tests::reference::plm_gpu`) against
//! the f64 one texel by texel.
//!
//! The edge scene is scenes/edge.ron's set-up in the light's view space: a one-sided quad over
//! `x in [-1, 0]`, `y in [-1, 1]` at view distance 2, a floor 1 further (view distance 3), a
//! distant disk straight overhead of angular diameter 10 degrees, the map covering
//! `[-1, 1] x [-1, 1]`. A floor receiver at signed distance `s` from the edge's shadow line
//! (positive outside the occluder) sees the disk cut by a chord at `u = s / (h tan(angle / 2))`,
//! `h = 1`, and its visible power is `f(u) = 1/2 + (u sqrt(1 - u^2) + asin u) / pi`, `u`
//! clamped to `[-1, 1]`.

use sshc_runtime::gpu::Gpu;
use sshc_tests::reference::Storage;
use sshc_tests::reference::penumbra::fixtures::{cuboid, quad, scene, sphere};
use sshc_tests::reference::penumbra::{AreaLight, LightProjection, PenumbraSetup, Resolve};
use sshc_tests::reference::plm::*;
use sshc_tests::reference::plm_gpu::{as_maps, plm_maps_gpu};
use std::ops::Range;
use std::sync::OnceLock;

type V3 = [f64; 3];
type Scene = (Vec<[V3; 3]>, Vec<Range<usize>>);

const IDENTITY: [f64; 16] = [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0];
/// The edge scene's occluder and floor view distances.
const Z_E: f64 = 2.0;
const Z_F: f64 = 3.0;
/// The receiver bias of the lookups (linear normalised depth).
const BIAS: f64 = 1e-4;
/// The largest slope `df/dl` of the limb-darkened table: `2 (0.8 + 0.3 pi) / (0.8 pi)`.
const LIMB_SLOPE: f64 = 2.0 * (0.8 + 0.3 * std::f64::consts::PI) / (0.8 * std::f64::consts::PI);
const STORAGES: [Option<Storage>; 5] = [
    None,
    Some(Storage::F32),
    Some(Storage::F16),
    Some(Storage::Unorm16),
    Some(Storage::Unorm8),
];

fn gpu() -> &'static Gpu {
    static GPU: OnceLock<Gpu> = OnceLock::new();
    GPU.get_or_init(|| Gpu::new().unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}")))
}

/// The edge scene's light: near 1.75, far 3.25 (`far - near = 1.5`), so that every texel within
/// one texel of the penumbra holds `|p_i| <= 2` at 16 texels (`(0.0875 + 0.125) / (0.0875 1.5)
/// = 1.62`) and the unorm range `[-2, 2]` of the stored `p_i / 4 + 1/2` clips none of them.
fn edge_light(size: usize, angle_deg: f64) -> PenumbraSetup {
    PenumbraSetup {
        view: IDENTITY,
        projection: LightProjection::Orthographic { half_height: 1.0 },
        near: Z_E - 0.25,
        far: Z_F + 0.25,
        size,
        light: AreaLight::DistantDisk {
            angle: angle_deg.to_radians(),
        },
        resolve: Resolve::KeepMin,
    }
}

fn edge_scene() -> Scene {
    scene(&[quad(-1.0, 1.0, -1.0, 1.0, -Z_F), quad(-1.0, 0.0, -1.0, 1.0, -Z_E)])
}

/// The visible power of a uniform disk cut by a chord at `u = s / w` (clamped).
fn closed_form(s: f64, w: f64) -> f64 {
    let u = (s / w).clamp(-1.0, 1.0);
    0.5 + (u * (1.0 - u * u).sqrt() + u.asin()) / std::f64::consts::PI
}

/// Half the step of a stored value in `[0, 1]` (the largest rounding error of one texel).
fn half_step(storage: Option<Storage>) -> f64 {
    match storage {
        None => 1e-15,
        Some(Storage::F32) => 2f64.powi(-25),
        Some(Storage::F16) => 2f64.powi(-12),
        Some(Storage::Unorm16) => 0.5 / 65535.0,
        Some(Storage::Unorm8) => 0.5 / 255.0,
    }
}

/// Penumbra limit maps are exact along a straight edge up to the stored precision (Lawlor,
/// section 4: "up to depth quantization error penumbra limit shadows are exact along straight
/// occluder edges").
///
/// Tolerance. Along the edge `c` is the constant occluder depth and `p_i = s / S` a plane
/// (`S = tan(angle / 2) (far - near)`), so bilinear interpolation reproduces both exactly;
/// what remains is the rounding of each stored texel: `e_c` on `c` and `e_p` on
/// `p = p_i / 4 + 1/2`, i.e. `4 e_p` on `p_i` (half a step: Unorm8 `1/510`, Unorm16 `1/131070`,
/// F16 `2^-12` for values in `[0, 1)`, F32 `2^-25`), and since the bilinear weights sum to 1 the
/// sampled values carry the same bounds. The floor receiver's `delta = d - c` is
/// `delta_0 = (Z_F - Z_E) / (far - near)` less the receiver bias `beta` and the error of `c`,
/// so with `u = p_i / delta_0`:
/// `|l' - l| <= (4 e_p + |u| (e_c + beta)) / (2 (delta_0 - beta - e_c))`.
/// Inside the penumbra equation 2 adds nothing (`d >= g`, `d >= c`, `d < b = 1`, so
/// `l_g = l`) and outside it saturates, and `sat` is 1-Lipschitz; the uniform disk's table has
/// `df/dl = (4 / pi) sqrt(1 - u^2) <= 4 / pi`. So the visibility is within
/// `(4 / pi) |l' - l|` of the closed form (plus 1e-12 for f64 rounding). At Unorm8 that is
/// `1.9 / 255` in the penumbra. The limb-darkened table's slope is `2 (0.8 a + 0.3 pi a^2) /
/// (0.8 pi)` with `a = sqrt(1 - u^2) <= 1` ([`LIMB_SLOPE`]).
#[test]
fn straight_edge_is_exact_up_to_the_storage_precision() {
    let (tris, meshes) = edge_scene();
    let w = 5f64.to_radians().tan() * (Z_F - Z_E);
    for n in [16usize, 128] {
        let setup = PlmSetup::new(edge_light(n, 10.0));
        let r = PlmReference::new(&tris, &meshes, &setup).unwrap();
        let texel = setup.texel();
        // the precondition: the texels within a texel of the penumbra hold the edge's ribbon
        // with |p_i| <= 2 (not clipped by the stored range)
        let edge_ribbon = r
            .ribbons
            .iter()
            .position(|rb| rb.a[0] == 0.0 && rb.b[0] == 0.0)
            .expect("the edge x = 0 draws a ribbon");
        for j in 0..n {
            for i in 0..n {
                let q = setup.texel_centre(i, j);
                if q[0].abs() <= w + texel && q[1].abs() <= 0.6 {
                    let k = j * n + i;
                    assert_eq!(r.maps.winner[k], Some(edge_ribbon), "texel ({i}, {j})");
                    assert!(r.maps.p_i[k].abs() <= 2.0);
                    assert!((r.maps.p_i[k] - q[0] / setup.limit_scale()).abs() < 1e-12);
                }
            }
        }
        let delta0 = (Z_F - Z_E) / (setup.light.far - setup.light.near);
        for storage in STORAGES {
            let e = half_step(storage);
            let (mut sq, mut count, mut worst) = (0.0, 0usize, 0.0f64);
            for k in 0..=600 {
                let s = -0.3 + 0.6 * k as f64 / 600.0;
                for y in [-0.41, 0.0137, 0.29] {
                    let p = [s, y, -Z_F];
                    let v = plm_visibility(&setup, &r.maps, p, BIAS, storage, Table::UniformDisk);
                    let want = closed_form(s, w);
                    let u = s / w;
                    let dl = (4.0 * e + u.abs() * (e + BIAS)) / (2.0 * (delta0 - BIAS - e));
                    let tol = 4.0 / std::f64::consts::PI * dl + 1e-12;
                    let err = (v - want).abs();
                    assert!(
                        err <= tol,
                        "{n} texels, {storage:?}, s {s}, y {y}: {v} vs the closed form {want} (error {err:e} > {tol:e})"
                    );
                    // the limb-darkened table: the same l, through its own slope bound
                    let limb = plm_visibility(&setup, &r.maps, p, BIAS, storage, Table::LimbDarkened);
                    let want = Table::LimbDarkened.illumination(0.5 + 0.5 * u.clamp(-1.0, 1.0));
                    assert!(
                        (limb - want).abs() <= LIMB_SLOPE * dl + 1e-12,
                        "{n} texels, {storage:?}, s {s}: limb-darkened {limb} vs {want}"
                    );
                    if u.abs() <= 1.0 {
                        sq += err * err;
                        count += 1;
                        worst = worst.max(err);
                    }
                }
            }
            let rms = (sq / count as f64).sqrt();
            eprintln!(
                "edge, {n} texels, {storage:?}: RMS {:.3} / 255, max {:.3} / 255 over the penumbra",
                rms * 255.0,
                worst * 255.0
            );
            // the figure: RMS against the closed form below 2/255 at 16 and 128
            assert!(rms < 2.0 / 255.0);
        }
    }
}

/// A light of angle 0 (and one of 0.001 degrees) gives the hard shadow map's 0 / 1 wherever the
/// bilinear footprint lies on one side of the edge (more than a texel away from it).
#[test]
fn zero_angle_is_the_hard_shadow() {
    let (tris, meshes) = edge_scene();
    for angle in [0.0, 1e-3] {
        for n in [16usize, 128] {
            let setup = PlmSetup::new(edge_light(n, angle));
            let r = PlmReference::new(&tris, &meshes, &setup).unwrap();
            let texel = setup.texel();
            let mut tested = 0;
            for k in 0..=400 {
                let x = -1.0 + 2.0 * k as f64 / 400.0;
                // away from the edge and from the occluder's and floor's other edges (x = -1, 1)
                if x.abs() <= texel * 1.0001 || x.abs() >= 1.0 - 2.0 * texel {
                    continue;
                }
                for y in [-0.5, 0.0137, 0.5] {
                    let p = [x, y, -Z_F];
                    let (uv, d) = receiver(&setup, p).unwrap();
                    let (i, j) = ((uv[0] * n as f64) as usize, (uv[1] * n as f64) as usize);
                    let hard = if d - BIAS > r.maps.depth[j * n + i] { 0.0 } else { 1.0 };
                    assert_eq!(hard, if x > 0.0 { 1.0 } else { 0.0 });
                    for storage in STORAGES {
                        for table in [Table::UniformDisk, Table::LimbDarkened] {
                            let v = plm_visibility(&setup, &r.maps, p, BIAS, storage, table);
                            assert_eq!(v, hard, "angle {angle}, {n} texels, {storage:?}, x {x}, y {y}");
                        }
                    }
                    tested += 1;
                }
            }
            assert!(tested > 300);
        }
    }
}

/// Receivers exactly at the occluder's depth on the edge line (`z - c -> 0`, `p_i -> 0`), and
/// around them, under a distant disk, a light of angle 0 and a local sphere light: every lookup
/// is finite and in `[0, 1]`.
#[test]
fn no_nan_as_the_receiver_meets_the_occluder_and_the_edge() {
    let edge = edge_scene();
    let sq = scene(&[quad(-6.0, 6.0, -6.0, 6.0, -10.0), quad(-1.0, 1.0, -1.0, 1.0, -5.0)]);
    let cases: Vec<(PlmSetup, &Scene, f64, f64)> = vec![
        (PlmSetup::new(edge_light(32, 10.0)), &edge, Z_E, 0.0),
        (PlmSetup::new(edge_light(32, 0.0)), &edge, Z_E, 0.0),
        (PlmSetup::smoothies(edge_light(32, 10.0)), &edge, Z_E, 0.0),
        (PlmSetup::new(sphere(0.5, 48, Resolve::KeepMin)), &sq, 5.0, 1.0),
        (PlmSetup::new(sphere(0.0, 48, Resolve::KeepMin)), &sq, 5.0, 1.0),
    ];
    let eps = [0.0, 1e-12, 1e-9, 1e-6, 1e-3];
    for (setup, (tris, meshes), z_occ, edge_x) in &cases {
        let r = PlmReference::new(tris, meshes, setup).unwrap();
        for m in [&r.maps.g, &r.maps.c, &r.maps.b, &r.maps.p_i, &r.maps.key, &r.maps.depth] {
            assert!(m.iter().all(|v| v.is_finite()));
        }
        let mut seen = 0;
        for dz in eps.iter().flat_map(|e| [*e, -*e]) {
            for dx in eps.iter().flat_map(|e| [*e, -*e]) {
                for y in [0.0, 0.3] {
                    // on the edge line at the occluder's depth (for the sphere light, the square's
                    // edge x = 1 seen from the origin: x / Z = 1 / 5)
                    let z = z_occ + dz;
                    let x = edge_x * z / z_occ + dx;
                    let p = [x, y, -z];
                    for bias in [0.0, BIAS] {
                        for storage in STORAGES {
                            for table in [Table::UniformDisk, Table::LimbDarkened] {
                                let (uv, d) = receiver(setup, p).unwrap();
                                let sh = plm_shade(setup, &r.maps, uv, d - bias, storage, table);
                                for v in [sh.l, sh.l_g, sh.visibility] {
                                    assert!(v.is_finite() && (0.0..=1.0).contains(&v), "{p:?} {storage:?}: {sh:?}");
                                }
                            }
                            let v = smoothie_visibility(setup, &r.maps, p, bias, storage);
                            assert!(v.is_finite() && (0.0..=1.0).contains(&v), "smoothie {p:?} {storage:?}: {v}");
                            seen += 1;
                        }
                    }
                }
            }
        }
        assert!(seen > 1000);
    }
}

/// Smoothies (Lawlor section 3.1, Chan & Durand 2003) have an outer penumbra only: 0 inside the
/// hard shadow, then `sat(1/2 p_i / delta) = sat(s / (2 w))` rising from 0 at the shadow line to
/// 1 at the full penumbra width `2 w` outside it (the half-width `w = h tan(angle / 2)`), 1/2 at
/// the true outer limit `s = w`.
///
/// Tolerance: as for penumbra limit maps (see `straight_edge_is_exact_up_to_the_storage_precision`)
/// with `|p_i / delta| <= 2` over the ramp and no table: `(4 e_p + 2 (e_c + beta)) /
/// (2 (delta_0 - beta - e_c))`.
#[test]
fn smoothies_have_the_outer_penumbra_only() {
    let (tris, meshes) = edge_scene();
    let w = 5f64.to_radians().tan() * (Z_F - Z_E);
    for n in [16usize, 128] {
        let setup = PlmSetup::smoothies(edge_light(n, 10.0));
        let r = PlmReference::new(&tris, &meshes, &setup).unwrap();
        let texel = setup.texel();
        let delta0 = (Z_F - Z_E) / (setup.light.far - setup.light.near);
        for storage in STORAGES {
            let e = half_step(storage);
            let tol = (4.0 * e + 2.0 * (e + BIAS)) / (2.0 * (delta0 - BIAS - e)) + 1e-12;
            for k in 0..=800 {
                let s = -1.0 + 2.0 * texel + (2.0 - 4.0 * texel) * k as f64 / 800.0;
                let p = [s, 0.0137, -Z_F];
                let v = smoothie_visibility(&setup, &r.maps, p, BIAS, storage);
                if s < 0.0 {
                    assert_eq!(v, 0.0, "{n} texels, {storage:?}, s {s}: inside the hard shadow");
                } else {
                    let want = (s / (2.0 * w)).min(1.0);
                    assert!(
                        (v - want).abs() <= tol,
                        "{n} texels, {storage:?}, s {s}: {v} vs the ramp {want} (tolerance {tol:e})"
                    );
                }
            }
            let v = smoothie_visibility(&setup, &r.maps, [w, 0.0137, -Z_F], BIAS, storage);
            assert!((v - 0.5).abs() <= tol, "at the outer limit: {v}");
        }
        // ribbons of the penumbra limit maps' reach would cut the ramp off where they end
        // (at 128 texels, 0.14 from the edge, before the ramp's 2 w = 0.175): there the lookup
        // leaves the ribbon (c -> 1) and reads 1 within a texel, far above the ramp
        if n == 128 {
            let plain = PlmSetup::new(edge_light(n, 10.0));
            let rp = PlmReference::new(&tris, &meshes, &plain).unwrap();
            let mut off = 0.0f64;
            for k in 0..=400 {
                let s = 0.2 * k as f64 / 400.0;
                let v = smoothie_visibility(&plain, &rp.maps, [s, 0.0137, -Z_F], BIAS, None);
                off = off.max(v - (s / (2.0 * w)).min(1.0));
            }
            eprintln!("smoothies on ribbons of the plain reach: up to {off:.3} above the ramp");
            assert!(off > 0.1, "{off}");
        }
    }
}

/// Figure 7's stacked occluders: a small square (view distance 3) above a large slab (a closed
/// box, top 6, bottom 6.5) above a floor (10), a distant disk with `tan(angle / 2) = 0.1`.
fn stacked() -> (Scene, PlmSetup) {
    let s = scene(&[
        quad(-6.0, 6.0, -6.0, 6.0, -10.0),
        cuboid([-3.0, -3.0, -6.5], [3.0, 3.0, -6.0]),
        quad(-0.5, 0.5, -0.5, 0.5, -3.0),
    ]);
    let light = PenumbraSetup {
        view: IDENTITY,
        projection: LightProjection::Orthographic { half_height: 4.0 },
        near: 2.0,
        far: 11.0,
        size: 64,
        light: AreaLight::DistantDisk {
            angle: 2.0 * 0.1f64.atan(),
        },
        resolve: Resolve::KeepMin,
    };
    (s, PlmSetup::new(light))
}

/// Figure 7 (B) and (C): the small occluder's ribbon wins over the slab's middle, and its
/// outer penumbra would light the floor under the slab ("casting light through the center of
/// the object"); `b`, the slab's bottom below `c + bias_b`, clamps it back to 0.
fn check_b_clamps_the_leak(setup: &PlmSetup, maps: &PlmMaps, what: &str) {
    let mut leak = 0.0f64;
    for k in 0..=40 {
        // under the slab's middle, in the small square's outer penumbra (x in [0.5, 1.3])
        let x = 0.5 + 0.8 * k as f64 / 40.0;
        let p = [x, 0.1, -10.0];
        for storage in STORAGES {
            let v = plm_visibility(setup, maps, p, BIAS, storage, Table::UniformDisk);
            assert_eq!(v, 0.0, "{what}: the floor under the slab at x {x}, {storage:?}: {v}");
        }
        let no_b = PlmMaps {
            b: vec![1.0; maps.b.len()],
            ..maps.clone()
        };
        leak = leak.max(plm_visibility(setup, &no_b, p, BIAS, None, Table::UniformDisk));
    }
    assert!(leak > 0.9, "{what}: without b the light leaks through the slab ({leak})");
}

#[test]
fn b_clamps_the_stacked_occluders_light_leak() {
    let ((tris, meshes), setup) = stacked();
    let r = PlmReference::new(&tris, &meshes, &setup).unwrap();
    check_b_clamps_the_leak(&setup, &r.maps, "f64");
}

// ---- the WGSL reference against the f64 one ----

/// f32's unit roundoff.
const U: f64 = 1.0 / (1u64 << 24) as f64;
/// Roundings counted along the longest chain, doubled (see `agree`).
const C: f64 = 16.0;
/// The largest share of texels allowed to differ in `b` at a triangle's or the threshold's
/// boundary.
const BOUNDARY_SHARE: f64 = 0.01;

/// The f32 error bounds of one ribbon's `c`, `p_i` and key at an image point.
#[derive(Clone, Copy, Debug)]
struct Tol {
    dc: f64,
    dp: f64,
    dkey: f64,
}

/// The f32 errors of one ribbon's `(c, p_i, key)` at image point `q` (see `agree`).
fn ribbon_tolerance(setup: &PlmSetup, rb: &Ribbon, q: [f64; 2], s: &RibbonSample) -> Tol {
    let (near, far) = (setup.light.near, setup.light.far);
    let dd = far - near;
    let norm = |v: [f64; 2]| v[0].hypot(v[1]);
    let lambda = norm(q) + norm(rb.a) + norm(rb.b) + rb.half_width;
    let ds = C * U * lambda;
    let dp = (ds + C * U * s.w.abs()) / setup.limit_scale() + C * U * s.p_i.abs();
    let df = C * U * lambda / rb.length + C * U;
    let z = setup.distance(s.c);
    let dz = if setup.distant() {
        C * U * (rb.z_a + rb.z_b) + (rb.z_b - rb.z_a).abs() * df
    } else {
        let diz = C * U * (1.0 / rb.z_a + 1.0 / rb.z_b) + (1.0 / rb.z_b - 1.0 / rb.z_a).abs() * df;
        z * z * diz + C * U * z
    };
    let dc = (dz + C * U * (z + far)) / dd;
    let dkey = if setup.distant() {
        dc + dp + C * U
    } else {
        let kk = 1.0 / near - 1.0 / far;
        let dcz = dd * dc + C * U * z;
        let h = (1.0 / near - 1.0 / z) / kk + s.p_i.abs();
        let dh = (dcz / (z * z) + C * U * (1.0 / near + 1.0 / z)) / kk + dp + C * U * h;
        let zk = 1.0 / (1.0 / near - h.min(1.0) * kk);
        let dzk = zk * zk * (kk * dh + C * U * (1.0 / near + h * kk)) + C * U * zk;
        (dzk + C * U * (zk + far)) / dd
    };
    Tol { dc, dp, dkey }
}

#[derive(Debug, Default)]
struct Stats {
    covered: usize,
    ambiguous_winner: usize,
    b_boundary: usize,
    max_c: f64,
    max_p: f64,
    max_g: f64,
    max_b: f64,
}

/// Compare the WGSL maps with the f64 ones texel by texel.
///
/// Tolerance. The WGSL rounds its inputs (view-space end points, triangles, the depth) to f32
/// and computes in f32, relative error `U = 2^-24` per operation; `C = 16` counts the roundings
/// along the longest chain (projection, the along and outward vectors, the dot products, the
/// interpolation, the division by `S`, the key), doubled. At image point `q` of the winning
/// ribbon, with `Lambda = |q| + |A| + |B| + h` (image-plane magnitudes):
/// - the along and across coordinates and `w` carry `ds = C U Lambda`;
/// - `p_i = w / S`: `dp = (ds + C U |w|) / S + C U |p_i|`;
/// - the interpolation parameter `t_c / L`: `df = C U Lambda / L + C U`; the depth
///   `Z = Z_A + (Z_B - Z_A) f` (distant) carries `C U (Z_A + Z_B) + |Z_B - Z_A| df`, and
///   `1 / Z` (local) the same in `1 / Z`, so `Z` carries `Z^2` times it plus `C U Z`;
///   `c = (Z - near) / (far - near)`: `dc = (dZ + C U (Z + far)) / (far - near)`;
/// - the key: `c + |p_i|` (distant): `dc + dp + C U`; a local light's hyperbolic key is
///   differentiated through `H` and `Z = 1 / (1 / near - H k)` (`ribbon_tolerance`);
/// - `g = min(depth, key)`: `dkey + U` (min is 1-Lipschitz; the depth is rounded once);
/// - `b`: the ray parameter of Moller-Trumbore, `t = dot(e2, q) / det`, carries
///   `C U kappa (Lambda_3 + Z)`, `kappa = |e1| |e2| / |det|` (the triangle's condition for the
///   ray), `Lambda_3` the ray's lateral offset from the triangle's first vertex; divided by
///   `far - near`.
///
/// A texel whose winning ribbon differs must be ambiguous in f64: a ribbon's rectangle boundary
/// within `ds` of the centre, or two covering keys within the sum of their `dkey`. A texel whose
/// `b` differs by more than its bound must have a 4-neighbour with a different f64 `b` (a
/// triangle's edge or the `c + bias_b` threshold crosses within a texel); they are counted and
/// bounded by 1%. The `w` switch at an end (`t = 0` or `L`, `s < 0`: from `s` to `|s|`) is
/// ambiguous too.
fn agree(name: &str, (tris, meshes): &Scene, setup: &PlmSetup) -> (PlmReference, PlmMaps, Stats) {
    let r = PlmReference::new(tris, meshes, setup).unwrap();
    let g = plm_maps_gpu(gpu(), setup, tris, meshes, &r).unwrap();
    let n = setup.light.size;
    let mut st = Stats::default();
    let back: Vec<[V3; 3]> = tris
        .iter()
        .map(|t| t.map(|p| setup.light.to_view(p)))
        .filter(|t| back_facing(setup, t))
        .collect();
    for j in 0..n {
        for i in 0..n {
            let k = j * n + i;
            let q = setup.texel_centre(i, j);
            let (gv, gc, gb, gp) = (g.g[k] as f64, g.c[k] as f64, g.b[k] as f64, g.p_i[k] as f64);
            for v in [gv, gc, gb, gp] {
                assert!(v.is_finite(), "{name} texel ({i}, {j}): {v}");
            }
            // every covering ribbon in f64, with its tolerances
            let cover: Vec<(usize, RibbonSample, Tol)> = r
                .ribbons
                .iter()
                .enumerate()
                .filter_map(|(x, rb)| rb.at(setup, q).map(|s| (x, s, ribbon_tolerance(setup, rb, q, &s))))
                .collect();
            let near_boundary = r.ribbons.iter().any(|rb| {
                let d = [q[0] - rb.a[0], q[1] - rb.a[1]];
                let t = d[0] * rb.along[0] + d[1] * rb.along[1];
                let s = d[0] * rb.outward[0] + d[1] * rb.outward[1];
                let ds = C * U * (q[0].hypot(q[1]) + rb.a[0].hypot(rb.a[1]) + rb.b[0].hypot(rb.b[1]) + rb.half_width);
                let h = rb.half_width;
                (s.abs() - h).abs() <= ds
                    || (t + h).abs() <= ds
                    || (t - rb.length - h).abs() <= ds
                    || (s < 0.0 && (t.abs() <= ds || (t - rb.length).abs() <= ds))
            });
            let close_keys = cover
                .iter()
                .enumerate()
                .any(|(x, a)| cover[x + 1..].iter().any(|b| (a.1.key - b.1.key).abs() <= a.2.dkey + b.2.dkey));
            if r.maps.winner[k] != g.winner[k] {
                assert!(
                    near_boundary || close_keys,
                    "{name} texel ({i}, {j}): winner {:?} on the GPU, {:?} in f64, not ambiguous",
                    g.winner[k],
                    r.maps.winner[k]
                );
                st.ambiguous_winner += 1;
                continue;
            }
            let depth32 = r.maps.depth[k] as f32 as f64;
            match r.maps.winner[k].and_then(|x| cover.iter().find(|c| c.0 == x)) {
                None => {
                    assert!(gc == 1.0 && gp == 0.0 && gv == depth32, "{name} texel ({i}, {j}): uncovered");
                }
                Some((_, s, Tol { dc, dp, dkey })) => {
                    st.covered += 1;
                    let (ec, ep, eg) = ((gc - s.c).abs(), (gp - s.p_i).abs(), (gv - r.maps.g[k]).abs());
                    let switch = near_boundary;
                    assert!(ec <= *dc, "{name} texel ({i}, {j}): c {gc} vs {} ({ec:e} > {dc:e})", s.c);
                    assert!(
                        switch || ep <= *dp,
                        "{name} texel ({i}, {j}): p_i {gp} vs {} ({ep:e} > {dp:e})",
                        s.p_i
                    );
                    assert!(
                        switch || eg <= dkey + U,
                        "{name} texel ({i}, {j}): g {gv} vs {} ({eg:e} > {:e})",
                        r.maps.g[k],
                        dkey + U
                    );
                    st.max_c = st.max_c.max(ec / dc);
                    st.max_p = st.max_p.max(ep / dp);
                    st.max_g = st.max_g.max(eg / (dkey + U));
                }
            }
            // b: the bound of the f64 hit triangle
            let (o, d) = setup.light.texel_ray(i, j);
            let want_b = r.maps.b[k];
            let db = if want_b < 1.0 {
                back.iter()
                    .filter_map(|t| {
                        let e1 = [t[1][0] - t[0][0], t[1][1] - t[0][1], t[1][2] - t[0][2]];
                        let e2 = [t[2][0] - t[0][0], t[2][1] - t[0][1], t[2][2] - t[0][2]];
                        let nrm = [
                            e1[1] * e2[2] - e1[2] * e2[1],
                            e1[2] * e2[0] - e1[0] * e2[2],
                            e1[0] * e2[1] - e1[1] * e2[0],
                        ];
                        let det = (nrm[0] * d[0] + nrm[1] * d[1] + nrm[2] * d[2]).abs();
                        let l = |v: V3| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                        let kappa = l(e1) * l(e2) * l(d) / det;
                        let zb = setup.distance(want_b);
                        let off = l([o[0] + zb * d[0] - t[0][0], o[1] + zb * d[1] - t[0][1], 0.0]);
                        kappa
                            .is_finite()
                            .then_some(C * U * kappa * (off + zb) / (setup.light.far - setup.light.near))
                    })
                    .fold(0.0, f64::max)
                    + U
            } else {
                0.0
            };
            let eb = (gb - want_b).abs();
            if eb > db {
                let neighbours = [(0, 1), (2, 1), (1, 0), (1, 2)]
                    .iter()
                    .filter_map(|&(a, b)| Some(((i + a).checked_sub(1)?, (j + b).checked_sub(1)?)))
                    .filter(|&(a, b)| a < n && b < n);
                assert!(
                    neighbours.into_iter().any(|(a, b)| r.maps.b[b * n + a] != want_b),
                    "{name} texel ({i}, {j}): b {gb} vs {want_b} ({eb:e} > {db:e}) away from any boundary"
                );
                st.b_boundary += 1;
            } else if db > 0.0 {
                st.max_b = st.max_b.max(eb / db);
            }
        }
    }
    assert!(st.covered > 0, "{name}: no ribbon covers any texel");
    assert!(
        st.b_boundary as f64 <= BOUNDARY_SHARE * (n * n) as f64,
        "{name}: {} texels differ in b",
        st.b_boundary
    );
    eprintln!("{name}: {st:?}");
    let depth = r.maps.depth.clone();
    (r, as_maps(&g, &depth), st)
}

#[test]
fn wgsl_agrees_on_the_edge() {
    let (tris, meshes) = edge_scene();
    for n in [16, 128] {
        let setup = PlmSetup::new(edge_light(n, 10.0));
        agree(&format!("edge {n}"), &(tris.clone(), meshes.clone()), &setup);
        let smooth = PlmSetup::smoothies(edge_light(n, 10.0));
        agree(&format!("edge smoothies {n}"), &(tris.clone(), meshes.clone()), &smooth);
    }
}

#[test]
fn wgsl_agrees_under_the_sphere_light() {
    let sq = scene(&[quad(-6.0, 6.0, -6.0, 6.0, -10.0), quad(-1.0, 1.0, -1.0, 1.0, -5.0)]);
    agree("square, sphere light", &sq, &PlmSetup::new(sphere(1.0, 128, Resolve::KeepMin)));
    // a rotated, tilted square: oblique ribbons, unequal depths along its edges
    let (s, c) = 0.4f64.sin_cos();
    let corner = |x: f64, y: f64| [c * x - s * y, s * x + c * y, -5.0 + 0.3 * x - 0.2 * y];
    let (a, b, cc, dd) = (corner(-1.2, -0.9), corner(1.1, -0.9), corner(1.1, 1.0), corner(-1.2, 1.0));
    let tilted = scene(&[quad(-6.0, 6.0, -6.0, 6.0, -10.0), vec![[a, b, cc], [a, cc, dd]]]);
    agree(
        "tilted square, sphere light",
        &tilted,
        &PlmSetup::new(sphere(0.7, 112, Resolve::KeepMin)),
    );
    // a closed box under the sphere light: back faces (its bottom and sides) in b
    let boxed = scene(&[quad(-6.0, 6.0, -6.0, 6.0, -10.0), cuboid([-1.0, -1.5, -6.0], [1.5, 1.0, -4.5])]);
    agree("box, sphere light", &boxed, &PlmSetup::new(sphere(0.6, 96, Resolve::KeepMin)));
}

#[test]
fn wgsl_agrees_on_the_stacked_occluders_and_b_clamps_the_leak() {
    let (sc, setup) = stacked();
    let (_, gpu_maps, st) = agree("stacked", &sc, &setup);
    assert!(st.covered > 100);
    check_b_clamps_the_leak(&setup, &gpu_maps, "WGSL");
}
