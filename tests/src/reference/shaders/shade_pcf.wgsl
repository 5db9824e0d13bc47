// Percentage-closer filtering (Reeves et al. 1987; Annen 2008, section 4.1): the mean of
// N x N binary tests spaced one texel apart and bilinearly interpolated, which reads
// (N + 1) x (N + 1) texels with weights (1 - tf, 1, ..., 1, tf) per axis.

struct Params {
    bias: f32,
    // N
    taps: i32,
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
    let n = params.taps;
    // The texel below and left of uv, and the bilinear weights tf; the footprint starts
    // N / 2 texels further (half a texel towards -x, -y for even N).
    let st = q.uv * vec2<f32>(size) - 0.5;
    let first = vec2<i32>(floor(st)) - n / 2;
    let tf = fract(st);
    let d = q.d - params.bias;
    var lit = 0.0;
    for (var j = 0; j <= n; j++) {
        let wy = select(1.0, 1.0 - tf.y, j == 0) * select(1.0, tf.y, j == n);
        var row = 0.0;
        for (var i = 0; i <= n; i++) {
            let wx = select(1.0, 1.0 - tf.x, i == 0) * select(1.0, tf.x, i == n);
            let texel = clamp(first + vec2<i32>(i, j), vec2<i32>(0), size - 1);
            // eq. 3.2 at each tap
            row += wx * select(0.0, 1.0, d <= textureLoad(depth, texel, 0).r);
        }
        lit += wy * row;
    }
    store_visibility(id.x, lit / f32(n * n));
}
