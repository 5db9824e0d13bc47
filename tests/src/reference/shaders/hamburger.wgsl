// The Hamburger 4MSM bounding distribution (Peters & Klein 2015, Algorithm 2; Peters et al.
// 2017, Algorithm 1 with m = 4): for moments b = (b1, b2, b3, b4) and a receiver zf, the
// Cholesky factorisation of [1 b1 b2; b1 b2 b3; b2 b3 b4] (pivots clamped at 1e-12), the
// solve of M c = (1, zf, zf^2), and the roots z2 <= z3 of c1 + c2 z + c3 z^2. Works for any
// depth scale (MSSM's signed depth as well as [0, 1]).

const PIVOT: f32 = 1e-12;

fn hamburger_roots(b: vec4<f32>, zf: f32) -> vec2<f32> {
    let l22 = sqrt(max(b.y - b.x * b.x, PIVOT));
    let l32 = (b.z - b.x * b.y) / l22;
    let l33 = sqrt(max(b.w - b.y * b.y - l32 * l32, PIVOT));
    let y2 = (zf - b.x) / l22;
    let y3 = (zf * zf - b.y - l32 * y2) / l33;
    let c3 = y3 / l33;
    let c2 = (y2 - l32 * c3) / l22;
    let c1 = 1.0 - b.x * c2 - b.y * c3;
    let p = c2 / c3;
    let q = c1 / c3;
    let r = sqrt(max(0.25 * p * p - q, 0.0));
    return vec2<f32>(-0.5 * p - r, -0.5 * p + r);
}

// the weight of x in the distribution on {x, y, z} with moments (1, b1, b2) (Lagrange)
fn three_point_weight(b: vec4<f32>, x: f32, y: f32, z: f32) -> f32 {
    return (b.y - (y + z) * b.x + y * z) / ((x - y) * (x - z));
}

// Algorithm 2's three cases: the weight of the bounding distribution below zf
fn hamburger_intensity(roots: vec2<f32>, b: vec4<f32>, zf: f32) -> f32 {
    if (zf <= roots.x) {
        return 0.0;
    }
    if (zf <= roots.y) {
        return three_point_weight(b, roots.x, zf, roots.y);
    }
    return 1.0 - three_point_weight(b, zf, roots.x, roots.y);
}
