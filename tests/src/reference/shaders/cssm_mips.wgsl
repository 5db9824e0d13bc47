// CSSM lookups through mip chains (filter = 0): `expand_width(f, w)` and friends read
// every basis image trilinearly at level log2(max(w * size, 1)) (docs/language.md 8.7), with
// w = max(u.x, u.y) / sqrt(3) for a kernel u wide: a trilinear lookup at level log2(w n)
// spreads like a box sqrt(3) times wider (cssm.ron).

// layer l: (sin, cos) of orders 2l + 1, 2l + 2, blurred and mipmapped (Unorm8)
@group(0) @binding(2) var series_tex: texture_2d_array<f32>;
// layer l: (z sin, z cos) of orders 2l + 1, 2l + 2, then z/2 (F16)
@group(0) @binding(3) var weighted_tex: texture_2d_array<f32>;
@group(0) @binding(4) var linear_clamp: sampler;
@group(0) @binding(5) var<uniform> params: Params;
@group(0) @binding(6) var<storage, read> encoding: array<Encoding>;
// 2 a_k / c_k for k = 1..M
@group(0) @binding(7) var<storage, read> amplitude: array<f32>;

fn lod_of(u: vec2<f32>) -> f32 {
    let w = 0.57735026 * max(u.x, u.y);
    return log2(max(w * params.size, 1.0));
}

// the decoded channels of one layer of the CSM basis, filtered over the kernel u
fn series_texels(layer: u32, uv: vec2<f32>, u: vec2<f32>) -> vec4<f32> {
    let e = encoding[layer];
    return textureSampleLevel(series_tex, linear_clamp, uv, layer, lod_of(u)) * e.span + e.lo;
}

// the same for the z-weighted set (its encodings follow the CSM basis's)
fn weighted_texels(layer: u32, uv: vec2<f32>, u: vec2<f32>) -> vec4<f32> {
    let e = encoding[(params.orders + 1u) / 2u + layer];
    return textureSampleLevel(weighted_tex, linear_clamp, uv, layer, lod_of(u)) * e.span + e.lo;
}
