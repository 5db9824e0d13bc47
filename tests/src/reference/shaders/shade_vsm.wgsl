// Variance shadow maps (Donnelly & Lauritzen 2006; Annen 2008, section 4.1): Chebyshev's
// one-tailed inequality bounds the lit fraction of a receiver behind the filtered mean,
// p_max = var / (var + (d - mean)^2), with the variance clamped below against acne and
// light bleeding reduced by linstep(bleed, 1, p).

struct Params {
    bias: f32,
    min_variance: f32,
    bleed: f32,
}

// (E[z], E[z^2]) in layer 0, blurred and mipmapped
@group(0) @binding(2) var moments: texture_2d_array<f32>;
@group(0) @binding(3) var linear_clamp: sampler;
@group(0) @binding(4) var<uniform> params: Params;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= arrayLength(&queries)) {
        return;
    }
    let q = queries[id.x];
    let m = textureSampleLevel(moments, linear_clamp, q.uv, 0, q.lod).xy;
    let d = q.d - params.bias;
    let variance = max(m.y - m.x * m.x, params.min_variance);
    let delta = d - m.x;
    let p_max = variance / (variance + delta * delta);
    // in front of the mean the receiver is lit
    let p = select(1.0, p_max, d > m.x);
    store_visibility(id.x, saturate((p - params.bleed) / (1.0 - params.bleed)));
}
