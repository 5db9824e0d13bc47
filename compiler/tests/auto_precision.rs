//! Precisions left to the compiler (`precision: Auto`, `--precision NAME=auto`):
//! chosen from the channel's range, which a compilation specialised for a scene takes from
//! the scene's depths (`SceneFacts::depth_floor`).

use std::path::Path;

fn source() -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/esm-auto.ron")).unwrap()
}

fn options(floor: Option<f32>) -> sshc::CompileOptions {
    sshc::CompileOptions {
        scene: Some(sshc::SceneFacts {
            scene: "a scene".into(),
            light: sshc_graph::LightKind::Sphere,
            depth_floor: floor,
        }),
        ..Default::default()
    }
}

/// The format of the texture holding the ESM basis, and `explain`'s line for it.
fn chosen(src: &str, o: &sshc::CompileOptions) -> (sshc_graph::Format, String) {
    let c = sshc::compile_str(src, o).unwrap_or_else(|d| panic!("{}", d.render("esm-auto.ron", src)));
    let t = c.graph.textures.iter().find(|t| t.name == "esm").expect("the basis texture");
    let text = c.explain();
    let line = text
        .lines()
        .find(|l| l.contains("channel `e` (Auto)"))
        .unwrap_or_else(|| panic!("{text}"));
    (t.format, line.trim().to_string())
}

/// exp(c (z - 1)) with c = 12 spans [exp(-12 (1 - z_min)), 1]: F16 holds it without
/// subnormals where exp(-12 (1 - z_min)) >= 2^-14, that is z_min >= 1 - 14 ln 2 / 12 =
/// 0.19127. Generic (z_min = 0) and below that floor: F32; above it: F16.
#[test]
fn a_precision_left_open_follows_the_scenes_depths() {
    use sshc_graph::Format::{R16Float, R32Float};
    let src = source();
    let generic = sshc::compile_str(&src, &sshc::CompileOptions::default()).unwrap();
    assert_eq!(generic.graph.textures.iter().find(|t| t.name == "esm").unwrap().format, R32Float);
    let (generic, line) = chosen(&src, &options(None));
    assert_eq!(generic, R32Float);
    assert!(
        line.contains("F32, spanning [6.144e-6, 1]") && line.contains("below F16's smallest normal"),
        "{line}"
    );
    let threshold = 1.0 - 14.0 * std::f64::consts::LN_2 / 12.0;
    for (floor, want) in [
        (0.0, R32Float),
        (threshold - 1e-3, R32Float),
        (threshold + 1e-3, R16Float),
        (0.2756, R16Float),
    ] {
        let (format, line) = chosen(&src, &options(Some(floor as f32)));
        assert_eq!(format, want, "depth floor {floor}: {line}");
    }
    let (_, line) = chosen(&src, &options(Some(0.2756)));
    assert!(line.contains("F16, spanning [1.678e-4, 1]"), "{line}");
    // the same choice asked for on the command line of an explicit precision
    let explicit = src.replace("precision: Auto", "precision: F32");
    let c = sshc::compile_str(&explicit, &options(Some(0.2756))).unwrap();
    assert_eq!(c.graph.textures.iter().find(|t| t.name == "esm").unwrap().format, R32Float);
    let mut o = options(Some(0.2756));
    o.precision = vec![("e".into(), "auto".into())];
    assert_eq!(chosen(&explicit, &o).0, R16Float);
    // an explicit precision is not narrowed by the scene: the specialised build stores what
    // the generic one stores (here the same F32 texels)
    let without = sshc::compile_str(&explicit, &options(None)).unwrap();
    assert_eq!(without.shaders, c.shaders);
    // the casters' least depth is recorded in the graph, for the runtime's check, only where
    // a precision was chosen from it
    assert_eq!(c.graph.specialised.and_then(|f| f.depth_floor), None);
    let auto = sshc::compile_str(&src, &options(Some(0.2756))).unwrap();
    assert_eq!(auto.graph.specialised.and_then(|f| f.depth_floor), Some(0.2756));
}
