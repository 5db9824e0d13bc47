//! Lookups and frame-dependent functions of the language on the GPU: summed-area tables
//! (u32 fixed point over unorm codes, two compute steps) read by `sample_box`, `nearest_at`,
//! `uv_width` and `div_or`, checked against values computed on the CPU from what the GPU stored.

mod support;

use support::{QueryPlane, compile_source, depth_field, gpu, run_plane};

/// A probe technique: `m` = z stored at `precision`, summed into a table, and the Shade
/// pass reading the mean of `m` over a box `wx` x `wy` texels wide (or, with
/// `lookup = "bilinear"`, the base level filtered bilinearly).
fn probe(precision: &str, lookup: &str) -> sshc::Compiled {
    let (reads, visibility) = match lookup {
        "box" => ("table", "sample_box(m, wx * texel_size, wy * texel_size)"),
        _ => ("mapped", "sample_lod(m, 0.0) + 0.0 * (wx + wy)"),
    };
    let src = format!(
        r#"Technique(
    name: "box_probe",
    params: {{
        "wx": Param(ty: F32, default: 1.0, range: (0.0, 64.0), doc: "box width in texels"),
        "wy": Param(ty: F32, default: 1.0, range: (0.0, 64.0), doc: "box height in texels"),
    }},
    channels: {{
        "z": Channel(precision: F32),
        "m": Channel(precision: {precision}, value: "z"),
    }},
    passes: [
        Depth(name: "depth", writes: "shadow", channel: "z"),
        Map(name: "map", reads: ["shadow"], writes: "mapped", channels: ["m"]),
        SummedArea(name: "sat", reads: "mapped", writes: "table"),
        Shade(name: "shade", reads: ["{reads}"], visibility: "{visibility}"),
    ],
)"#
    );
    compile_source("box_probe", &src, &[], &[])
}

const N: u32 = 32;

fn plane() -> QueryPlane {
    QueryPlane::new(N, 2 * N)
}

/// The unorm codes the Map pass stored, read back, as integers.
fn codes(c: &sshc::Compiled, depth: &[f32], scale: f64) -> (Vec<u64>, Vec<[f32; 4]>) {
    let ex = sshc_lab::run::Loaded::new(gpu(), c.graph.clone(), c.shaders.clone()).unwrap();
    let mut ex = ex.bind_scene(&plane().inputs()).unwrap();
    ex.set_depth_override(Some(depth.to_vec()));
    ex.run_frame().unwrap();
    let stored = ex.inspect().read_texture("mapped", 0, 0).unwrap();
    let table = ex.inspect().read_texture("table", 0, 0).unwrap();
    let codes = stored.rgba.iter().map(|t| (t[0] as f64 * scale).round() as u64).collect();
    (codes, table.rgba)
}

#[test]
fn table_holds_the_prefix_sums_of_the_stored_codes() {
    // Unorm8 only: lavapipe cannot render to 16-bit unorm targets (wgpu reports R16Unorm
    // as not renderable there), so a Map pass cannot write a Unorm16 channel on it.
    for (precision, scale) in [("Unorm8", 255.0)] {
        let c = probe(precision, "box");
        let depth = depth_field("noise", N);
        let (codes, table) = codes(&c, &depth, scale);
        let n = N as usize;
        let mut checked = 0;
        for y in 0..n {
            for x in 0..n {
                let want: u64 = (0..=y)
                    .flat_map(|j| (0..=x).map(move |i| (i, j)))
                    .map(|(i, j)| codes[j * n + i])
                    .sum();
                // the table is u32 and read back as f32: sums below 2^24 come back exactly
                if want < 1 << 24 {
                    assert_eq!(table[y * n + x][0] as u64, want, "{precision}: table at ({x}, {y})");
                    checked += 1;
                }
            }
        }
        assert!(checked > n * n / 4, "{precision}: only {checked} sums small enough to compare");
    }
}

/// CPU mean of the stored values over the box of `w` x `h` texels centred at `uv`, clipped
/// to the map, at least one texel each way: the lookup's definition (docs/language.md).
fn box_mean(codes: &[u64], scale: f64, uv: [f64; 2], w: f64, h: f64) -> f64 {
    let n = N as f64;
    let (c0, c1) = ((uv[0] * n).clamp(0.0, n), (uv[1] * n).clamp(0.0, n));
    let (hx, hy) = (w.max(1.0) / 2.0, h.max(1.0) / 2.0);
    let (x0, x1) = ((c0 - hx).clamp(0.0, n), (c0 + hx).clamp(0.0, n));
    let (y0, y1) = ((c1 - hy).clamp(0.0, n), (c1 + hy).clamp(0.0, n));
    let overlap = |a: f64, b: f64, i: usize| (b.min(i as f64 + 1.0) - a.max(i as f64)).max(0.0);
    let mut sum = 0.0;
    for j in 0..N as usize {
        for i in 0..N as usize {
            sum += overlap(x0, x1, i) * overlap(y0, y1, j) * codes[j * N as usize + i] as f64;
        }
    }
    sum / ((x1 - x0) * (y1 - y0) * scale)
}

#[test]
fn box_lookups_match_the_mean_over_the_box() {
    let p = plane();
    for (precision, scale) in [("Unorm8", 255.0)] {
        let c = probe(precision, "box");
        for field in ["noise", "checker"] {
            let depth = depth_field(field, N);
            let (codes, _) = codes(&c, &depth, scale);
            for (w, h) in [(1.0, 1.0), (5.5, 3.25), (0.2, 12.0), (40.0, 40.0)] {
                let run = run_plane(&c, &p, &depth, &[("wx", w), ("wy", h)], 1);
                let mut worst = 0.0f64;
                for (v, pos) in run.visibility.iter().zip(&run.positions) {
                    let (uv, _) = p.project(*pos);
                    let want = box_mean(&codes, scale, uv, w, h);
                    worst = worst.max((*v as f64 - want).abs());
                }
                // The box sums are exact integers; what remains is f32 rounding: the nine
                // weighted rectangles (2^-24 relative each, of sums at most the box's total)
                // and the uv the GPU computed in f32 from the world position (2^-24
                // relative, times N = 32 texels, moving a box edge by ~2e-6 texel, which
                // changes the mean by at most that over the box's width). 1e-5 bounds both
                // with margin; one texel of misplacement would show as ~0.3 on noise.
                assert!(worst <= 1e-5, "{precision} {field} box {w} x {h}: worst error {worst}");
            }
        }
    }
}

#[test]
fn a_box_one_texel_wide_is_bilinear_filtering() {
    // Identical stored codes, two lookups: the one-texel box integrates the piecewise
    // constant texels over one texel, which is exactly bilinear interpolation. Hardware
    // bilinear weights are quantised to the device's sub-texel precision (Vulkan requires
    // at least 4 bits; lavapipe and current desktop GPUs have 8), so the two differ by at
    // most 2^-8 of the largest difference between neighbouring texels (at most 1 for unorm
    // values in [0, 1]); and a device may filter an 8-bit format in 8-bit fixed point,
    // rounding the result to the nearest code (lavapipe does): 1/255 more.
    let p = plane();
    let depth = depth_field("noise", N);
    let sat = run_plane(&probe("Unorm8", "box"), &p, &depth, &[], 1);
    let bil = run_plane(&probe("Unorm8", "bilinear"), &p, &depth, &[], 1);
    let worst = sat
        .visibility
        .iter()
        .zip(&bil.visibility)
        .map(|(a, b)| (a - b).abs() as f64)
        .fold(0.0, f64::max);
    assert!(worst <= 1.0 / 256.0 + 1.0 / 255.0, "one-texel box vs bilinear: worst {worst}");
}

/// A technique whose visibility is `expr` over a depth map read as channel `z` (F32).
fn probe_expr(expr: &str) -> sshc::Compiled {
    let src = format!(
        r#"Technique(
    name: "expr_probe",
    channels: {{ "z": Channel(precision: F32) }},
    passes: [
        Depth(name: "depth", writes: "shadow", channel: "z"),
        Shade(name: "shade", reads: ["shadow"], visibility: "{expr}"),
    ],
)"#
    );
    compile_source("expr_probe", &src, &[], &[])
}

#[test]
fn nearest_at_reads_the_texel_under_the_offset_point() {
    let p = plane();
    let depth = depth_field("noise", N);
    let run = run_plane(
        &probe_expr("nearest_at(z, 3.0 * texel_size, -2.0 * texel_size)"),
        &p,
        &depth,
        &[],
        1,
    );
    for (v, pos) in run.visibility.iter().zip(&run.positions) {
        let (uv, _) = p.project(*pos);
        let n = N as f64;
        // the query plane's pixel centres sit a quarter texel from texel edges, far from
        // any rounding of uv, so the texel index is exact
        let i = ((uv[0] + 3.0 / n) * n).floor().clamp(0.0, n - 1.0) as usize;
        let j = ((uv[1] - 2.0 / n) * n).floor().clamp(0.0, n - 1.0) as usize;
        assert_eq!(*v, depth[j * N as usize + i], "at uv {uv:?}");
    }
}

#[test]
fn uv_width_maps_world_lengths_to_the_shadow_map() {
    // The query plane's orthographic light spans 2 world units: a length of 0.5 covers a
    // quarter of the map at every distance. f32: one division and one multiply-add, a few
    // ulps of 0.25.
    let p = plane();
    let run = run_plane(&probe_expr("uv_width(0.5, d_world)"), &p, &depth_field("one", N), &[], 1);
    for v in &run.visibility {
        assert!((v - 0.25).abs() <= 4.0 * f32::EPSILON, "uv_width(0.5) = {v}");
    }
}

#[test]
fn div_or_divides_where_the_denominator_is_large_enough() {
    let p = plane();
    let run = run_plane(
        &probe_expr("saturate(div_or(0.1, d - 0.5, 0.2, 0.25))"),
        &p,
        &depth_field("one", N),
        &[],
        1,
    );
    let mut counts = [0; 3];
    for (v, pos) in run.visibility.iter().zip(&run.positions) {
        let (_, d) = p.project(*pos);
        let den = d - 0.5;
        // pixels within f32 rounding of the threshold could go either way
        if (den.abs() - 0.2).abs() < 1e-5 {
            continue;
        }
        let want = if den.abs() >= 0.2 { (0.1 / den).clamp(0.0, 1.0) } else { 0.25 };
        counts[if den >= 0.2 {
            0
        } else if den <= -0.2 {
            1
        } else {
            2
        }] += 1;
        // f32: the GPU's d differs from the f64 one by a few ulps of the plane's depth
        // (1e-6), and 0.1 / den amplifies that by at most 0.1 / 0.2^2 = 2.5
        assert!((*v as f64 - want).abs() <= 1e-5, "d = {d}: {v} vs {want}");
    }
    assert!(counts.iter().all(|&c| c > 0), "every branch is exercised: {counts:?}");
}

/// `div_or` on vectors: component by component, a scalar `eps` splatted and a vector
/// fallback, the GPU against the closed form. Component x divides 0.1 by `d - 0.5`,
/// component y divides -0.1 by `0.5 - d`; their sum is `0.2 / (d - 0.5)` where both
/// denominators are at least 0.2 from 0, and the fallbacks' 0.25 + 0.5 elsewhere.
#[test]
fn div_or_divides_vectors_component_by_component() {
    let p = plane();
    let run = run_plane(
        &probe_expr("saturate(dot(div_or(vec2(0.1, -0.1), vec2(d - 0.5, 0.5 - d), 0.2, vec2(0.25, 0.5)), vec2(1.0, 1.0)))"),
        &p,
        &depth_field("one", N),
        &[],
        1,
    );
    let mut counts = [0; 2];
    for (v, pos) in run.visibility.iter().zip(&run.positions) {
        let (_, d) = p.project(*pos);
        let den = d - 0.5;
        if (den.abs() - 0.2).abs() < 1e-5 {
            continue;
        }
        let divides = den.abs() >= 0.2;
        let want = if divides { (0.2 / den).clamp(0.0, 1.0) } else { 0.75 };
        counts[usize::from(divides)] += 1;
        // as the scalar test: a few ulps of d, amplified by at most 0.2 / 0.2^2 = 5
        assert!((*v as f64 - want).abs() <= 2e-5, "d = {d}: {v} vs {want}");
    }
    assert!(counts.iter().all(|&c| c > 0), "both branches are exercised: {counts:?}");
}

/// A per-sample Depth pass takes one override map per light sample's view, each in its
/// own layer; a single map serves every view; any other count is refused, naming the pass.
#[test]
fn depth_overrides_fill_each_light_samples_view() {
    let c = compile_source("point_samples", &support::technique_source("point-samples"), &[], &[]);
    let p = plane();
    let mut inputs = p.inputs();
    inputs.samples = p.sample_views(2, 0.5);
    let ex = sshc_lab::run::Loaded::new(gpu(), c.graph.clone(), c.shaders.clone()).unwrap();
    let mut ex = ex.bind_scene(&inputs).unwrap();
    let texels = (N * N) as usize;
    let layer = |ex: &sshc_lab::run::Bound, k: u32| ex.inspect().read_texture("shadow", k, 0).unwrap().channel(0);
    ex.set_depth_override_views(Some(vec![vec![0.25; texels], vec![0.75; texels]]));
    ex.run_frame().unwrap();
    assert!(layer(&ex, 0).iter().all(|&z| z == 0.25) && layer(&ex, 1).iter().all(|&z| z == 0.75));
    ex.set_depth_override(Some(vec![0.5; texels]));
    ex.run_frame().unwrap();
    assert!((0..2).all(|k| layer(&ex, k).iter().all(|&z| z == 0.5)));
    ex.set_depth_override_views(Some(vec![vec![0.5; texels]; 3]));
    let Err(err) = ex.run_frame() else {
        panic!("three maps for two views were taken")
    };
    let err = err.to_string();
    assert!(err.contains("depth override has 3 maps, the Depth pass `depth` 2 view(s)"), "{err}");
}

/// A probe of `sample_mip_box_at`: `m` = z stored at `precision`, a Mean mip chain over it
/// (built in place: the chain's levels are texture `mapped`'s), and the Shade reading the
/// box `w` texels wide centred `(du, dv)` texels off the receiver.
fn mip_box_probe(precision: &str) -> sshc::Compiled {
    mip_box_probe_of(precision, LOOKUP)
}

/// The probe's lookup.
const LOOKUP: &str = "sample_mip_box_at(m, du * texel_size, dv * texel_size, w * texel_size)";

/// [`mip_box_probe`] with the Shade's visibility `visibility` (of [`LOOKUP`]).
fn mip_box_probe_of(precision: &str, visibility: &str) -> sshc::Compiled {
    let src = format!(
        r#"Technique(
    name: "mip_box_probe",
    params: {{
        "w": Param(ty: F32, default: 1.0, range: (0.0, 64.0), doc: "box width in texels"),
        "du": Param(ty: F32, default: 0.0, range: (-8.0, 8.0), doc: "offset in texels"),
        "dv": Param(ty: F32, default: 0.0, range: (-8.0, 8.0), doc: "offset in texels"),
    }},
    channels: {{
        "z": Channel(precision: F32),
        "m": Channel(precision: {precision}, value: "z"),
    }},
    passes: [
        Depth(name: "depth", writes: "shadow", channel: "z"),
        Map(name: "map", reads: ["shadow"], writes: "mapped", channels: ["m"]),
        Mipmap(name: "mips", reads: "mapped", writes: "chain", reduce: Mean),
        Shade(name: "shade", reads: ["chain"], visibility: "{visibility}"),
    ],
)"#
    );
    compile_source("mip_box_probe", &src, &[], &[])
}

/// Every level of the chain the GPU stored, level 0 first (level l is `N >> l` wide).
fn stored_levels(c: &sshc::Compiled, depth: &[f32]) -> Vec<Vec<f64>> {
    let ex = sshc_lab::run::Loaded::new(gpu(), c.graph.clone(), c.shaders.clone()).unwrap();
    let mut ex = ex.bind_scene(&plane().inputs()).unwrap();
    ex.set_depth_override(Some(depth.to_vec()));
    ex.run_frame().unwrap();
    (0..=N.ilog2())
        .map(|l| {
            let img = ex.inspect().read_texture("mapped", 0, l).unwrap();
            assert_eq!(img.rgba.len(), ((N >> l) * (N >> l)) as usize, "level {l}");
            img.rgba.iter().map(|t| t[0] as f64).collect()
        })
        .collect()
}

/// The coverage-weighted mean of the texels of a level `size` wide over the box
/// `[lo, hi]` (in that level's texels): each texel constant over its footprint.
fn covered_mean(level: &[f64], size: usize, lo: [f64; 2], hi: [f64; 2]) -> f64 {
    let overlap = |a: f64, b: f64, i: usize| (b.min(i as f64 + 1.0) - a.max(i as f64)).max(0.0);
    let mut sum = 0.0;
    for j in 0..size {
        for i in 0..size {
            sum += overlap(lo[0], hi[0], i) * overlap(lo[1], hi[1], j) * level[j * size + i];
        }
    }
    sum / ((hi[0] - lo[0]) * (hi[1] - lo[1]))
}

/// `sample_mip_box` (docs/language.md 8.7) on lavapipe, at several widths (levels 0 to 5 of
/// a 32^2 map) and offsets, against CPU means of the texels the GPU stored:
/// - everywhere, the definition: the covered mean of level L's stored texels, L the level
///   where the box spans one to two texels;
/// - where the box's edges lie on level L's texel edges (or the map's), exactness: the
///   covered mean of the level-0 texels, as a summed-area table would give it.
#[test]
fn the_mip_box_is_the_covered_mean_of_the_level_and_exact_when_aligned() {
    let p = plane();
    let n = N as f64;
    let depth = depth_field("noise", N);
    let mut aligned_above_0 = 0;
    for precision in ["F32", "Unorm8"] {
        let c = mip_box_probe(precision);
        let levels = stored_levels(&c, &depth);
        // What storing a level's mean may move it by, per level (the chain's stores add
        // up along it): F32, the mean's three roundings of 2^-24 relative (values in
        // [0, 1]); Unorm8, half a code (round to nearest, the interpreter's model of
        // lavapipe's stores, `interp::Model::storage`).
        let store = if precision == "F32" { 3.0 * 2f64.powi(-24) } else { 0.5 / 255.0 };
        // The lookup's own error: the box's edges off by the receiver's uv error (a few f32
        // roundings of a uv below 1: 4 * 2^-24, times N texels) and by the rounding of the
        // coordinates computed from it (two more of magnitude N), in level-0 texels; an
        // edge off by delta moves the mean by at most delta / (the box's extent, half a
        // texel at least after clipping) * (the values' spread, 1), four edges: 8 delta.
        // Then the f32 weighing of nine texels and the division: 32 roundings of 2^-24 of
        // values at most 1.
        let delta = 6.0 * n * 2f64.powi(-24);
        let lookup = 8.0 * delta + 32.0 * 2f64.powi(-24);
        let mut aligned = 0;
        for (du, dv) in [(0.75, 0.75), (3.3, -1.6)] {
            for w in [1.5, 2.0, 3.0, 4.0, 6.0, 16.0, 40.0] {
                let run = run_plane(&c, &p, &depth, &[("w", w), ("du", du), ("dv", dv)], 1);
                let width = f64::max(w, 1.0);
                let l = (width.log2().floor() as usize).min(levels.len() - 1);
                let (s, size) = ((1usize << l) as f64, N as usize >> l);
                let mut checked = 0;
                for (v, pos) in run.visibility.iter().zip(&run.positions) {
                    if pos[0].is_nan() {
                        continue;
                    }
                    let (uv, _) = p.project(*pos);
                    let c = [(uv[0] * n + du).clamp(0.0, n), (uv[1] * n + dv).clamp(0.0, n)];
                    let lo = [(c[0] - 0.5 * width).max(0.0), (c[1] - 0.5 * width).max(0.0)];
                    let hi = [(c[0] + 0.5 * width).min(n), (c[1] + 0.5 * width).min(n)];
                    let (v, got_lo, got_hi) = (*v as f64, lo.map(|x| x / s), hi.map(|x| x / s));
                    let def = covered_mean(&levels[l], size, got_lo, got_hi);
                    assert!(
                        (v - def).abs() <= lookup,
                        "{precision} w {w} at ({du}, {dv}), uv {uv:?}: {v} against the level-{l} mean {def}"
                    );
                    checked += 1;
                    // aligned: every edge on a level-L texel edge (the query plane's pixel
                    // centres sit on quarter texels; the projection's f64 of f32 positions
                    // is within 1e-6 texel of them, which `lookup` covers)
                    let on_edge = |x: &f64| (x - x.round()).abs() < 1e-6;
                    if got_lo.iter().chain(&got_hi).all(on_edge) {
                        let snap = |b: [f64; 2]| b.map(|x| (x / s).round() * s);
                        let exact = covered_mean(&levels[0], N as usize, snap(lo), snap(hi));
                        let allowed = lookup + l as f64 * store;
                        assert!(
                            (v - exact).abs() <= allowed,
                            "{precision} w {w} at ({du}, {dv}), uv {uv:?}: {v} against the level-0 mean {exact} (allowed {allowed})"
                        );
                        aligned += 1;
                        aligned_above_0 += usize::from(l > 0);
                    }
                }
                assert!(checked > run.visibility.len() / 2, "{precision} w {w}: {checked} pixels checked");
            }
        }
        assert!(aligned > 100, "{precision}: only {aligned} aligned boxes");
    }
    assert!(aligned_above_0 > 20, "only {aligned_above_0} aligned boxes above level 0");
}

/// A texel of the 3 x 3 window that the box does not cover weighs nothing, whatever it
/// holds: `0 * inf` and `0 * NaN` are NaN, so a weight-0 texel holding either made the whole
/// lookup NaN (issue 51). Analysis keeps a channel's values finite, so the map's texels are
/// set through the depth override, which nothing bounds: 0.25 left of the middle column,
/// +inf (then NaN) right of it; every box left of the middle must read 0.25, including
/// those whose window reaches across it. The boxes that cover the bad texels read them, so
/// the probe's visibility is the lookup where it is below 1/2 and 1 elsewhere (NaN
/// compares false): a frame with non-finite visibility is refused.
#[test]
fn texels_outside_the_mip_box_weigh_nothing_even_when_not_finite() {
    let p = plane();
    let n = N as f64;
    let c = mip_box_probe_of("F32", &format!("let v = {LOOKUP}; select(1.0, v, v < 0.5)"));
    for bad in [f32::INFINITY, f32::NAN] {
        let depth: Vec<f32> = (0..N * N).map(|i| if i % N < N / 2 { 0.25 } else { bad }).collect();
        let levels = stored_levels(&c, &depth);
        assert!(
            !levels[0][(N / 2) as usize].is_finite() && levels[0][0] == 0.25,
            "the map is not the step it should be"
        );
        // the mean of equal values: the f32 weighing of nine texels and the division (32
        // roundings of 2^-24 of a value below 1), as in the test above
        let allowed = 32.0 * 2f64.powi(-24);
        let mut across = 0;
        for w in [1.5, 3.0] {
            let run = run_plane(&c, &p, &depth, &[("w", w), ("du", 0.25), ("dv", 0.25)], 1);
            let s = (1 << (w.log2().floor() as i32)) as f64;
            for (v, pos) in run.visibility.iter().zip(&run.positions) {
                if pos[0].is_nan() {
                    continue;
                }
                let (uv, _) = p.project(*pos);
                let cx = (uv[0] * n + 0.25).clamp(0.0, n);
                let (lo, hi) = (((cx - 0.5 * w) / s).max(0.0), (cx + 0.5 * w) / s);
                // boxes wholly left of the middle (with a margin for the coordinates' rounding)
                if hi > n / 2.0 / s - 1e-3 {
                    continue;
                }
                assert!(
                    (*v as f64 - 0.25).abs() <= allowed,
                    "{bad} w {w}, uv {uv:?}: {v} (box [{lo}, {hi}], texel {s})"
                );
                // the window's third column lies at or right of the middle
                across += usize::from(lo.floor() + 2.0 >= n / 2.0 / s);
            }
        }
        assert!(across > 10, "{bad}: only {across} windows reached the texels right of the middle");
    }
}

/// The box's width varying from pixel to pixel, so that neighbouring pixels read different
/// levels (the researcher's walkthrough of issue 51: lavapipe answered the level's size
/// query with one level for a whole group of pixels, and whole columns read 0 where the
/// width crossed 2 and 4 texels). Against the covered mean of each pixel's own level, on a
/// noise field (so that a texel read from the wrong level shows).
#[test]
fn a_mip_box_whose_width_varies_per_pixel_reads_each_pixels_level() {
    let p = plane();
    let n = N as f64;
    let depth = depth_field("noise", N);
    let c = mip_box_probe_of(
        "F32",
        "sample_mip_box_at(m, du * texel_size, dv * texel_size, w * texel_size * (0.5 + d))",
    );
    let levels = stored_levels(&c, &depth);
    // as in the test above: the edges' f32 error and the weighing's roundings
    let lookup = 8.0 * 6.0 * n * 2f64.powi(-24) + 32.0 * 2f64.powi(-24);
    let mut by_level = [0usize; 6];
    for w in [3.0, 6.0] {
        let run = run_plane(&c, &p, &depth, &[("w", w), ("du", 0.25), ("dv", 0.25)], 1);
        for (v, pos) in run.visibility.iter().zip(&run.positions) {
            if pos[0].is_nan() {
                continue;
            }
            let (uv, d) = p.project(*pos);
            let width = f64::max(w * (0.5 + d), 1.0);
            // a width within f32's reach of a power of two may take either level
            if (width.log2() - width.log2().round()).abs() < 1e-5 {
                continue;
            }
            let l = (width.log2().floor() as usize).min(levels.len() - 1);
            let (s, size) = ((1usize << l) as f64, N as usize >> l);
            let c = [(uv[0] * n + 0.25).clamp(0.0, n), (uv[1] * n + 0.25).clamp(0.0, n)];
            let lo = [(c[0] - 0.5 * width).max(0.0) / s, (c[1] - 0.5 * width).max(0.0) / s];
            let hi = [(c[0] + 0.5 * width).min(n) / s, (c[1] + 0.5 * width).min(n) / s];
            let def = covered_mean(&levels[l], size, lo, hi);
            assert!(
                (*v as f64 - def).abs() <= lookup,
                "w {w}, uv {uv:?}, d {d}: {v} against the level-{l} mean {def}"
            );
            by_level[l] += 1;
        }
    }
    assert!(by_level[..3].iter().all(|&k| k > 100), "pixels per level: {by_level:?}");
}

/// `nearest_level(ch, level)` with a level that differs from pixel to pixel (0 to 3, from
/// the receiver's depth): each pixel reads the texel of its own level containing its uv,
/// exactly (an unfiltered read; lavapipe's per-group answer to the level's size query
/// read the wrong texel or none).
#[test]
fn nearest_level_reads_each_pixels_own_level() {
    let p = plane();
    let n = N as f64;
    let depth = depth_field("noise", N);
    let c = mip_box_probe_of("F32", "nearest_level(m, i32(floor(d * 4.0))) + 0.0 * (w + du + dv)");
    let levels = stored_levels(&c, &depth);
    let run = run_plane(&c, &p, &depth, &[], 1);
    let mut by_level = [0usize; 4];
    for (v, pos) in run.visibility.iter().zip(&run.positions) {
        if pos[0].is_nan() {
            continue;
        }
        let (uv, d) = p.project(*pos);
        // the level is floor(4 d) of an f32 d: skip depths within its reach of a boundary,
        // and uvs within a texel's f32 reach of a texel edge at that level
        let l = (d * 4.0).floor();
        if (d * 4.0 - (d * 4.0).round()).abs() < 1e-5 {
            continue;
        }
        let l = (l as usize).min(3);
        let size = N as usize >> l;
        let texel = uv.map(|u| u * size as f64);
        if texel.iter().any(|t| (t - t.round()).abs() < 1e-4 * n) {
            continue;
        }
        let [i, j] = texel.map(|t| (t.floor() as usize).min(size - 1));
        assert_eq!(*v as f64, levels[l][j * size + i], "uv {uv:?}, d {d}: level {l}, texel ({i}, {j})");
        by_level[l] += 1;
    }
    assert!(by_level.iter().filter(|&&k| k > 50).count() >= 3, "pixels per level: {by_level:?}");
}
