//! A hand-written WGSL twin (`shaders/linear.wgsl`) of the f64 linear-light reference
//! ([`super::linear`], Heidrich, Brabec & Seidel 2000, section 3.2), independent of the
//! compiler's code generator, to compare with it channel by channel.
//!
//! One compute dispatch per visibility channel (source view `i`, target view `j`), one
//! invocation per texel of view `j`, in f32: it loops over every triangle of view `i`'s mesh,
//! runs the skin detector on the depth map of view `i` itself, places the skin's corners in the
//! world, projects and tests them at the texel centre, interpolates, keeps and depth-tests.
//! Uploaded from the CPU (as f32): the two views' matrices, near and far, the technique's
//! `skin_threshold` and `keep_bias`, and the depth maps of views `i` and `j` (the Depth pass;
//! callers pass the f64 reference's [`super::linear::LinearMaps::depth`]). The detector,
//! corner placement, projection, rasterisation and interpolation are written anew in WGSL.
//! Not covered: skins with a corner at or behind view `j`'s eye (skipped; the f64 reference
//! ray-casts them).

use super::compute::{self, Input};
use super::linear::{Interpolation, LinearSetup};
use sshc_runtime::gpu::Gpu;

const SHADER: &str = include_str!("shaders/linear.wgsl");

/// One visibility channel as the WGSL reference writes it, per texel (row-major), f32.
#[derive(Clone, Debug, PartialEq)]
pub struct GpuChannel {
    pub size: usize,
    /// The channel (0.5 where no skin was kept).
    pub value: Vec<f32>,
    /// The winning fragment's linear depth (NaN where none).
    pub depth: Vec<f32>,
    /// The winning skin's index, `2 (y (S - 1) + x) + half` (as [`super::linear::Skin::index`]).
    pub winner: Vec<Option<u32>>,
}

/// Both channels of every sample.
#[derive(Clone, Debug, PartialEq)]
pub struct GpuLinearChannels {
    pub v_prev: Vec<GpuChannel>,
    pub v_next: Vec<GpuChannel>,
}

fn words(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// The channel of view `j` made of the skins of view `i`, from their depth maps.
pub fn warp_gpu(gpu: &Gpu, setup: &LinearSetup, depth_i: &[f64], depth_j: &[f64], i: usize, j: usize) -> Result<GpuChannel, String> {
    setup.check()?;
    let n = setup.size;
    if i >= setup.views.len() || j >= setup.views.len() {
        return Err(format!("views {i} and {j}: the set-up has {}", setup.views.len()));
    }
    if depth_i.len() != n * n || depth_j.len() != n * n {
        return Err(format!("the depth maps must hold {} texels", n * n));
    }
    let groups = (n as u32).div_ceil(8);
    if groups > gpu.limits.max_compute_workgroups_per_dimension {
        return Err(format!("a {n} x {n} map needs more workgroups than one dispatch takes"));
    }
    let (vi, vj) = (&setup.views[i], &setup.views[j]);
    let mut params: Vec<f32> = Vec::with_capacity(72);
    for m in [&vi.view, &vi.view_proj, &vj.view, &vj.view_proj] {
        params.extend(m.iter().map(|&x| x as f32));
    }
    let mut bytes = words(&params);
    bytes.extend_from_slice(&(n as u32).to_le_bytes());
    let screen = u32::from(setup.interpolation == Interpolation::Screen);
    bytes.extend_from_slice(&screen.to_le_bytes());
    bytes.extend_from_slice(&words(&[
        setup.skin_threshold as f32,
        setup.keep_bias as f32,
        vi.near as f32,
        vi.far as f32,
        vj.near as f32,
        vj.far as f32,
    ]));
    let di: Vec<f32> = depth_i.iter().map(|&z| z as f32).collect();
    let dj: Vec<f32> = depth_j.iter().map(|&z| z as f32).collect();
    let run = || -> Result<GpuChannel, String> {
        let storage = wgpu::BufferUsages::STORAGE;
        let inputs = [
            Input {
                label: "linear params",
                bytes: &bytes,
                usage: wgpu::BufferUsages::UNIFORM,
            },
            Input {
                label: "linear depth i",
                bytes: &words(&di),
                usage: storage,
            },
            Input {
                label: "linear depth j",
                bytes: &words(&dj),
                usage: storage,
            },
        ];
        let texels = (n * n) as u64;
        let out = compute::run(gpu, "linear.wgsl", SHADER, &inputs, &[16 * texels, 4 * texels], (groups, groups))?;
        let f: Vec<f32> = out[0]
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        let winner: Vec<Option<u32>> = out[1]
            .chunks_exact(4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .map(|k| (k != u32::MAX).then_some(k))
            .collect();
        let depth = f
            .iter()
            .skip(1)
            .step_by(4)
            .zip(&winner)
            .map(|(&d, w)| if w.is_some() { d } else { f32::NAN })
            .collect();
        Ok(GpuChannel {
            size: n,
            value: f.iter().step_by(4).copied().collect(),
            depth,
            winner,
        })
    };
    gpu.scoped("running the hand-written WGSL linear-light warp", run)
        .map_err(|e| e.to_string())?
}

/// Every channel of the set-up from the samples' depth maps (a cleared channel, 0.5, where a
/// sample has no neighbour on that side).
pub fn channels_gpu(gpu: &Gpu, setup: &LinearSetup, depth: &[Vec<f64>]) -> Result<GpuLinearChannels, String> {
    setup.check()?;
    if depth.len() != setup.views.len() {
        return Err(format!("{} depth maps for {} samples", depth.len(), setup.views.len()));
    }
    let n = setup.size;
    let clear = || GpuChannel {
        size: n,
        value: vec![0.5; n * n],
        depth: vec![f32::NAN; n * n],
        winner: vec![None; n * n],
    };
    let mut v_prev = Vec::new();
    let mut v_next = Vec::new();
    for j in 0..depth.len() {
        v_prev.push(match setup.prev_of(j) {
            Some(i) => warp_gpu(gpu, setup, &depth[i], &depth[j], i, j)?,
            None => clear(),
        });
        v_next.push(match setup.next_of(j) {
            Some(i) => warp_gpu(gpu, setup, &depth[i], &depth[j], i, j)?,
            None => clear(),
        });
    }
    Ok(GpuLinearChannels { v_prev, v_next })
}
