// Moment soft shadow maps (Peters, Münstermann, Wetzstein and Klein, JCGT 2017), the Map
// pass: the signed depth s = 2z - 1 (section 3.1) and its first four powers through the
// sparse quantisation transform (section 3.1), each in [0, 1],
//   q1 = 3/2 s - 2 s^3 + 1/2, q2 = 4 s^2 - 4 s^4,
//   q3 = sqrt(3)/2 s - 2 sqrt(3)/9 s^3 + 1/2, q4 = 1/2 s^2 + 1/2 s^4,
// or, with `quantise` off, the raw powers z^k; layer 0, summed into 16-bit fixed-point
// tables (sat.wgsl with scale 65535).

struct Params {
    quantise: u32,
}

@group(0) @binding(0) var depth: texture_2d<f32>;
@group(0) @binding(1) var moments: texture_storage_2d_array<FORMAT, write>;
@group(0) @binding(2) var<uniform> params: Params;

const SQRT3: f32 = 1.7320508;

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (any(id.xy >= textureDimensions(depth))) {
        return;
    }
    let z = textureLoad(depth, id.xy, 0).r;
    var q: vec4<f32>;
    if (params.quantise != 0u) {
        let s = 2.0 * z - 1.0;
        let s2 = s * s;
        let s3 = s2 * s;
        let s4 = s2 * s2;
        q = vec4<f32>(1.5 * s - 2.0 * s3 + 0.5, 4.0 * s2 - 4.0 * s4, 0.5 * SQRT3 * s - (2.0 * SQRT3 / 9.0) * s3 + 0.5, 0.5 * s2 + 0.5 * s4);
    } else {
        let z2 = z * z;
        q = vec4<f32>(z, z2, z2 * z, z2 * z2);
    }
    textureStore(moments, id.xy, 0, q);
}
