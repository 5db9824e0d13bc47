//! `sshc-light`: lights and the views their shadow maps are rendered from, as plain math
//! (glam, no GPU), shared by the runtime (a host's light each frame, `sshc_runtime::light`)
//! and the lab's scenes (`sshc-scene`, whose files name these lights).
//!
//! - [`Light`]: the kinds of light, their geometry (centre, direction, outline, bounding
//!   radius) and the positions of the sample views of per-sample techniques
//!   ([`Light::sample_chain`], Heidrich et al. 2000).
//! - [`LightView`]: a light's view and projection, with the extents the passes read.
//! - Fits: [`Light::view`] fits a view to a box (the `Scene` fit); [`casters_view`] fits it
//!   to the shadow casters padded by their penumbra's reach (the `Casters` fit), from any
//!   set of points that holds them ([`Occluders`]: a scene's vertices in the lab, the
//!   corners of the instances' bounding boxes in a host, every frame).
//!   [`sample_views`] makes the per-sample views and weights of a linear or area light.
//! - What a valid light is ([`Light::fault`], `valid.rs`): the runtime's [`Light::check`]
//!   and the scene files' [`Light::checked`] both word it.
//!
//! Conventions: right-handed world, +Y up, views look down -Z, projections map depth to
//! WebGPU's [0, 1]. Matrices are glam's (column-major).

#![deny(clippy::wildcard_enum_match_arm)]

mod cascades;
pub use cascades::{CameraFrustum, Cascade, MAX_CASCADES, cascade_views, practical_splits};
mod valid;
pub use valid::{LightFault, Problem};

/// Most lights one frame combines: the runtime gathers their visibilities four lights to an
/// RGBA layer (`Targets::visibility`, light `l` in layer `l / 4`, channel `l % 4`), and each
/// light runs every pass of the technique and the camera raster once a frame. The runtime
/// refuses more at binding; scene loaders refuse more when reading.
pub const MAX_LIGHTS: usize = 16;

use glam::{Mat4, Vec2, Vec3, Vec4};
use serde::{Deserialize, Serialize};

pub use sshc_graph::LightKind;

pub use glam;

/// A light. Visibility from a point is the fraction of the light that the point sees
/// (the ground truth of docs/truth.md); how each kind is sampled is in `sshc_lab::visibility`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Light {
    /// A point light.
    Point {
        /// World position.
        position: Vec3,
    },
    /// A light at infinity with no extent (parallel rays).
    Directional {
        /// Direction from the scene towards the light, e.g. (0, 1, 0) for straight
        /// overhead. Normalised on load.
        direction: Vec3,
    },
    /// A sphere, sampled uniformly over the cone it subtends from the receiver.
    Sphere {
        /// Centre, world space.
        center: Vec3,
        /// Radius, >= 0 (0 behaves as a point light).
        radius: f32,
    },
    /// A flat disk, sampled uniformly over its area.
    Disk {
        /// Centre, world space.
        center: Vec3,
        /// Normal of the disk's plane (the side it faces). Normalised on load.
        normal: Vec3,
        /// Radius, >= 0.
        radius: f32,
    },
    /// A rectangle, sampled uniformly over its area.
    Rectangle {
        /// Centre, world space.
        center: Vec3,
        /// Normal of the rectangle's plane (the side it faces). Normalised on load.
        normal: Vec3,
        /// Direction of the `half_width` side; its component along `normal` is removed
        /// and it is normalised on load. The other side runs along `normal x u_axis`.
        u_axis: Vec3,
        /// Half the extent along `u_axis`, >= 0.
        half_width: f32,
        /// Half the extent along `normal x u_axis`, >= 0.
        half_height: f32,
    },
    /// A linear light from `a` to `b`, sampled uniformly over its length.
    Segment {
        /// One end, world space.
        a: Vec3,
        /// The other end, world space.
        b: Vec3,
    },
    /// A disk at infinity (the sun), sampled uniformly over its disk in the tangent plane,
    /// i.e. directions within the cone of half-angle `angle_degrees / 2` around
    /// `direction`.
    DistantDisk {
        /// Direction from the scene towards the disk's centre. Normalised on load.
        direction: Vec3,
        /// Full angular diameter in degrees, in [0, 180). The sun is about 0.53.
        angle_degrees: f32,
    },
    /// A triangle, sampled uniformly over its area (two-sided, as every light here).
    /// Per-sample techniques take its three edges as linear lights (Heidrich et al. 2000,
    /// section 4, figure 8: the "crude approximation" of an area light by its outline).
    Triangle {
        /// First corner, world space.
        a: Vec3,
        /// Second corner, world space.
        b: Vec3,
        /// Third corner, world space.
        c: Vec3,
    },
}

/// The view of a light used to rasterise a shadow map.
///
/// The shaders compute linear depth as `(-(view * p).z - near) / (far - near)`; `near` and
/// `far` are view-space distances along the view axis, fitted so that every corner of the
/// bounds it was fitted to has linear depth in [0, 1] and lies inside the clip volume.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightView {
    /// World to light view (right-handed, looking down -Z).
    pub view: Mat4,
    /// Light view to clip space (depth range [0, 1]).
    pub proj: Mat4,
    /// `proj * view`.
    pub view_proj: Mat4,
    /// Near distance along the view axis, > 0.
    pub near: f32,
    /// Far distance along the view axis, > near.
    pub far: f32,
    /// `w = 1`: the light's centre (point-like lights); `w = 0`: unit direction towards
    /// the light (directional and distant-disk lights).
    pub position_or_direction: Vec4,
    /// Radius (sphere, disk), half of the larger side (rectangle), half length (segment),
    /// the farthest corner's distance from the centroid (triangle), 0 for point and directional lights, and `tan(angle / 2)` for a distant disk (the
    /// radius of its disk in the tangent plane at unit distance).
    pub size: f32,
    /// Half-extents of the light's outline along the view's x and y axes (the shadow map's
    /// u and v): r for a sphere, a disk or rectangle projected onto each axis, half the
    /// projected length for a segment, the farthest corner's projected offset from the
    /// centroid for a triangle, 0 for the rest.
    pub half_extents: Vec2,
    /// Full angular diameter in radians for a distant disk, else 0.
    pub angle: f32,
    /// True for an orthographic view (directional and distant-disk lights).
    pub orthographic: bool,
}

/// Right-handed view matrix looking from `eye` at `target` (view space: -Z forward, +Y up).
pub fn look_at(eye: Vec3, target: Vec3, up: Vec3) -> Mat4 {
    glam::camera::rh::view::look_at_mat4(eye, target, up)
}

/// Right-handed perspective projection to WebGPU clip space (depth [0, 1], Y up), as
/// `Mat4::perspective_rh` of older glam.
pub fn perspective(fov_y: f32, aspect: f32, near: f32, far: f32) -> Mat4 {
    glam::camera::rh::proj::directx::perspective(fov_y, aspect, near, far)
}

/// Right-handed perspective projection with no far plane, to WebGPU clip space (depth
/// `1 - near / distance`: [0, 1) from the near plane out).
pub fn perspective_infinite(fov_y: f32, aspect: f32, near: f32) -> Mat4 {
    glam::camera::rh::proj::directx::perspective_infinite(fov_y, aspect, near)
}

/// Right-handed perspective projection with no far plane and reversed depth (depth
/// `near / distance`: 1 at the near plane, towards 0 far away), as engines use it for its
/// precision (Bevy's default). A camera built with it is given to the runtime through
/// `Camera::from_reverse_z`.
pub fn perspective_infinite_reverse(fov_y: f32, aspect: f32, near: f32) -> Mat4 {
    glam::camera::rh::proj::directx::perspective_infinite_reverse(fov_y, aspect, near)
}

/// Right-handed orthographic projection to WebGPU clip space (depth [0, 1], Y up), as
/// `Mat4::orthographic_rh` of older glam.
pub fn orthographic(left: f32, right: f32, bottom: f32, top: f32, near: f32, far: f32) -> Mat4 {
    glam::camera::rh::proj::directx::orthographic(left, right, bottom, top, near, far)
}

/// Smallest and largest view-space distance (-z) of the corners of `bounds`.
pub fn depth_range(view: &Mat4, bounds: (Vec3, Vec3)) -> (f32, f32) {
    let mut lo = f32::INFINITY;
    let mut hi = f32::NEG_INFINITY;
    for c in corners(bounds) {
        let d = -view.transform_point3(c).z;
        lo = lo.min(d);
        hi = hi.max(d);
    }
    (lo, hi)
}

/// The 8 corners of a box.
pub fn corners((lo, hi): (Vec3, Vec3)) -> [Vec3; 8] {
    std::array::from_fn(|i| {
        Vec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    })
}

pub fn bounds_of(points: impl Iterator<Item = Vec3>) -> (Vec3, Vec3) {
    let (lo, hi) = points.fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| (lo.min(p), hi.max(p)));
    if lo.cmple(hi).all() { (lo, hi) } else { (Vec3::ZERO, Vec3::ZERO) }
}

/// A unit vector not parallel to `dir`, for `look_at` up vectors and tangent frames.
pub fn any_perpendicular_up(dir: Vec3) -> Vec3 {
    if dir.normalize_or_zero().dot(Vec3::Y).abs() < 0.99 {
        Vec3::Y
    } else {
        Vec3::Z
    }
}

// ---------------------------------------------------------------------------------------
// Lights
// ---------------------------------------------------------------------------------------

impl Light {
    /// The light's kind (the schema's one list of kinds, shared with techniques'
    /// light models).
    pub fn kind(&self) -> LightKind {
        match self {
            Light::Point { .. } => LightKind::Point,
            Light::Directional { .. } => LightKind::Directional,
            Light::Sphere { .. } => LightKind::Sphere,
            Light::Disk { .. } => LightKind::Disk,
            Light::Rectangle { .. } => LightKind::Rectangle,
            Light::Segment { .. } => LightKind::Segment,
            Light::DistantDisk { .. } => LightKind::DistantDisk,
            Light::Triangle { .. } => LightKind::Triangle,
        }
    }

    /// The variant's name as written in a scene file.
    pub fn kind_name(&self) -> &'static str {
        self.kind().name()
    }

    /// True for lights at infinity (directional, distant disk).
    pub fn is_distant(&self) -> bool {
        self.kind().is_distant()
    }

    /// The light moved by `by`: every point of it. A light at infinity is unchanged (it
    /// has no position).
    pub fn translated(&self, by: Vec3) -> Light {
        let mut l = self.clone();
        match &mut l {
            Light::Point { position } => *position += by,
            Light::Sphere { center, .. } | Light::Disk { center, .. } | Light::Rectangle { center, .. } => *center += by,
            Light::Segment { a, b } => {
                *a += by;
                *b += by;
            }
            Light::Triangle { a, b, c } => {
                *a += by;
                *b += by;
                *c += by;
            }
            Light::Directional { .. } | Light::DistantDisk { .. } => {}
        }
        l
    }

    /// A light at infinity with its direction replaced by `f` of it; a light at a finite
    /// position is unchanged (it has no direction).
    pub fn turned(&self, f: impl Fn(Vec3) -> Vec3) -> Light {
        let mut l = self.clone();
        match &mut l {
            Light::Directional { direction } | Light::DistantDisk { direction, .. } => *direction = f(*direction),
            Light::Point { .. }
            | Light::Sphere { .. }
            | Light::Disk { .. }
            | Light::Rectangle { .. }
            | Light::Segment { .. }
            | Light::Triangle { .. } => {}
        }
        l
    }

    /// The light's extent scaled by `f` about its centre: a radius, both half extents, a
    /// segment's ends and a triangle's corners, a distant disk's angle. A light without
    /// extent (point, directional) is unchanged.
    pub fn scaled(&self, f: f32) -> Light {
        let mut l = self.clone();
        match &mut l {
            Light::Sphere { radius, .. } | Light::Disk { radius, .. } => *radius *= f,
            Light::Rectangle {
                half_width, half_height, ..
            } => {
                *half_width *= f;
                *half_height *= f;
            }
            Light::Segment { a, b } => {
                let m = (*a + *b) * 0.5;
                *a = m + (*a - m) * f;
                *b = m + (*b - m) * f;
            }
            Light::Triangle { a, b, c } => {
                let m = (*a + *b + *c) / 3.0;
                for p in [a, b, c] {
                    *p = m + (*p - m) * f;
                }
            }
            Light::DistantDisk { angle_degrees, .. } => *angle_degrees *= f,
            Light::Point { .. } | Light::Directional { .. } => {}
        }
        l
    }

    /// The light's size: radius, half extent, half length (of a segment; a triangle's
    /// centre-to-corner distance) or angle; `None` for a light with no size to set (a point,
    /// a directional light).
    pub fn size(&self) -> Option<f32> {
        match self {
            Light::Point { .. } | Light::Directional { .. } => None,
            Light::Sphere { radius, .. } | Light::Disk { radius, .. } => Some(*radius),
            Light::Rectangle { half_width, .. } => Some(*half_width),
            Light::Segment { a, b } => Some(0.5 * (*b - *a).length()),
            Light::Triangle { a, b, c } => {
                let m = (*a + *b + *c) / 3.0;
                Some((*a - m).length())
            }
            Light::DistantDisk { angle_degrees, .. } => Some(*angle_degrees),
        }
    }

    /// The light with its [`Light::size`] set to `s` (its shape kept: [`Light::scaled`]
    /// about its centre by the ratio of the sizes; a light of size 0 has its size set).
    pub fn resized(&self, s: f32) -> Light {
        let s = s.max(0.0);
        match self.size().filter(|&old| old > 0.0) {
            Some(old) => self.scaled(s / old),
            // a light of size 0 grows from nothing: set its size itself
            None => {
                let mut l = self.clone();
                match &mut l {
                    Light::Sphere { radius, .. } | Light::Disk { radius, .. } => *radius = s,
                    Light::Rectangle { half_width, .. } => *half_width = s,
                    Light::DistantDisk { angle_degrees, .. } => *angle_degrees = s.min(179.0),
                    Light::Point { .. } | Light::Directional { .. } | Light::Segment { .. } | Light::Triangle { .. } => {}
                }
                l
            }
        }
    }

    /// Whether the light has an extent: `false` where one ray from a point answers its
    /// visibility (0 or 1), as for a point, a directional light and any light of size 0.
    pub fn has_extent(&self) -> bool {
        match self {
            Light::Point { .. } | Light::Directional { .. } => false,
            Light::Sphere { radius, .. } | Light::Disk { radius, .. } => *radius > 0.0,
            Light::Rectangle {
                half_width, half_height, ..
            } => *half_width > 0.0 || *half_height > 0.0,
            Light::Segment { a, b } => a != b,
            Light::Triangle { a, b, c } => a != b || b != c,
            Light::DistantDisk { angle_degrees, .. } => *angle_degrees > 0.0,
        }
    }

    /// The scene file's field that places the light (`position`, `center`, the first
    /// corner `a`, or a distant light's `direction`): where a message about its place points.
    pub fn placing_field(&self) -> &'static str {
        match self {
            Light::Point { .. } => "position",
            Light::Segment { .. } | Light::Triangle { .. } => "a",
            Light::Sphere { .. } | Light::Disk { .. } | Light::Rectangle { .. } => "center",
            Light::Directional { .. } | Light::DistantDisk { .. } => "direction",
        }
    }

    /// The centre of a light at a finite position (the midpoint of a segment); `None` for
    /// lights at infinity.
    pub fn center(&self) -> Option<Vec3> {
        match self {
            Light::Point { position } => Some(*position),
            Light::Sphere { center, .. } | Light::Disk { center, .. } | Light::Rectangle { center, .. } => Some(*center),
            Light::Segment { a, b } => Some((*a + *b) * 0.5),
            Light::Triangle { a, b, c } => Some((*a + *b + *c) / 3.0),
            Light::Directional { .. } | Light::DistantDisk { .. } => None,
        }
    }

    /// The unit direction towards a light at infinity; `None` for the others.
    pub fn direction(&self) -> Option<Vec3> {
        match self {
            Light::Directional { direction } | Light::DistantDisk { direction, .. } => Some(direction.normalize_or(Vec3::Y)),
            Light::Point { .. }
            | Light::Sphere { .. }
            | Light::Disk { .. }
            | Light::Rectangle { .. }
            | Light::Segment { .. }
            | Light::Triangle { .. } => None,
        }
    }

    /// Radius of a sphere around [`Light::center`] that holds the whole light (0 for a
    /// point, and for lights at infinity).
    pub fn bounding_radius(&self) -> f32 {
        match self {
            Light::Sphere { radius, .. } | Light::Disk { radius, .. } => radius.max(0.0),
            Light::Rectangle {
                half_width, half_height, ..
            } => half_width.hypot(*half_height),
            Light::Segment { a, b } => 0.5 * a.distance(*b),
            Light::Triangle { a, b, c } => {
                let m = (*a + *b + *c) / 3.0;
                m.distance(*a).max(m.distance(*b)).max(m.distance(*c))
            }
            Light::Point { .. } | Light::Directional { .. } | Light::DistantDisk { .. } => 0.0,
        }
    }

    /// Full angular diameter in radians of a distant disk, else 0.
    pub fn angle(&self) -> f32 {
        match self {
            Light::DistantDisk { angle_degrees, .. } => angle_degrees.to_radians(),
            Light::Point { .. }
            | Light::Directional { .. }
            | Light::Sphere { .. }
            | Light::Disk { .. }
            | Light::Rectangle { .. }
            | Light::Segment { .. }
            | Light::Triangle { .. } => 0.0,
        }
    }

    /// `n` points evenly spaced along a segment light, ends included (`n = 1`: the
    /// midpoint), for techniques that render one view per light sample; `None` for other
    /// kinds.
    pub fn segment_samples(&self, n: u32) -> Option<Vec<Vec3>> {
        match self {
            Light::Segment { a, b } => Some(match n {
                0 => Vec::new(),
                1 => vec![(*a + *b) * 0.5],
                _ => (0..n).map(|i| a.lerp(*b, i as f32 / (n - 1) as f32)).collect(),
            }),
            Light::Point { .. }
            | Light::Directional { .. }
            | Light::Sphere { .. }
            | Light::Disk { .. }
            | Light::Rectangle { .. }
            | Light::Triangle { .. }
            | Light::DistantDisk { .. } => None,
        }
    }

    /// The corners of a triangle or rectangle light in order around its outline (a
    /// rectangle's from `center - u half_width - v half_height`, `v = normal x u_axis`,
    /// counter-clockwise about `normal`); `None` for other kinds.
    pub fn outline(&self) -> Option<Vec<Vec3>> {
        match self {
            Light::Triangle { a, b, c } => Some(vec![*a, *b, *c]),
            Light::Rectangle {
                center,
                normal,
                u_axis,
                half_width,
                half_height,
            } => {
                let u = u_axis.normalize_or(Vec3::X) * *half_width;
                let v = normal.normalize_or(Vec3::Y).cross(u_axis.normalize_or(Vec3::X)) * *half_height;
                Some(vec![*center - u - v, *center + u - v, *center + u + v, *center - u + v])
            }
            Light::Point { .. }
            | Light::Directional { .. }
            | Light::Sphere { .. }
            | Light::Disk { .. }
            | Light::Segment { .. }
            | Light::DistantDisk { .. } => None,
        }
    }

    /// The positions of `n` light samples for techniques that render one view per sample
    /// (Heidrich et al. 2000), and whether they close a loop:
    ///
    /// - `n = 1`, a light at a finite position: its centre ([`Light::center`]; a
    ///   segment's midpoint, a triangle's centroid), open.
    /// - a segment, `n >= 2`: [`Light::segment_samples`] (ends included), open.
    /// - a triangle or rectangle, `n` a multiple of its edge count E (3 or 4): its outline
    ///   (paper section 4, figure 8: an area light approximated by the linear lights of its
    ///   edges), `n / E` samples per edge starting at each corner of [`Light::outline`]
    ///   (corners included), closed: the last sample's next is the first.
    ///
    /// `n = 0`: no samples. Anything else is an error naming what would fit: `n` above
    /// `max`, a light at infinity (no position to see from), a point, sphere or disk with
    /// `n > 1`, or `n` not a multiple of the edges.
    pub fn sample_chain(&self, n: u32, max: u32) -> Result<(Vec<Vec3>, bool), String> {
        let name = self.kind_name();
        if n > max {
            return Err(format!("{n} light samples is above the limit of {max}: write N in 1..={max}"));
        }
        if n == 0 {
            return Ok((Vec::new(), false));
        }
        let Some(centre) = self.center() else {
            return Err(format!(
                "a {name} light is at infinity: per-sample views look from points on the light, so they need a light at a finite position (Segment, Triangle, Rectangle, or any local light with N = 1)"
            ));
        };
        if n == 1 {
            return Ok((vec![centre], false));
        }
        if let Some(points) = self.segment_samples(n) {
            return Ok((points, false));
        }
        let Some(corners) = self.outline() else {
            return Err(format!(
                "a {name} light has no edges to sample: {n} light samples need a Segment, Triangle or Rectangle light (N = 1 takes the light's centre)"
            ));
        };
        let e = corners.len() as u32;
        if !n.is_multiple_of(e) {
            return Err(format!(
                "a {name} light's samples walk its {e} edges with the same count per edge, so N must be a multiple of {e}, not {n}"
            ));
        }
        let per = n / e;
        let mut out = Vec::with_capacity(n as usize);
        for (i, &p) in corners.iter().enumerate() {
            let q = corners[(i + 1) % corners.len()];
            out.extend((0..per).map(|j| p.lerp(q, j as f32 / per as f32)));
        }
        Ok((out, true))
    }

    /// The light's view for rasterising a shadow map of the geometry in `bounds`.
    ///
    /// Point-like lights (point, sphere, disk, rectangle, segment, triangle) get a square
    /// perspective frustum from the light's centre, wide enough for every corner of
    /// `bounds`, with near/far fitted to the corners (near at least far * 1e-4). It looks
    /// along the axis of the narrowest cone that holds the corners, which is the direction
    /// of the bounds' centre for a distant light but differs where the bounds reach
    /// beside or behind the light (a light low over a large floor). A light that no
    /// frustum narrower than 160 degrees can see the bounds from (a light inside them)
    /// gets that widest frustum, and corners outside it are left out. Directional and
    /// distant-disk lights get an orthographic view along their direction fitted to the
    /// bounds.
    pub fn view(&self, bounds: (Vec3, Vec3)) -> LightView {
        let v = match self.center() {
            Some(eye) => perspective_view(eye, bounds),
            None => orthographic_view(self.direction().unwrap_or(Vec3::Y), bounds),
        };
        self.with_extent(v)
    }

    /// `v` with the light's `size`, `half_extents` and `angle` filled in.
    pub fn with_extent(&self, mut v: LightView) -> LightView {
        v.size = match self {
            Light::Sphere { radius, .. } | Light::Disk { radius, .. } => *radius,
            Light::Rectangle {
                half_width, half_height, ..
            } => half_width.max(*half_height),
            Light::Segment { a, b } => 0.5 * a.distance(*b),
            Light::DistantDisk { angle_degrees, .. } => (0.5 * angle_degrees.to_radians()).tan(),
            Light::Triangle { .. } => self.bounding_radius(),
            Light::Point { .. } | Light::Directional { .. } => 0.0,
        };
        // half-extents along the shadow map's u and v axes (the view's x and y): the
        // half-widths of the light's outline projected onto them
        let (ax, ay) = (v.view.row(0).truncate(), v.view.row(1).truncate());
        let along = |axis: Vec3| -> f32 {
            match self {
                Light::Sphere { radius, .. } => *radius,
                Light::Disk { radius, normal, .. } => radius * (1.0 - normal.normalize_or_zero().dot(axis).powi(2)).max(0.0).sqrt(),
                Light::Rectangle {
                    normal,
                    u_axis,
                    half_width,
                    half_height,
                    ..
                } => {
                    // a host's light is used as given (a scene file's is normalised on
                    // load): a `u_axis` not of unit length would scale the width
                    let u = valid::unit(*u_axis);
                    let w = normal.cross(u).normalize_or_zero();
                    half_width * u.dot(axis).abs() + half_height * w.dot(axis).abs()
                }
                Light::Segment { a, b } => 0.5 * (*b - *a).dot(axis).abs(),
                // about the centroid: the farthest corner's offset (at least half the
                // projected width, and all of it on the side the centroid is near)
                Light::Triangle { a, b, c } => {
                    let m = (*a + *b + *c) / 3.0;
                    [a, b, c].iter().map(|p| (**p - m).dot(axis).abs()).fold(0.0, f32::max)
                }
                Light::Point { .. } | Light::Directional { .. } | Light::DistantDisk { .. } => 0.0,
            }
        };
        v.half_extents = Vec2::new(along(ax), along(ay));
        v.angle = self.angle();
        v
    }

    /// A perspective view from any point `eye` (for example one sample of a segment
    /// light) fitted to `bounds` as in [`Light::view`]; `size`, `half_extents` and `angle`
    /// are 0.
    pub fn view_from(eye: Vec3, bounds: (Vec3, Vec3)) -> LightView {
        perspective_view(eye, bounds)
    }
}

/// The least ratio of a perspective light view's near distance to its far one: where a
/// caster reaches the light's own plane (a light inside or beside a caster), the near
/// plane stops here and [`LightView::depth_warning`] says what is lost.
pub const MIN_NEAR_OVER_FAR: f32 = 1e-4;

/// Above this ratio of far to near, [`LightView::depth_warning`] warns: the depth buffer
/// of the light's raster (`z = far (d - near) / (d (far - near))`, f32) then resolves
/// casters less than about `2^-24 * far / near` of their distance apart, and kernels sized
/// on the near plane span most of the map.
pub const WARN_FAR_OVER_NEAR: f32 = 1e3;

impl LightView {
    /// [`depth_warning`] of this view.
    pub fn depth_warning(&self) -> Option<String> {
        depth_warning(self.near, self.far, self.orthographic)
    }
}

/// A warning where a perspective view's near plane is so close to the light, against its
/// far plane, that depth precision and near-plane kernels suffer (a caster reaches the
/// light's plane: the light is inside or beside it). `None` for an orthographic view and
/// a sound range.
pub fn depth_warning(near: f32, far: f32, orthographic: bool) -> Option<String> {
    (!orthographic && far > WARN_FAR_OVER_NEAR * near).then(|| {
        format!(
            "the light's view has its near plane at {near:e}, {:.0} times nearer than its far plane at {far:e}: a shadow caster reaches the light's own plane (the light is inside or beside it), so the light's depth loses precision and techniques that size their search on the near plane (PCSS, VSSM) may find no blocker; move the light clear of the casters",
            far / near
        )
    })
}

/// The `Casters` fit's guard band: the lateral extent is multiplied by `n / (n - 2)` for a
/// map of `n >= 3` texels, which adds one texel on each side (a caster never reaches the
/// outermost texels, which a lookup clamped to the map's edge reads); `1.001` below that
/// (the rounding margin of the `Scene` fit).
pub fn fit_guard(n: u32) -> f32 {
    if n >= 3 { n as f32 / (n - 2) as f32 } else { 1.001 }
}

/// Bounds with every side at least a small positive length, so views stay finite.
pub fn padded(bounds: (Vec3, Vec3)) -> (Vec3, Vec3) {
    let (lo, hi) = bounds;
    let scale = (hi - lo)
        .max_element()
        .max(lo.abs().max_element())
        .max(hi.abs().max_element())
        .max(1.0);
    let pad = Vec3::splat(scale * 1e-4);
    let mid = (lo + hi) * 0.5;
    let half = ((hi - lo) * 0.5).max(pad);
    (mid - half, mid + half)
}

/// The axis of (nearly) the narrowest cone from `eye` that holds every corner of
/// `bounds`: Badoiu–Clarkson iterations for the smallest ball around the unit directions
/// to the corners, started from their mean.
pub fn enclosing_axis(eye: Vec3, bounds: (Vec3, Vec3)) -> Vec3 {
    // on the stack, each dot product taken once an iteration (this runs every frame a host
    // places a light: 200 iterations); the first of equal minima, as `min_by` takes
    let mut dirs = [Vec3::ZERO; 8];
    let mut k = 0;
    for c in corners(bounds) {
        if let Some(d) = (c - eye).try_normalize() {
            dirs[k] = d;
            k += 1;
        }
    }
    let dirs = &dirs[..k];
    let mut axis = dirs.iter().copied().sum::<Vec3>().try_normalize().unwrap_or(-Vec3::Y);
    let Some((&first, rest)) = dirs.split_first() else {
        return axis;
    };
    for i in 1..=200 {
        let (mut far, mut least) = (first, first.dot(axis));
        for &d in rest {
            let x = d.dot(axis);
            if x.total_cmp(&least).is_lt() {
                (far, least) = (d, x);
            }
        }
        axis = (axis + (far - axis) / (i as f32 + 1.0)).try_normalize().unwrap_or(axis);
    }
    axis
}

fn perspective_view(eye: Vec3, bounds: (Vec3, Vec3)) -> LightView {
    let bounds = padded(bounds);
    let forward = enclosing_axis(eye, bounds);
    let view = look_at(eye, eye + forward, any_perpendicular_up(forward));
    let (lo, hi) = depth_range(&view, bounds);
    let far = (hi * 1.001).max(1e-6);
    let near = (lo * 0.999).max(far * MIN_NEAR_OVER_FAR);
    // Widest tangent over the corners in front of the near plane.
    let mut tan = 0.0f32;
    for c in corners(bounds) {
        let p = view.transform_point3(c);
        let depth = (-p.z).max(near);
        tan = tan.max(p.x.abs() / depth).max(p.y.abs() / depth);
    }
    let tan = (tan * 1.001).clamp(1e-6, 80f32.to_radians().tan());
    perspective_light_view(view, perspective(2.0 * tan.atan(), 1.0, near, far), eye, near, far)
}

/// A perspective light view from `eye` through `view` and `proj`, over `[near, far]` in
/// depth (its extents 0: [`Light::with_extent`] fills them).
pub fn perspective_light_view(view: Mat4, proj: Mat4, eye: Vec3, near: f32, far: f32) -> LightView {
    LightView {
        view,
        proj,
        view_proj: proj * view,
        near,
        far,
        position_or_direction: eye.extend(1.0),
        size: 0.0,
        half_extents: Vec2::ZERO,
        angle: 0.0,
        orthographic: false,
    }
}

fn orthographic_view(direction: Vec3, bounds: (Vec3, Vec3)) -> LightView {
    let bounds = padded(bounds);
    let centre = (bounds.0 + bounds.1) * 0.5;
    let radius = 0.5 * (bounds.1 - bounds.0).length();
    let dir = direction.normalize_or(Vec3::Y);
    let eye = centre + dir * (2.0 * radius);
    let view = look_at(eye, centre, any_perpendicular_up(dir));
    let (lo, hi) = depth_range(&view, bounds);
    let margin = radius * 1e-3;
    let far = hi + margin;
    let near = (lo - margin).max(far * 1e-4);
    let mut half = 0.0f32;
    for c in corners(bounds) {
        let p = view.transform_point3(c);
        half = half.max(p.x.abs()).max(p.y.abs());
    }
    ortho_light_view(view, dir, half * 1.001, near, far)
}

/// An orthographic light view looking down `view`'s -z towards a light in direction `dir`,
/// covering `[-half, half]` on both axes and `[near, far]` in depth.
pub fn ortho_light_view(view: Mat4, dir: Vec3, half: f32, near: f32, far: f32) -> LightView {
    let proj = orthographic(-half, half, -half, half, near, far);
    LightView {
        view,
        proj,
        view_proj: proj * view,
        near,
        far,
        position_or_direction: dir.extend(0.0),
        size: 0.0,
        half_extents: Vec2::ZERO,
        angle: 0.0,
        orthographic: true,
    }
}

// ---------------------------------------------------------------------------------------
// The `Casters` fit
// ---------------------------------------------------------------------------------------

/// What a fit sees of a scene: points whose convex hull holds every shadow caster, and
/// points whose hull holds every object (casters and receivers). A scene's vertices give
/// the tightest fit; the corners of each object's bounding box a looser one that is cheap
/// to compute every frame. Each iterator may be walked several times.
pub trait Occluders {
    /// Points holding the casters (empty when nothing casts).
    fn casters(&self) -> impl Iterator<Item = Vec3> + '_;
    /// Points holding every object.
    fn points(&self) -> impl Iterator<Item = Vec3> + '_;
    /// The bounding box of [`Occluders::points`].
    fn bounds(&self) -> (Vec3, Vec3);
    /// Whether anything casts.
    fn has_casters(&self) -> bool;
}

/// The farthest reach of the casters' penumbra under `light`, in world units: how far
/// beyond a caster's shadow outline (its outline seen from the light's centre) the
/// penumbra can extend on a receiver.
///
/// - A distant disk of angular diameter `a`: `h tan(a / 2)`, `h` the largest height of
///   a caster point above the lowest point of any object, both measured along the
///   light's direction (rays from a receiver within the cone of half-angle `a / 2`
///   around the direction meet a caster `h` above it at most `h tan(a / 2)` to the
///   side). A directional light: 0.
/// - A light at a finite position with bounding radius `s` ([`Light::bounding_radius`]):
///   `s (d_r - d_c) / d_c`, `d_c` the smallest distance of a caster point from the
///   light's centre along its view axis and `d_r` the largest of any object's point
///   (the penumbra width of a caster at `d_c` on a receiver at `d_r`, by similar
///   triangles). In the view's tangent space this is `s (1 / d_c - 1 / d_r)`, what the
///   `Casters` fit pads the view's half-angle tangent by.
///
/// 0 when nothing casts.
pub fn penumbra_reach(light: &Light, scene: &impl Occluders) -> f32 {
    match light.center() {
        None => {
            let dir = light.direction().unwrap_or(Vec3::Y);
            let top = scene.casters().map(|p| p.dot(dir)).fold(f32::NEG_INFINITY, f32::max);
            let low = scene.points().map(|p| p.dot(dir)).fold(f32::INFINITY, f32::min);
            if !(top.is_finite() && low.is_finite()) {
                return 0.0;
            }
            (top - low).max(0.0) * (0.5 * light.angle()).tan()
        }
        Some(_) => match local_reach(light, scene) {
            Some((_, dc, dr, s)) => s * (dr - dc) / dc,
            None => 0.0,
        },
    }
}

/// For a light at a finite position: its view fitted to the casters, the nearest
/// caster distance `d_c` and farthest object distance `d_r` along that view's axis
/// (`d_c` at least the view's near distance), and the light's bounding radius.
fn local_reach(light: &Light, scene: &impl Occluders) -> Option<(LightView, f32, f32, f32)> {
    let eye = light.center()?;
    if !scene.has_casters() {
        return None;
    }
    let cb = bounds_of(scene.casters());
    let forward = enclosing_axis(eye, padded(cb));
    let view = look_at(eye, eye + forward, any_perpendicular_up(forward));
    let (_, hi) = depth_range(&view, padded(scene.bounds()));
    let far = (hi * 1.001).max(1e-6);
    // The near plane at the nearest caster, what the Depth pass draws: not at the scene
    // box's nearest corner, which for a wide ground reaches beside or behind the light
    // (its corners at the casters' height, far to the side) and took the near plane to
    // its floor, far * 1e-4, where techniques that size their kernels on the near plane
    // (PCSS's blocker search, Fernando 2005 equation 1) searched the whole map and found
    // nothing (issue 49). Receivers nearer than every caster are lit whatever their depth.
    let lo = scene.casters().map(|p| -view.transform_point3(p).z).fold(f32::INFINITY, f32::min);
    let near = (lo * 0.999).min(far * 0.999).max(far * MIN_NEAR_OVER_FAR);
    let dc = lo.max(near);
    let dr = scene.points().map(|p| -view.transform_point3(p).z).fold(dc, f32::max);
    // the projection is the caller's (identity here, so `view_proj` is `view` until then)
    let base = perspective_light_view(view, Mat4::IDENTITY, eye, near, far);
    Some((base, dc, dr, light.bounding_radius()))
}

/// The view of `light` fitted to the casters of `scene` for a map of `shadow_map` texels
/// a side (the `Casters` fit; [`Light::view`] of the bounds when nothing casts).
///
/// - A light at infinity: an orthographic view along its direction, centred on the
///   casters, as wide as they are plus the penumbra's reach ([`penumbra_reach`]) and one
///   guard texel a side ([`fit_guard`]); in depth, the bounds of every object.
/// - A light at a finite position: a perspective view along the axis of the narrowest
///   cone holding the casters, its half-angle tangent that of the casters plus the
///   penumbra's reach in tangent units, times the guard.
pub fn casters_view(light: &Light, scene: &impl Occluders, shadow_map: u32) -> LightView {
    if !scene.has_casters() {
        return light.view(scene.bounds());
    }
    let guard = fit_guard(shadow_map.max(1));
    let v = match light.center() {
        None => {
            let dir = light.direction().unwrap_or(Vec3::Y);
            let up = any_perpendicular_up(dir);
            let cb = bounds_of(scene.casters());
            let cc = (cb.0 + cb.1) * 0.5;
            let v0 = look_at(cc + dir, cc, up);
            let (mut x0, mut x1, mut y0, mut y1) = (f32::INFINITY, f32::NEG_INFINITY, f32::INFINITY, f32::NEG_INFINITY);
            for p in scene.casters() {
                let q = v0.transform_point3(p);
                (x0, x1, y0, y1) = (x0.min(q.x), x1.max(q.x), y0.min(q.y), y1.max(q.y));
            }
            let (right, upv) = (v0.row(0).truncate(), v0.row(1).truncate());
            let centre = cc + right * (0.5 * (x0 + x1)) + upv * (0.5 * (y0 + y1));
            let half_c = (0.5 * (x1 - x0)).max(0.5 * (y1 - y0));
            let bounds = padded(scene.bounds());
            let (sc, radius) = ((bounds.0 + bounds.1) * 0.5, 0.5 * (bounds.1 - bounds.0).length());
            let eye = centre + dir * (2.0 * radius + centre.distance(sc));
            let view = look_at(eye, centre, up);
            let (lo, hi) = depth_range(&view, bounds);
            let margin = radius * 1e-3;
            let far = hi + margin;
            let near = (lo - margin).max(far * 1e-4);
            let half = ((half_c + penumbra_reach(light, scene)) * guard).max(radius * 1e-4);
            ortho_light_view(view, dir, half, near, far)
        }
        Some(_) => {
            let Some((mut v, dc, dr, s)) = local_reach(light, scene) else {
                return light.view(scene.bounds());
            };
            let mut tan = 0.0f32;
            for p in scene.casters() {
                let q = v.view.transform_point3(p);
                let depth = (-q.z).max(v.near);
                tan = tan.max(q.x.abs() / depth).max(q.y.abs() / depth);
            }
            let reach = s * (1.0 / dc - 1.0 / dr);
            let tan = ((tan + reach) * guard).clamp(1e-6, 80f32.to_radians().tan());
            v.proj = perspective(2.0 * tan.atan(), 1.0, v.near, v.far);
            v.view_proj = v.proj * v.view;
            v
        }
    };
    light.with_extent(v)
}

// ---------------------------------------------------------------------------------------
// Per-sample views
// ---------------------------------------------------------------------------------------

/// One sample view of a light ([`sample_views`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampleFit {
    /// The sample's position, world space.
    pub position: Vec3,
    /// The view a point light at the sample gets.
    pub view: LightView,
    /// Weights of the segment of light before the sample and of the one after it.
    pub weights: [f32; 2],
}

/// `n` sample views of `light`, in order along the light, and whether they close a loop
/// (Heidrich et al. 2000, sections 3 and 4):
///
/// - positions: [`Light::sample_chain`] (a segment's evenly spaced points, ends included;
///   a triangle's or rectangle's perimeter, corners included, `n` a multiple of the
///   edges, closed; `n = 1`: the centre of any light at a finite position);
/// - each view is `view_of` a point light at the sample (the caller's fit, so that the
///   samples are fitted as the centre is), with its own near, far and projection;
/// - weights: each segment between consecutive samples weighs its length over the chain's
///   total (N - 1 segments when open, N when closed); a sample carries the weights of the
///   segments before and after it (0 where there is none); a lone sample carries [1, 1]
///   (its two channels start at one half, section 3.2, so a lit point sums to 1). A chain
///   of zero length (a segment with a = b) weighs its segments equally.
///
/// Errors as [`Light::sample_chain`]'s.
pub fn sample_views(
    light: &Light,
    n: u32,
    max: u32,
    mut view_of: impl FnMut(&Light) -> LightView,
) -> Result<(Vec<SampleFit>, bool), String> {
    let (points, closed) = light.sample_chain(n, max)?;
    let k = points.len();
    // segment i joins sample i and sample i + 1 (mod k when closed)
    let segments = match (k < 2, closed) {
        (true, _) => 0,
        (false, true) => k,
        (false, false) => k - 1,
    };
    let lengths: Vec<f32> = (0..segments).map(|i| points[i].distance(points[(i + 1) % k])).collect();
    let total: f32 = lengths.iter().sum();
    let weight = |i: usize| {
        if total > 0.0 && total.is_finite() {
            lengths[i] / total
        } else {
            1.0 / segments as f32
        }
    };
    let fits = points
        .iter()
        .enumerate()
        .map(|(i, &position)| {
            let weights = if k == 1 {
                [1.0, 1.0]
            } else {
                let before = if i > 0 { Some(i - 1) } else { closed.then_some(k - 1) };
                let after = (i + 1 < k || closed).then_some(i);
                [before.map_or(0.0, weight), after.map_or(0.0, weight)]
            };
            SampleFit {
                position,
                view: view_of(&Light::Point { position }),
                weights,
            }
        })
        .collect();
    Ok((fits, closed))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A light of size 0 of every kind is answered by one ray; any size makes it an extent,
    /// and resizing one from 0 gives it that size.
    #[test]
    fn a_light_has_an_extent_exactly_when_it_has_a_size() {
        let zero = [
            Light::Point { position: Vec3::Y },
            Light::Directional { direction: Vec3::Y },
            Light::Sphere {
                center: Vec3::Y,
                radius: 0.0,
            },
            Light::Disk {
                center: Vec3::Y,
                normal: Vec3::NEG_Y,
                radius: 0.0,
            },
            Light::Segment { a: Vec3::Y, b: Vec3::Y },
            Light::DistantDisk {
                direction: Vec3::Y,
                angle_degrees: 0.0,
            },
        ];
        for l in zero {
            assert!(!l.has_extent(), "{l:?}");
            let grown = l.resized(0.5);
            assert_eq!(
                grown.has_extent(),
                l.size().is_some() && grown.size() == Some(0.5),
                "{l:?} -> {grown:?}"
            );
        }
        let segment = Light::Segment { a: Vec3::ZERO, b: Vec3::X };
        assert!(segment.has_extent());
        assert_eq!((segment.size(), segment.placing_field()), (Some(0.5), "a"));
    }

    /// A host's rectangle whose `u_axis` is not of unit length (the runtime fits a host's
    /// light as given) has the extents of the same rectangle with a unit axis.
    #[test]
    fn a_rectangle_axis_of_any_length_gives_the_same_extents() {
        let rect = |u: Vec3| Light::Rectangle {
            center: Vec3::new(0.3, 4.0, -0.2),
            normal: Vec3::new(0.0, -1.0, 0.0),
            u_axis: u,
            half_width: 0.5,
            half_height: 0.25,
        };
        let bounds = (Vec3::splat(-1.0), Vec3::splat(1.0));
        let unit = rect(Vec3::X).view(bounds);
        for u in [Vec3::X * 2.0, Vec3::X * 0.5] {
            let v = rect(u).view(bounds);
            assert_eq!(v.half_extents, unit.half_extents, "u_axis {u}");
        }
    }

    /// Boxes as occluders: casters' corners, and every object's.
    struct Boxes {
        casters: Vec<(Vec3, Vec3)>,
        others: Vec<(Vec3, Vec3)>,
    }

    impl Occluders for Boxes {
        fn casters(&self) -> impl Iterator<Item = Vec3> + '_ {
            self.casters.iter().flat_map(|b| corners(*b))
        }
        fn points(&self) -> impl Iterator<Item = Vec3> + '_ {
            self.casters.iter().chain(&self.others).flat_map(|b| corners(*b))
        }
        fn bounds(&self) -> (Vec3, Vec3) {
            bounds_of(self.points())
        }
        fn has_casters(&self) -> bool {
            !self.casters.is_empty()
        }
    }

    /// Issue 49: a box of half-size 0.5 standing on a ground of half-size 4 to 64 under a
    /// sphere light to one side. The `Casters` fit's near plane lies at the nearest caster
    /// (within the 0.999 rounding margin), whatever the ground's size; before, a ground of
    /// half-size 6 or more took it to far * 1e-4 (the scene box's top corners, at the
    /// caster's height and far to the side, lay behind the light's plane).
    #[test]
    fn the_casters_fit_puts_the_near_plane_at_the_nearest_caster_whatever_the_ground() {
        let light = Light::Sphere {
            center: Vec3::new(1.5, 3.0, 0.5),
            radius: 0.3,
        };
        let caster = (Vec3::new(-0.5, 0.0, -0.5), Vec3::new(0.5, 1.0, 0.5));
        for half in [4.0f32, 6.0, 16.0, 64.0] {
            let scene = Boxes {
                casters: vec![caster],
                others: vec![(Vec3::new(-half, -0.1, -half), Vec3::new(half, 0.0, half))],
            };
            let v = casters_view(&light, &scene, 1024);
            let nearest = corners(caster)
                .iter()
                .map(|p| -v.view.transform_point3(*p).z)
                .fold(f32::INFINITY, f32::min);
            assert!(nearest > 0.0);
            assert!(
                v.near <= nearest && v.near >= 0.998 * nearest,
                "ground {half}: near {} against the nearest caster at {nearest}",
                v.near
            );
            assert_eq!(v.depth_warning(), None, "ground {half}");
            // every caster corner inside the clip volume, in depth
            for p in corners(caster) {
                let c = v.view_proj.project_point3(p);
                assert!((0.0..=1.0).contains(&c.z), "ground {half}: caster corner {p} at clip depth {}", c.z);
            }
        }
    }

    /// A light inside a caster: the near plane stops at its floor, and the view says so.
    #[test]
    fn a_light_inside_a_caster_is_warned_about() {
        let light = Light::Point {
            position: Vec3::new(0.0, 0.5, 0.0),
        };
        let scene = Boxes {
            casters: vec![(Vec3::splat(-1.0), Vec3::splat(1.0))],
            others: vec![(Vec3::new(-8.0, -1.1, -8.0), Vec3::new(8.0, -1.0, 8.0))],
        };
        let v = casters_view(&light, &scene, 1024);
        assert!((v.near - v.far * MIN_NEAR_OVER_FAR).abs() <= v.far * 1e-7, "{} {}", v.near, v.far);
        let w = v.depth_warning().expect("a warning");
        assert!(w.contains("inside or beside"), "{w}");
    }
}
