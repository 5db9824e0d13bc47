//! The per-frame cost of the embedding API, for every bundled technique:
//!
//! - **CPU**: the host thread's own CPU time (`CLOCK_THREAD_CPUTIME_ID`) in the frame's
//!   state changed (camera and every light) + `prepare` + `record` into the host's encoder,
//!   median of `FRAMES` frames after 10 untimed ones, two ways: *cold* (each frame recorded
//!   just after waiting for the last) and *isolated* (frames back to back, no GPU work in
//!   flight); each beside bare wgpu's floor for as many passes ([`Floor`]) timed the same
//!   way, alternating with sshc's frames; on a host's binding (`TargetLimits::default`: no
//!   GPU timestamps), and isolated again on the lab's (every pass timed). Beside them, the wall time of the cold frames (and
//!   its `prepare` / `record` split), with the scene bound as a triangle soup and again as
//!   host geometry, there also with the light's view fitted by sshc every frame
//!   (`Targets::fit_light`). The host's own encoder creation, its submission and the wait
//!   are outside the timing.
//! - **GPU, moving against static**: the GPU time of a frame (the sum of its passes'
//!   timestamps, read back through the ring) with the light and camera moving every frame,
//!   against the same executor with them still (the lab's binding). Frames alternate moving and static so that
//!   drifts of the machine hit both; the ratio is of the two medians, taken in one run.
//!   Beside it, the wall time of the frame's submission until the device is idle, for the
//!   same two sets of frames: on lavapipe the end timestamp of a compute pass does not wait
//!   for its last dispatch (docs/agreement.md), so the wall time is the check on the
//!   timestamps.
//!
//! Prints a Markdown table and writes it to `target/embedding/frame-cost.md` (quoted in
//! docs/embedding.md). A measurement, minutes on lavapipe: `cargo bench -p sshc-tests
//! --bench frame_cost`; `SSHC_FRAMES` (default 1000), `SSHC_CAMERA` (side, default 128),
//! `SSHC_SHADOW` (default 256), `SSHC_TECHNIQUES` (a comma-separated subset), `SSHC_BYTES=0` (without the bytes table). The test suite only builds it (`cargo clippy --all-targets`).

#[path = "../tests/support/mod.rs"]
mod support;

use sshc_lab::run::Loaded;
use sshc_lab::scene::{Light, Scene};
use sshc_runtime::gpu::{Fit, SceneInputs, TargetLimits};
use std::time::Instant;
use support::host::at_frame;
use support::{gpu, root};

fn env(name: &str, default: u32) -> u32 {
    std::env::var(name).ok().and_then(|v| v.parse().ok()).unwrap_or(default)
}

/// The calling thread's own CPU time, in µs (`CLOCK_THREAD_CPUTIME_ID`): the time the host
/// thread spent running, without the time it waited while lavapipe's threads (which run
/// the previous frame's passes on the same cores) held them.
fn thread_cpu_us() -> f64 {
    let mut t = libc::timespec { tv_sec: 0, tv_nsec: 0 };
    // SAFETY: `t` is a valid timespec to write into; the clock exists on Linux
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut t) };
    assert_eq!(rc, 0, "clock_gettime(CLOCK_THREAD_CPUTIME_ID)");
    t.tv_sec as f64 * 1e6 + t.tv_nsec as f64 * 1e-3
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

fn percentile(v: &mut [f64], p: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(((v.len() as f64 - 1.0) * p).round() as usize).copied().unwrap_or(f64::NAN)
}

fn main() {
    let frames = env("SSHC_FRAMES", 1000);
    let (camera, shadow) = (env("SSHC_CAMERA", 128), env("SSHC_SHADOW", 256));
    let gpu = gpu();
    let mut names = support::bundled("techniques");
    // `SSHC_TECHNIQUES=a,b`: only these
    if let Ok(only) = std::env::var("SSHC_TECHNIQUES") {
        names.retain(|n| only.split(',').any(|o| o == n));
    }
    let floor = Floor::new();
    let mut table = format!(
        "Device: {}. {frames} frames a technique, camera {camera}^2, shadow map {shadow}^2. CPU times are the host thread's own (`CLOCK_THREAD_CPUTIME_ID`), medians. *Cold*: each frame recorded just after waiting for the last (as a host that waits for its GPU; on lavapipe the GPU is the same cores, idle a frame's time). *Isolated*: the frames back to back with no GPU work in flight (command buffers dropped unsubmitted). The host's binding (`TargetLimits::default`) has no GPU timestamps; *with timestamps* is the lab's binding (two timestamp writes a pass, resolved and copied every frame). *Floor*: bare wgpu recording as many render passes (each clearing a 256^2 target, with timestamps where sshc's have them) and one 256-byte `write_buffer`, in the same conditions, alternating with sshc's frames. GPU ms: the lab's binding.\n\n| technique | scene | passes recorded | cold µs | cold floor µs | cold / floor | isolated µs | isolated floor µs | isolated / floor | with GPU timestamps: passes recorded | with timestamps: isolated µs | isolated floor with timestamps µs | with timestamps: isolated / floor | four lights: passes recorded | four lights: isolated µs | eight lights: passes recorded | eight lights: isolated µs | cold wall µs, 90th percentile | cold `prepare` / `record` wall µs | on host geometry, cold wall µs | host geometry, light placed by sshc, cold wall µs | GPU ms moving | GPU ms static | moving / static | wall ms moving | wall ms static | moving / static |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
        gpu.describe()
    );
    for t in &names {
        let c = support::compile_source(t, &support::technique_source(t), &[], &[]);
        let sc = if sshc_lab::bind::graph_samples(&c.graph) > 0 {
            "linear"
        } else {
            "triangle"
        };
        let mut base = Scene::load(root().join("scenes").join(format!("{sc}.ron"))).unwrap();
        base.set_camera_size(camera, camera);
        base.shadow_map = shadow;
        // the states of the orbit, computed before any timing (the lab's light fit is not
        // sshc's per-frame cost)
        let states: Vec<SceneInputs> = (0..frames + 10)
            .map(|f| sshc_lab::bind::scene_inputs_for(&at_frame(&base, f), &c.graph).unwrap())
            .collect();
        let views: Vec<_> = states.iter().map(|s| (s.camera(), s.light_inputs())).collect();
        // the lab's binding times every pass on the GPU; a host's (`TargetLimits::default`)
        // does not: the CPU columns are the host's, the GPU columns the lab's
        let lab = Loaded::new(gpu, c.graph.clone(), c.shaders.clone()).unwrap_or_else(|e| panic!("{t}: {e}"));
        let host = Loaded {
            limits: TargetLimits::default(),
            ..lab.clone()
        };
        let mut ex = host.bind_scene(&states[0]).unwrap();
        let mut timed = lab.bind_scene(&states[0]).unwrap();
        let (mut cpu, mut thread) = (Vec::new(), Vec::new());
        let (mut prepare_us, mut record_us) = (Vec::new(), Vec::new());
        let (mut moving, mut still) = (Vec::new(), Vec::new());
        let mut last: Option<u64> = None;
        let (mut wall_moving, mut wall_still) = (Vec::new(), Vec::new());
        let passes = ex.targets.recorded_passes();
        let mut floor_cold = Vec::new();
        for (f, (cam, light)) in views.iter().enumerate() {
            let move_this = f % 2 == 0;
            if !move_this {
                // bare wgpu's floor for as many passes, in the same conditions: just after
                // waiting for a frame of this technique (its clears waited for, untimed)
                let (us, encoder) = floor.record(passes, false);
                gpu.queue.submit([encoder.finish()]);
                gpu.wait().unwrap();
                if f >= 10 {
                    floor_cold.push(us);
                }
            }
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            let c0 = thread_cpu_us();
            let t0 = Instant::now();
            if move_this {
                ex.state.camera = *cam;
                ex.state.lights[0].clone_from(light);
            }
            let tp = Instant::now();
            ex.targets.prepare(&mut ex.scene, &ex.state).unwrap();
            let prepared = tp.elapsed().as_secs_f64() * 1e6;
            let tr = Instant::now();
            ex.targets.record(&ex.scene, &mut encoder).unwrap();
            let recorded = tr.elapsed().as_secs_f64() * 1e6;
            let dt = t0.elapsed().as_secs_f64() * 1e6;
            let dc = thread_cpu_us() - c0;
            let t1 = Instant::now();
            gpu.queue.submit([encoder.finish()]);
            gpu.wait().unwrap();
            let wall = t1.elapsed().as_secs_f64() * 1e3;
            if f >= 10 {
                if move_this {
                    cpu.push(dt);
                    thread.push(dc);
                    prepare_us.push(prepared);
                    record_us.push(recorded);
                    wall_moving.push(wall);
                } else {
                    wall_still.push(wall);
                }
            }
        }
        // The GPU time of the same frames on the lab's binding (timestamps on), moving and
        // still alternating, each submitted and waited for; the newest frame's times read
        // through the ring (each counted once).
        for (f, (cam, light)) in views.iter().enumerate() {
            if f % 2 == 0 {
                timed.state.camera = *cam;
                timed.state.lights[0].clone_from(light);
            }
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            timed.targets.prepare(&mut timed.scene, &timed.state).unwrap();
            timed.targets.record(&timed.scene, &mut encoder).unwrap();
            gpu.queue.submit([encoder.finish()]);
            gpu.wait().unwrap();
            if let Some((n, times)) = timed.targets.frame_times().unwrap()
                && last.is_none_or(|l| n > l)
            {
                last = Some(n);
                if let (true, Some(ms)) = (n >= 10, times.lights[0]) {
                    if n % 2 == 0 { moving.push(ms) } else { still.push(ms) }
                }
            }
        }
        // Isolated: the same frames' prepare + record with no GPU work in flight, their
        // command buffers dropped unsubmitted (an empty submission applies the writes and
        // runs the timestamp ring's callbacks): sshc's and wgpu's own code, warm; and bare
        // wgpu's floor for as many passes, alternating with it.
        // The same with the lab's timestamps, beside a floor with them, alternating too.
        let (mut isolated, mut floor_isolated) = (Vec::new(), Vec::new());
        let (mut isolated_timed, mut floor_timed) = (Vec::new(), Vec::new());
        let timed_passes = timed.targets.recorded_passes();
        for (f, (cam, light)) in views.iter().enumerate() {
            for (b, is_timed) in [(&mut ex, false), (&mut timed, true)] {
                let mut encoder = gpu.device.create_command_encoder(&Default::default());
                let c0 = thread_cpu_us();
                if f % 2 == 0 {
                    b.state.camera = *cam;
                    b.state.lights[0].clone_from(light);
                }
                b.targets.prepare(&mut b.scene, &b.state).unwrap();
                b.targets.record(&b.scene, &mut encoder).unwrap();
                let dc = thread_cpu_us() - c0;
                drop(encoder.finish());
                gpu.queue.submit([]);
                let (floor_us, encoder) = floor.record(if is_timed { timed_passes } else { passes }, is_timed);
                drop(encoder.finish());
                gpu.queue.submit([]);
                if f >= 10 {
                    let (sshc, bare) = if is_timed {
                        (&mut isolated_timed, &mut floor_timed)
                    } else {
                        (&mut isolated, &mut floor_isolated)
                    };
                    sshc.push(dc);
                    bare.push(floor_us);
                }
            }
        }
        gpu.wait().unwrap();
        // Four and eight lights on one set of targets, isolated as above: every light moved
        // every other frame (each a view of the orbit a frame apart), the camera with them
        let mut many = Vec::new();
        for n in [4, 8] {
            let mut b = host
                .bind_lights(&vec![states[0].clone(); n])
                .unwrap_or_else(|e| panic!("{t}, {n} lights: {e}"));
            let mut isolated = Vec::new();
            for f in 0..views.len() {
                let mut encoder = gpu.device.create_command_encoder(&Default::default());
                let c0 = thread_cpu_us();
                if f % 2 == 0 {
                    b.state.camera = views[f].0;
                    for (k, light) in b.state.lights.iter_mut().enumerate() {
                        light.clone_from(&views[(f + k) % views.len()].1);
                    }
                }
                b.targets.prepare(&mut b.scene, &b.state).unwrap();
                b.targets.record(&b.scene, &mut encoder).unwrap();
                let dc = thread_cpu_us() - c0;
                drop(encoder.finish());
                gpu.queue.submit([]);
                if f >= 10 {
                    isolated.push(dc);
                }
            }
            gpu.wait().unwrap();
            many.push((b.targets.recorded_passes(), median(&mut isolated)));
        }
        let [(passes4, iso4), (passes8, iso8)] = [many[0], many[1]];
        drop(timed);
        let (gm, gs) = (median(&mut moving), median(&mut still));
        let (wm, ws) = (median(&mut wall_moving), median(&mut wall_still));
        let lights: Vec<Light> = (0..frames + 10).map(|f| at_frame(&base, f).lights.remove(0)).collect();
        let (hosted, placed) = host_geometry_cpu(&c, &views, &lights, &states[0])
            .map_or(("refused (Geometry passes)".to_string(), "refused".to_string()), |(us, placed)| {
                (format!("{us:.1}"), format!("{placed:.1}"))
            });
        let (cold, floor_c) = (median(&mut thread), median(&mut floor_cold));
        let (iso, floor_i) = (median(&mut isolated), median(&mut floor_isolated));
        let (iso_t, floor_t) = (median(&mut isolated_timed), median(&mut floor_timed));
        let row = format!(
            "| {t} | {sc} | {passes} | {cold:.1} | {floor_c:.1} | {:.2} | {iso:.1} | {floor_i:.1} | {:.2} | {timed_passes} | {iso_t:.1} | {floor_t:.1} | {:.2} | {passes4} | {iso4:.1} | {passes8} | {iso8:.1} | {:.1} | {:.1} / {:.1} | {hosted} | {placed} | {gm:.3} | {gs:.3} | {:.3} | {wm:.3} | {ws:.3} | {:.3} |\n",
            cold / floor_c,
            iso / floor_i,
            iso_t / floor_t,
            percentile(&mut cpu, 0.9),
            median(&mut prepare_us),
            median(&mut record_us),
            gm / gs,
            wm / ws
        );
        print!("{row}");
        table.push_str(&row);
    }
    // `SSHC_BYTES=0`: without the bytes table (minutes and gigabytes: 273 bunnies), so
    // that a profile of the bench is a profile of the frame loop
    if env("SSHC_BYTES", 1) != 0 {
        table.push_str(&bytes_table());
    }
    let dir = root().join("target").join("embedding");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("frame-cost.md"), &table).unwrap();
    println!("\n{table}");
}

/// The median CPU µs of the state changed + `prepare` + `record` over the same orbit with
/// the scene uploaded as host geometry (its soup welded into indexed meshes, one instance
/// each), and with the light's view fitted by sshc to the instances' boxes
/// (`Targets::fit_light`); `None` for a graph with Geometry passes (refused on that
/// path).
fn host_geometry_cpu(
    c: &sshc::Compiled,
    views: &[(sshc_runtime::gpu::Camera, sshc_runtime::gpu::LightInputs)],
    lights: &[Light],
    s: &SceneInputs,
) -> Option<(f64, f64)> {
    let gpu = gpu();
    let mut g = support::host::geometry_of(s, [0.0; 3]);
    g.instances.pop(); // the turned copy
    let mut loaded = Loaded::new(gpu, c.graph.clone(), c.shaders.clone()).unwrap();
    loaded.limits = TargetLimits::default(); // a host's binding: no GPU timestamps
    let mut ex = loaded
        .bind_geometry(&g, &s.camera(), &[s.light_inputs()], s.camera_size, s.shadow_size)
        .ok()?;
    let (mut cpu, mut placed) = (Vec::new(), Vec::new());
    for (f, ((cam, light), shape)) in views.iter().zip(lights).enumerate() {
        for place in [false, true] {
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            let t0 = Instant::now();
            ex.state.camera = *cam;
            if place {
                ex.place_light(0, shape, Fit::Casters).unwrap();
            } else {
                ex.state.lights[0].clone_from(light);
            }
            ex.encode(&mut encoder).unwrap();
            let dt = t0.elapsed().as_secs_f64() * 1e6;
            gpu.queue.submit([encoder.finish()]);
            gpu.wait().unwrap();
            ex.targets.frame_times().unwrap();
            if f >= 10 {
                if place { &mut placed } else { &mut cpu }.push(dt);
            }
        }
    }
    Some((median(&mut cpu), median(&mut placed)))
}

/// Buffer bytes a binding allocates (wgpu's `buffer_memory` counter, before and after, the
/// uploads' staging memory freed),
/// for a triangle soup against the same triangles as indexed, instanced host geometry: the
/// bundled bunny on its floor, and the bunny instanced on a grid to at least 1 M triangles.
fn bytes_table() -> String {
    use sshc_runtime::gpu::{IDENTITY, Instance};
    let gpu = gpu();
    let c = support::compile_source("hard", &support::technique_source("hard"), &[], &[]);
    let mut base = Scene::load(root().join("scenes").join("bunny.ron")).unwrap();
    base.set_camera_size(64, 64);
    base.shadow_map = 64;
    let s = sshc_lab::bind::scene_inputs_for(&base, &c.graph).unwrap();
    // what stays allocated: the uploads' staging buffers are submitted and freed first
    let memory = || {
        gpu.queue.submit([]);
        gpu.wait().unwrap();
        gpu.device.get_internal_counters().hal.buffer_memory.read()
    };
    let mut out = String::from(
        "\n| geometry | triangles | soup buffer bytes | per triangle | indexed + instanced buffer bytes | per triangle | the same, identity instances in world space | per triangle | host (CPU) bytes, soup | host bytes, indexed |\n|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for copies in [1usize, 273] {
        let mut g = support::host::geometry_of(&s, [0.0; 3]);
        g.instances.pop(); // the turned copy
        // the bunny: the mesh of most triangles
        let bunny = (0..g.instances.len())
            .max_by_key(|&i| g.meshes[g.instances[i].mesh].indices.len())
            .unwrap();
        for k in 1..copies {
            let (x, z) = ((k % 17) as f32 * 0.25 - 2.0, (k / 17) as f32 * 0.25 - 2.0);
            let mut t = IDENTITY;
            (t[12], t[14]) = (x, z);
            g.instances.push(Instance {
                name: format!("bunny {k}"),
                mesh: g.instances[bunny].mesh,
                transform: t,
                casts: true,
                receives: true,
                moves: true,
            });
        }
        let soup = support::host::listed_out(&s, &g);
        let loaded = Loaded::new(gpu, c.graph.clone(), c.shaders.clone()).unwrap();
        let m0 = memory();
        let ex = loaded.bind_scene(&soup).unwrap();
        let soup_bytes = memory() - m0;
        drop(ex);
        gpu.wait().unwrap();
        let m0 = memory();
        let ex = loaded
            .bind_geometry(&g, &s.camera(), &[s.light_inputs()], s.camera_size, s.shadow_size)
            .unwrap();
        let indexed_bytes = memory() - m0;
        drop(ex);
        gpu.wait().unwrap();
        // the instances under the identity (the first bunny, the floor) kept still: drawn
        // from their meshes, with no placed copy
        let mut still = g.clone();
        for i in still.instances.iter_mut().filter(|i| i.transform == IDENTITY) {
            i.moves = false;
        }
        let m0 = memory();
        let ex = loaded
            .bind_geometry(&still, &s.camera(), &[s.light_inputs()], s.camera_size, s.shadow_size)
            .unwrap();
        let still_bytes = memory() - m0;
        drop(ex);
        let tris = g.triangles();
        let host_indexed: usize =
            g.meshes.iter().map(|m| m.positions.len() * 24 + m.indices.len() * 4).sum::<usize>() + g.instances.len() * 64;
        out.push_str(&format!(
            "| bunny x {copies} + floor | {tris} | {soup_bytes} | {:.1} | {indexed_bytes} | {:.1} | {still_bytes} | {:.1} | {} | {host_indexed} |\n",
            soup_bytes as f64 / tris as f64,
            indexed_bytes as f64 / tris as f64,
            still_bytes as f64 / tris as f64,
            soup.vertices.len() * 4,
        ));
    }
    out
}

/// What bare wgpu costs the host, as the floor under sshc's per-frame CPU: an encoder
/// recording `k` render passes that only clear one 256^2 `Rgba8Unorm` target (each with a
/// pair of timestamp writes when sshc's passes have them) after one 256-byte
/// `Queue::write_buffer` (a `Frame` uniform's write).
struct Floor {
    view: wgpu::TextureView,
    queries: Option<wgpu::QuerySet>,
    uniform: wgpu::Buffer,
}

impl Floor {
    fn new() -> Floor {
        let gpu = gpu();
        let device = &gpu.device;
        let target = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("floor target"),
            size: wgpu::Extent3d {
                width: 256,
                height: 256,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba8Unorm,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        });
        let timed = gpu.features.contains(wgpu::Features::TIMESTAMP_QUERY);
        Floor {
            view: target.create_view(&Default::default()),
            queries: timed.then(|| {
                device.create_query_set(&wgpu::QuerySetDescriptor {
                    label: Some("floor times"),
                    ty: wgpu::QueryType::Timestamp,
                    count: 2,
                })
            }),
            uniform: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("floor uniform"),
                size: 256,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
        }
    }

    /// The host thread's CPU µs of one write and `passes` passes (each with a pair of
    /// timestamp writes when `timed`), and the encoder (the caller submits or drops it).
    fn record(&self, passes: usize, timed: bool) -> (f64, wgpu::CommandEncoder) {
        let gpu = gpu();
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        let c0 = thread_cpu_us();
        gpu.queue.write_buffer(&self.uniform, 0, &[0u8; 256]);
        for _ in 0..passes {
            let _pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("floor"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &self.view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::WHITE),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: self.queries.as_ref().filter(|_| timed).map(|q| wgpu::RenderPassTimestampWrites {
                    query_set: q,
                    beginning_of_pass_write_index: Some(0),
                    end_of_pass_write_index: Some(1),
                }),
                occlusion_query_set: None,
                multiview_mask: None,
            });
        }
        (thread_cpu_us() - c0, encoder)
    }
}
