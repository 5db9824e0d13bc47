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

const PIVOT: f32 = 1e-12;

fn intensity(b: vec4<f32>, zf: f32) -> f32 {
    // [1 b1 b2; b1 b2 b3; b2 b3 b4] = L L^T, L = [1 0 0; b1 l22 0; b2 l32 l33]
    let l22 = sqrt(max(b.y - b.x * b.x, PIVOT));
    let l32 = (b.z - b.x * b.y) / l22;
    let l33 = sqrt(max(b.w - b.y * b.y - l32 * l32, PIVOT));
    // forward substitution of (1, zf, zf^2), then back substitution
    let y2 = (zf - b.x) / l22;
    let y3 = (zf * zf - b.y - l32 * y2) / l33;
    let c3 = y3 / l33;
    let c2 = (y2 - l32 * c3) / l22;
    let c1 = 1.0 - b.x * c2 - b.y * c3;
    // roots of c3 z^2 + c2 z + c1
    let p = c2 / c3;
    let q = c1 / c3;
    let r = sqrt(max(0.25 * p * p - q, 0.0));
    let z2 = -0.5 * p - r;
    let z3 = -0.5 * p + r;
    if (zf <= z2) {
        return 0.0;
    }
    if (zf <= z3) {
        return (zf * z3 - b.x * (zf + z3) + b.y) / ((z3 - z2) * (zf - z2));
    }
    return 1.0 - (z2 * z3 - b.x * (z2 + z3) + b.y) / ((zf - z2) * (zf - z3));
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
