//! The pass graph: resources, passes and the shader modules that run them, plus the
//! binding conventions every generated module follows.
//!
//! Conventions shared by the compiler and the runtime:
//! - `@group(0) @binding(0)`: the [`FRAME_WGSL`] uniform `frame` (light and camera matrices,
//!   depth range, sizes), filled by the runtime each frame.
//! - `@group(0) @binding(1)`: the technique's `Params` uniform, present when
//!   [`PassGraph::params_size`] > 0; every field is 4 bytes at [`ParamDecl::offset`].
//! - `@group(0) @binding(2)`: a filtering sampler (linear, mipmap linear, clamp to edge),
//!   present when [`Step::sampler`] is true.
//! - `@group(0) @binding(3)`: the [`LIGHT_SAMPLES_WGSL`] uniform `light_samples` (every
//!   light sample's view), present when [`Step::light_samples`] is true. A step of a
//!   `PerLightSample` pass runs once per sample k with view k's `frame` (`sample.x = k`).
//! - `@group(1) @binding(i)`: the textures in [`Step::reads`], in order; a summed-area table
//!   ([`Format::SummedAreaU32`]) is a read-only storage buffer `array<vec4<u32>>`, one
//!   element per texel, rows of the shadow map's width, layers one after another.
//! - `@group(2) @binding(i)`: compute steps only: the tables in [`Step::writes`], read-write.
//! - Scene draws use one vertex buffer: `@location(0)` position and `@location(1)` normal,
//!   `vec3<f32>` each, interleaved (24-byte stride), in world space.

#![deny(clippy::wildcard_enum_match_arm)]

pub mod traffic;

use serde::{Deserialize, Serialize};
use std::fmt;

/// Version of this schema; a graph of another version is refused.
pub const SCHEMA_VERSION: u32 = 1;

/// The type of one field of the `Frame` uniform: its WGSL spelling, size and alignment
/// (WGSL's uniform address space), and the Rust array that holds it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameType {
    /// `mat4x4<f32>`, column-major: `[f32; 16]`.
    Mat4,
    /// `vec4<f32>`: `[f32; 4]`.
    Vec4,
}

impl FrameType {
    pub const fn wgsl(self) -> &'static str {
        match self {
            FrameType::Mat4 => "mat4x4<f32>",
            FrameType::Vec4 => "vec4<f32>",
        }
    }

    /// Bytes.
    pub const fn size(self) -> u32 {
        match self {
            FrameType::Mat4 => 64,
            FrameType::Vec4 => 16,
        }
    }

    /// Alignment in bytes.
    pub const fn align(self) -> u32 {
        16
    }
}

/// One field of the `Frame` uniform, in declaration order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameField {
    pub name: &'static str,
    pub ty: FrameType,
}

const fn round_up(v: u32, to: u32) -> u32 {
    v.div_ceil(to) * to
}

/// Byte offset of field `i` of `fields` (WGSL's uniform layout rules: each field at the
/// next multiple of its alignment).
pub const fn field_offset(fields: &[FrameField], i: usize) -> u32 {
    let mut end = 0;
    let mut k = 0;
    while k < i {
        end = round_up(end, fields[k].ty.align()) + fields[k].ty.size();
        k += 1;
    }
    round_up(end, fields[i].ty.align())
}

/// Bytes of a struct of `fields` (its last field's end, rounded up to 16: the struct's
/// alignment, which an array of it strides by).
pub const fn struct_size(fields: &[FrameField]) -> u32 {
    let last = fields.len() - 1;
    round_up(field_offset(fields, last) + fields[last].ty.size(), 16)
}

/// Byte offset of field `i` of [`FRAME_FIELDS`].
pub const fn frame_offset(i: usize) -> u32 {
    field_offset(FRAME_FIELDS, i)
}

macro_rules! frame_type {
    (wgsl Mat4) => {
        "mat4x4<f32>"
    };
    (wgsl Vec4) => {
        "vec4<f32>"
    };
    (rust Mat4) => {
        [f32; 16]
    };
    (rust Vec4) => {
        [f32; 4]
    };
}

/// The one definition of a uniform struct: from the field list come its WGSL declaration
/// (each doc line becomes a `//` comment; `then` is appended), its field table with
/// offsets and size ([`field_offset`], [`struct_size`]), and the Rust struct whose
/// `to_bytes` writes each field at its offset. The `Frame` uniform and one light sample's
/// `SampleView` are made by it; the layout test against naga's layouter is in
/// runtime/src/frame.rs.
macro_rules! uniform_struct {
    (
        $(#[doc = $sdoc:literal])+
        struct $wgsl_name:literal => $rust:ident;
        wgsl: $wgsl:ident, then: $then:literal;
        fields: $fields:ident, size: $size:ident;
        $( $(#[doc = $doc:literal])+ $name:ident: $ty:ident, )+
    ) => {
        /// The WGSL declaration of the struct (and what follows it).
        pub const $wgsl: &str = concat!(
            "struct ", $wgsl_name, " {\n",
            $( $("    //", $doc, "\n",)+ "    ", stringify!($name), ": ", frame_type!(wgsl $ty), ",\n", )+
            "}\n",
            $then
        );

        /// The fields of the struct, in declaration order.
        pub const $fields: &[FrameField] = &[$(FrameField { name: stringify!($name), ty: FrameType::$ty },)+];

        /// Bytes of the struct.
        pub const $size: u32 = struct_size($fields);

        $(#[doc = $sdoc])+
        #[derive(Clone, Copy, Debug, Default, PartialEq)]
        #[repr(C)]
        pub struct $rust {
            $( $(#[doc = $doc])+ pub $name: frame_type!(rust $ty), )+
        }

        impl $rust {
            /// The struct's bytes (little-endian), its size of them, each field at its
            /// [`field_offset`].
            pub fn to_bytes(&self) -> Vec<u8> {
                let mut out = vec![0u8; $size as usize];
                let values: &[&[f32]] = &[$(&self.$name,)+];
                for (i, v) in values.iter().enumerate() {
                    let at = field_offset($fields, i) as usize;
                    for (k, x) in v.iter().enumerate() {
                        out[at + 4 * k..at + 4 * k + 4].copy_from_slice(&x.to_le_bytes());
                    }
                }
                out
            }

            /// Byte offsets of the Rust struct's fields, in declaration order (for the
            /// layout test: the `#[repr(C)]` struct matches the WGSL layout).
            pub fn rust_offsets() -> Vec<usize> {
                vec![$(std::mem::offset_of!($rust, $name),)+]
            }
        }
    };
}

uniform_struct! {
    /// The values of the `Frame` uniform every module declares at `@group(0) @binding(0)`
    /// (matrices column-major).
    struct "Frame" => FrameUniform;
    wgsl: FRAME_WGSL, then: "";
    fields: FRAME_FIELDS, size: FRAME_SIZE;
    /// world -> light clip space
    light_view_proj: Mat4,
    /// world -> light view space (the light looks down -z)
    light_view: Mat4,
    /// world -> camera clip space
    camera_view_proj: Mat4,
    /// xyz: light position (w = 1) or direction towards the light (w = 0)
    light_position: Vec4,
    /// xyz: camera position
    camera_position: Vec4,
    /// x: near, y: far (light view distances), z: 1 / (far - near)
    depth_range: Vec4,
    /// xy: shadow-map size in texels, zw: 1 / size
    shadow_size: Vec4,
    /// x: light radius or half-extent (world units), y: angular diameter (radians),
    /// zw: half-extents of the light along the shadow map's u and v axes (world units)
    light_size: Vec4,
    /// xy: size of the current render target, zw: 1 / size
    target_size: Vec4,
    /// world size of one shadow-map texel: x per unit of view distance (perspective light),
    /// y constant (orthographic light); the size at distance D is x * D + y
    texel_world: Vec4,
    /// x: index of the light-sample view being rendered (0 outside per-sample passes),
    /// y: number of light samples, z: 1 where the samples close a loop (the edges of a
    /// triangle or rectangle light), else 0
    sample: Vec4,
    /// x: frames run since the scene was bound (the `frame` input; exact to 2^24), yzw 0
    counters: Vec4,
}

/// The most light samples a pass graph may render views of ([`PassGraph::samples`]).
pub const MAX_LIGHT_SAMPLES: u32 = 16;

uniform_struct! {
    /// One light sample's view, as the `LightSamples` uniform holds it (matrices
    /// column-major). `LIGHT_SAMPLES_WGSL` declares it and the uniform at
    /// `@group(0) @binding(3)` of steps with [`Step::light_samples`]: one per light sample,
    /// [`MAX_LIGHT_SAMPLES`] of them (unused ones zero).
    struct "SampleView" => SampleViewUniform;
    wgsl: LIGHT_SAMPLES_WGSL, then: "struct LightSamples {\n    views: array<SampleView, 16>,\n}\n";
    fields: SAMPLE_VIEW_FIELDS, size: SAMPLE_VIEW_SIZE;
    /// world -> this sample's light clip space
    view_proj: Mat4,
    /// world -> this sample's light view space (looking down -z)
    view: Mat4,
    /// xyz: the sample's position (w = 1)
    position: Vec4,
    /// x: near, y: far (view distances), z: 1 / (far - near)
    depth_range: Vec4,
    /// x: weight of the segment before the sample, y: of the segment after it (0 where
    /// there is none); z: world size of one texel per unit of view distance; w: tan of half
    /// the (square, symmetric) perspective view's field of view
    weights: Vec4,
}

/// Bytes of the `LightSamples` uniform ([`MAX_LIGHT_SAMPLES`] views; the array length in
/// [`LIGHT_SAMPLES_WGSL`] is checked against it by the layout test).
pub const LIGHT_SAMPLES_SIZE: u32 = SAMPLE_VIEW_SIZE * MAX_LIGHT_SAMPLES;

impl SampleViewUniform {
    /// The bytes of `views` as the `LightSamples` uniform ([`LIGHT_SAMPLES_SIZE`] bytes;
    /// views past [`MAX_LIGHT_SAMPLES`] are dropped, missing ones zero).
    pub fn light_samples_bytes(views: &[SampleViewUniform]) -> Vec<u8> {
        let mut out = Vec::with_capacity(LIGHT_SAMPLES_SIZE as usize);
        for k in 0..MAX_LIGHT_SAMPLES as usize {
            out.extend(views.get(k).copied().unwrap_or_default().to_bytes());
        }
        out
    }
}

/// Workgroup size of compute steps ([`Draw::ComputeRows`], [`Draw::ComputeColumns`]).
pub const COMPUTE_WORKGROUP: u32 = 64;
impl Draw {
    /// Whether the step is a compute dispatch (else a raster draw).
    pub fn is_dispatch(&self) -> bool {
        match self {
            Draw::ComputeRows
            | Draw::ComputeColumns
            | Draw::ComputeTexels
            | Draw::ComputeMipLevels
            | Draw::ComputePixels
            | Draw::Silhouettes { .. }
            | Draw::Discontinuities { .. } => true,
            Draw::SceneFromLight
            | Draw::SceneFromCamera
            | Draw::CameraGBuffer
            | Draw::FullScreen
            | Draw::MipLevels
            | Draw::Primitives { .. } => false,
        }
    }

    /// Whether the step appends records to a generated buffer (a Geometry pass's
    /// classification: silhouette edges, depth discontinuities).
    pub fn generates_records(&self) -> bool {
        match self {
            Draw::Silhouettes { .. } | Draw::Discontinuities { .. } => true,
            Draw::SceneFromLight
            | Draw::SceneFromCamera
            | Draw::CameraGBuffer
            | Draw::ComputePixels
            | Draw::FullScreen
            | Draw::MipLevels
            | Draw::ComputeRows
            | Draw::ComputeColumns
            | Draw::ComputeTexels
            | Draw::ComputeMipLevels
            | Draw::Primitives { .. } => false,
        }
    }

    /// Whether the step is part of a deferred Shade (its G-buffer raster, or the compute
    /// step over its pixels), which only a Shade pass may hold.
    pub fn is_deferred_shade(&self) -> bool {
        match self {
            Draw::CameraGBuffer | Draw::ComputePixels => true,
            Draw::SceneFromLight
            | Draw::SceneFromCamera
            | Draw::FullScreen
            | Draw::MipLevels
            | Draw::ComputeRows
            | Draw::ComputeColumns
            | Draw::ComputeTexels
            | Draw::ComputeMipLevels
            | Draw::Silhouettes { .. }
            | Draw::Primitives { .. }
            | Draw::Discontinuities { .. } => false,
        }
    }

    /// Whether a compute step stores into its target textures (which must then have a
    /// storage format).
    pub fn stores_textures(&self) -> bool {
        match self {
            Draw::ComputeTexels | Draw::ComputeMipLevels => true,
            Draw::SceneFromLight
            | Draw::SceneFromCamera
            | Draw::CameraGBuffer
            | Draw::ComputePixels
            | Draw::FullScreen
            | Draw::MipLevels
            | Draw::ComputeRows
            | Draw::ComputeColumns
            | Draw::Silhouettes { .. }
            | Draw::Primitives { .. }
            | Draw::Discontinuities { .. } => false,
        }
    }

    /// Whether the step writes the levels below the base of its targets' mip chains.
    pub fn writes_levels_below_base(&self) -> bool {
        match self {
            Draw::MipLevels | Draw::ComputeMipLevels => true,
            Draw::SceneFromLight
            | Draw::SceneFromCamera
            | Draw::CameraGBuffer
            | Draw::ComputePixels
            | Draw::FullScreen
            | Draw::ComputeRows
            | Draw::ComputeColumns
            | Draw::ComputeTexels
            | Draw::Silhouettes { .. }
            | Draw::Primitives { .. }
            | Draw::Discontinuities { .. } => false,
        }
    }
}

/// Workgroup side of [`Draw::ComputeTexels`] and [`Draw::ComputePixels`] steps (8 x 8
/// invocations).
pub const TEXEL_WORKGROUP: u32 = 8;

/// The receiver's normal in WGSL, in a fragment entry whose input `in` has `world` and
/// `normal`: surfaces are two-sided, and the receiver is the side the camera sees. Defines
/// `n`. The compiler's Shade passes and the runtime's draw of objects that receive no
/// shadow share it.
pub const SHADE_NORMAL_WGSL: &str = "    // Two-sided surfaces: the receiver is the side the camera sees. The triangle's own
    // normal from screen-space derivatives, cross(dpdy, dpdx) of the world position, faces
    // the camera whatever the winding (framebuffer y runs down); the interpolated normal is
    // turned to its side, so a smooth normal at a silhouette keeps its sign.
    let in_face = cross(dpdy(in.world), dpdx(in.world));
    let in_smooth = normalize(in.normal);
    let n = select(in_smooth, -in_smooth, dot(in_smooth, in_face) < 0.0);
";

/// The shaded colour of the camera image in WGSL, an expression of the visibility `vis`
/// and `lambert` (`max(n . l, 0)`): 12 % ambient, the rest lit. The compiler's Shade passes
/// and the runtime's draw of objects that receive no shadow (`vis` = 1) share it.
pub const SHADE_COLOR_WGSL: &str = "vec4<f32>(vec3<f32>(0.12 + 0.88 * vis * lambert), 1.0)";

/// The receiver-plane depth slope (Isidoro 2006) in WGSL: from the derivatives over the
/// screen of the light-space uv (`duv_dx`, `duv_dy`) and of the normalised depth (`dd_dx`,
/// `dd_dy`), solve `[duv/dx; duv/dy] g = [dd/dx; dd/dy]` and define `in_depth_slope`
/// (`|g|` in texels, at most 0.1; 0 where the Jacobian is singular). The compiler's Shade
/// passes take the derivatives from the hardware (`dpdx`, `dpdy`); the runtime's step that
/// turns a host's pixels into the G-buffer from neighbouring pixels. One definition for both.
pub const DEPTH_SLOPE_WGSL: &str = "    let det = duv_dx.x * duv_dy.y - duv_dx.y * duv_dy.x;
    let g = vec2<f32>(dd_dx * duv_dy.y - duv_dx.y * dd_dy, duv_dx.x * dd_dy - dd_dx * duv_dy.x);
    let in_depth_slope = select(0.0, min(length(g / det) * frame.shadow_size.z, 0.1), abs(det) > 1e-14);
";

/// The G-buffer's normal encoding in WGSL: `octahedral` and its inverse `from_octahedral`
/// (Cigolle et al. 2014, section 3.1), shared by the compiler's deferred Shade and the
/// runtime's host pixels.
pub const OCTAHEDRAL_WGSL: &str = "// Octahedral encoding of a unit vector (Cigolle et al. 2014, section 3.1).
fn octahedral(v: vec3<f32>) -> vec2<f32> {
    let p = v.xy / (abs(v.x) + abs(v.y) + abs(v.z));
    let sign = select(vec2<f32>(-1.0), vec2<f32>(1.0), p >= vec2<f32>(0.0));
    return select((1.0 - abs(p.yx)) * sign, p, v.z >= 0.0);
}

fn from_octahedral(e: vec2<f32>) -> vec3<f32> {
    var v = vec3<f32>(e, 1.0 - abs(e.x) - abs(e.y));
    let t = max(-v.z, 0.0);
    let sign = select(vec2<f32>(1.0), vec2<f32>(-1.0), v.xy >= vec2<f32>(0.0));
    v = vec3<f32>(v.xy + t * sign, v.z);
    return normalize(v);
}
";

/// The G-buffer a deferred Shade pass writes in its [`Draw::CameraGBuffer`] step and reads
/// in its [`Draw::ComputePixels`] step, one texture per entry at the camera's resolution,
/// the same for every technique (32 bytes a pixel, WebGPU's limit on colour attachments):
/// - `Rgba32Float`: xyz the receiver's world position, w the receiver-plane depth slope
///   of the light's centre view (`depth_slope`, >= 0); the clear value, where the camera
///   sees no surface, has w = -1;
/// - `Rg32Float`: the world normal turned to the camera's side (`n`), octahedral encoding
///   (Cigolle et al. 2014);
/// - `Rgba16Float`: the screen-space derivatives of the centre view's shadow-map
///   coordinates, xy `dpdx(uv)`, zw `dpdy(uv)` (the footprint of implicit-LOD lookups).
pub const GBUFFER: [Format; 3] = [Format::Rgba32Float, Format::Rg32Float, Format::Rgba16Float];

/// The four camera outputs of a Shade pass, in the order of [`Draw::SceneFromCamera`]'s
/// targets and [`Draw::ComputePixels`]'s bindings.
pub const CAMERA_OUTPUTS: [Format; 4] = [Format::R32Float, Format::Rgba8Unorm, Format::Rgba32Float, Format::Rgba16Float];

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PassGraph {
    pub version: u32,
    pub technique: String,
    pub title: Option<String>,
    /// The paper and equations the technique implements.
    pub paper: Option<String>,
    /// Light models the technique assumes (empty: any).
    pub lights: Vec<LightModel>,
    pub params: Vec<ParamDecl>,
    /// Bytes of the `Params` uniform (0: none).
    pub params_size: u32,
    pub textures: Vec<TextureDecl>,
    /// Light samples the `PerLightSample` passes render one view each of, 1 to
    /// [`MAX_LIGHT_SAMPLES`] (1 when there are none).
    #[serde(default = "one", skip_serializing_if = "is_one")]
    pub samples: u32,
    /// Buffers generated on the GPU (Geometry passes); absent when there are none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub buffers: Vec<BufferDecl>,
    /// In execution order.
    pub passes: Vec<PassDecl>,
    /// What the compiler removed, and why.
    pub removed: Vec<String>,
    /// The scene facts the graph was specialised for (`sshc compile --scene`); the runtime
    /// refuses a scene that breaks them. Absent for a generic graph.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub specialised: Option<SceneFacts>,
}

/// What a graph specialised for a scene assumes of it: the kind of its light,
/// from which the compiler folds the light inputs that are 0 for every light of that kind
/// ([`SceneFacts::zero_inputs`]), and the least depth its casters reach in the light's
/// view, from which it narrows the range of what the Depth pass writes (and so the
/// precision a channel left open takes).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFacts {
    /// The scene file it was specialised for (for messages).
    pub scene: String,
    /// The kind of the scene's light.
    pub light: LightKind,
    /// The least normalised depth of the scene's casters in each light's view
    /// ([`caster_depth_floor`]): the Depth pass writes values in `[depth_floor, 1]`.
    /// Absent: `[0, 1]` (no caster, or facts from before it was recorded).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub depth_floor: Option<f32>,
}

/// The least normalised linear depth, `(-(view p).z - near) / (far - near)` clamped to
/// [0, 1] (the Depth pass's), of the first `casting` vertices of `vertices` (interleaved
/// position and normal, 6 floats a vertex; `None`: all) under the column-major
/// `light_view`; `None` without a casting vertex. Depth is affine in position, so a
/// triangle's least depth inside the view is at least its vertices' least: a lower bound
/// of what the Depth pass writes where a caster covers a texel (elsewhere it writes 1).
/// One function for the facts a compilation assumes and the runtime's check of a scene
/// against them, so both compute the same value.
pub fn caster_depth_floor(vertices: &[f32], casting: Option<u32>, light_view: &[f32; 16], near: f32, far: f32) -> Option<f32> {
    let n = casting.map_or(vertices.len() / 6, |c| (c as usize).min(vertices.len() / 6));
    let span = far - near;
    if span.is_nan() || span <= 0.0 {
        return None;
    }
    vertices
        .chunks_exact(6)
        .take(n)
        .map(|v| {
            // row 2 of the column-major matrix: the view-space z
            let z = light_view[2] * v[0] + light_view[6] * v[1] + light_view[10] * v[2] + light_view[14];
            ((-z - near) / span).clamp(0.0, 1.0)
        })
        .reduce(f32::min)
}

impl SceneFacts {
    /// The light inputs (by their names in techniques) that are 0 for every light of the
    /// kind: a light's size, radius or half-extent and its width are 0 for a point, a
    /// directional light and a distant disk (whose extent is its angle); the spread is 0
    /// for every light but a distant disk.
    pub fn zero_inputs(&self) -> Vec<&'static str> {
        let k = self.light;
        [
            ("light_size", k.has_size()),
            ("light_width", k.has_width()),
            ("light_spread", k.has_spread()),
        ]
        .into_iter()
        .filter(|(_, has)| !has)
        .map(|(name, _)| name)
        .collect()
    }
}

/// The kinds of light. This is the one list: a technique's [`LightModel`] is `Any` or one
/// of these (the compiler parses `light:` through [`LightKind::from_name`]), and a scene's
/// light, which adds the geometry, says its kind with `Light::kind`. Adding a kind means
/// a variant here, its entry in [`LightKind::ALL`], and the arms the compiler then asks
/// for (names, [`LightModel`], the scene's geometry).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum LightKind {
    Point,
    Directional,
    Sphere,
    Disk,
    Rectangle,
    /// A linear light; a technique renders one view per sample along it (Heidrich et al. 2000).
    Segment,
    /// A disk at infinity given by its angular diameter (Lawlor 2006).
    DistantDisk,
    /// A triangle; per-sample techniques take its edges as linear lights (Heidrich et al.
    /// 2000, section 4, figure 8).
    Triangle,
}

impl LightKind {
    pub const ALL: [LightKind; 8] = [
        LightKind::Point,
        LightKind::Directional,
        LightKind::Sphere,
        LightKind::Disk,
        LightKind::Rectangle,
        LightKind::Segment,
        LightKind::DistantDisk,
        LightKind::Triangle,
    ];

    /// The name scene and technique files write.
    pub fn name(self) -> &'static str {
        match self {
            LightKind::Point => "Point",
            LightKind::Directional => "Directional",
            LightKind::Sphere => "Sphere",
            LightKind::Disk => "Disk",
            LightKind::Rectangle => "Rectangle",
            LightKind::Segment => "Segment",
            LightKind::DistantDisk => "DistantDisk",
            LightKind::Triangle => "Triangle",
        }
    }

    pub fn from_name(name: &str) -> Option<LightKind> {
        LightKind::ALL.into_iter().find(|k| k.name() == name)
    }

    /// Whether the light has a size in world units (`light_size`: a radius or half-extent):
    /// 0 for a point and a directional light, and for a distant disk, whose extent is its
    /// angle.
    pub fn has_size(self) -> bool {
        match self {
            LightKind::Sphere
            | LightKind::Disk
            | LightKind::Rectangle
            | LightKind::Segment
            | LightKind::Triangle
            | LightKind::DistantDisk => true,
            LightKind::Point | LightKind::Directional => false,
        }
    }

    /// Whether the light has a width across the shadow map (`light_width`); 0 for a point,
    /// a directional light and a distant disk.
    pub fn has_width(self) -> bool {
        match self {
            LightKind::Sphere | LightKind::Disk | LightKind::Rectangle | LightKind::Segment | LightKind::Triangle => true,
            LightKind::Point | LightKind::Directional | LightKind::DistantDisk => false,
        }
    }

    /// Whether the light has an angular spread (`light_spread`): a distant disk only.
    pub fn has_spread(self) -> bool {
        match self {
            LightKind::DistantDisk => true,
            LightKind::Point
            | LightKind::Directional
            | LightKind::Sphere
            | LightKind::Disk
            | LightKind::Rectangle
            | LightKind::Segment
            | LightKind::Triangle => false,
        }
    }

    /// True for lights at infinity (orthographic light views).
    pub fn is_distant(self) -> bool {
        match self {
            LightKind::Directional | LightKind::DistantDisk => true,
            LightKind::Point | LightKind::Sphere | LightKind::Disk | LightKind::Rectangle | LightKind::Segment | LightKind::Triangle => {
                false
            }
        }
    }
}

/// The light a technique assumes: any, or a [`LightKind`] (with the number of views
/// along a segment light).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum LightModel {
    Any,
    Point,
    Directional,
    Sphere,
    Disk,
    Rectangle,
    Segment { samples: u32 },
    DistantDisk,
    Triangle,
}

impl LightModel {
    /// The kind assumed; `None` for `Any`.
    pub fn kind(self) -> Option<LightKind> {
        match self {
            LightModel::Any => None,
            LightModel::Point => Some(LightKind::Point),
            LightModel::Directional => Some(LightKind::Directional),
            LightModel::Sphere => Some(LightKind::Sphere),
            LightModel::Disk => Some(LightKind::Disk),
            LightModel::Rectangle => Some(LightKind::Rectangle),
            LightModel::Segment { .. } => Some(LightKind::Segment),
            LightModel::DistantDisk => Some(LightKind::DistantDisk),
            LightModel::Triangle => Some(LightKind::Triangle),
        }
    }

    /// The model assuming `kind`; `samples` is the number of views along a segment light
    /// (ignored for the other kinds).
    pub fn of(kind: LightKind, samples: u32) -> LightModel {
        match kind {
            LightKind::Point => LightModel::Point,
            LightKind::Directional => LightModel::Directional,
            LightKind::Sphere => LightModel::Sphere,
            LightKind::Disk => LightModel::Disk,
            LightKind::Rectangle => LightModel::Rectangle,
            LightKind::Segment => LightModel::Segment { samples },
            LightKind::DistantDisk => LightModel::DistantDisk,
            LightKind::Triangle => LightModel::Triangle,
        }
    }

    /// Whether a technique assuming this model is meant for a light of `kind`.
    pub fn accepts(self, kind: LightKind) -> bool {
        self.kind().is_none_or(|k| k == kind)
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum ParamType {
    F32,
    I32,
    Bool,
}

impl ParamType {
    /// A value's 4 bytes in the `Params` uniform (little-endian): an f32, an i32 (truncated
    /// towards zero), or a bool as the u32 0 or 1 (any non-zero value is true).
    pub fn bytes(self, v: f64) -> [u8; 4] {
        match self {
            ParamType::F32 => (v as f32).to_le_bytes(),
            ParamType::I32 => (v as i32).to_le_bytes(),
            ParamType::Bool => u32::from(v != 0.0).to_le_bytes(),
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParamDecl {
    pub name: String,
    pub ty: ParamType,
    /// The value compiled in (fixed) or the default (uniform).
    pub value: f64,
    pub range: Option<(f64, f64)>,
    /// Byte offset in `Params` when a runtime uniform; `None` when fixed at compile time.
    pub offset: Option<u32>,
    pub doc: Option<String>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Format {
    R8Unorm,
    Rg8Unorm,
    Rgba8Unorm,
    R16Unorm,
    Rg16Unorm,
    Rgba16Unorm,
    R16Float,
    Rg16Float,
    Rgba16Float,
    R32Float,
    Rg32Float,
    Rgba32Float,
    /// Summed-area tables: u32 fixed point, stored in a storage buffer.
    SummedAreaU32,
}

impl Format {
    pub fn bytes_per_texel(self) -> u32 {
        match self {
            Format::R8Unorm => 1,
            Format::Rg8Unorm | Format::R16Unorm | Format::R16Float => 2,
            Format::Rgba8Unorm | Format::Rg16Unorm | Format::Rg16Float | Format::R32Float => 4,
            Format::Rgba16Unorm | Format::Rgba16Float | Format::Rg32Float => 8,
            Format::Rgba32Float => 16,
            Format::SummedAreaU32 => 16,
        }
    }

    /// Whether WebGPU can write the format from a shader without an optional feature
    /// (`textureStore` into a storage texture): the compute schedule's condition.
    pub fn storable(self) -> bool {
        matches!(
            self,
            Format::Rgba8Unorm | Format::Rgba16Float | Format::R32Float | Format::Rg32Float | Format::Rgba32Float
        )
    }

    /// The WGSL storage format name, as in `texture_storage_2d<...>`.
    pub fn wgsl(self) -> &'static str {
        match self {
            Format::R8Unorm => "r8unorm",
            Format::Rg8Unorm => "rg8unorm",
            Format::Rgba8Unorm => "rgba8unorm",
            Format::R16Unorm => "r16unorm",
            Format::Rg16Unorm => "rg16unorm",
            Format::Rgba16Unorm => "rgba16unorm",
            Format::R16Float => "r16float",
            Format::Rg16Float => "rg16float",
            Format::Rgba16Float => "rgba16float",
            Format::R32Float => "r32float",
            Format::Rg32Float => "rg32float",
            Format::Rgba32Float => "rgba32float",
            Format::SummedAreaU32 => "rgba32uint",
        }
    }
}

/// How large a texture is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Extent {
    /// The shadow-map resolution the scene asks for.
    ShadowMap,
    /// The camera's resolution.
    Camera,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TextureDecl {
    pub name: String,
    pub format: Format,
    pub layers: u32,
    pub extent: Extent,
    /// A full mip chain.
    pub mips: bool,
    /// Only used within one pass (the intermediate of a separable filter).
    pub transient: bool,
    pub channels: Vec<ChannelDecl>,
    /// Views the texture holds (written by a `PerLightSample` pass: [`PassGraph::samples`];
    /// else 1): `layers` array layers per view, view k's layer l at `k * layers + l`.
    #[serde(default = "one", skip_serializing_if = "is_one")]
    pub views: u32,
}

impl TextureDecl {
    /// Array layers the texture is allocated with: `layers` per view.
    pub fn array_layers(&self) -> u32 {
        self.layers.saturating_mul(self.views)
    }
}

fn one() -> u32 {
    1
}

fn is_one(v: &u32) -> bool {
    *v == 1
}

/// Where a channel lives in a texture and how to decode it: `value = stored / scale + bias`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ChannelDecl {
    pub name: String,
    pub layer: u32,
    pub component: u32,
    pub bias: f64,
    pub scale: f64,
    /// Value range found by range analysis.
    pub range: (f64, f64),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum PassKind {
    Depth,
    Map,
    Filter,
    Mipmap,
    SummedArea,
    Geometry,
    Shade,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PassDecl {
    pub name: String,
    pub kind: PassKind,
    /// For scene draws from the light: its centre, or once per light sample (linear lights).
    pub views: Views,
    /// The WGSL file, relative to the graph's folder.
    pub shader: String,
    pub steps: Vec<Step>,
}

/// Which light views a pass that draws the scene from the light renders.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Views {
    /// One view from the light's centre.
    LightCenter,
    /// One view per light sample; the pass's textures get one layer block per view.
    PerLightSample,
}

/// What one step draws or dispatches.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Draw {
    /// The scene rasterised from the light.
    SceneFromLight,
    /// The scene rasterised from the camera, into the four camera outputs (visibility
    /// `r32float`, colour `rgba8unorm`, world position `rgba32float`, world normal
    /// `rgba16float`) and the camera's depth: a forward Shade pass.
    SceneFromCamera,
    /// The scene rasterised from the camera into the runtime's G-buffer ([`GBUFFER`]) and
    /// the camera's depth: the first step of a deferred Shade pass. Background texels keep
    /// the clear value, NaN.
    CameraGBuffer,
    /// One invocation per camera pixel ([`TEXEL_WORKGROUP`] x [`TEXEL_WORKGROUP`] per
    /// workgroup, x the column, y the row; invocations past the target's edge do nothing):
    /// the second step of a deferred Shade pass, after a [`Draw::CameraGBuffer`] step. Group
    /// 2 binds the four camera outputs (in [`Draw::SceneFromCamera`]'s order) at bindings 0
    /// to 3 as `texture_storage_2d_array<format, write>` of one layer; group 3 binds the
    /// G-buffer's textures at bindings 0 to 2 as `texture_2d<f32>` (read with
    /// `textureLoad`). The step writes every pixel, the background's included.
    ComputePixels,
    /// One full-screen triangle (3 vertices, no vertex buffer) over the targets.
    FullScreen,
    /// One full-screen triangle per mip level 1.. of the targets, each reading the level above.
    MipLevels,
    /// A compute dispatch with one invocation per row of the shadow map (64 per workgroup).
    ComputeRows,
    /// A compute dispatch with one invocation per column of the shadow map (64 per workgroup).
    ComputeColumns,
    /// A compute dispatch with one invocation per texel of the shadow map
    /// ([`TEXEL_WORKGROUP`] x [`TEXEL_WORKGROUP`] per workgroup, x the column, y the row;
    /// invocations past the map's edge do nothing): the compute schedule of a Map pass. It
    /// writes its targets with `textureStore`: group 2 binds write `i` at binding `i` as a
    /// `texture_storage_2d_array<format, write>` of the texture's base level, all layers
    /// (the target's `layer` is the layer the entry stores); each written format must be
    /// a storage format ([`Format::storable`]).
    ComputeTexels,
    /// The compute schedule of a Mipmap pass: for each mip level k >= 1 of the targets, a
    /// dispatch with one invocation per texel of level k (as [`Draw::ComputeTexels`]),
    /// reading level k - 1 (`View::PreviousLevel`) and storing into level k (group 2
    /// binding 0: a storage view of that level, all layers).
    ComputeMipLevels,
    /// A compute dispatch with one invocation per edge of the scene's meshes (64 per
    /// workgroup): it classifies the edge as seen from the light's centre and, for a
    /// silhouette, appends one record to `buffer` and adds the record's vertices to the
    /// buffer's draw arguments (Geometry passes; the runtime's `adjacency` module states
    /// the silhouette rule). The runtime resets the vertex count before the dispatch. The
    /// dispatch may be two-dimensional (at most 65,535 workgroups along x): the edge index is
    /// `id.x + id.y * 64 * num_workgroups.x`, and indices past the edge count do nothing.
    Silhouettes { buffer: String },
    /// The primitives of the records in `buffer`, drawn indirectly with the arguments a
    /// `Silhouettes` step wrote (the vertex stage reads the records: vertex pulling, one
    /// record per `vertices_per_record` vertices), overlaps resolved by `resolve`. Group 3
    /// binds the buffer at binding 4 (read-only); a `Silhouettes` step binds the edges,
    /// face planes and face references at 0 to 2, the buffer at 3 and one `u32` claim per
    /// welded vertex at 5 (read-write, cleared before the dispatch).
    Primitives { buffer: String, resolve: Resolve },
    /// A compute dispatch with one invocation per cell of the mesh joining the shadow
    /// map's texel centres ((size - 1)^2 cells; x the column, y the row, 64 per workgroup
    /// along x), over the view `source` of a `PerLightSample` pass: the cell's depth
    /// discontinuities become records appended to `buffer` as a `Silhouettes` step does
    /// (Heidrich et al. 2000, section 3.2). Run once per view k of the pass, before the
    /// view's `Primitives` step; group 3 binds the buffer at 3. The buffer holds at most
    /// [`MAX_DISCONTINUITY_RECORDS`] records; the shader drops records past its capacity.
    Discontinuities { buffer: String, source: Neighbour },
}

/// The most records a [`Draw::Discontinuities`] buffer holds (or one per cell, if fewer).
pub const MAX_DISCONTINUITY_RECORDS: u32 = 1 << 18;

/// Which view's depth discontinuities a `Skins` pass warps into view k.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Neighbour {
    /// View k - 1 (none for view 0, unless the samples close a loop).
    Previous,
    /// View k + 1 (none for the last view, unless the samples close a loop).
    Next,
}

/// How the fragments of overlapping generated primitives combine in a target: the three
/// overlap rules of Wyman & Hansen 2003, figure 6, and the lightest, by blending (every
/// target starts at the rule's identity); or a depth test (`Nearest`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Resolve {
    /// The smallest value wins (the darkest shadow); targets start at 1.
    KeepMin,
    /// The largest value wins; targets start at 0 (the identity of `max`), so a texel no
    /// fragment covers reads 0: a technique using it reads coverage from the value.
    KeepMax,
    /// Shadow contributions add: each fragment writes its shadow amount `1 - v`, and the
    /// target keeps `1 - sum(1 - v)` (clamp it to [0, 1] when reading); targets start at 1.
    Add,
    /// Values multiply; targets start at 1.
    Multiply,
    /// The fragment nearest the light wins, by a depth test (`Less`) on the depth the
    /// fragment writes (`@builtin(frag_depth)`, or its rasterised depth): no blending;
    /// targets and depth start at 1. Every channel of the winning fragment is kept
    /// together, so values written by one fragment stay consistent (Lawlor 2006,
    /// section 3.1: "highest penumbra limit wins").
    Nearest,
}

/// A buffer of records generated on the GPU by a `Silhouettes` step: 16 bytes of draw
/// arguments (`vertex_count`, `instance_count`, `first_vertex`, `first_instance`: what
/// `draw_indirect` reads) followed by at most one record of `record_bytes` per edge of
/// the scene's meshes. The runtime sizes it from the edge count before allocation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BufferDecl {
    pub name: String,
    /// Bytes per record: a multiple of 16, at most [`MAX_RECORD_BYTES`].
    pub record_bytes: u32,
    /// Vertices drawn per record, at most [`MAX_VERTICES_PER_RECORD`].
    pub vertices_per_record: u32,
}

/// Largest record of a generated buffer, bytes.
pub const MAX_RECORD_BYTES: u32 = 1024;
/// Most vertices drawn per generated record.
pub const MAX_VERTICES_PER_RECORD: u32 = 4096;
/// Bytes of the draw arguments at the start of a generated buffer.
pub const DRAW_ARGS_BYTES: u32 = 16;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum View {
    /// Every mip level.
    All,
    /// Level 0 only.
    Base,
    /// For [`Draw::MipLevels`]: the level above the one being written.
    PreviousLevel,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Binding {
    pub binding: u32,
    pub texture: String,
    pub view: View,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Target {
    pub texture: String,
    pub layer: u32,
}

/// Operation counts of one invocation of an entry point, counted on the naga IR.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OpCount {
    pub fetches: u32,
    pub ops: u32,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Step {
    pub vertex: Option<String>,
    pub fragment: Option<String>,
    pub compute: Option<String>,
    pub draw: Draw,
    pub reads: Vec<Binding>,
    pub writes: Vec<Target>,
    /// Binds the `Params` uniform.
    pub params: bool,
    /// Binds the filtering sampler.
    pub sampler: bool,
    /// Binds the `LightSamples` uniform ([`LIGHT_SAMPLES_WGSL`]) at group 0, binding 3.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub light_samples: bool,
    /// Per fragment or compute invocation.
    pub cost: OpCount,
}

/// Why a graph was refused.
#[derive(Clone, Debug, PartialEq)]
pub enum GraphError {
    Syntax {
        message: String,
        line: usize,
        column: usize,
    },
    Version {
        found: u32,
        expected: u32,
    },
    Path {
        pass: String,
        path: String,
    },
    Reference {
        pass: String,
        name: String,
    },
    /// A param whose value or range is not finite, or whose value lies outside its range.
    Param {
        param: String,
        message: String,
    },
    /// Two textures, passes or params of the same name.
    Duplicate {
        what: &'static str,
        name: String,
    },
    /// A pass reads a texture that no earlier step writes.
    Unwritten {
        pass: String,
        texture: String,
    },
    /// A pass writes a layer the texture does not have.
    Layer {
        pass: String,
        texture: String,
        layer: u32,
        layers: u32,
    },
    /// A texture field with a value no texture can have.
    Texture {
        texture: String,
        field: &'static str,
        message: String,
    },
    /// A generated buffer that is undeclared, malformed, or drawn before it is written.
    Buffer {
        buffer: String,
        message: String,
    },
    /// Light-sample views that do not fit together: the count, a per-sample pass writing
    /// a texture of one view, or reading one across views.
    Samples(String),
    /// A step whose entry points do not fit what it draws or dispatches.
    Step {
        pass: String,
        message: String,
    },
    /// Scene facts (`specialised`) no scene can have.
    Facts(String),
}

impl fmt::Display for GraphError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            GraphError::Syntax { message, line, column } => write!(f, "{line}:{column}: not a valid pass graph: {message}"),
            GraphError::Version { found, expected } => write!(
                f,
                "pass graph schema version {found}, but this runtime reads version {expected}; recompile the technique with a matching sshc"
            ),
            GraphError::Path { pass, path } => write!(
                f,
                "pass `{pass}` names shader `{path}`, which is not a plain file name inside the graph's folder"
            ),
            GraphError::Reference { pass, name } => write!(f, "pass `{pass}` refers to texture `{name}`, which the graph does not declare"),
            GraphError::Param { param, message } => write!(f, "param `{param}`: {message}"),
            GraphError::Facts(message) => write!(f, "the scene facts the graph was specialised for: {message}"),
            GraphError::Duplicate { what, name } => {
                // "two passes", "two textures", "two params"
                let plural = if what.ends_with('s') { "es" } else { "s" };
                write!(f, "two {what}{plural} are named `{name}`")
            }
            GraphError::Unwritten { pass, texture } => {
                write!(f, "pass `{pass}` reads texture `{texture}`, which no earlier step writes")
            }
            GraphError::Layer {
                pass,
                texture,
                layer,
                layers,
            } => write!(
                f,
                "pass `{pass}` writes layer {layer} of texture `{texture}`, which has {layers} layer(s)"
            ),
            GraphError::Texture { texture, field, message } => write!(f, "texture `{texture}`, field `{field}`: {message}"),
            GraphError::Buffer { buffer, message } => write!(f, "buffer `{buffer}`: {message}"),
            GraphError::Samples(message) => write!(f, "light samples: {message}"),
            GraphError::Step { pass, message } => write!(f, "pass `{pass}`: {message}"),
        }
    }
}

impl std::error::Error for GraphError {}

impl PassGraph {
    /// The `Params` uniform with every runtime param at its default value (`params_size`
    /// bytes, each param at its offset, padding zero): what an executor binds first.
    pub fn default_params(&self) -> Vec<u8> {
        let mut bytes = vec![0u8; self.params_size as usize];
        for p in &self.params {
            if let Some(off) = p.offset {
                let o = off as usize;
                if o + 4 <= bytes.len() {
                    bytes[o..o + 4].copy_from_slice(&p.ty.bytes(p.value));
                }
            }
        }
        bytes
    }

    /// Serialise as pretty RON.
    pub fn to_ron(&self) -> String {
        let config = ron::ser::PrettyConfig::new().depth_limit(8).indentor("  ".to_string());
        ron::ser::to_string_pretty(self, config).unwrap_or_else(|e| format!("// serialisation failed: {e}"))
    }

    /// Parse and check a graph: schema version, shader paths that stay inside the graph's
    /// folder, and texture names that resolve. Shader validation and device limits are
    /// checked by the executor when it loads the modules.
    pub fn from_ron(text: &str) -> Result<PassGraph, GraphError> {
        // Read the version first, so that an old graph gets the version error, not a schema one.
        #[derive(Deserialize)]
        struct Versioned {
            version: u32,
        }
        let syntax = |e: ron::error::SpannedError| GraphError::Syntax {
            message: e.code.to_string(),
            line: e.span.start.line,
            column: e.span.start.col,
        };
        if let Ok(v) = ron::from_str::<ron::Value>(text)
            && let Ok(v) = v.into_rust::<Versioned>()
            && v.version != SCHEMA_VERSION
        {
            return Err(GraphError::Version {
                found: v.version,
                expected: SCHEMA_VERSION,
            });
        }
        let g: PassGraph = ron::from_str(text).map_err(syntax)?;
        if g.version != SCHEMA_VERSION {
            return Err(GraphError::Version {
                found: g.version,
                expected: SCHEMA_VERSION,
            });
        }
        g.check_params()?;
        check_unique("texture", g.textures.iter().map(|t| &t.name))?;
        check_unique("pass", g.passes.iter().map(|p| &p.name))?;
        check_unique("param", g.params.iter().map(|p| &p.name))?;
        check_unique("buffer", g.buffers.iter().map(|b| &b.name))?;
        g.check_buffers()?;
        if g.samples == 0 || g.samples > MAX_LIGHT_SAMPLES {
            return Err(GraphError::Samples(format!(
                "samples {} is outside 1..={MAX_LIGHT_SAMPLES}",
                g.samples
            )));
        }
        for t in &g.textures {
            if t.views != 1 && t.views != g.samples {
                return Err(GraphError::Texture {
                    texture: t.name.clone(),
                    field: "views",
                    message: format!("{} views; a texture holds 1 or the graph's {} samples", t.views, g.samples),
                });
            }
            if t.layers == 0 {
                return Err(GraphError::Texture {
                    texture: t.name.clone(),
                    field: "layers",
                    message: "0 layers; a texture has at least 1".into(),
                });
            }
            // The channel table describes the storage (decoding, dumps): finite numbers,
            // places inside the texture.
            for c in &t.channels {
                let bad = |field: &'static str, message: String| GraphError::Texture {
                    texture: t.name.clone(),
                    field,
                    message: format!("channel `{}`: {message}", c.name),
                };
                if !(c.bias.is_finite() && c.scale.is_finite() && c.scale != 0.0) {
                    return Err(bad(
                        "channels",
                        format!("bias {} and scale {} must be finite, the scale non-zero", c.bias, c.scale),
                    ));
                }
                if !(c.range.0.is_finite() && c.range.1.is_finite() && c.range.0 <= c.range.1) {
                    return Err(bad(
                        "channels",
                        format!("range ({}, {}) must be finite and ordered", c.range.0, c.range.1),
                    ));
                }
                if c.layer >= t.layers || c.component > 3 {
                    return Err(bad(
                        "channels",
                        format!(
                            "layer {} component {} lies outside the texture's {} layer(s) of 4 components",
                            c.layer, c.component, t.layers
                        ),
                    ));
                }
            }
        }
        for p in &g.passes {
            if !is_plain_file_name(&p.shader) {
                return Err(GraphError::Path {
                    pass: p.name.clone(),
                    path: p.shader.clone(),
                });
            }
            let per_sample = p.views == Views::PerLightSample;
            for s in &p.steps {
                for w in &s.writes {
                    let views = g.texture(&w.texture).map_or(1, |t| t.views);
                    if per_sample && views != g.samples || !per_sample && views != 1 {
                        return Err(GraphError::Samples(format!(
                            "pass `{}` ({:?}) writes texture `{}` of {views} view(s)",
                            p.name, p.views, w.texture
                        )));
                    }
                }
                if matches!(s.draw, Draw::Discontinuities { .. }) && !per_sample {
                    return Err(GraphError::Samples(format!(
                        "pass `{}` finds discontinuities between sample views, but renders the light's centre only",
                        p.name
                    )));
                }
                let names = s.reads.iter().map(|b| &b.texture).chain(s.writes.iter().map(|t| &t.texture));
                for n in names {
                    if !g.textures.iter().any(|t| &t.name == n) {
                        return Err(GraphError::Reference {
                            pass: p.name.clone(),
                            name: n.clone(),
                        });
                    }
                }
            }
        }
        g.check_order()?;
        if let Some(f) = g.specialised.as_ref().and_then(|s| s.depth_floor)
            && !(0.0..=1.0).contains(&f)
        {
            return Err(GraphError::Facts(format!("`depth_floor` {f} is not a normalised depth in [0, 1]")));
        }
        Ok(g)
    }

    /// Every param value and range finite, and every value within its range.
    fn check_params(&self) -> Result<(), GraphError> {
        for p in &self.params {
            let bad = |message: String| {
                Err(GraphError::Param {
                    param: p.name.clone(),
                    message,
                })
            };
            if !p.value.is_finite() {
                return bad(format!("value {} is not a finite number", p.value));
            }
            if let Some((lo, hi)) = p.range {
                if !lo.is_finite() || !hi.is_finite() || lo > hi {
                    return bad(format!("range [{lo}, {hi}] is not a finite interval"));
                }
                if !(lo..=hi).contains(&p.value) {
                    return bad(format!("value {} lies outside its range [{lo}, {hi}]", p.value));
                }
            }
        }
        Ok(())
    }

    /// Every texture a step reads is written by an earlier step (of an earlier pass, or
    /// earlier in the same pass; a mip chain's step reads the levels of the texture it
    /// writes), and every written layer lies within its texture.
    fn check_order(&self) -> Result<(), GraphError> {
        let mut written: Vec<&str> = Vec::new();
        for p in &self.passes {
            for s in &p.steps {
                // a dispatch names a compute entry and nothing else; a draw a vertex and a
                // fragment entry and no compute entry
                let dispatch = s.draw.is_dispatch();
                let fits = if dispatch {
                    s.compute.is_some() && s.vertex.is_none() && s.fragment.is_none()
                } else {
                    s.compute.is_none() && s.vertex.is_some() && s.fragment.is_some()
                };
                if !fits {
                    return Err(GraphError::Step {
                        pass: p.name.clone(),
                        message: format!(
                            "a {:?} step needs {}",
                            s.draw,
                            if dispatch {
                                "a compute entry point and no vertex or fragment entry"
                            } else {
                                "vertex and fragment entry points and no compute entry"
                            }
                        ),
                    });
                }
                // a deferred Shade: the G-buffer, then the pixels that read it
                if s.draw.is_deferred_shade() && p.kind != PassKind::Shade {
                    return Err(GraphError::Step {
                        pass: p.name.clone(),
                        message: format!("a {:?} step belongs to a Shade pass, not a {:?} pass", s.draw, p.kind),
                    });
                }
                if s.draw == Draw::ComputePixels
                    && !p
                        .steps
                        .iter()
                        .take_while(|t| !std::ptr::eq(*t, s))
                        .any(|t| t.draw == Draw::CameraGBuffer)
                {
                    return Err(GraphError::Step {
                        pass: p.name.clone(),
                        message: "a ComputePixels step reads the G-buffer, which no earlier CameraGBuffer step of its pass writes".into(),
                    });
                }
                for b in &s.reads {
                    let same_step = b.view == View::PreviousLevel && s.writes.iter().any(|w| w.texture == b.texture);
                    if !same_step && !written.contains(&b.texture.as_str()) {
                        return Err(GraphError::Unwritten {
                            pass: p.name.clone(),
                            texture: b.texture.clone(),
                        });
                    }
                }
                for w in &s.writes {
                    if s.draw.stores_textures()
                        && let Some(t) = self.texture(&w.texture)
                        && !t.format.storable()
                    {
                        return Err(GraphError::Texture {
                            texture: w.texture.clone(),
                            field: "format",
                            message: format!(
                                "pass `{}` writes it from a compute step, but {:?} is not a storage format",
                                p.name, t.format
                            ),
                        });
                    }
                    let layers = self.texture(&w.texture).map_or(0, |t| t.layers);
                    if w.layer >= layers {
                        return Err(GraphError::Layer {
                            pass: p.name.clone(),
                            texture: w.texture.clone(),
                            layer: w.layer,
                            layers,
                        });
                    }
                    written.push(&w.texture);
                }
            }
        }
        Ok(())
    }

    pub fn texture(&self, name: &str) -> Option<&TextureDecl> {
        self.textures.iter().find(|t| t.name == name)
    }

    pub fn buffer(&self, name: &str) -> Option<&BufferDecl> {
        self.buffers.iter().find(|b| b.name == name)
    }

    /// Every generated buffer well formed, every step naming a declared one, and drawn
    /// only after a `Silhouettes` step wrote it.
    fn check_buffers(&self) -> Result<(), GraphError> {
        for b in &self.buffers {
            let bad = |message: String| {
                Err(GraphError::Buffer {
                    buffer: b.name.clone(),
                    message,
                })
            };
            if b.record_bytes == 0 || b.record_bytes % 16 != 0 || b.record_bytes > MAX_RECORD_BYTES {
                return bad(format!(
                    "record_bytes {} is not a multiple of 16 in 16..={MAX_RECORD_BYTES}",
                    b.record_bytes
                ));
            }
            if b.vertices_per_record == 0 || b.vertices_per_record > MAX_VERTICES_PER_RECORD {
                return bad(format!(
                    "vertices_per_record {} is outside 1..={MAX_VERTICES_PER_RECORD}",
                    b.vertices_per_record
                ));
            }
        }
        let mut written: Vec<&str> = Vec::new();
        for p in &self.passes {
            for s in &p.steps {
                let (name, writes) = match &s.draw {
                    Draw::Silhouettes { buffer } | Draw::Discontinuities { buffer, .. } => (buffer, true),
                    Draw::Primitives { buffer, .. } => (buffer, false),
                    Draw::SceneFromLight
                    | Draw::SceneFromCamera
                    | Draw::CameraGBuffer
                    | Draw::FullScreen
                    | Draw::MipLevels
                    | Draw::ComputeRows
                    | Draw::ComputeColumns
                    | Draw::ComputeTexels
                    | Draw::ComputePixels
                    | Draw::ComputeMipLevels => continue,
                };
                let bad = |message: String| {
                    Err(GraphError::Buffer {
                        buffer: name.clone(),
                        message,
                    })
                };
                if self.buffer(name).is_none() {
                    return bad(format!("pass `{}` names it, but the graph does not declare it", p.name));
                }
                if writes {
                    written.push(name);
                } else if !written.contains(&name.as_str()) {
                    return bad(format!("pass `{}` draws it, but no earlier Silhouettes step writes it", p.name));
                }
            }
        }
        Ok(())
    }
}

fn check_unique<'a>(what: &'static str, names: impl Iterator<Item = &'a String>) -> Result<(), GraphError> {
    let mut seen = std::collections::HashSet::new();
    for n in names {
        if !seen.insert(n.as_str()) {
            return Err(GraphError::Duplicate { what, name: n.clone() });
        }
    }
    Ok(())
}

/// A file name with no directory part, no `..`, not absolute.
pub fn is_plain_file_name(p: &str) -> bool {
    !p.is_empty() && !p.contains(['/', '\\', ':']) && p != "." && p != ".." && !p.starts_with('.')
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tiny() -> PassGraph {
        PassGraph {
            version: SCHEMA_VERSION,
            technique: "t".into(),
            title: None,
            paper: None,
            lights: vec![LightModel::Any],
            params: vec![],
            params_size: 0,
            textures: vec![TextureDecl {
                name: "z".into(),
                format: Format::R32Float,
                layers: 1,
                extent: Extent::ShadowMap,
                mips: false,
                transient: false,
                channels: vec![],
                views: 1,
            }],
            samples: 1,
            buffers: vec![],
            passes: vec![PassDecl {
                name: "depth".into(),
                kind: PassKind::Depth,
                views: Views::LightCenter,
                shader: "t.depth.wgsl".into(),
                steps: vec![Step {
                    vertex: Some("vs".into()),
                    fragment: Some("fs".into()),
                    compute: None,
                    draw: Draw::SceneFromLight,
                    reads: vec![],
                    writes: vec![Target {
                        texture: "z".into(),
                        layer: 0,
                    }],
                    params: false,
                    sampler: false,
                    light_samples: false,
                    cost: OpCount::default(),
                }],
            }],
            removed: vec![],
            specialised: None,
        }
    }

    #[test]
    fn light_kinds_round_trip() {
        for (i, k) in LightKind::ALL.into_iter().enumerate() {
            assert_eq!(k as usize, i);
            assert_eq!(LightKind::from_name(k.name()), Some(k));
            let m = LightModel::of(k, 4);
            assert_eq!(m.kind(), Some(k));
            assert!(m.accepts(k) && LightModel::Any.accepts(k));
            // the model's serialised name is the kind's
            assert!(ron::to_string(&m).unwrap().starts_with(k.name()));
        }
        assert_eq!(LightKind::Triangle as usize + 1, LightKind::ALL.len());
        assert_eq!(LightModel::Any.kind(), None);
    }

    #[test]
    fn refuses_channel_tables_that_do_not_describe_the_storage() {
        let channel = |bias: f64, scale: f64, range: (f64, f64), layer: u32, component: u32| ChannelDecl {
            name: "z".into(),
            layer,
            component,
            bias,
            scale,
            range,
        };
        let ok = channel(0.0, 1.0, (0.0, 1.0), 0, 0);
        let mut g = tiny();
        g.textures[0].channels = vec![ok.clone()];
        assert!(PassGraph::from_ron(&g.to_ron()).is_ok());
        for bad in [
            channel(f64::NAN, 1.0, (0.0, 1.0), 0, 0),
            channel(0.0, f64::INFINITY, (0.0, 1.0), 0, 0),
            channel(0.0, 0.0, (0.0, 1.0), 0, 0),
            channel(0.0, 1.0, (f64::NAN, 1.0), 0, 0),
            channel(0.0, 1.0, (1.0, 0.0), 0, 0),
            channel(0.0, 1.0, (0.0, 1.0), 1, 0),
            channel(0.0, 1.0, (0.0, 1.0), 0, 4),
        ] {
            let mut g = tiny();
            g.textures[0].channels = vec![bad.clone()];
            let e = PassGraph::from_ron(&g.to_ron()).expect_err("refused");
            assert!(
                matches!(&e, GraphError::Texture { field: "channels", message, .. } if message.starts_with("channel `z`")),
                "{bad:?}: {e:?}"
            );
        }
    }

    #[test]
    fn steps_name_the_entry_points_their_draw_needs() {
        let mut g = tiny();
        g.passes[0].steps[0].compute = Some("cs".into());
        let e = PassGraph::from_ron(&g.to_ron()).expect_err("a draw with a compute entry");
        assert!(
            matches!(&e, GraphError::Step { message, .. } if message.contains("no compute entry")),
            "{e}"
        );
        let mut g = tiny();
        g.passes[0].steps[0].draw = Draw::ComputeTexels;
        let e = PassGraph::from_ron(&g.to_ron()).expect_err("a dispatch with raster entries");
        assert!(
            matches!(&e, GraphError::Step { message, .. } if message.contains("needs a compute entry point")),
            "{e}"
        );
    }

    /// A deferred Shade: a `CameraGBuffer` step, then a `ComputePixels` step reading it, in
    /// a Shade pass only.
    #[test]
    fn a_deferred_shade_draws_its_g_buffer_before_reading_it() {
        let shade = |draws: &[Draw]| {
            let mut g = tiny();
            let step = g.passes[0].steps[0].clone();
            g.passes.push(PassDecl {
                name: "shade".into(),
                kind: PassKind::Shade,
                views: Views::LightCenter,
                shader: "t.shade.wgsl".into(),
                steps: draws
                    .iter()
                    .map(|d| {
                        let mut s = step.clone();
                        s.writes.clear();
                        s.draw = d.clone();
                        if d.is_dispatch() {
                            (s.vertex, s.fragment, s.compute) = (None, None, Some("cs_shade".into()));
                        }
                        s
                    })
                    .collect(),
            });
            g
        };
        let ok = shade(&[Draw::CameraGBuffer, Draw::ComputePixels]);
        assert_eq!(PassGraph::from_ron(&ok.to_ron()).map(|g| g.passes.len()), Ok(2));
        let e = PassGraph::from_ron(&shade(&[Draw::ComputePixels]).to_ron()).expect_err("no G-buffer drawn");
        assert!(
            matches!(&e, GraphError::Step { message, .. } if message.contains("no earlier CameraGBuffer step")),
            "{e}"
        );
        let e = PassGraph::from_ron(&shade(&[Draw::ComputePixels, Draw::CameraGBuffer]).to_ron()).expect_err("read before drawn");
        assert!(
            matches!(&e, GraphError::Step { message, .. } if message.contains("no earlier CameraGBuffer step")),
            "{e}"
        );
        let mut g = ok.clone();
        g.passes[1].kind = PassKind::Map;
        let e = PassGraph::from_ron(&g.to_ron()).expect_err("a G-buffer in a Map pass");
        assert!(
            matches!(&e, GraphError::Step { message, .. } if message.contains("belongs to a Shade pass")),
            "{e}"
        );
    }

    #[test]
    fn compute_steps_store_only_into_storage_formats() {
        let with = |format: Format| {
            let mut g = tiny();
            g.textures[0].format = format;
            let s = &mut g.passes[0].steps[0];
            (s.vertex, s.fragment, s.compute, s.draw) = (None, None, Some("cs".into()), Draw::ComputeTexels);
            PassGraph::from_ron(&g.to_ron())
        };
        for f in [
            Format::R32Float,
            Format::Rg32Float,
            Format::Rgba32Float,
            Format::Rgba16Float,
            Format::Rgba8Unorm,
        ] {
            assert!(f.storable() && with(f).is_ok(), "{f:?}");
        }
        for f in [
            Format::R8Unorm,
            Format::Rg8Unorm,
            Format::R16Float,
            Format::Rg16Float,
            Format::R16Unorm,
            Format::Rgba16Unorm,
        ] {
            let e = with(f).expect_err("refused");
            assert!(
                matches!(&e, GraphError::Texture { field: "format", message, .. } if message.contains("not a storage format")),
                "{f:?}: {e:?}"
            );
        }
    }

    #[test]
    fn round_trip() {
        let g = tiny();
        assert_eq!(PassGraph::from_ron(&g.to_ron()).unwrap(), g);
    }

    #[test]
    fn refuses_wrong_version_paths_and_names() {
        let mut g = tiny();
        g.version = 99;
        assert_eq!(
            PassGraph::from_ron(&g.to_ron()),
            Err(GraphError::Version {
                found: 99,
                expected: SCHEMA_VERSION
            })
        );
        let mut g = tiny();
        g.passes[0].shader = "../evil.wgsl".into();
        assert!(matches!(PassGraph::from_ron(&g.to_ron()), Err(GraphError::Path { .. })));
        let mut g = tiny();
        g.passes[0].steps[0].writes[0].texture = "nope".into();
        assert!(matches!(PassGraph::from_ron(&g.to_ron()), Err(GraphError::Reference { .. })));
        assert!(matches!(
            PassGraph::from_ron("PassGraph(version: 1"),
            Err(GraphError::Syntax { .. })
        ));
    }

    /// `tiny` plus a param and a Shade pass reading the depth: a valid graph as RON text.
    fn valid_text() -> String {
        let mut g = tiny();
        g.params.push(ParamDecl {
            name: "bias".into(),
            ty: ParamType::F32,
            value: 0.5,
            range: Some((0.0, 1.0)),
            offset: None,
            doc: None,
        });
        let mut shade = g.passes[0].clone();
        shade.name = "shade".into();
        shade.kind = PassKind::Shade;
        shade.steps[0].writes.clear();
        shade.steps[0].reads.push(Binding {
            binding: 0,
            texture: "z".into(),
            view: View::All,
        });
        g.passes.push(shade);
        let text = g.to_ron();
        assert_eq!(PassGraph::from_ron(&text).unwrap(), g);
        text
    }

    /// `valid_text` with the one occurrence of `from` replaced.
    fn changed(from: &str, to: &str) -> Result<PassGraph, GraphError> {
        let text = valid_text();
        assert_eq!(text.matches(from).count(), 1, "`{from}` in {text}");
        PassGraph::from_ron(&text.replacen(from, to, 1))
    }

    #[test]
    fn refuses_unknown_fields() {
        let e = changed("params_size: 0,", "params_size: 0, extra: 1,").unwrap_err();
        assert!(matches!(e, GraphError::Syntax { .. }) && e.to_string().contains("extra"), "{e}");
        let e = changed("mips: false,", "mips: false, sparse: true,").unwrap_err();
        assert!(e.to_string().contains("sparse"), "{e}");
    }

    #[test]
    fn refuses_nan_param() {
        let e = changed("value: 0.5,", "value: NaN,").unwrap_err();
        assert!(matches!(&e, GraphError::Param { param, .. } if param == "bias"), "{e}");
        assert!(e.to_string().contains("`bias`") && e.to_string().contains("finite"), "{e}");
    }

    #[test]
    fn refuses_infinite_param() {
        let e = changed("value: 0.5,", "value: inf,").unwrap_err();
        assert!(matches!(&e, GraphError::Param { param, .. } if param == "bias"), "{e}");
    }

    #[test]
    fn refuses_param_outside_its_range() {
        let e = changed("value: 0.5,", "value: 1.5,").unwrap_err();
        assert!(e.to_string().contains("outside its range"), "{e}");
        let e = changed("range: Some((0.0, 1.0)),", "range: Some((0.0, inf)),").unwrap_err();
        assert!(matches!(&e, GraphError::Param { param, .. } if param == "bias"), "{e}");
    }

    #[test]
    fn scene_facts_round_trip_and_a_depth_floor_outside_0_1_is_refused() {
        let mut g = tiny();
        let facts = |depth_floor| SceneFacts {
            scene: "scenes/contact.ron".into(),
            light: LightKind::Sphere,
            depth_floor,
        };
        g.specialised = Some(facts(Some(0.25)));
        assert_eq!(PassGraph::from_ron(&g.to_ron()).unwrap().specialised, Some(facts(Some(0.25))));
        // absent: the facts of graphs from before the field
        g.specialised = Some(facts(None));
        assert!(!g.to_ron().contains("depth_floor"));
        assert_eq!(PassGraph::from_ron(&g.to_ron()).unwrap().specialised, Some(facts(None)));
        for bad in [-0.5, 1.5, f32::NAN, f32::INFINITY] {
            g.specialised = Some(facts(Some(bad)));
            let e = PassGraph::from_ron(&g.to_ron()).unwrap_err();
            assert!(
                matches!(e, GraphError::Facts(_)) && e.to_string().contains("depth_floor"),
                "{bad}: {e}"
            );
        }
    }

    /// The casters' least depth: vertices in front of the near plane clamp to 0, the
    /// non-casting ones are skipped, no caster gives none.
    #[test]
    fn caster_depth_floor_takes_the_least_normalised_depth_of_the_casters() {
        // identity view: view-space z is the world z; depth = (-z - near) / (far - near)
        let mut view = [0.0f32; 16];
        for i in 0..4 {
            view[5 * i] = 1.0;
        }
        let vertex = |z: f32| [0.0, 0.0, z, 0.0, 1.0, 0.0];
        let vertices: Vec<f32> = [-3.0, -5.0, -2.0, -1.5].iter().flat_map(|&z| vertex(z)).collect();
        // near 1, far 5: depths 0.5, 1.0, 0.25, 0.125
        assert_eq!(caster_depth_floor(&vertices, Some(3), &view, 1.0, 5.0), Some(0.25));
        assert_eq!(caster_depth_floor(&vertices, None, &view, 1.0, 5.0), Some(0.125));
        assert_eq!(caster_depth_floor(&vertices, None, &view, 2.0, 5.0), Some(0.0));
        assert_eq!(caster_depth_floor(&vertices, Some(0), &view, 1.0, 5.0), None);
        assert_eq!(caster_depth_floor(&vertices, None, &view, 5.0, 5.0), None);
    }

    #[test]
    fn refuses_duplicate_texture_names() {
        let mut g = tiny();
        g.textures.push(g.textures[0].clone());
        let e = PassGraph::from_ron(&g.to_ron()).unwrap_err();
        assert_eq!(
            e,
            GraphError::Duplicate {
                what: "texture",
                name: "z".into()
            }
        );
    }

    #[test]
    fn refuses_duplicate_pass_names() {
        let e = changed("name: \"shade\",", "name: \"depth\",").unwrap_err();
        assert_eq!(
            e,
            GraphError::Duplicate {
                what: "pass",
                name: "depth".into()
            }
        );
        assert_eq!(e.to_string(), "two passes are named `depth`");
    }

    #[test]
    fn refuses_duplicate_param_names() {
        let mut g = tiny();
        let p = ParamDecl {
            name: "k".into(),
            ty: ParamType::I32,
            value: 1.0,
            range: None,
            offset: None,
            doc: None,
        };
        g.params = vec![p.clone(), p];
        let e = PassGraph::from_ron(&g.to_ron()).unwrap_err();
        assert_eq!(
            e,
            GraphError::Duplicate {
                what: "param",
                name: "k".into()
            }
        );
    }

    #[test]
    fn refuses_reading_an_unwritten_texture() {
        // The depth pass no longer writes `z`, which the shade pass reads.
        let mut g = tiny();
        g.textures.push(TextureDecl {
            name: "other".into(),
            ..g.textures[0].clone()
        });
        let text = valid_text().replacen("texture: \"z\",\n", "texture: \"other\",\n", 1);
        let e = PassGraph::from_ron(&text.replacen(
            "textures: [",
            &format!("textures: [{},", ron::to_string(&g.textures[1]).unwrap()),
            1,
        ))
        .unwrap_err();
        assert_eq!(
            e,
            GraphError::Unwritten {
                pass: "shade".into(),
                texture: "z".into()
            }
        );
        assert!(e.to_string().contains("pass `shade` reads texture `z`"), "{e}");
    }

    #[test]
    fn refuses_a_target_layer_outside_the_texture() {
        let e = changed("layer: 0,", "layer: 99,").unwrap_err();
        assert_eq!(
            e,
            GraphError::Layer {
                pass: "depth".into(),
                texture: "z".into(),
                layer: 99,
                layers: 1
            }
        );
        assert!(e.to_string().contains("pass `depth` writes layer 99"), "{e}");
    }

    #[test]
    fn refuses_zero_layers() {
        let e = changed("layers: 1,", "layers: 0,").unwrap_err();
        assert!(
            matches!(&e, GraphError::Texture { texture, field: "layers", .. } if texture == "z"),
            "{e}"
        );
        assert!(e.to_string().contains("texture `z`, field `layers`"), "{e}");
    }
}
