// Hausdorff moment shadow mapping (Peters & Klein 2015, the variant for depths known to lie
// in [0, 1]): the moments as MSM's (map_msm.wgsl, box blur, mip chain), biased towards
// (1/2, 1/2, 1/2, 1/2). The Hamburger bounding distribution at t = d - bias (hamburger.wgsl)
// holds where its support lies in [0, 1]; otherwise the distribution on {0, t, g, 1} with
// the moments b0..b4 (every such distribution has E[z (z - 1)(z - t)(z - g)] = 0), written
// in R = E[(z - 1)(z - t)], A = E[z (z - 1)(z - t)], B = E[z (z - 1)(z - t)^2], each taken
// by nested differences of the moments (D_k = b_(k+1) - b_k = E[z^k (z - 1)], then
// E[p (z - t)] = E[z p] - t E[p]), so that a subtraction cancels only what the level before
// left, not values of the moments' size: g - t = B / A, w0 = (g R - A) / (t g),
// wg = A / (g (g - t)(g - 1)); the shadow intensity is the weight below t, w0 plus wg where
// g < t. Degenerate cases: t <= 0: 0; t >= 1: the Hamburger bound; |A| < 1e-12: the three
// points {0, t, 1}, R / t; a vanishing denominator of a weight: that weight 0.
// Visibility 1 - clamp(G).

struct Params {
    alpha: f32,
    bias: f32,
}

@group(0) @binding(2) var moments: texture_2d_array<f32>;
@group(0) @binding(3) var linear_clamp: sampler;
@group(0) @binding(4) var<uniform> params: Params;

fn guarded(num: f32, den: f32) -> f32 {
    if (abs(den) < 1e-12) {
        return 0.0;
    }
    return num / den;
}

fn hausdorff(b: vec4<f32>, t: f32) -> f32 {
    let roots = hamburger_roots(b, t);
    if ((roots.x >= 0.0 && roots.y <= 1.0) || t >= 1.0) {
        return hamburger_intensity(roots, b, t);
    }
    if (t <= 0.0) {
        return 0.0;
    }
    // nested differences: D_k = E[z^k (z - 1)], then E[p (z - t)] = E[z p] - t E[p]
    let d0 = b.x - 1.0;
    let d1 = b.y - b.x;
    let d2 = b.z - b.y;
    let d3 = b.w - b.z;
    let r = d1 - t * d0;
    let a = d2 - t * d1;
    let bb = (d3 - t * d2) - t * a;
    if (abs(a) < 1e-12) {
        return r / t;
    }
    let q = bb / a;
    let g = t + q;
    let w0 = guarded(g * r - a, t * g);
    let wg = guarded(a, g * q * (g - 1.0));
    return select(w0, w0 + wg, q < 0.0);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= arrayLength(&queries)) {
        return;
    }
    let q = queries[id.x];
    let m = textureSampleLevel(moments, linear_clamp, q.uv, 0, q.lod);
    let b = (1.0 - params.alpha) * m + params.alpha * 0.5;
    store_visibility(id.x, 1.0 - saturate(hausdorff(b, q.d - params.bias)));
}
