//! What a valid light is, decided once: [`Light::fault`]. The runtime refuses a host's
//! light with [`Light::check`] (the fault in words); a scene file's lights are checked and
//! normalised with [`Light::checked`], and `sshc-scene` words the same fault with the
//! value's path in the file and a fix.

use crate::Light;
use glam::Vec3;
use std::fmt;

/// What [`Light::fault`] found wrong with a light: the field at fault and the problem.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightFault {
    /// The field as a scene file names it (`center`, `half_width`, `a`).
    pub field: &'static str,
    /// The field in words (`centre`, `half width`, `end a`, `corner a`).
    pub words: &'static str,
    pub problem: Problem,
}

/// What is wrong with a light's field.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Problem {
    /// A position (a centre, an end, a corner) that is not finite.
    PositionNotFinite(Vec3),
    /// A direction or normal that is not finite.
    DirectionNotFinite(Vec3),
    /// A direction or normal of length zero.
    DirectionZero,
    /// A rectangle's `u_axis` that is not finite.
    AxisNotFinite(Vec3),
    /// A rectangle's `u_axis` of length zero.
    AxisZero,
    /// A rectangle's `u_axis` (nearly) parallel to its normal: less than 1e-4 of its length
    /// is left once its component along the normal is removed.
    AxisAlongNormal,
    /// A length (a radius, a half extent) that is negative or not finite.
    Length(f32),
    /// A distant disk's angular diameter outside [0, 180) degrees.
    Angle(f32),
}

/// The runtime's words ([`Light::check`]).
impl fmt::Display for LightFault {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let words = self.words;
        match self.problem {
            Problem::PositionNotFinite(v) | Problem::DirectionNotFinite(v) | Problem::AxisNotFinite(v) => {
                write!(f, "its {words} {v} is not finite")
            }
            Problem::DirectionZero | Problem::AxisZero => write!(f, "its {words} is zero"),
            Problem::AxisAlongNormal => write!(f, "its `u_axis` is parallel to its normal"),
            Problem::Length(x) => write!(f, "its {words} {x} is not a finite length >= 0"),
            Problem::Angle(a) => write!(f, "its angular diameter {a} is outside [0, 180) degrees"),
        }
    }
}

/// `v` normalised, or kept as it is where it is already of unit length to within f32
/// rounding (so that normalising a normalised light changes nothing).
pub(crate) fn unit(v: Vec3) -> Vec3 {
    if (v.length_squared() - 1.0).abs() > 4.0 * f32::EPSILON {
        v.normalize()
    } else {
        v
    }
}

/// `u_axis` less its component along `normal` (of unit length, by [`unit`]).
fn in_plane(u_axis: Vec3, normal: Vec3) -> Vec3 {
    u_axis - normal * u_axis.dot(normal)
}

impl Light {
    /// The first thing that makes this a light no view can be fitted to, field by field in
    /// the order a scene file's checks report them: a position that is not finite, a
    /// direction or normal that is not finite or zero, a radius or half extent negative or
    /// not finite, a rectangle's `u_axis` not finite, zero or parallel to its normal, an
    /// angular diameter outside [0, 180) degrees. `None` for a valid light. The one
    /// definition of a valid light: [`Light::check`] and [`Light::checked`] word it.
    pub fn fault(&self) -> Option<LightFault> {
        fn fault(field: &'static str, words: &'static str, problem: Problem) -> LightFault {
            LightFault { field, words, problem }
        }
        fn point(v: &Vec3, field: &'static str, words: &'static str) -> Option<LightFault> {
            (!v.is_finite()).then(|| fault(field, words, Problem::PositionNotFinite(*v)))
        }
        fn direction(v: &Vec3, field: &'static str) -> Option<LightFault> {
            if !v.is_finite() {
                Some(fault(field, field, Problem::DirectionNotFinite(*v)))
            } else if v.length_squared() == 0.0 {
                Some(fault(field, field, Problem::DirectionZero))
            } else {
                None
            }
        }
        fn length(x: f32, field: &'static str, words: &'static str) -> Option<LightFault> {
            (!(x.is_finite() && x >= 0.0)).then(|| fault(field, words, Problem::Length(x)))
        }
        match self {
            Light::Point { position } => point(position, "position", "position"),
            Light::Directional { direction: d } => direction(d, "direction"),
            Light::Sphere { center, radius } => point(center, "center", "centre").or_else(|| length(*radius, "radius", "radius")),
            Light::Disk { center, normal, radius } => point(center, "center", "centre")
                .or_else(|| direction(normal, "normal"))
                .or_else(|| length(*radius, "radius", "radius")),
            Light::Rectangle {
                center,
                normal,
                u_axis,
                half_width,
                half_height,
            } => point(center, "center", "centre")
                .or_else(|| direction(normal, "normal"))
                .or_else(|| length(*half_width, "half_width", "half width"))
                .or_else(|| length(*half_height, "half_height", "half height"))
                .or_else(|| {
                    let problem = if !u_axis.is_finite() {
                        Problem::AxisNotFinite(*u_axis)
                    } else if u_axis.length_squared() == 0.0 {
                        Problem::AxisZero
                    } else {
                        let u = in_plane(*u_axis, unit(*normal));
                        if u.is_finite() && u.length() > 1e-4 * u_axis.length() {
                            return None;
                        }
                        Problem::AxisAlongNormal
                    };
                    Some(fault("u_axis", "u_axis", problem))
                }),
            Light::Segment { a, b } => point(a, "a", "end a").or_else(|| point(b, "b", "end b")),
            Light::Triangle { a, b, c } => point(a, "a", "corner a")
                .or_else(|| point(b, "b", "corner b"))
                .or_else(|| point(c, "c", "corner c")),
            Light::DistantDisk {
                direction: d,
                angle_degrees,
            } => direction(d, "direction").or_else(|| {
                (!(*angle_degrees >= 0.0 && *angle_degrees < 180.0))
                    .then(|| fault("angle_degrees", "angular diameter", Problem::Angle(*angle_degrees)))
            }),
        }
    }

    /// Refuse what no view can be fitted to ([`Light::fault`], in words). This is the check
    /// for lights made in code, such as a host's; a scene file's lights are checked by
    /// [`Light::checked`], and the scene names the value's path in the file.
    pub fn check(&self) -> Result<(), String> {
        match self.fault() {
            Some(f) => Err(f.to_string()),
            None => Ok(()),
        }
    }

    /// The light checked ([`Light::fault`]), its directions and normals normalised (one
    /// already of unit length to within f32 rounding kept as it is) and a rectangle's
    /// `u_axis` made a unit vector in its plane, as a scene file's light is: checking a
    /// checked light changes nothing.
    pub fn checked(&self) -> Result<Light, LightFault> {
        if let Some(f) = self.fault() {
            return Err(f);
        }
        let mut l = self.clone();
        match &mut l {
            Light::Directional { direction } | Light::DistantDisk { direction, .. } => *direction = unit(*direction),
            Light::Disk { normal, .. } => *normal = unit(*normal),
            Light::Rectangle { normal, u_axis, .. } => {
                *normal = unit(*normal);
                let u = in_plane(*u_axis, *normal);
                if (u.length_squared() - 1.0).abs() > 4.0 * f32::EPSILON || u != *u_axis {
                    *u_axis = u.normalize();
                }
            }
            Light::Point { .. } | Light::Sphere { .. } | Light::Segment { .. } | Light::Triangle { .. } => {}
        }
        Ok(l)
    }
}
