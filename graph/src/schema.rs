//! The pass graph's types: passes, steps, draws, textures, params and their errors.

use crate::lights::{LightModel, SceneFacts};
use serde::{Deserialize, Serialize};
use std::fmt;

/// Version of this schema; a graph of another version is refused.
pub const SCHEMA_VERSION: u32 = 1;

/// Workgroup size of compute steps ([`Draw::ComputeRows`], [`Draw::ComputeColumns`]).
pub const COMPUTE_WORKGROUP: u32 = 64;
/// What a step's [`Draw`] is, as the compiler, the validator and the runtime ask it: one
/// row per draw in [`Draw::facts`], so a new draw states all of them in one place.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct DrawFacts {
    /// A compute dispatch (else a raster draw).
    dispatch: bool,
    /// Appends records to a generated buffer (a Geometry pass's classification).
    generates: bool,
    /// Part of a deferred Shade (its G-buffer raster or its compute step over pixels).
    deferred: bool,
    /// Stores into its target textures (which need a storage format).
    stores: bool,
    /// Its targets are camera-sized (else the shadow map's).
    camera: bool,
    /// Writes the levels below the base of its targets' mip chains.
    below_base: bool,
    /// Reads every texel of what it reads, once (a full-screen or compute step over the
    /// map); else only where its fragments or edges look (the camera's raster, a
    /// classification over the scene's edges, a draw of generated primitives).
    whole_reads: bool,
}

impl Draw {
    /// Every fact of every draw: one exhaustive table.
    fn facts(&self) -> DrawFacts {
        let f = |dispatch, generates, deferred, stores, camera, below_base, whole_reads| DrawFacts {
            dispatch,
            generates,
            deferred,
            stores,
            camera,
            below_base,
            whole_reads,
        };
        // the columns: dispatch, generates, deferred, stores, camera, below_base, whole_reads
        match self {
            Draw::SceneFromLight => f(false, false, false, false, false, false, true),
            Draw::SceneFromCamera => f(false, false, false, false, true, false, false),
            Draw::CameraGBuffer => f(false, false, true, false, false, false, true),
            Draw::ComputePixels => f(true, false, true, false, true, false, true),
            Draw::FullScreen => f(false, false, false, false, false, false, true),
            Draw::MipLevels => f(false, false, false, false, false, true, true),
            Draw::ComputeRows => f(true, false, false, false, false, false, true),
            Draw::ComputeColumns => f(true, false, false, false, false, false, true),
            Draw::ComputeTexels => f(true, false, false, true, false, false, true),
            Draw::ComputeMipLevels => f(true, false, false, true, false, true, true),
            Draw::Silhouettes { .. } => f(true, true, false, false, false, false, false),
            Draw::Discontinuities { .. } => f(true, true, false, false, false, false, true),
            Draw::Primitives { .. } => f(false, false, false, false, false, false, false),
        }
    }

    /// Whether the step is a compute dispatch (else a raster draw).
    pub fn is_dispatch(&self) -> bool {
        self.facts().dispatch
    }

    /// Whether the step appends records to a generated buffer (a Geometry pass's
    /// classification: silhouette edges, depth discontinuities).
    pub fn generates_records(&self) -> bool {
        self.facts().generates
    }

    /// Whether the step is part of a deferred Shade (its G-buffer raster, or the compute
    /// step over its pixels), which only a Shade pass may hold.
    /// The buffer of records the step appends to (`Silhouettes`, `Discontinuities`); `None`
    /// for every other step (a `Primitives` step draws from its buffer).
    pub fn appends_to(&self) -> Option<&str> {
        match self {
            Draw::Silhouettes { buffer } | Draw::Discontinuities { buffer, .. } => Some(buffer),
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
            | Draw::Primitives { .. } => None,
        }
    }

    /// Finds the depth discontinuities between two light-sample views (skins): the pass
    /// must render one view per sample.
    pub fn joins_sample_views(&self) -> bool {
        match self {
            Draw::Discontinuities { .. } => true,
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
            | Draw::Silhouettes { .. }
            | Draw::Primitives { .. } => false,
        }
    }

    /// The deferred Shade's compute step, which reads the G-buffer an earlier step of its
    /// pass wrote.
    pub fn reads_gbuffer(&self) -> bool {
        self.is_deferred_shade() && self.is_dispatch()
    }

    /// The deferred Shade's raster step, which writes the G-buffer.
    pub fn writes_gbuffer(&self) -> bool {
        self.is_deferred_shade() && !self.is_dispatch()
    }

    pub fn is_deferred_shade(&self) -> bool {
        self.facts().deferred
    }

    /// Whether a compute step stores into its target textures (which must then have a
    /// storage format).
    pub fn stores_textures(&self) -> bool {
        self.facts().stores
    }

    /// Whether the step's targets are camera-sized ([`Extent::Camera`]: a Shade's debug
    /// outputs, after its camera outputs); every other step's are the shadow map's.
    pub fn writes_camera_textures(&self) -> bool {
        self.facts().camera
    }

    /// Whether the step writes the levels below the base of its targets' mip chains.
    pub fn writes_levels_below_base(&self) -> bool {
        self.facts().below_base
    }

    /// Whether the step's reads are compulsory traffic, every texel of what it reads once
    /// (the cost model's traffic): a full-screen or compute step over the map; not the
    /// camera's raster, a classification over edges or a draw of generated primitives.
    pub fn reads_whole_textures(&self) -> bool {
        self.facts().whole_reads
    }
}

/// Workgroup side of [`Draw::ComputeTexels`] and [`Draw::ComputePixels`] steps (8 x 8
/// invocations).
pub const TEXEL_WORKGROUP: u32 = 8;

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
/// targets and [`Draw::ComputePixels`]'s bindings: the visibility (finite, in [0, 1]), the
/// shaded colour, the world position (w = 1 on a surface) and the normal turned to the
/// camera, whose w is 1 where the technique's visibility at a receiver facing the light
/// was not a finite number (written as 1 for NaN, clamped for an infinity), else 0.
pub const CAMERA_OUTPUTS: [Format; 4] = [Format::R32Float, Format::Rgba8Unorm, Format::Rgba32Float, Format::Rgba16Float];

/// The most debug outputs a Shade pass writes besides [`CAMERA_OUTPUTS`]: a forward Shade
/// renders them as colour attachments after the camera outputs, and WebGPU has 8.
pub const MAX_DEBUG_OUTPUTS: usize = 4;

/// The prefix of the camera-sized textures ([`Extent::Camera`]) that hold a Shade pass's
/// debug outputs: `debug_<name>`, written by its [`Draw::SceneFromCamera`] or
/// [`Draw::ComputePixels`] step and read by no pass.
pub const DEBUG_PREFIX: &str = "debug_";

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
    /// [`crate::MAX_LIGHT_SAMPLES`] (1 when there are none).
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
    /// The shadow-map size the technique names (`shadow_map:`, as `sshc tune` writes it):
    /// a host uses it where nothing else sets the size (a command's `--shadow-map`
    /// outranks it, and it outranks a scene file's). Absent for most techniques.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shadow_map: Option<u32>,
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
    /// Summed-area tables of f32 sums, stored in a storage buffer.
    SummedAreaF32,
}

/// How one component of a texel is stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Component {
    /// An unsigned 8-bit code `c`, read as `c / 255`.
    Unorm8,
    /// An unsigned 16-bit code `c`, read as `c / 65535`.
    Unorm16,
    /// An IEEE half.
    Float16,
    /// An IEEE single.
    Float32,
    /// An unsigned 32-bit integer (a fixed-point summed-area table's sums).
    Uint32,
}

impl Component {
    /// An unsigned code read as a fraction of its largest value.
    pub fn is_unorm(self) -> bool {
        match self {
            Component::Unorm8 | Component::Unorm16 => true,
            Component::Float16 | Component::Float32 | Component::Uint32 => false,
        }
    }

    pub const fn bytes(self) -> u32 {
        match self {
            Component::Unorm8 => 1,
            Component::Unorm16 | Component::Float16 => 2,
            Component::Float32 | Component::Uint32 => 4,
        }
    }
}

impl Format {
    /// Every format, in declaration order.
    pub const ALL: [Format; 14] = [
        Format::R8Unorm,
        Format::Rg8Unorm,
        Format::Rgba8Unorm,
        Format::R16Unorm,
        Format::Rg16Unorm,
        Format::Rgba16Unorm,
        Format::R16Float,
        Format::Rg16Float,
        Format::Rgba16Float,
        Format::R32Float,
        Format::Rg32Float,
        Format::Rgba32Float,
        Format::SummedAreaU32,
        Format::SummedAreaF32,
    ];

    /// The one table of the formats' layouts: how each component is stored, and how many
    /// components a texel has (a summed-area table's texel is a `vec4` of sums). Every
    /// other fact of layout ([`Format::bytes_per_texel`], [`Format::of`], the 16-bit norm
    /// and 32-bit float families, how the runtime decodes a texel) follows from it.
    pub const fn layout(self) -> (Component, u32) {
        match self {
            Format::R8Unorm => (Component::Unorm8, 1),
            Format::Rg8Unorm => (Component::Unorm8, 2),
            Format::Rgba8Unorm => (Component::Unorm8, 4),
            Format::R16Unorm => (Component::Unorm16, 1),
            Format::Rg16Unorm => (Component::Unorm16, 2),
            Format::Rgba16Unorm => (Component::Unorm16, 4),
            Format::R16Float => (Component::Float16, 1),
            Format::Rg16Float => (Component::Float16, 2),
            Format::Rgba16Float => (Component::Float16, 4),
            Format::R32Float => (Component::Float32, 1),
            Format::Rg32Float => (Component::Float32, 2),
            Format::Rgba32Float => (Component::Float32, 4),
            Format::SummedAreaU32 => (Component::Uint32, 4),
            Format::SummedAreaF32 => (Component::Float32, 4),
        }
    }

    /// The texture format (not a table) with `count` components stored as `component`;
    /// `None` where there is none (three components, a `Uint32` texture).
    pub fn of(component: Component, count: u32) -> Option<Format> {
        Format::ALL.into_iter().find(|f| !f.is_table() && f.layout() == (component, count))
    }

    pub const fn bytes_per_texel(self) -> u32 {
        let (component, count) = self.layout();
        component.bytes() * count
    }

    /// A 16-bit norm format: rendering into one is an adapter's format feature.
    pub fn is_norm16(self) -> bool {
        !self.is_table() && matches!(self.layout().0, Component::Unorm16)
    }

    /// A 32-bit float texture format: filtering and blending one are features.
    pub fn is_float32(self) -> bool {
        !self.is_table() && matches!(self.layout().0, Component::Float32)
    }

    /// A summed-area table: a storage buffer of `vec4` prefix sums, one per texel.
    pub fn is_table(self) -> bool {
        match self {
            Format::SummedAreaU32 | Format::SummedAreaF32 => true,
            Format::R8Unorm
            | Format::Rg8Unorm
            | Format::Rgba8Unorm
            | Format::R16Unorm
            | Format::Rg16Unorm
            | Format::Rgba16Unorm
            | Format::R16Float
            | Format::Rg16Float
            | Format::Rgba16Float
            | Format::R32Float
            | Format::Rg32Float
            | Format::Rgba32Float => false,
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
            Format::SummedAreaF32 => "rgba32float",
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

pub(crate) fn one() -> u32 {
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

/// What a pass is, without its data: the one pass-kind enum whose facts every phase asks
/// (the compiler's AST and IR kinds carry the data and answer `kind()` with this).
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

impl PassKind {
    /// The name a technique file writes (`Shade(...)`).
    pub fn name(self) -> &'static str {
        match self {
            PassKind::Depth => "Depth",
            PassKind::Map => "Map",
            PassKind::Filter => "Filter",
            PassKind::Mipmap => "Mipmap",
            PassKind::SummedArea => "SummedArea",
            PassKind::Geometry => "Geometry",
            PassKind::Shade => "Shade",
        }
    }

    /// The pass that evaluates visibility per camera pixel (one per technique).
    pub fn is_shade(self) -> bool {
        matches!(self, PassKind::Shade)
    }

    /// Rasterises the scene's depth from the light.
    pub fn is_depth(self) -> bool {
        matches!(self, PassKind::Depth)
    }

    /// Computes channel values per shadow-map texel from the maps it reads.
    pub fn is_map(self) -> bool {
        matches!(self, PassKind::Map)
    }

    /// Rasterises primitives generated from the scene's edges or discontinuities.
    pub fn is_geometry(self) -> bool {
        matches!(self, PassKind::Geometry)
    }

    /// Makes a mip chain of its source (lookups with a width read its levels).
    pub fn makes_mip_chain(self) -> bool {
        matches!(self, PassKind::Mipmap)
    }

    /// Makes a summed-area table of its source (box lookups read it).
    pub fn makes_table(self) -> bool {
        matches!(self, PassKind::SummedArea)
    }
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

impl PassGraph {
    /// Views `pass` runs in a frame: one per light sample ([`PassGraph::samples`]) for a
    /// `PerLightSample` pass, else one.
    pub fn views_of(&self, pass: &PassDecl) -> u32 {
        match pass.views {
            Views::PerLightSample => self.samples,
            Views::LightCenter => 1,
        }
    }
}

/// Which light views a pass that draws the scene from the light renders.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Views {
    /// One view from the light's centre.
    LightCenter,
    /// One view per light sample; the pass's textures get one layer block per view.
    PerLightSample,
}

impl Views {
    /// One view per light sample (rather than the centre's alone).
    pub fn is_per_sample(self) -> bool {
        match self {
            Views::PerLightSample => true,
            Views::LightCenter => false,
        }
    }
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

impl Resolve {
    /// The blended rules, in the order of the integer a technique's `resolve` expression
    /// gives (0 to 3).
    pub const ALL: [Resolve; 4] = [Resolve::KeepMin, Resolve::KeepMax, Resolve::Add, Resolve::Multiply];
}

/// A buffer of records generated on the GPU by a `Silhouettes` (or `Discontinuities`)
/// step: a [`GENERATED_HEADER_BYTES`] header, then the records of `record_bytes`. The
/// header is 16 bytes of draw arguments (`vertex_count`, `instance_count`,
/// `first_vertex`, `first_instance`: what `draw_indirect` reads), then `claimed` (the
/// records the step asked for), `dropped` (those past the buffer's capacity, written
/// nowhere) and two words of padding. The runtime sizes it before allocation: at most one
/// record per edge of the casting meshes, and no more than one storage binding holds; a
/// record past the capacity is counted in `dropped`, never drawn half-written, and the
/// runtime reports it (`Inspect::generated`).
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
/// Bytes of a generated buffer's header: the draw arguments, `claimed`, `dropped` and two
/// words of padding (the records, of 16-byte vectors, start 16-byte aligned).
pub const GENERATED_HEADER_BYTES: u32 = 32;

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
    /// Binds the `LightSamples` uniform ([`crate::LIGHT_SAMPLES_WGSL`]) at group 0, binding 3.
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
    /// A `shadow_map` size outside 1..=[`MAX_SHADOW_MAP`].
    ShadowMap(u32),
}

/// The largest shadow map a technique or graph may name (texels a side): wgpu guarantees
/// 8,192; the devices sshc runs on reach 16,384 at most.
pub const MAX_SHADOW_MAP: u32 = 16384;

impl fmt::Display for GraphError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            GraphError::ShadowMap(n) => write!(f, "shadow_map {n} is outside 1..={MAX_SHADOW_MAP} texels"),
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
