//! An independent f64 CPU reference of penumbra limit maps (Lawlor 2006, "Interpolation-Friendly
//! Soft Shadow Maps") and of smoothies as Lawlor's section 3.1 describes them (Chan & Durand
//! 2003: "exactly the same approach", outer penumbra only), written from the paper alone,
//! without the compiler's code generator.
//!
//! The light view, the texel rays and the silhouettes are those of the penumbra-maps reference
//! ([`super::penumbra`]: [`PenumbraSetup`], [`silhouettes`]); its `resolve` field is not read.
//! Everything is computed in the light's view space (the light looks down `-z`, the view
//! distance is `Z = -z`).
//!
//! # Maps (Lawlor section 3.1, the three generation steps; section 2.2, the four channels)
//!
//! - **Image-plane coordinates**: a distant disk (orthographic view) uses the view `x, y` in
//!   world units; a local light (perspective view) uses `(x / Z, y / Z)` (tangent units).
//! - **Ribbons** ([`Ribbon`], step 2): each silhouette edge with projected end points `A`, `B`
//!   (length `L > 0`) becomes the rectangle `t in [-h, L + h]`, `|s| <= h` of its along
//!   coordinate `t` (0 at `A`) and across coordinate `s` (positive on the OUTWARD side: away
//!   from the interior of the edge's first face that faces the light, else its first face).
//!   Half-width `h = reach + 2 texels`: distant `reach = (far - min(Z_A, Z_B)) tan(angle / 2)`
//!   (1 texel = `2 half_height / N` world units), local `reach = L_r (1 / min(Z_A, Z_B) -
//!   1 / far)` (1 texel = `2 / (f N)` tangent units); smoothies double `reach`
//!   ([`PlmSetup::reach_scale`]). At an image point `q` of the ribbon, with
//!   `t_c = clamp(t, 0, L)`: the occluder depth `c` is the linear normalised depth of the edge
//!   point projecting to `t_c` (`Z` linear in `t` for a distant light, `1 / Z` for a local
//!   one); the signed distance `w = s` for `0 <= t <= L`, else `+|q - nearest end|`; the
//!   penumbra limit `p_i = w / S` with `S = tan(angle / 2) (far - near)` (distant) or
//!   `S = L_r (1 / near - 1 / far)` (local) (Lawlor section 3: `p_i = w s r`,
//!   `r = 1 / tan(lightAngle / 2)`, here in normalised depth so that equation 1 reads
//!   `l = 1/2 + 1/2 p_i / delta`; a light of size 0 gives `p_i = 2 sign(w)`); the depth-test
//!   key ("highest penumbra limit wins") is the penumbra-limit surface's linear normalised
//!   depth, `c + |p_i|` (distant) or, for a local
//!   light, the hyperbolic `H = (1 / near - 1 / C) / (1 / near - 1 / far) + |p_i|` taken back
//!   to a linear depth; clamped to `[0, 1]`. A texel takes the `c`, `p_i` of the ribbon with
//!   the smallest key at its centre (ties: the first ribbon in silhouette-edge order);
//!   uncovered texels read `c = 1`, `p_i = 0`.
//! - **g** (step 1): the nearest surface's linear normalised depth along the texel's ray over
//!   all faces ([`shadow_map`], 1 where the ray meets nothing), then raised to the outer
//!   penumbra limit: `g = min(g, key)`.
//! - **b** (step 3): the nearest linear normalised depth along the texel's ray among
//!   back-facing triangles (geometric normal `cross(b - a, c - a)` pointing away from the light:
//!   `n.z < 0` in view space for a distant light, the light's centre behind the plane,
//!   `dot(n, a) > 0`, for a local one; edge-on faces are neither) within `[near, far]` whose
//!   depth exceeds `c + bias_b` ("throw away geometry above or near the occluder depth c")
//!   and, inside the silhouette (`p_i < 0`), the inner penumbra limit plus `bias_b`
//!   (`key + bias_b`): a face there lies in the edge's umbra, where every ray to the light is
//!   already blocked, so it blocks no light the edge lets through (issue 35: under a low light
//!   a thin occluder's far face recedes fast behind its silhouette and, kept, blacked out its
//!   own inner penumbra); 1 if none.
//! - **p**: stored as `p_i / 4 + 1/2` (Lawlor section 2.2), so a unorm channel holds
//!   `p_i in [-2, 2]`.
//!
//! Ribbons are evaluated exactly at each texel centre (not rasterised), so a texel is covered
//! when its centre lies in the closed rectangle.
//!
//! # Lookup
//!
//! Texel `(i, j)` has its centre at uv `((i + 0.5) / N, (j + 0.5) / N)`; bilinear sampling
//! reads texels `floor(uv N - 0.5) + {0, 1}` clamped to the edge with weights
//! `fract(uv N - 0.5)`, each texel value first quantised to the storage precision
//! ([`quantise`]). [`plm_visibility`] evaluates equation 1 with `delta = d - c` (distant) or
//! `delta = (1 / C - 1 / Z) / (1 / near - 1 / far)` (local; Lawlor section 5: the hyperbolic
//! depth makes a local light distant; `Z` is the view distance of the receiver depth `d` after
//! the bias, as `d - c` is for a distant light), `l = sat(1/2 + 1/2 p_i / max(delta, 1e-6))`, then the
//! clamped equation 2, `l_g = sat(l + 4 [d < g] - 2 [d < c] + [d < b] - 1)`, and the
//! visibility-to-illumination table of appendix A ([`Table`], computed exactly rather than
//! looked up in a 1D texture). [`smoothie_visibility`] is the hard shadow map (nearest texel of
//! the unraised depth) with, where it says lit, `sat(1/2 p_i / max(delta, 1e-6))` when
//! `d > c` (the whole penumbra width placed outside the hard shadow), no table.
//!
//! Bilinear weights are exact here; GPU samplers quantise them (commonly to 8 fractional bits).

use super::Storage;
use super::penumbra::{AreaLight, LightProjection, PenumbraSetup, Silhouettes, ray_triangle, shadow_map, silhouettes};
use std::collections::HashMap;
use std::ops::Range;

type V3 = [f64; 3];
type V2 = [f64; 2];

fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: V3, b: V3) -> V3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}
fn finite(a: V3) -> bool {
    a.iter().all(|c| c.is_finite())
}

/// `sat(x)`: clamp to `[0, 1]`, NaN reading 0.
pub fn sat(x: f64) -> f64 {
    if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) }
}

/// The smallest `delta` (receiver depth below the occluder, normalised) equation 1 divides by.
pub const MIN_DELTA: f64 = 1e-6;

/// The light view (the penumbra-maps reference's) and the technique's `bias_b` (the margin,
/// in linear normalised depth, below the occluder depth `c` above which back faces are thrown
/// away from the `b` channel; the technique's default is 0.01).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlmSetup {
    pub light: PenumbraSetup,
    pub bias_b: f64,
    /// The ribbon's reach in units of the light's reach: 1 for penumbra limit maps (the
    /// half-width `h = reach + 2 texels`); 2 for smoothies, whose ramp
    /// `sat(1/2 p_i / delta)` places the whole penumbra width outside the hard shadow and so
    /// reaches 1 only at twice the penumbra limit maps' half-width (with 1, a smoothie's ramp
    /// is cut off at the ribbon's side and jumps to 1 there).
    pub reach_scale: f64,
}

impl PlmSetup {
    /// Penumbra limit maps with the default `bias_b = 0.01`.
    pub fn new(light: PenumbraSetup) -> PlmSetup {
        PlmSetup {
            light,
            bias_b: 0.01,
            reach_scale: 1.0,
        }
    }

    /// Smoothies: ribbons of twice the reach (`reach_scale = 2`), `bias_b = 0.01` (unused).
    pub fn smoothies(light: PenumbraSetup) -> PlmSetup {
        PlmSetup {
            reach_scale: 2.0,
            ..PlmSetup::new(light)
        }
    }

    /// Check the light ([`PenumbraSetup::check`]), `bias_b` (finite, `>= 0`) and
    /// `reach_scale` (finite, `> 0`).
    pub fn check(&self) -> Result<(), String> {
        self.light.check()?;
        if !(self.bias_b.is_finite() && self.bias_b >= 0.0) {
            return Err(format!("bias_b {} must be finite and >= 0", self.bias_b));
        }
        if !(self.reach_scale.is_finite() && self.reach_scale > 0.0) {
            return Err(format!("reach_scale {} must be finite and > 0", self.reach_scale));
        }
        Ok(())
    }

    /// Whether the light is a distant disk (orthographic view).
    pub fn distant(&self) -> bool {
        matches!(self.light.projection, LightProjection::Orthographic { .. })
    }

    /// One texel's width in image-plane units: `2 half_height / N` (world) or `2 / (f N)`
    /// (tangent).
    pub fn texel(&self) -> f64 {
        let n = self.light.size as f64;
        match self.light.projection {
            LightProjection::Orthographic { half_height } => 2.0 * half_height / n,
            LightProjection::Perspective { f } => 2.0 / (f * n),
        }
    }

    /// The image-plane point of the centre of texel `(i, j)` (row 0 at the top: `y = 1 - 2 v`).
    pub fn texel_centre(&self, i: usize, j: usize) -> V2 {
        let n = self.light.size as f64;
        let x = 2.0 * (i as f64 + 0.5) / n - 1.0;
        let y = 1.0 - 2.0 * (j as f64 + 0.5) / n;
        match self.light.projection {
            LightProjection::Orthographic { half_height: h } => [x * h, y * h],
            LightProjection::Perspective { f } => [x / f, y / f],
        }
    }

    /// A view-space point's image-plane point and view distance `Z`; `None` for a local light
    /// when `Z <= 0` (at or behind the light's centre) or a non-finite point.
    pub fn image(&self, q: V3) -> Option<(V2, f64)> {
        let z = -q[2];
        if !finite(q) {
            return None;
        }
        if self.distant() {
            Some(([q[0], q[1]], z))
        } else if z > 0.0 {
            Some(([q[0] / z, q[1] / z], z))
        } else {
            None
        }
    }

    /// The shadow-map uv of an image-plane point.
    pub fn uv(&self, p: V2) -> V2 {
        let (x, y) = match self.light.projection {
            LightProjection::Orthographic { half_height: h } => (p[0] / h, p[1] / h),
            LightProjection::Perspective { f } => (p[0] * f, p[1] * f),
        };
        [0.5 + 0.5 * x, 0.5 - 0.5 * y]
    }

    /// Linear normalised depth `(Z - near) / (far - near)` of a view distance `Z`.
    pub fn linear(&self, z: f64) -> f64 {
        (z - self.light.near) / (self.light.far - self.light.near)
    }

    /// The view distance of a linear normalised depth.
    pub fn distance(&self, d: f64) -> f64 {
        self.light.near + d * (self.light.far - self.light.near)
    }

    /// `tan(angle / 2)` (distant disk) or the light radius `L_r` (local light).
    pub fn spread(&self) -> f64 {
        match self.light.light {
            AreaLight::DistantDisk { angle } => (0.5 * angle).tan(),
            AreaLight::Sphere { radius } => radius,
        }
    }

    /// `S`, the image-plane distance for which `p_i = 1`: `tan(angle / 2) (far - near)` or
    /// `L_r (1 / near - 1 / far)`.
    pub fn limit_scale(&self) -> f64 {
        let (near, far) = (self.light.near, self.light.far);
        if self.distant() {
            self.spread() * (far - near)
        } else {
            self.spread() * (1.0 / near - 1.0 / far)
        }
    }

    /// `p_i = w / S` of a signed image-plane distance `w`; a light of size 0 (`S = 0`) gives
    /// `2 sign(w)`, the end of the stored range (so the map holds a hard edge, never an
    /// infinity or a NaN).
    pub fn penumbra_limit(&self, w: f64) -> f64 {
        let s = self.limit_scale();
        if s > 0.0 {
            w / s
        } else if w == 0.0 {
            0.0
        } else {
            2.0 * w.signum()
        }
    }

    /// Equation 1's `delta`: `d - c` (distant) or `(1 / C - 1 / Z) / (1 / near - 1 / far)`
    /// (local), `C`, `Z` the view distances of `c` and of the receiver depth `d` (both linear
    /// normalised, `d` after the bias). Non-finite results read [`MIN_DELTA`].
    pub fn delta(&self, d: f64, c: f64) -> f64 {
        let v = if self.distant() {
            d - c
        } else {
            let (near, far) = (self.light.near, self.light.far);
            (1.0 / self.distance(c) - 1.0 / self.distance(d)) / (1.0 / near - 1.0 / far)
        };
        if v.is_finite() { v } else { MIN_DELTA }
    }

    /// The depth-test key of an occluder depth `c` and penumbra limit `p_i` (see the module
    /// documentation), clamped to `[0, 1]`.
    pub fn key(&self, c: f64, p_i: f64) -> f64 {
        if self.distant() {
            return sat(c + p_i.abs());
        }
        let (near, far) = (self.light.near, self.light.far);
        let k = 1.0 / near - 1.0 / far;
        let h = sat((1.0 / near - 1.0 / self.distance(c)) / k + p_i.abs());
        if h >= 1.0 {
            return 1.0; // far, exactly
        }
        sat(self.linear(1.0 / (1.0 / near - h * k)))
    }
}

/// A soft-shadow ribbon of one silhouette edge (Lawlor section 3.1, step 2), in image-plane
/// coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ribbon {
    /// Index into [`Silhouettes::edges`].
    pub edge: usize,
    /// The projected end points (image plane) and their view distances `Z_A`, `Z_B`.
    pub a: V2,
    pub b: V2,
    pub z_a: f64,
    pub z_b: f64,
    /// `L = |B - A| > 0`, the unit vector from `A` to `B`, and the unit outward normal.
    pub length: f64,
    pub along: V2,
    pub outward: V2,
    /// `h = reach + 2 texels` (image-plane units).
    pub half_width: f64,
}

/// What one ribbon writes at an image point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RibbonSample {
    /// Along and across coordinates of the point (image-plane units).
    pub t: f64,
    pub s: f64,
    /// The signed distance `w` (image-plane units), the occluder depth `c` (linear normalised),
    /// the penumbra limit `p_i` and the depth-test key (linear normalised).
    pub w: f64,
    pub c: f64,
    pub p_i: f64,
    pub key: f64,
}

impl Ribbon {
    /// The ribbon at image point `q`, `None` outside its rectangle.
    pub fn at(&self, setup: &PlmSetup, q: V2) -> Option<RibbonSample> {
        let d = [q[0] - self.a[0], q[1] - self.a[1]];
        let t = d[0] * self.along[0] + d[1] * self.along[1];
        let s = d[0] * self.outward[0] + d[1] * self.outward[1];
        let (h, l) = (self.half_width, self.length);
        if !(t >= -h && t <= l + h && s.abs() <= h) {
            return None;
        }
        let tc = t.clamp(0.0, l);
        let z = if setup.distant() {
            self.z_a + (self.z_b - self.z_a) * (tc / l)
        } else {
            1.0 / (1.0 / self.z_a + (1.0 / self.z_b - 1.0 / self.z_a) * (tc / l))
        };
        let c = setup.linear(z);
        let w = if (0.0..=l).contains(&t) {
            s
        } else {
            let e = if t < 0.0 { self.a } else { self.b };
            (q[0] - e[0]).hypot(q[1] - e[1])
        };
        let p_i = setup.penumbra_limit(w);
        Some(RibbonSample {
            t,
            s,
            w,
            c,
            p_i,
            key: setup.key(c, p_i),
        })
    }
}

fn view_key(p: V3) -> [u64; 3] {
    p.map(|c| (c + 0.0).to_bits())
}

/// Per mesh, per edge (its two view-space end points' bits, ordered), the faces around it in
/// triangle order: (faces the light, the third vertex in view space). The weld, the
/// degenerate-triangle rule and the facing rule are those of [`silhouettes`].
type EdgeFaces = HashMap<(usize, [u64; 3], [u64; 3]), Vec<(bool, V3)>>;

fn edge_faces(triangles: &[[V3; 3]], meshes: &[Range<usize>], setup: &PenumbraSetup) -> EdgeFaces {
    let perspective = matches!(setup.projection, LightProjection::Perspective { .. });
    let mut out: EdgeFaces = HashMap::new();
    for (mesh, range) in meshes.iter().enumerate() {
        for tri in &triangles[range.clone()] {
            if !tri.iter().all(|p| finite(*p)) {
                continue;
            }
            let v = tri.map(|p| setup.to_view(p));
            let k = v.map(view_key);
            let w = tri.map(|p| p.map(|c| (c + 0.0).to_bits()));
            let n = cross(sub(v[1], v[0]), sub(v[2], v[0]));
            if w[0] == w[1] || w[1] == w[2] || w[0] == w[2] || n == [0.0; 3] || !finite(n) {
                continue;
            }
            let facing = if perspective { -dot(n, v[0]) > 0.0 } else { n[2] > 0.0 };
            for e in 0..3 {
                let (p, q, r) = (e, (e + 1) % 3, (e + 2) % 3);
                let (lo, hi) = if k[p] <= k[q] { (k[p], k[q]) } else { (k[q], k[p]) };
                out.entry((mesh, lo, hi)).or_default().push((facing, v[r]));
            }
        }
    }
    out
}

/// Silhouettes ([`silhouettes`]) and their ribbons. An edge draws no ribbon when it is seen
/// end-on (`L = 0`), when an end point cannot be projected (a local light and `Z <= 0`), when
/// its chosen face lies in the plane through the light and the edge (no interior side), or when
/// `h <= 0`.
pub fn ribbons(triangles: &[[V3; 3]], meshes: &[Range<usize>], setup: &PlmSetup) -> Result<(Silhouettes, Vec<Ribbon>), String> {
    setup.check()?;
    let light = &setup.light;
    let sil = silhouettes(triangles, meshes, light)?;
    let faces = edge_faces(triangles, meshes, light);
    let far = light.far;
    let mut out = Vec::new();
    for (k, e) in sil.edges.iter().enumerate() {
        let (va, vb) = (sil.vertices[e.a].position, sil.vertices[e.b].position);
        let (ka, kb) = (view_key(va), view_key(vb));
        let key = if ka <= kb { (e.mesh, ka, kb) } else { (e.mesh, kb, ka) };
        let Some(list) = faces.get(&key) else { continue };
        let Some(&(_, third)) = list.iter().find(|f| f.0).or(list.first()) else {
            continue;
        };
        let (Some((a, z_a)), Some((b, z_b))) = (setup.image(va), setup.image(vb)) else {
            continue;
        };
        let d = [b[0] - a[0], b[1] - a[1]];
        let length = d[0].hypot(d[1]);
        if !(length > 0.0 && length.is_finite()) {
            continue;
        }
        let along = [d[0] / length, d[1] / length];
        // The plane through the light ray(s) and the edge: m . x = 0 (perspective, m = a x b)
        // or m . (x - a) = 0 (orthographic, m = (b - a) x z). In the image plane its trace is
        // the projected edge and m.xy is that line's normal (the gradient of m . (q, -1), or of
        // m . (q - a)); a point of the face near the edge has Z > 0, so the face's interior
        // lies on the side sign(m . third) (perspective, m . a = 0) or sign(m . (third - a)).
        let (m, side) = if setup.distant() {
            let m = cross(sub(vb, va), [0.0, 0.0, 1.0]);
            (m, dot(m, sub(third, va)))
        } else {
            let m = cross(va, vb);
            (m, dot(m, third))
        };
        let ml = m[0].hypot(m[1]);
        if side == 0.0 || !side.is_finite() || ml.is_nan() || ml <= 0.0 {
            continue;
        }
        let outward = [-side.signum() * m[0] / ml, -side.signum() * m[1] / ml];
        let zmin = z_a.min(z_b);
        let reach = if setup.distant() {
            (far - zmin) * setup.spread()
        } else {
            setup.spread() * (1.0 / zmin - 1.0 / far)
        };
        let half_width = setup.reach_scale * reach + 2.0 * setup.texel();
        if !(half_width > 0.0 && half_width.is_finite()) {
            continue;
        }
        out.push(Ribbon {
            edge: k,
            a,
            b,
            z_a,
            z_b,
            length,
            along,
            outward,
            half_width,
        });
    }
    Ok((sil, out))
}

/// The four channels per texel (row-major, row 0 first), all linear normalised depths except
/// `p_i`; f64, unquantised.
#[derive(Clone, Debug, PartialEq)]
pub struct PlmMaps {
    pub size: usize,
    /// The unraised nearest-surface depth (the Depth pass; 1 where the ray meets nothing).
    pub depth: Vec<f64>,
    /// `g = min(depth, key of the winning ribbon)`.
    pub g: Vec<f64>,
    /// The winning ribbon's occluder depth (1 uncovered).
    pub c: Vec<f64>,
    /// The nearest back face deeper than `c + bias_b`, and than `key + bias_b` where
    /// `p_i < 0` (1 if none).
    pub b: Vec<f64>,
    /// The winning ribbon's penumbra limit (0 uncovered); stored as `p_i / 4 + 1/2`.
    pub p_i: Vec<f64>,
    /// The winning ribbon's key (1 uncovered).
    pub key: Vec<f64>,
    /// Index into the ribbons of the winning ribbon, for debugging.
    pub winner: Vec<Option<usize>>,
}

impl PlmMaps {
    /// Maps read back from a penumbra limit map as stored (Lawlor section 2.2: `c`, `g`, `b` and
    /// `p = p_i / 4 + 1/2`, each `size x size`, row-major, row 0 first) and the unraised depth
    /// (smoothies' hard test), e.g. a generated map to shade with [`plm_shade`]; `key` and
    /// `winner` are unknown (NaN, `None`). Refused when a channel has the wrong length.
    pub fn from_stored(size: usize, depth: &[f64], g: &[f64], c: &[f64], b: &[f64], p: &[f64]) -> Result<PlmMaps, String> {
        let texels = size * size;
        for (name, v) in [("depth", depth), ("g", g), ("c", c), ("b", b), ("p", p)] {
            if size == 0 || v.len() != texels {
                return Err(format!(
                    "channel `{name}` has {} values; a {size} x {size} map needs {texels}",
                    v.len()
                ));
            }
        }
        Ok(PlmMaps {
            size,
            depth: depth.to_vec(),
            g: g.to_vec(),
            c: c.to_vec(),
            b: b.to_vec(),
            p_i: p.iter().map(|p| 4.0 * (p - 0.5)).collect(),
            key: vec![f64::NAN; texels],
            winner: vec![None; texels],
        })
    }
}

/// Whether a view-space triangle faces away from the light (see the module documentation).
pub fn back_facing(setup: &PlmSetup, tri: &[V3; 3]) -> bool {
    let n = cross(sub(tri[1], tri[0]), sub(tri[2], tri[0]));
    if setup.distant() { n[2] < 0.0 } else { dot(n, tri[0]) > 0.0 }
}

/// The winning ribbon at an image point: its index and sample (the smallest key, the first
/// on ties), `None` when no ribbon covers it.
pub fn winner(setup: &PlmSetup, ribbons: &[Ribbon], q: V2) -> Option<(usize, RibbonSample)> {
    let mut best: Option<(usize, RibbonSample)> = None;
    for (k, r) in ribbons.iter().enumerate() {
        if let Some(s) = r.at(setup, q)
            && best.is_none_or(|(_, b)| s.key < b.key)
        {
            best = Some((k, s));
        }
    }
    best
}

/// The maps of world-space `triangles` grouped into `meshes` (ranges of triangle indices),
/// given the ribbons ([`ribbons`]).
pub fn plm_maps(triangles: &[[V3; 3]], setup: &PlmSetup, ribbons: &[Ribbon]) -> Result<PlmMaps, String> {
    setup.check()?;
    let light = &setup.light;
    let n = light.size;
    let shadow = shadow_map(triangles, light)?;
    let view: Vec<[V3; 3]> = triangles
        .iter()
        .map(|t| t.map(|p| light.to_view(p)))
        .filter(|t| t.iter().all(|p| finite(*p)) && back_facing(setup, t))
        .collect();
    let mut maps = PlmMaps {
        size: n,
        depth: vec![1.0; n * n],
        g: vec![1.0; n * n],
        c: vec![1.0; n * n],
        b: vec![1.0; n * n],
        p_i: vec![0.0; n * n],
        key: vec![1.0; n * n],
        winner: vec![None; n * n],
    };
    for j in 0..n {
        for i in 0..n {
            let k = j * n + i;
            let depth = if shadow.hit[k] { shadow.z(light, k) } else { 1.0 };
            maps.depth[k] = depth;
            let q = setup.texel_centre(i, j);
            if let Some((r, s)) = winner(setup, ribbons, q) {
                maps.c[k] = s.c;
                maps.p_i[k] = s.p_i;
                maps.key[k] = s.key;
                maps.winner[k] = Some(r);
            }
            maps.g[k] = depth.min(maps.key[k]);
            let (o, d) = light.texel_ray(i, j);
            // inside the silhouette, the inner penumbra limit (the module documentation)
            let floor = if maps.p_i[k] < 0.0 { maps.key[k] } else { maps.c[k] } + setup.bias_b;
            for t in &view {
                if let Some(z) = ray_triangle(o, d, t)
                    && z >= light.near
                    && z <= light.far
                {
                    let z = setup.linear(z);
                    if z > floor && z < maps.b[k] {
                        maps.b[k] = z;
                    }
                }
            }
        }
    }
    Ok(maps)
}

/// Silhouettes, ribbons and maps of one light.
#[derive(Clone, Debug, PartialEq)]
pub struct PlmReference {
    pub silhouettes: Silhouettes,
    pub ribbons: Vec<Ribbon>,
    pub maps: PlmMaps,
}

impl PlmReference {
    /// Everything for world-space `triangles` grouped into `meshes`.
    pub fn new(triangles: &[[V3; 3]], meshes: &[Range<usize>], setup: &PlmSetup) -> Result<PlmReference, String> {
        let (silhouettes, ribbons) = ribbons(triangles, meshes, setup)?;
        let maps = plm_maps(triangles, setup, &ribbons)?;
        Ok(PlmReference {
            silhouettes,
            ribbons,
            maps,
        })
    }
}

/// A value as stored at `storage`: Unorm8 `round(sat(v) 255) / 255`, Unorm16 the same with
/// 65535, F16 binary16 round-to-nearest-even (the `half` crate), F32 binary32; `None` keeps the
/// f64 value.
pub fn quantise(v: f64, storage: Option<Storage>) -> f64 {
    match storage {
        None => v,
        Some(Storage::Unorm8) => (sat(v) * 255.0).round() / 255.0,
        Some(Storage::Unorm16) => (sat(v) * 65535.0).round() / 65535.0,
        Some(Storage::F16) => half::f16::from_f64(v).to_f64(),
        Some(Storage::F32) => v as f32 as f64,
    }
}

/// Bilinear sample of a square `size x size` channel at `uv` (clamp to edge, texel centres at
/// `(i + 0.5) / size`), each texel's value quantised by `stored` first.
pub fn bilinear(values: &[f64], size: usize, uv: V2, stored: impl Fn(f64) -> f64) -> f64 {
    let n = size as f64;
    let x = uv[0] * n - 0.5;
    let y = uv[1] * n - 0.5;
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let last = size as i64 - 1;
    let at = |i: f64, j: f64| {
        let i = (i.clamp(-1.0, n) as i64).clamp(0, last) as usize;
        let j = (j.clamp(-1.0, n) as i64).clamp(0, last) as usize;
        stored(values[j * size + i])
    };
    let top = at(x0, y0) * (1.0 - fx) + at(x0 + 1.0, y0) * fx;
    let bottom = at(x0, y0 + 1.0) * (1.0 - fx) + at(x0 + 1.0, y0 + 1.0) * fx;
    top * (1.0 - fy) + bottom * fy
}

/// The four channels sampled bilinearly at one uv.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sampled {
    pub g: f64,
    pub c: f64,
    pub b: f64,
    /// Unpacked from the stored `p = p_i / 4 + 1/2`: `p_i = 4 (p - 1/2)`.
    pub p_i: f64,
}

/// Sample `g`, `c`, `b` and `p` bilinearly at `uv`, stored at `storage` (`None`: unquantised).
pub fn sample(maps: &PlmMaps, uv: V2, storage: Option<Storage>) -> Sampled {
    let q = |v: f64| quantise(v, storage);
    let n = maps.size;
    let p = bilinear(&maps.p_i, n, uv, |p_i| quantise(p_i / 4.0 + 0.5, storage));
    Sampled {
        g: bilinear(&maps.g, n, uv, q),
        c: bilinear(&maps.c, n, uv, q),
        b: bilinear(&maps.b, n, uv, q),
        p_i: 4.0 * (p - 0.5),
    }
}

/// The visibility-to-illumination table of Lawlor's appendix A.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Table {
    /// A uniform disk: `f(l) = 1/2 + (u sqrt(1 - u^2) + asin u) / pi`, `u = 2 l - 1`.
    UniformDisk,
    /// A limb-darkened sun, intensity `I(mu) = 1 - 0.6 (1 - mu)`, `mu = sqrt(1 - r^2)`: the
    /// fraction of the disk's power on the visible side `x <= u` of the chord at `u = 2 l - 1`.
    /// Integrating `I` across the chord at `x` (half length `a = sqrt(1 - x^2)`) gives
    /// `0.8 a + 0.3 pi a^2`, the whole disk `0.8 pi`, so
    /// `f = [0.4 (u a + asin u + pi / 2) + 0.3 pi (u - u^3 / 3 + 2 / 3)] / (0.8 pi)`.
    LimbDarkened,
}

impl Table {
    /// `f(l)` for `l` in `[0, 1]` (clamped).
    pub fn illumination(self, l: f64) -> f64 {
        let u = (2.0 * sat(l) - 1.0).clamp(-1.0, 1.0);
        let a = (1.0 - u * u).max(0.0).sqrt();
        let pi = std::f64::consts::PI;
        let f = match self {
            Table::UniformDisk => 0.5 + (u * a + u.asin()) / pi,
            Table::LimbDarkened => (0.4 * (u * a + u.asin() + 0.5 * pi) + 0.3 * pi * (u - u * u * u / 3.0 + 2.0 / 3.0)) / (0.8 * pi),
        };
        sat(f)
    }
}

/// A world point's shadow-map uv and linear normalised depth (before any bias); `None` when a
/// local light cannot project it.
pub fn receiver(setup: &PlmSetup, p: V3) -> Option<(V2, f64)> {
    let (q, z) = setup.image(setup.light.to_view(p))?;
    Some((setup.uv(q), setup.linear(z)))
}

/// Every step of the penumbra-limit-map lookup at one receiver.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shade {
    /// The receiver depth `d` (linear normalised, after the bias) and the sampled channels.
    pub d: f64,
    pub sampled: Sampled,
    /// Equation 1's `delta`, `l` (equation 1, saturated) and `l_g` (equation 2).
    pub delta: f64,
    pub l: f64,
    pub l_g: f64,
    /// `table(l_g)`.
    pub visibility: f64,
}

/// Penumbra-limit-map shading of a receiver at linear normalised depth `d` (after the bias)
/// and uv `uv`: equations 1 and 2 (Lawlor section 2.1) and `table`.
pub fn plm_shade(setup: &PlmSetup, maps: &PlmMaps, uv: V2, d: f64, storage: Option<Storage>, table: Table) -> Shade {
    let s = sample(maps, uv, storage);
    let delta = setup.delta(d, s.c);
    let l = sat(0.5 + 0.5 * s.p_i / delta.max(MIN_DELTA));
    let step = |x: bool| if x { 1.0 } else { 0.0 };
    let l_g = sat(l + 4.0 * step(d < s.g) - 2.0 * step(d < s.c) + step(d < s.b) - 1.0);
    Shade {
        d,
        sampled: s,
        delta,
        l,
        l_g,
        visibility: table.illumination(l_g),
    }
}

/// Penumbra-limit-map visibility in `[0, 1]` of a world-space receiver `p`: its depth less
/// `bias` (linear normalised units), the maps sampled bilinearly at `storage` (`None`:
/// unquantised), equations 1 and 2 and `table`. A point a local light cannot project reads 1.
pub fn plm_visibility(setup: &PlmSetup, maps: &PlmMaps, p: V3, bias: f64, storage: Option<Storage>, table: Table) -> f64 {
    match receiver(setup, p) {
        Some((uv, d)) => plm_shade(setup, maps, uv, d - bias, storage, table).visibility,
        None => 1.0,
    }
}

/// Smoothie visibility (outer penumbra only) of a receiver at linear normalised depth `d`
/// (after the bias) and uv: 0 when the hard shadow map (the unraised depth at the nearest
/// texel, stored as f32 unless `storage` is `None`) says shadowed, else
/// `sat(1/2 p_i / max(delta, 1e-6))` when `d > c`, else 1; `c` and `p` bilinear at `storage`.
pub fn smoothie_shade(setup: &PlmSetup, maps: &PlmMaps, uv: V2, d: f64, storage: Option<Storage>) -> f64 {
    let n = maps.size;
    let last = n as i64 - 1;
    let nf = n as f64;
    let i = ((uv[0] * nf).floor().clamp(-1.0, nf) as i64).clamp(0, last) as usize;
    let j = ((uv[1] * nf).floor().clamp(-1.0, nf) as i64).clamp(0, last) as usize;
    let depth = maps.depth[j * n + i];
    let depth = if storage.is_some() { depth as f32 as f64 } else { depth };
    if d > depth {
        return 0.0;
    }
    let s = sample(maps, uv, storage);
    if d > s.c {
        sat(0.5 * s.p_i / setup.delta(d, s.c).max(MIN_DELTA))
    } else {
        1.0
    }
}

/// [`smoothie_shade`] of a world-space receiver `p` with its depth less `bias`. A point a
/// local light cannot project reads 1.
pub fn smoothie_visibility(setup: &PlmSetup, maps: &PlmMaps, p: V3, bias: f64, storage: Option<Storage>) -> f64 {
    match receiver(setup, p) {
        Some((uv, d)) => smoothie_shade(setup, maps, uv, d - bias, storage),
        None => 1.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn limb_darkened_table_matches_numerical_integration() {
        // integrate I(r) over the disk's part x <= u on a fine grid (midpoint rule)
        let n = 1200;
        let h = 2.0 / n as f64;
        let power = |u: f64| {
            let mut sum = 0.0;
            for a in 0..n {
                let x = -1.0 + (a as f64 + 0.5) * h;
                if x > u {
                    continue;
                }
                for b in 0..n {
                    let y = -1.0 + (b as f64 + 0.5) * h;
                    let r2 = x * x + y * y;
                    if r2 < 1.0 {
                        sum += 1.0 - 0.6 * (1.0 - (1.0 - r2).sqrt());
                    }
                }
            }
            sum
        };
        let total = power(1.0);
        for l in [0.0, 0.1, 0.25, 0.5, 0.7, 0.95, 1.0] {
            let want = power(2.0 * l - 1.0) / total;
            let got = Table::LimbDarkened.illumination(l);
            // the grid's boundary error: a band one cell wide around the disk's rim and the chord
            assert!((got - want).abs() < 4e-3, "l {l}: {got} vs {want}");
        }
        // complementarity f(l) = 1 - f(1 - l) (appendix A, figure 12), and limb darkening
        // flattens the curve (figure 12): a dim limb uncovered first, below the uniform
        // disk's for l < 1/2
        for k in 0..=20 {
            let l = k as f64 / 20.0;
            for t in [Table::UniformDisk, Table::LimbDarkened] {
                assert!((t.illumination(l) + t.illumination(1.0 - l) - 1.0).abs() < 1e-12);
            }
            if l > 0.0 && l < 0.5 {
                assert!(Table::LimbDarkened.illumination(l) < Table::UniformDisk.illumination(l));
            }
        }
        // "covering up the first 10% of the diameter of a disk light source decreases the
        // delivered illumination by less than 6%"
        assert!(1.0 - Table::UniformDisk.illumination(0.9) < 0.06);
    }

    use crate::reference::penumbra::Resolve;
    use crate::reference::penumbra::fixtures::{cuboid, quad, scene, sphere};

    const IDENTITY: [f64; 16] = [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0];

    fn disk(size: usize) -> PlmSetup {
        PlmSetup::new(PenumbraSetup {
            view: IDENTITY,
            projection: LightProjection::Orthographic { half_height: 4.0 },
            near: 1.0,
            far: 11.0,
            size,
            light: AreaLight::DistantDisk { angle: 0.2 },
            resolve: Resolve::KeepMin,
        })
    }

    #[test]
    fn ribbons_point_away_from_the_lit_face() {
        // a closed box: its top outline, each ribbon's outward side away from the box, under a
        // distant disk and a sphere light (where the sides of the box also face away)
        let (tris, meshes) = scene(&[cuboid([-1.0, -1.0, -6.0], [1.0, 1.0, -4.0])]);
        for setup in [disk(32), PlmSetup::new(sphere(0.5, 32, Resolve::KeepMin))] {
            let (sil, rbs) = ribbons(&tris, &meshes, &setup).unwrap();
            assert_eq!(rbs.len(), 4, "{:?}", setup.light.projection);
            for rb in &rbs {
                let e = sil.edges[rb.edge];
                assert!(sil.vertices[e.a].position[2] == -4.0 && sil.vertices[e.b].position[2] == -4.0);
                let mid = [(rb.a[0] + rb.b[0]) / 2.0, (rb.a[1] + rb.b[1]) / 2.0];
                // the outward normal points from the edge's middle away from the box's centre
                assert!(mid[0] * rb.outward[0] + mid[1] * rb.outward[1] > 0.0);
                assert!((rb.outward[0].hypot(rb.outward[1]) - 1.0).abs() < 1e-12);
            }
        }
        // one-sided quads wound either way: the same outward side (the face's, not its winding)
        for z in [-5.0] {
            let up = quad(-1.0, 0.0, -1.0, 1.0, z);
            let down: Vec<[V3; 3]> = up.iter().map(|t| [t[0], t[2], t[1]]).collect();
            for q in [up, down] {
                let (tris, meshes) = scene(&[q]);
                let (_, rbs) = ribbons(&tris, &meshes, &disk(32)).unwrap();
                let right = rbs.iter().find(|rb| rb.a[0] == 0.0 && rb.b[0] == 0.0).unwrap();
                assert_eq!(right.outward, [1.0, 0.0]);
            }
        }
    }

    #[test]
    fn keys_pick_the_highest_penumbra_limit() {
        // two parallel edges at different depths covering one point: the one whose penumbra
        // limit surface is higher (smaller key) wins, whichever is drawn first
        let (tris, meshes) = scene(&[quad(-3.0, 0.0, -3.0, 3.0, -3.0), quad(-3.0, 0.3, -3.0, 3.0, -6.0)]);
        let setup = disk(64);
        let (_, rbs) = ribbons(&tris, &meshes, &setup).unwrap();
        let q = [0.2, 0.0];
        let (k, s) = winner(&setup, &rbs, q).unwrap();
        let all: Vec<RibbonSample> = rbs.iter().filter_map(|r| r.at(&setup, q)).collect();
        assert!(all.len() >= 2);
        assert!(all.iter().all(|o| o.key >= s.key));
        let mut reversed = rbs.clone();
        reversed.reverse();
        let (k2, s2) = winner(&setup, &reversed, q).unwrap();
        assert_eq!(rbs[k], reversed[k2]);
        assert_eq!(s, s2);
        // the winner is the upper edge (x = 0 at depth 3): c there, p_i = 0.2 / S
        assert!((s.c - setup.linear(3.0)).abs() < 1e-12);
        assert!((s.p_i - 0.2 / setup.limit_scale()).abs() < 1e-12);
        // a local light's key is the penumbra limit surface's linear depth: at p_i = 0 it is c,
        // and it grows with |p_i| up to 1
        let local = PlmSetup::new(sphere(0.5, 32, Resolve::KeepMin));
        for c in [0.0, 0.2, 0.7, 1.0] {
            assert!((local.key(c, 0.0) - c).abs() < 1e-12);
            assert!(local.key(c, 0.1) > c || c == 1.0);
            assert_eq!(local.key(c, 5.0), 1.0);
        }
    }

    #[test]
    fn stored_maps_shade_as_the_reference() {
        let (tris, meshes) = scene(&[quad(-6.0, 6.0, -6.0, 6.0, -10.0), quad(-1.0, 1.0, -1.0, 1.0, -5.0)]);
        let setup = disk(32);
        let r = PlmReference::new(&tris, &meshes, &setup).unwrap();
        let m = &r.maps;
        let p: Vec<f64> = m.p_i.iter().map(|p| p / 4.0 + 0.5).collect();
        let stored = PlmMaps::from_stored(32, &m.depth, &m.g, &m.c, &m.b, &p).unwrap();
        for k in 0..200 {
            let x = -3.0 + 6.0 * k as f64 / 200.0;
            let pt = [x, 0.3, -10.0];
            for storage in [None, Some(Storage::Unorm8)] {
                let (a, b) = (
                    plm_visibility(&setup, m, pt, 1e-4, storage, Table::UniformDisk),
                    plm_visibility(&setup, &stored, pt, 1e-4, storage, Table::UniformDisk),
                );
                assert!((a - b).abs() < 1e-12, "{x}: {a} vs {b}");
            }
        }
        let err = PlmMaps::from_stored(32, &m.depth, &m.g, &m.c[1..], &m.b, &p).unwrap_err();
        assert!(err.contains("channel `c` has 1023 values"), "{err}");
    }

    #[test]
    fn quantise_rounds_as_stored() {
        assert_eq!(quantise(0.5 / 255.0 + 1e-9, Some(Storage::Unorm8)), 1.0 / 255.0);
        assert_eq!(quantise(-0.3, Some(Storage::Unorm8)), 0.0);
        assert_eq!(quantise(1.7, Some(Storage::Unorm16)), 1.0);
        // 1 + 2^-11 is halfway between two f16 values: ties to even (1.0)
        assert_eq!(quantise(1.0 + 2f64.powi(-11), Some(Storage::F16)), 1.0);
        assert_eq!(quantise(1.0 + 3.0 * 2f64.powi(-11), Some(Storage::F16)), 1.0 + 2f64.powi(-9));
        assert_eq!(quantise(0.1, Some(Storage::F32)), 0.1f32 as f64);
        assert_eq!(quantise(0.1, None), 0.1);
    }
}
