// Exponential variance shadow maps (Lauritzen & McCool 2008): Chebyshev's one-sided bound
// (Donnelly & Lauritzen 2006) in the space of each warp, the receiver warped like the
// stored depths; the minimum variance, given in units of t = 2z - 1, is scaled into each
// warp by the square of its derivative c w at the receiver. The smaller of the two bounds
// is kept, then light bleeding is reduced by linstep(bleed, 1, p). No constant bias.

struct Params {
    lo: vec4<f32>,
    span: vec4<f32>,
    c_pos: f32,
    c_neg: f32,
    min_variance: f32,
    bleed: f32,
}

// (E[w+], E[w+^2], E[w-], E[w-^2]) in layer 0, encoded, blurred and mipmapped
@group(0) @binding(2) var moments: texture_2d_array<f32>;
@group(0) @binding(3) var linear_clamp: sampler;
@group(0) @binding(4) var<uniform> params: Params;

// the fraction of the filter region at or behind w (mean and second moment given)
fn one_sided(mean: f32, second: f32, w: f32, least: f32) -> f32 {
    let variance = max(second - mean * mean, least);
    let delta = w - mean;
    return select(1.0, variance / (variance + delta * delta), w > mean);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= arrayLength(&queries)) {
        return;
    }
    let q = queries[id.x];
    let m = textureSampleLevel(moments, linear_clamp, q.uv, 0, q.lod) * params.span + params.lo;
    let t = 2.0 * q.d - 1.0;
    let wp = exp(params.c_pos * t);
    let wn = -exp(-params.c_neg * t);
    let sp = params.c_pos * wp;
    let sn = params.c_neg * wn;
    let vp = one_sided(m.x, m.y, wp, params.min_variance * sp * sp);
    let vn = one_sided(m.z, m.w, wn, params.min_variance * sn * sn);
    store_visibility(id.x, saturate((min(vp, vn) - params.bleed) / (1.0 - params.bleed)));
}
