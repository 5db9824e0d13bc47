// Moment shadow mapping, Hamburger 4MSM (Peters & Klein 2015, Algorithm 2): bias the
// filtered moments towards (1/2, 1/2, 1/2, 1/2), solve the 3 x 3 Hankel system for c by a
// Cholesky factorisation, take the roots z2 <= z3 of c1 + c2 z + c3 z^2, and bound the
// shadow intensity G from below by the three cases; the visibility is 1 - G. The pivots
// are clamped below at 1e-12 (the boundary of the moment space, where every filtered depth
// is 0 or every one is 1, is read as the limit of the positive-definite case).

struct Params {
    alpha: f32,
    bias: f32,
}

// (b1, b2, b3, b4) = E[(z, z^2, z^3, z^4)] in layer 0, blurred and mipmapped
@group(0) @binding(2) var moments: texture_2d_array<f32>;
@group(0) @binding(3) var linear_clamp: sampler;
@group(0) @binding(4) var<uniform> params: Params;

// the bound: hamburger.wgsl (appended)
fn intensity(b: vec4<f32>, zf: f32) -> f32 {
    return hamburger_intensity(hamburger_roots(b, zf), b, zf);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= arrayLength(&queries)) {
        return;
    }
    let q = queries[id.x];
    let m = textureSampleLevel(moments, linear_clamp, q.uv, 0, q.lod);
    let b = (1.0 - params.alpha) * m + params.alpha * 0.5;
    store_visibility(id.x, 1.0 - intensity(b, q.d - params.bias));
}
