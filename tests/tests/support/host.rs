//! Host geometry made from a bound scene, for the embedding tests and the frame-cost bench.

use glam::Vec3;
use sshc_lab::scene::{Camera, Light, Scene};
use sshc_runtime::gpu::{Geometry, IDENTITY, Instance, Mesh, SceneInputs};

/// The soup of `s` as indexed meshes (one per mesh range of the casters, one for the rest),
/// welded by exact position and normal, each an identity instance; plus a second instance
/// of the last caster mesh (the scene's last casting object: after the ground, in the
/// bundled scenes), turned a quarter about y and moved by `shift` (a 3 x 3 of 0 and +-1
/// and a short translation: placement rounds as the CPU does, once per coordinate).
pub fn geometry_of(s: &SceneInputs, shift: [f32; 3]) -> Geometry {
    let total = (s.vertices.len() / 18) as u32;
    let casting_tris = s.casting_vertices.map_or(total, |c| c / 3);
    let mut ranges: Vec<(std::ops::Range<u32>, bool)> = s.meshes.iter().filter(|r| !r.is_empty()).map(|r| (r.clone(), true)).collect();
    if ranges.is_empty() && casting_tris > 0 {
        ranges.push((0..casting_tris, true));
    }
    if casting_tris < total {
        ranges.push((casting_tris..total, false));
    }
    let mut g = Geometry::default();
    for (i, (r, casts)) in ranges.iter().enumerate() {
        let mut mesh = Mesh {
            name: format!("part {i}"),
            ..Default::default()
        };
        let mut weld = std::collections::HashMap::new();
        for v in s.vertices[r.start as usize * 18..r.end as usize * 18].chunks_exact(6) {
            let key: Vec<u32> = v.iter().map(|c| c.to_bits()).collect();
            let next = mesh.positions.len() as u32;
            let ix = *weld.entry(key).or_insert_with(|| {
                mesh.positions.push([v[0], v[1], v[2]]);
                mesh.normals.push([v[3], v[4], v[5]]);
                next
            });
            mesh.indices.push(ix);
        }
        g.meshes.push(mesh);
        g.instances.push(Instance {
            name: format!("part {i}"),
            mesh: i,
            transform: IDENTITY,
            casts: *casts,
            receives: true,
            moves: true,
        });
    }
    let last_caster = ranges.iter().rposition(|(_, casts)| *casts).unwrap_or(0);
    g.instances.push(Instance {
        name: "turned copy".into(),
        mesh: last_caster,
        transform: quarter_turn(shift),
        casts: true,
        receives: true,
        moves: true,
    });
    g
}

/// A quarter turn about y, then a translation.
pub fn quarter_turn(t: [f32; 3]) -> [f32; 16] {
    [0., 0., -1., 0., 0., 1., 0., 0., 1., 0., 0., 0., t[0], t[1], t[2], 1.]
}

/// `s` with the geometry's triangles listed out in its place.
pub fn listed_out(s: &SceneInputs, g: &Geometry) -> SceneInputs {
    let (vertices, casting) = g.soup().unwrap_or_else(|e| panic!("{e}"));
    SceneInputs {
        casting_vertices: Some(casting),
        unshadowed: g.soup_unshadowed(),
        meshes: g.soup_meshes(),
        vertices,
        ..s.clone()
    }
}

/// Move a light by `d` (a position or centre), or tilt it towards `d` (a direction).
pub fn shift(light: &mut Light, d: Vec3) {
    match light {
        Light::Point { position } => *position += d,
        Light::Sphere { center, .. } | Light::Disk { center, .. } | Light::Rectangle { center, .. } => *center += d,
        Light::Segment { a, b } => {
            *a += d;
            *b += d;
        }
        Light::Triangle { a, b, c } => {
            *a += d;
            *b += d;
            *c += d;
        }
        Light::Directional { direction } | Light::DistantDisk { direction, .. } => *direction = (*direction + 0.1 * d).normalize(),
    }
}

/// The scene at frame `f` of an orbit: the light circles its start by a tenth of the
/// scene's size, and the camera sways sideways.
pub fn at_frame(base: &Scene, f: u32) -> Scene {
    let mut s = base.clone();
    let (lo, hi) = s.bounds();
    let r = 0.1 * (hi - lo).length();
    let a = f as f32 * 0.37;
    let d = Vec3::new(r * a.cos(), 0.0, r * a.sin()) - Vec3::new(r, 0.0, 0.0);
    for l in &mut s.lights {
        shift(l, d);
    }
    match &mut s.camera {
        Camera::Perspective { position, .. } | Camera::Orthographic { position, .. } => *position += 0.2 * r * a.sin() * Vec3::X,
    }
    s
}
