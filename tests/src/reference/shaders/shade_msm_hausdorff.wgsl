// Hausdorff moment shadow mapping (Peters & Klein 2015, the variant for depths known to lie
// in [0, 1]): the moments as MSM's (map_msm.wgsl, box blur, mip chain), biased towards
// (1/2, 1/2, 1/2, 1/2). The Hamburger bounding distribution at t = d - bias (hamburger.wgsl)
// holds where its support lies in [0, 1]; otherwise the distribution on {0, t, g, 1} with
// the moments b0..b4: g = (b4 - (1 + t) b3 + t b2) / (b3 - (1 + t) b2 + t b1) (every such
// distribution has E[z (z - 1)(z - t)(z - g)] = 0), and the shadow intensity is the weight
// below t, w0 plus wg where g < t (Lagrange over the four points, moments b0..b3). Degenerate
// cases: t <= 0: 0; t >= 1: the Hamburger bound; b3 - (1 + t) b2 + t b1 = 0 (within 1e-12):
// the three points {0, t, 1}; a vanishing denominator of a weight: that weight 0.
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
    let eq = b.z - (1.0 + t) * b.y + t * b.x;
    if (abs(eq) < 1e-12) {
        return (b.y - (1.0 + t) * b.x + t) / t;
    }
    let g = (b.w - (1.0 + t) * b.z + t * b.y) / eq;
    let w0 = guarded(b.z - (1.0 + t + g) * b.y + (t * g + t + g) * b.x - t * g, -t * g);
    let wg = guarded(eq, g * (g - t) * (g - 1.0));
    return select(w0, w0 + wg, g < t);
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
