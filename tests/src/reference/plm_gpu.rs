//! A hand-written WGSL penumbra limit map (`shaders/plm.wgsl`, Lawlor 2006, section 3.1),
//! independent of the compiler's code generator, to compare with the f64 reference
//! ([`super::plm`]) texel by texel.
//!
//! One compute invocation per texel, in f32: for every ribbon it projects the edge's view-space
//! end points itself, builds the ribbon's rectangle (along and outward unit vectors, half-width
//! `reach_scale reach + 2 texels`), and at the texel centre computes `c`, `w`, `p_i` and the
//! depth-test key; the smallest key wins; `g = min(depth, key)`; then it casts the texel's ray
//! at every triangle, keeps the back-facing ones, and writes as `b` the nearest hit deeper than
//! `c + bias_b` (inside the silhouette, `p_i < 0`, deeper than the key + `bias_b`). Uploaded from the CPU (as f32): the silhouette edges of the f64 reference's
//! ribbons (view-space end points and which side is outward: the silhouette rule and the face
//! choice are shared, the ribbon geometry is not), the triangles in view space, and the
//! unraised nearest-surface depth (the Depth pass, [`PlmMaps::depth`]).

use super::compute::{self, Input};
use super::penumbra::LightProjection;
use super::plm::{PlmMaps, PlmReference, PlmSetup};
use sshc_runtime::gpu::Gpu;
use std::ops::Range;

type V3 = [f64; 3];

const SHADER: &str = include_str!("shaders/plm.wgsl");

/// The maps the WGSL reference writes, per texel (row-major, row 0 first), f32.
#[derive(Clone, Debug, PartialEq)]
pub struct GpuPlmMaps {
    pub size: usize,
    pub g: Vec<f32>,
    pub c: Vec<f32>,
    pub b: Vec<f32>,
    pub p_i: Vec<f32>,
    /// Index into [`PlmReference::ribbons`] of the winning ribbon.
    pub winner: Vec<Option<usize>>,
}

fn words(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// The WGSL maps of world-space `triangles` for the ribbons and depth of the f64 reference
/// `r` (built with the same `setup`). `meshes` is not read beyond a check of its ranges.
pub fn plm_maps_gpu(
    gpu: &Gpu,
    setup: &PlmSetup,
    triangles: &[[V3; 3]],
    meshes: &[Range<usize>],
    r: &PlmReference,
) -> Result<GpuPlmMaps, String> {
    setup.check()?;
    let light = &setup.light;
    let n = light.size;
    if r.maps.size != n || r.maps.depth.len() != n * n {
        return Err(format!("the reference's maps are {0} x {0}, the setup {n} x {n}", r.maps.size));
    }
    if let Some(m) = meshes.iter().find(|m| m.start > m.end || m.end > triangles.len()) {
        return Err(format!("mesh range {m:?} lies outside the {} triangles", triangles.len()));
    }
    let mut edges: Vec<f32> = Vec::with_capacity(8 * r.ribbons.len().max(1));
    for rb in &r.ribbons {
        let e = r.silhouettes.edges[rb.edge];
        let (a, b) = (r.silhouettes.vertices[e.a].position, r.silhouettes.vertices[e.b].position);
        // outward = sign perp(along), perp(v) = (-v.y, v.x)
        let perp = [-rb.along[1], rb.along[0]];
        let sign = (rb.outward[0] * perp[0] + rb.outward[1] * perp[1]).signum() as f32;
        edges.extend_from_slice(&[a[0] as f32, a[1] as f32, a[2] as f32, sign]);
        edges.extend_from_slice(&[b[0] as f32, b[1] as f32, b[2] as f32, 0.0]);
    }
    let mut tris: Vec<f32> = Vec::with_capacity(12 * triangles.len().max(1));
    for t in triangles {
        for p in t {
            let v = light.to_view(*p);
            tris.extend_from_slice(&[v[0] as f32, v[1] as f32, v[2] as f32, 0.0]);
        }
    }
    if edges.is_empty() {
        edges.resize(8, 0.0);
    }
    if tris.is_empty() {
        tris.resize(12, 0.0);
    }
    let limit = gpu.limits.max_storage_buffer_binding_size;
    let biggest = (4 * edges.len().max(tris.len()).max(4 * n * n)) as u64;
    if biggest > limit {
        return Err(format!("{biggest} bytes exceed the device's storage buffer limit of {limit}"));
    }
    let groups = (n as u32).div_ceil(8);
    if groups > gpu.limits.max_compute_workgroups_per_dimension {
        return Err(format!("a {n} x {n} map needs more workgroups than one dispatch takes"));
    }
    let (perspective, scale) = match light.projection {
        LightProjection::Perspective { f } => (1u32, f as f32),
        LightProjection::Orthographic { half_height } => (0u32, half_height as f32),
    };
    let mut params: Vec<u8> = Vec::with_capacity(48);
    for w in [n as u32, perspective, r.ribbons.len() as u32, triangles.len() as u32] {
        params.extend_from_slice(&w.to_le_bytes());
    }
    params.extend_from_slice(&words(&[
        scale,
        light.near as f32,
        light.far as f32,
        setup.spread() as f32,
        setup.bias_b as f32,
        setup.reach_scale as f32,
        0.0,
        0.0,
    ]));
    let depth: Vec<f32> = r.maps.depth.iter().map(|&z| z as f32).collect();

    let run = || -> Result<GpuPlmMaps, String> {
        let storage = wgpu::BufferUsages::STORAGE;
        let map_bytes = 16 * (n * n) as u64;
        let win_bytes = 4 * (n * n) as u64;
        let inputs = [
            Input {
                label: "plm params",
                bytes: &params,
                usage: wgpu::BufferUsages::UNIFORM,
            },
            Input {
                label: "plm depth",
                bytes: &words(&depth),
                usage: storage,
            },
            Input {
                label: "plm edges",
                bytes: &words(&edges),
                usage: storage,
            },
            Input {
                label: "plm triangles",
                bytes: &words(&tris),
                usage: storage,
            },
        ];
        let out = compute::run(gpu, "plm.wgsl", SHADER, &inputs, &[map_bytes, win_bytes], (groups, groups))?;
        let (m, w) = (&out[0], &out[1]);
        let f: Vec<f32> = m.chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect();
        let channel = |c: usize| f.iter().skip(c).step_by(4).copied().collect::<Vec<f32>>();
        Ok(GpuPlmMaps {
            size: n,
            g: channel(0),
            c: channel(1),
            b: channel(2),
            p_i: channel(3),
            winner: w
                .chunks_exact(4)
                .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .map(|k| (k != u32::MAX).then_some(k as usize))
                .collect(),
        })
    };
    gpu.scoped("running the hand-written WGSL penumbra limit map", run)
        .map_err(|e| e.to_string())?
}

/// The WGSL maps as [`PlmMaps`] (f64 copies of the f32 values, the depth the reference's),
/// so that the f64 lookup ([`super::plm::plm_visibility`]) can shade with them.
pub fn as_maps(gpu: &GpuPlmMaps, depth: &[f64]) -> PlmMaps {
    let f = |v: &[f32]| v.iter().map(|&x| x as f64).collect::<Vec<f64>>();
    PlmMaps {
        size: gpu.size,
        depth: depth.to_vec(),
        g: f(&gpu.g),
        c: f(&gpu.c),
        b: f(&gpu.b),
        p_i: f(&gpu.p_i),
        key: vec![f64::NAN; gpu.size * gpu.size],
        winner: gpu.winner.clone(),
    }
}
