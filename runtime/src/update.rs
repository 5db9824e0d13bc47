//! The per-frame path: what changes every frame (the camera, the lights, the params, the
//! frame counter) written into the buffers that binding allocated ([`Resources`]).
//!
//! [`FrameWriter`] holds the queue and never the device, so nothing on this path can create
//! a texture, a buffer, a bind group or a pipeline: the no-reallocation rule is in the
//! types. Writes go through `Queue::write_buffer`, which wgpu applies at the next
//! submission, before its command buffers: one recording per submission sees the state
//! last written before it (last write wins).

use crate::frame::{Camera, LightInputs};
use crate::graph::{self, SampleViewUniform};
use crate::resources::{Resources, f32_bytes};

pub(crate) struct FrameWriter<'a> {
    queue: &'a wgpu::Queue,
}

impl<'a> FrameWriter<'a> {
    pub fn new(queue: &'a wgpu::Queue) -> FrameWriter<'a> {
        FrameWriter { queue }
    }

    /// Light `light`'s `Frame` uniforms (the centre's and every sample view's) and its
    /// `LightSamples`, seen by `camera`. The light's sample count is the bound one
    /// (checked by the caller).
    pub fn light(&self, res: &Resources, camera: &Camera, light: &LightInputs) {
        self.queue
            .write_buffer(&res.frame, 0, &light.frame(camera, res.shadow_size).to_bytes());
        for (k, buf) in res.sample_frames.iter().enumerate() {
            if let Some(f) = light.sample_frame(camera, res.shadow_size, k) {
                self.queue.write_buffer(buf, 0, &f.to_bytes());
            }
        }
        if !light.samples.is_empty() {
            self.queue.write_buffer(
                &res.light_samples,
                0,
                &SampleViewUniform::to_bytes(&light.light_samples(res.shadow_size)),
            );
        }
    }

    /// The `counters` field (`counters.x`: frames run since the scene was bound) of every
    /// `Frame` buffer of `res`.
    pub fn counters(&self, res: &Resources, frame: u32) {
        // internal invariant: `FrameUniform` has the field (the frame layout tests check it)
        let field = graph::FRAME_FIELDS
            .iter()
            .position(|f| f.name == "counters")
            .expect("the Frame uniform has a `counters` field");
        let at = graph::frame_offset(field) as u64;
        let counters = [frame as f32, 0.0, 0.0, 0.0];
        for buf in std::iter::once(&res.frame).chain(&res.sample_frames) {
            self.queue.write_buffer(buf, at, &f32_bytes(&counters));
        }
    }

    /// The `Params` uniform.
    pub fn params(&self, buf: &wgpu::Buffer, bytes: &[u8]) {
        self.queue.write_buffer(buf, 0, bytes);
    }
}
