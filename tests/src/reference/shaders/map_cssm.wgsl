// Convolution soft shadow maps (Annen 2008, chapter 8): the basis images of one of CSSM's
// two channel sets, four channels per layer. Channel c < 2M is order k = c / 2 + 1, the
// sine (even c) or cosine (odd c) of c_k z = pi (2k - 1) z (eq. 6.6); the z-weighted set
// multiplies it by z (the complementary basis [B_i(z) z] of eq. 8.5 and 8.8) and appends z/2
// (eq. 8.8's constant term) as channel 2M. A unorm precision keeps each as (v - lo) / span.

struct Params {
    // M
    orders: u32,
    // 1 for the z-weighted set
    weighted: u32,
    // index of this set's first layer in `encoding`
    first_layer: u32,
}

struct Encoding {
    lo: vec4<f32>,
    span: vec4<f32>,
}

@group(0) @binding(0) var depth: texture_2d<f32>;
@group(0) @binding(1) var basis: texture_storage_2d_array<FORMAT, write>;
@group(0) @binding(2) var<uniform> params: Params;
@group(0) @binding(3) var<storage, read> encoding: array<Encoding>;

// (sin, cos) of 2 pi t, the argument reduced to [-pi, pi] where Vulkan bounds their error
// (2^-11 absolute): c_k z = 2 pi t with t = (2k - 1) z / 2 turns.
fn sin_cos_turns(t: f32) -> vec2<f32> {
    let a = 6.2831853 * (t - round(t));
    return vec2<f32>(sin(a), cos(a));
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (any(id.xy >= textureDimensions(depth))) {
        return;
    }
    let z = textureLoad(depth, id.xy, 0).r;
    let layer = id.z;
    var v = vec4<f32>(0.0);
    for (var i = 0u; i < 4u; i++) {
        let c = 4u * layer + i;
        if (c < 2u * params.orders) {
            let k = c / 2u + 1u;
            let sc = sin_cos_turns(f32(2u * k - 1u) * 0.5 * z);
            var b = select(sc.y, sc.x, c % 2u == 0u);
            if (params.weighted == 1u) {
                b = z * b;
            }
            v[i] = b;
        } else if (params.weighted == 1u && c == 2u * params.orders) {
            v[i] = 0.5 * z;
        }
    }
    let e = encoding[params.first_layer + layer];
    textureStore(basis, id.xy, layer, (v - e.lo) / e.span);
}
