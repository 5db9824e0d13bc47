//! Library code of Geometry passes: for each `primitive` kind, the WGSL that classifies
//! silhouette edges on the GPU and builds the primitives from the records it appends. A
//! technique's Geometry pass supplies only what each fragment writes (its channel
//! expressions); code generation appends its fragment entry to this library.
//!
//! `ConesAndSheets` (penumbra maps, Wyman & Hansen 2003, section 3): `cones_and_sheets.wgsl`.

use sshc_graph::FRAME_WGSL;

/// Triangles per cone (the base polygon is circumscribed about the cone's circle).
pub const CONE_SEGMENTS: u32 = 16;
/// Quads along a sheet (the paper subdivides non-planar sheets).
pub const SHEET_STRIPS: u32 = 4;
/// Vertices drawn per silhouette edge: two cones and a sheet.
pub const CONES_AND_SHEETS_VERTICES: u32 = 2 * 3 * CONE_SEGMENTS + 6 * SHEET_STRIPS;
/// Bytes of one record (`ConeSheet`: three `vec4<f32>`).
pub const CONES_AND_SHEETS_RECORD_BYTES: u32 = 48;
/// Entry points of the library.
pub const CONES_AND_SHEETS_COMPUTE: &str = "cs_cones_and_sheets";
pub const CONES_AND_SHEETS_VERTEX: &str = "vs_cones_and_sheets";

const CONES_AND_SHEETS: &str = include_str!("cones_and_sheets.wgsl");

/// The library of `ConesAndSheets` with its constants and the group 3 bindings (see
/// `sshc_graph::Draw::Primitives`), to follow the module's `Frame` declaration.
pub fn cones_and_sheets() -> String {
    format!(
        "const CONE_SEGMENTS: u32 = {CONE_SEGMENTS}u;
const SHEET_STRIPS: u32 = {SHEET_STRIPS}u;
const VERTICES_PER_RECORD: u32 = {CONES_AND_SHEETS_VERTICES}u;
{CONES_AND_SHEETS}
@group(3) @binding(0) var<storage, read> cs_edges: array<Edge>;
@group(3) @binding(1) var<storage, read> cs_planes: array<vec4<f32>>;
@group(3) @binding(2) var<storage, read> cs_edge_faces: array<u32>;
@group(3) @binding(3) var<storage, read_write> cs_out: GeneratedRw;
@group(3) @binding(4) var<storage, read> cs_records: Generated;
@group(3) @binding(5) var<storage, read_write> cs_claims: array<atomic<u32>>;
"
    )
}

/// A whole module around the library: the `Frame` declaration and a fragment entry
/// writing `value` (a WGSL expression of `in: ConesAndSheetsVarying`). For tests and
/// for the runtime's reference of the machinery.
pub fn cones_and_sheets_module(value: &str) -> String {
    format!(
        "{FRAME_WGSL}@group(0) @binding(0) var<uniform> frame: Frame;
{}
@fragment
fn fs_value(in: ConesAndSheetsVarying) -> @location(0) vec4<f32> {{
    return vec4<f32>({value});
}}
",
        cones_and_sheets()
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cones_and_sheets_library_validates_and_has_its_entry_points() {
        let src = cones_and_sheets_module("in.z_frag - in.z_vertex");
        let module = crate::back::validate(&src).unwrap_or_else(|e| panic!("{e}\n{src}"));
        let entries: Vec<&str> = module.entry_points.iter().map(|e| e.name.as_str()).collect();
        for want in [CONES_AND_SHEETS_COMPUTE, CONES_AND_SHEETS_VERTEX, "fs_value"] {
            assert!(entries.contains(&want), "{entries:?}");
        }
        // The record's WGSL size is the graph's record_bytes.
        let ty = module
            .types
            .iter()
            .find(|(_, t)| t.name.as_deref() == Some("ConeSheet"))
            .map(|(_, t)| t.inner.size(module.to_ctx()))
            .expect("ConeSheet is declared");
        assert_eq!(ty, CONES_AND_SHEETS_RECORD_BYTES);
    }
}
