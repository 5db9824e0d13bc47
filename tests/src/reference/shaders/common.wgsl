// Shared by every Shade shader of the references: the receivers in, the visibility out.

struct Query {
    uv: vec2<f32>,
    // receiver depth from the light, normalised to [0, 1]
    d: f32,
    // level of detail of filtered lookups
    lod: f32,
}

@group(0) @binding(0) var<storage, read> queries: array<Query>;
@group(0) @binding(1) var<storage, read_write> visibility: array<f32>;

// The Shade pass's output: clamped to [0, 1], NaN reads as 1 (lit). The NaN test reads the
// bits, which no assumption that floats are finite can fold away.
fn store_visibility(i: u32, v: f32) {
    let nan = (bitcast<u32>(v) & 0x7fffffffu) > 0x7f800000u;
    visibility[i] = select(saturate(v), 1.0, nan);
}
