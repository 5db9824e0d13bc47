//! Library code of Geometry passes: for each `primitive` kind built from silhouettes, the
//! WGSL that classifies silhouette edges on the GPU and builds the primitives from the
//! records it appends. A technique's Geometry pass supplies only what each fragment writes
//! (its channel expressions); code generation appends its fragment entry to this library.
//!
//! - `silhouettes.wgsl`: the edges, the silhouette rule and the light-view helpers, shared.
//! - `ConesAndSheets` (penumbra maps, Wyman & Hansen 2003, section 3): `cones_and_sheets.wgsl`.
//! - `Ribbons` (penumbra limit maps, Lawlor 2006, section 3.1): `ribbons.wgsl`.
//! - `Skins` (linear lights, Heidrich et al. 2000, section 3.2): `skins.wgsl`, built from
//!   the depth discontinuities of a neighbouring sample's map rather than from silhouettes;
//!   the compiler prepends `SKIN_FROM`, `sk_depth` and `sk_threshold` (`geometry_pass.rs`).
//!
//! `BackFaces` draws the scene's own triangles and needs no library (`geometry_pass.rs`).

use crate::front::ast::Primitive;
#[cfg(test)]
use sshc_graph::FRAME_WGSL;

/// Triangles per cone (the base polygon is circumscribed about the cone's circle).
pub const CONE_SEGMENTS: u32 = 16;
/// Quads along a sheet (the paper subdivides non-planar sheets).
pub const SHEET_STRIPS: u32 = 4;
/// Vertices drawn per silhouette edge: two cones and a sheet.
pub const CONES_AND_SHEETS_VERTICES: u32 = 2 * 3 * CONE_SEGMENTS + 6 * SHEET_STRIPS;
/// Texels a ribbon reaches past the penumbra's widest extent (Lawlor 2006, section 3.1:
/// "bias up ... to expand the penumbra limit over a few extra pixels"), so that bilinear
/// interpolation at the ribbon's border reads the ribbon's values.
pub const RIBBON_MARGIN: u32 = 2;

const SILHOUETTES: &str = include_str!("silhouettes.wgsl");

/// `silhouettes.wgsl` with the `Edge` struct the runtime writes (`sshc_graph::EDGE_WGSL`,
/// the one definition, checked against naga's layout) after its opening comment.
fn silhouettes() -> String {
    let (head, body) = SILHOUETTES.split_once("\n\n").unwrap_or(("", SILHOUETTES));
    format!("{head}\n\n{}{body}", sshc_graph::EDGE_WGSL)
}
const CONES_AND_SHEETS: &str = include_str!("cones_and_sheets.wgsl");
const RIBBONS: &str = include_str!("ribbons.wgsl");
const SKINS: &str = include_str!("skins.wgsl");

/// The technique param a `Skins` pass reads its discontinuity threshold from (normalised
/// depth; `skins.wgsl` states the detector).
pub const SKIN_THRESHOLD_PARAM: &str = "skin_threshold";

/// The library of one primitive kind: its entry points, record layout and what its
/// fragments provide.
pub struct Library {
    /// The compute entry appending one record per silhouette edge.
    pub compute: &'static str,
    /// The vertex entry pulling the primitives from the records.
    pub vertex: &'static str,
    /// Bytes of one record (the WGSL struct's size).
    pub record_bytes: u32,
    /// The record's WGSL struct name (the library's test checks its size against
    /// `record_bytes`).
    #[cfg_attr(not(test), allow(dead_code))]
    pub record: &'static str,
    pub vertices_per_record: u32,
    /// The fragment entries' parameter type.
    pub varying: &'static str,
    /// WGSL lines defining the `in_*` locals of the primitive's geometry inputs.
    pub inputs: &'static str,
    /// The depth each fragment writes (a WGSL expression over the inputs), when the
    /// primitive resolves by a depth test.
    pub depth: Option<&'static str>,
    /// The library's source with its constants and the group 3 bindings (see
    /// `sshc_graph::Draw::Primitives`), to follow the module's `Frame` declaration.
    pub source: String,
}

/// The library of `primitive`, or `None` for a primitive not built from silhouettes.
pub fn library(primitive: Primitive) -> Option<Library> {
    let bindings = "
@group(3) @binding(0) var<storage, read> cs_edges: array<Edge>;
@group(3) @binding(1) var<storage, read> cs_planes: array<vec4<f32>>;
@group(3) @binding(2) var<storage, read> cs_edge_faces: array<u32>;
@group(3) @binding(3) var<storage, read_write> cs_out: GeneratedRw;
@group(3) @binding(4) var<storage, read> cs_records: Generated;
@group(3) @binding(5) var<storage, read_write> cs_claims: array<atomic<u32>>;
";
    // the generated buffer of a record type: draw arguments, then the records
    let generated = |record: &str| {
        format!(
            "
struct GeneratedRw {{
    vertex_count: atomic<u32>,
    instance_count: u32,
    first_vertex: u32,
    first_instance: u32,
    claimed: atomic<u32>,
    dropped: atomic<u32>,
    pad: vec2<u32>,
    records: array<{record}>,
}}

struct Generated {{
    vertex_count: u32,
    instance_count: u32,
    first_vertex: u32,
    first_instance: u32,
    claimed: u32,
    dropped: u32,
    pad: vec2<u32>,
    records: array<{record}>,
}}

// The slot of a new record, or NO_SLOT past the buffer's capacity (counted in `dropped`:
// the runtime reports it). A record written to its slot is drawn once `cs_commit` counts
// its vertices, so the draw never reads a slot that was not written.
const NO_SLOT: u32 = 0xffffffffu;

fn cs_claim() -> u32 {{
    let at = atomicAdd(&cs_out.claimed, 1u);
    if at >= arrayLength(&cs_out.records) {{
        atomicAdd(&cs_out.dropped, 1u);
        return NO_SLOT;
    }}
    return at;
}}

fn cs_commit(vertices: u32) {{
    atomicAdd(&cs_out.vertex_count, vertices);
}}
"
        )
    };
    match primitive {
        Primitive::ConesAndSheets => Some(Library {
            compute: "cs_cones_and_sheets",
            vertex: "vs_cones_and_sheets",
            record_bytes: 48,
            record: "ConeSheet",
            vertices_per_record: CONES_AND_SHEETS_VERTICES,
            varying: "ConesAndSheetsVarying",
            inputs: "    let in_z_frag = in.z_frag;\n    let in_z_vertex = in.z_vertex;\n    let in_cone_radius = in.cone_radius;\n",
            depth: None,
            source: format!(
                "const CONE_SEGMENTS: u32 = {CONE_SEGMENTS}u;
const SHEET_STRIPS: u32 = {SHEET_STRIPS}u;
const VERTICES_PER_RECORD: u32 = {CONES_AND_SHEETS_VERTICES}u;
{}
{CONES_AND_SHEETS}{}{bindings}",
                silhouettes(),
                generated("ConeSheet")
            ),
        }),
        Primitive::Ribbons => Some(Library {
            compute: "cs_ribbons",
            vertex: "vs_ribbons",
            record_bytes: 48,
            record: "Ribbon",
            vertices_per_record: 6,
            varying: "RibbonsVarying",
            inputs: "    let ribbon = rb_inputs(in);\n    let in_occluder_depth = ribbon.c;\n    let in_penumbra_limit = ribbon.p;\n    let in_limit_depth = ribbon.limit;\n",
            depth: Some("ribbon.depth"),
            source: format!(
                "const RIBBON_MARGIN: u32 = {RIBBON_MARGIN}u;
const VERTICES_PER_RECORD: u32 = 6u;
{}
{RIBBONS}{}{bindings}",
                silhouettes(),
                generated("Ribbon")
            ),
        }),
        Primitive::Skins => Some(Library {
            compute: "cs_skins",
            vertex: "vs_skins",
            record_bytes: 48,
            record: "Skin",
            vertices_per_record: 3,
            varying: "SkinsVarying",
            inputs: "    let in_skin = in.skin;\n    let in_z_frag = in.z_frag;\n",
            depth: None,
            // no edges: the records come from a depth map (group 1)
            source: format!(
                "{SKINS}{}
@group(3) @binding(3) var<storage, read_write> cs_out: GeneratedRw;
@group(3) @binding(4) var<storage, read> cs_records: Generated;
",
                generated("Skin")
            ),
        }),
        Primitive::BackFaces => None,
    }
}

/// A whole module around a library: the `Frame` declaration and a fragment entry writing
/// `value` (a WGSL expression of `in`, the library's varying): what the library's test
/// validates.
#[cfg(test)]
fn module(primitive: Primitive, value: &str) -> Option<String> {
    let lib = library(primitive)?;
    Some(format!(
        "{FRAME_WGSL}@group(0) @binding(0) var<uniform> frame: Frame;
{}
@fragment
fn fs_value(in: {}) -> @location(0) vec4<f32> {{
{}    return vec4<f32>({value});
}}
",
        lib.source, lib.varying, lib.inputs
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_library_validates_and_has_its_entry_points_and_record_size() {
        for (primitive, value) in [
            (Primitive::ConesAndSheets, "in.z_frag - in.z_vertex"),
            (Primitive::Ribbons, "in_occluder_depth + in_penumbra_limit + in_limit_depth"),
        ] {
            let lib = library(primitive).expect("a library");
            let src = module(primitive, value).expect("a module");
            let module = crate::back::validate(&src).unwrap_or_else(|e| panic!("{e}\n{src}"));
            let entries: Vec<&str> = module.entry_points.iter().map(|e| e.name.as_str()).collect();
            for want in [lib.compute, lib.vertex, "fs_value"] {
                assert!(entries.contains(&want), "{primitive:?}: {entries:?}");
            }
            // The record's WGSL size is the graph's record_bytes.
            let size = module
                .types
                .iter()
                .find(|(_, t)| t.name.as_deref() == Some(lib.record))
                .map(|(_, t)| t.inner.size(module.to_ctx()))
                .expect("the record is declared");
            assert_eq!(size, lib.record_bytes, "{primitive:?}");
        }
        assert!(library(Primitive::BackFaces).is_none());
    }
}
