//! What a window resize costs the viewer (docs/embedding.md, "Resizing"): before issue 49
//! it bound the scene again at the new size (`bind_scene`: the soup uploaded again, the edge
//! adjacency built again, every texture and bind group made again); now it calls
//! `Bound::resize`, which makes only the camera-sized targets. For a few bundled
//! techniques on the bunny (a raster one, one with Geometry passes and a mip chain, one
//! with summed-area tables), alternately one and the other between two sizes, the median
//! wall time of each (until the device is idle, so that lazily made objects count), and
//! the textures each made again (the fall of wgpu-hal's live texture count, which counts
//! a texture when it is destroyed but not when it is made: every texture made again
//! replaces one).
//!
//! Beside it, what a host pays today to add an instance (a spawned entity): the bunny as
//! host geometry (its soup welded into meshes, one instance each) with and without one
//! more bunny instance, alternately, each a new `Scene::upload` (every mesh uploaded
//! again, the adjacency built again where the technique classifies silhouettes) and
//! `Targets::set_scene` (no texture made again; bind groups and bundles made again): the
//! baseline. And what it pays now: the same instance added and removed in place
//! (`Scene::add_instance`, `remove_instance`, then `Targets::set_scene`): its 256-byte
//! record written, the draws recorded again into the scene-drawing bundles (the steps
//! that classify silhouettes bound again where edges changed); the buffers that grew and
//! the step bindings made, over all the changes (docs/embedding.md section 7).
//!
//! `cargo bench -p sshc-tests --bench resize_cost` (about a minute on lavapipe);
//! `SSHC_RESIZES` (default 9 of each). Writes `target/embedding/resize-cost.md`.

#[path = "../tests/support/mod.rs"]
mod support;

use sshc_lab::run::Loaded;
use sshc_lab::scene::Scene;
use std::time::Instant;
use support::{gpu, root};

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

fn main() {
    let n: usize = std::env::var("SSHC_RESIZES").ok().and_then(|v| v.parse().ok()).unwrap_or(9);
    let gpu = gpu();
    let textures = || gpu.device.get_internal_counters().hal.textures.read();
    let mut table = format!(
        "Device: {}. Bunny scene (`scenes/bunny.ron`), shadow map 1024^2, window 640 x 480 <-> 800 x 600, {n} resizes of each kind, alternating; wall time until the device is idle.\n\n| technique | rebind (before), ms median | textures made | `resize` (now), ms median | textures made | rebind / resize | an instance added or removed: `Scene::upload` + `set_scene`, ms median | textures made | in place: `add_instance` or `remove_instance` + `set_scene`, ms median | upload / in place | buffers grown, all changes | step bindings made per change | bytes written per instance added |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
        gpu.describe()
    );
    for t in ["hard", "pcss", "vssm", "penumbra-maps"] {
        let c = support::compile_source(t, &support::technique_source(t), &[], &[]);
        let mut scene = Scene::load(root().join("scenes").join("bunny.ron")).unwrap();
        scene.shadow_map = 1024;
        let sizes = [(640, 480), (800, 600)];
        let inputs: Vec<_> = sizes
            .iter()
            .map(|&(w, h)| {
                scene.set_camera_size(w, h);
                sshc_lab::bind::scene_inputs_for(&scene, &c.graph).unwrap()
            })
            .collect();
        let loaded = Loaded::new(gpu, c.graph.clone(), c.shaders.clone()).unwrap();
        let mut ex = loaded.bind_scene(&inputs[0]).unwrap();
        ex.run_frame().unwrap();
        let (mut rebind, mut resize) = (Vec::new(), Vec::new());
        let (mut made_rebind, mut made_resize) = (0, 0);
        for i in 0..2 * n {
            let to = (i + 1) % 2;
            let before = textures();
            let t0 = Instant::now();
            if i % 2 == 0 {
                ex = loaded.bind_scene(&inputs[to]).unwrap();
            } else {
                ex.targets.resize(inputs[to].camera_size).unwrap();
                ex.state.camera = inputs[to].camera();
            }
            gpu.wait().unwrap();
            let ms = t0.elapsed().as_secs_f64() * 1e3;
            // the replaced textures are destroyed once the next frame's submission is done
            ex.run_frame().unwrap();
            let made = before - textures();
            if i % 2 == 0 {
                rebind.push(ms);
                made_rebind = made;
            } else {
                resize.push(ms);
                made_resize = made;
            }
        }
        let (a, b) = (median(&mut rebind), median(&mut resize));
        // an instance spawned and despawned, alternately: the whole scene uploaded again
        let mut g = support::host::geometry_of(&inputs[1], [0.0; 3]);
        g.instances.pop(); // the turned copy
        let bunny = (0..g.instances.len())
            .max_by_key(|&i| g.meshes[g.instances[i].mesh].indices.len())
            .unwrap();
        let mut more = g.clone();
        let mut spawned = more.instances[bunny].clone();
        spawned.transform[12] += 0.6;
        more.instances.push(spawned);
        let technique = &loaded.technique;
        let mut ex = loaded
            .bind_geometry(
                &g,
                &inputs[1].camera(),
                &[inputs[1].light_inputs()],
                inputs[1].camera_size,
                inputs[1].shadow_size,
            )
            .unwrap();
        ex.run_frame().unwrap();
        let (mut spawn, mut made_spawn) = (Vec::new(), 0);
        for i in 0..2 * n {
            let geometry = if i % 2 == 0 { &more } else { &g };
            let before = textures();
            let t0 = Instant::now();
            ex.scene = sshc_runtime::gpu::Scene::upload(gpu, geometry, &[technique]).unwrap();
            ex.targets.set_scene(&ex.scene).unwrap();
            gpu.wait().unwrap();
            spawn.push(t0.elapsed().as_secs_f64() * 1e3);
            ex.run_frame().unwrap();
            made_spawn = before - textures();
        }
        // the same instance added and removed in place
        let spawned = more.instances.last().unwrap().clone();
        let (grown, bound, written) = (ex.scene.buffers_grown(), ex.targets.step_bindings_made(), ex.scene.bytes_added());
        let mut in_place = Vec::new();
        for i in 0..2 * n {
            let t0 = Instant::now();
            if i % 2 == 0 {
                ex.scene.add_instance(&spawned).unwrap();
            } else {
                ex.scene.remove_instance(g.instances.len()).unwrap();
            }
            ex.targets.set_scene(&ex.scene).unwrap();
            gpu.wait().unwrap();
            in_place.push(t0.elapsed().as_secs_f64() * 1e3);
            ex.run_frame().unwrap();
        }
        let (up, here) = (median(&mut spawn), median(&mut in_place));
        let row = format!(
            "| {t} | {a:.2} | {made_rebind} | {b:.2} | {made_resize} | {:.1} | {up:.2} | {made_spawn} | {here:.3} | {:.0} | {} | {:.1} | {} |\n",
            a / b,
            up / here,
            ex.scene.buffers_grown() - grown,
            (ex.targets.step_bindings_made() - bound) as f64 / (2 * n) as f64,
            (ex.scene.bytes_added() - written) / n as u64,
        );
        print!("{row}");
        table.push_str(&row);
    }
    let dir = root().join("target").join("embedding");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("resize-cost.md"), &table).unwrap();
    println!("\n{table}");
}
