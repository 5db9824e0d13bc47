//! A hand-written WGSL penumbra map (`shaders/penumbra.wgsl`, Wyman & Hansen 2003, section
//! 3), independent of the compiler's code generator, to compare with the f64 reference
//! ([`super::penumbra`]) texel by texel.
//!
//! One compute invocation per texel intersects the texel's light ray in f32 with every cone
//! and sheet of [`Primitives`] analytically (the cone as a circular cone around the light
//! ray through its vertex, the sheet as the bilinear patch `v0 v1 T1 T0`; no
//! tessellation, no rasterisation), discards fragments with `Z_F > Z_P`, applies equation 1
//! and `s = 3 I^2 - 2 I^3`, resolves by the setup's rule and writes the value and the number
//! of kept fragments. The shadow map's view depths `Z_P` ([`ShadowMap::depth`]) and the
//! primitives (view space) are uploaded as f32; the conventions are the f64 reference's
//! (texel centres, row 0 at the top, `Z = -z`, the ray parameter is the depth).
//!
//! Records (storage buffers of `vec4<f32>`):
//! - cone: `[tip.x, tip.y, tip.z, Z_v]`, `[k, 0, 0, 0]`, `k` the radius growth per unit of
//!   depth ([`PenumbraSetup::spread`]);
//! - sheet: `[v0, Z_v0]`, `[v1, Z_v1]`, `[t0, k(Z_v0)]`, `[t1, k(Z_v1)]`.
//!
//! Primitives with `k <= 0` (a light of radius 0) have no area and draw nothing, so the map
//! is then exactly 1. [`Target::F16`] rounds each stored value with `quantizeToF16`, as an
//! `r16float` target stores it (WGSL lets that conversion round either way to a neighbour,
//! so results are within one f16 ulp of the f32 map).

use super::compute::{self, Input};
use super::penumbra::{LightProjection, PenumbraSetup, Primitives, Resolve, ShadowMap};
use sshc_runtime::gpu::Gpu;

const SHADER: &str = include_str!("shaders/penumbra.wgsl");

/// The precision the map is stored at.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target {
    F32,
    /// Rounded to binary16, as an `r16float` colour target stores it.
    F16,
}

/// The GPU penumbra map: per texel the resolved value and the number of kept fragments.
#[derive(Clone, Debug, PartialEq)]
pub struct GpuPenumbra {
    pub size: usize,
    pub value: Vec<f32>,
    pub fragments: Vec<u32>,
}

/// The penumbra map in f32 (see the module documentation).
pub fn penumbra_map_gpu(gpu: &Gpu, setup: &PenumbraSetup, shadow: &ShadowMap, prims: &Primitives) -> Result<Vec<f32>, String> {
    penumbra_map_gpu_at(gpu, setup, shadow, prims, Target::F32).map(|m| m.value)
}

/// The penumbra map rounded to f16 as an `r16float` target would store it.
pub fn penumbra_map_gpu_f16(gpu: &Gpu, setup: &PenumbraSetup, shadow: &ShadowMap, prims: &Primitives) -> Result<Vec<f32>, String> {
    penumbra_map_gpu_at(gpu, setup, shadow, prims, Target::F16).map(|m| m.value)
}

fn words(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// The records of the cones and sheets (at least one record each: wgpu binds no empty
/// buffer; the counts in the parameters say how many are used).
fn records(setup: &PenumbraSetup, prims: &Primitives) -> (Vec<f32>, Vec<f32>) {
    let mut cones = Vec::with_capacity(8 * prims.cones.len().max(1));
    for c in &prims.cones {
        let t = c.tip.map(|x| x as f32);
        cones.extend_from_slice(&[t[0], t[1], t[2], c.z_v as f32, c.spread as f32, 0.0, 0.0, 0.0]);
    }
    let mut sheets = Vec::with_capacity(16 * prims.sheets.len().max(1));
    for s in &prims.sheets {
        let f = |p: [f64; 3], w: f64| [p[0] as f32, p[1] as f32, p[2] as f32, w as f32];
        sheets.extend_from_slice(&f(s.v0, s.z_v0));
        sheets.extend_from_slice(&f(s.v1, s.z_v1));
        sheets.extend_from_slice(&f(s.t0, setup.spread(s.z_v0)));
        sheets.extend_from_slice(&f(s.t1, setup.spread(s.z_v1)));
    }
    if cones.is_empty() {
        cones.resize(8, 0.0);
    }
    if sheets.is_empty() {
        sheets.resize(16, 0.0);
    }
    (cones, sheets)
}

/// The penumbra map at `target` precision, with the fragment counts.
pub fn penumbra_map_gpu_at(
    gpu: &Gpu,
    setup: &PenumbraSetup,
    shadow: &ShadowMap,
    prims: &Primitives,
    target: Target,
) -> Result<GpuPenumbra, String> {
    setup.check()?;
    let n = setup.size;
    if shadow.size != n || shadow.depth.len() != n * n {
        return Err(format!(
            "the shadow map is {0} x {0} ({1} texels), the setup {n} x {n}",
            shadow.size,
            shadow.depth.len()
        ));
    }
    let (cones, sheets) = records(setup, prims);
    let limit = gpu.limits.max_storage_buffer_binding_size;
    let biggest = (4 * cones.len().max(sheets.len()).max(n * n)) as u64;
    if biggest > limit {
        return Err(format!("{biggest} bytes exceed the device's storage buffer limit of {limit}"));
    }
    let groups = (n as u32).div_ceil(8);
    if groups > gpu.limits.max_compute_workgroups_per_dimension {
        return Err(format!("a {n} x {n} map needs more workgroups than one dispatch takes"));
    }
    let (orthographic, scale) = match setup.projection {
        LightProjection::Perspective { f } => (0u32, f as f32),
        LightProjection::Orthographic { half_height } => (1u32, half_height as f32),
    };
    let resolve = match setup.resolve {
        Resolve::KeepMin => 0u32,
        Resolve::KeepMax => 1,
        Resolve::Add => 2,
        Resolve::Multiply => 3,
    };
    let mut params: Vec<u8> = Vec::with_capacity(48);
    for w in [
        n as u32,
        orthographic,
        resolve,
        (target == Target::F16) as u32,
        prims.cones.len() as u32,
        prims.sheets.len() as u32,
    ] {
        params.extend_from_slice(&w.to_le_bytes());
    }
    params.extend_from_slice(&words(&[scale, setup.near as f32, setup.far as f32, 0.0, 0.0, 0.0]));
    let depth: Vec<f32> = shadow.depth.iter().map(|&z| z as f32).collect();

    let run = || -> Result<GpuPenumbra, String> {
        let storage = wgpu::BufferUsages::STORAGE;
        let bytes = 4 * (n * n) as u64;
        let inputs = [
            Input {
                label: "penumbra params",
                bytes: &params,
                usage: wgpu::BufferUsages::UNIFORM,
            },
            Input {
                label: "penumbra Z_P",
                bytes: &words(&depth),
                usage: storage,
            },
            Input {
                label: "penumbra cones",
                bytes: &words(&cones),
                usage: storage,
            },
            Input {
                label: "penumbra sheets",
                bytes: &words(&sheets),
                usage: storage,
            },
        ];
        let out = compute::run(gpu, "penumbra.wgsl", SHADER, &inputs, &[bytes, bytes], (groups, groups))?;
        let (v, c) = (&out[0], &out[1]);
        Ok(GpuPenumbra {
            size: n,
            value: v.chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect(),
            fragments: c.chunks_exact(4).map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect(),
        })
    };
    gpu.scoped("running the hand-written WGSL penumbra map", run)
        .map_err(|e| e.to_string())?
}
