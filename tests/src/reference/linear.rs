//! An f64 reference of soft shadow maps for linear lights (Heidrich, Brabec & Seidel 2000,
//! "Soft Shadow Maps for Linear Lights"), written from the paper and sshc's stated conventions,
//! independently of the compiler's code generator.
//!
//! Conventions implemented (every quantity in f64):
//!
//! - Light samples `k = 0..N` each have a view ([`LinearView`]): a world -> view matrix (the
//!   view looks down `-z`), a world -> clip matrix, its own `near` and `far` and the weights
//!   `[w_before, w_after]` of the light segments on either side of it (0 where there is none;
//!   a lone sample has `[1, 1]`). An open chain's sample `k` has neighbours `k - 1` and `k + 1`
//!   where they exist; a closed chain (the edges of a polygonal light, paper section 4) also
//!   links sample `N - 1` to sample 0.
//! - Linear depth in view `k`: `z = (dist - near_k) / (far_k - near_k)`, `dist = -(view_k p).z`;
//!   `uv = clip.xy / clip.w * (0.5, -0.5) + 0.5`; texel `(x, y)` of an `S x S` map has its centre
//!   at uv `((x + 0.5) / S, (y + 0.5) / S)`; maps are row-major, row 0 first.
//! - Depth map of view `k` (paper section 3, first pass): the linear depth of the nearest caster
//!   along the ray through each texel centre, ray-cast against the triangles, clear 1.
//! - Visibility channels (section 3.2): two per sample, `v_prev` (segment `k-1..k`, skins of view
//!   `k-1` warped into view `k`) and `v_next` (segment `k..k+1`, skins of view `k+1`), each
//!   initialised to 0.5 ("initializing all entries in the visibility channel to 0.5").
//! - Skins of source view `i` (section 3.2): the depth samples are triangulated over texel
//!   centres, cell `(x, y)` for `x, y` in `0..S-1` with corners `c00 = (x, y)`, `c10 = (x+1, y)`,
//!   `c01 = (x, y+1)`, `c11 = (x+1, y+1)` and triangles `T1 = (c00, c10, c11)`,
//!   `T2 = (c00, c11, c01)`. The paper finds discontinuities with a 3x3 Laplacian-of-Gaussian
//!   (section 4); here the detector is stated: `LoG(t) = 4 z(t) - z(t-x) - z(t+x) - z(t-y) -
//!   z(t+y)` (neighbours clamped to the map), and a triangle is a skin iff the spread (max - min)
//!   of its corner depths exceeds `tau` and some corner has `|LoG| > tau` (a corner at depth 1,
//!   no surface, is a receiver at the far plane). A corner's Gouraud value is 0 (occluder) if its
//!   depth is below the midpoint `(min + max) / 2` of its triangle's, else 1 (receiver). Its
//!   world position is the point at view distance `near_i + z (far_i - near_i)` on the ray of
//!   view `i` through its texel centre.
//! - Warping into target view `j = i -+ 1`: the skins are projected into view `j` and
//!   rasterised at its texel centres: a centre is covered iff it lies inside the projected
//!   triangle, edges included, either winding. The edge functions of an edge shared by two
//!   skins are computed from the same corner (the one whose source texel comes first), so they
//!   are exact negatives: a centre on a shared edge is never missed by both (no crack), which
//!   matters because sample views that share an orientation and differ by a shift along a
//!   screen axis map the mesh's rows onto rows of texel centres exactly. The value is
//!   interpolated perspective-correctly (`b_k = (l_k / w_k) / sum (l_m / w_m)`, `l` the screen
//!   barycentrics, [`Interpolation::Perspective`], the conventions') or affinely in view `j`'s
//!   screen ([`Interpolation::Screen`], for comparison); the fragment's linear depth is the
//!   perspective-correct interpolation of the corners', and the near and far planes clip it to
//!   `[0, 1]`. A skin with a corner at or behind the eye is ray-cast instead (the texel centre's
//!   ray at the world triangle, as clipping would give). A fragment is kept iff its linear depth
//!   in view `j` is `<= z_j(texel) + keep_bias`; of the kept ones the nearest wins (of equal
//!   depths the first skin in cell order, `T1` before `T2`).
//! - Shade (section 3, the `shade(p)` procedure, with the per-segment channels of section 3.3):
//!   `V(p) = sum_k lit_k(p) (w_before_k v_prev_k + w_after_k v_next_k)`,
//!   `lit_k = [d_k(p) - bias <= z_k]`, depth and channels read at the texel of view `k` that
//!   holds `p` (clamped to the map). `N = 1` gives the hard shadow map; a point every sample
//!   sees with no skin on it gets `sum_k (w_b + w_a) / 2 = 1`. [`visibility`] returns the raw
//!   sum (it can exceed 1 where a skin's receiver end overlaps a lit texel);
//!   [`visibility_clamped`] clamps it to `[0, 1]`.
//!
//! Degenerate skins (edge-on in view `j`, zero area, at the map border, one texel wide) give no
//! hit rather than a NaN: a ray meets a triangle only where its determinant is non-zero and
//! finite, and a value is only formed from finite barycentrics.

use super::penumbra::ray_triangle;

pub type V3 = [f64; 3];
/// A 4 x 4 matrix, column-major (glam's `to_cols_array`).
pub type M4 = [f64; 16];

/// How a skin's corner values are interpolated across it in the target view.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    /// Perspective-correct: the barycentrics of the hit point on the world triangle.
    Perspective,
    /// Affine in the target view's screen (the corner values weighted by `b_k w_k`, `w_k` the
    /// corner's clip w), where every corner lies in front of the eye; perspective-correct
    /// otherwise.
    Screen,
}

/// One light sample's view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinearView {
    /// World -> view (the view looks down `-z`).
    pub view: M4,
    /// World -> clip (projection times view).
    pub view_proj: M4,
    pub near: f64,
    pub far: f64,
    /// `[w_before, w_after]`.
    pub weights: [f64; 2],
}

/// Everything the reference needs.
#[derive(Clone, Debug, PartialEq)]
pub struct LinearSetup {
    /// The samples in order along the light.
    pub views: Vec<LinearView>,
    /// Whether sample `N - 1`'s next is sample 0 (a polygonal light's closed chain).
    pub closed: bool,
    /// Map size `S` (texels per side).
    pub size: usize,
    /// `tau`, normalised depth.
    pub skin_threshold: f64,
    /// The warp's keep test: a fragment is kept iff its depth `<= z_j + keep_bias`.
    pub keep_bias: f64,
    /// The shade's receiver bias.
    pub bias: f64,
    pub interpolation: Interpolation,
}

fn row(m: &M4, r: usize) -> [f64; 4] {
    [m[r], m[4 + r], m[8 + r], m[12 + r]]
}

fn apply(r: [f64; 4], p: V3) -> f64 {
    r[0] * p[0] + r[1] * p[1] + r[2] * p[2] + r[3]
}

fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn add_scaled(a: V3, d: V3, t: f64) -> V3 {
    [a[0] + d[0] * t, a[1] + d[1] * t, a[2] + d[2] * t]
}

fn cross(a: V3, b: V3) -> V3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn finite(p: V3) -> bool {
    p.iter().all(|v| v.is_finite())
}

impl LinearView {
    /// The view of a runtime light sample (its f32 matrices, near, far and weights widened).
    pub fn from_sample(s: &sshc_runtime::gpu::SampleView) -> LinearView {
        LinearView {
            view: s.light_view.map(f64::from),
            view_proj: s.light_view_proj.map(f64::from),
            near: f64::from(s.near),
            far: f64::from(s.far),
            weights: s.weights.map(f64::from),
        }
    }

    /// View distance `dist = -(view p).z` of a world point.
    pub fn dist(&self, p: V3) -> f64 {
        -apply(row(&self.view, 2), p)
    }

    /// Linear depth of a world point.
    pub fn depth(&self, p: V3) -> f64 {
        (self.dist(p) - self.near) / (self.far - self.near)
    }

    /// Clip coordinates of a world point.
    pub fn clip(&self, p: V3) -> [f64; 4] {
        [0, 1, 2, 3].map(|r| apply(row(&self.view_proj, r), p))
    }

    /// uv of a world point; `None` at or behind the eye (clip w <= 0) or for a non-finite one.
    pub fn uv(&self, p: V3) -> Option<[f64; 2]> {
        let c = self.clip(p);
        if c[3].is_nan() || c[3] <= 0.0 || !c.iter().all(|v| v.is_finite()) {
            return None;
        }
        Some([c[0] / c[3] * 0.5 + 0.5, c[1] / c[3] * -0.5 + 0.5])
    }

    /// The world point at view distance `dist` on the ray through uv `(u, v)`: the solution of
    /// `clip.x - ndc_x clip.w = 0`, `clip.y - ndc_y clip.w = 0`, `-(view p).z = dist` (Cramer's
    /// rule); `None` where the system is singular.
    pub fn point_at(&self, u: f64, v: f64, dist: f64) -> Option<V3> {
        let (nx, ny) = (2.0 * u - 1.0, 1.0 - 2.0 * v);
        let (r0, r1, r3) = (row(&self.view_proj, 0), row(&self.view_proj, 1), row(&self.view_proj, 3));
        let rz = row(&self.view, 2);
        let a = [
            [r0[0] - nx * r3[0], r0[1] - nx * r3[1], r0[2] - nx * r3[2]],
            [r1[0] - ny * r3[0], r1[1] - ny * r3[1], r1[2] - ny * r3[2]],
            [-rz[0], -rz[1], -rz[2]],
        ];
        let b = [-(r0[3] - nx * r3[3]), -(r1[3] - ny * r3[3]), dist + rz[3]];
        let det = dot(a[0], cross(a[1], a[2]));
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        // Cramer: x_c = det(A with column c replaced by b) / det(A) = (b . (a1 x a2)) ... by
        // the columns; written with the rows' cross products.
        let c12 = cross(a[1], a[2]);
        let c20 = cross(a[2], a[0]);
        let c01 = cross(a[0], a[1]);
        let x = [
            (b[0] * c12[0] + b[1] * c20[0] + b[2] * c01[0]) / det,
            (b[0] * c12[1] + b[1] * c20[1] + b[2] * c01[1]) / det,
            (b[0] * c12[2] + b[1] * c20[2] + b[2] * c01[2]) / det,
        ];
        finite(x).then_some(x)
    }

    /// The ray through the centre of texel `(x, y)` of an `size`-texel map: origin at view
    /// distance `near`, direction to the point at `far`, so that the ray parameter is the
    /// linear depth.
    pub fn texel_ray(&self, x: usize, y: usize, size: usize) -> Option<(V3, V3)> {
        let s = size as f64;
        let (u, v) = ((x as f64 + 0.5) / s, (y as f64 + 0.5) / s);
        let o = self.point_at(u, v, self.near)?;
        let f = self.point_at(u, v, self.far)?;
        Some((o, sub(f, o)))
    }

    /// The texel of an `size`-texel map holding a world point (clamped to the map).
    pub fn texel_of(&self, p: V3, size: usize) -> Option<(usize, usize)> {
        let [u, v] = self.uv(p)?;
        let s = size as f64;
        let last = size as f64 - 1.0;
        Some(((u * s).floor().clamp(0.0, last) as usize, (v * s).floor().clamp(0.0, last) as usize))
    }
}

impl LinearSetup {
    /// Check ranges: `1 <= N <= 16` views with finite matrices, `0 < near < far` and finite
    /// non-negative weights, `2 <= S <= 1024`, finite non-negative `tau`, `keep_bias`, finite
    /// `bias`.
    pub fn check(&self) -> Result<(), String> {
        if !(1..=16).contains(&self.views.len()) {
            return Err(format!("need 1 to 16 light samples, not {}", self.views.len()));
        }
        for (k, v) in self.views.iter().enumerate() {
            if !v.view.iter().chain(v.view_proj.iter()).all(|x| x.is_finite()) {
                return Err(format!("sample {k}: the view matrices must be finite"));
            }
            if !(v.near.is_finite() && v.far.is_finite() && v.near > 0.0 && v.far > v.near) {
                return Err(format!("sample {k}: need 0 < near < far (near {}, far {})", v.near, v.far));
            }
            if !v.weights.iter().all(|w| w.is_finite() && *w >= 0.0) {
                return Err(format!("sample {k}: the weights {:?} must be finite and >= 0", v.weights));
            }
        }
        if !(2..=1024).contains(&self.size) {
            return Err(format!("the map size {} must lie in 2..=1024", self.size));
        }
        if !(self.skin_threshold.is_finite() && self.skin_threshold >= 0.0) {
            return Err(format!("skin_threshold {} must be finite and >= 0", self.skin_threshold));
        }
        if !(self.keep_bias.is_finite() && self.keep_bias >= 0.0) {
            return Err(format!("keep_bias {} must be finite and >= 0", self.keep_bias));
        }
        if !self.bias.is_finite() {
            return Err(format!("bias {} must be finite", self.bias));
        }
        Ok(())
    }

    /// Sample `k`'s previous sample (whose skins make `v_prev`), if any.
    pub fn prev_of(&self, k: usize) -> Option<usize> {
        let n = self.views.len();
        if n < 2 {
            None
        } else if k > 0 {
            Some(k - 1)
        } else if self.closed {
            Some(n - 1)
        } else {
            None
        }
    }

    /// Sample `k`'s next sample (whose skins make `v_next`), if any.
    pub fn next_of(&self, k: usize) -> Option<usize> {
        let n = self.views.len();
        if n < 2 {
            None
        } else if k + 1 < n {
            Some(k + 1)
        } else if self.closed {
            Some(0)
        } else {
            None
        }
    }
}

fn check_view(setup: &LinearSetup, k: usize) -> Result<&LinearView, String> {
    setup.check()?;
    setup
        .views
        .get(k)
        .ok_or_else(|| format!("no sample {k}: the set-up has {}", setup.views.len()))
}

fn check_len(what: &str, v: &[f64], size: usize) -> Result<(), String> {
    if v.len() != size * size {
        return Err(format!("{what} has {} texels, not {}", v.len(), size * size));
    }
    Ok(())
}

/// The depth map of view `k` (linear depth of the nearest of `triangles` at each texel
/// centre, 1 where the ray meets none between near and far).
pub fn depth_map(triangles: &[[V3; 3]], setup: &LinearSetup, k: usize) -> Result<Vec<f64>, String> {
    let view = check_view(setup, k)?;
    let n = setup.size;
    let tris: Vec<&[V3; 3]> = triangles.iter().filter(|t| t.iter().all(|p| finite(*p))).collect();
    let mut z = vec![1.0; n * n];
    for y in 0..n {
        for x in 0..n {
            let Some((o, d)) = view.texel_ray(x, y, n) else { continue };
            for t in &tris {
                if let Some(h) = ray_triangle(o, d, t)
                    && (0.0..=1.0).contains(&h)
                    && h < z[y * n + x]
                {
                    z[y * n + x] = h;
                }
            }
        }
    }
    Ok(z)
}

/// The detector's Laplacian `4 z(t) - z(t-x) - z(t+x) - z(t-y) - z(t+y)`, neighbours clamped.
pub fn laplacian(depth: &[f64], size: usize) -> Result<Vec<f64>, String> {
    check_len("the depth map", depth, size)?;
    let n = size;
    let at = |x: usize, y: usize| depth[y * n + x];
    let mut out = vec![0.0; n * n];
    for y in 0..n {
        for x in 0..n {
            let l = at(x.saturating_sub(1), y) + at((x + 1).min(n - 1), y) + at(x, y.saturating_sub(1)) + at(x, (y + 1).min(n - 1));
            out[y * n + x] = 4.0 * at(x, y) - l;
        }
    }
    Ok(out)
}

/// A skin triangle of a source view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Skin {
    /// `2 (y (S - 1) + x) + half`, `half` 0 for `T1`, 1 for `T2`: the order of the depth test's
    /// ties.
    pub index: u32,
    /// The corners' texels `(x, y)`.
    pub texels: [(usize, usize); 3],
    /// The corners' linear depths in the source view.
    pub depth: [f64; 3],
    /// The corners' Gouraud values (0 occluder, 1 receiver).
    pub value: [f64; 3],
    /// The corners' world positions.
    pub world: [V3; 3],
}

/// The corner texels of triangle `half` of cell `(x, y)`.
pub fn cell_corners(x: usize, y: usize, half: u32) -> [(usize, usize); 3] {
    if half == 0 {
        [(x, y), (x + 1, y), (x + 1, y + 1)]
    } else {
        [(x, y), (x + 1, y + 1), (x, y + 1)]
    }
}

/// The skins of source view `i` given its depth map.
pub fn skins(depth: &[f64], setup: &LinearSetup, i: usize) -> Result<Vec<Skin>, String> {
    let view = check_view(setup, i)?;
    let n = setup.size;
    let tau = setup.skin_threshold;
    let log = laplacian(depth, n)?;
    let mut out = Vec::new();
    for y in 0..n - 1 {
        for x in 0..n - 1 {
            for half in 0..2u32 {
                let texels = cell_corners(x, y, half);
                let d = texels.map(|(a, b)| depth[b * n + a]);
                let lo = d[0].min(d[1]).min(d[2]);
                let hi = d[0].max(d[1]).max(d[2]);
                let edge = texels.iter().any(|&(a, b)| log[b * n + a].abs() > tau);
                if !(hi - lo > tau && edge) {
                    continue;
                }
                let mid = 0.5 * (lo + hi);
                let value = d.map(|z| if z < mid { 0.0 } else { 1.0 });
                let mut world = [[0.0; 3]; 3];
                let mut ok = true;
                for c in 0..3 {
                    let (a, b) = texels[c];
                    let s = n as f64;
                    let dist = view.near + d[c] * (view.far - view.near);
                    match view.point_at((a as f64 + 0.5) / s, (b as f64 + 0.5) / s, dist) {
                        Some(p) => world[c] = p,
                        None => ok = false,
                    }
                }
                if ok {
                    out.push(Skin {
                        index: 2 * (y * (n - 1) + x) as u32 + half,
                        texels,
                        depth: d,
                        value,
                        world,
                    });
                }
            }
        }
    }
    Ok(out)
}

/// Ray-triangle intersection with barycentrics (Moller-Trumbore, both sides, edges included):
/// `(t, [b0, b1, b2])` with the hit at `b0 A + b1 B + b2 C`; `None` for a miss or a triangle
/// seen edge-on.
pub fn ray_hit(o: V3, d: V3, tri: &[V3; 3]) -> Option<(f64, [f64; 3])> {
    let e1 = sub(tri[1], tri[0]);
    let e2 = sub(tri[2], tri[0]);
    let p = cross(d, e2);
    let det = dot(e1, p);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv = 1.0 / det;
    let s = sub(o, tri[0]);
    let u = dot(s, p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = cross(s, e1);
    let v = dot(d, q) * inv;
    if !(v >= 0.0 && u + v <= 1.0) {
        return None;
    }
    let t = dot(e2, q) * inv;
    (t.is_finite() && u.is_finite() && v.is_finite()).then_some((t, [1.0 - u - v, u, v]))
}

/// A skin's fragment at one texel of the target view (before the keep test).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fragment {
    /// Linear depth in the target view.
    pub depth: f64,
    /// The interpolated value.
    pub value: f64,
    /// The fragment's perspective-correct barycentrics (weights of the world corners).
    pub bary: [f64; 3],
    /// The screen-space barycentrics (edge functions over their sum) where the skin was
    /// rasterised, NaN where it was ray-cast (a corner at or behind the eye); their smallest is
    /// how far inside the projected triangle the texel centre lies, in units of its size.
    pub screen: [f64; 3],
}

/// A skin projected into a target view: corner positions in texels (`x` right, `y` down: uv
/// times `S`) and clip `w`; `None` where a corner lies at or behind the eye.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Projected {
    pub q: [[f64; 2]; 3],
    pub w: [f64; 3],
}

/// Project a skin into `view` (an `size`-texel map).
pub fn project(skin: &Skin, view: &LinearView, size: usize) -> Option<Projected> {
    let s = size as f64;
    let mut q = [[0.0; 2]; 3];
    let mut w = [0.0; 3];
    for k in 0..3 {
        let c = view.clip(skin.world[k]);
        if c[3].is_nan() || c[3] <= 0.0 || !c.iter().all(|v| v.is_finite()) {
            return None;
        }
        q[k] = [(c[0] / c[3] * 0.5 + 0.5) * s, (c[1] / c[3] * -0.5 + 0.5) * s];
        w[k] = c[3];
    }
    Some(Projected { q, w })
}

/// The edge function of the edge from corner `a` to corner `b` at `p`, computed from the
/// corner whose source texel comes first (row-major) so that the two triangles sharing an edge
/// get exactly opposite values: a texel centre on a shared edge is covered by both or by
/// exactly one of them, never by neither (a watertight mesh).
fn edge_fn(skin: &Skin, pr: &Projected, a: usize, b: usize, p: [f64; 2]) -> f64 {
    let key = |k: usize| (skin.texels[k].1, skin.texels[k].0);
    let (first, second, sign) = if key(a) <= key(b) { (a, b, 1.0) } else { (b, a, -1.0) };
    let (qa, qb) = (pr.q[first], pr.q[second]);
    sign * ((qb[0] - qa[0]) * (p[1] - qa[1]) - (qb[1] - qa[1]) * (p[0] - qa[0]))
}

/// The signed distances, in texels of view `j`, from the centre of texel `(x, y)` to the three
/// edges of `skin` projected into view `j` (edge `k` opposite corner `k`), positive inside for
/// either winding; `None` where a corner lies at or behind the eye or the projection has no
/// area.
pub fn edge_distances(skin: &Skin, setup: &LinearSetup, j: usize, x: usize, y: usize) -> Option<[f64; 3]> {
    let pr = project(skin, setup.views.get(j)?, setup.size)?;
    let p = [x as f64 + 0.5, y as f64 + 0.5];
    let e = [
        edge_fn(skin, &pr, 1, 2, p),
        edge_fn(skin, &pr, 2, 0, p),
        edge_fn(skin, &pr, 0, 1, p),
    ];
    let area = e[0] + e[1] + e[2];
    if area == 0.0 || !area.is_finite() {
        return None;
    }
    let len = |a: usize, b: usize| ((pr.q[b][0] - pr.q[a][0]).powi(2) + (pr.q[b][1] - pr.q[a][1]).powi(2)).sqrt();
    let l = [len(1, 2), len(2, 0), len(0, 1)];
    Some([0, 1, 2].map(|k| e[k] * area.signum() / l[k]))
}

fn interpolate(skin: &Skin, setup: &LinearSetup, view: &LinearView, bary: [f64; 3], screen: Option<[f64; 3]>) -> Option<Fragment> {
    let persp = bary[0] * skin.value[0] + bary[1] * skin.value[1] + bary[2] * skin.value[2];
    let value = match (setup.interpolation, screen) {
        (Interpolation::Screen, Some(l)) => l[0] * skin.value[0] + l[1] * skin.value[1] + l[2] * skin.value[2],
        _ => persp,
    };
    // linear depth is affine in the world point: interpolate it with the world barycentrics
    let d = skin.world.map(|p| view.depth(p));
    let depth = bary[0] * d[0] + bary[1] * d[1] + bary[2] * d[2];
    if !(value.is_finite() && depth.is_finite() && (0.0..=1.0).contains(&depth)) {
        return None; // clipped by the near or far plane
    }
    // a convex combination of values in [0, 1]: clamp away the rounding of the weights
    Some(Fragment {
        depth,
        value: value.clamp(0.0, 1.0),
        bary,
        screen: screen.unwrap_or([f64::NAN; 3]),
    })
}

/// The fragment of a projected skin at texel `(x, y)`: the texel centre inside the projected
/// triangle (edges included, either winding), screen barycentrics `l_k`, perspective-correct
/// ones `b_k = (l_k / w_k) / sum_m (l_m / w_m)`.
fn raster_fragment(skin: &Skin, pr: &Projected, setup: &LinearSetup, view: &LinearView, x: usize, y: usize) -> Option<Fragment> {
    let p = [x as f64 + 0.5, y as f64 + 0.5];
    // l_2 from edge 0-1, l_0 from edge 1-2, l_1 from edge 2-0
    let e = [edge_fn(skin, pr, 1, 2, p), edge_fn(skin, pr, 2, 0, p), edge_fn(skin, pr, 0, 1, p)];
    let inside = e.iter().all(|v| *v >= 0.0) || e.iter().all(|v| *v <= 0.0);
    let area = e[0] + e[1] + e[2];
    if !inside || area == 0.0 || !area.is_finite() {
        return None;
    }
    let l = e.map(|v| v / area);
    let r = [l[0] / pr.w[0], l[1] / pr.w[1], l[2] / pr.w[2]];
    let sum = r[0] + r[1] + r[2];
    if !(sum > 0.0 && sum.is_finite()) {
        return None;
    }
    interpolate(skin, setup, view, r.map(|v| v / sum), Some(l))
}

/// The fragment of a skin with a corner at or behind the eye: the texel centre's ray cast at
/// the world triangle between the near and far planes (what clipping then rasterising gives).
fn ray_fragment(skin: &Skin, setup: &LinearSetup, view: &LinearView, x: usize, y: usize) -> Option<Fragment> {
    let (o, d) = view.texel_ray(x, y, setup.size)?;
    let (_, b) = ray_hit(o, d, &skin.world)?;
    interpolate(skin, setup, view, b, None)
}

/// The fragment of `skin` at texel `(x, y)` of view `j`, if it covers the texel centre
/// between the near and far planes.
pub fn fragment(skin: &Skin, setup: &LinearSetup, j: usize, x: usize, y: usize) -> Option<Fragment> {
    let view = setup.views.get(j)?;
    match project(skin, view, setup.size) {
        Some(pr) => raster_fragment(skin, &pr, setup, view, x, y),
        None => ray_fragment(skin, setup, view, x, y),
    }
}

/// One visibility channel of a view.
#[derive(Clone, Debug, PartialEq)]
pub struct Channel {
    /// The channel's value per texel (0.5 where no skin was kept).
    pub value: Vec<f64>,
    /// The winning fragment's linear depth (NaN where none).
    pub depth: Vec<f64>,
    /// The winning skin's [`Skin::index`].
    pub winner: Vec<Option<u32>>,
}

impl Channel {
    /// The cleared channel: 0.5 everywhere.
    pub fn clear(size: usize) -> Channel {
        Channel {
            value: vec![0.5; size * size],
            depth: vec![f64::NAN; size * size],
            winner: vec![None; size * size],
        }
    }
}

/// The skins of a source view warped into view `j` with depth map `depth_j`.
pub fn warp(skins: &[Skin], depth_j: &[f64], setup: &LinearSetup, j: usize) -> Result<Channel, String> {
    let view = check_view(setup, j)?;
    let n = setup.size;
    check_len("the target's depth map", depth_j, n)?;
    let mut ch = Channel::clear(n);
    let last = n as f64 - 1.0;
    for skin in skins {
        let pr = project(skin, view, n);
        // the texels whose centres the projected triangle can hold, or all
        let (x0, x1, y0, y1) = match &pr {
            Some(pr) => {
                let lo = |c: usize| pr.q.iter().map(|q| q[c]).fold(f64::INFINITY, f64::min);
                let hi = |c: usize| pr.q.iter().map(|q| q[c]).fold(f64::NEG_INFINITY, f64::max);
                let first = |v: f64| (v - 0.5).ceil().clamp(0.0, last) as usize;
                let end = |v: f64| (v - 0.5).floor().clamp(-1.0, last);
                let (ex, ey) = (end(hi(0)), end(hi(1)));
                if ex < 0.0 || ey < 0.0 {
                    continue;
                }
                (first(lo(0)), ex as usize, first(lo(1)), ey as usize)
            }
            None => (0, n - 1, 0, n - 1),
        };
        for y in y0..=y1 {
            for x in x0..=x1 {
                let f = match &pr {
                    Some(pr) => raster_fragment(skin, pr, setup, view, x, y),
                    None => ray_fragment(skin, setup, view, x, y),
                };
                let Some(f) = f else { continue };
                let k = y * n + x;
                // of equal depths the earlier skin keeps the texel
                if f.depth <= depth_j[k] + setup.keep_bias && (ch.depth[k].is_nan() || f.depth < ch.depth[k]) {
                    ch.value[k] = f.value;
                    ch.depth[k] = f.depth;
                    ch.winner[k] = Some(skin.index);
                }
            }
        }
    }
    Ok(ch)
}

/// Every map of the technique.
#[derive(Clone, Debug, PartialEq)]
pub struct LinearMaps {
    pub size: usize,
    /// Per sample: the depth map.
    pub depth: Vec<Vec<f64>>,
    /// Per sample: the skins of its depth map.
    pub skins: Vec<Vec<Skin>>,
    /// Per sample: `v_prev` (skins of the previous sample warped in) and `v_next`.
    pub v_prev: Vec<Channel>,
    pub v_next: Vec<Channel>,
}

/// The maps from given depth maps (one per sample, `S x S` each, values in `[0, 1]`).
pub fn linear_maps_from_depth(depth: Vec<Vec<f64>>, setup: &LinearSetup) -> Result<LinearMaps, String> {
    setup.check()?;
    let n = setup.size;
    if depth.len() != setup.views.len() {
        return Err(format!("{} depth maps for {} samples", depth.len(), setup.views.len()));
    }
    for (k, d) in depth.iter().enumerate() {
        if d.len() != n * n {
            return Err(format!("depth map {k} has {} texels, not {}", d.len(), n * n));
        }
        if let Some(z) = d.iter().find(|z| !(0.0..=1.0).contains(*z)) {
            return Err(format!("depth map {k} holds {z}, outside [0, 1]"));
        }
    }
    let skins = (0..depth.len())
        .map(|i| self::skins(&depth[i], setup, i))
        .collect::<Result<Vec<_>, _>>()?;
    let channel = |src: Option<usize>, j: usize| match src {
        Some(i) => warp(&skins[i], &depth[j], setup, j),
        None => Ok(Channel::clear(n)),
    };
    let v_prev = (0..depth.len())
        .map(|j| channel(setup.prev_of(j), j))
        .collect::<Result<Vec<_>, _>>()?;
    let v_next = (0..depth.len())
        .map(|j| channel(setup.next_of(j), j))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(LinearMaps {
        size: n,
        depth,
        skins,
        v_prev,
        v_next,
    })
}

/// The maps of world-space caster `triangles` (depth maps ray-cast, then skins and channels).
pub fn linear_maps(triangles: &[[V3; 3]], setup: &LinearSetup) -> Result<LinearMaps, String> {
    setup.check()?;
    let depth = (0..setup.views.len())
        .map(|k| depth_map(triangles, setup, k))
        .collect::<Result<Vec<_>, _>>()?;
    linear_maps_from_depth(depth, setup)
}

/// Whether sample `k` sees `p` (the shadow-map test with the shade's bias); false at or
/// behind the eye, and for a sample or texel the maps do not hold.
pub fn lit(setup: &LinearSetup, maps: &LinearMaps, k: usize, p: V3) -> bool {
    let (Some(view), Some(depth)) = (setup.views.get(k), maps.depth.get(k)) else {
        return false;
    };
    match view.texel_of(p, maps.size).and_then(|(x, y)| depth.get(y * maps.size + x)) {
        Some(z) => view.depth(p) - setup.bias <= *z,
        None => false,
    }
}

/// The shaded visibility of a world point, unclamped (a channel the maps lack reads 0.5):
/// `sum_k lit_k (w_before_k v_prev_k + w_after_k v_next_k)`.
pub fn visibility(setup: &LinearSetup, maps: &LinearMaps, p: V3) -> f64 {
    let mut v = 0.0;
    for (k, view) in setup.views.iter().enumerate() {
        if !lit(setup, maps, k, p) {
            continue;
        }
        let Some((x, y)) = view.texel_of(p, maps.size) else { continue };
        let t = y * maps.size + x;
        let read = |c: &[Channel]| c.get(k).and_then(|c| c.value.get(t)).copied().unwrap_or(0.5);
        v += view.weights[0] * read(&maps.v_prev) + view.weights[1] * read(&maps.v_next);
    }
    v
}

/// [`visibility`] clamped to `[0, 1]`.
pub fn visibility_clamped(setup: &LinearSetup, maps: &LinearMaps, p: V3) -> f64 {
    let v = visibility(setup, maps, p);
    if v.is_nan() { 1.0 } else { v.clamp(0.0, 1.0) }
}

/// Set-up helpers: views and weights the way sshc fits them for tests.
pub mod fixtures {
    use super::*;

    /// A right-handed look-at view (world -> view, looking down `-z`).
    pub fn look_at(eye: V3, target: V3, up: V3) -> M4 {
        let norm = |v: V3| {
            let l = dot(v, v).sqrt();
            [v[0] / l, v[1] / l, v[2] / l]
        };
        let f = norm(sub(target, eye));
        let s = norm(cross(f, up));
        let u = cross(s, f);
        [
            s[0],
            u[0],
            -f[0],
            0.0,
            s[1],
            u[1],
            -f[1],
            0.0,
            s[2],
            u[2],
            -f[2],
            0.0,
            -dot(s, eye),
            -dot(u, eye),
            dot(f, eye),
            1.0,
        ]
    }

    /// A right-handed perspective projection of vertical field of view `fov_y` (square, depth
    /// to `[0, 1]`; only x, y and w matter to the technique).
    pub fn perspective(fov_y: f64, near: f64, far: f64) -> M4 {
        let f = 1.0 / (0.5 * fov_y).tan();
        let r = far / (near - far);
        [f, 0.0, 0.0, 0.0, 0.0, f, 0.0, 0.0, 0.0, 0.0, r, -1.0, 0.0, 0.0, r * near, 0.0]
    }

    /// `a b` for column-major 4 x 4 matrices.
    pub fn mul(a: &M4, b: &M4) -> M4 {
        let mut m = [0.0; 16];
        for c in 0..4 {
            for r in 0..4 {
                m[c * 4 + r] = (0..4).map(|k| a[k * 4 + r] * b[c * 4 + k]).sum();
            }
        }
        m
    }

    /// The weights of `n` evenly spaced samples of an open segment (`n = 1`: `[1, 1]`).
    pub fn segment_weights(n: usize) -> Vec<[f64; 2]> {
        if n == 1 {
            return vec![[1.0, 1.0]];
        }
        let w = 1.0 / (n - 1) as f64;
        (0..n)
            .map(|k| [if k > 0 { w } else { 0.0 }, if k + 1 < n { w } else { 0.0 }])
            .collect()
    }

    /// `n` samples evenly spaced on the segment `a..b` (ends included; `n = 1`: the midpoint),
    /// each looking from its position along `dir` with `up`, field of view `fov_y`, `near`,
    /// `far`.
    #[allow(clippy::too_many_arguments)]
    pub fn segment_views(a: V3, b: V3, n: usize, dir: V3, up: V3, fov_y: f64, near: f64, far: f64) -> Vec<LinearView> {
        let weights = segment_weights(n);
        let proj = perspective(fov_y, near, far);
        (0..n)
            .map(|k| {
                let s = if n == 1 { 0.5 } else { k as f64 / (n - 1) as f64 };
                let eye = add_scaled(a, sub(b, a), s);
                let view = look_at(eye, add_scaled(eye, dir, 1.0), up);
                LinearView {
                    view,
                    view_proj: mul(&proj, &view),
                    near,
                    far,
                    weights: weights[k],
                }
            })
            .collect()
    }

    /// A quad at height `z` (two triangles).
    pub fn quad(x0: f64, x1: f64, y0: f64, y1: f64, z: f64) -> Vec<[V3; 3]> {
        vec![[[x0, y0, z], [x1, y0, z], [x1, y1, z]], [[x0, y0, z], [x1, y1, z], [x0, y1, z]]]
    }
}
