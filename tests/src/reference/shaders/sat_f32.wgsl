// Summed-area table of f32 channels (`SummedArea(sum: F32)`, docs/language.md 8.7 "Tables
// over float channels"): per texel and channel, the f32 sum of v - centre over every texel
// above and to the left, inclusive, built as the u32 tables are: `rows` sums each row in
// order (one invocation per row and channel), `columns` then sums each column of those in
// order. Every addition rounds to f32; VSSM's error model bounds what that does.
// Layout: entry (x, y) of channel c (4 per layer) at ((c * size) + y) * size + x.

struct Params {
    size: u32,
    // the middle of the channel's range, subtracted before summing
    centre: f32,
}

@group(0) @binding(0) var src: texture_2d_array<f32>;
@group(0) @binding(1) var<storage, read_write> table: array<f32>;
@group(0) @binding(2) var<uniform> params: Params;

fn entry(c: u32, x: u32, y: u32) -> u32 {
    return (c * params.size + y) * params.size + x;
}

// id.x: the row, id.y: the channel
@compute @workgroup_size(64)
fn rows(@builtin(global_invocation_id) id: vec3<u32>) {
    let n = params.size;
    if (id.x >= n) {
        return;
    }
    let layer = id.y / 4u;
    let comp = id.y % 4u;
    var acc = 0.0;
    for (var x = 0u; x < n; x++) {
        let v = textureLoad(src, vec2<u32>(x, id.x), layer, 0)[comp];
        acc += v - params.centre;
        table[entry(id.y, x, id.x)] = acc;
    }
}

// id.x: the column, id.y: the channel
@compute @workgroup_size(64)
fn columns(@builtin(global_invocation_id) id: vec3<u32>) {
    let n = params.size;
    if (id.x >= n) {
        return;
    }
    var acc = 0.0;
    for (var y = 0u; y < n; y++) {
        let i = entry(id.y, id.x, y);
        acc += table[i];
        table[i] = acc;
    }
}
