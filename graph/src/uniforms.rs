//! The uniforms every generated module declares (`Frame`, `LightSamples`): one field list
//! each, from which come the WGSL declaration, the layout and the Rust struct.

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
                self.to_array().to_vec()
            }

            /// [`Self::to_bytes`] on the stack (the per-frame path allocates nothing).
            pub fn to_array(&self) -> [u8; $size as usize] {
                let mut out = [0u8; $size as usize];
                let values: [&[f32]; $fields.len()] = [$(&self.$name,)+];
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
