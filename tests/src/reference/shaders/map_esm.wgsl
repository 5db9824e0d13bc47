// Exponential shadow maps (Annen 2008, chapter 7): store the basis e^{cz} of eq. 7.1, so
// that filtering it filters the shadow test (eq. 7.2). A unorm precision keeps it as
// (e^{cz} - lo) / span over its range [1, e^c]; a float precision as is (lo 0, span 1).

struct Params {
    c: f32,
    lo: f32,
    span: f32,
}

@group(0) @binding(0) var depth: texture_2d<f32>;
@group(0) @binding(1) var esm: texture_storage_2d_array<FORMAT, write>;
@group(0) @binding(2) var<uniform> params: Params;

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (any(id.xy >= textureDimensions(depth))) {
        return;
    }
    let z = textureLoad(depth, id.xy, 0).r;
    let e = exp(params.c * z);
    textureStore(esm, id.xy, 0, vec4<f32>((e - params.lo) / params.span, 0.0, 0.0, 0.0));
}
