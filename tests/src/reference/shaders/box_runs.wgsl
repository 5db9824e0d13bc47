// `sample_box` (docs/language.md 8.7): one axis of the box w wide (uv, at least one texel)
// centred at c (clamped to the map), clipped to the map, as runs [start, end) of texels with
// the covered fraction of each: a partial first texel, whole texels, a partial last texel.
// Appended to the Shade shaders that read summed-area tables (CSSM, VSSM, MSSM).

struct Runs {
    start: vec3<i32>,
    end: vec3<i32>,
    weight: vec3<f32>,
    length: f32,
}

fn box_axis(c: f32, w: f32, n: f32) -> Runs {
    let last = i32(n) - 1;
    let wt = max(w * n, 1.0);
    let centre = clamp(c * n, 0.0, n);
    let x0 = max(centre - 0.5 * wt, 0.0);
    let x1 = min(centre + 0.5 * wt, n);
    let a = clamp(i32(floor(x0)), 0, last);
    let b = clamp(i32(ceil(x1)) - 1, 0, last);
    var r: Runs;
    r.length = x1 - x0;
    if (a == b) {
        r.start = vec3<i32>(a, 0, 0);
        r.end = vec3<i32>(a + 1, 0, 0);
        r.weight = vec3<f32>(x1 - x0, 0.0, 0.0);
    } else {
        r.start = vec3<i32>(a, a + 1, b);
        r.end = vec3<i32>(a + 1, b, b + 1);
        r.weight = vec3<f32>(f32(a + 1) - x0, 1.0, x1 - f32(b));
    }
    return r;
}
