//! The WGSL functions a generated module declares where its code calls them: the `noise`
//! hash and the mip-chain box lookup.

#[cfg(doc)]
use super::Func;

/// The WGSL of [`Func::Noise`], added to a module whose code calls it: PCG3D
/// (Jarzynski & Olano 2020, "Hash functions for GPU rendering", section 2) on the three
/// integers, the top 24 bits of the first word as a float in [0, 1).
pub const NOISE_WGSL: &str = "
fn sshc_noise(x: f32, y: f32, k: f32) -> f32 {
    var v = vec3<u32>(vec3<i32>(floor(vec3<f32>(x, y, k))));
    v = v * 1664525u + 1013904223u;
    v.x += v.y * v.z;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    v ^= v >> vec3<u32>(16u);
    v.x += v.y * v.z;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    return f32(v.x >> 8u) * (1.0 / 16777216.0);
}
";

/// The WGSL function the mip-chain box lookups call (declared by [`MIP_BOX_WGSL`]).
pub const MIP_BOX: &str = "mip_box";

/// `sample_mip_box` in WGSL: the level where the box, `max(w N, 1)` level-0 texels wide,
/// spans one to two texels (`firstLeadingBit` of its whole width: exact, unlike `log2`),
/// the box in that level's texels (centre clamped to the map, clipped to it), and the
/// coverage-weighted sum of the at most 3 x 3 texels it touches over its area (a texel it
/// misses not read, as a non-finite one would poison the sum). The same arithmetic in f64
/// is `interp`'s `Texels::mip_box`.
pub const MIP_BOX_WGSL: &str = "
// the mean over the box `w` wide (uv units, one texel at least) centred at `uv`, clipped
// to the map, of the texels of the Mean mip level where it spans one to two texels
// (docs/language.md 8.7, sample_mip_box): at most 3 x 3 loads, one call of mip_box_texel
// each (so that the cost model counts each load). The level's size is level 0's shifted,
// not queried at the level: where neighbouring pixels chose different levels, lavapipe
// answered textureDimensions(t, level) wrongly for some of them (whole columns read 0).
fn mip_box(t: texture_2d_array<f32>, layer: i32, uv: vec2<f32>, w: f32) -> vec4<f32> {
    let base = vec2<i32>(textureDimensions(t, 0i));
    let n = vec2<f32>(base);
    let width = clamp(w * n.x, 1.0, 4294967040.0);
    let level = clamp(i32(firstLeadingBit(u32(width))), 0i, i32(textureNumLevels(t)) - 1i);
    let s = f32(1u << u32(level));
    let size = max(base >> vec2<u32>(u32(level)), vec2<i32>(1i));
    let c = clamp(uv * n, vec2<f32>(0.0), n);
    let lo = max((c - 0.5 * width) / s, vec2<f32>(0.0));
    let hi = min((c + 0.5 * width) / s, vec2<f32>(size));
    let first = vec2<i32>(floor(lo));
    let sum = mip_box_texel(t, layer, level, first, size, lo, hi, vec2<i32>(0i, 0i))
        + mip_box_texel(t, layer, level, first, size, lo, hi, vec2<i32>(1i, 0i))
        + mip_box_texel(t, layer, level, first, size, lo, hi, vec2<i32>(2i, 0i))
        + mip_box_texel(t, layer, level, first, size, lo, hi, vec2<i32>(0i, 1i))
        + mip_box_texel(t, layer, level, first, size, lo, hi, vec2<i32>(1i, 1i))
        + mip_box_texel(t, layer, level, first, size, lo, hi, vec2<i32>(2i, 1i))
        + mip_box_texel(t, layer, level, first, size, lo, hi, vec2<i32>(0i, 2i))
        + mip_box_texel(t, layer, level, first, size, lo, hi, vec2<i32>(1i, 2i))
        + mip_box_texel(t, layer, level, first, size, lo, hi, vec2<i32>(2i, 2i));
    return sum / ((hi.x - lo.x) * (hi.y - lo.y));
}

// texel `first + o` of the level weighted by the area of it the box [lo, hi] covers; a
// texel the box misses is not read: 0 times an infinite or NaN texel is NaN
fn mip_box_texel(t: texture_2d_array<f32>, layer: i32, level: i32, first: vec2<i32>, size: vec2<i32>, lo: vec2<f32>, hi: vec2<f32>, o: vec2<i32>) -> vec4<f32> {
    let x = vec2<f32>(first + o);
    let cover = max(min(hi, x + 1.0) - max(lo, x), vec2<f32>(0.0));
    let weight = cover.x * cover.y;
    if (weight > 0.0) {
        return weight * textureLoad(t, min(first + o, size - 1i), layer, level);
    }
    return vec4<f32>(0.0);
}
";
