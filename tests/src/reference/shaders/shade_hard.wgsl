// Hard shadow map (Williams 1978), the binary test of Annen 2008, section 3.2.2.

struct Params {
    bias: f32,
}

@group(0) @binding(2) var depth: texture_2d<f32>;
@group(0) @binding(3) var<uniform> params: Params;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= arrayLength(&queries)) {
        return;
    }
    let q = queries[id.x];
    let size = vec2<i32>(textureDimensions(depth));
    // nearest(z): the texel that contains uv
    let texel = clamp(vec2<i32>(floor(q.uv * vec2<f32>(size))), vec2<i32>(0), size - 1);
    let z = textureLoad(depth, texel, 0).r;
    // eq. 3.2: s = 1 if d <= z, else 0
    store_visibility(id.x, select(0.0, 1.0, q.d - params.bias <= z));
}
