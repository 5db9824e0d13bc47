//! Issue 49: a frame allocates nothing on the CPU heap in sshc's own code. Every bundled
//! technique on host geometry (a box over a ground) runs a few frames to reach its steady
//! state, then for two frames the host's whole per-frame call sequence is counted:
//! `set_transforms`, `set_camera`, `set_light` (or `place_light`, the light fitted by sshc,
//! for lights without sample views: a fit of sample views builds their chain in vectors),
//! `prepare` and `record`. A counting global allocator takes a backtrace at each allocation
//! and gives it to the innermost frame outside the standard library and the allocator
//! itself: sshc-runtime's must be none. wgpu's own (its command recording, its staging
//! writes, the boxed map callbacks) are counted apart and printed, not asserted: they are
//! wgpu's, and no host can avoid them.

use sshc_runtime::gpu::{Camera, Fit, FrameState, Geometry, Gpu, IDENTITY, Instance, LightInputs, Mesh, Scene, Sizes, Targets, Technique};
use sshc_runtime::graph::ValidGraph;
use sshc_runtime::light::Light;
use sshc_runtime::light::glam::Vec3;
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicUsize, Ordering};

struct Counting;

thread_local! {
    /// Counting on this thread (the test's), and inside the allocator's own bookkeeping
    /// (a backtrace allocates: those allocations pass through uncounted).
    static COUNTING: Cell<bool> = const { Cell::new(false) };
    static INSIDE: Cell<bool> = const { Cell::new(false) };
}

static SSHC: AtomicUsize = AtomicUsize::new(0);
static OTHERS: AtomicUsize = AtomicUsize::new(0);
static FIRST_SSHC: std::sync::Mutex<Option<String>> = std::sync::Mutex::new(None);

/// The owner of an allocation: the innermost frame of the backtrace outside the standard
/// library, this file (the allocator) and hashbrown (the standard `HashMap`'s). A frame
/// with a source file is judged by it (inlined frames carry short names, and a
/// dependency's code inlined into sshc's carries its registry path); dependencies are
/// built without debug information (the workspace's `Cargo.toml`), so a frame without a
/// file is a dependency's unless its name is the standard library's. `true` for sshc's own
/// source (the workspace's, outside cargo's registry), with the frame.
fn owner(trace: &str) -> (bool, String) {
    // each frame: its name, then the file its `at` line gives, if any
    let mut frames: Vec<(String, Option<String>)> = Vec::new();
    for line in trace.lines().map(str::trim_start) {
        if let Some(file) = line.strip_prefix("at ") {
            if let Some(f) = frames.last_mut() {
                f.1.get_or_insert_with(|| file.to_string());
            }
        } else if let Some((n, name)) = line.split_once(": ")
            && n.chars().all(|c| c.is_ascii_digit())
        {
            frames.push((name.to_string(), None));
        }
    }
    let standard = |name: &str| {
        let name = name.trim_start_matches('<');
        ["std::", "core::", "alloc::", "__rustc::", "hashbrown::", "allocations::"]
            .iter()
            .any(|p| name.starts_with(p))
    };
    for (name, file) in frames {
        match file {
            Some(file) if file.contains("/rustc/") || file.contains("tests/allocations.rs") || file.contains("/hashbrown-") => {}
            Some(file) => return (!file.contains(".cargo/registry"), file),
            None if standard(&name) => {}
            None => return (false, name),
        }
    }
    (false, "unknown".into())
}

fn count() {
    if !COUNTING.with(Cell::get) || INSIDE.with(Cell::get) {
        return;
    }
    INSIDE.with(|i| i.set(true));
    let trace = std::backtrace::Backtrace::force_capture().to_string();
    if owner(&trace).0 {
        SSHC.fetch_add(1, Ordering::Relaxed);
        if let Ok(mut f) = FIRST_SSHC.lock()
            && f.is_none()
        {
            *f = Some(trace);
        }
    } else {
        OTHERS.fetch_add(1, Ordering::Relaxed);
    }
    INSIDE.with(|i| i.set(false));
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        count();
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count();
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// A box of half-size `h` standing on y = 0, 12 triangles.
fn box_mesh(h: f32) -> Mesh {
    let mut m = Mesh {
        name: "box".into(),
        ..Default::default()
    };
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let n = Vec3::from_array(std::array::from_fn(|i| if i == axis { sign } else { 0.0 }));
            let (u, v) = n.any_orthonormal_pair();
            let (u, v) = (u * h, v * h);
            let c = n * h + Vec3::new(0.0, h, 0.0);
            let base = m.positions.len() as u32;
            for p in [c - u - v, c + u - v, c + u + v, c - u + v] {
                m.positions.push(p.to_array());
                m.normals.push(n.to_array());
            }
            let quad = if u.cross(v).dot(n) > 0.0 {
                [0, 1, 2, 0, 2, 3]
            } else {
                [0, 2, 1, 0, 3, 2]
            };
            m.indices.extend(quad.map(|i| base + i));
        }
    }
    m
}

fn geometry() -> Geometry {
    let ground = Mesh {
        name: "ground".into(),
        positions: vec![[-3.0, 0.0, -3.0], [3.0, 0.0, -3.0], [3.0, 0.0, 3.0], [-3.0, 0.0, 3.0]],
        normals: vec![[0.0, 1.0, 0.0]; 4],
        indices: vec![0, 2, 1, 0, 3, 2],
    };
    let instance = |name: &str, mesh: usize, casts: bool, moves: bool| Instance {
        name: name.into(),
        mesh,
        transform: IDENTITY,
        casts,
        receives: true,
        moves,
    };
    Geometry {
        meshes: vec![box_mesh(0.5), ground],
        instances: vec![instance("box", 0, true, true), instance("ground", 1, false, false)],
    }
}

fn camera(f: u32) -> Camera {
    let eye = Vec3::new(0.3 * f as f32, 5.0, 5.0);
    let m = sshc_runtime::light::perspective(0.9, 1.0, 0.1, 100.0) * sshc_runtime::light::look_at(eye, Vec3::ZERO, Vec3::Y);
    Camera {
        view_proj: m.to_cols_array(),
        position: eye.to_array(),
    }
}

#[test]
fn a_frame_allocates_nothing_in_sshc_on_every_bundled_technique() {
    // A `Backtrace::capture` inside the counted calls (enabled when the suite sets
    // `RUST_BACKTRACE`) would hold the standard library's backtrace lock while it
    // allocates, and the count's own capture would wait on it forever: library captures
    // are turned off before anything runs (the one test of this binary; panics keep their
    // backtraces, which `RUST_BACKTRACE` still governs).
    // SAFETY: no other thread of this process runs yet.
    unsafe { std::env::set_var("RUST_LIB_BACKTRACE", "0") };
    let gpu = Gpu::new().unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}"));
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../techniques");
    let mut names: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok()?.path().file_stem()?.to_str().map(String::from))
        .filter(|n| dir.join(format!("{n}.ron")).is_file())
        .collect();
    names.sort();
    assert!(names.len() >= 15, "{names:?}");
    let mut report = Vec::new();
    for t in &names {
        let src = std::fs::read_to_string(dir.join(format!("{t}.ron"))).unwrap();
        let c = sshc::compile_str(&src, &Default::default()).unwrap_or_else(|d| panic!("{}", d.render(t, &src)));
        let samples = c.graph.passes.iter().any(|p| p.views == sshc_runtime::graph::Views::PerLightSample);
        let (light, n) = if samples {
            let n = c.graph.samples;
            (
                Light::Segment {
                    a: Vec3::new(0.8, 3.0, 0.3),
                    b: Vec3::new(1.8, 3.0, 0.6),
                },
                n,
            )
        } else {
            (
                Light::Sphere {
                    center: Vec3::new(1.5, 3.0, 0.5),
                    radius: 0.3,
                },
                0,
            )
        };
        let mut g = geometry();
        let technique =
            Technique::new(&gpu, ValidGraph::try_from(c.graph.clone()).unwrap(), c.shaders.clone()).unwrap_or_else(|e| panic!("{t}: {e}"));
        let first = LightInputs::fit(&light, &g.boxes(), Fit::Casters, 128, n).unwrap();
        let mut scene = Scene::upload(&gpu, &g, &[&technique]).unwrap_or_else(|e| panic!("{t}: {e}"));
        let mut state = FrameState::new(&technique, camera(0), vec![first]);
        let sizes = Sizes {
            camera: (48, 48),
            shadow: 128,
        };
        let mut targets = Targets::new(&technique, &scene, &state, sizes).unwrap_or_else(|e| panic!("{t}: {e}"));
        let mut counted = (0, 0);
        for f in 1..=6 {
            g.instances[0].transform[12] = 0.05 * f as f32;
            let transforms: Vec<[f32; 16]> = g.instances.iter().map(|i| i.transform).collect();
            let moved = LightInputs::fit(&light, &g.boxes(), Fit::Casters, 128, n).unwrap();
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            // the first frames reach the steady state (the vectors kept from frame to
            // frame reach their sizes); the last two are counted
            let counting = f > 4;
            let (s0, o0) = (SSHC.load(Ordering::Relaxed), OTHERS.load(Ordering::Relaxed));
            COUNTING.with(|c| c.set(counting));
            scene.set_transforms(&transforms).unwrap();
            state.camera = camera(f);
            // sshc's fit of a light with sample views builds the sample chain (vectors):
            // those lights are fitted outside the count and set
            if f % 2 == 0 || n > 0 {
                state.lights[0] = moved;
            } else {
                state.lights[0] = targets.fit_light(&scene, 0, &light, Fit::Casters).unwrap();
            }
            targets.prepare(&mut scene, &state).unwrap();
            targets.record(&scene, &mut encoder).unwrap();
            COUNTING.with(|c| c.set(false));
            if counting {
                counted.0 += SSHC.load(Ordering::Relaxed) - s0;
                counted.1 += OTHERS.load(Ordering::Relaxed) - o0;
            }
            gpu.queue.submit([encoder.finish()]);
            gpu.wait().unwrap();
        }
        let first = FIRST_SSHC.lock().unwrap().take();
        assert_eq!(
            counted.0,
            0,
            "{t}: sshc allocated {} time(s) in two frames; the first:\n{}",
            counted.0,
            first.unwrap_or_default()
        );
        report.push(format!("{t}: {} by wgpu a frame", counted.1 / 2));
    }
    eprintln!(
        "allocations per frame outside sshc (wgpu's recording and writes):\n{}",
        report.join("\n")
    );
}
