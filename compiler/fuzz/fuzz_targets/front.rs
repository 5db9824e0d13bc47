//! Whole technique files: the spanned RON reader, the technique parser, the expression
//! strings inside them, then resolve, check and the rest of the pipeline, and the
//! rendering of every diagnostic.
#![no_main]

use libfuzzer_sys::fuzz_target;

#[path = "common.rs"]
mod common;

fuzz_target!(|data: &[u8]| {
    if let Ok(source) = std::str::from_utf8(data) {
        common::drive(source);
    }
});
