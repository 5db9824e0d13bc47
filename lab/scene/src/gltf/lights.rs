//! The lights of `KHR_lights_punctual` as the scene's lights, sized by their `extras`,
//! and the sun of a scene that has none.

use super::{DEFAULT_RADIUS_FRACTION, DEFAULT_SUN_DEGREES, fail};
use crate::error::SceneError;

use glam::{Mat4, Vec3};
use gltf::khr_lights_punctual::Kind;
use sshc_light::Light;

/// A number from a light's `extras` (an object), or `default` when absent.
fn extra(light: &gltf::khr_lights_punctual::Light, key: &str, default: f32, file: &str, at: &str) -> Result<f32, SceneError> {
    let Some(raw) = light.extras() else { return Ok(default) };
    let value: serde_json::Value = serde_json::from_str(raw.get()).map_err(|e| {
        fail(
            file,
            format_args!("{at}'s extras are not JSON: {e}"),
            "write the extras as a JSON object",
        )
    })?;
    match value.get(key) {
        None => Ok(default),
        Some(v) => v.as_f64().map(|x| x as f32).filter(|x| x.is_finite()).ok_or_else(|| {
            fail(
                file,
                format_args!("{at}'s `extras.{key}` is {v}, not a finite number"),
                "write a number",
            )
        }),
    }
}

pub(super) fn map_light(
    light: &gltf::khr_lights_punctual::Light,
    world: &Mat4,
    node: usize,
    diagonal: f32,
    file: &str,
    spots: &mut usize,
) -> Result<Light, SceneError> {
    let at = match light.name() {
        Some(n) => format!("light {} (\"{n}\") of node {node}", light.index()),
        None => format!("light {} of node {node}", light.index()),
    };
    let position = world.transform_point3(Vec3::ZERO);
    // a light shines along its node's -Z
    let facing = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
    let radius = |file: &str| -> Result<f32, SceneError> {
        let r = extra(light, "radius", DEFAULT_RADIUS_FRACTION * diagonal, file, &at)?;
        if r < 0.0 {
            return Err(fail(
                file,
                format_args!("{at}'s `extras.radius` is {r}, below 0"),
                "write a radius >= 0",
            ));
        }
        Ok(r)
    };
    let unit = |v: Vec3| {
        if v == Vec3::ZERO {
            Err(fail(
                file,
                format_args!("{at}: its node's transform collapses the light's direction"),
                "give the light's node an invertible transform",
            ))
        } else {
            Ok(v)
        }
    };
    let light = match light.kind() {
        Kind::Directional => {
            let angle_degrees = extra(light, "angle_degrees", DEFAULT_SUN_DEGREES, file, &at)?;
            if !(0.0..180.0).contains(&angle_degrees) {
                return Err(fail(
                    file,
                    format_args!("{at}'s `extras.angle_degrees` is {angle_degrees}, outside [0, 180)"),
                    "write the sun's angular diameter in degrees (about 0.53)",
                ));
            }
            Light::DistantDisk {
                direction: unit(-facing)?,
                angle_degrees,
            }
        }
        Kind::Point => Light::Sphere {
            center: position,
            radius: radius(file)?,
        },
        Kind::Spot { .. } => {
            *spots += 1;
            Light::Disk {
                center: position,
                normal: unit(facing)?,
                radius: radius(file)?,
            }
        }
    };
    if !(position.is_finite()) {
        return Err(fail(
            file,
            format_args!("{at} is placed at a position that is not finite"),
            "write finite transforms",
        ));
    }
    Ok(light)
}

/// The light of a glTF scene that has none: a sun from above, [`DEFAULT_SUN_DEGREES`] wide.
pub(crate) fn default_sun() -> Light {
    Light::DistantDisk {
        direction: Vec3::new(0.4, 1.0, 0.3).normalize(),
        angle_degrees: DEFAULT_SUN_DEGREES,
    }
}
