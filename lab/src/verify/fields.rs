//! The inputs verify runs on: the synthetic depth fields, the depth map a scene renders
//! from its light, and what an input gives the passes (a depth map or caster meshes).

use crate::run::Loaded;
use sshc_runtime::gpu::Gpu;
use std::path::Path;

/// Deterministic noise in [0, 1) (a 64-bit LCG hashed per texel).
pub fn noise(i: u64) -> f32 {
    let mut x = i.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
    x ^= x >> 33;
    x = x.wrapping_mul(0xff51afd7ed558ccd);
    x ^= x >> 33;
    (x >> 40) as f32 / (1u64 << 24) as f32
}

/// The synthetic depth fields, by name.
pub const FIELDS: [&str; 6] = ["ramp", "step", "checker", "noise", "zero", "one"];

/// A synthetic depth field of `n` x `n` texels, linear depth in [0, 1], by name
/// ([`FIELDS`]); `None` for another name.
pub fn depth_field(name: &str, n: u32) -> Option<Vec<f32>> {
    let n = n as usize;
    let texel = |k: usize| -> Option<f32> {
        let (i, j) = (k % n, k / n);
        let (u, v) = ((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
        Some(match name {
            // occluders rising across the map, crossing the receiver's depth ramp
            "ramp" => 0.1 + 0.8 * v,
            // a straight occluder edge half way
            "step" => {
                if u < 0.5 {
                    0.3
                } else {
                    1.0
                }
            }
            "checker" => {
                if ((i / 4) + (j / 4)) % 2 == 0 {
                    0.2
                } else {
                    0.8
                }
            }
            "noise" => noise(k as u64),
            "zero" => 0.0,
            "one" => 1.0,
            _ => return None,
        })
    };
    (0..n * n).map(texel).collect()
}

/// The depth map a scene renders from its (first) light, `n` x `n`, with the bundled hard
/// technique.
pub fn scene_depth(gpu: &Gpu, path: &Path, n: u32) -> Result<Vec<f32>, String> {
    let hard = include_str!("../../../techniques/hard.ron");
    let c = sshc::compile_str(hard, &sshc::CompileOptions::default()).map_err(|d| d.render("techniques/hard.ron", hard))?;
    let mut s = crate::session::load_scene(path, Some((8, 8)), Some(n))?;
    if s.lights.len() > 1 {
        s.lights.truncate(1);
    }
    let loaded = Loaded::new(gpu, c.graph.clone(), c.shaders.clone()).map_err(crate::session::rt)?;
    let mut ex = loaded.bind_scene(&crate::bind::scene_inputs(&s)?).map_err(crate::session::rt)?;
    ex.run_frame().map_err(crate::session::rt)?;
    let depth = c
        .graph
        .passes
        .iter()
        .find(|p| p.kind.is_depth())
        .ok_or("the hard technique has no Depth pass")?;
    Ok(ex
        .inspect()
        .read_texture(&depth.steps[0].writes[0].texture, 0, 0)
        .map_err(crate::session::rt)?
        .channel(0))
}

/// What an input gives the passes.
#[derive(Clone, Debug)]
pub enum Source {
    /// A depth map of the light's centre view, fed in place of the Depth pass's output
    /// (each light sample's view sees it translated by the sample's offset).
    Depth(Vec<f32>),
    /// Caster meshes above the query plane (triangles, position and normal per vertex, and
    /// their meshes): the Depth pass and Geometry passes rasterise them, and their outputs
    /// are read back and given to the CPU evaluation.
    Casters(Vec<f32>, Vec<std::ops::Range<u32>>),
}

/// One input to verify on.
#[derive(Clone, Debug)]
pub struct Input {
    pub name: String,
    pub source: Source,
}
