//! Every WGSL file sshc emits, read back from disk as a user's tool would read it, passes
//! naga's front end and validator on its own (outside the compiler), and the SPIR-V that
//! naga's back end writes from it passes Khronos `spirv-val` (Debian package
//! `spirv-tools`): a validator that shares no code with naga.
//!
//! `spirv-val` is installed by `scripts/test.sh`; when it is missing this test fails and
//! says how to install it (it never skips).

use std::path::{Path, PathBuf};
use std::process::Command;

fn tool(name: &str, install: &str) -> PathBuf {
    let found = std::env::var_os("PATH")
        .map(|paths| std::env::split_paths(&paths).map(|p| p.join(name)).find(|p| p.is_file()))
        .unwrap_or(None);
    found.unwrap_or_else(|| panic!("`{name}` is not installed: {install} (scripts/test.sh installs it)"))
}

/// WGSL text to SPIR-V words, as the naga command-line tool does: parse, validate with
/// every check and capability, write SPIR-V 1.0 (which `spirv-val` then checks against
/// Vulkan 1.1).
fn to_spirv(text: &str) -> Result<Vec<u32>, String> {
    let module = naga::front::wgsl::parse_str(text).map_err(|e| e.emit_to_string(text))?;
    let info = naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::all())
        .validate(&module)
        .map_err(|e| e.emit_to_string(text))?;
    naga::back::spv::write_vec(&module, &info, &naga::back::spv::Options::default(), None).map_err(|e| e.to_string())
}

fn techniques() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../techniques");
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "ron"))
        .collect();
    v.sort();
    v
}

/// The bundled techniques, plus variants that reach other code paths of the back end.
fn variants() -> Vec<(PathBuf, sshc::CompileOptions)> {
    let mut out: Vec<(PathBuf, sshc::CompileOptions)> = techniques().into_iter().map(|t| (t, sshc::CompileOptions::default())).collect();
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../techniques");
    let set = |pairs: &[(&str, &str)]| sshc::CompileOptions {
        set: pairs.iter().map(|(a, b)| (a.to_string(), b.to_string())).collect(),
        ..Default::default()
    };
    let prec = |pairs: &[(&str, &str)]| sshc::CompileOptions {
        precision: pairs.iter().map(|(a, b)| (a.to_string(), b.to_string())).collect(),
        ..Default::default()
    };
    out.push((dir.join("csm.ron"), set(&[("M", "16")])));
    out.push((dir.join("csm.ron"), prec(&[("f", "f16")])));
    out.push((dir.join("csm.ron"), prec(&[("f", "f32")])));
    out.push((dir.join("esm.ron"), set(&[("classify", "2")])));
    out.push((dir.join("esm.ron"), set(&[("classify", "0"), ("c", "10.0")])));
    out.push((dir.join("vsm.ron"), prec(&[("m1", "unorm16"), ("m2", "unorm16")])));
    out.push((dir.join("pcf.ron"), set(&[("N", "1")])));
    out
}

#[test]
fn emitted_wgsl_passes_naga_and_spirv_val() {
    let spirv_val = tool("spirv-val", "`apt-get install -y spirv-tools`");
    let out = std::env::temp_dir().join(format!("sshc-validators-{}", std::process::id()));
    let mut checked = 0;
    for (i, (t, opts)) in variants().into_iter().enumerate() {
        let src = std::fs::read_to_string(&t).unwrap();
        let c = sshc::compile_str(&src, &opts).unwrap_or_else(|d| panic!("{}: {}", t.display(), d.render("t", &src)));
        let dir = out.join(format!("{i}"));
        let files = sshc::write_outputs(&c, &dir).unwrap();
        for wgsl in files.iter().filter(|f| f.extension().is_some_and(|e| e == "wgsl")) {
            let spv = wgsl.with_extension("spv");
            let text = std::fs::read_to_string(wgsl).unwrap();
            let words = to_spirv(&text).unwrap_or_else(|e| panic!("naga refused {}:\n{e}", wgsl.display()));
            let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
            std::fs::write(&spv, bytes).unwrap();
            let r = Command::new(&spirv_val)
                .args(["--target-env", "vulkan1.1"])
                .arg(&spv)
                .output()
                .unwrap();
            assert!(
                r.status.success(),
                "spirv-val refused the SPIR-V of {}:\n{}{}",
                wgsl.display(),
                String::from_utf8_lossy(&r.stdout),
                String::from_utf8_lossy(&r.stderr)
            );
            checked += 1;
        }
    }
    let _ = std::fs::remove_dir_all(&out);
    assert!(checked >= 30, "only {checked} modules were checked");
}
