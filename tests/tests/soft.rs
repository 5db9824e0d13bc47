//! Soft-shadow techniques on the GPU (lavapipe on machines without one): convolution soft
//! shadow maps (techniques/cssm.ron, Annen 2008 chapter 8) and percentage-closer soft
//! shadows (techniques/pcss.ron, Fernando 2005). They render every bundled scene within
//! [0, 1]; at light size 0 they reduce to their point-light bases (CSM at the finest level,
//! the hard shadow map); where no occluder lies in front of the receiver (1 - s_f -> 0) CSSM's
//! guarded division gives the lit fallback; and both penumbrae widen with the light, PCSS's
//! by Fernando's predicted width. Variance and moment soft shadow maps (techniques/vssm.ron,
//! techniques/mssm.ron) find an occluder's depth in their blocker searches and give
//! Fernando's filter width, read from their debug outputs (a wrong sign in either blocker
//! estimate fails it).
//! Without an adapter these tests fail, they never skip.

mod support;

use sshc_lab::run::Loaded;
use sshc_lab::scene::{Light, Scene};
use sshc_runtime::gpu::{CameraOutput, SceneInputs};
use support::{QueryPlane, compile_source, depth_field, gpu, root, technique_source};

const SCENES: [&str; 5] = ["bunny", "contact", "fence", "edge", "triangle"];

fn compile(name: &str, set: &[(&str, &str)]) -> sshc::Compiled {
    let set: Vec<(&str, String)> = set.iter().map(|(k, v)| (*k, v.to_string())).collect();
    compile_source(name, &technique_source(name), &set, &[])
}

fn scene(name: &str, camera: u32, shadow: u32) -> Scene {
    let mut s = Scene::load(root().join("scenes").join(format!("{name}.ron"))).unwrap_or_else(|e| panic!("{name}: {e}"));
    s.set_camera_size(camera, camera);
    s.shadow_map = shadow;
    s
}

/// Visibility and world positions (NaN where no surface) of one frame of `c` over `inputs`,
/// with runtime params set and, optionally, a synthetic depth field instead of the Depth pass.
fn run(c: &sshc::Compiled, inputs: &SceneInputs, depth: Option<&[f32]>, params: &[(&str, f64)]) -> (Vec<f32>, Vec<[f32; 4]>) {
    let mut ex = Loaded::new(gpu(), c.graph.clone(), c.shaders.clone()).unwrap_or_else(|e| panic!("{e}"));
    for (k, v) in params {
        ex.set_param(k, *v).unwrap_or_else(|e| panic!("{e}"));
    }
    let mut ex = ex.bind_scene(inputs).unwrap_or_else(|e| panic!("{e}"));
    ex.set_depth_override(depth.map(<[f32]>::to_vec));
    ex.run_frame().unwrap_or_else(|e| panic!("{e}"));
    let vis = ex
        .inspect()
        .read_camera(CameraOutput::Visibility)
        .unwrap_or_else(|e| panic!("{e}"))
        .channel(0);
    let pos = ex
        .inspect()
        .read_camera(CameraOutput::Position)
        .unwrap_or_else(|e| panic!("{e}"))
        .rgba;
    (vis, pos)
}

/// The query plane (support/mod.rs: orthographic light, receiver depth running from 1 at
/// u = 0 to 0 at u = 1) under a light `width` world units wide on both map axes.
fn plane_inputs(plane: &QueryPlane, width: f32) -> SceneInputs {
    SceneInputs {
        light_size: 0.5 * width,
        light_half_extents: [0.5 * width, 0.5 * width],
        ..plane.inputs()
    }
}

/// As [`plane_inputs`] with a flat receiver instead of the tilted one: a horizontal square at
/// height -1, view distance 11 from the light's eye (normalised depth 0.75 between the query
/// plane's near 8 and far 12), seen by the same orthographic camera, so camera pixel (i, j)
/// still shades light uv ((i + 0.5) / camera, (j + 0.5) / camera).
fn flat_inputs(plane: &QueryPlane, width: f32) -> SceneInputs {
    let (a, b, y) = (-1.05f32, 1.05f32, -1.0f32);
    let quad = [[a, a], [b, a], [b, b], [a, a], [b, b], [a, b]];
    SceneInputs {
        vertices: quad.iter().flat_map(|[x, z]| [*x, y, *z, 0.0, 1.0, 0.0]).collect(),
        ..plane_inputs(plane, width)
    }
}

/// Largest |a_i| sum of the CSM series with c_k = pi (2k - 1) and a_k = exp(-alpha (k/M)^2):
/// each k contributes (2 a_k / c_k) (|cos| + |sin|) <= 2 sqrt(2) a_k / c_k.
fn csm_coefficient_sum(m: i32, alpha: f64) -> f64 {
    (1..=m)
        .map(|k| {
            let ck = std::f64::consts::PI * (2 * k - 1) as f64;
            2.0 * std::f64::consts::SQRT_2 * (-alpha * (k as f64 / m as f64).powi(2)).exp() / ck
        })
        .sum()
}

#[test]
fn soft_techniques_render_every_bundled_scene_finite_and_in_range() {
    let variants = [("cssm", "0"), ("cssm", "1"), ("pcss", "")];
    for (t, filter) in variants {
        let set: &[(&str, &str)] = if filter.is_empty() { &[] } else { &[("filter", filter)] };
        let c = compile(t, set);
        for sc in SCENES {
            let s = scene(sc, 32, 128);
            let (vis, pos) = run(&c, &sshc_lab::bind::scene_inputs(&s).unwrap(), None, &[]);
            let mut shadowed = 0;
            for (i, v) in vis.iter().enumerate() {
                assert!(
                    v.is_finite() && (0.0..=1.0).contains(v),
                    "{t} filter {filter:?} on {sc}: pixel {i} has visibility {v}"
                );
                if pos[i][0].is_nan() {
                    assert_eq!(*v, 1.0, "{t} on {sc}: empty pixel {i} reads {v}");
                } else if *v < 0.5 {
                    shadowed += 1;
                }
            }
            // every bundled scene has a shadow in view: the techniques must not read all lit
            assert!(shadowed > 0, "{t} filter {filter:?} on {sc}: no pixel in shadow");
        }
    }
}

#[test]
fn cssm_at_light_size_zero_is_csm_at_the_finest_level() {
    // With the light's width 0 both CSSM kernels are 0 (w_0 = light_width (d - near) / d and
    // f_w = light_width ...): the mipmap path samples level 0 (sample_width at w = 0), the
    // table path a one-texel box (bilinear). Sharpening (A = 0) and ringing suppression
    // (ring = 0) are switched off; then CSSM is saturate(s_f), as CSM's `saturate(s)` with
    // the same M, alpha, fix, blur and bias (the defaults of both files agree).
    //
    // Tolerances. Both read the same Unorm8 basis images (same Map and blur passes). Mipmap
    // path: the same bilinear lookup at level 0 and the same coefficients; what differs is
    // CSSM's pow(s, 1) = exp2(log2 s), within 3 + 2|log2 s| ulp of exp2 and 2^-21 of log2
    // (Vulkan's precision rules): below 1e-5 for any s in [0, 1] (and s^1 < 2^-8 when s is).
    // Table path: exact box sums of the unorm codes (a one-texel box is exact bilinear
    // interpolation) against the sampler's bilinear weights, which Vulkan computes to the
    // device's subTexelPrecisionBits (8 on lavapipe): each axis's weight may be off by 2^-8,
    // times a code difference of at most 1 (stored units), so 2/256 stored units over two
    // axes, 4/256 decoded ([-1, 1] channels are stored as (v + 1) / 2), times the sum of
    // |a_i| over the series: 1/64 of the coefficient sum (0.019 at M = 4, alpha = 1), plus
    // f32. (Measured: at most 0.0054.)
    let csm_src = technique_source("csm").replace("let s = expand(f);", "let s = expand_lod(f, 0.0);");
    let csm = compile_source("csm", &csm_src, &[], &[]);
    let sum = csm_coefficient_sum(4, 1.0);
    let off = [("A", 0.0), ("ring", 0.0)];
    let n = 32;
    let plane = QueryPlane::new(n, 2 * n);
    for (filter, tol) in [("0", 1e-5), ("1", sum * 4.0 / 256.0 + 1e-5)] {
        let cssm = compile("cssm", &[("filter", filter)]);
        // synthetic depth fields under the query plane's receiver (every depth difference)
        for field in ["ramp", "checker", "noise", "step"] {
            let depth = depth_field(field, n);
            for width in [0.0, 1e-6] {
                let inputs = plane_inputs(&plane, width);
                let (a, pos) = run(&cssm, &inputs, Some(&depth), &off);
                let (b, _) = run(&csm, &inputs, Some(&depth), &[]);
                let worst = a
                    .iter()
                    .zip(&b)
                    .zip(&pos)
                    .filter(|(_, p)| !p[0].is_nan())
                    .map(|((x, y), _)| (x - y).abs() as f64)
                    .fold(0.0, f64::max);
                assert!(
                    worst <= tol,
                    "filter {filter}, field {field}, light width {width}: CSSM and CSM differ by {worst} > {tol}"
                );
            }
        }
        // a bundled scene (perspective light) with its sphere light shrunk to 1e-4
        let mut s = scene("contact", 48, 256);
        for l in &mut s.lights {
            if let Light::Sphere { radius, .. } = l {
                *radius = 1e-4;
            }
        }
        let inputs = sshc_lab::bind::scene_inputs(&s).unwrap();
        let (a, _) = run(&cssm, &inputs, None, &off);
        let (b, _) = run(&csm, &inputs, None, &[]);
        let worst = a.iter().zip(&b).map(|(x, y)| (x - y).abs() as f64).fold(0.0, f64::max);
        assert!(
            worst <= tol,
            "filter {filter}, contact with a point-like light: CSSM and CSM differ by {worst} > {tol}"
        );
        assert!(
            b.iter().any(|v| *v < 0.1),
            "the contact scene has an umbra under a point-like light"
        );
    }
}

#[test]
fn cssm_with_no_occluder_in_front_of_the_receiver_is_lit() {
    // Depth field "one": every occluder lies at the far plane, behind every receiver, so the
    // blocker fraction 1 - s_f at the initial kernel approaches 0 (it is the series' lit
    // ringing, 1 - f(t) for t = z - d + 1/(2M) in [1/(2M), 1 - 1/(2M)], at most 0.039 for
    // M = 4, alpha = 1, plus unorm8 quantisation of 1/255 times the coefficient sum, 0.005)
    // and eq. 8.6 divides by it. With the default min_blocker = 0.05 the guarded division
    // takes the no-blocker fallback, the unsharpened series at the initial kernel, >= 0.956,
    // which the ringing suppression (ring = 0.05: (s - 0.05) / 0.9 >= 1.006) clamps to 1.
    // With min_blocker = 0 the quotient is computed wherever 1 - s_f != 0; z_avg is clamped
    // to [0, d], the final lookup over a field of constant depth reads the same lit series
    // at every width, so the result is 1 again. The series is periodic in z - d with period
    // 2, so for t beyond 1 - 1/(2M) it reads the next edge, as plain CSM does: t = 1 - d_r +
    // 1/(2M) with d_r = d - slope_bias depth_slope, and the query plane's receiver depth
    // changes by 1/n per texel (slope_bias = 1), so only receivers with d >= 1/M + 1/n (plus
    // 0.01 for the blur and the kernel) are checked for 1; elsewhere finiteness and range.
    let n = 32;
    let plane = QueryPlane::new(n, n);
    let depth = depth_field("one", n);
    for filter in ["0", "1"] {
        let c = compile("cssm", &[("filter", filter)]);
        for min_blocker in [0.05, 0.0] {
            for width in [0.5f32, 2.0] {
                let (vis, pos) = run(&c, &plane_inputs(&plane, width), Some(&depth), &[("min_blocker", min_blocker)]);
                let mut checked = 0;
                for (v, p) in vis.iter().zip(&pos) {
                    assert!(v.is_finite() && (0.0..=1.0).contains(v), "filter {filter}: visibility {v}");
                    if p[0].is_nan() {
                        continue;
                    }
                    let (_, d) = plane.project([p[0], p[1], p[2]]);
                    if d >= 0.25 + 1.0 / n as f64 + 0.01 {
                        assert_eq!(
                            *v, 1.0,
                            "filter {filter}, min_blocker {min_blocker}, light width {width}: receiver at d = {d} in front of every occluder reads {v}"
                        );
                        checked += 1;
                    }
                }
                assert!(checked > (n * n / 2) as usize, "only {checked} pixels checked");
            }
        }
    }
}

/// Mean number of partly lit pixels (0 < v < 1) per camera row.
fn penumbra_pixels_per_row(vis: &[f32], width: usize) -> f64 {
    let partial = vis.iter().filter(|v| **v > 0.0 && **v < 1.0).count();
    partial as f64 / (vis.len() / width) as f64
}

#[test]
fn pcss_penumbra_widens_as_the_light_grows() {
    // Depth field "step": an occluder at z = 0.3 over u < 1/2 (view distance 8 + 0.3 * 4 =
    // 9.2 on the query plane), nothing over u >= 1/2, above a flat receiver at distance 11.
    // Fernando's penumbra: w = (11 - 9.2) light_width / 9.2, projected to the near plane
    // (* 8 / 11) and, for this orthographic light spanning 2 world units, w / 2 in uv:
    // 0.0712 light_width, 4.55 texels of a 64-texel map per world unit of light width, 9.1
    // camera pixels at 2 per texel. The search region, light_width (11 - 8) / 11 at the near
    // plane (0.136 light_width in uv), reaches the edge from 4.4 texels per unit away, beyond
    // the penumbra's half-width (2.3), so the blocker is found wherever the penumbra lies.
    // The partly lit run per row is the PCF kernel, which covers the edge over its own width,
    // plus at most one texel (2 pixels) of nearest-texel rounding; 10 % for the M x M
    // sampling of the width (a lattice of M^2 = 64 distinct offsets per axis).
    let n = 64;
    let plane = QueryPlane::new(n, 2 * n);
    let depth = depth_field("step", n);
    let c = compile("pcss", &[]);
    let mut widths = Vec::new();
    for light in [0.0f32, 0.5, 1.0, 2.0, 4.0] {
        let (vis, _) = run(&c, &flat_inputs(&plane, light), Some(&depth), &[]);
        assert!(vis.iter().all(|v| v.is_finite() && (0.0..=1.0).contains(v)));
        let w = penumbra_pixels_per_row(&vis, (2 * n) as usize);
        let expected = 9.1 * light as f64;
        assert!(
            (w - expected).abs() <= 2.0 + 0.1 * expected,
            "light width {light}: {w:.2} partly lit pixels per row, expected about {expected:.2}"
        );
        widths.push((light, w));
    }
    // a point light gives the hard shadow: no partly lit pixel
    assert_eq!(widths[0].1, 0.0, "{widths:?}");
    for pair in widths.windows(2) {
        assert!(pair[1].1 > pair[0].1, "the penumbra does not widen: {widths:?}");
    }
}

#[test]
fn pcss_at_light_size_zero_is_the_hard_shadow_map() {
    // With light_width = 0 every search and filter sample is the receiver's own texel, with
    // the bias of hard.ron (bias + slope_bias * depth_slope, the same defaults): PCSS reads
    // the hard shadow test exactly (both are 0 or 1).
    let n = 32;
    let plane = QueryPlane::new(n, 2 * n);
    let pcss = compile("pcss", &[]);
    let hard = compile("hard", &[]);
    for field in ["ramp", "step", "checker", "noise"] {
        let depth = depth_field(field, n);
        let inputs = plane_inputs(&plane, 0.0);
        let (a, _) = run(&pcss, &inputs, Some(&depth), &[]);
        let (b, _) = run(&hard, &inputs, Some(&depth), &[]);
        let differ = a.iter().zip(&b).filter(|(x, y)| x != y).count();
        assert_eq!(differ, 0, "field {field}: {differ} pixels differ from the hard shadow map");
    }
}

#[test]
fn cssm_penumbra_widens_as_the_light_grows() {
    // The edge and flat receiver of the PCSS test. CSSM's final kernel f_w (8.3.1) is the
    // same similar-triangles width as PCSS's penumbra, 9.1 camera pixels per unit of light
    // width here, when z_avg is the occluder's depth (eq. 8.6 is exact for one occluder depth
    // up to the series' ringing). A box of width f_w over the edge gives a linear ramp f_w
    // wide, and the ringing suppression (s - ring) / (1 - 2 ring), clamped, leaves 0 < v < 1
    // over (1 - 2 ring) f_w of it: 0.9 * 9.1 = 8.2 pixels per unit. Added to it is the
    // prefilter's own spread at light size 0 (the 3x3 Gaussian blur, bilinear filtering, the
    // series' slope in depth), which does not grow with the light. Checked: the partly lit
    // run widens with every step of the light, and grows from light width 1 to 4 by 3 * 8.2
    // = 24.6 pixels within -40 % (mipmaps: the kernel is rounded to trilinear levels of
    // widths 2^L) and +20 %.
    let n = 64;
    let plane = QueryPlane::new(n, 2 * n);
    let depth = depth_field("step", n);
    for filter in ["0", "1"] {
        let c = compile("cssm", &[("filter", filter)]);
        let mut widths = Vec::new();
        for light in [0.0f32, 0.5, 1.0, 2.0, 4.0] {
            let (vis, _) = run(&c, &flat_inputs(&plane, light), Some(&depth), &[]);
            assert!(vis.iter().all(|v| v.is_finite() && (0.0..=1.0).contains(v)));
            widths.push((light, penumbra_pixels_per_row(&vis, (2 * n) as usize)));
        }
        for pair in widths.windows(2) {
            assert!(pair[1].1 > pair[0].1, "filter {filter}: the penumbra does not widen: {widths:?}");
        }
        let growth = widths[4].1 - widths[2].1;
        let expected = 3.0 * 0.9 * 9.1;
        assert!(
            (0.6 * expected..=1.2 * expected).contains(&growth),
            "filter {filter}: grew by {growth} pixels from light width 1 to 4, expected about {expected}: {widths:?}"
        );
    }
}

#[test]
fn vssm_and_mssm_find_the_blockers_depth_and_pcss_s_penumbra_width() {
    // An occluder at z = 0.3 over u < 1/2 (view distance 9.2) and, over u >= 1/2, the flat
    // receiver's own depth 0.75 (distance 11): the receiver drawn into the map, the
    // non-blockers at the receiver's depth, as VSSM's blocker estimate (Yang et al. 2010,
    // section 3) takes them. Both searches must then find the occluder's depth: VSSM's
    // one-sided bound is exact for two depths one of which is the receiver's, P = 1 - f for
    // a blocker fraction f; MSSM's bounding distribution has its support points at the two
    // depths, up to the moment bias alpha and the weight lit_weight on the receiver, which
    // moves the mean by at most lit_weight (s_f - s_b) / f = 0.009 (signed depth) at f = 0.1.
    // The filter width is then Fernando's, as in the PCSS test: (11 - 9.2) / 9.2 L at the
    // receiver, * 8 / 11 at the near plane, / 2 in uv, * 64 texels: 4.553 L texels, which a
    // blocker depth off by 0.005 moves by 1.3 %. Checked at the camera pixels whose search
    // region (8.73 L texels wide) holds a blocker fraction of at least 0.1: z_occ within 0.01
    // of 0.3 and the filter within 3 % of 4.553 L texels; where the search region holds no
    // blocker, no penumbra (a one-texel filter).
    let n = 64usize;
    let plane = QueryPlane::new(n as u32, 2 * n as u32);
    let depth: Vec<f32> = (0..n * n).map(|k| if k % n < n / 2 { 0.3 } else { 0.75 }).collect();
    for name in ["vssm", "mssm"] {
        let opts = sshc::CompileOptions {
            debug: true,
            ..Default::default()
        };
        let src = technique_source(name);
        let c = sshc::compile_str(&src, &opts).unwrap_or_else(|d| panic!("{}", d.render(name, &src)));
        for light in [1.0f32, 2.0] {
            let ex = Loaded::new(gpu(), c.graph.clone(), c.shaders.clone()).unwrap_or_else(|e| panic!("{e}"));
            let mut ex = ex.bind_scene(&flat_inputs(&plane, light)).unwrap_or_else(|e| panic!("{e}"));
            ex.set_depth_override(Some(depth.clone()));
            ex.run_frame().unwrap_or_else(|e| panic!("{e}"));
            let z_occ = ex.inspect().read_debug(0, "z_occ").unwrap_or_else(|e| panic!("{e}"));
            let filter = ex.inspect().read_debug(0, "filter_texels").unwrap_or_else(|e| panic!("{e}"));
            let (search, width) = (8.727 * light as f64, 4.553 * light as f64);
            let (mut checked, mut unshadowed) = (0, 0);
            for x in 0..2 * n as u32 {
                // the blocker fraction of the search box about texel coordinate u n
                let u = (x as f64 + 0.5) / 2.0;
                let f = ((n as f64 / 2.0 - (u - search / 2.0)) / search).clamp(0.0, 1.0);
                let (z, w) = (z_occ.at(x, n as u32)[0] as f64, filter.at(x, n as u32)[0] as f64);
                if f >= 0.1 {
                    assert!(
                        (z - 0.3).abs() <= 0.01,
                        "{name}, light {light}, pixel {x} (blocker fraction {f:.2}): z_occ {z}"
                    );
                    assert!(
                        (w - width).abs() <= 0.03 * width,
                        "{name}, light {light}, pixel {x}: the filter is {w} texels wide, Fernando's width {width:.3}"
                    );
                    checked += 1;
                } else if f == 0.0 && u > n as f64 / 2.0 + search / 2.0 + 1.0 {
                    assert!(
                        (w - 1.0).abs() < 1e-3,
                        "{name}, light {light}, pixel {x}: no blocker, but a {w}-texel filter"
                    );
                    unshadowed += 1;
                }
            }
            assert!(
                checked > 60 && unshadowed > 10,
                "{name}, light {light}: {checked} and {unshadowed} pixels checked"
            );
        }
    }
}
