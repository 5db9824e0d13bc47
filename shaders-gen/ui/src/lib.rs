//! No code: this package holds `technique!`'s compile-fail cases (`tests/ui.rs`), apart from
//! `sshc-shaders-gen` so that trybuild builds only what the cases use.
