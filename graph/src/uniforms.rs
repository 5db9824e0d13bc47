//! The structs the GPU and the host share, each one field list from which come the WGSL
//! declaration, the layout and the Rust struct: the uniforms every generated module
//! declares (`Frame`, `LightSamples`), the scene's edges as the Geometry passes and the
//! placement step read them (`Edge`), one instance's placement record (`Placement`) and the
//! cascades' slices (`Slices`). Each is checked against naga's layout (runtime/src/frame.rs).

/// The type of one field of a shared struct: its WGSL spelling, size and alignment (WGSL's
/// layout rules, the same in the uniform and the storage address space for these types),
/// and the Rust value that holds it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameType {
    /// `mat4x4<f32>`, column-major: `[f32; 16]`.
    Mat4,
    /// `vec4<f32>`: `[f32; 4]`.
    Vec4,
    /// `vec3<f32>`: `[f32; 3]` (16-aligned, 12 bytes: a 4-byte field may follow in its last word).
    Vec3,
    /// `vec4<u32>`: `[u32; 4]`.
    UVec4,
    /// `vec2<u32>`: `[u32; 2]`.
    UVec2,
    /// `u32`.
    U32,
}

impl FrameType {
    pub const fn wgsl(self) -> &'static str {
        match self {
            FrameType::Mat4 => "mat4x4<f32>",
            FrameType::Vec4 => "vec4<f32>",
            FrameType::Vec3 => "vec3<f32>",
            FrameType::UVec4 => "vec4<u32>",
            FrameType::UVec2 => "vec2<u32>",
            FrameType::U32 => "u32",
        }
    }

    /// Bytes.
    pub const fn size(self) -> u32 {
        match self {
            FrameType::Mat4 => 64,
            FrameType::Vec4 | FrameType::UVec4 => 16,
            FrameType::Vec3 => 12,
            FrameType::UVec2 => 8,
            FrameType::U32 => 4,
        }
    }

    /// Alignment in bytes.
    pub const fn align(self) -> u32 {
        match self {
            FrameType::Mat4 | FrameType::Vec4 | FrameType::Vec3 | FrameType::UVec4 => 16,
            FrameType::UVec2 => 8,
            FrameType::U32 => 4,
        }
    }
}

/// A field's value written little-endian at the start of a byte slice (the shared structs'
/// `to_array`).
pub trait LeBytes {
    fn put(&self, out: &mut [u8]);
}

impl LeBytes for f32 {
    fn put(&self, out: &mut [u8]) {
        out[..4].copy_from_slice(&self.to_le_bytes());
    }
}

impl LeBytes for u32 {
    fn put(&self, out: &mut [u8]) {
        out[..4].copy_from_slice(&self.to_le_bytes());
    }
}

impl<T: LeBytes, const N: usize> LeBytes for [T; N] {
    fn put(&self, out: &mut [u8]) {
        for (k, x) in self.iter().enumerate() {
            x.put(&mut out[4 * k..]);
        }
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

/// Bytes of a struct of `fields`: its last field's end, rounded up to the struct's
/// alignment (its fields' largest), which an array of it strides by.
pub const fn struct_size(fields: &[FrameField]) -> u32 {
    let last = fields.len() - 1;
    let mut align = 4;
    let mut k = 0;
    while k < fields.len() {
        if fields[k].ty.align() > align {
            align = fields[k].ty.align();
        }
        k += 1;
    }
    round_up(field_offset(fields, last) + fields[last].ty.size(), align)
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
    (wgsl Vec3) => {
        "vec3<f32>"
    };
    (wgsl UVec4) => {
        "vec4<u32>"
    };
    (wgsl UVec2) => {
        "vec2<u32>"
    };
    (wgsl U32) => {
        "u32"
    };
    (rust Mat4) => {
        [f32; 16]
    };
    (rust Vec4) => {
        [f32; 4]
    };
    (rust Vec3) => {
        [f32; 3]
    };
    (rust UVec4) => {
        [u32; 4]
    };
    (rust UVec2) => {
        [u32; 2]
    };
    (rust U32) => {
        u32
    };
}

/// The one definition of a struct the GPU and the host share: from the field list come its
/// WGSL declaration (each field's doc lines become `//` comments; `then` is appended), its
/// field table with offsets and size ([`field_offset`], [`struct_size`]), and the
/// `#[repr(C)]` Rust struct whose `to_bytes` writes each field at its offset. Every struct
/// of this module is made by it; the layout tests against naga's layouter are in
/// runtime/src/frame.rs.
macro_rules! uniform_struct {
    (
        $(#[doc = $sdoc:literal])+
        struct $wgsl_name:literal => $rust:ident;
        wgsl: $wgsl:ident, then: $then:literal;
        fields: $fields:ident, size: $size:ident;
        $( $(#[doc = $doc:literal])* $name:ident: $ty:ident, )+
    ) => {
        /// The WGSL declaration of the struct (and what follows it).
        pub const $wgsl: &str = concat!(
            "struct ", $wgsl_name, " {\n",
            $( $("    //", $doc, "\n",)* "    ", stringify!($name), ": ", frame_type!(wgsl $ty), ",\n", )+
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
            $( $(#[doc = $doc])* pub $name: frame_type!(rust $ty), )+
        }

        impl $rust {
            /// The struct's bytes (little-endian), its size of them, each field at its
            /// [`field_offset`].
            pub fn to_bytes(&self) -> Vec<u8> {
                self.to_array().to_vec()
            }

            /// [`Self::to_bytes`] on the stack (the per-frame path allocates nothing).
            pub fn to_array(&self) -> [u8; $size as usize] {
                let mut out = [0u8; $size as usize];
                let values: [&dyn LeBytes; $fields.len()] = [$(&self.$name,)+];
                for (i, v) in values.iter().enumerate() {
                    v.put(&mut out[field_offset($fields, i) as usize..]);
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

/// The most light samples a pass graph may render views of ([`crate::PassGraph::samples`]).
pub const MAX_LIGHT_SAMPLES: u32 = 16;

uniform_struct! {
    /// One light sample's view, as the `LightSamples` uniform holds it (matrices
    /// column-major). `LIGHT_SAMPLES_WGSL` declares it and the uniform at
    /// `@group(0) @binding(3)` of steps with [`crate::Step::light_samples`]: one per light sample,
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
        Self::light_samples_array(views).to_vec()
    }

    /// [`Self::light_samples_bytes`] on the stack (the per-frame path allocates nothing).
    pub fn light_samples_array(views: &[SampleViewUniform]) -> [u8; LIGHT_SAMPLES_SIZE as usize] {
        let mut out = [0u8; LIGHT_SAMPLES_SIZE as usize];
        for (k, chunk) in out.chunks_exact_mut(SAMPLE_VIEW_SIZE as usize).enumerate() {
            chunk.copy_from_slice(&views.get(k).copied().unwrap_or_default().to_array());
        }
        out
    }
}

uniform_struct! {
    /// One edge of the scene's adjacency as the GPU reads it (an element of a storage
    /// array, 48 bytes): its two welded end points `a` and `b`; `first_face`, the first of
    /// its face references, and `face_count`, how many (1: an open boundary, 2: manifold,
    /// more: non-manifold); `ia` and `ib`, its end points' indices among the scene's welded
    /// vertices (so that something drawn once per silhouette vertex, such as a penumbra
    /// map's cone, is claimed by exactly one of its edges). The runtime's adjacency builds
    /// them, its placement step moves them into world space, and the Geometry passes'
    /// silhouette library (the compiler's `silhouettes.wgsl`) reads them.
    struct "Edge" => GpuEdge;
    wgsl: EDGE_WGSL, then: "";
    fields: EDGE_FIELDS, size: EDGE_SIZE;
    a: Vec3,
    first_face: U32,
    b: Vec3,
    face_count: U32,
    /// the end points' indices among the scene's welded vertices
    ia: U32,
    ib: U32,
    pad: UVec2,
}

uniform_struct! {
    /// One instance's placement, the uniform the runtime's placement step reads at a
    /// dynamic offset (one record per instance, each padded to 256 bytes): the instance's
    /// matrix and normal matrix (column-major), then for its mesh's vertices, edges, face
    /// planes and face references where they start, how many, and where the placed ones go.
    struct "Placement" => PlacementUniform;
    wgsl: PLACEMENT_WGSL, then: "";
    fields: PLACEMENT_FIELDS, size: PLACEMENT_SIZE;
    /// object -> world
    model: Mat4,
    /// the normal matrix (the inverse transpose of model's upper 3 x 3)
    normal: Mat4,
    /// first, count, destination; w unused
    vertices: UVec4,
    /// first, count, destination; w: the mesh's first welded vertex among the scene's
    edges: UVec4,
    /// first, count, destination; w: 1 where the matrix mirrors (the planes are negated)
    planes: UVec4,
    /// first, count, destination; w: the first placed plane
    faces: UVec4,
}

uniform_struct! {
    /// Where cascades split the camera's view, as the runtime's combining step reads it:
    /// each pixel takes the cascade whose slice of view distances holds its own, mixed with
    /// the next over the last `band` fraction of its slice.
    struct "Slices" => SlicesUniform;
    wgsl: SLICES_WGSL, then: "";
    fields: SLICES_FIELDS, size: SLICES_SIZE;
    /// xyz: the camera's position; w: the band
    eye: Vec4,
    /// xyz: the camera's unit view direction; w: the number of cascades
    forward: Vec4,
    /// the first four of the n + 1 split distances (unused ones past the last)
    lo: Vec4,
    /// x: the fifth split distance
    hi: Vec4,
}
