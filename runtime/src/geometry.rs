//! A host's geometry: indexed meshes uploaded once, drawn as instances, each with its own
//! transform, every frame.
//!
//! The generated shaders read world-space positions and normals (`@location(0)` and `(1)`).
//! So that they stay as they are, a runtime compute step *places* the instances: for each
//! instance it writes its mesh's vertices, transformed, into a buffer of placed vertices
//! (`p' = M p`, `n' = N n` with `N` the inverse transpose of `M`'s upper 3 x 3, not
//! normalised: the shaders normalise the interpolated normal). The scene's draws then take
//! the mesh's index buffer with the instance's placed vertices as base vertex, one indexed
//! draw per instance; the light's draws take the casting instances only. Placement runs in
//! the frame after the transforms change ([`crate::gpu::Executor::set_transforms`]), so a
//! frame whose transforms did not move pays nothing for it.
//!
//! Memory: the meshes once (24 bytes a vertex and 4 an index) and the placed vertices
//! (24 bytes a vertex per instance), against a triangle soup's 72 bytes a triangle per
//! instance ([`Geometry::gpu_bytes`]).
//!
//! With an identity transform, placement is exact: each coordinate is `1 x + 0 y + 0 z +
//! 0`, so the placed vertices are the mesh's (up to the sign of a zero). Transforms whose
//! 3 x 3 holds only 0 and +-1 add one rounding (of the translation), the same one a CPU
//! computing `M p` in f32 makes.

use crate::device::Gpu;
use crate::error::{Result, RuntimeError};
use crate::frame::SceneInputs;

/// An indexed triangle mesh in its object space.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// For errors.
    pub name: String,
    pub positions: Vec<[f32; 3]>,
    /// One per position.
    pub normals: Vec<[f32; 3]>,
    /// Three per triangle, each below `positions.len()`.
    pub indices: Vec<u32>,
}

/// One placement of a mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct Instance {
    /// For errors.
    pub name: String,
    /// Index into [`Geometry::meshes`].
    pub mesh: usize,
    /// Column-major object-to-world matrix (affine: its last row is 0, 0, 0, 1).
    pub transform: [f32; 16],
    /// Drawn into the light's views (a shadow caster). Every instance is drawn by the camera.
    pub casts: bool,
}

/// A host's meshes and their instances, in draw order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Geometry {
    pub meshes: Vec<Mesh>,
    pub instances: Vec<Instance>,
}

/// The identity matrix, column-major.
pub const IDENTITY: [f32; 16] = [1., 0., 0., 0., 0., 1., 0., 0., 0., 0., 1., 0., 0., 0., 0., 1.];

/// Most instances one geometry holds: each has a 256-byte placement record.
pub const MAX_INSTANCES: usize = 1 << 16;

/// Bytes of one instance's placement record (a uniform read at a dynamic offset, which
/// WebGPU aligns to 256 bytes).
const RECORD_BYTES: u64 = 256;

/// `M p` for a column-major affine `m`, as the placement shader computes it.
pub fn transform_point(m: &[f32; 16], p: [f32; 3]) -> [f32; 3] {
    [0, 1, 2].map(|r| m[r] * p[0] + m[4 + r] * p[1] + m[8 + r] * p[2] + m[12 + r])
}

/// The inverse transpose of `m`'s upper 3 x 3, column-major in a 4 x 4 (for normals);
/// `None` when it is singular.
pub fn normal_matrix(m: &[f32; 16]) -> Option<[f32; 16]> {
    let a = |r: usize, c: usize| f64::from(m[4 * c + r]);
    let cof = |r: usize, c: usize| {
        let (r1, r2) = ((r + 1) % 3, (r + 2) % 3);
        let (c1, c2) = ((c + 1) % 3, (c + 2) % 3);
        a(r1, c1) * a(r2, c2) - a(r1, c2) * a(r2, c1)
    };
    let det = a(0, 0) * cof(0, 0) + a(0, 1) * cof(0, 1) + a(0, 2) * cof(0, 2);
    if !(det.is_finite() && det != 0.0) {
        return None;
    }
    // (M^-1)^T = cofactor matrix / det
    let mut n = [0.0f32; 16];
    for c in 0..3 {
        for r in 0..3 {
            n[4 * c + r] = (cof(r, c) / det) as f32;
        }
    }
    n[15] = 1.0;
    Some(n)
}

impl Geometry {
    /// Refuse what cannot be drawn, naming the mesh or instance: a normal count that is not
    /// the position count, an index count not a multiple of 3, an index out of range, a
    /// non-finite position, an instance of a mesh that does not exist, a transform that is
    /// not finite, not affine or singular, and counts over `limits`.
    pub fn check(&self, limits: &wgpu::Limits) -> Result<()> {
        let bad = |m: String| Err(RuntimeError::Param(m));
        for (i, m) in self.meshes.iter().enumerate() {
            let name = if m.name.is_empty() {
                format!("mesh {i}")
            } else {
                format!("mesh {i} (`{}`)", m.name)
            };
            if m.normals.len() != m.positions.len() {
                return bad(format!(
                    "{name} has {} normals for {} positions",
                    m.normals.len(),
                    m.positions.len()
                ));
            }
            if m.indices.len() % 3 != 0 {
                return bad(format!("{name} has {} indices, not a multiple of 3", m.indices.len()));
            }
            if let Some((k, ix)) = m.indices.iter().enumerate().find(|(_, ix)| **ix as usize >= m.positions.len()) {
                return bad(format!(
                    "{name}: index {k} is {ix}, out of range of its {} vertices",
                    m.positions.len()
                ));
            }
            if let Some(v) = m.positions.iter().chain(&m.normals).position(|p| !p.iter().all(|c| c.is_finite())) {
                return bad(format!("{name}: vertex {} is not finite", v % m.positions.len().max(1)));
            }
        }
        if self.instances.len() > MAX_INSTANCES {
            return Err(RuntimeError::Limit {
                what: "instances of one geometry".into(),
                needed: self.instances.len() as u64,
                limit: MAX_INSTANCES as u64,
            });
        }
        for (i, inst) in self.instances.iter().enumerate() {
            let name = if inst.name.is_empty() {
                format!("instance {i}")
            } else {
                format!("instance {i} (`{}`)", inst.name)
            };
            if inst.mesh >= self.meshes.len() {
                return bad(format!(
                    "{name} places mesh {}, but there are {} meshes",
                    inst.mesh,
                    self.meshes.len()
                ));
            }
            check_transform(&inst.transform, &name)?;
        }
        let storage = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size);
        let sizes = [
            ("the meshes' vertices (bytes)", self.mesh_vertices() * 24, storage),
            (
                "the meshes' indices (bytes)",
                self.meshes.iter().map(|m| m.indices.len() as u64).sum::<u64>() * 4,
                limits.max_buffer_size,
            ),
            (
                "the placed vertices of every instance (bytes)",
                self.placed_vertices() * 24,
                storage,
            ),
            (
                "the instances' placement records (bytes)",
                self.instances.len() as u64 * RECORD_BYTES,
                limits.max_buffer_size,
            ),
        ];
        for (what, needed, limit) in sizes {
            if needed > limit {
                return Err(RuntimeError::Limit {
                    what: what.into(),
                    needed,
                    limit,
                });
            }
        }
        Ok(())
    }

    fn mesh_vertices(&self) -> u64 {
        self.meshes.iter().map(|m| m.positions.len() as u64).sum()
    }

    fn placed_vertices(&self) -> u64 {
        self.instances
            .iter()
            .map(|i| self.meshes.get(i.mesh).map_or(0, |m| m.positions.len() as u64))
            .sum()
    }

    /// Triangles drawn by the camera (every instance's).
    pub fn triangles(&self) -> u64 {
        self.instances
            .iter()
            .map(|i| self.meshes.get(i.mesh).map_or(0, |m| m.indices.len() as u64 / 3))
            .sum()
    }

    /// Bytes the GPU holds for this geometry: the meshes' vertices and indices, the placed
    /// vertices and the placement records.
    pub fn gpu_bytes(&self) -> u64 {
        let indices: u64 = self.meshes.iter().map(|m| m.indices.len() as u64).sum();
        self.mesh_vertices() * 24 + indices * 4 + self.placed_vertices() * 24 + self.instances.len() as u64 * RECORD_BYTES
    }

    /// The same triangles listed out, world space, casting instances first (in order),
    /// then the others: what [`SceneInputs::vertices`] holds for this geometry, its
    /// transforms applied on the CPU ([`transform_point`], and the normal matrix).
    pub fn soup(&self) -> (Vec<f32>, u32) {
        let mut out = Vec::new();
        let mut casting = 0;
        for pass in [true, false] {
            for inst in self.instances.iter().filter(|i| i.casts == pass) {
                let Some(m) = self.meshes.get(inst.mesh) else { continue };
                let n = normal_matrix(&inst.transform).unwrap_or(IDENTITY);
                for &ix in &m.indices {
                    let (p, q) = (m.positions[ix as usize], m.normals[ix as usize]);
                    out.extend(transform_point(&inst.transform, p));
                    out.extend([0, 1, 2].map(|r| n[r] * q[0] + n[4 + r] * q[1] + n[8 + r] * q[2]));
                }
            }
            if pass {
                casting = (out.len() / 6) as u32;
            }
        }
        (out, casting)
    }
}

/// The bounding box of the casting instances, world space: each instance's mesh box
/// (`boxes[i]`, object space) with its corners transformed; `None` without a casting vertex.
fn instances_bounds(boxes: &[Option<[[f32; 3]; 2]>], casts: &[bool], transforms: &[[f32; 16]]) -> Option<[[f32; 3]; 2]> {
    let corners = boxes
        .iter()
        .zip(casts)
        .zip(transforms)
        .filter(|((_, c), _)| **c)
        .filter_map(|((b, _), t)| b.map(|b| (b, t)))
        .flat_map(|(b, t)| (0..8).map(move |i| transform_point(t, [0, 1, 2].map(|a| b[(i >> a) & 1][a]))));
    box_of(corners)
}

fn box_of(points: impl Iterator<Item = [f32; 3]>) -> Option<[[f32; 3]; 2]> {
    points.fold(None, |b, p| {
        let [lo, hi] = b.unwrap_or([p, p]);
        Some([
            [lo[0].min(p[0]), lo[1].min(p[1]), lo[2].min(p[2])],
            [hi[0].max(p[0]), hi[1].max(p[1]), hi[2].max(p[2])],
        ])
    })
}

/// Refuse a transform that is not finite, not affine or singular, naming `what`.
pub(crate) fn check_transform(m: &[f32; 16], what: &str) -> Result<()> {
    if !m.iter().all(|c| c.is_finite()) {
        return Err(RuntimeError::Param(format!("{what}: its transform is not finite: {m:?}")));
    }
    if [m[3], m[7], m[11], m[15]] != [0.0, 0.0, 0.0, 1.0] {
        return Err(RuntimeError::Param(format!(
            "{what}: its transform is not affine (last row {:?}, not [0, 0, 0, 1])",
            [m[3], m[7], m[11], m[15]]
        )));
    }
    if normal_matrix(m).is_none() {
        return Err(RuntimeError::Param(format!("{what}: its transform is singular (no normal matrix)")));
    }
    Ok(())
}

/// One draw of the scene: a range of indices (or of vertices, without an index buffer)
/// with its base vertex, and whether the light's views draw it.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct DrawRange {
    pub elements: std::ops::Range<u32>,
    pub base_vertex: i32,
    pub casts: bool,
}

/// What a scene draw binds and draws: a triangle soup's vertex buffer (its casting
/// vertices first), or a host geometry's placed vertices with the meshes' index buffer.
#[derive(Clone)]
pub(crate) struct SceneDraw {
    pub vertices: wgpu::Buffer,
    pub indices: Option<wgpu::Buffer>,
    pub ranges: Vec<DrawRange>,
}

impl SceneDraw {
    /// A soup of `count` vertices, the first `casting` drawn from the light.
    pub fn soup(vertices: wgpu::Buffer, count: u32, casting: u32) -> SceneDraw {
        let casting = casting.min(count);
        SceneDraw {
            vertices,
            indices: None,
            ranges: [(0..casting, true), (casting..count, false)]
                .into_iter()
                .filter(|(r, _)| !r.is_empty())
                .map(|(elements, casts)| DrawRange {
                    elements,
                    base_vertex: 0,
                    casts,
                })
                .collect(),
        }
    }

    /// Record the draws into `rp` (the casting ones only when `from_light`).
    pub fn record(&self, rp: &mut wgpu::RenderPass<'_>, from_light: bool) {
        let mut ranges = self.ranges.iter().filter(|r| r.casts || !from_light).peekable();
        if ranges.peek().is_none() {
            return;
        }
        rp.set_vertex_buffer(0, self.vertices.slice(..));
        match &self.indices {
            Some(indices) => {
                rp.set_index_buffer(indices.slice(..), wgpu::IndexFormat::Uint32);
                for r in ranges {
                    rp.draw_indexed(r.elements.clone(), r.base_vertex, 0..1);
                }
            }
            None => {
                for r in ranges {
                    rp.draw(r.elements.clone(), 0..1);
                }
            }
        }
    }
}

const PLACE_WGSL: &str = "
struct Placement {
    model: mat4x4<f32>,
    normal: mat4x4<f32>,
    // first vertex of the mesh in the mesh buffer, vertices, first placed vertex
    src: u32,
    count: u32,
    dst: u32,
    pad: u32,
}
@group(0) @binding(0) var<uniform> place: Placement;
@group(0) @binding(1) var<storage, read> meshes: array<f32>;
@group(0) @binding(2) var<storage, read_write> placed: array<f32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x + id.y * 64u * 65535u;
    if i >= place.count {
        return;
    }
    let s = (place.src + i) * 6u;
    let d = (place.dst + i) * 6u;
    let p = place.model * vec4<f32>(meshes[s], meshes[s + 1u], meshes[s + 2u], 1.0);
    let n = place.normal * vec4<f32>(meshes[s + 3u], meshes[s + 4u], meshes[s + 5u], 0.0);
    placed[d] = p.x;
    placed[d + 1u] = p.y;
    placed[d + 2u] = p.z;
    placed[d + 3u] = n.x;
    placed[d + 4u] = n.y;
    placed[d + 5u] = n.z;
}
";

/// A host geometry on the GPU: the meshes, the placed vertices, the placement step, and
/// the draws. Shared by every light.
pub(crate) struct GeometryBuffers {
    pub draw: SceneDraw,
    records: wgpu::Buffer,
    pipeline: wgpu::ComputePipeline,
    group: wgpu::BindGroup,
    /// Per instance: its vertex count (the dispatch size).
    counts: Vec<u32>,
    /// Per instance: its mesh, its casting, its mesh's first vertex and first placed vertex.
    layout: Vec<(usize, u32, u32)>,
    /// Placement is due (the transforms changed since it last ran).
    pub dirty: bool,
    pub transforms: Vec<[f32; 16]>,
    /// Per instance: whether it casts, and its mesh's box (object space).
    casts: Vec<bool>,
    boxes: Vec<Option<[[f32; 3]; 2]>>,
}

impl GeometryBuffers {
    /// Upload `g` (checked) and create its placement step.
    pub fn new(gpu: &Gpu, g: &Geometry) -> Result<GeometryBuffers> {
        g.check(&gpu.limits)?;
        // the meshes, one after the other; the placed vertices, one instance after the other
        let mut vertex_first = Vec::new();
        let mut index_first = Vec::new();
        let (mut vertex_data, mut index_data) = (Vec::new(), Vec::new());
        for m in &g.meshes {
            vertex_first.push((vertex_data.len() / 24) as u32);
            index_first.push((index_data.len() / 4) as u32);
            for (p, n) in m.positions.iter().zip(&m.normals) {
                for c in p.iter().chain(n) {
                    vertex_data.extend(c.to_le_bytes());
                }
            }
            for ix in &m.indices {
                index_data.extend(ix.to_le_bytes());
            }
        }
        let mut ranges = Vec::new();
        let mut places = Vec::new();
        let mut counts = Vec::new();
        let mut placed = 0u32;
        for inst in &g.instances {
            let m = &g.meshes[inst.mesh];
            let first = index_first[inst.mesh];
            ranges.push(DrawRange {
                elements: first..first + m.indices.len() as u32,
                base_vertex: i32::try_from(placed).map_err(|_| RuntimeError::Limit {
                    what: "placed vertices (a base vertex is an i32)".into(),
                    needed: placed.into(),
                    limit: i32::MAX as u64,
                })?,
                casts: inst.casts,
            });
            places.push((inst.mesh, vertex_first[inst.mesh], placed));
            counts.push(m.positions.len() as u32);
            placed += m.positions.len() as u32;
        }
        gpu.scoped("uploading the host geometry", || {
            let device = &gpu.device;
            let buffer = |label: &str, size: u64, usage: wgpu::BufferUsages| {
                device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    // a binding may not be empty
                    size: size.max(24).next_multiple_of(4),
                    usage,
                    mapped_at_creation: false,
                })
            };
            let copy = wgpu::BufferUsages::COPY_DST;
            let meshes = buffer("mesh vertices", vertex_data.len() as u64, wgpu::BufferUsages::STORAGE | copy);
            let indices = buffer("mesh indices", index_data.len() as u64, wgpu::BufferUsages::INDEX | copy);
            let placed_buf = buffer(
                "placed vertices",
                u64::from(placed) * 24,
                wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::VERTEX,
            );
            let records = buffer(
                "placement records",
                g.instances.len() as u64 * RECORD_BYTES,
                wgpu::BufferUsages::UNIFORM | copy,
            );
            if !vertex_data.is_empty() {
                gpu.queue.write_buffer(&meshes, 0, &vertex_data);
            }
            if !index_data.is_empty() {
                gpu.queue.write_buffer(&indices, 0, &index_data);
            }
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("place instances"),
                source: wgpu::ShaderSource::Wgsl(PLACE_WGSL.into()),
            });
            let entry = |binding, ty| wgpu::BindGroupLayoutEntry {
                binding,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty,
                count: None,
            };
            let storage = |read_only| wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only },
                has_dynamic_offset: false,
                min_binding_size: None,
            };
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("place instances"),
                entries: &[
                    entry(
                        0,
                        wgpu::BindingType::Buffer {
                            ty: wgpu::BufferBindingType::Uniform,
                            has_dynamic_offset: true,
                            min_binding_size: wgpu::BufferSize::new(RECORD_BYTES),
                        },
                    ),
                    entry(1, storage(true)),
                    entry(2, storage(false)),
                ],
            });
            let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("place instances"),
                bind_group_layouts: &[Some(&layout)],
                immediate_size: 0,
            });
            let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some("place instances"),
                layout: Some(&pipeline_layout),
                module: &module,
                entry_point: Some("main"),
                compilation_options: Default::default(),
                cache: None,
            });
            let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("place instances"),
                layout: &layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                            buffer: &records,
                            offset: 0,
                            size: wgpu::BufferSize::new(RECORD_BYTES),
                        }),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: meshes.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: placed_buf.as_entire_binding(),
                    },
                ],
            });
            let mut out = GeometryBuffers {
                draw: SceneDraw {
                    vertices: placed_buf,
                    indices: Some(indices),
                    ranges,
                },
                records,
                pipeline,
                group,
                counts,
                layout: places,
                dirty: true,
                transforms: g.instances.iter().map(|i| i.transform).collect(),
                casts: g.instances.iter().map(|i| i.casts).collect(),
                boxes: g
                    .instances
                    .iter()
                    .map(|i| box_of(g.meshes[i.mesh].positions.iter().copied()))
                    .collect(),
            };
            out.write_records(&gpu.queue);
            out
        })
    }

    /// Set every instance's transform (checked: as many as instances, each finite, affine
    /// and invertible); placement runs in the next frame.
    pub fn set_transforms(&mut self, queue: &wgpu::Queue, transforms: &[[f32; 16]]) -> Result<()> {
        if transforms.len() != self.transforms.len() {
            return Err(RuntimeError::Param(format!(
                "{} transforms for {} instances: a new instance set is a new binding",
                transforms.len(),
                self.transforms.len()
            )));
        }
        for (i, t) in transforms.iter().enumerate() {
            check_transform(t, &format!("instance {i}"))?;
        }
        self.transforms.copy_from_slice(transforms);
        self.write_records(queue);
        Ok(())
    }

    /// Write every placement record and mark placement due.
    fn write_records(&mut self, queue: &wgpu::Queue) {
        let mut bytes = vec![0u8; self.transforms.len() * RECORD_BYTES as usize];
        for (i, (t, &(_, src, dst))) in self.transforms.iter().zip(&self.layout).enumerate() {
            let n = normal_matrix(t).unwrap_or(crate::geometry::IDENTITY);
            let r = &mut bytes[i * RECORD_BYTES as usize..];
            for (k, c) in t.iter().chain(&n).enumerate() {
                r[4 * k..4 * k + 4].copy_from_slice(&c.to_le_bytes());
            }
            for (k, w) in [src, self.counts[i], dst, 0].iter().enumerate() {
                r[128 + 4 * k..132 + 4 * k].copy_from_slice(&w.to_le_bytes());
            }
        }
        if !bytes.is_empty() {
            queue.write_buffer(&self.records, 0, &bytes);
        }
        self.dirty = true;
    }

    /// The casting instances' bounding box at the current transforms.
    pub fn caster_bounds(&self) -> Option<[[f32; 3]; 2]> {
        instances_bounds(&self.boxes, &self.casts, &self.transforms)
    }

    /// Record the placement of every instance, when it is due.
    pub fn record(&mut self, encoder: &mut wgpu::CommandEncoder) {
        if !self.dirty {
            return;
        }
        self.dirty = false;
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("place instances"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.pipeline);
        for (i, &count) in self.counts.iter().enumerate() {
            if count == 0 {
                continue;
            }
            pass.set_bind_group(0, &self.group, &[(i as u64 * RECORD_BYTES) as u32]);
            let groups = count.div_ceil(64);
            let (x, y) = if groups <= 65535 {
                (groups, 1)
            } else {
                (65535, groups.div_ceil(65535))
            };
            pass.dispatch_workgroups(x, y, 1);
        }
    }
}

/// The inputs of a light bound over host geometry: its sizes and views with no vertices
/// (the draws come from the geometry).
pub(crate) fn sized(
    camera: &crate::frame::Camera,
    light: &crate::frame::LightInputs,
    camera_size: (u32, u32),
    shadow_size: u32,
) -> SceneInputs {
    SceneInputs {
        vertices: Vec::new(),
        meshes: Vec::new(),
        casting_vertices: None,
        camera_view_proj: camera.view_proj,
        camera_position: camera.position,
        camera_size,
        shadow_size,
        light_view: light.view,
        light_view_proj: light.view_proj,
        light_position: light.position,
        near: light.near,
        far: light.far,
        light_size: light.size,
        light_half_extents: light.half_extents,
        light_angle: light.angle,
        light_proj_y: light.proj_y,
        light_orthographic: light.orthographic,
        samples: light.samples.clone(),
        samples_closed: light.samples_closed,
        light: light.kind,
    }
}
