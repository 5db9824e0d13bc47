//! The checks of a scene file's values, and the limits they enforce.

use crate::error::SceneError;
use crate::schema::{Camera, Mesh, Object, Rotation, SceneDesc};

use glam::{Vec2, Vec3};
use sshc_light::{Light, LightFault, Problem};

/// Most segments of a `Sphere` mesh (it has `segments * max(2, segments / 2) * 2`
/// triangles: 1,048,576 at this limit).
pub const MAX_SPHERE_SEGMENTS: u32 = 1024;
/// Most triangles in a scene, all objects together (checked before allocating).
pub const MAX_SCENE_TRIANGLES: usize = 1 << 24;
/// Largest mesh file read (an OBJ file, a glTF file or one of its buffers), in bytes (256 MiB).
pub const MAX_OBJ_BYTES: u64 = 256 << 20;
/// Smallest magnitude of a scale component: below it the object's triangles underflow f32.
pub const MIN_SCALE: f32 = 1e-10;
/// Largest camera `near`, `far` and position-to-target distance: the projection multiplies
/// near by far, which must stay within f32.
pub const MAX_CAMERA_DISTANCE: f32 = 1e15;
/// Most pixels of the scene's camera (4096 x 4096).
pub const MAX_CAMERA_PIXELS: u64 = 4096 * 4096;
/// Smallest object size (bounds' diagonal) relative to the scene's largest coordinate
/// magnitude: 2^-16, the ground truth's ray offset relative to a point's coordinates
/// (128 to 256 ulp); see [`crate::Scene::check_precision`].
pub const PRECISION_RATIO: f32 = 1.0 / 65536.0;
/// f32 ulps of a local light's distance allowed per shadow-map texel of the scene: the
/// light view's coordinates must resolve 1/16 of a texel; see [`crate::Scene::check_precision`].
pub const LIGHT_PRECISION_MARGIN: f32 = 16.0;

fn finite3(v: Vec3) -> bool {
    v.is_finite()
}

/// Checks ranges and normalises directions in place.
pub(crate) fn validate(desc: &mut SceneDesc) -> Result<(), SceneError> {
    if let Some(c) = &desc.cascades {
        let max = sshc_light::MAX_CASCADES;
        let bad = |field: &str, message: String, hint: &str| Err(SceneError::invalid(format!("cascades.{field}"), message, hint));
        if !(1..=max).contains(&c.count) {
            return bad("count", format!("{} cascades", c.count), &format!("write 1 to {max}"));
        }
        if !(0.0..=1.0).contains(&c.lambda) {
            return bad(
                "lambda",
                format!("the split weight {} is outside [0, 1]", c.lambda),
                "write 0 (uniform) to 1 (logarithmic)",
            );
        }
        if !(0.0..1.0).contains(&c.band) {
            return bad(
                "band",
                format!("the band {} is outside [0, 1)", c.band),
                "write a fraction of a slice, such as 0.1",
            );
        }
        if c.count > 1 && (desc.lights.len() != 1 || desc.lights[0].direction().is_none()) {
            return bad(
                "count",
                format!(
                    "{} cascades split one light at infinity's view; the scene has {} light(s)",
                    c.count,
                    desc.lights.len()
                ),
                "give the scene one Directional or DistantDisk light, or remove `cascades`",
            );
        }
    }
    if desc.shadow_map == 0 {
        return Err(SceneError::invalid(
            "shadow_map",
            "the shadow map has no texels",
            "write a resolution of at least 1, such as 512",
        ));
    }
    validate_camera(&desc.camera)?;
    if desc.lights.len() > sshc_light::MAX_LIGHTS {
        return Err(SceneError::invalid(
            "lights",
            format!(
                "{} lights, above the runtime's limit of {} a frame",
                desc.lights.len(),
                sshc_light::MAX_LIGHTS
            ),
            format!("keep at most {} lights in the scene", sshc_light::MAX_LIGHTS),
        ));
    }
    for (i, light) in desc.lights.iter_mut().enumerate() {
        let name = light.kind_name();
        let at = |field: &str| format!("lights[{i}] ({name}).{field}");
        validate_light(light, &at)?;
    }
    for (i, object) in desc.objects.iter().enumerate() {
        let at = |field: &str| match &object.name {
            Some(n) => format!("objects[{i}] (\"{n}\").{field}"),
            None => format!("objects[{i}].{field}"),
        };
        validate_object(object, &at)?;
    }
    Ok(())
}

/// The most a perspective camera's far may exceed its near: at the far plane the f32 depth
/// test then orders surfaces 2^-24 x 1e6 = 6 % of their distance apart (the step of a
/// depth near 1 is 2^-24, and depth changes by about near / z^2 per unit of z).
pub const MAX_DEPTH_RATIO: f32 = 1e6;

pub(crate) fn validate_camera(camera: &Camera) -> Result<(), SceneError> {
    let (name, position, target, up, width, height, near, far) = match camera {
        Camera::Perspective {
            position,
            target,
            up,
            width,
            height,
            near,
            far,
            ..
        } => ("Perspective", position, target, up, width, height, near, far),
        Camera::Orthographic {
            position,
            target,
            up,
            width,
            height,
            near,
            far,
            ..
        } => ("Orthographic", position, target, up, width, height, near, far),
    };
    let at = |f: &str| format!("camera ({name}).{f}");
    for (field, v) in [("position", position), ("target", target), ("up", up)] {
        if !finite3(*v) {
            return Err(SceneError::invalid(at(field), "the vector is not finite", "write finite numbers"));
        }
    }
    let dir = *target - *position;
    if dir.length_squared() == 0.0 {
        return Err(SceneError::invalid(
            at("target"),
            "the camera looks at its own position",
            "move `target` away from `position`",
        ));
    }
    let distance = (target.as_dvec3() - position.as_dvec3()).length();
    if distance > f64::from(MAX_CAMERA_DISTANCE) {
        return Err(SceneError::invalid(
            at("target"),
            format!("`target` is {distance:e} from `position`, beyond the limit of {MAX_CAMERA_DISTANCE:e} (f32 cannot hold the view)"),
            "bring the camera closer to its target, or scale the scene down",
        ));
    }
    if up.length_squared() == 0.0 || dir.normalize().cross(up.normalize()).length() < 1e-4 {
        return Err(SceneError::invalid(
            at("up"),
            "`up` is zero or parallel to the view direction",
            "choose an `up` not parallel to `target - position` (looking straight down, use (0.0, 0.0, -1.0))",
        ));
    }
    if *width == 0 || *height == 0 {
        return Err(SceneError::invalid(
            at("width"),
            "the image has no pixels",
            "write a width and height of at least 1",
        ));
    }
    let pixels = u64::from(*width) * u64::from(*height);
    if pixels > MAX_CAMERA_PIXELS {
        return Err(SceneError::invalid(
            at("width"),
            format!("{width} x {height} is {pixels} pixels, above the limit of {MAX_CAMERA_PIXELS} (4096 x 4096)"),
            "write a smaller camera size: the read-backs hold several float images of this size",
        ));
    }
    match camera {
        Camera::Perspective { fov_y_degrees, .. } if !(*fov_y_degrees > 0.0 && *fov_y_degrees < 180.0) => {
            return Err(SceneError::invalid(
                at("fov_y_degrees"),
                format!("field of view {fov_y_degrees} is outside (0, 180) degrees"),
                "write a field of view such as 45.0",
            ));
        }
        Camera::Orthographic { half_height, .. } if !(*half_height > 0.0 && half_height.is_finite()) => {
            return Err(SceneError::invalid(
                at("half_height"),
                format!("half height {half_height} is not positive"),
                "write a positive half height",
            ));
        }
        Camera::Perspective { .. } | Camera::Orthographic { .. } => {}
    }
    if let Some(n) = near
        && !(*n > 0.0 && n.is_finite())
    {
        return Err(SceneError::invalid(
            at("near"),
            format!("near {n} is not positive"),
            "write a positive near distance or leave it out",
        ));
    }
    for (field, v) in [("near", near), ("far", far)] {
        if let Some(v) = v
            && *v > MAX_CAMERA_DISTANCE
        {
            return Err(SceneError::invalid(
                at(field),
                format!(
                    "{field} {v:e} is beyond the limit of {MAX_CAMERA_DISTANCE:e}: the projection multiplies near by far, which overflows f32"
                ),
                "write near and far of at most 1e15, or leave them out to fit the scene",
            ));
        }
    }
    if let Some(f) = far
        && !(*f > near.unwrap_or(0.0) && f.is_finite())
    {
        return Err(SceneError::invalid(
            at("far"),
            format!("far {f} is not positive and beyond near"),
            "write far > near > 0 or leave them out",
        ));
    }
    Ok(())
}

/// A light checked and normalised by its crate's one definition ([`Light::checked`]), the
/// fault worded for a scene file: the value's path (`at` of the field) and a fix.
pub(crate) fn validate_light(light: &mut Light, at: &dyn Fn(&str) -> String) -> Result<(), SceneError> {
    *light = light.checked().map_err(|f| light_error(&f, at))?;
    Ok(())
}

/// A light's fault ([`Light::fault`]) as a scene file's error.
pub(crate) fn light_error(f: &LightFault, at: &dyn Fn(&str) -> String) -> SceneError {
    let at = at(f.field);
    match f.problem {
        Problem::PositionNotFinite(_) => SceneError::invalid(at, "the position is not finite", "write finite numbers"),
        Problem::DirectionNotFinite(_) | Problem::DirectionZero => SceneError::invalid(
            at,
            "the direction is zero or not finite",
            "write a non-zero direction such as (0.0, -1.0, 0.0)",
        ),
        Problem::AxisNotFinite(_) | Problem::AxisZero | Problem::AxisAlongNormal => SceneError::invalid(
            at,
            "`u_axis` is zero or parallel to `normal`",
            "write an axis that lies in the rectangle's plane, perpendicular to `normal`",
        ),
        Problem::Length(x) => SceneError::invalid(
            at,
            format!("{} {x} is negative or not finite", f.words),
            format!("write a {} >= 0", f.words),
        ),
        Problem::Angle(a) => SceneError::invalid(
            at,
            format!("angular diameter {a} is outside [0, 180) degrees"),
            "write the full angular diameter in degrees, such as 0.53 for the sun",
        ),
    }
}

fn validate_object(object: &Object, at: &dyn Fn(&str) -> String) -> Result<(), SceneError> {
    let t = &object.transform;
    if !(t.translate.is_finite() && t.scale.is_finite()) {
        return Err(SceneError::invalid(
            at("transform"),
            "the transform is not finite",
            "write finite numbers",
        ));
    }
    let s = t.scale;
    if s.x == 0.0 || s.y == 0.0 || s.z == 0.0 {
        return Err(SceneError::invalid(
            at("transform.scale"),
            format!("a scale of 0 flattens the object (scale ({}, {}, {}))", s.x, s.y, s.z),
            "write non-zero scales",
        ));
    }
    if s.abs().min_element() < MIN_SCALE {
        return Err(SceneError::invalid(
            at("transform.scale"),
            format!(
                "scale ({:e}, {:e}, {:e}) is too small: below {MIN_SCALE:e} the object degenerates in f32 (its triangles lose their area)",
                s.x, s.y, s.z
            ),
            "write scales of at least 1e-10 in magnitude, or change the scene's units",
        ));
    }
    match &t.rotate {
        Rotation::AxisAngle { axis, degrees } if !(axis.is_finite() && axis.length_squared() > 0.0 && degrees.is_finite()) => {
            return Err(SceneError::invalid(
                at("transform.rotate"),
                "the rotation axis is zero or not finite",
                "write a non-zero axis",
            ));
        }
        Rotation::Euler(x, y, z) if !(x.is_finite() && y.is_finite() && z.is_finite()) => {
            return Err(SceneError::invalid(
                at("transform.rotate"),
                "the angles are not finite",
                "write finite angles",
            ));
        }
        Rotation::None | Rotation::Euler(..) | Rotation::AxisAngle { .. } => {}
    }
    match &object.mesh {
        Mesh::Plane { size } if !(size.is_finite() && size.cmpgt(Vec2::ZERO).all()) => Err(SceneError::invalid(
            at("mesh.size"),
            "a plane needs a positive size",
            "write (x, z) sizes > 0",
        )),
        Mesh::Box { size } if !(size.is_finite() && size.cmpgt(Vec3::ZERO).all()) => Err(SceneError::invalid(
            at("mesh.size"),
            "a box needs a positive size",
            "write (x, y, z) sizes > 0",
        )),
        Mesh::Sphere { radius, .. } if !(*radius > 0.0 && radius.is_finite()) => Err(SceneError::invalid(
            at("mesh.radius"),
            format!("radius {radius} is not positive"),
            "write a radius > 0",
        )),
        Mesh::Sphere { segments, .. } if *segments < 3 => Err(SceneError::invalid(
            at("mesh.segments"),
            format!("{segments} segments cannot make a sphere"),
            "write at least 3 segments",
        )),
        Mesh::Sphere { segments, .. } if *segments > MAX_SPHERE_SEGMENTS => Err(SceneError::invalid(
            at("mesh.segments"),
            format!("{segments} segments is above the limit of {MAX_SPHERE_SEGMENTS}"),
            format!("write at most {MAX_SPHERE_SEGMENTS} segments (a sphere of {MAX_SPHERE_SEGMENTS} segments has 1,048,576 triangles)"),
        )),
        Mesh::Triangle { a, b, c } if !(a.is_finite() && b.is_finite() && c.is_finite()) => {
            Err(SceneError::invalid(at("mesh"), "a corner is not finite", "write finite numbers"))
        }
        Mesh::Quad { a, b, c, d } if !(a.is_finite() && b.is_finite() && c.is_finite() && d.is_finite()) => {
            Err(SceneError::invalid(at("mesh"), "a corner is not finite", "write finite numbers"))
        }
        Mesh::City { triangles, .. } if *triangles as usize > MAX_SCENE_TRIANGLES => Err(SceneError::invalid(
            at("mesh.triangles"),
            format!("{triangles} triangles is above the scene limit of {MAX_SCENE_TRIANGLES}"),
            format!("ask for at most {MAX_SCENE_TRIANGLES} triangles"),
        )),
        Mesh::Plane { .. }
        | Mesh::Box { .. }
        | Mesh::Sphere { .. }
        | Mesh::Triangle { .. }
        | Mesh::Quad { .. }
        | Mesh::Obj { .. }
        | Mesh::Gltf { .. }
        | Mesh::City { .. } => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use crate::checked_light;
    use glam::Vec3;
    use sshc_light::Light;

    /// The two paths a light is checked by, the runtime's (`Light::check`, a host's light)
    /// and a scene file's (`checked_light`), word one decision (`Light::fault`): a light one
    /// refuses the other refuses, at the same field, and each keeps its words.
    #[test]
    fn a_light_refused_by_the_runtime_is_refused_by_the_scene_with_the_same_reason() {
        let (nan, inf) = (f32::NAN, f32::INFINITY);
        let p = Vec3::new(0.0, 2.0, 0.0);
        let bad = Vec3::new(nan, 1.0, 0.0);
        let n = Vec3::NEG_Y;
        // (light, the scene's field path, its message, the runtime's message)
        let cases: Vec<(Light, &str, String, String)> = vec![
            (
                Light::Point { position: bad },
                "Point).position",
                "the position is not finite".into(),
                format!("its position {bad} is not finite"),
            ),
            (
                Light::Directional { direction: Vec3::ZERO },
                "Directional).direction",
                "the direction is zero or not finite".into(),
                "its direction is zero".into(),
            ),
            (
                Light::Directional { direction: bad },
                "Directional).direction",
                "the direction is zero or not finite".into(),
                format!("its direction {bad} is not finite"),
            ),
            (
                Light::Sphere { center: p, radius: -1.0 },
                "Sphere).radius",
                "radius -1 is negative or not finite".into(),
                "its radius -1 is not a finite length >= 0".into(),
            ),
            (
                Light::Sphere { center: bad, radius: -1.0 },
                "Sphere).center",
                "the position is not finite".into(),
                format!("its centre {bad} is not finite"),
            ),
            (
                Light::Disk {
                    center: p,
                    normal: Vec3::ZERO,
                    radius: 1.0,
                },
                "Disk).normal",
                "the direction is zero or not finite".into(),
                "its normal is zero".into(),
            ),
            (
                Light::Disk {
                    center: p,
                    normal: n,
                    radius: inf,
                },
                "Disk).radius",
                "radius inf is negative or not finite".into(),
                "its radius inf is not a finite length >= 0".into(),
            ),
            (
                Light::Rectangle {
                    center: p,
                    normal: n,
                    u_axis: Vec3::X,
                    half_width: nan,
                    half_height: 1.0,
                },
                "Rectangle).half_width",
                "half width NaN is negative or not finite".into(),
                "its half width NaN is not a finite length >= 0".into(),
            ),
            (
                Light::Rectangle {
                    center: p,
                    normal: n,
                    u_axis: Vec3::X,
                    half_width: 1.0,
                    half_height: -0.5,
                },
                "Rectangle).half_height",
                "half height -0.5 is negative or not finite".into(),
                "its half height -0.5 is not a finite length >= 0".into(),
            ),
            (
                Light::Rectangle {
                    center: p,
                    normal: n,
                    u_axis: Vec3::new(0.0, 3.0, 0.0),
                    half_width: 1.0,
                    half_height: 1.0,
                },
                "Rectangle).u_axis",
                "`u_axis` is zero or parallel to `normal`".into(),
                "its `u_axis` is parallel to its normal".into(),
            ),
            (
                Light::Rectangle {
                    center: p,
                    normal: n,
                    u_axis: Vec3::ZERO,
                    half_width: 1.0,
                    half_height: 1.0,
                },
                "Rectangle).u_axis",
                "`u_axis` is zero or parallel to `normal`".into(),
                "its u_axis is zero".into(),
            ),
            (
                Light::Rectangle {
                    center: p,
                    normal: n,
                    u_axis: bad,
                    half_width: 1.0,
                    half_height: 1.0,
                },
                "Rectangle).u_axis",
                "`u_axis` is zero or parallel to `normal`".into(),
                format!("its u_axis {bad} is not finite"),
            ),
            (
                Light::Segment { a: p, b: bad },
                "Segment).b",
                "the position is not finite".into(),
                format!("its end b {bad} is not finite"),
            ),
            (
                Light::Triangle { a: p, b: p, c: bad },
                "Triangle).c",
                "the position is not finite".into(),
                format!("its corner c {bad} is not finite"),
            ),
            (
                Light::DistantDisk {
                    direction: Vec3::Y,
                    angle_degrees: 180.0,
                },
                "DistantDisk).angle_degrees",
                "angular diameter 180 is outside [0, 180) degrees".into(),
                "its angular diameter 180 is outside [0, 180) degrees".into(),
            ),
        ];
        for (light, at, scene, runtime) in cases {
            let e = checked_light(2, light.clone()).unwrap_err();
            assert_eq!(e.at(), Some(format!("lights[2] ({at}").as_str()), "{light:?}");
            assert_eq!(e.message(), scene, "{light:?}");
            assert!(e.hint().is_some(), "{light:?}");
            assert_eq!(light.check(), Err(runtime), "{light:?}");
        }
    }

    /// Every light built from good and bad values of each field: accepted or refused alike
    /// by both paths, refused at the field `Light::fault` names, and a light the scene
    /// accepts (normalised) accepted again (unchanged, but for a rectangle's `u_axis`).
    #[test]
    fn both_paths_decide_every_light_alike() {
        let (nan, inf) = (f32::NAN, f32::INFINITY);
        let points = [Vec3::new(0.5, 2.0, -1.0), Vec3::new(nan, 0.0, 0.0), Vec3::new(0.0, -inf, 0.0)];
        let dirs = [
            Vec3::new(0.0, -2.0, 0.0),
            Vec3::new(0.3, -1.0, 0.2),
            Vec3::ZERO,
            Vec3::new(0.0, nan, 0.0),
            Vec3::new(inf, 1.0, 0.0),
            Vec3::new(1e-30, 0.0, 0.0),
        ];
        let axes = [
            Vec3::X,
            Vec3::new(2.0, 0.5, 0.0),
            Vec3::new(0.0, 5.0, 0.0),
            Vec3::new(1e-6, 1.0, 0.0),
            Vec3::ZERO,
            Vec3::new(nan, 0.0, 1.0),
        ];
        let sizes = [0.5, 0.0, -1.0, nan, inf, 1e38];
        let angles = [0.53, 0.0, 179.9, 180.0, -0.1, nan];
        let mut lights = Vec::new();
        for &p in &points {
            lights.push(Light::Point { position: p });
            lights.push(Light::Segment { a: p, b: points[0] });
            lights.push(Light::Segment { a: points[0], b: p });
            lights.push(Light::Triangle {
                a: points[0],
                b: p,
                c: points[0],
            });
            for &r in &sizes {
                lights.push(Light::Sphere { center: p, radius: r });
                for &d in &dirs {
                    lights.push(Light::Disk {
                        center: p,
                        normal: d,
                        radius: r,
                    });
                }
            }
        }
        for &d in &dirs {
            lights.push(Light::Directional { direction: d });
            for &a in &angles {
                lights.push(Light::DistantDisk {
                    direction: d,
                    angle_degrees: a,
                });
            }
            for &u in &axes {
                for &w in &sizes {
                    for &h in &sizes {
                        for &c in &points[..2] {
                            lights.push(Light::Rectangle {
                                center: c,
                                normal: d,
                                u_axis: u,
                                half_width: w,
                                half_height: h,
                            });
                        }
                    }
                }
            }
        }
        let (mut accepted, mut refused) = (0, 0);
        for light in lights {
            let name = light.kind_name();
            match (light.fault(), checked_light(0, light.clone())) {
                (None, Ok(checked)) => {
                    accepted += 1;
                    assert_eq!(light.check(), Ok(()), "{light:?}");
                    assert_eq!(checked.check(), Ok(()), "{checked:?}");
                    let again = checked_light(0, checked.clone());
                    assert!(again.is_ok(), "{light:?}");
                    // (a rectangle's `u_axis` is made perpendicular again, which may move
                    // it by an ulp)
                    if !matches!(light, Light::Rectangle { .. }) {
                        assert_eq!(again.ok(), Some(checked), "{light:?}");
                    }
                }
                (Some(f), Err(e)) => {
                    refused += 1;
                    assert_eq!(light.check(), Err(f.to_string()), "{light:?}");
                    assert_eq!(e.at(), Some(format!("lights[0] ({name}).{}", f.field).as_str()), "{light:?}");
                }
                (f, e) => panic!("{light:?}: the runtime's fault {f:?}, the scene's {e:?}"),
            }
        }
        assert!(accepted > 50 && refused > 1000, "{accepted} accepted, {refused} refused");
    }
}
