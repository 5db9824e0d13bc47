//! trybuild cases of `technique!`: mistakes fail the build with the expected messages
//! (tests/ui/fail/*.stderr; `TRYBUILD=overwrite` rewrites them, to be reviewed as a diff).
//! What a correct use compiles to is tested in `embedded.rs`, built with the workspace.
//!
//! trybuild builds the cases in its own crate under `target/tests/trybuild`, where
//! `CARGO_MANIFEST_DIR` is that crate's folder; the macro resolves technique paths against
//! `SSHC_SHADERS_GEN_BASE_DIR` instead when it is set, so the cases name files as a crate in
//! `shaders-gen/ui/` would. This package depends on the macro and `sshc-graph` alone:
//! trybuild builds every dependency of it for the cases.

#[test]
fn ui() {
    // SAFETY: this binary has no other test, and no thread of ours reads the environment
    // concurrently; trybuild's cargo inherits the variable.
    unsafe { std::env::set_var("SSHC_SHADERS_GEN_BASE_DIR", env!("CARGO_MANIFEST_DIR")) };
    // trybuild's crate is built once per run, from nothing on a fresh clone: without debug
    // information or incremental state, which no case reads (its messages are rustc's)
    unsafe { std::env::set_var("CARGO_PROFILE_DEV_DEBUG", "false") };
    unsafe { std::env::set_var("CARGO_INCREMENTAL", "0") };
    // scripts/test.sh builds the workspace under clippy-driver; trybuild's crate is built
    // by plain rustc, so that its messages are rustc's alone
    unsafe { std::env::remove_var("RUSTC_WORKSPACE_WRAPPER") };
    unsafe { std::env::remove_var("CLIPPY_ARGS") };
    let t = trybuild::TestCases::new();
    t.compile_fail("tests/ui/fail/*.rs");
}
