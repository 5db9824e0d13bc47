//! The GPU reference: hand-written WGSL compute shaders (`shaders/*.wgsl`) run on wgpu.
//!
//! Every intermediate image is stored at the technique's storage precision
//! ([`Storage`]: `rgba8unorm`, `rgba16unorm`, `rgba16float`, `rgba32float`), channels packed
//! four per layer of a 2D array texture in the order of [`Resolved::stored_channels`]. The
//! passes after Depth run in one compute pass, timed with timestamp queries when the device
//! has them:
//!
//! - Map: one invocation per texel (and layer) computes the channels and encodes them;
//! - Filter: a separable kernel as two dispatches, the first writing an `rgba32float`
//!   intermediate (so only the second rounds to the storage precision); skipped for K = 1;
//! - Mipmap: one dispatch per level, each texel the mean of the 2 x 2 texels below;
//! - Shade: one invocation per query, filtered lookups through a linear, clamp-to-edge
//!   sampler with `textureSampleLevel` at the query's level of detail.
//!
//! EVSM and MSM store their four channels in one layer (`(w+, w+^2, w-, w-^2)` and
//! `(z, z^2, z^3, z^4)`), so one sampler lookup filters all four with the same weights.
//!
//! CSSM keeps its CSM basis (Unorm8) and its z-weighted set (z-weighted basis and z/2, F16
//! for mipmaps, Unorm8 for tables) in two array textures, each mapped, blurred and then
//! mipmapped, or summed into u32 tables (`sat.wgsl`: rows, then columns) in one storage
//! buffer. PCSS reads the r32float depth directly.

use super::compute::map_read;
use super::{DepthMap, Kind, Query, Resolved, Storage, StoredChannel, Technique, check_map, resolve};
use sshc_runtime::gpu::Gpu;
use std::collections::HashMap;
use std::sync::{Arc, Mutex};
use std::time::Instant;
use wgpu::util::DeviceExt;

const COMMON: &str = include_str!("shaders/common.wgsl");

/// What a binding holds, in the order of the shader's `@binding` numbers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Slot {
    /// `texture_2d<f32>` read with `textureLoad` (the r32float depth, z-max).
    Depth,
    /// `texture_2d_array<f32>` read with `textureLoad`.
    Texels,
    /// `texture_2d_array<f32>` sampled through the linear sampler.
    Filtered,
    Sampler,
    /// `texture_storage_2d_array<FORMAT, write>`, FORMAT chosen per pipeline.
    Write,
    /// `texture_storage_2d<r32float, write>`.
    WriteR32,
    Uniform,
    Read,
    ReadWrite,
}

/// One entry point of one shader file.
struct Program {
    file: &'static str,
    source: &'static str,
    entry: &'static str,
    slots: &'static [Slot],
    /// Shade shaders start with `common.wgsl` (queries in, visibility out).
    shade: bool,
    /// Appended after `source` (CSSM's shade body after its lookups).
    tail: &'static str,
}

/// `program!(file, entry, [slots], shade)`: the shader source comes from `shaders/<file>`;
/// `program!(file + tail + ..., ...)` appends `shaders/<tail>`, each in turn.
macro_rules! program {
    ($file:literal, $entry:literal, [$($slot:ident),*], $shade:literal) => {
        Program {
            file: $file,
            source: include_str!(concat!("shaders/", $file)),
            entry: $entry,
            slots: &[$(Slot::$slot),*],
            shade: $shade,
            tail: "",
        }
    };
    ($file:literal $(+ $tail:literal)+, $entry:literal, [$($slot:ident),*], $shade:literal) => {
        Program {
            file: $file,
            source: include_str!(concat!("shaders/", $file)),
            entry: $entry,
            slots: &[$(Slot::$slot),*],
            shade: $shade,
            tail: concat!($(include_str!(concat!("shaders/", $tail)), "\n"),+),
        }
    };
}

const MAP_VSM: Program = program!("map_vsm.wgsl", "main", [Depth, Write], false);
const MAP_EVSM: Program = program!("map_evsm.wgsl", "main", [Depth, Write, Uniform], false);
const MAP_MSM: Program = program!("map_msm.wgsl", "main", [Depth, Write], false);
const MAP_ESM: Program = program!("map_esm.wgsl", "main", [Depth, Write, Uniform], false);
const MAP_CSM: Program = program!("map_csm.wgsl", "main", [Depth, Write, Uniform, Read], false);
const BLUR: Program = program!("blur.wgsl", "main", [Texels, Write, Uniform, Read], false);
const MIP: Program = program!("mip.wgsl", "main", [Texels, Write], false);
const ZMAX: Program = program!("zmax.wgsl", "main", [Depth, WriteR32, Uniform], false);
const SHADE_HARD: Program = program!("shade_hard.wgsl", "main", [Read, ReadWrite, Depth, Uniform], true);
const SHADE_PCF: Program = program!("shade_pcf.wgsl", "main", [Read, ReadWrite, Depth, Uniform], true);
const SHADE_VSM: Program = program!("shade_vsm.wgsl", "main", [Read, ReadWrite, Filtered, Sampler, Uniform], true);
const SHADE_EVSM: Program = program!("shade_evsm.wgsl", "main", [Read, ReadWrite, Filtered, Sampler, Uniform], true);
const SHADE_MSM: Program = program!(
    "shade_msm.wgsl" + "hamburger.wgsl",
    "main",
    [Read, ReadWrite, Filtered, Sampler, Uniform],
    true
);
/// By `classify`: none, threshold (7.3.2), z-max (7.3.1).
const SHADE_ESM: [Program; 3] = [
    program!("shade_esm.wgsl", "plain", [Read, ReadWrite, Filtered, Sampler, Uniform], true),
    program!("shade_esm.wgsl", "threshold", [Read, ReadWrite, Filtered, Sampler, Uniform], true),
    program!(
        "shade_esm.wgsl",
        "z_max",
        [Read, ReadWrite, Filtered, Sampler, Uniform, Depth],
        true
    ),
];
const SHADE_CSM: Program = program!(
    "shade_csm.wgsl",
    "main",
    [Read, ReadWrite, Filtered, Sampler, Uniform, Read, Read],
    true
);

const MAP_CSSM: Program = program!("map_cssm.wgsl", "main", [Depth, Write, Uniform, Read], false);
const SAT_ROWS: Program = program!("sat.wgsl", "rows", [Texels, ReadWrite, Uniform], false);
const SAT_COLUMNS: Program = program!("sat.wgsl", "columns", [Texels, ReadWrite, Uniform], false);
const SHADE_CSSM_MIPS: Program = program!(
    "cssm_mips.wgsl" + "shade_cssm.wgsl",
    "main",
    [Read, ReadWrite, Filtered, Filtered, Sampler, Uniform, Read, Read],
    true
);
const SHADE_CSSM_TABLE: Program = program!(
    "cssm_table.wgsl" + "shade_cssm.wgsl" + "box_runs.wgsl",
    "main",
    [Read, ReadWrite, Read, Uniform, Read, Read],
    true
);
const SHADE_PCSS: Program = program!("shade_pcss.wgsl", "main", [Read, ReadWrite, Depth, Uniform], true);

const SAT_F32_ROWS: Program = program!("sat_f32.wgsl", "rows", [Texels, ReadWrite, Uniform], false);
const SAT_F32_COLUMNS: Program = program!("sat_f32.wgsl", "columns", [Texels, ReadWrite, Uniform], false);
const SHADE_VSSM: Program = program!("shade_vssm.wgsl" + "box_runs.wgsl", "main", [Read, ReadWrite, Read, Uniform], true);
const MAP_MSSM: Program = program!("map_mssm.wgsl", "main", [Depth, Write, Uniform], false);
const SHADE_MSSM: Program = program!(
    "shade_mssm.wgsl" + "box_runs.wgsl" + "hamburger.wgsl",
    "main",
    [Read, ReadWrite, Read, Uniform],
    true
);
const SHADE_MSM_HAUSDORFF: Program = program!(
    "shade_msm_hausdorff.wgsl" + "hamburger.wgsl",
    "main",
    [Read, ReadWrite, Filtered, Sampler, Uniform],
    true
);

/// The texture format of a storage precision, and its WGSL name.
pub fn texture_format(s: Storage) -> (wgpu::TextureFormat, &'static str) {
    match s {
        Storage::Unorm8 => (wgpu::TextureFormat::Rgba8Unorm, "rgba8unorm"),
        Storage::Unorm16 => (wgpu::TextureFormat::Rgba16Unorm, "rgba16unorm"),
        Storage::F16 => (wgpu::TextureFormat::Rgba16Float, "rgba16float"),
        Storage::F32 => (wgpu::TextureFormat::Rgba32Float, "rgba32float"),
    }
}

struct Pipeline {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
}

type PipelineKey = (&'static str, &'static str, Option<Storage>);

/// The hand-written WGSL references on one device; pipelines are built once and cached
/// (lavapipe compiles each through LLVM).
pub struct GpuReference<'g> {
    gpu: &'g Gpu,
    sampler: wgpu::Sampler,
    pipelines: Mutex<HashMap<PipelineKey, Arc<Pipeline>>>,
}

/// One dispatch of the compute pass.
struct Dispatch {
    pipeline: Arc<Pipeline>,
    group: wgpu::BindGroup,
    workgroups: [u32; 3],
}

/// Little-endian words of a uniform block.
#[derive(Default)]
struct Words(Vec<u8>);

/// The light as the soft techniques' shaders read it first: its width along u and v, the
/// depth range's near and far distances, and uv per world unit at the near plane.
fn light_words(light: &super::LightFrame) -> Words {
    Words::default()
        .f(light.width[0])
        .f(light.width[1])
        .f(light.near)
        .f(light.far)
        .f(light.uv_per_world(light.near))
}

impl Words {
    fn f(mut self, v: f64) -> Words {
        self.0.extend_from_slice(&(v as f32).to_le_bytes());
        self
    }
    fn u(mut self, v: u32) -> Words {
        self.0.extend_from_slice(&v.to_le_bytes());
        self
    }
    fn i(mut self, v: i32) -> Words {
        self.0.extend_from_slice(&v.to_le_bytes());
        self
    }
}

fn groups(n: u32, per: u32) -> u32 {
    n.div_ceil(per)
}

impl<'g> GpuReference<'g> {
    pub fn new(gpu: &'g Gpu) -> Result<GpuReference<'g>, String> {
        let sampler = gpu
            .scoped("creating the reference sampler", || {
                gpu.device.create_sampler(&wgpu::SamplerDescriptor {
                    label: Some("reference linear clamp"),
                    address_mode_u: wgpu::AddressMode::ClampToEdge,
                    address_mode_v: wgpu::AddressMode::ClampToEdge,
                    address_mode_w: wgpu::AddressMode::ClampToEdge,
                    mag_filter: wgpu::FilterMode::Linear,
                    min_filter: wgpu::FilterMode::Linear,
                    mipmap_filter: wgpu::MipmapFilterMode::Linear,
                    ..Default::default()
                })
            })
            .map_err(|e| e.to_string())?;
        Ok(GpuReference {
            gpu,
            sampler,
            pipelines: Mutex::new(HashMap::new()),
        })
    }

    /// Visibility at every query, and the GPU time in nanoseconds of the passes after Depth
    /// for this one run (timestamp queries when the device has them, else the wall time of
    /// submitting and waiting, read-back included). On lavapipe the end timestamp does not
    /// wait for a pass's last dispatch (docs/agreement.md): techniques whose work is one
    /// dispatch read near zero there.
    pub fn visibility(&self, t: &Technique, map: &DepthMap, queries: &[Query]) -> Result<(Vec<f32>, f64), String> {
        self.visibility_repeated(t, map, queries, 1).map(|(v, gpu, _)| (v, gpu))
    }

    /// [`GpuReference::visibility`] with the Shade dispatch (the last) run `shade_repeats`
    /// times (at least once; it writes the same results each time), and the wall time in
    /// nanoseconds from submission to read-back as well. The difference of wall times with
    /// different repeats is the Shade dispatch's cost with every fixed cost cancelled: what
    /// a device whose timestamps skip the last dispatch cannot measure otherwise.
    pub fn visibility_repeated(
        &self,
        t: &Technique,
        map: &DepthMap,
        queries: &[Query],
        shade_repeats: u32,
    ) -> Result<(Vec<f32>, f64, f64), String> {
        let r = resolve(t)?;
        check_map(map)?;
        if queries.is_empty() {
            return Ok((Vec::new(), 0.0, 0.0));
        }
        self.check_device(&r, map, queries)?;
        let gpu = self.gpu;
        let run = || -> Result<(Vec<f32>, f64, f64), String> {
            let device = &gpu.device;
            let n = map.size;
            let depth = device.create_texture(&wgpu::TextureDescriptor {
                label: Some("reference depth"),
                size: wgpu::Extent3d {
                    width: n,
                    height: n,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::R32Float,
                usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                view_formats: &[],
            });
            let bytes: Vec<u8> = map.z.iter().flat_map(|z| z.to_le_bytes()).collect();
            gpu.queue.write_texture(
                depth.as_image_copy(),
                &bytes,
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(4 * n),
                    rows_per_image: Some(n),
                },
                wgpu::Extent3d {
                    width: n,
                    height: n,
                    depth_or_array_layers: 1,
                },
            );
            let depth = depth.create_view(&Default::default());
            let query_bytes: Vec<u8> = queries
                .iter()
                .flat_map(|q| [q.uv[0], q.uv[1], q.d, q.lod])
                .flat_map(f32::to_le_bytes)
                .collect();
            let query_buffer = self.buffer("queries", &query_bytes, wgpu::BufferUsages::STORAGE);
            let size = 4 * queries.len() as u64;
            let results = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("reference visibility"),
                size,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            let readback = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("reference read-back"),
                size,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let mut dispatches = Vec::new();
            let shade_groups = [groups(queries.len() as u32, 64), 1, 1];
            let io = [query_buffer.as_entire_binding(), results.as_entire_binding()];
            self.passes(&r, n, &depth, io, shade_groups, &mut dispatches)?;

            let timer = gpu.features.contains(wgpu::Features::TIMESTAMP_QUERY).then(|| {
                let set = device.create_query_set(&wgpu::QuerySetDescriptor {
                    label: Some("reference time"),
                    ty: wgpu::QueryType::Timestamp,
                    count: 2,
                });
                let resolved = device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("reference timestamps"),
                    size: 16,
                    usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                });
                let read = device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("reference timestamps read-back"),
                    size: 16,
                    usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                });
                (set, resolved, read)
            });
            let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("reference passes"),
            });
            {
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("reference passes after Depth"),
                    timestamp_writes: timer.as_ref().map(|(set, _, _)| wgpu::ComputePassTimestampWrites {
                        query_set: set,
                        beginning_of_pass_write_index: Some(0),
                        end_of_pass_write_index: Some(1),
                    }),
                });
                let last = dispatches.len().saturating_sub(1);
                for (i, d) in dispatches.iter().enumerate() {
                    pass.set_pipeline(&d.pipeline.pipeline);
                    pass.set_bind_group(0, &d.group, &[]);
                    let [x, y, z] = d.workgroups;
                    let times = if i == last { shade_repeats.max(1) } else { 1 };
                    for _ in 0..times {
                        pass.dispatch_workgroups(x, y, z);
                    }
                }
            }
            encoder.copy_buffer_to_buffer(&results, 0, &readback, 0, size);
            if let Some((set, resolved, read)) = &timer {
                encoder.resolve_query_set(set, 0..2, resolved, 0);
                encoder.copy_buffer_to_buffer(resolved, 0, read, 0, 16);
            }
            let start = Instant::now();
            gpu.queue.submit([encoder.finish()]);
            let values = map_read(gpu, &readback)?;
            let wall = start.elapsed().as_nanos() as f64;
            let visibility: Vec<f32> = values
                .chunks_exact(4)
                .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                .collect();
            let time = match &timer {
                Some((_, _, read)) => {
                    let raw = map_read(gpu, read)?;
                    let tick = |i: usize| u64::from_le_bytes(raw[8 * i..8 * i + 8].try_into().unwrap_or([0; 8]));
                    let (a, b) = (tick(0), tick(1));
                    if b > a && a > 0 {
                        (b - a) as f64 * gpu.queue.get_timestamp_period() as f64
                    } else {
                        wall
                    }
                }
                None => wall,
            };
            Ok((visibility, time, wall))
        };
        gpu.scoped(&format!("running the GPU reference of `{}`", t.name), run)
            .map_err(|e| e.to_string())?
    }

    /// Refuse what the device cannot do, before allocating anything.
    fn check_device(&self, r: &Resolved, map: &DepthMap, queries: &[Query]) -> Result<(), String> {
        let limits = &self.gpu.limits;
        let features = self.gpu.features;
        if map.size > limits.max_texture_dimension_2d {
            return Err(format!(
                "a {0} x {0} depth map exceeds the device's limit of {1} x {1}",
                map.size, limits.max_texture_dimension_2d
            ));
        }
        let layers = layers(r);
        if layers > limits.max_texture_array_layers {
            return Err(format!(
                "{layers} texture layers exceed the device's limit of {}",
                limits.max_texture_array_layers
            ));
        }
        let bytes = 16 * queries.len() as u64;
        if bytes > limits.max_storage_buffer_binding_size || groups(queries.len() as u32, 64) > limits.max_compute_workgroups_per_dimension
        {
            return Err(format!(
                "{} queries are more than one dispatch of the device can take",
                queries.len()
            ));
        }
        if r.kind == Kind::Cssm {
            let (series, weighted) = cssm_sets(r);
            let table = 4 * 4 * (layers_of(&series) + layers_of(&weighted)) as u64 * (map.size as u64).pow(2);
            if r.int("filter") == 1 && table > limits.max_storage_buffer_binding_size {
                return Err(format!(
                    "the summed-area tables of a {0} x {0} map ({table} bytes) exceed the device's storage buffer limit",
                    map.size
                ));
            }
            if r.int("filter") == 1 && map.size > 4096 {
                return Err("u32 summed-area tables of unorm8 codes hold maps up to 4096 x 4096".into());
            }
        }
        if matches!(
            r.kind,
            Kind::Vsm | Kind::Esm | Kind::Evsm | Kind::Msm | Kind::MsmHausdorff | Kind::Csm
        ) {
            if r.storage == Storage::Unorm16 && !features.contains(wgpu::Features::TEXTURE_FORMAT_16BIT_NORM) {
                return Err("Unorm16 storage needs the device feature TEXTURE_FORMAT_16BIT_NORM".into());
            }
            if r.storage == Storage::F32 && !features.contains(wgpu::Features::FLOAT32_FILTERABLE) {
                return Err("filtered lookups of F32 storage need the device feature FLOAT32_FILTERABLE".into());
            }
        }
        Ok(())
    }

    /// Append the dispatches of every pass after Depth.
    fn passes(
        &self,
        r: &Resolved,
        n: u32,
        depth: &wgpu::TextureView,
        io: [wgpu::BindingResource<'_>; 2],
        shade_groups: [u32; 3],
        out: &mut Vec<Dispatch>,
    ) -> Result<(), String> {
        let [queries, results] = io;
        let sampler = wgpu::BindingResource::Sampler(&self.sampler);
        match r.kind {
            Kind::Hard => {
                let params = self.uniform("hard", Words::default().f(r.get("bias")));
                let resources = vec![queries, results, view(depth), params.as_entire_binding()];
                out.push(self.dispatch(&SHADE_HARD, None, resources, shade_groups)?);
            }
            Kind::Pcf => {
                let params = self.uniform("pcf", Words::default().f(r.get("bias")).i(r.int("N") as i32));
                let resources = vec![queries, results, view(depth), params.as_entire_binding()];
                out.push(self.dispatch(&SHADE_PCF, None, resources, shade_groups)?);
            }
            Kind::Vsm => {
                let filtered = self.prefilter(r, n, depth, (&MAP_VSM, Vec::new()), out)?;
                let words = Words::default().f(r.get("bias")).f(r.get("min_variance")).f(r.get("bleed"));
                let params = self.uniform("vsm", words);
                let resources = vec![queries, results, view(&filtered), sampler, params.as_entire_binding()];
                out.push(self.dispatch(&SHADE_VSM, None, resources, shade_groups)?);
            }
            Kind::Evsm => {
                // (lo, span) of the four warps, in the order p1, p2, n1, n2
                let mut lo = Words::default();
                let mut span = Words::default();
                for c in r.stored_channels() {
                    let (l, s) = c.encoding(r.storage);
                    lo = lo.f(l);
                    span = span.f(s);
                }
                let encoding = || Words(lo.0.iter().chain(&span.0).copied().collect());
                let (cp, cn) = (r.get("c_pos"), r.get("c_neg"));
                let map_params = self.uniform("evsm map", encoding().f(cp).f(cn));
                let map = (&MAP_EVSM, vec![map_params.as_entire_binding()]);
                let filtered = self.prefilter(r, n, depth, map, out)?;
                let words = encoding().f(cp).f(cn).f(r.get("min_variance")).f(r.get("bleed"));
                let params = self.uniform("evsm", words);
                let resources = vec![queries, results, view(&filtered), sampler, params.as_entire_binding()];
                out.push(self.dispatch(&SHADE_EVSM, None, resources, shade_groups)?);
            }
            Kind::Msm | Kind::MsmHausdorff => {
                let filtered = self.prefilter(r, n, depth, (&MAP_MSM, Vec::new()), out)?;
                let params = self.uniform("msm", Words::default().f(r.get("alpha")).f(r.get("bias")));
                let resources = vec![queries, results, view(&filtered), sampler, params.as_entire_binding()];
                let shade = if r.kind == Kind::Msm { &SHADE_MSM } else { &SHADE_MSM_HAUSDORFF };
                out.push(self.dispatch(shade, None, resources, shade_groups)?);
            }
            Kind::Vssm => {
                // Map (z, z^2) at F32, then f32 tables of v - 1/2 (sat_f32.wgsl)
                let stack = self.filtered_stack(n, depth, (&MAP_VSM, Vec::new()), Storage::F32, 1, &[1.0], false, out)?;
                let table = self.table(4 * 2 * (n as u64).pow(2));
                let sat_params = self.uniform("vssm sat", Words::default().u(n).f(0.5));
                for program in [&SAT_F32_ROWS, &SAT_F32_COLUMNS] {
                    let resources = vec![view(&stack), table.as_entire_binding(), sat_params.as_entire_binding()];
                    out.push(self.dispatch(program, None, resources, [groups(n, 64), 2, 1])?);
                }
                let light = r.light();
                let words = light_words(&light)
                    .f(r.get("bias"))
                    .f(r.get("min_variance"))
                    .u(u32::from(r.int("subdivide") != 0))
                    .f(n as f64)
                    .f(0.5);
                let params = self.uniform("vssm", words);
                let resources = vec![queries, results, table.as_entire_binding(), params.as_entire_binding()];
                out.push(self.dispatch(&SHADE_VSSM, None, resources, shade_groups)?);
            }
            Kind::Mssm => {
                // Map q1..q4 at F32, then 16-bit fixed-point tables (sat.wgsl, scale 65535)
                let quantise = u32::from(r.int("quantise") != 0);
                let map_params = self.uniform("mssm map", Words::default().u(quantise));
                let map = (&MAP_MSSM, vec![map_params.as_entire_binding()]);
                let stack = self.filtered_stack(n, depth, map, Storage::F32, 1, &[1.0], false, out)?;
                let table = self.table(4 * 4 * (n as u64).pow(2));
                let sat_params = self.uniform("mssm sat", Words::default().u(n).u(0).f(65535.0));
                for program in [&SAT_ROWS, &SAT_COLUMNS] {
                    let resources = vec![view(&stack), table.as_entire_binding(), sat_params.as_entire_binding()];
                    out.push(self.dispatch(program, Some(Storage::Unorm8), resources, [groups(n, 64), 4, 1])?);
                }
                let light = r.light();
                let words = light_words(&light)
                    .f(r.get("bias"))
                    .f(r.get("alpha"))
                    .f(r.get("lit_weight"))
                    .u(quantise)
                    .f(n as f64);
                let params = self.uniform("mssm", words);
                let resources = vec![queries, results, table.as_entire_binding(), params.as_entire_binding()];
                out.push(self.dispatch(&SHADE_MSSM, None, resources, shade_groups)?);
            }
            Kind::Esm => {
                let c = r.get("c");
                let (lo, span) = r.stored_channels()[0].encoding(r.storage);
                let map_params = self.uniform("esm map", Words::default().f(c).f(lo).f(span));
                let map = (&MAP_ESM, vec![map_params.as_entire_binding()]);
                let filtered = self.prefilter(r, n, depth, map, out)?;
                let words = Words::default()
                    .f(c)
                    .f(r.get("bias"))
                    .f(r.get("eps"))
                    .f(r.get("zmax_offset"))
                    .f(lo)
                    .f(span);
                let params = self.uniform("esm", words);
                let classify = r.int("classify").clamp(0, 2);
                let zmax = match classify {
                    2 => Some(self.zmax(n, depth, r.int("K") as u32 + 2, out)?),
                    _ => None,
                };
                let mut resources = vec![queries, results, view(&filtered), sampler, params.as_entire_binding()];
                resources.extend(zmax.as_ref().map(view));
                out.push(self.dispatch(&SHADE_ESM[classify as usize], None, resources, shade_groups)?);
            }
            Kind::Csm => {
                let m = r.int("M");
                // per layer: (lo, span) of its four channels; unused slots (odd M) decode as is
                let mut encoding = Words::default();
                for layer in r.stored_channels().chunks(4) {
                    let mut lo = [0.0; 4];
                    let mut span = [1.0; 4];
                    for (i, c) in layer.iter().enumerate() {
                        (lo[i], span[i]) = c.encoding(r.storage);
                    }
                    for v in lo.into_iter().chain(span) {
                        encoding = encoding.f(v);
                    }
                }
                let encoding = self.buffer("csm encoding", &encoding.0, wgpu::BufferUsages::STORAGE);
                let map_params = self.uniform("csm map", Words::default().u(m as u32));
                let map = (&MAP_CSM, vec![map_params.as_entire_binding(), encoding.as_entire_binding()]);
                let filtered = self.prefilter(r, n, depth, map, out)?;
                // 2 a_k / c_k with a_k = exp(-alpha (k/M)^2), c_k = pi (2k - 1) (eq. 6.6, 6.1.1)
                let alpha = r.get("alpha");
                let mut amplitude = Words::default();
                for k in 1..=m {
                    let ck = std::f64::consts::PI * (2 * k - 1) as f64;
                    amplitude = amplitude.f(2.0 * (-alpha * (k as f64 / m as f64).powi(2)).exp() / ck);
                }
                let amplitude = self.buffer("csm amplitudes", &amplitude.0, wgpu::BufferUsages::STORAGE);
                let fix = r.int("fix");
                let shift = r.get("bias") + if fix == 1 { 0.5 / m as f64 } else { 0.0 };
                let scale = if fix == 2 { 2.0 } else { 1.0 };
                let params = self.uniform("csm", Words::default().u(m as u32).f(shift).f(scale));
                let resources = vec![
                    queries,
                    results,
                    view(&filtered),
                    sampler,
                    params.as_entire_binding(),
                    encoding.as_entire_binding(),
                    amplitude.as_entire_binding(),
                ];
                out.push(self.dispatch(&SHADE_CSM, None, resources, shade_groups)?);
            }
            Kind::Cssm => self.cssm(r, n, depth, [queries, results], shade_groups, out)?,
            Kind::Pcss => {
                let light = r.light();
                let words = light_words(&light).f(r.get("bias")).i(r.int("N") as i32).i(r.int("M") as i32);
                let params = self.uniform("pcss", words);
                let resources = vec![queries, results, view(depth), params.as_entire_binding()];
                out.push(self.dispatch(&SHADE_PCSS, None, resources, shade_groups)?);
            }
        }
        Ok(())
    }

    /// CSSM: two channel sets (the CSM basis; the z-weighted basis and z/2), each mapped and
    /// blurred, then mipmapped (filter = 0) or summed into tables (filter = 1); the Shade
    /// pass reads both.
    fn cssm(
        &self,
        r: &Resolved,
        n: u32,
        depth: &wgpu::TextureView,
        io: [wgpu::BindingResource<'_>; 2],
        shade_groups: [u32; 3],
        out: &mut Vec<Dispatch>,
    ) -> Result<(), String> {
        let [queries, results] = io;
        let m = r.int("M");
        let sat = r.int("filter") == 1;
        let (series, weighted) = cssm_sets(r);
        let (series_layers, weighted_layers) = (layers_of(&series), layers_of(&weighted));
        // per layer (the CSM basis's, then the z-weighted set's): (lo, span) of its four
        // channels, each at its own precision's encoding; unused slots decode as is
        let mut encoding = Words::default();
        for set in [&series, &weighted] {
            for layer in set.chunks(4) {
                let mut lo = [0.0; 4];
                let mut span = [1.0; 4];
                for (i, c) in layer.iter().enumerate() {
                    (lo[i], span[i]) = c.encoding(r.channel_storage(&c.name));
                }
                for v in lo.into_iter().chain(span) {
                    encoding = encoding.f(v);
                }
            }
        }
        let encoding = self.buffer("cssm encoding", &encoding.0, wgpu::BufferUsages::STORAGE);
        let weights = super::cpu::gaussian_weights(r.int("K").max(1) as usize, r.get("sigma"));
        let mut stacks = Vec::new();
        for (weighted, set, layers, first_layer) in [(0, &series, series_layers, 0), (1, &weighted, weighted_layers, series_layers)] {
            let storage = r.channel_storage(&set[0].name);
            let map_params = self.uniform("cssm map", Words::default().u(m as u32).u(weighted).u(first_layer));
            let map = (&MAP_CSSM, vec![map_params.as_entire_binding(), encoding.as_entire_binding()]);
            stacks.push(self.filtered_stack(n, depth, map, storage, layers, &weights, !sat, out)?);
        }
        let amplitude = (1..=m).fold(Words::default(), |w, k| w.f(super::cpu::cssm_amplitude(r, k)));
        let amplitude = self.buffer("cssm amplitudes", &amplitude.0, wgpu::BufferUsages::STORAGE);
        let light = r.light();
        let fix = r.int("fix");
        let words = light_words(&light)
            .f(r.get("bias"))
            .f(if fix == 1 { 0.5 / m as f64 } else { 0.0 })
            .f(if fix == 2 { 2.0 } else { 1.0 })
            .f(r.get("ring"))
            .f(r.get("min_blocker"))
            .f(r.get("A"))
            .f(r.get("B"))
            .u(m as u32)
            .f(n as f64);
        let params = self.uniform("cssm", words);
        if !sat {
            let resources = vec![
                queries,
                results,
                view(&stacks[0]),
                view(&stacks[1]),
                wgpu::BindingResource::Sampler(&self.sampler),
                params.as_entire_binding(),
                encoding.as_entire_binding(),
                amplitude.as_entire_binding(),
            ];
            out.push(self.dispatch(&SHADE_CSSM_MIPS, None, resources, shade_groups)?);
            return Ok(());
        }
        let channels = 4 * (series_layers + weighted_layers) as u64;
        let table = self.gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("cssm summed-area tables"),
            size: 4 * channels * (n as u64) * (n as u64),
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        for (stack, layers, first_channel) in [(&stacks[0], series_layers, 0), (&stacks[1], weighted_layers, 4 * series_layers)] {
            let sat_params = self.uniform("sat", Words::default().u(n).u(first_channel).f(255.0));
            let groups = [groups(n, 64), 4 * layers, 1];
            for program in [&SAT_ROWS, &SAT_COLUMNS] {
                let resources = vec![view(stack), table.as_entire_binding(), sat_params.as_entire_binding()];
                out.push(self.dispatch(program, Some(Storage::Unorm8), resources, groups)?);
            }
        }
        let resources = vec![
            queries,
            results,
            table.as_entire_binding(),
            params.as_entire_binding(),
            encoding.as_entire_binding(),
            amplitude.as_entire_binding(),
        ];
        out.push(self.dispatch(&SHADE_CSSM_TABLE, None, resources, shade_groups)?);
        Ok(())
    }

    /// The technique's Map pass (the program, with its extra bindings after the depth and
    /// the target), its Filter pass (separable; skipped for one tap, which changes nothing)
    /// and, for VSM and CSM, its Mipmap pass. Returns a view of every level of the result.
    fn prefilter(
        &self,
        r: &Resolved,
        n: u32,
        depth: &wgpu::TextureView,
        map: (&Program, Vec<wgpu::BindingResource<'_>>),
        out: &mut Vec<Dispatch>,
    ) -> Result<wgpu::TextureView, String> {
        // the techniques' Filter kernels; VSM, EVSM, MSM and CSM build a mean mip chain, ESM
        // does not
        let (weights, mips) = match r.kind {
            Kind::Csm => (super::cpu::gaussian_weights(r.int("K").max(1) as usize, r.get("sigma")), true),
            _ => (
                super::cpu::box_weights(r.int("K").max(1) as usize),
                matches!(r.kind, Kind::Vsm | Kind::Evsm | Kind::Msm | Kind::MsmHausdorff),
            ),
        };
        self.filtered_stack(n, depth, map, r.storage, layers(r), &weights, mips, out)
    }

    /// A Map pass into `layers` layers at `storage`, the separable Filter `weights` and, with
    /// `mips`, a mean mip chain. Returns a view of every level of the result.
    #[allow(clippy::too_many_arguments)]
    fn filtered_stack(
        &self,
        n: u32,
        depth: &wgpu::TextureView,
        map: (&Program, Vec<wgpu::BindingResource<'_>>),
        storage: Storage,
        layers: u32,
        weights: &[f64],
        mips: bool,
        out: &mut Vec<Dispatch>,
    ) -> Result<wgpu::TextureView, String> {
        let levels = if mips { 32 - n.leading_zeros() } else { 1 };
        let (format, _) = texture_format(storage);
        let filtered = self.texture("filtered", n, layers, levels, format);
        let tile = [groups(n, 8), groups(n, 8), layers];
        let (program, extra) = map;
        let map_resources = |target| [view(depth), target].into_iter().chain(extra.iter().cloned()).collect::<Vec<_>>();
        let base = level_view(&filtered, 0);
        if weights.len() > 1 {
            let mapped = level_view(&self.texture("mapped", n, layers, 1, format), 0);
            let tmp = level_view(
                &self.texture("filter intermediate", n, layers, 1, wgpu::TextureFormat::Rgba32Float),
                0,
            );
            let taps = weights.iter().fold(Words::default(), |w, &v| w.f(v));
            let taps = self.buffer("filter weights", &taps.0, wgpu::BufferUsages::STORAGE);
            let radius = (weights.len() / 2) as i32;
            let horizontal = self.uniform("filter x", Words::default().i(1).i(0).i(radius));
            let vertical = self.uniform("filter y", Words::default().i(0).i(1).i(radius));
            out.push(self.dispatch(program, Some(storage), map_resources(view(&mapped)), tile)?);
            let resources = vec![view(&mapped), view(&tmp), horizontal.as_entire_binding(), taps.as_entire_binding()];
            out.push(self.dispatch(&BLUR, Some(Storage::F32), resources, tile)?);
            let resources = vec![view(&tmp), view(&base), vertical.as_entire_binding(), taps.as_entire_binding()];
            out.push(self.dispatch(&BLUR, Some(storage), resources, tile)?);
        } else {
            out.push(self.dispatch(program, Some(storage), map_resources(view(&base)), tile)?);
        }
        for level in 1..levels {
            let size = (n >> level).max(1);
            out.push(self.dispatch(
                &MIP,
                Some(storage),
                vec![view(&level_view(&filtered, level - 1)), view(&level_view(&filtered, level))],
                [groups(size, 8), groups(size, 8), layers],
            )?);
        }
        Ok(filtered.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        }))
    }

    /// ESM's z-max texture (7.3.1): the depth max-filtered over `taps x taps`.
    fn zmax(&self, n: u32, depth: &wgpu::TextureView, taps: u32, out: &mut Vec<Dispatch>) -> Result<wgpu::TextureView, String> {
        let texture = |label| {
            self.gpu
                .device
                .create_texture(&wgpu::TextureDescriptor {
                    label: Some(label),
                    size: wgpu::Extent3d {
                        width: n,
                        height: n,
                        depth_or_array_layers: 1,
                    },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format: wgpu::TextureFormat::R32Float,
                    usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::STORAGE_BINDING,
                    view_formats: &[],
                })
                .create_view(&Default::default())
        };
        let (tmp, zmax) = (texture("z-max intermediate"), texture("z-max"));
        let radius = (taps / 2) as i32;
        let horizontal = self.uniform("z-max x", Words::default().i(1).i(0).i(radius));
        let vertical = self.uniform("z-max y", Words::default().i(0).i(1).i(radius));
        let tile = [groups(n, 8), groups(n, 8), 1];
        out.push(self.dispatch(&ZMAX, None, vec![view(depth), view(&tmp), horizontal.as_entire_binding()], tile)?);
        out.push(self.dispatch(&ZMAX, None, vec![view(&tmp), view(&zmax), vertical.as_entire_binding()], tile)?);
        Ok(zmax)
    }

    fn texture(&self, label: &str, n: u32, layers: u32, levels: u32, format: wgpu::TextureFormat) -> wgpu::Texture {
        self.gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width: n,
                height: n,
                depth_or_array_layers: layers,
            },
            mip_level_count: levels,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::STORAGE_BINDING,
            view_formats: &[],
        })
    }

    /// A storage buffer of `size` bytes for summed-area tables.
    fn table(&self, size: u64) -> wgpu::Buffer {
        self.gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("summed-area tables"),
            size,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        })
    }

    fn buffer(&self, label: &str, bytes: &[u8], usage: wgpu::BufferUsages) -> wgpu::Buffer {
        self.gpu.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: bytes,
            usage,
        })
    }

    /// A uniform block, padded to 16 bytes.
    fn uniform(&self, label: &str, words: Words) -> wgpu::Buffer {
        let mut bytes = words.0;
        bytes.resize(bytes.len().div_ceil(16).max(1) * 16, 0);
        self.buffer(label, &bytes, wgpu::BufferUsages::UNIFORM)
    }

    fn dispatch(
        &self,
        program: &Program,
        storage: Option<Storage>,
        resources: Vec<wgpu::BindingResource<'_>>,
        workgroups: [u32; 3],
    ) -> Result<Dispatch, String> {
        let pipeline = self.pipeline(program, storage)?;
        let entries: Vec<wgpu::BindGroupEntry> = resources
            .into_iter()
            .enumerate()
            .map(|(i, resource)| wgpu::BindGroupEntry {
                binding: i as u32,
                resource,
            })
            .collect();
        let group = self.gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(program.file),
            layout: &pipeline.layout,
            entries: &entries,
        });
        Ok(Dispatch {
            pipeline,
            group,
            workgroups,
        })
    }

    /// The pipeline of one entry point, with FORMAT set to the storage precision's format.
    fn pipeline(&self, program: &Program, storage: Option<Storage>) -> Result<Arc<Pipeline>, String> {
        let key = (program.file, program.entry, storage);
        let mut cache = self.pipelines.lock().map_err(|_| "the pipeline cache is poisoned".to_string())?;
        if let Some(p) = cache.get(&key) {
            return Ok(p.clone());
        }
        let format = storage.map(texture_format);
        let mut source = String::new();
        if program.shade {
            source.push_str(COMMON);
            source.push('\n');
        }
        source.push_str(&program.source.replace("FORMAT", format.map_or("rgba32float", |f| f.1)));
        source.push('\n');
        source.push_str(program.tail);
        let entries: Vec<wgpu::BindGroupLayoutEntry> = program
            .slots
            .iter()
            .enumerate()
            .map(|(i, slot)| wgpu::BindGroupLayoutEntry {
                binding: i as u32,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: binding_type(*slot, format.map_or(wgpu::TextureFormat::Rgba32Float, |f| f.0)),
                count: None,
            })
            .collect();
        let context = format!("building the reference pipeline {}:{} ({storage:?})", program.file, program.entry);
        let device = &self.gpu.device;
        let pipeline = self
            .gpu
            .scoped(&context, || {
                let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                    label: Some(program.file),
                    source: wgpu::ShaderSource::Wgsl(source.into()),
                });
                let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                    label: Some(program.file),
                    entries: &entries,
                });
                let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                    label: Some(program.file),
                    bind_group_layouts: &[Some(&layout)],
                    immediate_size: 0,
                });
                let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some(program.file),
                    layout: Some(&pipeline_layout),
                    module: &module,
                    entry_point: Some(program.entry),
                    compilation_options: Default::default(),
                    cache: None,
                });
                Pipeline { pipeline, layout }
            })
            .map_err(|e| e.to_string())?;
        let pipeline = Arc::new(pipeline);
        cache.insert(key, pipeline.clone());
        Ok(pipeline)
    }
}

fn binding_type(slot: Slot, format: wgpu::TextureFormat) -> wgpu::BindingType {
    use Slot::*;
    let texture = |filterable, view_dimension| wgpu::BindingType::Texture {
        sample_type: wgpu::TextureSampleType::Float { filterable },
        view_dimension,
        multisampled: false,
    };
    let storage_texture = |format, view_dimension| wgpu::BindingType::StorageTexture {
        access: wgpu::StorageTextureAccess::WriteOnly,
        format,
        view_dimension,
    };
    let buffer = |ty| wgpu::BindingType::Buffer {
        ty,
        has_dynamic_offset: false,
        min_binding_size: None,
    };
    match slot {
        Depth => texture(false, wgpu::TextureViewDimension::D2),
        Texels => texture(false, wgpu::TextureViewDimension::D2Array),
        Filtered => texture(true, wgpu::TextureViewDimension::D2Array),
        Sampler => wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
        Write => storage_texture(format, wgpu::TextureViewDimension::D2Array),
        WriteR32 => storage_texture(wgpu::TextureFormat::R32Float, wgpu::TextureViewDimension::D2),
        Uniform => buffer(wgpu::BufferBindingType::Uniform),
        Read => buffer(wgpu::BufferBindingType::Storage { read_only: true }),
        ReadWrite => buffer(wgpu::BufferBindingType::Storage { read_only: false }),
    }
}

fn view(v: &wgpu::TextureView) -> wgpu::BindingResource<'_> {
    wgpu::BindingResource::TextureView(v)
}

/// A view of one level of an array texture, all layers.
fn level_view(t: &wgpu::Texture, level: u32) -> wgpu::TextureView {
    t.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        base_mip_level: level,
        mip_level_count: Some(1),
        ..Default::default()
    })
}

/// Layers of the technique's channel texture (four channels each).
fn layers(r: &Resolved) -> u32 {
    match r.kind {
        Kind::Cssm => {
            let (series, weighted) = cssm_sets(r);
            layers_of(&series).max(layers_of(&weighted))
        }
        _ => layers_of(&r.stored_channels()),
    }
}

fn layers_of(channels: &[StoredChannel]) -> u32 {
    (channels.len() as u32).div_ceil(4).max(1)
}

/// CSSM's two channel sets: the CSM basis (`f` or `fs`, 2M channels), and the z-weighted
/// basis with z/2 (`g` and `zh`, or `gs` and `zhs`, 2M + 1 channels).
fn cssm_sets(r: &Resolved) -> (Vec<StoredChannel>, Vec<StoredChannel>) {
    let mut series = r.stored_channels();
    let weighted = series.split_off(2 * r.int("M") as usize);
    (series, weighted)
}
