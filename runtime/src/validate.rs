//! The runtime's own naga validation of the shaders a graph names: a graph is untrusted
//! input, whoever wrote it, so every module is parsed and validated again before wgpu sees it.

/// Parse and validate WGSL with naga (every validation flag, every capability); the error
/// is naga's report, rendered against the source.
pub fn validate_wgsl(src: &str) -> Result<(), String> {
    let module = naga::front::wgsl::parse_str(src).map_err(|e| e.emit_to_string(src))?;
    naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::all())
        .validate(&module)
        .map_err(|e| e.emit_to_string(src))?;
    Ok(())
}
