// CSSM lookups through summed-area tables (filter = 1): `sample_box(ch, wx, wy)` is the mean
// of the channel over the box wx x wy (uv units, at least one texel each way) centred at uv,
// clipped to the map (docs/language.md 8.7). The piecewise-constant texels are integrated
// exactly: per axis a partial first texel, whole texels and a partial last texel, each run
// of whole texels summed from the table in u32 (exact, whatever the wrapping), the partial
// ones weighted by their covered fraction. The centre is clamped to the map first (for uv
// outside it; the docs leave that case open).

// the u32 tables (sat.wgsl): the CSM basis's channels first, then the z-weighted set's
@group(0) @binding(2) var<storage, read> table: array<u32>;
@group(0) @binding(3) var<uniform> params: Params;
@group(0) @binding(4) var<storage, read> encoding: array<Encoding>;
// 2 a_k / c_k for k = 1..M
@group(0) @binding(5) var<storage, read> amplitude: array<f32>;

// one axis of the box: `box_axis` (box_runs.wgsl, appended)

// table entry (x, y) of channel c, 0 left of or above the map
fn entry(c: u32, x: i32, y: i32) -> u32 {
    if (x < 0 || y < 0) {
        return 0u;
    }
    let n = u32(params.size);
    return table[(c * n + u32(y)) * n + u32(x)];
}

// the sum of the codes of texels [x0, x1) x [y0, y1), modulo 2^32
fn block(c: u32, x0: i32, x1: i32, y0: i32, y1: i32) -> u32 {
    if (x1 <= x0 || y1 <= y0) {
        return 0u;
    }
    return entry(c, x1 - 1, y1 - 1) - entry(c, x0 - 1, y1 - 1) - entry(c, x1 - 1, y0 - 1) + entry(c, x0 - 1, y0 - 1);
}

// the mean of four channels (from `first`) over the box, in [0, 1] (codes / 255)
fn box_mean(first: u32, uv: vec2<f32>, u: vec2<f32>) -> vec4<f32> {
    let rx = box_axis(uv.x, u.x, params.size);
    let ry = box_axis(uv.y, u.y, params.size);
    var sum = vec4<f32>(0.0);
    for (var j = 0; j < 3; j++) {
        for (var i = 0; i < 3; i++) {
            let w = rx.weight[i] * ry.weight[j];
            if (w > 0.0) {
                for (var c = 0u; c < 4u; c++) {
                    sum[c] += w * f32(block(first + c, rx.start[i], rx.end[i], ry.start[j], ry.end[j]));
                }
            }
        }
    }
    return sum / (rx.length * ry.length * 255.0);
}

fn series_texels(layer: u32, uv: vec2<f32>, u: vec2<f32>) -> vec4<f32> {
    let e = encoding[layer];
    return box_mean(4u * layer, uv, u) * e.span + e.lo;
}

fn weighted_texels(layer: u32, uv: vec2<f32>, u: vec2<f32>) -> vec4<f32> {
    let first_layer = (params.orders + 1u) / 2u + layer;
    let e = encoding[first_layer];
    return box_mean(4u * first_layer, uv, u) * e.span + e.lo;
}
