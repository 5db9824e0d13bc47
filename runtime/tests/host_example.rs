//! The host example (`examples/host.rs`, docs/embedding.md) runs for real: its own device on
//! lavapipe, its own meshes and lighting pass, sshc's visibility sampled in it, PNG frames
//! written. Cargo builds examples with the tests, so the binary is beside this one's folder.

use std::path::PathBuf;
use std::process::Command;

fn example() -> PathBuf {
    // target/<profile>/deps/host_example-<hash> -> target/<profile>/examples/host
    let exe = std::env::current_exe().expect("the test's own path");
    let profile = exe.parent().and_then(|d| d.parent()).expect("target/<profile>");
    profile.join("examples").join("host")
}

#[test]
fn the_host_example_renders_moving_shadows_into_its_own_frames() {
    let out = std::env::temp_dir().join(format!("sshc-host-example-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let bin = example();
    assert!(
        bin.exists(),
        "{} was not built (cargo builds examples with the tests)",
        bin.display()
    );
    let run = Command::new(&bin)
        .arg(&out)
        .args(["--frames", "3", "--size", "96"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("the example runs");
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(run.status.success(), "{stdout}\n{}", String::from_utf8_lossy(&run.stderr));
    // it reports sshc's CPU time per frame
    let us: f64 = stdout
        .split("took ")
        .nth(1)
        .and_then(|r| r.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("{stdout}"));
    assert!(us.is_finite() && us > 0.0, "{stdout}");
    let frames: Vec<Vec<u8>> = (0..3)
        .map(|f| {
            let img = image::open(out.join(format!("frame-{f:03}.png")))
                .unwrap_or_else(|e| panic!("frame {f}: {e}"))
                .to_rgba8();
            assert_eq!(img.dimensions(), (96, 96));
            img.into_raw()
        })
        .collect();
    // the light moves between frames: the shading and the shadows change
    for f in 1..3 {
        let changed = frames[f]
            .chunks_exact(4)
            .zip(frames[f - 1].chunks_exact(4))
            .filter(|(a, b)| a != b)
            .count();
        assert!(
            changed > 96 * 96 / 100,
            "frame {f} differs from frame {} in {changed} pixels",
            f - 1
        );
    }
    let _ = std::fs::remove_dir_all(&out);
}
