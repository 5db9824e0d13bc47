//! One failing fixture per user mistake (Halide's `test/error/`): every `errors/*.ron`
//! must be refused, and its rendered diagnostic must match `errors/*.stderr`.
//! Set `UPDATE_EXPECT=1` to rewrite the expected files after reviewing a change.

mod expect;

use std::path::Path;

fn render(path: &Path) -> String {
    let source = std::fs::read_to_string(path).expect("fixture is readable");
    let name = path.file_name().unwrap().to_string_lossy().into_owned();
    match sshc::compile_str(&source, &sshc::CompileOptions::default()) {
        Ok(_) => panic!("{name}: compiled, but it is a fixture of a mistake"),
        Err(d) => {
            assert!(d.has_errors(), "{name}: refused without an error");
            d.render(&name, &source)
        }
    }
}

#[test]
fn every_mistake_has_its_diagnostic() {
    let fixtures = expect::fixtures("tests/errors");
    assert!(fixtures.len() >= 12, "expected at least 12 fixtures, found {}", fixtures.len());
    expect::check(&fixtures, "diagnostic", |f, name| {
        let got = render(f);
        // Every diagnostic names the file with a line and column.
        assert!(got.contains(&format!("{name}:")), "{name}: no file:line:column in\n{got}");
        got
    });
}

#[test]
fn wrong_precision_names_the_largest_safe_exponent() {
    // F16 holds at most 65504, so exp(c z) at f16 needs c <= ln 65504 = 11.0898 for z in [0, 1].
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/errors/wrong_precision.ron");
    let got = render(&path);
    assert!(got.contains("at or below 11.0898"), "{got}");
    assert!(got.contains("F16"), "{got}");
}

#[test]
fn command_line_overrides_are_checked() {
    let src = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../techniques/csm.ron")).unwrap();
    let opts = |set: &[(&str, &str)]| sshc::CompileOptions {
        set: set.iter().map(|(a, b)| (a.to_string(), b.to_string())).collect(),
        ..Default::default()
    };
    let e = sshc::compile_str(&src, &opts(&[("M", "65")])).unwrap_err();
    assert!(
        e.render("csm.ron", &src).contains("out of range: set on the command line to 65"),
        "{}",
        e.render("csm.ron", &src)
    );
    let e = sshc::compile_str(&src, &opts(&[("MM", "4")])).unwrap_err();
    assert!(e.render("csm.ron", &src).contains("did you mean `M`?"));
    let e = sshc::compile_str(&src, &opts(&[("M", "4.5")])).unwrap_err();
    assert!(e.render("csm.ron", &src).contains("expected a value of type i32"));
    let e = sshc::compile_str(
        &src,
        &sshc::CompileOptions {
            precision: vec![("f".into(), "f64".into())],
            ..Default::default()
        },
    )
    .unwrap_err();
    assert!(e.render("csm.ron", &src).contains("unknown precision"));

    // several channels at once (`c,g,b,p=...`), each name checked
    let plm = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../techniques/penumbra-limit-maps.ron")).unwrap();
    let prec = |name: &str| sshc::CompileOptions {
        precision: vec![(name.into(), "f16".into())],
        ..Default::default()
    };
    let c = sshc::compile_str(&plm, &prec("c, g,b,p")).unwrap_or_else(|e| panic!("{}", e.render("plm", &plm)));
    let packed = c.graph.textures.iter().find(|t| t.name == "plm").expect("the packed map");
    assert_eq!(packed.format, sshc_graph::Format::Rgba16Float, "all four channels at F16");
    let e = sshc::compile_str(&plm, &prec("c,q")).unwrap_err();
    assert!(
        e.render("plm", &plm).contains("no channel or expansion named `q`"),
        "{}",
        e.render("plm", &plm)
    );
}
