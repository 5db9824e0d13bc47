//! Runs the example `render_embedded` on a real adapter (lavapipe on machines without a
//! GPU). The example's source is included here as a module and its `run` called with the
//! arguments the command line would give, so `cargo nextest run --workspace` runs the
//! example's code without a nested cargo. Never skips: with no adapter it fails.
//! (nextest's `gpu` test group, one test at a time, takes this binary, `embed`:
//! `.config/nextest.toml`.)

#[allow(dead_code)]
#[path = "../main.rs"]
mod render_embedded;

#[test]
fn render_embedded_example_writes_the_shadowed_bunny() {
    let dir = std::env::temp_dir().join(format!("sshc-shaders-gen-{}", std::process::id()));
    let out = dir.join("nested").join("embedded.png");
    let s = render_embedded::run([out.clone().into_os_string()]).unwrap_or_else(|e| panic!("the example failed: {e}"));
    let png = std::fs::read(&out).unwrap_or_else(|e| panic!("{}: {e}", out.display()));
    assert_eq!(png[..8], *b"\x89PNG\r\n\x1a\n", "not a PNG");
    assert_eq!(s.size, (256, 256), "the bunny scene's camera size");
    let v = &s.visibility;
    assert_eq!(v.len(), 256 * 256);
    assert!(
        v.iter().all(|x| x.is_finite() && (0.0..=1.0).contains(x)),
        "visibility outside [0, 1]"
    );
    let shadowed = v.iter().filter(|&&x| x == 0.0).count();
    let lit = v.iter().filter(|&&x| x == 1.0).count();
    let penumbra = v.len() - shadowed - lit;
    // The bunny casts a shadow on the floor, PCF softens its edge, most of the floor is lit.
    assert!(shadowed > 500, "{shadowed} fully shadowed pixels");
    assert!(penumbra > 100, "{penumbra} penumbra pixels");
    assert!(lit > v.len() / 2, "{lit} lit pixels");
    assert_eq!(s.times.iter().map(|t| t.0.as_str()).collect::<Vec<_>>(), ["depth", "shade"]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn render_embedded_example_refuses_extra_arguments() {
    let e = render_embedded::run(["a.png", "b.ron", "c"].map(Into::into)).unwrap_err();
    assert!(e.contains("unexpected argument `c`"), "{e}");
}
