//! `sshc compare`: the comparison image and its figures, and cascades kept while the light
//! moves.

use super::{number_after, ok, read_pfm, sshc};
use crate::common::{root, temp_dir};

/// `sshc compare` reads the truth that `sshc truth` cached (every technique's camera pass
/// writes the same positions), writes one image with three panels and the figures, and
/// prints them.
#[test]
fn compare_command_writes_the_comparison_and_its_figures() {
    let dir = temp_dir("compare");
    let cache = dir.join("cache");
    let common = [
        "--scene",
        "scenes/contact.ron",
        "--size",
        "32x32",
        "--samples",
        "16",
        "--runs",
        "2",
        "--cache",
    ];
    let mut truth_args = vec!["truth"];
    truth_args.extend(common);
    let truth_out = dir.join("truth.pfm");
    truth_args.extend([cache.to_str().unwrap(), "-o", truth_out.to_str().unwrap()]);
    ok(&truth_args);
    let png = dir.join("compare.png");
    let mut args = vec!["compare", "techniques/pcf.ron"];
    args.extend(common);
    args.extend([
        cache.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
        "--set",
        "N=5",
        "--frames",
        "3",
        "--stability-frames",
        "3",
    ]);
    let out = ok(&args);
    for needle in [
        "truth: read from the cache",
        "pcf.ron on contact.ron: 32x32 px",
        "N=5",
        "error facing the light: RMS",
        "error in penumbra (0 < truth < 1): RMS",
        "temporal: mean |change|",
        "GPU time per frame:",
        "memory peak",
        "device:",
    ] {
        assert!(out.contains(needle), "`{needle}` missing from:\n{out}");
    }
    // The figures, recomputed here from what `sshc truth` and `sshc render` write: the
    // truth read from the cache, and the same technique's visibility, positions and normals.
    let (vis, pos, nrm) = (dir.join("vis.pfm"), dir.join("pos.pfm"), dir.join("nrm.pfm"));
    ok(&[
        "render",
        "techniques/pcf.ron",
        "--scene",
        "scenes/contact.ron",
        "--size",
        "32x32",
        "--set",
        "N=5",
        "-o",
        dir.join("render.png").to_str().unwrap(),
        "--visibility",
        vis.to_str().unwrap(),
        "--positions",
        pos.to_str().unwrap(),
        "--normals",
        nrm.to_str().unwrap(),
    ]);
    let (vis, truth, pos, nrm) = (read_pfm(&vis), read_pfm(&truth_out), read_pfm(&pos), read_pfm(&nrm));
    assert_eq!(
        (vis.data.len(), truth.data.len(), pos.data.len(), nrm.data.len()),
        (1024, 1024, 3072, 3072)
    );
    // contact.ron's sphere light is centred at (-0.8, 3.2, 1.6): a pixel faces it when its
    // normal points to that side of its surface
    let centre = [-0.8f32, 3.2, 1.6];
    let (mut facing, mut penumbra) = (Vec::new(), Vec::new());
    for i in 0..1024 {
        let (p, n) = (&pos.data[3 * i..3 * i + 3], &nrm.data[3 * i..3 * i + 3]);
        if !p.iter().chain(n).all(|c| c.is_finite()) {
            continue;
        }
        let dot: f32 = (0..3).map(|k| n[k] * (centre[k] - p[k])).sum();
        if dot > 0.0 {
            // signed error in 0..255 units
            let e = 255.0 * (vis.data[i] as f64 - truth.data[i] as f64);
            facing.push(e);
            if truth.data[i] > 0.0 && truth.data[i] < 1.0 {
                penumbra.push(e);
            }
        }
    }
    let stats = |e: &[f64]| {
        let rms = (e.iter().map(|x| x * x).sum::<f64>() / e.len().max(1) as f64).sqrt();
        (rms, e.iter().fold(0.0f64, |m, x| m.max(x.abs())), e.len())
    };
    // "error <what>: RMS r, max m (0..255) over n px", as printed: r to 2 decimals, m to 1
    let printed = |what: &str| -> (f64, f64, usize) {
        let line = out
            .lines()
            .find(|l| l.starts_with(&format!("error {what}: RMS ")))
            .unwrap_or_else(|| panic!("no `error {what}` line in:\n{out}"));
        let field = |after: &str, end: &str| -> String {
            let rest = &line[line.find(after).unwrap_or_else(|| panic!("{line}")) + after.len()..];
            rest[..rest.find(end).unwrap_or_else(|| panic!("{line}"))].to_string()
        };
        let parse = |t: String| -> f64 { t.parse().unwrap_or_else(|_| panic!("`{t}` in `{line}`")) };
        (
            parse(field("RMS ", ",")),
            parse(field("max ", " ")),
            parse(field("over ", " px")) as usize,
        )
    };
    for (what, errors) in [("facing the light", &facing), ("in penumbra (0 < truth < 1)", &penumbra)] {
        let (rms, max, n) = stats(errors);
        let (p_rms, p_max, p_n) = printed(what);
        assert_eq!(p_n, n, "{what}: pixels\n{out}");
        // half a unit in the last printed digit, and f32 storage of the PFMs (2^-24 of 255)
        assert!(
            (p_rms - rms).abs() <= 0.005 + 1e-4,
            "{what}: RMS printed {p_rms}, recomputed {rms:.4}\n{out}"
        );
        assert!(
            (p_max - max).abs() <= 0.05 + 1e-4,
            "{what}: max printed {p_max}, recomputed {max:.4}\n{out}"
        );
    }
    assert!(stats(&penumbra).0 > 0.0, "PCF is not exact in the penumbra:\n{out}");
    // FLIP, recomputed from the same files: the image shaded with the visibility against
    // it shaded with the truth's, averaged over the facing pixels (printed to 4 decimals)
    let vec3s = |d: &[f32]| -> Vec<glam::Vec3> { d.chunks(3).map(|c| glam::Vec3::new(c[0], c[1], c[2])).collect() };
    let (p3, n3) = (vec3s(&pos.data), vec3s(&nrm.data));
    let light = sshc_lab::scene::Scene::load(root().join("scenes/contact.ron")).unwrap().lights[0].clone();
    let mask = sshc_lab::metrics::facing_light(&p3, &n3, &light).unwrap();
    let flip = sshc_lab::metrics::flip(&vis.data, &truth.data, &p3, &n3, &light, (32, 32), &mask).unwrap();
    let line = out
        .lines()
        .find(|l| l.starts_with("FLIP facing the light: "))
        .unwrap_or_else(|| panic!("no FLIP line:\n{out}"));
    let printed: f64 = line["FLIP facing the light: ".len()..].split(' ').next().unwrap().parse().unwrap();
    assert!(
        (printed - flip).abs() <= 0.00005 + 1e-7,
        "FLIP printed {printed}, recomputed {flip:.6}\n{out}"
    );
    assert!(flip > 0.0 && flip < 1.0, "{flip}");
    // Temporal: the mean |change| per frame while the light moves 0.25 texel per frame. It
    // is above 0 (a penumbra in view moves) and below what one frame can change a PCF
    // pixel by: N x N bilinear taps over (N + 1)^2 texels with N = 5. Moving the kernel by
    // t texels over fixed depths changes the lit fraction by at most t / N (the weights of
    // its first and last columns move by t, the others not: (1/N^2) N t); the depth map is
    // rasterised anew, and an edge that moves by under a texel flips at most one texel per
    // row of the kernel: N + 1 taps of weight at most 1/N^2. With t < 2 x 0.25 (the step is
    // set at the scene's centre; the occluders are no nearer the light than half its
    // distance to the centre, parallax at most doubles it), at most
    // 255 ((N + 1) / N^2 + 0.5 / N) = 86.7 per pixel (depth tests at near-ties aside, which
    // flip single taps of weight 1/N^2 on few pixels), so also on average.
    let temporal = number_after("temporal: mean |change|", &out);
    let bound = 255.0 * (6.0 / 25.0 + 0.5 / 5.0);
    assert!(temporal > 0.0 && temporal <= bound, "temporal {temporal}, bound {bound:.1}:\n{out}");
    // Three 32-pixel panels scaled by 8, side by side, text below.
    let img = image::open(&png).unwrap().to_rgb8();
    assert!(img.width() >= 3 * 256 && img.height() > 256 + 8 * 19, "{:?}", img.dimensions());
    // The error panel (third) holds red or blue somewhere: PCF errs in the penumbra.
    let x0 = 12 + 2 * (256 + 12);
    let coloured = (0..256)
        .flat_map(|y| (0..256).map(move |x| (x, y)))
        .map(|(x, y)| img.get_pixel(x0 + x, 34 + y).0)
        .filter(|p| p[0].abs_diff(p[2]) > 40)
        .count();
    assert!(coloured > 0, "the error panel is blank");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `compare --cascades 2` binds the cascades, states them, and keeps them through the
/// temporal run (each moved light's frame bound with its cascades), and `render` refuses
/// cascades of a light at a finite position, saying why.
#[test]
fn compare_with_cascades_states_them_and_keeps_them_while_the_light_moves() {
    let dir = std::env::temp_dir().join(format!("sshc-cli-cascades-{}", std::process::id()));
    let out = ok(&[
        "compare",
        "techniques/pcss.ron",
        "--scene",
        "scenes/triangle.ron",
        "--cascades",
        "2",
        "--size",
        "32x32",
        "--samples",
        "16",
        "--runs",
        "2",
        "--stability-frames",
        "3",
        "--cache",
        &dir.join("cache").to_string_lossy(),
        "-o",
        &dir.join("c.png").to_string_lossy(),
    ]);
    assert!(out.contains("cascades: 2 of 512 texels"), "{out}");
    assert!(out.contains("temporal: mean |change|") && out.contains("3 frames"), "{out}");
    let o = sshc(&[
        "render",
        "techniques/pcss.ron",
        "--scene",
        "scenes/bunny.ron",
        "--cascades",
        "2",
        "-o",
        &dir.join("r.png").to_string_lossy(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("a light at infinity") && err.contains("Rectangle"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
