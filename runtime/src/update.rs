//! The per-frame path: what changes every frame (the camera, the lights, the params, the
//! frame counter) written into the buffers that binding allocated ([`Resources`]).
//!
//! Each light keeps its uniforms on the CPU ([`LightUniforms`]): setting the camera or a
//! light recomputes them there, and recording a frame writes each `Frame` buffer once, with
//! that frame's counter, and the `LightSamples` and `Params` uniforms only when they
//! changed. [`FrameWriter`] holds the queue and never the device, so nothing on this path
//! can create a texture, a buffer, a bind group or a pipeline: the no-reallocation rule is
//! in the types. Writes go through `Queue::write_buffer`, which wgpu applies at the next
//! submission, before its command buffers: one recording per submission sees the state
//! last written before it (last write wins).

use crate::frame::{Camera, LightInputs};
use crate::graph::{FrameUniform, SampleViewUniform};
use crate::resources::{Resources, pack_frames};

/// One light's uniforms as the next frame writes them. Set again in place (its vectors
/// keep their capacity): setting a camera or a light allocates nothing once the light's
/// number of samples is bound.
pub(crate) struct LightUniforms {
    /// The centre view's `Frame` and each light sample's.
    centre: FrameUniform,
    samples: Vec<FrameUniform>,
    /// Their bytes as [`Resources::frames`] holds them (one `Frame` every `stride` bytes),
    /// made once: each frame writes them with one `write_buffer`.
    bytes: Vec<u8>,
    stride: usize,
    /// The `LightSamples` uniform, and whether it changed since it was last written.
    light_samples: Vec<SampleViewUniform>,
    light_samples_pending: bool,
}

impl LightUniforms {
    /// The uniforms of `light` seen by `camera`; the `LightSamples` pending when `fresh`
    /// (binding has just written them: not pending).
    /// `stride`: the bytes between two views' `Frame`s ([`Resources::frame_stride`]).
    pub fn new(camera: &Camera, light: &LightInputs, shadow_size: u32, stride: u64, fresh: bool) -> LightUniforms {
        let stride = stride as usize;
        let mut u = LightUniforms {
            centre: FrameUniform::default(),
            samples: Vec::with_capacity(light.samples.len()),
            bytes: vec![0; stride * (1 + light.samples.len())],
            stride,
            light_samples: Vec::with_capacity(light.samples.len()),
            light_samples_pending: false,
        };
        u.set(camera, light, shadow_size, fresh);
        u
    }

    /// Light `light` seen by `camera`, in place; its `LightSamples` pending unless `fresh`.
    pub fn set(&mut self, camera: &Camera, light: &LightInputs, shadow_size: u32, fresh: bool) {
        self.set_camera(camera, light, shadow_size);
        light.write_light_samples(shadow_size, &mut self.light_samples);
        self.light_samples_pending = !fresh && !light.samples.is_empty();
    }

    /// A new camera: the `Frame` uniforms change, the `LightSamples` do not.
    pub fn set_camera(&mut self, camera: &Camera, light: &LightInputs, shadow_size: u32) {
        self.centre = light.frame(camera, shadow_size);
        self.samples.clear();
        self.samples
            .extend((0..light.samples.len()).filter_map(|k| light.sample_frame(camera, shadow_size, k)));
    }
}

pub(crate) struct FrameWriter<'a> {
    queue: &'a wgpu::Queue,
}

impl<'a> FrameWriter<'a> {
    pub fn new(queue: &'a wgpu::Queue) -> FrameWriter<'a> {
        FrameWriter { queue }
    }

    /// Write light `u`'s uniforms into `res` for frame `frame` (`counters.x`: frames run
    /// since the scene was bound): every view's `Frame` in one write (each `write_buffer`
    /// stages through a buffer of its own), the `LightSamples` if they changed.
    pub fn light(&self, res: &Resources, u: &mut LightUniforms, frame: u32) {
        for f in std::iter::once(&mut u.centre).chain(u.samples.iter_mut()) {
            f.counters[0] = frame as f32;
        }
        pack_frames(&mut u.bytes, u.stride, std::iter::once(&u.centre).chain(&u.samples));
        self.queue.write_buffer(&res.frames, 0, &u.bytes);
        if std::mem::take(&mut u.light_samples_pending) {
            self.queue
                .write_buffer(&res.light_samples, 0, &SampleViewUniform::light_samples_array(&u.light_samples));
        }
    }

    /// The `Params` uniform.
    pub fn params(&self, buf: &wgpu::Buffer, bytes: &[u8]) {
        self.queue.write_buffer(buf, 0, bytes);
    }
}
