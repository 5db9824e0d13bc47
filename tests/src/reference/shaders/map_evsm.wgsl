// Exponential variance shadow maps (Lauritzen & McCool 2008, exponential warping): the
// depth mapped to t = 2z - 1 in [-1, 1] is warped by w+ = e^{c+ t} and w- = -e^{-c- t}
// (both increasing in t), and each warp is stored with its square, like VSM's moments:
// layer 0 holds (w+, w+^2, w-, w-^2). A unorm precision keeps each as (v - lo) / span over
// its range; a float precision as is (lo 0, span 1).

struct Params {
    lo: vec4<f32>,
    span: vec4<f32>,
    c_pos: f32,
    c_neg: f32,
}

@group(0) @binding(0) var depth: texture_2d<f32>;
@group(0) @binding(1) var moments: texture_storage_2d_array<FORMAT, write>;
@group(0) @binding(2) var<uniform> params: Params;

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (any(id.xy >= textureDimensions(depth))) {
        return;
    }
    let z = textureLoad(depth, id.xy, 0).r;
    let t = 2.0 * z - 1.0;
    let v = vec4<f32>(
        exp(params.c_pos * t),
        exp(2.0 * params.c_pos * t),
        -exp(-params.c_neg * t),
        exp(-2.0 * params.c_neg * t),
    );
    textureStore(moments, id.xy, 0, (v - params.lo) / params.span);
}
