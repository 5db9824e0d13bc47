//! GPU timestamps read back a frame or more later, from a small ring of buffers: recording
//! a frame never waits for an earlier one.
//!
//! Each slot of the ring holds a query set (two timestamps per pass and light), the buffer
//! it resolves into and a readable copy. A frame takes the slot of its number modulo
//! [`RING`] if that slot is free, and records untimed otherwise (the GPU is more than
//! [`RING`] frames behind). Once the frame is submitted, the slot's copy is mapped; when the
//! mapping completes (found by a non-blocking poll), its times become the newest
//! [`FrameTimes`] and the slot is free again.

use crate::device::Gpu;
use crate::error::{Result, RuntimeError};
use crate::steps::Stamps;
use std::sync::Arc;
use std::sync::atomic::{AtomicU8, Ordering};

/// Slots in the ring: frames whose times may be pending at once.
pub(crate) const RING: usize = 3;

/// GPU time of each pass of one frame, in milliseconds (None without timestamp queries).
#[derive(Clone, Debug, PartialEq)]
pub struct FrameTimes {
    /// Each pass's time, summed over the lights when several are bound.
    pub passes: Vec<(String, Option<f64>)>,
    /// Each light's time: the sum of its passes (one entry when one light is bound).
    pub lights: Vec<Option<f64>>,
}

impl FrameTimes {
    /// A frame without times: every pass and light `None`.
    pub(crate) fn untimed(passes: &[String], lights: usize) -> FrameTimes {
        FrameTimes {
            passes: passes.iter().map(|p| (p.clone(), None)).collect(),
            lights: vec![None; lights],
        }
    }
}

const FREE: u8 = 0;
/// Recorded into an encoder: mapped once the frame is submitted.
const RECORDED: u8 = 1;
const MAPPING: u8 = 2;
const MAPPED: u8 = 3;
const FAILED: u8 = 4;

struct Slot {
    set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    read: wgpu::Buffer,
    state: Arc<AtomicU8>,
    /// The frame recorded into it.
    frame: u64,
}

/// The ring, sized for `passes` passes times `lights` lights.
pub(crate) struct Timestamps {
    slots: Vec<Slot>,
    passes: Vec<String>,
    lights: usize,
    /// The newest frame whose times came back, and its times.
    latest: Option<(u64, FrameTimes)>,
}

impl Timestamps {
    /// The ring, or `None` on a device without timestamp queries.
    pub fn new(gpu: &Gpu, passes: Vec<String>, lights: usize) -> Option<Timestamps> {
        if !gpu.features.contains(wgpu::Features::TIMESTAMP_QUERY) {
            return None;
        }
        let n = (passes.len() * lights * 2) as u32;
        let slots = (0..RING)
            .map(|_| Slot {
                set: gpu.device.create_query_set(&wgpu::QuerySetDescriptor {
                    label: Some("pass times"),
                    ty: wgpu::QueryType::Timestamp,
                    count: n,
                }),
                resolve: gpu.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("timestamps"),
                    size: n as u64 * 8,
                    usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                }),
                read: gpu.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("timestamps read"),
                    size: n as u64 * 8,
                    usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                }),
                state: Arc::new(AtomicU8::new(FREE)),
                frame: 0,
            })
            .collect();
        Some(Timestamps {
            slots,
            passes,
            lights,
            latest: None,
        })
    }

    /// The slot frame `frame` records its timestamps into, if it is free (taken for it).
    pub fn begin(&mut self, frame: u64) -> Option<usize> {
        let i = (frame % RING as u64) as usize;
        let s = &mut self.slots[i];
        (s.state.load(Ordering::Acquire) == FREE).then(|| {
            s.frame = frame;
            i
        })
    }

    /// The writes of pass `pass` of light `light` into slot `slot`: its start (`first`)
    /// and end (`last`) timestamps.
    pub fn stamps(&self, slot: usize, light: usize, pass: usize, first: bool, last: bool) -> Stamps<'_> {
        let q = 2 * (light * self.passes.len() + pass) as u32;
        Stamps {
            set: &self.slots[slot].set,
            begin: first.then_some(q),
            end: last.then_some(q + 1),
        }
    }

    /// Resolve slot `slot`'s queries into its readable copy, at the end of the frame that
    /// took it ([`Timestamps::begin`]). A frame recorded twice resolves twice: the second
    /// recording's times are the ones read.
    pub fn finish(&self, encoder: &mut wgpu::CommandEncoder, slot: usize) {
        let s = &self.slots[slot];
        let n = (self.passes.len() * self.lights * 2) as u32;
        encoder.resolve_query_set(&s.set, 0..n, &s.resolve, 0);
        encoder.copy_buffer_to_buffer(&s.resolve, 0, &s.read, 0, n as u64 * 8);
        s.state.store(RECORDED, Ordering::Release);
    }

    /// Without waiting: map the slots of frames recorded (and, by the one-recording-per-
    /// submission rule, submitted) since the last call, poll the device once when `poll`
    /// (submissions also run the mapping callbacks), and take the times of every slot whose
    /// mapping has completed.
    pub fn collect(&mut self, gpu: &Gpu, poll: bool) -> Result<()> {
        for s in &self.slots {
            if s.state.load(Ordering::Acquire) == RECORDED {
                s.state.store(MAPPING, Ordering::Release);
                let state = s.state.clone();
                s.read.slice(..).map_async(wgpu::MapMode::Read, move |r| {
                    state.store(if r.is_ok() { MAPPED } else { FAILED }, Ordering::Release);
                });
            }
        }
        if poll {
            gpu.device
                .poll(wgpu::PollType::Poll)
                .map_err(|e| RuntimeError::Device(e.to_string()))?;
        }
        let period = gpu.queue.get_timestamp_period() as f64;
        for i in 0..self.slots.len() {
            let s = &self.slots[i];
            match s.state.load(Ordering::Acquire) {
                MAPPED => {
                    let frame = s.frame;
                    if self.latest.as_ref().is_none_or(|(f, _)| *f < frame) {
                        // the times written in place (made once): nothing is allocated
                        // per frame
                        let (latest, times) = self
                            .latest
                            .get_or_insert_with(|| (frame, FrameTimes::untimed(&self.passes, self.lights)));
                        *latest = frame;
                        if let Ok(view) = s.read.slice(..).get_mapped_range() {
                            let tick = |i: usize| {
                                view.get(8 * i..8 * i + 8)
                                    .map_or(0, |c| u64::from_le_bytes(c.try_into().unwrap_or([0; 8])))
                            };
                            times_into(tick, self.passes.len(), self.lights, period, times);
                        }
                    }
                    s.read.unmap();
                    s.state.store(FREE, Ordering::Release);
                }
                FAILED => {
                    s.state.store(FREE, Ordering::Release);
                }
                _ => {}
            }
        }
        Ok(())
    }

    /// The newest frame whose times came back, and its times.
    pub fn latest(&self) -> Option<&(u64, FrameTimes)> {
        self.latest.as_ref()
    }
}

/// Each pass's time (summed over lights) and each light's, from the raw ticks (`tick(q)`,
/// query `q`), written into `out` (made for `passes` passes and `lights` lights).
fn times_into(tick: impl Fn(usize) -> u64, passes: usize, lights: usize, period: f64, out: &mut FrameTimes) {
    let ms = |l: usize, i: usize| {
        let (a, z) = (tick(2 * (l * passes + i)), tick(2 * (l * passes + i) + 1));
        (z >= a && a > 0).then(|| (z - a) as f64 * period * 1e-6)
    };
    for (i, (_, t)) in out.passes.iter_mut().enumerate() {
        *t = (0..lights).map(|l| ms(l, i)).sum();
    }
    for (l, t) in out.lights.iter_mut().enumerate() {
        *t = (0..passes).map(|i| ms(l, i)).sum();
    }
}
