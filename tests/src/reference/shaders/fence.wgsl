// Timing only: one invocation that reads and writes back the first visibility, dispatched
// in a compute pass of its own after the one of the Shade shader, carrying its end timestamp. The storage buffer's write-after-write
// makes wgpu put a barrier before it, and the barrier waits for the Shade dispatch: lavapipe
// writes a pass's end timestamp without waiting for the pass's last dispatch, so without
// this the reference's time would leave its Shade pass out.
@group(0) @binding(0) var<storage, read_write> visibility: array<f32>;

@compute @workgroup_size(1)
fn main() {
    visibility[0] = visibility[0];
}
