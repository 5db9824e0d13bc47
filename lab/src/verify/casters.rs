//! Caster meshes above the query plane: the bundled sets of boxes, and a scene's casters
//! fitted into the slab above the plane.

use super::plane::CASTER_SLAB;
use glam::Vec3;
use std::path::Path;

/// The caster sets of [`caster_set`], by name.
pub const CASTERS: [&str; 2] = ["box", "bars"];

/// Triangles (position and normal per vertex) of an axis-aligned box from `lo` to `hi`,
/// turned by `turn` radians about the vertical through its centre.
fn box_triangles(lo: Vec3, hi: Vec3, turn: f32) -> Vec<f32> {
    let c = 0.5 * (lo + hi);
    let rot = glam::Quat::from_rotation_y(turn);
    let h = 0.5 * (hi - lo);
    let mut out = Vec::new();
    // each face: its normal axis and sign; corners in counter-clockwise order seen from outside
    for (axis, sign) in [(0, 1.0f32), (0, -1.0), (1, 1.0), (1, -1.0), (2, 1.0), (2, -1.0)] {
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        let corner = |a: f32, b: f32| {
            let mut p = Vec3::ZERO;
            p[axis] = sign * h[axis];
            p[u] = a * h[u];
            p[v] = b * h[v] * sign;
            c + rot * p
        };
        let mut n = Vec3::ZERO;
        n[axis] = sign;
        let n = rot * n;
        let q = [corner(-1.0, -1.0), corner(1.0, -1.0), corner(1.0, 1.0), corner(-1.0, 1.0)];
        for i in [0, 1, 2, 0, 2, 3] {
            out.extend([q[i].x, q[i].y, q[i].z, n.x, n.y, n.z]);
        }
    }
    out
}

/// A bundled caster set above the query plane (heights within [`CASTER_SLAB`]), by name
/// ([`CASTERS`]): its triangles and meshes (ranges of triangles), or `None`.
///
/// - `box`: one box, 0.7 wide, its silhouette square to the map;
/// - `bars`: three boxes at three heights, one turned by 30 degrees (diagonal silhouettes).
pub fn caster_set(name: &str) -> Option<(Vec<f32>, Vec<std::ops::Range<u32>>)> {
    let boxes: Vec<(Vec3, Vec3, f32)> = match name {
        "box" => vec![(Vec3::new(-0.35, 2.45, -0.35), Vec3::new(0.35, 2.9, 0.35), 0.0)],
        "bars" => vec![
            (Vec3::new(-0.75, 2.4, -0.7), Vec3::new(-0.45, 2.6, 0.7), 0.0),
            (Vec3::new(-0.1, 2.7, -0.5), Vec3::new(0.15, 2.95, 0.5), std::f32::consts::FRAC_PI_6),
            (Vec3::new(0.45, 3.05, -0.6), Vec3::new(0.7, 3.25, 0.2), 0.0),
        ],
        _ => return None,
    };
    let mut vertices = Vec::new();
    let mut meshes = Vec::new();
    for (lo, hi, turn) in boxes {
        let first = (vertices.len() / 18) as u32;
        vertices.extend(box_triangles(lo, hi, turn));
        meshes.push(first..(vertices.len() / 18) as u32);
    }
    Some((vertices, meshes))
}

/// A scene's shadow casters fitted into the slab above the query plane: uniformly scaled
/// and moved so that they span at most 1.5 across x and z and lie within [`CASTER_SLAB`].
pub fn scene_casters(path: &Path) -> Result<(Vec<f32>, Vec<std::ops::Range<u32>>), String> {
    let s = crate::session::load_scene(path, Some((8, 8)), Some(8))?;
    let inputs = crate::bind::scene_inputs(&s)?;
    let casting = inputs.casting_vertices.map_or(inputs.vertices.len() / 6, |n| n as usize);
    let triangles = (casting / 3) as u32;
    let all = 0..triangles;
    let meshes = if inputs.meshes.is_empty() {
        std::slice::from_ref(&all)
    } else {
        &inputs.meshes[..]
    };
    let bounds = |m: &std::ops::Range<u32>| {
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for t in m.start..m.end.min(triangles) {
            for v in inputs.vertices[t as usize * 18..t as usize * 18 + 18].chunks(6) {
                lo = lo.min(Vec3::new(v[0], v[1], v[2]));
                hi = hi.max(Vec3::new(v[0], v[1], v[2]));
            }
        }
        (lo, hi)
    };
    // floors (flat and level) receive; they are left out, as the plane receives here
    let kept: Vec<std::ops::Range<u32>> = meshes
        .iter()
        .filter(|m| m.start < triangles)
        .filter(|m| {
            let (lo, hi) = bounds(m);
            let e = hi - lo;
            e.y > 0.01 * e.x.max(e.z)
        })
        .cloned()
        .collect();
    if kept.is_empty() {
        return Err(format!("scene `{}` has no shadow casters but floors", path.display()));
    }
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for m in &kept {
        let (a, b) = bounds(m);
        lo = lo.min(a);
        hi = hi.max(b);
    }
    let ext = hi - lo;
    let scale = (1.5 / ext.x.max(ext.z).max(f32::MIN_POSITIVE)).min((CASTER_SLAB.1 - CASTER_SLAB.0) / ext.y.max(f32::MIN_POSITIVE));
    let centre = Vec3::new(0.5 * (lo.x + hi.x), lo.y, 0.5 * (lo.z + hi.z));
    let mut out = Vec::new();
    let mut out_meshes = Vec::new();
    for m in &kept {
        let first = (out.len() / 18) as u32;
        for v in inputs.vertices[m.start as usize * 18..m.end.min(triangles) as usize * 18].chunks(6) {
            let p = (Vec3::new(v[0], v[1], v[2]) - centre) * scale + Vec3::new(0.0, CASTER_SLAB.0, 0.0);
            out.extend([p.x, p.y, p.z, v[3], v[4], v[5]]);
        }
        out_meshes.push(first..(out.len() / 18) as u32);
    }
    Ok((out, out_meshes))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every vertex within the slab above the plane and the light's square (x, z in [-1, 1]).
    fn in_slab(vertices: &[f32]) -> bool {
        vertices
            .chunks(6)
            .all(|v| (CASTER_SLAB.0 - 1e-5..=CASTER_SLAB.1 + 1e-5).contains(&v[1]) && v[0].abs() < 1.0 && v[2].abs() < 1.0)
    }

    #[test]
    fn caster_sets_are_closed_boxes_in_the_slab_with_outward_normals() {
        for name in CASTERS {
            let (vertices, meshes) = caster_set(name).expect("a bundled set");
            assert!(in_slab(&vertices), "{name}");
            // one mesh of 12 triangles per box, covering every triangle in order
            assert!(meshes.iter().all(|m| m.end - m.start == 12), "{name}: {meshes:?}");
            assert_eq!(meshes.last().map(|m| m.end), Some((vertices.len() / 18) as u32), "{name}");
            for m in &meshes {
                let tri = |t: u32| &vertices[t as usize * 18..t as usize * 18 + 18];
                let centre = (m.start..m.end)
                    .flat_map(|t| tri(t).chunks(6).map(|v| Vec3::new(v[0], v[1], v[2])).collect::<Vec<_>>())
                    .sum::<Vec3>()
                    / (3.0 * 12.0);
                for t in m.clone() {
                    let v: Vec<Vec3> = tri(t).chunks(6).map(|v| Vec3::new(v[0], v[1], v[2])).collect();
                    let n = Vec3::new(tri(t)[3], tri(t)[4], tri(t)[5]);
                    let face = (v[1] - v[0]).cross(v[2] - v[0]);
                    // counter-clockwise seen from outside, the normal pointing away from the box
                    assert!(
                        face.dot(n) > 0.0 && n.dot((v[0] + v[1] + v[2]) / 3.0 - centre) > 0.0,
                        "{name}: triangle {t}"
                    );
                }
            }
        }
        assert!(caster_set("bogus").is_none());
    }

    #[test]
    fn a_scenes_casters_leave_its_floor_out_and_fit_the_slab() {
        let bunny = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/bunny.ron");
        let (vertices, meshes) = scene_casters(&bunny).unwrap_or_else(|e| panic!("{e}"));
        assert!(in_slab(&vertices));
        // the floor (flat and level) is left out: every mesh kept has height
        assert!(!meshes.is_empty());
        for m in &meshes {
            let ys: Vec<f32> = vertices[m.start as usize * 18..m.end as usize * 18]
                .chunks(6)
                .map(|v| v[1])
                .collect();
            let (lo, hi) = ys
                .iter()
                .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &y| (a.min(y), b.max(y)));
            assert!(hi - lo > 0.1, "a flat mesh was kept: {m:?}, heights {lo}..{hi}");
        }
    }
}
