//! A GPU buffer with room to grow, its space handed out in ranges of fixed-size elements:
//! how a [`crate::gpu::Scene`] takes a mesh or an instance added after its upload without
//! uploading the rest again.
//!
//! The free space is kept by `range-alloc` (gfx-rs's range allocator, best fit). A range
//! that does not fit grows the buffer to twice what it would hold: a new buffer, the
//! old contents copied into it on the GPU, submitted at once, so that the queue writes
//! that follow land after the copy. Growth is amortised: a grown buffer holds twice what
//! it then holds, so as many elements again fit with nothing created. What binds the buffer binds it again after a growth
//! ([`Pool::grown`]).

use crate::device::Gpu;
use crate::error::{Result, RuntimeError};
use range_alloc::RangeAllocator;
use std::ops::Range;

/// One buffer and its free ranges, in elements of `unit` bytes.
pub(crate) struct Pool {
    pub buffer: wgpu::Buffer,
    label: &'static str,
    usage: wgpu::BufferUsages,
    unit: u64,
    /// Its largest size in bytes (the device's buffer or storage-binding limit).
    limit: u64,
    free: RangeAllocator<u64>,
    /// Times the buffer was made again to grow.
    grown: u64,
}

/// A buffer's bytes for `elements` elements of `unit` bytes: a binding may not be empty,
/// and a storage binding's size is a multiple of 16.
pub(crate) fn buffer_bytes(elements: u64, unit: u64) -> u64 {
    (elements * unit).max(48).next_multiple_of(16)
}

impl Pool {
    /// Take `buffer` (made for `used` elements at its start, with `usage`), whose bytes are
    /// at most `limit`.
    pub fn adopt(buffer: wgpu::Buffer, label: &'static str, usage: wgpu::BufferUsages, unit: u64, used: u64, limit: u64) -> Pool {
        let capacity = buffer.size() / unit;
        let mut free = RangeAllocator::new(0..capacity);
        if used > 0 {
            // a fresh allocator hands out its first range from its start
            let taken = free.allocate_range(used);
            debug_assert_eq!(taken.ok(), Some(0..used));
        }
        Pool {
            buffer,
            label,
            usage,
            unit,
            limit,
            free,
            grown: 0,
        }
    }

    /// The usage every pool's buffer has on top of its own: written by the queue, copied
    /// into a grown one.
    pub const COPIES: wgpu::BufferUsages = wgpu::BufferUsages::COPY_DST.union(wgpu::BufferUsages::COPY_SRC);

    /// A range of `n` elements (`n` > 0), growing the buffer when none is free; refused when
    /// the grown buffer would pass the limit.
    pub fn alloc(&mut self, gpu: &Gpu, n: u64) -> Result<Range<u64>> {
        if let Ok(r) = self.free.allocate_range(n) {
            return Ok(r);
        }
        let capacity = self.free.initial_range().end;
        let at_most = self.limit / self.unit;
        // twice what it then holds: after a growth as much again fits with nothing made
        // (the free space at the end joins the new room, so `n` more always fits)
        let wanted = (capacity + n) * 2;
        let elements = wanted.min(at_most);
        if elements < capacity + n {
            return Err(RuntimeError::Limit {
                what: format!("{} (bytes, grown to take {n} more)", self.label),
                needed: (capacity + n) * self.unit,
                limit: self.limit,
            });
        }
        let bytes = buffer_bytes(elements, self.unit);
        let buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(self.label),
            size: bytes,
            usage: self.usage | Pool::COPIES,
            mapped_at_creation: false,
        });
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(self.label) });
        encoder.copy_buffer_to_buffer(&self.buffer, 0, &buffer, 0, self.buffer.size());
        gpu.queue.submit([encoder.finish()]);
        self.buffer = buffer;
        self.free.grow_to(bytes / self.unit);
        self.grown += 1;
        self.free.allocate_range(n).map_err(|_| RuntimeError::Limit {
            what: format!("{} (elements, after growing)", self.label),
            needed: n,
            limit: self.free.total_available(),
        })
    }

    /// Hand a range back.
    pub fn free(&mut self, r: Range<u64>) {
        if !r.is_empty() {
            self.free.free_range(r);
        }
    }

    /// Elements up to the end of the last range in use (what a dispatch over them covers).
    pub fn extent(&self) -> u64 {
        self.free.allocated_ranges().map(|r| r.end).max().unwrap_or(0)
    }

    /// Times the buffer was made again to grow: whatever bound the old one binds again.
    pub fn grown(&self) -> u64 {
        self.grown
    }

    /// What it holds, for errors.
    pub fn label(&self) -> &'static str {
        self.label
    }

    /// Byte offset of element `at`.
    pub fn offset(&self, at: u64) -> u64 {
        at * self.unit
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn buffer_bytes_are_never_empty_and_multiples_of_16() {
        assert_eq!(buffer_bytes(0, 24), 48);
        assert_eq!(buffer_bytes(3, 24), 80);
        assert_eq!(buffer_bytes(4, 256), 1024);
    }
}
