// Summed-area table (Crow 1984; Annen 2008, 8.3.1) of images in u32 fixed point, as
// docs/language.md (8.7) describes: per texel and channel, the sum of the codes
// round(saturate(v) * scale) of every texel above and to the left, inclusive (scale 255 for
// CSSM's unorm8 channels; 65535 for MSSM's `sum: Fixed(bits: 16)` over [0, 1]). Two steps: `rows` sums
// each row (one invocation per row and channel), `columns` then sums each column of those
// (one invocation per column and channel). u32 additions wrap modulo 2^32; box sums taken
// as differences of four entries stay exact while the box's own sum stays below 2^32.
// Layout: entry (x, y) of channel c (4 per layer, counted from `first_channel`) at
// ((c * size) + y) * size + x.

struct Params {
    size: u32,
    first_channel: u32,
    // 2^B - 1: the largest code
    scale: f32,
}

@group(0) @binding(0) var src: texture_2d_array<f32>;
@group(0) @binding(1) var<storage, read_write> table: array<u32>;
@group(0) @binding(2) var<uniform> params: Params;

fn entry(c: u32, x: u32, y: u32) -> u32 {
    return ((params.first_channel + c) * params.size + y) * params.size + x;
}

// id.x: the row, id.y: the channel of this set
@compute @workgroup_size(64)
fn rows(@builtin(global_invocation_id) id: vec3<u32>) {
    let n = params.size;
    if (id.x >= n) {
        return;
    }
    let layer = id.y / 4u;
    let comp = id.y % 4u;
    var acc = 0u;
    for (var x = 0u; x < n; x++) {
        let v = textureLoad(src, vec2<u32>(x, id.x), layer, 0)[comp];
        acc += u32(round(saturate(v) * params.scale));
        table[entry(id.y, x, id.x)] = acc;
    }
}

// id.x: the column, id.y: the channel of this set
@compute @workgroup_size(64)
fn columns(@builtin(global_invocation_id) id: vec3<u32>) {
    let n = params.size;
    if (id.x >= n) {
        return;
    }
    var acc = 0u;
    for (var y = 0u; y < n; y++) {
        let i = entry(id.y, id.x, y);
        acc += table[i];
        table[i] = acc;
    }
}
