//! A procedural city, written as glTF (GLB), for measuring techniques on large scenes.
//!
//! A square grid of blocks on a ground plane; on each block a tower: a prism of 4 to 12
//! sides, floor upon floor, each floor a wall band and a ledge that juts out and back (8
//! triangles a side and floor), capped by a flat roof. Six tower meshes are built once;
//! every tower is a node placing one of them (scaled, turned about +Y, moved), so the file
//! holds instancing as an engine's would, and the importer reads it as it reads any glTF.
//! Towers are added until the triangle count reaches the one asked for.
//!
//! Reproducible: the same `(triangles, seed)` gives the same bytes on every machine (the
//! random numbers are SplitMix64's, the layout plain f32 arithmetic).

use glam::{Quat, Vec3};
use serde_json::json;

/// Towers' meshes: (sides, floors); each has `8 * sides * floors + sides` triangles.
const TOWERS: [(u32, u32); 6] = [(4, 10), (6, 16), (8, 24), (12, 32), (4, 40), (8, 8)];

/// Distance between blocks' centres, in scene units (the ground spans the grid).
pub const BLOCK: f32 = 1.0;

/// SplitMix64 (Steele, Lea and Flood 2014): a fixed generator, so the city does not change
/// with a crate's version.
struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    fn unit(&mut self) -> f32 {
        (self.next() >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// One tower mesh in a unit box: radius 1 about +Y, from y = 0 to y = 1; flat normals
/// (each quad has its own four vertices).
fn tower(sides: u32, floors: u32) -> (Vec<[f32; 3]>, Vec<[f32; 3]>, Vec<u32>) {
    let (mut p, mut n, mut ix) = (Vec::new(), Vec::new(), Vec::new());
    let corner = |k: u32, r: f32, y: f32| {
        let a = std::f32::consts::TAU * (k % sides) as f32 / sides as f32;
        Vec3::new(r * a.cos(), y, -r * a.sin())
    };
    // a quad a, b, c, d counter-clockwise seen from its front
    let mut quad = |q: [Vec3; 4]| {
        let normal = (q[1] - q[0]).cross(q[2] - q[0]).normalize_or_zero();
        let base = p.len() as u32;
        for v in q {
            p.push(v.to_array());
            n.push(normal.to_array());
        }
        ix.extend([base, base + 1, base + 2, base, base + 2, base + 3]);
    };
    let (inner, outer) = (1.0 / 1.08, 1.0);
    let storey = 1.0 / floors as f32;
    for f in 0..floors {
        let y0 = f as f32 * storey;
        let (y1, y2) = (y0 + 0.8 * storey, y0 + storey);
        // the wall band (facing out), the ledge's underside (down), its front (out) and its
        // top (up): each a quad from (radius, height) to (radius, height) across a side
        let bands = [
            (inner, y0, inner, y1),
            (inner, y1, outer, y1),
            (outer, y1, outer, y2),
            (outer, y2, inner, y2),
        ];
        for k in 0..sides {
            let (a, b) = (k, k + 1);
            for (r0, h0, r1, h1) in bands {
                quad([corner(a, r0, h0), corner(b, r0, h0), corner(b, r1, h1), corner(a, r1, h1)]);
            }
        }
    }
    // the roof: a fan about its centre, facing up
    let centre = p.len() as u32;
    p.push([0.0, 1.0, 0.0]);
    n.push([0.0, 1.0, 0.0]);
    for k in 0..sides {
        let base = p.len() as u32;
        for c in [corner(k, inner, 1.0), corner(k + 1, inner, 1.0)] {
            p.push(c.to_array());
            n.push([0.0, 1.0, 0.0]);
        }
        ix.extend([centre, base, base + 1]);
    }
    (p, n, ix)
}

/// Triangles of tower mesh `k`.
fn tower_triangles(k: usize) -> usize {
    let (s, f) = TOWERS[k];
    (8 * s * f + s) as usize
}

/// The city of about `triangles` triangles (at least one tower and the ground), as GLB
/// bytes: a ground plane node, a node per tower, no camera and no light (a scene file adds
/// them).
pub fn city_glb(triangles: usize, seed: u64) -> Vec<u8> {
    let mut rng = SplitMix(seed);
    // the towers, in order, until the count is reached
    let mut kinds = Vec::new();
    let mut total = 2usize;
    while total < triangles || kinds.is_empty() {
        let k = (rng.next() % TOWERS.len() as u64) as usize;
        kinds.push(k);
        total += tower_triangles(k);
    }
    let side = (kinds.len() as f64).sqrt().ceil() as usize;
    let extent = side as f32 * BLOCK;

    // the binary chunk: the ground, then each tower mesh (positions, normals, indices)
    let mut bin: Vec<u8> = Vec::new();
    let (mut views, mut accessors, mut meshes) = (Vec::new(), Vec::new(), Vec::new());
    let mut push_mesh = |name: String, p: &[[f32; 3]], n: &[[f32; 3]], ix: &[u32], bin: &mut Vec<u8>| {
        let (lo, hi) = p.iter().fold(([f32::MAX; 3], [f32::MIN; 3]), |(lo, hi), v| {
            (
                [lo[0].min(v[0]), lo[1].min(v[1]), lo[2].min(v[2])],
                [hi[0].max(v[0]), hi[1].max(v[1]), hi[2].max(v[2])],
            )
        });
        let first = accessors.len();
        for (floats, target) in [(p, 34962), (n, 34962)] {
            let offset = bin.len();
            bin.extend(floats.iter().flatten().flat_map(|x| x.to_le_bytes()));
            views.push(json!({"buffer": 0, "byteOffset": offset, "byteLength": bin.len() - offset, "target": target}));
        }
        let offset = bin.len();
        bin.extend(ix.iter().flat_map(|i| i.to_le_bytes()));
        views.push(json!({"buffer": 0, "byteOffset": offset, "byteLength": bin.len() - offset, "target": 34963}));
        let v = views.len() - 3;
        accessors.push(json!({"bufferView": v, "componentType": 5126, "count": p.len(), "type": "VEC3", "min": lo, "max": hi}));
        accessors.push(json!({"bufferView": v + 1, "componentType": 5126, "count": n.len(), "type": "VEC3"}));
        accessors.push(json!({"bufferView": v + 2, "componentType": 5125, "count": ix.len(), "type": "SCALAR"}));
        meshes.push(json!({"name": name, "primitives": [{"attributes": {"POSITION": first, "NORMAL": first + 1}, "indices": first + 2}]}));
    };
    let g = 0.5 * extent + BLOCK;
    let ground = [[-g, 0.0, -g], [-g, 0.0, g], [g, 0.0, g], [g, 0.0, -g]];
    push_mesh("ground".into(), &ground, &[[0.0, 1.0, 0.0]; 4], &[0, 1, 2, 0, 2, 3], &mut bin);
    for (k, (s, f)) in TOWERS.iter().enumerate() {
        let (p, n, ix) = tower(*s, *f);
        push_mesh(format!("tower {k} ({s} sides, {f} floors)"), &p, &n, &ix, &mut bin);
    }

    let mut nodes = vec![json!({"name": "ground", "mesh": 0})];
    for (i, &k) in kinds.iter().enumerate() {
        let (col, row) = ((i % side) as f32, (i / side) as f32);
        let centre = Vec3::new((col + 0.5) * BLOCK - 0.5 * extent, 0.0, (row + 0.5) * BLOCK - 0.5 * extent);
        // footprint 0.25 to 0.4 of a block's half, heights skewed towards low towers
        let radius = BLOCK * (0.25 + 0.15 * rng.unit());
        let height = BLOCK * (0.4 + 3.6 * rng.unit().powi(3)) * (1.0 + 0.3 * TOWERS[k].1 as f32 / 40.0);
        let turn = Quat::from_rotation_y(std::f32::consts::TAU * rng.unit());
        nodes.push(json!({
            "name": format!("tower {i}"),
            "mesh": k + 1,
            "translation": centre.to_array(),
            "rotation": turn.to_array(),
            "scale": [radius, height, radius],
        }));
    }
    let root = json!({
        "asset": {"version": "2.0", "generator": format!("sshc scene city (triangles {triangles}, seed {seed})")},
        "scene": 0,
        "scenes": [{"nodes": (0..nodes.len()).collect::<Vec<_>>()}],
        "nodes": nodes,
        "meshes": meshes,
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": bin.len()}],
    });
    glb(&root, bin)
}

/// A triangle soup as GLB: one mesh of the triangles listed out (no index buffer), with
/// their corners' normals, placed by one node at the identity. Read back, it gives the same
/// triangles, bit for bit (the importer places nothing at the identity).
pub fn soup_glb(triangles: &[[Vec3; 3]], normals: &[[Vec3; 3]]) -> Vec<u8> {
    let mut bin: Vec<u8> = triangles
        .iter()
        .flatten()
        .flat_map(|v| v.to_array())
        .flat_map(f32::to_le_bytes)
        .collect();
    let split = bin.len();
    bin.extend(normals.iter().flatten().flat_map(|v| v.to_array()).flat_map(f32::to_le_bytes));
    let (lo, hi) = sshc_light::bounds_of(triangles.iter().flatten().copied());
    let count = 3 * triangles.len();
    let root = json!({
        "asset": {"version": "2.0", "generator": "sshc soup_glb"},
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}}]}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": count, "type": "VEC3", "min": lo.to_array(), "max": hi.to_array()},
            {"bufferView": 1, "componentType": 5126, "count": count, "type": "VEC3"},
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": split},
            {"buffer": 0, "byteOffset": split, "byteLength": bin.len() - split},
        ],
        "buffers": [{"byteLength": bin.len()}],
    });
    glb(&root, bin)
}

/// One small triangle placed by `copies` nodes on a square grid of unit spacing over the
/// ground (no ground, camera or light: a scene file adds them), as GLB: a scene of many
/// instances of one mesh.
pub fn instances_glb(copies: usize) -> Vec<u8> {
    let tri = [[0.0f32, 0.0, 0.0], [0.4, 0.0, 0.0], [0.0, 0.4, 0.0]];
    let mut bin: Vec<u8> = tri.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
    let split = bin.len();
    bin.extend([[0.0f32, 0.0, 1.0]; 3].iter().flatten().flat_map(|x| x.to_le_bytes()));
    let side = (copies as f64).sqrt().ceil().max(1.0) as usize;
    let nodes: Vec<serde_json::Value> = (0..copies)
        .map(|k| json!({"mesh": 0, "translation": [(k % side) as f32, 0.5, (k / side) as f32]}))
        .collect();
    let root = json!({
        "asset": {"version": "2.0", "generator": "sshc instances_glb"},
        "nodes": nodes,
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}}]}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0.0, 0.0, 0.0], "max": [0.4, 0.4, 0.0]},
            {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC3"},
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": split},
            {"buffer": 0, "byteOffset": split, "byteLength": bin.len() - split},
        ],
        "buffers": [{"byteLength": bin.len()}],
    });
    glb(&root, bin)
}

/// A GLB container (glTF 2.0 section 4.4) around `json` and one binary chunk, written by
/// the `gltf` crate (which pads both chunks to 4 bytes and sets the lengths).
pub fn glb(json: &serde_json::Value, bin: Vec<u8>) -> Vec<u8> {
    let glb = gltf::binary::Glb {
        header: gltf::binary::Header {
            magic: *b"glTF",
            version: 2,
            length: 0,
        },
        json: std::borrow::Cow::Owned(json.to_string().into_bytes()),
        bin: (!bin.is_empty()).then_some(std::borrow::Cow::Owned(bin)),
    };
    // writing to a Vec cannot fail: it has no I/O error
    glb.to_vec().unwrap_or_default()
}
