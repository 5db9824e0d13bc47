//! The runtime as a host renderer uses it: the host's device, per-frame camera
//! and light updates that allocate nothing, recording into the host's encoder, the
//! visibility sampled as a texture, and the refusal of a device that lacks what a graph
//! needs. Every comparison of visibilities here is bit for bit: the in-place path and a
//! fresh binding run the same shaders on the same uniforms, so the arithmetic is the same.

mod support;

use sshc_lab::run::{Bound, Loaded};
use sshc_lab::scene::Scene;
use sshc_runtime::gpu::{CameraOutput, Geometry, Gpu, Requirements, RuntimeError, SceneInputs};
use support::host::{at_frame, geometry_of, listed_out};
use support::{gpu, root};

fn compile(technique: &str) -> sshc::Compiled {
    support::compile_source(technique, &support::technique_source(technique), &[], &[])
}

fn scene(name: &str, size: u32, shadow: u32) -> Scene {
    let mut s = Scene::load(root().join("scenes").join(format!("{name}.ron"))).unwrap_or_else(|e| panic!("{name}: {e}"));
    s.set_camera_size(size, size);
    s.shadow_map = shadow;
    s
}

/// The bundled techniques, by name, sorted.
fn techniques() -> Vec<String> {
    support::bundled("techniques")
}

fn inputs(s: &Scene, c: &sshc::Compiled) -> SceneInputs {
    sshc_lab::bind::scene_inputs_for(s, &c.graph).unwrap_or_else(|e| panic!("{e}"))
}

/// Every light of the scene as its own inputs (what `bind_lights` takes).
fn all_lights(s: &Scene, c: &sshc::Compiled) -> Vec<SceneInputs> {
    (0..s.lights.len())
        .map(|l| {
            let mut one = s.clone();
            one.lights = vec![s.lights[l].clone()];
            inputs(&one, c)
        })
        .collect()
}

/// The visibility of a freshly loaded and bound executor for these lights.
fn fresh(c: &sshc::Compiled, lights: &[SceneInputs]) -> Vec<[f32; 4]> {
    let ex = Loaded::new(gpu(), c.graph.clone(), c.shaders.clone()).unwrap_or_else(|e| panic!("{e}"));
    let mut ex = ex.bind_lights(lights).unwrap_or_else(|e| panic!("{e}"));
    ex.run_frame().unwrap_or_else(|e| panic!("{e}"));
    ex.inspect().read_visibilities().unwrap_or_else(|e| panic!("{e}")).rgba
}

/// Set every light and the camera of `ex` to these inputs (the per-frame path).
fn update(ex: &mut Bound, lights: &[SceneInputs]) {
    ex.state.camera = lights[0].camera();
    for (l, s) in lights.iter().enumerate() {
        ex.state.lights[l] = s.light_inputs();
    }
}

/// wgpu's live object counts (its `counters` feature), the command encoders left out
/// (the host makes one a frame).
fn live_objects(gpu: &Gpu) -> [(&'static str, isize); 11] {
    let c = gpu.device.get_internal_counters().hal;
    [
        ("buffers", c.buffers.read()),
        ("textures", c.textures.read()),
        ("texture views", c.texture_views.read()),
        ("bind groups", c.bind_groups.read()),
        ("bind group layouts", c.bind_group_layouts.read()),
        ("render pipelines", c.render_pipelines.read()),
        ("compute pipelines", c.compute_pipelines.read()),
        ("pipeline layouts", c.pipeline_layouts.read()),
        ("samplers", c.samplers.read()),
        ("shader modules", c.shader_modules.read()),
        ("query sets", c.query_sets.read()),
    ]
}

/// One frame as a host runs it: its encoder, `encode`, its submission, then a wait.
fn host_frame(ex: &mut Bound) {
    let gpu = gpu();
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    ex.encode(&mut encoder).unwrap_or_else(|e| panic!("{}: {e}", ex.graph().technique));
    gpu.queue.submit([encoder.finish()]);
    gpu.wait().unwrap_or_else(|e| panic!("{e}"));
}

/// A scene each technique runs on: its light samples need a segment light.
fn scene_for(c: &sshc::Compiled) -> &'static str {
    if sshc_lab::bind::graph_samples(&c.graph) > 0 {
        "linear"
    } else {
        "triangle"
    }
}

#[test]
fn every_bundled_technique_updated_in_place_matches_a_fresh_binding() {
    let names = techniques();
    assert!(names.len() >= 15, "{names:?}");
    for t in &names {
        let c = compile(t);
        let base = scene(scene_for(&c), 32, 64);
        let ex = Loaded::new(gpu(), c.graph.clone(), c.shaders.clone()).unwrap_or_else(|e| panic!("{e}"));
        let mut ex = ex.bind_scene(&inputs(&base, &c)).unwrap_or_else(|e| panic!("{t}: {e}"));
        let generation = ex.targets.generation();
        for f in 1..=2 {
            let now = [inputs(&at_frame(&base, f), &c)];
            update(&mut ex, &now);
            ex.run_frame().unwrap_or_else(|e| panic!("{t}: {e}"));
            let moved = ex.inspect().read_visibilities().unwrap_or_else(|e| panic!("{t}: {e}")).rgba;
            assert!(
                moved == fresh(&c, &now),
                "{t}, frame {f}: the updated executor differs from a fresh binding"
            );
        }
        assert_eq!(ex.targets.generation(), generation, "{t}: updates reallocated");
    }
}

#[test]
fn a_hundred_moving_frames_create_no_wgpu_object_and_match_fresh_bindings() {
    // a raster technique, a Geometry one, a per-sample one and three lights at once
    for (t, sc) in [
        ("pcss", "triangle"),
        ("penumbra-limit-maps", "triangle"),
        ("linear-light", "linear"),
        ("pcf", "three-lights"),
    ] {
        let c = compile(t);
        let base = scene(sc, 32, 64);
        let gpu = gpu();
        let ex = Loaded::new(gpu, c.graph.clone(), c.shaders.clone()).unwrap_or_else(|e| panic!("{e}"));
        let mut ex = ex.bind_lights(&all_lights(&base, &c)).unwrap_or_else(|e| panic!("{t}: {e}"));
        let generation = ex.targets.generation();
        host_frame(&mut ex);
        let before = live_objects(gpu);
        let mut checked = Vec::new();
        for f in 1..=100 {
            let now = all_lights(&at_frame(&base, f), &c);
            update(&mut ex, &now);
            host_frame(&mut ex);
            // read after each frame completes, before any read-back of this frame
            assert_eq!(live_objects(gpu), before, "{t}: frame {f} created or destroyed wgpu objects");
            if [25, 50, 100].contains(&f) {
                checked.push((now, ex.inspect().read_visibilities().unwrap_or_else(|e| panic!("{t}: {e}")).rgba));
            }
        }
        assert_eq!(ex.targets.generation(), generation, "{t}: updates reallocated");
        assert_eq!(ex.targets.frames(), 101);
        // the orbit moves the shadows: the checked frames differ from each other
        assert!(
            checked[0].1 != checked[1].1 && checked[1].1 != checked[2].1,
            "{t}: the shadows did not move"
        );
        for (now, moved) in &checked {
            assert!(
                *moved == fresh(&c, now),
                "{t}: a moving frame differs from a fresh binding of its state"
            );
        }
    }
}

#[test]
fn timestamps_come_back_frames_later_without_a_wait_in_recording() {
    let c = compile("pcss");
    let s = inputs(&scene("triangle", 32, 64), &c);
    let gpu = gpu();
    let ex = Loaded::new(gpu, c.graph.clone(), c.shaders.clone()).unwrap_or_else(|e| panic!("{e}"));
    let mut ex = ex.bind_scene(&s).unwrap();
    for _ in 0..5 {
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        ex.encode(&mut encoder).unwrap();
        gpu.queue.submit([encoder.finish()]);
    }
    gpu.wait().unwrap();
    // the last frame's slot is mapped by this call and read by the next, after the device
    // has answered; no call waited
    ex.targets.frame_times().unwrap();
    gpu.wait().unwrap();
    let (frame, times) = ex.targets.frame_times().unwrap().expect("lavapipe has timestamp queries");
    assert_eq!(frame, 4, "the newest frame's times");
    assert_eq!(times.passes.len(), c.graph.passes.len());
    for (pass, ms) in &times.passes {
        assert!(ms.is_some_and(|ms| ms >= 0.0), "pass `{pass}`: {ms:?}");
    }
}

/// A host's own device and queue, from its own instance, with its own error handler
/// (which counts the errors it sees) and what `req` asks for.
fn host_device(
    features: wgpu::Features,
    limits: impl Fn(&wgpu::Adapter) -> wgpu::Limits,
) -> (Gpu, std::sync::Arc<std::sync::atomic::AtomicUsize>) {
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
        backends: wgpu::Backends::VULKAN,
        ..wgpu::InstanceDescriptor::new_without_display_handle()
    });
    let adapter = pollster::block_on(instance.request_adapter(&Default::default())).expect("an adapter (lavapipe)");
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("host"),
        required_features: features & adapter.features(),
        required_limits: limits(&adapter),
        ..Default::default()
    }))
    .unwrap();
    let seen = std::sync::Arc::new(std::sync::atomic::AtomicUsize::new(0));
    let count = seen.clone();
    device.on_uncaptured_error(std::sync::Arc::new(move |_: wgpu::Error| {
        count.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
    }));
    (Gpu::from_host(&adapter, device, queue), seen)
}

/// The host's own pass: a compute shader that loads the visibility texture and stores it
/// in a buffer, read back.
fn host_samples(gpu: &Gpu, visibility: &wgpu::Texture) -> Vec<f32> {
    let device = &gpu.device;
    let (w, h) = (visibility.width(), visibility.height());
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("host lighting"),
        source: wgpu::ShaderSource::Wgsl(
            "@group(0) @binding(0) var vis: texture_2d<f32>;
@group(0) @binding(1) var<storage, read_write> out: array<f32>;
@compute @workgroup_size(8, 8) fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(vis);
    if id.x < size.x && id.y < size.y { out[id.y * size.x + id.x] = textureLoad(vis, id.xy, 0).r; }
}"
            .into(),
        ),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: None,
        layout: None,
        module: &module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
    let bytes = (w * h * 4) as u64;
    let out = device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: bytes,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let read = device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: bytes,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let view = visibility.create_view(&Default::default());
    let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::TextureView(&view),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: out.as_entire_binding(),
            },
        ],
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(w.div_ceil(8), h.div_ceil(8), 1);
    }
    encoder.copy_buffer_to_buffer(&out, 0, &read, 0, bytes);
    gpu.queue.submit([encoder.finish()]);
    read.slice(..).map_async(wgpu::MapMode::Read, |_| {});
    gpu.wait().unwrap();
    let data = read.slice(..).get_mapped_range().unwrap();
    data.chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect()
}

#[test]
fn on_a_hosts_device_the_graph_records_into_its_frame_and_its_error_handler_stays() {
    let c = compile("pcss");
    let s = inputs(&scene("triangle", 32, 64), &c);
    let req = Requirements::of(&c.graph);
    let (host, errors) = host_device(req.features() | wgpu::Features::TIMESTAMP_QUERY, |a| req.limits(a.limits()));
    assert!(host.is_host_device());
    let ex = Loaded::new(&host, c.graph.clone(), c.shaders.clone()).unwrap_or_else(|e| panic!("{e}"));
    let mut ex = ex.bind_scene(&s).unwrap_or_else(|e| panic!("{e}"));
    // the host's frame: its encoder, its submission
    let mut encoder = host.device.create_command_encoder(&Default::default());
    ex.encode(&mut encoder).unwrap();
    host.queue.submit([encoder.finish()]);
    host.wait().unwrap();
    let ours = ex.inspect().read_camera(CameraOutput::Visibility).unwrap().channel(0);
    // the same graph on the runtime's own device
    let own = Loaded::new(gpu(), c.graph.clone(), c.shaders.clone()).unwrap();
    let mut own = own.bind_scene(&s).unwrap();
    own.run_frame().unwrap();
    assert!(
        ours == own.inspect().read_camera(CameraOutput::Visibility).unwrap().channel(0),
        "the host's device gives another visibility"
    );
    // the host samples the visibility texture in its own pass
    assert!(
        host_samples(&host, ex.targets.visibility()) == ours,
        "the host's pass reads another visibility"
    );
    assert_eq!(errors.load(std::sync::atomic::Ordering::SeqCst), 0);
    // an error outside any scope reaches the host's handler, not the runtime's
    let _ = host.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("invalid on purpose"),
        size: 4,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::MAP_WRITE,
        mapped_at_creation: false,
    });
    host.wait().unwrap();
    assert_eq!(
        errors.load(std::sync::atomic::Ordering::SeqCst),
        1,
        "the host's handler saw its error"
    );
}

#[test]
fn a_device_without_what_a_graph_needs_is_refused_with_each_need_and_its_pass() {
    // a bare device: no features, WebGPU's default limits
    let (bare, _) = host_device(wgpu::Features::empty(), |_| wgpu::Limits::default());
    let mut refused = 0;
    let mut lines = Vec::new();
    for t in techniques() {
        let c = compile(&t);
        let missing = Requirements::of(&c.graph).missing(&bare);
        match Loaded::new(&bare, c.graph.clone(), c.shaders.clone()) {
            Ok(_) => assert!(missing.is_empty(), "{t} loaded on a device lacking {missing:?}"),
            Err(RuntimeError::Unsatisfied {
                technique,
                missing: listed,
            }) => {
                assert_eq!(technique, c.graph.technique);
                assert_eq!(listed, missing, "{t}");
                assert!(!listed.is_empty());
                // every line names a pass of the graph, or the graph itself
                for l in &listed {
                    assert!(
                        c.graph.passes.iter().any(|p| l.contains(&format!("needed by pass `{}`", p.name)))
                            || l.contains("needed by the graph")
                            || l.contains("needed by the Frame uniform")
                            || l.contains("a raster pass renders texture `"),
                        "{t}: {l}"
                    );
                }
                refused += 1;
                lines.extend(listed);
            }
            Err(e) => panic!("{t}: refused for another reason: {e}"),
        }
    }
    assert!(refused > 0);
    // what the bundled techniques need beyond WebGPU: the camera outputs' 36 bytes a pixel
    // (R32Float 4, Rgba8Unorm 8, Rgba32Float 16, Rgba16Float 8, over the default 32), and
    // filtering of 32-bit float maps
    assert!(
        lines.iter().any(|l| l.contains("max_color_attachment_bytes_per_sample of 36")),
        "{lines:#?}"
    );
    assert!(lines.iter().any(|l| l.contains("FLOAT32_FILTERABLE")), "{lines:#?}");
    // and a device with exactly what the graph asks for runs it
    let c = compile("vsm");
    let req = Requirements::of(&c.graph);
    let (fit, _) = host_device(req.features(), |a| {
        let _ = a;
        req.limits(wgpu::Limits::default())
    });
    Loaded::new(&fit, c.graph.clone(), c.shaders.clone()).unwrap_or_else(|e| panic!("{e}"));
    // issue 49: a host switching among every bundled technique asks for their union once:
    // a device with exactly that loads each of them, and every need is named with its
    // technique
    let all: Vec<sshc::Compiled> = techniques().iter().map(|t| compile(t)).collect();
    let union = Requirements::of_all(all.iter().map(|c| &c.graph));
    for c in &all {
        let own = Requirements::of(&c.graph);
        assert!(union.features().contains(own.features()), "{}", c.graph.technique);
        let base = wgpu::Limits::default();
        let (mine, theirs) = (own.limits(base.clone()), union.limits(base));
        assert!(
            mine.max_color_attachment_bytes_per_sample <= theirs.max_color_attachment_bytes_per_sample
                && mine.max_storage_buffers_per_shader_stage <= theirs.max_storage_buffers_per_shader_stage
                && mine.max_sampled_textures_per_shader_stage <= theirs.max_sampled_textures_per_shader_stage,
            "{}",
            c.graph.technique
        );
    }
    assert!(
        union.features.iter().all(|n| n.who.starts_with("technique `")) && union.limits.iter().all(|n| n.who.starts_with("technique `")),
        "{union:?}"
    );
    let (every, _) = host_device(union.features(), |_| union.limits(wgpu::Limits::default()));
    for c in &all {
        Loaded::new(&every, c.graph.clone(), c.shaders.clone()).unwrap_or_else(|e| panic!("{}: {e}", c.graph.technique));
    }
    // and the bare device is told what each technique lacks, by name
    let missing = union.missing(&bare);
    assert!(missing.iter().any(|l| l.contains("technique `pcss`")), "{missing:#?}");
}

#[test]
fn per_frame_states_refuse_what_would_need_new_targets() {
    let c = compile("pcss");
    let s = inputs(&scene("triangle", 32, 64), &c);
    let loaded = Loaded::new(gpu(), c.graph.clone(), c.shaders.clone()).unwrap();
    // issue 49: a camera of no pixels is said to be so, not "above the device's limit"
    let mut empty = s.clone();
    empty.camera_size = (0, 240);
    let e = loaded.bind_scene(&empty).unwrap_err();
    assert!(
        e.to_string()
            .contains("the camera image is 0 x 240 pixels: it needs at least 1 x 1"),
        "{e}"
    );
    let mut ex = loaded.bind_scene(&s).unwrap();
    ex.run_frame().unwrap();
    // The state is plain data: prepare checks what changed, refuses it with the reason,
    // and writes nothing (the next good frame renders as before).
    let before = ex.inspect().read_visibilities().unwrap().rgba;
    let refused = |ex: &mut sshc_lab::run::Bound, change: &dyn Fn(&mut sshc_runtime::gpu::FrameState)| {
        let good = ex.state.clone();
        change(&mut ex.state);
        let e = ex.run_frame().unwrap_err().to_string();
        ex.state = good;
        e
    };
    // issue 49: an all-zero camera matrix drew every pixel lit; refused
    let e = refused(&mut ex, &|st| st.camera.view_proj = [0.0; 16]);
    assert!(e.contains("has no inverse"), "{e}");
    let e = refused(&mut ex, &|st| st.camera.view_proj[5] = f32::NAN);
    assert!(e.contains("not finite"), "{e}");
    let e = refused(&mut ex, &|st| st.lights[0].position[0] = f32::INFINITY);
    assert!(e.contains("light 0") && e.contains("not finite"), "{e}");
    let e = refused(&mut ex, &|st| st.lights[0].far = st.lights[0].near);
    assert!(e.contains("depth range"), "{e}");
    let e = refused(&mut ex, &|st| st.lights.push(st.lights[0].clone()));
    assert!(e.contains("2 light(s) in the frame for targets made for 1"), "{e}");
    // issue 49: a light of a kind the technique's file does not list (PCSS is written for
    // area lights) is refused where the host states its kind; the lab, which runs such
    // pairs on purpose, gives it without its kind (`run::outside_the_model`)
    let e = refused(&mut ex, &|st| st.lights[0].kind = Some(sshc_runtime::graph::LightKind::Point));
    assert!(
        e.contains("technique `pcss` is written for Rectangle, Disk, Sphere, DistantDisk lights") && e.contains("light 0 is a Point light"),
        "{e}"
    );
    let other = Loaded::new(gpu(), c.graph.clone(), c.shaders.clone()).unwrap();
    let e = refused(&mut ex, &|st| st.params = other.params.clone());
    assert!(e.contains("params were made for another technique"), "{e}");
    // targets run only on the scene they were made on
    let mut elsewhere = loaded.bind_scene(&s).unwrap();
    let mut encoder = gpu().device.create_command_encoder(&Default::default());
    let e = ex.targets.prepare(&mut elsewhere.scene, &ex.state).unwrap_err().to_string();
    assert!(e.contains("made on another scene"), "{e}");
    // recording before any prepare is refused with what to call
    let e = elsewhere.targets.record(&elsewhere.scene, &mut encoder).unwrap_err().to_string();
    assert!(e.contains("call prepare (queue writes), then record"), "{e}");
    drop(encoder);
    // a sample count is a size
    let lc = compile("linear-light");
    let ls = inputs(&scene("linear", 32, 64), &lc);
    let lloaded = Loaded::new(gpu(), lc.graph.clone(), lc.shaders.clone()).unwrap();
    let mut lex = lloaded.bind_scene(&ls).unwrap();
    let e = refused(&mut lex, &|st| {
        st.lights[0].samples.pop();
    });
    assert!(e.contains("a new number of samples is new targets"), "{e}");
    // the lights of a frame share one scene (uploaded once for all of them): a light whose
    // soup differs is refused
    let mut moved = s.clone();
    moved.vertices[0] += 0.5;
    let e = loaded.bind_lights(&[s.clone(), moved]).unwrap_err().to_string();
    assert!(e.contains("light 1's scene differs") && e.contains("share one scene"), "{e}");
    // every refusal left the targets as they were
    assert_eq!((ex.targets.generation(), ex.targets.lights()), (0, 1));
    ex.run_frame().unwrap();
    assert!(ex.inspect().read_visibilities().unwrap().rgba == before);
}

// Host geometry: indexed meshes, instances, transforms.

#[test]
fn indexed_instanced_geometry_matches_the_same_triangles_listed_out() {
    let (mut geometry_passes, mut pairs, mut one_view) = (0, 0, 0);
    let scenes = support::bundled("scenes");
    for t in techniques() {
        let c = compile(&t);
        one_view += usize::from(sshc_lab::bind::graph_samples(&c.graph) == 0);
        let mut records = 0;
        for sc in &scenes {
            // a technique of light samples runs under the lights that have its samples
            let Ok(s) = sshc_lab::bind::scene_inputs_for(&scene(sc, 32, 64), &c.graph) else {
                assert!(sshc_lab::bind::graph_samples(&c.graph) > 0, "{t} on {sc}: not bound");
                continue;
            };
            let what = format!("{t} on {sc}");
            // a quarter turn about the origin: every coordinate of the copy, its edges and
            // its face planes are its mesh's permuted and negated, exactly (a translation
            // would round the planes' offsets apart from the listed-out triangles' own)
            let g = geometry_of(&s, [0.0; 3]);
            let host = Loaded::new(gpu(), c.graph.clone(), c.shaders.clone()).unwrap();
            let mut host = host
                .bind_geometry(&g, &s.camera(), &[s.light_inputs()], s.camera_size, s.shadow_size)
                .unwrap_or_else(|e| panic!("{what}: {e}"));
            host.run_frame().unwrap();
            let soup = Loaded::new(gpu(), c.graph.clone(), c.shaders.clone()).unwrap();
            let mut soup = soup.bind_scene(&listed_out(&s, &g)).unwrap();
            soup.run_frame().unwrap();
            let visibility = |ex: &Bound| ex.inspect().read_visibilities().unwrap().rgba;
            assert!(
                visibility(&host) == visibility(&soup),
                "{what}: indexed and instanced differs from listed out"
            );
            // Geometry passes: the same edges where silhouettes are classified (host
            // geometry builds no adjacency for a graph that reads none), and the same
            // records generated
            let classifies = c
                .graph
                .passes
                .iter()
                .flat_map(|p| &p.steps)
                .any(|st| matches!(st.draw, sshc_runtime::graph::Draw::Silhouettes { .. }));
            let edges = host.scene.edge_counts();
            assert_eq!(edges.is_some(), classifies, "{what}");
            if classifies {
                assert_eq!(edges, soup.scene.edge_counts(), "{what}");
            }
            for b in &c.graph.buffers {
                let (h, l) = (
                    host.inspect().generated(&b.name).unwrap(),
                    soup.inspect().generated(&b.name).unwrap(),
                );
                assert_eq!(h, l, "{what}: buffer `{}`", b.name);
                records += h.records;
            }
            pairs += 1;
        }
        // (a buffer may be empty, as the skins towards a chain's missing neighbour are)
        assert!(
            c.graph.buffers.is_empty() || records > 0,
            "{t}: nothing generated: the comparison would be vacuous"
        );
        geometry_passes += usize::from(!c.graph.buffers.is_empty());
    }
    assert!(
        geometry_passes >= 5,
        "{geometry_passes} techniques with Geometry passes ran on host geometry"
    );
    // every technique of one view ran on every scene (the per-sample ones where they can)
    assert!(pairs > one_view * scenes.len(), "{pairs} technique-scene pairs");
}

#[test]
fn moving_instances_create_no_wgpu_object_and_match_listed_out() {
    // a raster technique, and a Geometry one whose edges and face planes move with the
    // instance (under the scene's distant light the silhouette test reads the planes'
    // normals only, which a translation leaves exact)
    for t in ["pcss", "penumbra-limit-maps"] {
        let c = compile(t);
        let s = inputs(&scene("triangle", 32, 64), &c);
        let mut g = geometry_of(&s, [0.0; 3]);
        // the scene's triangle (its ground is an instance too)
        let moving = g
            .instances
            .iter()
            .position(|i| g.meshes[i.mesh].indices.len() == 3)
            .expect("the triangle");
        let gpu = gpu();
        let loaded = Loaded::new(gpu, c.graph.clone(), c.shaders.clone()).unwrap();
        let mut ex = loaded
            .bind_geometry(&g, &s.camera(), &[s.light_inputs()], s.camera_size, s.shadow_size)
            .unwrap();
        host_frame(&mut ex);
        let before = live_objects(gpu);
        let mut checked = Vec::new();
        for f in 1..=20 {
            // the caster slides in steps of 1/128 (exact in f32), inside the light's fitted view
            g.instances[moving].transform[12] = f as f32 / 128.0;
            let transforms: Vec<[f32; 16]> = g.instances.iter().map(|i| i.transform).collect();
            ex.scene.set_transforms(&transforms).unwrap();
            host_frame(&mut ex);
            assert_eq!(live_objects(gpu), before, "{t}: frame {f} created or destroyed wgpu objects");
            if f % 10 == 0 {
                checked.push((g.clone(), ex.inspect().read_visibilities().unwrap().rgba));
            }
        }
        assert_eq!(ex.targets.generation(), 0);
        assert!(checked[0].1 != checked[1].1, "{t}: the caster's shadow did not move");
        for (g, moved) in &checked {
            assert!(
                *moved == fresh(&c, &[listed_out(&s, g)]),
                "{t}: a moved instance differs from its triangles listed out"
            );
        }
    }
}

/// A host that knows only its light (kind, position, size) lets the runtime fit the view
/// every frame (`place_light`, to the instances' boxes under their current transforms):
/// nothing is created, and each frame equals a fresh binding of the light fitted the same
/// way. A per-sample technique gets its sample views fitted too.
#[test]
fn lights_placed_by_the_runtime_every_frame_create_nothing_and_match_fresh_fits() {
    use sshc_runtime::gpu::{Fit, LightInputs};
    for (t, sc) in [("pcss", "triangle"), ("linear-light", "linear")] {
        let c = compile(t);
        let base = scene(sc, 32, 64);
        let s = inputs(&base, &c);
        let mut g = geometry_of(&s, [0.0; 3]);
        let samples = sshc_lab::bind::graph_samples(&c.graph);
        let gpu = gpu();
        let fitted = |g: &Geometry, light: &sshc_lab::scene::Light| {
            LightInputs::fit(light, &g.boxes(), Fit::Casters, s.shadow_size, samples).unwrap_or_else(|e| panic!("{t}: {e}"))
        };
        let loaded = Loaded::new(gpu, c.graph.clone(), c.shaders.clone()).unwrap();
        let mut ex = loaded
            .bind_geometry(&g, &s.camera(), &[fitted(&g, &base.lights[0])], s.camera_size, s.shadow_size)
            .unwrap_or_else(|e| panic!("{t}: {e}"));
        host_frame(&mut ex);
        let before = live_objects(gpu);
        let moving = g.instances.len() - 1;
        let mut checked = Vec::new();
        for f in 1..=20 {
            let light = at_frame(&base, f).lights.remove(0);
            g.instances[moving].transform[12] = f as f32 / 64.0;
            let transforms: Vec<[f32; 16]> = g.instances.iter().map(|i| i.transform).collect();
            ex.scene.set_transforms(&transforms).unwrap();
            ex.place_light(0, &light, Fit::Casters)
                .unwrap_or_else(|e| panic!("{t}: frame {f}: {e}"));
            host_frame(&mut ex);
            assert_eq!(live_objects(gpu), before, "{t}: frame {f} created or destroyed wgpu objects");
            if f % 10 == 0 {
                checked.push((g.clone(), light, ex.inspect().read_visibilities().unwrap().rgba));
            }
        }
        assert_eq!(ex.targets.generation(), 0);
        assert!(checked[0].2 != checked[1].2, "{t}: the shadows did not move");
        for (g, light, moved) in &checked {
            let inputs = fitted(g, light);
            assert_eq!(inputs.samples.len(), samples as usize);
            let mut again = loaded
                .bind_geometry(g, &s.camera(), &[inputs], s.camera_size, s.shadow_size)
                .unwrap();
            again.run_frame().unwrap();
            assert!(
                *moved == again.inspect().read_visibilities().unwrap().rgba,
                "{t}: a light placed per frame differs from a fresh binding of the same fit"
            );
        }
        // a light no view can hold is refused and leaves the bound one as it was
        let bad = sshc_lab::scene::Light::Point {
            position: glam::Vec3::new(f32::NAN, 1.0, 0.0),
        };
        let e = ex.place_light(0, &bad, Fit::Casters).unwrap_err().to_string();
        assert!(e.contains("not finite"), "{t}: {e}");
        host_frame(&mut ex);
        assert!(
            ex.inspect().read_visibilities().unwrap().rgba == checked[1].2,
            "{t}: a refused light changed the frame"
        );
    }
    // over a triangle soup, the instances fitted to are its objects; a light the targets
    // were not made for is refused
    let c = compile("pcss");
    let s = inputs(&scene("triangle", 8, 16), &c);
    // a light PCSS's file lists (a host's light of another kind is refused: `by_hand` below
    // states the kind the fit gives)
    let light = sshc_lab::scene::Light::Sphere {
        center: glam::Vec3::Y,
        radius: 0.05,
    };
    let loaded = Loaded::new(gpu(), c.graph.clone(), c.shaders.clone()).unwrap();
    let mut ex = loaded.bind_scene(&s).unwrap();
    let e = ex.targets.fit_light(&ex.scene, 1, &light, Fit::Scene).unwrap_err().to_string();
    assert!(e.contains("light 1 is not in these targets (1 light(s) are)"), "{e}");
    ex.place_light(0, &light, Fit::Casters).unwrap();
    ex.run_frame().unwrap();
    let objects = Geometry::from_soup(&s.vertices, &s.meshes, s.casting_vertices, &s.unshadowed).unwrap();
    let fitted = LightInputs::fit(&light, &objects.boxes(), Fit::Casters, s.shadow_size, 0).unwrap();
    let mut by_hand = loaded.bind_scene(&s).unwrap();
    by_hand.state.lights[0] = fitted.clone();
    by_hand.run_frame().unwrap();
    assert!(ex.inspect().read_visibilities().unwrap().rgba == by_hand.inspect().read_visibilities().unwrap().rgba);
}

#[test]
fn host_geometry_is_checked_at_upload_naming_the_mesh_or_instance() {
    let c = compile("pcss");
    let s = inputs(&scene("triangle", 32, 64), &c);
    let good = geometry_of(&s, [0.0; 3]);
    let loaded = Loaded::new(gpu(), c.graph.clone(), c.shaders.clone()).unwrap();
    let mut bind = |g: &Geometry| {
        loaded
            .bind_geometry(g, &s.camera(), &[s.light_inputs()], s.camera_size, s.shadow_size)
            .map(|_| ())
    };
    let refused = |g: Geometry, want: &str, bind: &mut dyn FnMut(&Geometry) -> sshc_runtime::gpu::Result<()>| {
        let e = bind(&g).expect_err(want);
        assert!(e.to_string().contains(want), "{e}");
    };
    let mut g = good.clone();
    g.meshes[0].indices[4] = g.meshes[0].positions.len() as u32;
    refused(g, "mesh 0 (`part 0`): index 4 is", &mut bind);
    let mut g = good.clone();
    g.meshes[0].indices.pop();
    refused(g, "not a multiple of 3", &mut bind);
    let mut g = good.clone();
    g.meshes[0].normals.pop();
    refused(g, "normals for", &mut bind);
    let mut g = good.clone();
    g.meshes[0].positions[0][1] = f32::NAN;
    refused(g, "mesh 0 (`part 0`): vertex 0 is not finite", &mut bind);
    let mut g = good.clone();
    g.instances[0].transform[5] = f32::NAN;
    refused(g, "instance 0 (`part 0`): its transform is not finite", &mut bind);
    let mut g = good.clone();
    g.instances[0].transform[3] = 1.0;
    refused(g, "not affine", &mut bind);
    let mut g = good.clone();
    g.instances[0].transform[0] = 0.0;
    g.instances[0].transform[10] = 0.0;
    refused(g, "singular", &mut bind);
    let mut g = good.clone();
    g.instances[0].mesh = 9;
    refused(g, "places mesh 9", &mut bind);
    // nothing at all is a scene with nothing in it, not an error
    bind(&Geometry::default()).unwrap();
    let mut ex = loaded
        .bind_geometry(&good, &s.camera(), &[s.light_inputs()], s.camera_size, s.shadow_size)
        .unwrap();
    // per frame: the count, and NaN
    let mut ts: Vec<[f32; 16]> = good.instances.iter().map(|i| i.transform).collect();
    ts.pop();
    assert!(
        ex.scene
            .set_transforms(&ts)
            .unwrap_err()
            .to_string()
            .contains("a new instance set is a new binding")
    );
    let mut ts: Vec<[f32; 16]> = good.instances.iter().map(|i| i.transform).collect();
    ts[1][12] = f32::INFINITY;
    assert!(
        ex.scene
            .set_transforms(&ts)
            .unwrap_err()
            .to_string()
            .contains("instance 1: its transform is not finite")
    );
    // a soup's objects are instances in world space: their transforms stay the identity
    let mut ex = loaded.bind_scene(&s).unwrap();
    let objects = Geometry::from_soup(&s.vertices, &s.meshes, s.casting_vertices, &s.unshadowed)
        .unwrap()
        .instances
        .len();
    let mut ts = vec![sshc_runtime::gpu::IDENTITY; objects];
    ex.scene.set_transforms(&ts).unwrap();
    ts[0][12] = 1.0;
    let e = ex.scene.set_transforms(&ts).unwrap_err().to_string();
    assert!(e.contains("instance 0 does not move"), "{e}");
}

#[test]
fn a_specialised_graph_is_rechecked_per_frame_from_the_casters_bounds() {
    let sc = scene("triangle", 32, 64);
    // ESM with its basis channel's precision left to the compiler: the specialisation keeps
    // the casters' depth floor, which that choice reads
    let src = support::technique_source("esm");
    let s = inputs(&sc, &compile("esm"));
    let floor = sshc_runtime::graph::caster_depth_floor(&s.vertices, s.casting_vertices, &s.light_view, s.near, s.far).unwrap();
    let opts = sshc::CompileOptions {
        scene: Some(sshc::SceneFacts {
            scene: "triangle".into(),
            light: sc.lights[0].kind(),
            depth_floor: Some(floor),
        }),
        precision: vec![("e".into(), "auto".into())],
        ..Default::default()
    };
    let c = sshc::compile_str(&src, &opts).unwrap_or_else(|d| panic!("{}", d.render("esm", &src)));
    assert_eq!(c.graph.specialised.as_ref().and_then(|f| f.depth_floor), Some(floor));
    let loaded = Loaded::new(gpu(), c.graph.clone(), c.shaders.clone()).unwrap();
    let mut ex = loaded.bind_scene(&s).unwrap();
    // the same light passes: the bounds' least depth is the triangles' here (the top corner)
    ex.state.lights[0] = s.light_inputs();
    ex.run_frame().unwrap();
    // a near plane pushed towards the casters brings them below the floor
    let mut closer = s.light_inputs();
    closer.near += 0.5 * (closer.far - closer.near) * floor;
    ex.state.lights[0] = closer.clone();
    let e = ex.run_frame().unwrap_err();
    assert!(e.to_string().contains("bounding box reaches"), "{e}");
    // host geometry: the exact check at making the targets, the bounds per frame, on
    // transforms too
    let mut g = geometry_of(&s, [0.0; 3]);
    g.instances.pop();
    let mut ex = loaded
        .bind_geometry(&g, &s.camera(), &[s.light_inputs()], s.camera_size, s.shadow_size)
        .unwrap();
    ex.run_frame().unwrap();
    let raised: Vec<[f32; 16]> = g
        .instances
        .iter()
        .map(|i| {
            let mut t = i.transform;
            t[13] += 0.25; // up, towards the overhead light
            t
        })
        .collect();
    ex.scene.set_transforms(&raised).unwrap();
    let e = ex.run_frame().unwrap_err();
    assert!(e.to_string().contains("bounding box reaches"), "{e}");
    // the transforms back where they were: the frame passes again
    let back: Vec<[f32; 16]> = g.instances.iter().map(|i| i.transform).collect();
    ex.scene.set_transforms(&back).unwrap();
    ex.run_frame().unwrap();
    for (i, t) in g.instances.iter_mut().zip(&raised) {
        i.transform = *t;
    }
    let e = loaded
        .bind_geometry(&g, &s.camera(), &[s.light_inputs()], s.camera_size, s.shadow_size)
        .unwrap_err();
    assert!(e.to_string().contains("but this scene's come to"), "{e}");
    // the exact check reads the placed casters: a bad geometry is refused before it, not a panic
    g.meshes[0].indices[0] = u32::MAX;
    let e = loaded
        .bind_geometry(&g, &s.camera(), &[s.light_inputs()], s.camera_size, s.shadow_size)
        .unwrap_err();
    assert!(e.to_string().contains("out of range"), "{e}");
}

// Host pixels: the deferred Shade fed by the host's G-buffer.

/// The host's own G-buffer pass: the soup of `s` rasterised from its camera into the world
/// position (xyz, w = 1 on a surface, 0 elsewhere) and the interpolated normal, both
/// `Rgba32Float`, as a deferred renderer's geometry pass writes them.
fn host_gbuffer(gpu: &Gpu, s: &SceneInputs) -> [wgpu::Texture; 2] {
    use wgpu::util::DeviceExt;
    let device = &gpu.device;
    let (w, h) = s.camera_size;
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("host g-buffer"),
        source: wgpu::ShaderSource::Wgsl(
            "@group(0) @binding(0) var<uniform> view_proj: mat4x4<f32>;
struct V { @builtin(position) pos: vec4<f32>, @location(0) world: vec3<f32>, @location(1) normal: vec3<f32> }
@vertex fn vs(@location(0) p: vec3<f32>, @location(1) n: vec3<f32>) -> V {
    var v: V;
    v.pos = view_proj * vec4<f32>(p, 1.0);
    v.world = p;
    v.normal = n;
    return v;
}
struct G { @location(0) world: vec4<f32>, @location(1) normal: vec4<f32> }
@fragment fn fs(v: V) -> G { return G(vec4<f32>(v.world, 1.0), vec4<f32>(v.normal, 0.0)); }"
                .into(),
        ),
    });
    let attrs = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3];
    let target = Some(wgpu::ColorTargetState::from(wgpu::TextureFormat::Rgba32Float));
    let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("host g-buffer"),
        layout: None,
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs"),
            compilation_options: Default::default(),
            buffers: &[Some(wgpu::VertexBufferLayout {
                array_stride: 24,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &attrs,
            })],
        },
        primitive: Default::default(),
        depth_stencil: Some(wgpu::DepthStencilState {
            format: wgpu::TextureFormat::Depth32Float,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Less),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs"),
            compilation_options: Default::default(),
            targets: &[target.clone(), target],
        }),
        multiview_mask: None,
        cache: None,
    });
    let bytes = |v: &[f32]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
    let vertices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: None,
        contents: &bytes(&s.vertices),
        usage: wgpu::BufferUsages::VERTEX,
    });
    let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: None,
        contents: &bytes(&s.camera_view_proj),
        usage: wgpu::BufferUsages::UNIFORM,
    });
    let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: uniform.as_entire_binding(),
        }],
    });
    let texture = |format, usage| {
        device.create_texture(&wgpu::TextureDescriptor {
            label: None,
            size: wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage,
            view_formats: &[],
        })
    };
    let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING;
    let out = [
        texture(wgpu::TextureFormat::Rgba32Float, usage),
        texture(wgpu::TextureFormat::Rgba32Float, usage),
    ];
    let depth = texture(wgpu::TextureFormat::Depth32Float, wgpu::TextureUsages::RENDER_ATTACHMENT);
    let views: Vec<wgpu::TextureView> = out.iter().map(|t| t.create_view(&Default::default())).collect();
    let depth_view = depth.create_view(&Default::default());
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let attachment = |view| {
            Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Store,
                },
            })
        };
        let mut rp = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("host g-buffer"),
            color_attachments: &[attachment(&views[0]), attachment(&views[1])],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &depth_view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        rp.set_pipeline(&pipeline);
        rp.set_bind_group(0, &group, &[]);
        rp.set_vertex_buffer(0, vertices.slice(..));
        rp.draw(0..(s.vertices.len() / 6) as u32, 0..1);
    }
    gpu.queue.submit([encoder.finish()]);
    out
}

/// The triangle of `s` that world point `p` lies on, or `None` when none or more than one
/// holds it (a point on an edge).
fn triangle_of(s: &SceneInputs, p: [f32; 3]) -> Option<usize> {
    let v = |t: usize, k: usize| glam::Vec3::from_slice(&s.vertices[t * 18 + k * 6..t * 18 + k * 6 + 3]);
    let p = glam::Vec3::from(p);
    let mut found = None;
    for t in 0..s.vertices.len() / 18 {
        let (a, b, c) = (v(t, 0), v(t, 1), v(t, 2));
        let n = (b - a).cross(c - a);
        let area = n.length();
        if area == 0.0 || (p - a).dot(n).abs() / area > 1e-4 {
            continue;
        }
        // barycentric coordinates, each at least a margin inside
        let w = [(c - b).cross(p - b), (a - c).cross(p - c), (b - a).cross(p - a)].map(|e| e.dot(n) / (area * area));
        if w.iter().all(|x| *x > -1e-4) {
            if found.is_some() || w.iter().any(|x| *x < 1e-4) {
                return None;
            }
            found = Some(t);
        }
    }
    found
}

#[test]
fn host_pixels_give_the_forward_shade_where_a_quad_lies_on_one_triangle() {
    for t in ["hard", "pcf", "pcss"] {
        let forward = compile(t);
        let src = support::technique_source(t);
        let opts = sshc::CompileOptions {
            schedule: vec![("shade".into(), "compute".into())],
            ..Default::default()
        };
        let deferred = sshc::compile_str(&src, &opts).unwrap_or_else(|d| panic!("{}", d.render(t, &src)));
        let s = inputs(&scene("triangle", 48, 128), &forward);
        let ex = Loaded::new(gpu(), forward.graph.clone(), forward.shaders.clone()).unwrap();
        let mut ex = ex.bind_scene(&s).unwrap();
        ex.run_frame().unwrap();
        let want = ex.inspect().read_camera(CameraOutput::Visibility).unwrap();
        let position = ex.inspect().read_camera(CameraOutput::Position).unwrap();
        // a forward graph is refused host pixels, with the reason
        let [world, normal] = host_gbuffer(gpu(), &s);
        let pixels = sshc_runtime::gpu::HostPixels {
            world: &world,
            normal: &normal,
        };
        let e = ex.targets.set_host_pixels(Some(pixels)).unwrap_err();
        assert!(e.to_string().contains("need the deferred Shade"), "{e}");
        // the deferred graph on the host's pixels
        let host = Loaded::new(gpu(), deferred.graph.clone(), deferred.shaders.clone()).unwrap();
        let mut host = host.bind_scene(&s).unwrap();
        host.targets.set_host_pixels(Some(pixels)).unwrap();
        host.run_frame().unwrap();
        let got = host.inspect().read_camera(CameraOutput::Visibility).unwrap();
        let (w, h) = (want.width, want.height);
        let tri = |x: u32, y: u32| {
            let p = position.at(x, y);
            if p[0].is_nan() { None } else { triangle_of(&s, [p[0], p[1], p[2]]) }
        };
        let (mut interior, mut surface, mut at_edges) = (0, 0, 0);
        for y in 0..h {
            for x in 0..w {
                let (a, b) = (want.at(x, y)[0], got.at(x, y)[0]);
                if position.at(x, y)[0].is_nan() {
                    assert_eq!(b, 1.0, "{t} ({x}, {y}): no surface reads 1");
                    continue;
                }
                surface += 1;
                let (qx, qy) = (x & !1, y & !1);
                let quad = [(qx, qy), (qx + 1, qy), (qx, qy + 1), (qx + 1, qy + 1)];
                let here = tri(x, y);
                let one_triangle = here.is_some() && quad.iter().all(|&(u, v)| u < w && v < h && tri(u, v) == here);
                if one_triangle {
                    assert_eq!(a.to_bits(), b.to_bits(), "{t} ({x}, {y}): {a} forward, {b} from host pixels");
                    interior += 1;
                } else if a != b {
                    at_edges += 1;
                }
            }
        }
        assert!(
            interior * 10 >= surface * 8,
            "{t}: {interior} of {surface} surface pixels have their quad on one triangle"
        );
        eprintln!("{t}: {interior} of {surface} pixels bit for bit; {at_edges} of the others differ");
    }
}

#[test]
fn host_pixels_of_the_wrong_format_or_size_are_refused() {
    let src = support::technique_source("pcss");
    let opts = sshc::CompileOptions {
        schedule: vec![("shade".into(), "compute".into())],
        ..Default::default()
    };
    let c = sshc::compile_str(&src, &opts).unwrap_or_else(|d| panic!("{}", d.render("pcss", &src)));
    let s = inputs(&scene("triangle", 32, 64), &c);
    let ex = Loaded::new(gpu(), c.graph.clone(), c.shaders.clone()).unwrap();
    let texture = |format, size: u32, usage| {
        gpu().device.create_texture(&wgpu::TextureDescriptor {
            label: None,
            size: wgpu::Extent3d {
                width: size,
                height: size,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage,
            view_formats: &[],
        })
    };
    let sampled = wgpu::TextureUsages::TEXTURE_BINDING;
    let good = texture(wgpu::TextureFormat::Rgba32Float, 32, sampled);
    fn pixels<'a>(world: &'a wgpu::Texture, normal: &'a wgpu::Texture) -> sshc_runtime::gpu::HostPixels<'a> {
        sshc_runtime::gpu::HostPixels { world, normal }
    }
    let mut ex = ex.bind_scene(&s).unwrap();
    for (world, normal, want) in [
        (
            texture(wgpu::TextureFormat::Rgba16Float, 32, sampled),
            None,
            "world-position texture is Rgba16Float; it must be Rgba32Float",
        ),
        (
            texture(wgpu::TextureFormat::Rgba32Float, 48, sampled),
            None,
            "is 48 x 48, the camera 32 x 32",
        ),
        (
            texture(wgpu::TextureFormat::Rgba32Float, 32, wgpu::TextureUsages::COPY_DST),
            None,
            "has no TEXTURE_BINDING usage",
        ),
        (
            texture(wgpu::TextureFormat::Rgba32Float, 32, sampled),
            Some(texture(wgpu::TextureFormat::Rgba8Unorm, 32, sampled)),
            "normal texture is Rgba8Unorm",
        ),
    ] {
        let normal = normal.as_ref().unwrap_or(&good);
        let e = ex.targets.set_host_pixels(Some(pixels(&world, normal))).unwrap_err();
        assert!(e.to_string().contains(want), "{e}");
    }
    ex.targets.set_host_pixels(Some(pixels(&good, &good))).unwrap();
}

/// Objects that receive no shadow (`receives: false` in a scene, `Instance::receives` in a
/// host's geometry) read visibility 1 and are drawn lit, in every schedule of the Shade
/// (forward, deferred) and on a Geometry technique; everything else stays as it was, bit
/// for bit; host geometry gives what the same triangles listed out give; and the truth
/// follows the same rule.
#[test]
fn objects_that_receive_no_shadow_read_one_in_the_techniques_and_the_truth() {
    use sshc_lab::truth::{self, Points, TruthSettings};
    use sshc_lab::visibility::Visibility;
    let text = std::fs::read_to_string(root().join("scenes/triangle.ron")).unwrap();
    let ground = "Object(name: \"ground\", mesh: Plane(size: (3.0, 3.0)))";
    assert!(text.contains(ground), "scenes/triangle.ron's ground changed");
    let load = |text: &str| {
        let mut s = Scene::from_str(text, root().join("scenes")).unwrap_or_else(|e| panic!("{e}"));
        s.set_camera_size(32, 32);
        s.shadow_map = 64;
        s
    };
    let base = load(&text);
    let unlit = load(&text.replace(ground, &format!("{}, receives: false)", &ground[..ground.len() - 1])));
    assert!(!unlit.receives(0) && unlit.receives(1) && base.receives(0));
    assert_ne!(base.fingerprint(), unlit.fingerprint(), "the truth cache tells the two apart");
    let deferred = {
        let src = support::technique_source("pcss");
        let opts = sshc::CompileOptions {
            schedule: vec![("shade".into(), "compute".into())],
            ..Default::default()
        };
        sshc::compile_str(&src, &opts).unwrap_or_else(|d| panic!("{}", d.render("pcss", &src)))
    };
    let vis = Visibility::new(&unlit);
    let run = |c: &sshc::Compiled, s: &SceneInputs| {
        let ex = Loaded::new(gpu(), c.graph.clone(), c.shaders.clone()).unwrap();
        let mut ex = ex.bind_scene(s).unwrap();
        ex.run_frame().unwrap();
        let read = |o| ex.inspect().read_camera(o).unwrap().rgba;
        (
            read(CameraOutput::Visibility),
            read(CameraOutput::Color),
            read(CameraOutput::Position),
        )
    };
    for (name, c) in [
        ("pcss", compile("pcss")),
        ("pcss, deferred", deferred),
        ("penumbra-limit-maps", compile("penumbra-limit-maps")),
    ] {
        let (si, su) = (inputs(&base, &c), inputs(&unlit, &c));
        assert_eq!(
            su.unshadowed,
            vec![0..6],
            "{name}: the ground's two triangles, listed first (it casts too)"
        );
        let (v0, c0, p0) = run(&c, &si);
        let (v1, c1, p1) = run(&c, &su);
        let bits = |p: &[[f32; 4]]| p.iter().flatten().map(|c| c.to_bits()).collect::<Vec<u32>>();
        assert!(bits(&p0) == bits(&p1), "{name}: the camera raster changed");
        let positions: Vec<glam::Vec3> = p1.iter().map(|p| glam::Vec3::new(p[0], p[1], p[2])).collect();
        let on_ground = vis.on_non_receivers(&unlit, &positions);
        let (mut ground, mut shadowed) = (0, 0);
        for i in 0..positions.len() {
            if on_ground[i] {
                ground += 1;
                shadowed += usize::from(v0[i][0] < 1.0);
                assert_eq!(v1[i][0], 1.0, "{name}: pixel {i} on the ground");
                // lit: the colour a visibility of 1 gives, within one unorm8 step of the
                // Shade's own where it read 1 (the same formula in another shader)
                assert!(c1[i][0] >= c0[i][0], "{name}: pixel {i} darker unshadowed");
                if v0[i][0] == 1.0 {
                    assert!(
                        (c1[i][0] - c0[i][0]).abs() <= 1.0 / 255.0,
                        "{name}: pixel {i}: {} against {}",
                        c1[i][0],
                        c0[i][0]
                    );
                }
            } else {
                assert!(
                    bits(&[v1[i]]) == bits(&[v0[i]]) && c1[i] == c0[i],
                    "{name}: pixel {i} off the ground changed"
                );
            }
        }
        assert!(
            ground > 100 && shadowed > 10,
            "{name}: {ground} ground pixels, {shadowed} in shadow"
        );
        // host geometry: the ground an instance that does not receive, against its
        // triangles listed out
        let mut g = geometry_of(&su, [0.0; 3]);
        g.instances.pop(); // the turned copy
        // the ground: the mesh of two triangles (it casts, as in the scene)
        let ground = g
            .instances
            .iter()
            .position(|i| g.meshes[i.mesh].indices.len() == 6)
            .expect("the ground");
        g.instances[ground].receives = false;
        let listed = listed_out(&su, &g);
        assert!(!listed.unshadowed.is_empty());
        let ex = Loaded::new(gpu(), c.graph.clone(), c.shaders.clone()).unwrap();
        let mut ex = ex
            .bind_geometry(&g, &su.camera(), &[su.light_inputs()], su.camera_size, su.shadow_size)
            .unwrap();
        ex.run_frame().unwrap();
        assert!(
            ex.inspect().read_camera(CameraOutput::Visibility).unwrap().rgba == run(&c, &listed).0,
            "{name}: host geometry differs from its triangles listed out"
        );
    }
    // the truth: 1 on the ground, exactly; elsewhere the same rays as with a receiving ground
    let (_, _, p) = run(&compile("hard"), &inputs(&unlit, &compile("hard")));
    let positions: Vec<glam::Vec3> = p.iter().map(|p| glam::Vec3::new(p[0], p[1], p[2])).collect();
    let points = Points {
        width: 32,
        height: 32,
        positions: &positions,
        normals: &[],
    };
    let settings = TruthSettings {
        samples: 16,
        runs: 2,
        ..Default::default()
    };
    let no_progress = |_| {};
    let t0 = truth::compute(&base, &Visibility::new(&base), &points, &settings, &no_progress).unwrap();
    let t1 = truth::compute(&unlit, &vis, &points, &settings, &no_progress).unwrap();
    let on_ground = vis.on_non_receivers(&unlit, &positions);
    assert!(
        t0.visibility.iter().zip(&on_ground).any(|(v, g)| *g && *v < 1.0),
        "the ground has a shadow"
    );
    for (i, &on) in on_ground.iter().enumerate() {
        if on {
            assert_eq!((t1.visibility[i], t1.std_error[i]), (1.0, 0.0), "truth at pixel {i}");
        } else {
            assert_eq!(t1.visibility[i], t0.visibility[i], "truth at pixel {i}");
        }
    }
}

/// Instances that do not move, under the identity, are drawn straight from their meshes
/// (no placed copy, no placement) and give the visibility of the same instances placed on
/// the GPU, bit for bit; their transforms stay as bound, while a moving instance beside
/// them moves.
#[test]
fn world_space_instances_keep_no_placed_copy_and_match_instances_placed_on_the_gpu() {
    for t in ["pcss", "penumbra-limit-maps"] {
        let c = compile(t);
        let s = inputs(&scene("triangle", 32, 64), &c);
        let placed = geometry_of(&s, [0.0; 3]);
        let mut world = placed.clone();
        for i in world.instances.iter_mut().filter(|i| i.transform == sshc_runtime::gpu::IDENTITY) {
            i.moves = false;
        }
        let still: Vec<usize> = (0..world.instances.len())
            .filter(|&i| world.instances[i].in_world_space())
            .collect();
        let moving = world.instances.iter().position(|i| i.moves).expect("the turned copy moves");
        assert!(!still.is_empty(), "{t}: no instance in world space");
        // the placed copies of the instances in world space are gone, and nothing else
        let saved: u64 = still
            .iter()
            .map(|&i| world.meshes[world.instances[i].mesh].positions.len() as u64 * 24)
            .sum();
        assert_eq!(placed.gpu_bytes() - world.gpu_bytes(), saved, "{t}");
        let loaded = Loaded::new(gpu(), c.graph.clone(), c.shaders.clone()).unwrap();
        let bind = |g: &Geometry| {
            let mut ex = loaded
                .bind_geometry(g, &s.camera(), &[s.light_inputs()], s.camera_size, s.shadow_size)
                .unwrap_or_else(|e| panic!("{t}: {e}"));
            ex.run_frame().unwrap();
            ex
        };
        let (mut w, p) = (bind(&world), bind(&placed));
        assert!(
            w.inspect().read_visibilities().unwrap().rgba == p.inspect().read_visibilities().unwrap().rgba,
            "{t}"
        );
        if !c.graph.buffers.is_empty() {
            assert_eq!(w.scene.edge_counts(), p.scene.edge_counts(), "{t}");
            for b in &c.graph.buffers {
                assert_eq!(
                    w.inspect().generated(&b.name).unwrap(),
                    p.inspect().generated(&b.name).unwrap(),
                    "{t}: `{}`",
                    b.name
                );
            }
        }
        // the bound transforms are accepted again; a changed one is refused for a still
        // instance, and taken for the moving one
        let mut transforms: Vec<[f32; 16]> = world.instances.iter().map(|i| i.transform).collect();
        w.scene.set_transforms(&transforms).unwrap();
        let mut bad = transforms.clone();
        bad[still[0]][13] = 0.25;
        let e = w.scene.set_transforms(&bad).unwrap_err().to_string();
        assert!(e.contains(&format!("instance {} does not move", still[0])), "{t}: {e}");
        transforms[moving][13] = 1.0 / 64.0;
        w.scene.set_transforms(&transforms).unwrap();
        w.run_frame().unwrap();
        world.instances[moving].transform = transforms[moving];
        assert!(
            w.inspect().read_visibilities().unwrap().rgba == fresh(&c, &[listed_out(&s, &world)]),
            "{t}: the moving instance beside still ones differs from its triangles listed out"
        );
    }
}

/// The placement step binds the vertices it places whole, as storage; a mesh drawn only in
/// world space is a vertex buffer and is not held to that binding's limit. On a host device
/// whose storage bindings hold 64 KiB, a mesh of 96 KiB of vertices binds in world space
/// and gives the visibility the full device gives it, and the same mesh placed on the GPU
/// is refused, naming the limit.
#[test]
fn world_space_and_upload_placed_meshes_are_free_of_the_storage_binding_limit() {
    const LIMIT: u64 = 64 << 10;
    let c = compile("pcss");
    let s = inputs(&scene("triangle", 32, 64), &c);
    // a floor of 64 x 64 vertices (24 bytes each: 96 KiB), under the scene's triangle
    let n = 64u32;
    let mut floor = sshc_runtime::gpu::Mesh {
        name: "fine floor".into(),
        ..Default::default()
    };
    for k in 0..n * n {
        let (x, z) = ((k % n) as f32 / (n - 1) as f32, (k / n) as f32 / (n - 1) as f32);
        floor.positions.push([4.0 * x - 2.0, -0.01, 4.0 * z - 2.0]);
        floor.normals.push([0.0, 1.0, 0.0]);
    }
    for r in 0..n - 1 {
        for q in 0..n - 1 {
            let v = r * n + q;
            floor.indices.extend([v, v + n, v + 1, v + 1, v + n, v + n + 1]);
        }
    }
    assert!(floor.positions.len() * 24 > LIMIT as usize);
    let mut g = geometry_of(&s, [0.0; 3]);
    for i in &mut g.instances {
        i.moves = false;
    }
    g.meshes.push(floor);
    g.instances.push(sshc_runtime::gpu::Instance {
        name: "fine floor".into(),
        mesh: g.meshes.len() - 1,
        transform: sshc_runtime::gpu::IDENTITY,
        casts: false,
        receives: true,
        moves: false,
    });
    // the turned copy is the one instance not in world space; it places a small mesh
    let (host, _) = host_device(wgpu::Features::TIMESTAMP_QUERY, |a| wgpu::Limits {
        max_storage_buffer_binding_size: LIMIT,
        ..a.limits()
    });
    let on_host = Loaded::new(&host, c.graph.clone(), c.shaders.clone()).unwrap();
    let mut ex = on_host
        .bind_geometry(&g, &s.camera(), &[s.light_inputs()], s.camera_size, s.shadow_size)
        .unwrap();
    ex.run_frame().unwrap();
    let loaded = Loaded::new(gpu(), c.graph.clone(), c.shaders.clone()).unwrap();
    let mut full = loaded
        .bind_geometry(&g, &s.camera(), &[s.light_inputs()], s.camera_size, s.shadow_size)
        .unwrap();
    full.run_frame().unwrap();
    assert!(ex.inspect().read_visibilities().unwrap().rgba == full.inspect().read_visibilities().unwrap().rgba);
    let last = g.instances.len() - 1;
    // still but moved (placed at upload, on the CPU): its placed copy is written, never
    // bound as storage, so it binds as well, and gives the full device's visibility
    g.instances[last].transform[13] = -0.005;
    assert!(g.instances[last].placed_at_upload());
    let mut ex = on_host
        .bind_geometry(&g, &s.camera(), &[s.light_inputs()], s.camera_size, s.shadow_size)
        .unwrap();
    ex.run_frame().unwrap();
    let mut full = loaded
        .bind_geometry(&g, &s.camera(), &[s.light_inputs()], s.camera_size, s.shadow_size)
        .unwrap();
    full.run_frame().unwrap();
    assert!(ex.inspect().read_visibilities().unwrap().rgba == full.inspect().read_visibilities().unwrap().rgba);
    // placed on the GPU, the floor's vertices would be bound whole
    g.instances[last].moves = true;
    let e = on_host
        .bind_geometry(&g, &s.camera(), &[s.light_inputs()], s.camera_size, s.shadow_size)
        .unwrap_err();
    assert!(
        matches!(&e, RuntimeError::Limit { what, limit, .. } if what.contains("meshes placed on the GPU") && *limit == LIMIT),
        "{e}"
    );
}

/// Instances that do not move are placed once, on the CPU, at upload (`placed_at_upload`):
/// under any transform (here 30 degrees about y, scaled by 1.3 and moved, which rounds every
/// coordinate) their vertices, edges and face planes are the listed-out soup's, bit for bit
/// (the same arithmetic as `Geometry::soup`), for a raster technique and a Geometry one, and
/// the placement step has no work (nothing is bound whole, so no storage-binding limit holds
/// them: the 4 M-triangle city's instances bind this way, docs/scale.md).
#[test]
fn static_instances_placed_at_upload_match_the_same_triangles_listed_out() {
    let (sin, cos) = 30f32.to_radians().sin_cos();
    let k = 1.3f32;
    let turn = [
        k * cos,
        0.,
        -k * sin,
        0.,
        0.,
        k,
        0.,
        0.,
        k * sin,
        0.,
        k * cos,
        0.,
        0.3,
        0.05,
        -0.2,
        1.,
    ];
    for t in ["pcss", "penumbra-limit-maps"] {
        let c = compile(t);
        let s = inputs(&scene("triangle", 32, 64), &c);
        let mut g = geometry_of(&s, [0.0; 3]);
        for i in &mut g.instances {
            i.moves = false;
        }
        let copy = g.instances.len() - 1;
        g.instances[copy].transform = turn;
        assert!(g.instances[copy].placed_at_upload() && g.instances[..copy].iter().all(|i| i.in_world_space()));
        let ex = Loaded::new(gpu(), c.graph.clone(), c.shaders.clone()).unwrap();
        let mut ex = ex
            .bind_geometry(&g, &s.camera(), &[s.light_inputs()], s.camera_size, s.shadow_size)
            .unwrap_or_else(|e| panic!("{t}: {e}"));
        ex.run_frame().unwrap();
        let listed = fresh(&c, &[listed_out(&s, &g)]);
        assert!(
            ex.inspect().read_visibilities().unwrap().rgba == listed,
            "{t}: an instance placed at upload differs from its triangles listed out"
        );
        // the copy casts a shadow of its own: without it the frame differs
        let mut without = g.clone();
        without.instances.pop();
        assert!(
            fresh(&c, &[listed_out(&s, &without)]) != listed,
            "{t}: the placed copy changed nothing"
        );
    }
}

/// A box of half-size `h` on the ground (y from 0 to 2h), its 12 triangles with flat
/// normals, indexed.
fn box_mesh(h: f32) -> sshc_runtime::gpu::Mesh {
    let mut m = sshc_runtime::gpu::Mesh {
        name: "box".into(),
        ..Default::default()
    };
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let n = glam::Vec3::from_array(std::array::from_fn(|i| if i == axis { sign } else { 0.0 }));
            let (u, v) = (n.any_orthonormal_pair().0 * h, n.any_orthonormal_pair().1 * h);
            let c = n * h + glam::Vec3::new(0.0, h, 0.0);
            let base = m.positions.len() as u32;
            for p in [c - u - v, c + u - v, c + u + v, c - u + v] {
                m.positions.push(p.to_array());
                m.normals.push(n.to_array());
            }
            // counter-clockwise seen from outside
            let ccw = (u.cross(v)).dot(n) > 0.0;
            let quad = if ccw { [0, 1, 2, 0, 2, 3] } else { [0, 2, 1, 0, 3, 2] };
            m.indices.extend(quad.map(|i| base + i));
        }
    }
    m
}

/// Issue 49: PCSS and VSSM cast a shadow on a ground of half-size 4 to 64 under the fit
/// docs/embedding.md recommends (`Fit::Casters`). Before, a ground of half-size 6 or more
/// took the light's near plane to its floor (far * 1e-4): the blocker search, sized on the
/// near plane, spread over the whole map and found nothing, and every pixel was lit. The
/// shadow is the box's, and the fit's lateral extent the box's too, so only the depth
/// range changes with the ground (its far plane holds every receiver): the box-to-ground
/// gap then takes a smaller share of the normalised depth, and a filtered technique's
/// penumbra edge moves a little (measured: PCSS's count of shadowed ground pixels the
/// same for every ground, VSSM's about a tenth less on the largest). What is checked is that each ground keeps at
/// least half the smallest ground's shadow; the defect left none.
#[test]
fn pcss_and_vssm_cast_shadows_on_a_ground_of_any_size_under_the_casters_fit() {
    use sshc_runtime::gpu::{Camera, Fit, Instance, LightInputs, Mesh};
    use sshc_runtime::light::{Light, look_at, perspective};
    let camera_view_proj = perspective(0.9, 1.0, 0.1, 100.0) * look_at(glam::Vec3::new(0.0, 5.0, 5.0), glam::Vec3::ZERO, glam::Vec3::Y);
    let camera = Camera {
        view_proj: camera_view_proj.to_cols_array(),
        position: [0.0, 5.0, 5.0],
    };
    let light = Light::Sphere {
        center: glam::Vec3::new(1.5, 3.0, 0.5),
        radius: 0.3,
    };
    for t in ["pcss", "vssm"] {
        let c = compile(t);
        let mut counts = Vec::new();
        for half in [4.0f32, 6.0, 16.0, 64.0] {
            let ground = Mesh {
                name: "ground".into(),
                positions: vec![[-half, 0.0, -half], [half, 0.0, -half], [half, 0.0, half], [-half, 0.0, half]],
                normals: vec![[0.0, 1.0, 0.0]; 4],
                indices: vec![0, 2, 1, 0, 3, 2],
            };
            let instance = |name: &str, mesh: usize, casts: bool| Instance {
                name: name.into(),
                mesh,
                transform: sshc_runtime::gpu::IDENTITY,
                casts,
                receives: true,
                moves: false,
            };
            let g = Geometry {
                meshes: vec![box_mesh(0.5), ground],
                instances: vec![instance("box", 0, true), instance("ground", 1, false)],
            };
            let inputs = LightInputs::fit(&light, &g.boxes(), Fit::Casters, 256, 0).unwrap_or_else(|e| panic!("{t}: {e}"));
            let ex = Loaded::new(gpu(), c.graph.clone(), c.shaders.clone()).unwrap();
            let mut ex = ex
                .bind_geometry(&g, &camera, &[inputs], (64, 64), 256)
                .unwrap_or_else(|e| panic!("{t}: {e}"));
            ex.run_frame().unwrap_or_else(|e| panic!("{t}: {e}"));
            let v = ex
                .inspect()
                .read_camera(CameraOutput::Visibility)
                .unwrap_or_else(|e| panic!("{t}: {e}"));
            // on the ground only (the box's faces turned from the light read 0 anyway)
            let p = ex
                .inspect()
                .read_camera(CameraOutput::Position)
                .unwrap_or_else(|e| panic!("{t}: {e}"));
            let on_ground = |i: usize| p.rgba[i][1].abs() < 1e-3;
            counts.push((
                half,
                v.channel(0).iter().enumerate().filter(|(i, x)| on_ground(*i) && **x < 0.5).count(),
            ));
        }
        let least = counts[0].1;
        assert!(
            least > 40,
            "{t}: only {least} of 4096 pixels of the ground in shadow on the smallest ground"
        );
        for (half, n) in &counts {
            assert!(
                2 * n >= least,
                "{t}: ground of half-size {half}: {n} pixels in shadow against {least} on a ground of half-size 4 ({counts:?})"
            );
        }
    }
}

/// Issue 49: a new camera size (a window resized) makes only what depends on it: every
/// shadow-map-sized texture is the same wgpu object after the resize, the visibility is a
/// new one of the new size, no wgpu object is left over or missing (the live counts of
/// every kind are as before: each camera-sized target was replaced, nothing else made),
/// and the frame is a fresh binding's at the new size, bit for bit. Every bundled
/// technique, and three lights combined.
#[test]
fn a_camera_resize_makes_only_the_camera_sized_targets_and_renders_as_a_fresh_binding() {
    let gpu = gpu();
    let mut cases: Vec<(String, &str)> = techniques().into_iter().map(|t| (t, "")).collect();
    cases.push(("pcss".into(), "three-lights"));
    for (t, sc) in &cases {
        let c = compile(t);
        let sc = if sc.is_empty() { scene_for(&c) } else { sc };
        let base = scene(sc, 24, 64);
        let lights = all_lights(&base, &c);
        let ex = Loaded::new(gpu, c.graph.clone(), c.shaders.clone()).unwrap_or_else(|e| panic!("{t}: {e}"));
        let mut ex = ex.bind_lights(&lights).unwrap_or_else(|e| panic!("{t}: {e}"));
        host_frame(&mut ex);
        let shadow_sized: Vec<(String, wgpu::Texture)> = c
            .graph
            .textures
            .iter()
            .filter(|d| d.extent == sshc_runtime::graph::Extent::ShadowMap && !d.format.is_table())
            .map(|d| (d.name.clone(), ex.targets.texture(&d.name).unwrap().clone()))
            .collect();
        let old_visibility = ex.targets.visibility().clone();
        let generation = ex.targets.generation();
        let mut bigger = base.clone();
        bigger.set_camera_size(40, 32);
        let now = all_lights(&bigger, &c);
        let before = live_objects(gpu);
        ex.targets.resize((40, 32)).unwrap_or_else(|e| panic!("{t}: {e}"));
        let v = ex.targets.visibility();
        assert!(
            v != &old_visibility && (v.width(), v.height()) == (40, 32),
            "{t}: the visibility was not made at the new size"
        );
        drop(old_visibility);
        for (name, old) in &shadow_sized {
            assert!(
                ex.targets.texture(name).unwrap() == old,
                "{t}: `{name}` was made again by a camera resize"
            );
        }
        update(&mut ex, &now);
        host_frame(&mut ex);
        host_frame(&mut ex);
        // wgpu-hal 30's Vulkan device counts a texture when it is destroyed but not when
        // it is created, so the live count falls by the textures made again: each light's
        // camera outputs and depth, a deferred Shade's G-buffer, camera-sized graph
        // textures, and the combination's four with several lights. Every other kind is
        // exactly as before (replaced one for one).
        let after = live_objects(gpu);
        let camera_sized = c
            .graph
            .textures
            .iter()
            .filter(|d| d.extent == sshc_runtime::graph::Extent::Camera)
            .count();
        let deferred = c
            .graph
            .passes
            .iter()
            .flat_map(|p| &p.steps)
            .any(|s| s.draw == sshc_runtime::graph::Draw::CameraGBuffer);
        let per_light = 5 + camera_sized + if deferred { 3 } else { 0 };
        let combined = if lights.len() > 1 { 4 } else { 0 };
        let made_again = (per_light * lights.len() + combined) as isize;
        assert_eq!(
            before[1].1 - after[1].1,
            made_again,
            "{t} on {sc}: textures made again by the resize"
        );
        let others = |o: [(&'static str, isize); 11]| o.into_iter().filter(|(k, _)| *k != "textures").collect::<Vec<_>>();
        assert_eq!(
            others(after),
            others(before),
            "{t} on {sc}: a resize made or kept objects besides the camera-sized targets"
        );
        assert_eq!(
            ex.targets.generation(),
            generation + 1,
            "{t}: a resize changes the host's views: the generation says so"
        );
        ex.run_frame().unwrap();
        assert!(
            ex.inspect().read_visibilities().unwrap().rgba == fresh(&c, &now),
            "{t} on {sc}: a resized executor differs from a fresh binding at the new size"
        );
    }
}

/// Issue 49: `prepare` writes a frame's uniforms through the queue and `record` (from
/// `&self`) only records: a prepared frame recorded twice in one submission, into two
/// encoders, gives the frame recorded once, bit for bit; `record` before any `prepare` is
/// refused with what to call.
#[test]
fn a_prepared_frame_recorded_twice_in_one_submission_is_the_frame_recorded_once() {
    let gpu = gpu();
    for (t, sc) in [("pcss", "triangle"), ("penumbra-maps", "triangle"), ("pcss", "three-lights")] {
        let c = compile(t);
        let base = scene(sc, 32, 64);
        let lights = all_lights(&base, &c);
        let moved = all_lights(&at_frame(&base, 3), &c);
        let ex = Loaded::new(gpu, c.graph.clone(), c.shaders.clone()).unwrap();
        let mut ex = ex.bind_lights(&lights).unwrap();
        let e = ex
            .targets
            .record(&ex.scene, &mut gpu.device.create_command_encoder(&Default::default()))
            .unwrap_err()
            .to_string();
        assert!(e.contains("prepare"), "{e}");
        update(&mut ex, &moved);
        ex.targets.prepare(&mut ex.scene, &ex.state).unwrap();
        let (mut a, mut b) = (
            gpu.device.create_command_encoder(&Default::default()),
            gpu.device.create_command_encoder(&Default::default()),
        );
        ex.targets.record(&ex.scene, &mut a).unwrap();
        ex.targets.record(&ex.scene, &mut b).unwrap();
        gpu.queue.submit([a.finish(), b.finish()]);
        gpu.wait().unwrap();
        let twice = ex.inspect().read_visibilities().unwrap().rgba;
        assert!(
            twice == fresh(&c, &moved),
            "{t} on {sc}: recorded twice, the frame differs from one recording"
        );
    }
}

/// Issue 49: more than four lights on one set of targets. Six lights (the three of
/// `scenes/three-lights.ron` and three moved copies of its rectangle and sphere) gather
/// their visibilities four to an RGBA layer: light `l`'s in layer `l / 4`, channel `l % 4`,
/// bit for bit what the light bound alone gives (a copy of its f32 visibility), the unused
/// channels of the last layer 0; the frame's colour is the mean of the six lights' colours
/// within one 8-bit quantum (the mean of six 8-bit values lies between two codes, and the
/// store may round to either). Seventeen lights are refused, naming the limit.
#[test]
fn more_than_four_lights_gather_four_to_a_layer_and_frame_as_each_alone() {
    use sshc_runtime::gpu::MAX_LIGHTS;
    use sshc_runtime::light::glam::Vec3;
    let mut six = scene("three-lights", 32, 64);
    let [rect, sphere] = [six.lights[0].clone(), six.lights[1].clone()];
    six.lights.extend([
        rect.translated(Vec3::new(1.2, 0.3, -0.8)),
        sphere.translated(Vec3::new(-1.5, 0.4, 0.3)),
        sphere.translated(Vec3::new(-0.6, 0.2, -1.9)),
    ]);
    for t in ["pcf", "pcss"] {
        let c = compile(t);
        let lights = all_lights(&six, &c);
        assert_eq!(lights.len(), 6);
        let loaded = Loaded::new(gpu(), c.graph.clone(), c.shaders.clone()).unwrap_or_else(|e| panic!("{t}: {e}"));
        let mut ex = loaded.bind_lights(&lights).unwrap_or_else(|e| panic!("{t}: {e}"));
        ex.run_frame().unwrap_or_else(|e| panic!("{t}: {e}"));
        let layers = [0, 1].map(|k| ex.inspect().read_visibility_layer(k).unwrap_or_else(|e| panic!("{t}: {e}")));
        assert!(ex.inspect().read_visibility_layer(2).is_err(), "{t}: six lights fill two layers");
        assert!(
            layers[1].rgba.iter().all(|p| p[2] == 0.0 && p[3] == 0.0),
            "{t}: the second layer's unused channels"
        );
        let combined = ex
            .inspect()
            .read_camera(CameraOutput::Color)
            .unwrap_or_else(|e| panic!("{t}: {e}"))
            .rgba;
        let mut sum = vec![[0f32; 4]; combined.len()];
        let mut differ = 0;
        for (l, one) in lights.iter().enumerate() {
            let mut alone = loaded.bind_scene(one).unwrap_or_else(|e| panic!("{t}: {e}"));
            alone.run_frame().unwrap_or_else(|e| panic!("{t}: {e}"));
            let v = alone.inspect().read_camera(CameraOutput::Visibility).unwrap().channel(0);
            let gathered = layers[l / 4].channel(l % 4);
            assert!(
                v.iter().zip(&gathered).all(|(a, b)| a.to_bits() == b.to_bits()),
                "{t}: light {l}'s gathered visibility differs from the light alone"
            );
            if l > 0 && gathered != layers[0].channel(0) {
                differ += 1;
            }
            let color = alone.inspect().read_camera(CameraOutput::Color).unwrap().rgba;
            for (s, c) in sum.iter_mut().zip(&color) {
                for k in 0..4 {
                    s[k] += c[k];
                }
            }
        }
        assert!(
            differ >= 4,
            "{t}: the lights should shade differently ({differ} of 5 differ from light 0)"
        );
        for (i, (s, c)) in sum.iter().zip(&combined).enumerate() {
            for k in 0..3 {
                let mean = s[k] / 6.0;
                // one 8-bit quantum, and f32 rounding of a sum of six values in [0, 1]
                assert!(
                    (mean - c[k]).abs() <= 1.0 / 255.0 + 8.0 * f32::EPSILON,
                    "{t}: pixel {i} channel {k}: {} against the mean {mean}",
                    c[k]
                );
            }
        }
    }
    // more than a frame combines: refused by the runtime, naming the limit
    let c = compile("pcf");
    let one = all_lights(&six, &c).remove(0);
    let loaded = Loaded::new(gpu(), c.graph.clone(), c.shaders.clone()).unwrap();
    let Err(e) = loaded.bind_lights(&vec![one; MAX_LIGHTS + 1]) else {
        panic!("17 lights are refused")
    };
    assert!(e.to_string().contains(&format!("a frame combines 1 to {MAX_LIGHTS} lights")), "{e}");
}

/// Issue 49: the lights of one set of targets share their shadow-map-sized textures (made
/// once, from a pool keyed by declaration; transient ones always), since each light's
/// passes run before the next light's and nothing after them reads those textures. With
/// the three lights of `scenes/three-lights.ron`, every technique that renders them frames
/// bit for bit as with each light's own textures (the old layout, `share_light_textures`
/// false), and holds exactly two lights' shadow-map-sized textures fewer. The figure, at
/// the scene file's sizes, is written to `target/embedding/light-memory.md`
/// (docs/embedding.md).
#[test]
fn three_lights_share_their_shadow_textures_and_frame_as_lights_with_their_own() {
    use sshc_runtime::graph::Extent;
    let mut table = String::from(
        "| technique | before (each light every texture), MiB | each light its own, transients shared, MiB | now (shared by the lights), MiB | now / before |\n|---|---|---|---|---|\n",
    );
    let mib = |b: u64| b as f64 / 1048576.0;
    let total = |ex: &Bound| ex.inspect().memory().iter().map(|m| m.1).sum::<u64>();
    let mut ran = 0;
    for t in techniques() {
        let c = compile(&t);
        // the per-sample techniques sample a segment light, which the scene has not
        if sshc_lab::bind::graph_samples(&c.graph) > 0 {
            continue;
        }
        let mut loaded = Loaded::new(gpu(), c.graph.clone(), c.shaders.clone()).unwrap_or_else(|e| panic!("{t}: {e}"));
        let small = all_lights(&scene("three-lights", 32, 64), &c);
        let frame = |loaded: &Loaded| {
            let mut ex = loaded.bind_lights(&small).unwrap_or_else(|e| panic!("{t}: {e}"));
            ex.run_frame().unwrap_or_else(|e| panic!("{t}: {e}"));
            let v = ex.inspect().read_visibilities().unwrap_or_else(|e| panic!("{t}: {e}")).rgba;
            let c = ex
                .inspect()
                .read_camera(CameraOutput::Color)
                .unwrap_or_else(|e| panic!("{t}: {e}"))
                .rgba;
            (v, c)
        };
        let shared = frame(&loaded);
        loaded.limits.share_light_textures = false;
        let own = frame(&loaded);
        assert!(shared == own, "{t}: lights sharing their textures frame differently");
        // the figure, at the file's sizes (nothing run: the bytes are the targets' own)
        let file = Scene::load(root().join("scenes/three-lights.ron")).unwrap();
        let lights = all_lights(&file, &c);
        let before = total(&loaded.bind_lights(&lights).unwrap_or_else(|e| panic!("{t}: {e}")));
        loaded.limits.share_light_textures = true;
        let ex = loaded.bind_lights(&lights).unwrap_or_else(|e| panic!("{t}: {e}"));
        let now = total(&ex);
        let per_light: u64 = ex
            .inspect()
            .memory()
            .iter()
            .filter(|(n, _)| n.ends_with("(shared by the lights)"))
            .map(|m| m.1)
            .sum();
        let bytes = |transient: bool| -> u64 {
            c.graph
                .textures
                .iter()
                .filter(|d| d.extent == Extent::ShadowMap && (transient || !d.transient))
                .map(|d| {
                    let layers = u64::from(d.array_layers());
                    let texels = u64::from(file.shadow_map).pow(2) * layers * u64::from(d.format.bytes_per_texel());
                    if d.mips { texels * 4 / 3 } else { texels }
                })
                .sum()
        };
        assert_eq!(per_light, bytes(true), "{t}: the shared textures are the shadow-map-sized ones");
        // transient textures (a separable filter's intermediate) were one before as well
        assert_eq!(before - now, 2 * bytes(false), "{t}: two lights' shadow-map-sized textures fewer");
        // the old executor's layout: every texture, transient ones too, once per light
        let old = before + 2 * (bytes(true) - bytes(false));
        table.push_str(&format!(
            "| {t} | {:.1} | {:.1} | {:.1} | {:.2} |\n",
            mib(old),
            mib(before),
            mib(now),
            now as f64 / old as f64
        ));
        ran += 1;
    }
    assert!(ran >= 15, "{ran} techniques");
    let dir = root().join("target").join("embedding");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("light-memory.md"), &table).unwrap();
}

/// Issue 49: cameras as hosts build them. An infinite perspective (no far plane) runs as
/// it is; a reverse-Z one (depth 1 near, towards 0 far, Bevy's default) is given through
/// `Camera::from_reverse_z`, which keeps x, y and w bit for bit, so every pixel sees what
/// the forward infinite camera's sees: the frames are equal bit for bit. A reverse-Z matrix
/// given as it is would draw the farthest surfaces: it is refused, saying what to call.
#[test]
fn infinite_and_reverse_z_cameras_render_as_the_forward_camera() {
    use sshc_runtime::gpu::Camera;
    use sshc_runtime::light::{glam::Vec3, look_at, perspective_infinite, perspective_infinite_reverse};
    for t in ["pcss", "penumbra-limit-maps"] {
        let c = compile(t);
        let s = inputs(&scene("triangle", 32, 64), &c);
        let loaded = Loaded::new(gpu(), c.graph.clone(), c.shaders.clone()).unwrap();
        let mut ex = loaded.bind_scene(&s).unwrap_or_else(|e| panic!("{t}: {e}"));
        let eye = Vec3::new(1.9, 1.0, 0.6);
        let view = look_at(eye, Vec3::new(0.0, 0.1, 0.0), Vec3::Y);
        let fov = 40f32.to_radians();
        let mut frame = |camera: Camera| {
            ex.state.camera = camera;
            ex.run_frame().map(|_| ex.inspect().read_visibilities().unwrap().rgba)
        };
        let forward = frame(Camera {
            view_proj: (perspective_infinite(fov, 1.0, 0.05) * view).to_cols_array(),
            position: eye.to_array(),
        })
        .unwrap_or_else(|e| panic!("{t}: {e}"));
        assert!(forward.iter().any(|p| p[0] < 0.5), "{t}: no shadow in view");
        let reversed = (perspective_infinite_reverse(fov, 1.0, 0.05) * view).to_cols_array();
        let mapped = frame(Camera::from_reverse_z(reversed, eye.to_array())).unwrap_or_else(|e| panic!("{t}: {e}"));
        assert!(mapped == forward, "{t}: the reverse-Z camera, mapped, sees another frame");
        let e = frame(Camera {
            view_proj: reversed,
            position: eye.to_array(),
        })
        .unwrap_err()
        .to_string();
        assert!(e.contains("reverse-Z") && e.contains("Camera::from_reverse_z"), "{t}: {e}");
    }
}

/// Issue 49: a host's mesh added (a box spawned beside the triangle) is a new scene under
/// the same targets: `Targets::set_scene` keeps every texture (the shadow-map-sized ones
/// are the same wgpu objects), takes the new scene's draws and edges, binds again only the
/// steps that bind the scene (`Targets::step_bindings_made`), and the frame equals
/// fresh targets on the new scene, bit for bit; removing the box again gives the first
/// frame back. For a raster technique and a Geometry one (its edges and generated buffers
/// follow the scene).
#[test]
fn a_mesh_added_or_removed_keeps_the_targets_and_frames_as_fresh_ones() {
    use sshc_runtime::gpu::{FrameState, IDENTITY, Instance, Scene as Uploaded, Sizes, Targets, Technique};
    use sshc_runtime::graph::ValidGraph;
    let mut kept_some = false;
    for t in ["pcss", "penumbra-limit-maps"] {
        let c = compile(t);
        let s = inputs(&scene("triangle", 32, 64), &c);
        let technique = Technique::new(gpu(), ValidGraph::try_from(c.graph.clone()).unwrap(), c.shaders.clone()).unwrap();
        let first = geometry_of(&s, [0.0; 3]);
        let mut more = first.clone();
        more.meshes.push(box_mesh(0.08));
        let mut at = IDENTITY;
        (at[12], at[14]) = (-0.3, 0.25);
        more.instances.push(Instance {
            name: "spawned box".into(),
            mesh: more.meshes.len() - 1,
            transform: at,
            casts: true,
            receives: true,
            moves: true,
        });
        let state = FrameState::of_inputs(&technique, &s);
        let frame = |targets: &mut Targets, scene: &mut Uploaded| {
            targets.run_frame(scene, &state).unwrap_or_else(|e| panic!("{t}: {e}"));
            targets.inspect().read_visibilities().unwrap_or_else(|e| panic!("{t}: {e}")).rgba
        };
        let fresh = |g: &sshc_runtime::gpu::Geometry| {
            let mut scene = Uploaded::upload(gpu(), g, &[&technique]).unwrap();
            let mut targets = Targets::new(&technique, &scene, &state, Sizes::of(&s)).unwrap();
            frame(&mut targets, &mut scene)
        };
        let mut scene = Uploaded::upload(gpu(), &first, &[&technique]).unwrap();
        let mut targets = Targets::new(&technique, &scene, &state, Sizes::of(&s)).unwrap();
        let before = frame(&mut targets, &mut scene);
        let kept: Vec<(String, wgpu::Texture)> = c
            .graph
            .textures
            .iter()
            .filter(|d| !d.format.is_table())
            .map(|d| (d.name.clone(), targets.texture(&d.name).unwrap().clone()))
            .collect();
        let visibility = targets.visibility().clone();
        // spawned: the old scene's targets refuse the new scene until it is set
        let mut spawned = Uploaded::upload(gpu(), &more, &[&technique]).unwrap();
        assert!(targets.prepare(&mut spawned, &state).is_err(), "{t}");
        let bound_before = targets.step_bindings_made();
        targets.set_scene(&spawned).unwrap_or_else(|e| panic!("{t}: {e}"));
        // only the steps that bind the scene are bound again (its draws from the light and
        // the camera, a Geometry pass's edges, generated buffers and their draws): every
        // other step keeps its bind groups and bundles
        use sshc_runtime::graph::Draw;
        let scene_steps = c
            .graph
            .passes
            .iter()
            .flat_map(|p| &p.steps)
            .filter(|st| {
                matches!(
                    st.draw,
                    Draw::SceneFromLight
                        | Draw::SceneFromCamera
                        | Draw::CameraGBuffer
                        | Draw::Silhouettes { .. }
                        | Draw::Primitives { .. }
                        | Draw::Discontinuities { .. }
                )
            })
            .count() as u64;
        let all_steps = c.graph.passes.iter().map(|p| p.steps.len()).sum::<usize>() as u64;
        // PCSS's two steps both bind the scene; penumbra limit maps' Map and Filter steps do not
        kept_some |= scene_steps < all_steps;
        assert_eq!(
            targets.step_bindings_made() - bound_before,
            scene_steps,
            "{t}: steps bound again by set_scene"
        );
        let with_box = frame(&mut targets, &mut spawned);
        assert!(with_box != before, "{t}: the spawned box casts nothing (a test of nothing)");
        assert!(
            with_box == fresh(&more),
            "{t}: a mesh added differs from fresh targets on the new scene"
        );
        for (name, old) in &kept {
            assert!(targets.texture(name).unwrap() == old, "{t}: `{name}` was made again");
        }
        assert!(targets.visibility() == &visibility, "{t}: the visibility was made again");
        // despawned
        targets.set_scene(&scene).unwrap_or_else(|e| panic!("{t}: {e}"));
        assert!(frame(&mut targets, &mut scene) == before, "{t}: the box removed again differs");
        if t == "penumbra-limit-maps" {
            assert!(spawned.edge_counts().unwrap().edges > scene.edge_counts().unwrap().edges);
        }
    }
    assert!(kept_some, "every step of every technique binds the scene (a test of nothing)");
}

/// Issue 49: a host's mesh or instance added or removed in place (`Scene::add_mesh`,
/// `add_instance`, `remove_instance`, `remove_mesh`), without uploading or binding the
/// rest again. Spawned boxes (moving instances of a mesh already uploaded), a static box in
/// world space, a moving instance of a mesh uploaded for world space only (its vertices
/// copied on the GPU), then a new mesh: each frames as a fresh upload of the same geometry,
/// bit for bit (the same shaders place the same transforms). The scene's buffers grow at
/// most twofold, so the spawn after a growth makes no buffer: for PCSS its targets then
/// take the change by recording their scene-drawing bundles again, with no bind group made
/// (`Targets::step_bindings_made`) and wgpu's live buffers and bind groups unchanged. A
/// new mesh uploads its own bytes only (its vertices, indices and, for penumbra limit
/// maps, edge adjacency), an instance its 256-byte record. Penumbra limit maps' edges
/// follow (its classification binds again), a removed instance's edges are zeroed holes;
/// what cannot be done is refused, saying why.
#[test]
fn a_mesh_or_instance_added_or_removed_in_place_frames_as_a_fresh_upload() {
    use sshc_runtime::adjacency::Adjacency;
    use sshc_runtime::gpu::{FrameState, IDENTITY, Instance, Scene as Uploaded, Sizes, Targets, Technique};
    use sshc_runtime::graph::ValidGraph;
    let gpu = gpu();
    let counts = || {
        let c = gpu.device.get_internal_counters().hal;
        (c.buffers.read(), c.bind_groups.read())
    };
    for t in ["pcss", "penumbra-limit-maps"] {
        let c = compile(t);
        let s = inputs(&scene("triangle", 32, 64), &c);
        let technique = Technique::new(gpu, ValidGraph::try_from(c.graph.clone()).unwrap(), c.shaders.clone()).unwrap();
        let mut g = geometry_of(&s, [0.0; 3]);
        // the first part stays in world space: its mesh is uploaded for world space only
        g.instances[0].moves = false;
        let world_mesh = g.instances[0].mesh;
        assert!(g.instances.iter().all(|i| i.mesh != world_mesh || !i.moves), "{t}");
        g.meshes.push(box_mesh(0.06));
        let boxed = g.meshes.len() - 1;
        let spawn = |name: &str, x: f32, z: f32, moves: bool| {
            let mut at = IDENTITY;
            (at[12], at[14]) = (x, z);
            Instance {
                name: name.into(),
                mesh: boxed,
                transform: at,
                casts: true,
                receives: true,
                moves,
            }
        };
        g.instances.push(spawn("box 0", -0.3, 0.25, true));
        let state = FrameState::of_inputs(&technique, &s);
        let frame = |targets: &mut Targets, scene: &mut Uploaded| {
            targets.run_frame(scene, &state).unwrap_or_else(|e| panic!("{t}: {e}"));
            targets.inspect().read_visibilities().unwrap_or_else(|e| panic!("{t}: {e}")).rgba
        };
        let fresh = |g: &Geometry| {
            let mut scene = Uploaded::upload(gpu, g, &[&technique]).unwrap();
            let mut targets = Targets::new(&technique, &scene, &state, Sizes::of(&s)).unwrap();
            frame(&mut targets, &mut scene)
        };
        let mut scene = Uploaded::upload(gpu, &g, &[&technique]).unwrap();
        let mut targets = Targets::new(&technique, &scene, &state, Sizes::of(&s)).unwrap();
        let first = frame(&mut targets, &mut scene);
        let mut shadows = vec![first.clone()];
        // spawned boxes: the first may grow the buffers, those after fit in the room left
        for (k, (x, z)) in [(0.3, 0.2), (0.1, 0.4), (-0.1, 0.45)].into_iter().enumerate() {
            let inst = spawn(&format!("box {}", k + 1), x, z, true);
            let (grown, bound, live) = (scene.buffers_grown(), targets.step_bindings_made(), counts());
            let before = scene.bytes_added();
            assert_eq!(scene.add_instance(&inst).unwrap(), g.instances.len(), "{t}");
            assert_eq!(scene.bytes_added() - before, 256, "{t}: an instance writes its record only");
            g.instances.push(inst);
            assert!(
                targets
                    .prepare(&mut scene, &state)
                    .unwrap_err()
                    .to_string()
                    .contains("Targets::set_scene"),
                "{t}"
            );
            targets.set_scene(&scene).unwrap_or_else(|e| panic!("{t}: {e}"));
            let now = frame(&mut targets, &mut scene);
            assert!(now == fresh(&g), "{t}: box {} spawned differs from a fresh upload", k + 1);
            assert!(!shadows.contains(&now), "{t}: box {} casts nothing (a test of nothing)", k + 1);
            shadows.push(now);
            if k > 0 {
                assert_eq!(scene.buffers_grown(), grown, "{t}: box {} grew a buffer", k + 1);
                if t == "pcss" {
                    assert_eq!(targets.step_bindings_made(), bound, "{t}: a step was bound again");
                    assert_eq!(counts(), live, "{t}: buffers or bind groups made");
                }
            }
        }
        // a static box in world space: drawn from its mesh, its edges placed exactly
        let still = spawn("still box", 0.0, 0.0, false);
        let mut still = Instance {
            transform: IDENTITY,
            ..still
        };
        scene.add_instance(&still).unwrap_or_else(|e| panic!("{t}: {e}"));
        g.instances.push(still.clone());
        targets.set_scene(&scene).unwrap();
        assert!(frame(&mut targets, &mut scene) == fresh(&g), "{t}: the static box differs");
        // a moving instance of a mesh uploaded for world space only
        still.mesh = world_mesh;
        still.moves = true;
        still.transform[13] = 0.05;
        let copied = scene.add_instance(&still);
        if t == "pcss" {
            copied.unwrap_or_else(|e| panic!("{t}: {e}"));
            g.instances.push(still);
            targets.set_scene(&scene).unwrap();
            assert!(
                frame(&mut targets, &mut scene) == fresh(&g),
                "{t}: the world-space mesh placed differs"
            );
        } else {
            // its adjacency was not kept where the placement step reads it
            let e = copied.unwrap_err().to_string();
            assert!(
                e.contains("Scene::add_mesh") && e.contains(&format!("mesh {world_mesh}")),
                "{t}: {e}"
            );
            assert_eq!(scene.instance_count(), g.instances.len(), "{t}: a refusal changed the scene");
        }
        // removed: box 2 (the others move down one place), a hole among the edges
        scene.remove_instance(2).unwrap();
        g.instances.remove(2);
        targets.set_scene(&scene).unwrap();
        assert!(frame(&mut targets, &mut scene) == fresh(&g), "{t}: box 2 removed differs");
        // a new mesh: its own bytes
        let tall = box_mesh(0.04);
        let mut bytes = 24 * tall.positions.len() + 4 * tall.indices.len();
        if t == "penumbra-limit-maps" {
            let tris: Vec<[[f32; 3]; 3]> = tall
                .indices
                .chunks(3)
                .map(|f| [0, 1, 2].map(|k| tall.positions[f[k] as usize]))
                .collect();
            let a = Adjacency::build(&tris, std::iter::once(0..tris.len()));
            bytes += 48 * a.edges.len() + 16 * a.planes.len() + 4 * a.edge_faces.len();
        }
        let before = scene.bytes_added();
        let mesh = scene.add_mesh(&tall).unwrap();
        assert_eq!(
            scene.bytes_added() - before,
            bytes as u64,
            "{t}: a new mesh uploads its own bytes only"
        );
        g.meshes.push(tall);
        assert_eq!(mesh, g.meshes.len() - 1, "{t}");
        let tower = Instance {
            mesh,
            ..spawn("tower", 0.1, 0.3, true)
        };
        scene.add_instance(&tower).unwrap();
        g.instances.push(tower);
        targets.set_scene(&scene).unwrap();
        assert!(frame(&mut targets, &mut scene) == fresh(&g), "{t}: the new mesh differs");
        // every spawned box removed, then its mesh: the first frame's boxes but box 0
        let e = scene.remove_mesh(boxed).unwrap_err().to_string();
        assert!(e.contains("remove its instances first"), "{t}: {e}");
        while let Some(k) = g.instances.iter().rposition(|i| i.mesh == boxed) {
            scene.remove_instance(k).unwrap();
            g.instances.remove(k);
        }
        scene.remove_mesh(boxed).unwrap();
        let e = scene.add_instance(&spawn("late", 0.0, 0.0, true)).unwrap_err().to_string();
        assert!(e.contains("does not hold"), "{t}: {e}");
        targets.set_scene(&scene).unwrap();
        let last = frame(&mut targets, &mut scene);
        // the fresh geometry without the box mesh: the tower's mesh index moves down one
        let mut fewer = g.clone();
        fewer.meshes.remove(boxed);
        for i in &mut fewer.instances {
            i.mesh -= usize::from(i.mesh > boxed);
        }
        assert!(last == fresh(&fewer), "{t}: the boxes removed differ");
        assert_eq!(scene.mesh_count(), fewer.meshes.len(), "{t}");
    }
}

/// Issue 49: one loaded technique serving two views of one scene (split screen): the
/// technique (its shader modules and pipelines) is made once; each half of the screen is
/// its own `Targets` (its own camera, a half-width size), both prepared and recorded into
/// one encoder and submitted together. Making the second view's targets creates no
/// pipeline, and each half frames bit for bit as that camera bound alone.
#[test]
fn one_loaded_technique_serves_two_views_recorded_in_one_submission() {
    use sshc_runtime::gpu::{Camera, FrameState, Scene as Uploaded, Sizes, Targets, Technique};
    use sshc_runtime::graph::ValidGraph;
    use sshc_runtime::light::{glam::Vec3, look_at, perspective};
    let gpu = gpu();
    let pipelines = || {
        let c = gpu.device.get_internal_counters().hal;
        (c.render_pipelines.read(), c.compute_pipelines.read())
    };
    for t in ["pcss", "cssm", "penumbra-limit-maps"] {
        let c = compile(t);
        let s = inputs(&scene("contact", 32, 64), &c);
        let technique = Technique::new(gpu, ValidGraph::try_from(c.graph.clone()).unwrap(), c.shaders.clone()).unwrap();
        let mut scene = Uploaded::upload(gpu, &geometry_of(&s, [0.0; 3]), &[&technique]).unwrap();
        // the two halves: 24 x 32 each, from two sides of the scene
        let sizes = Sizes {
            camera: (24, 32),
            shadow: s.shadow_size,
        };
        let camera = |eye: Vec3| Camera {
            view_proj: (perspective(45f32.to_radians(), 24.0 / 32.0, 0.05, 20.0) * look_at(eye, Vec3::new(0.0, 0.2, 0.0), Vec3::Y))
                .to_cols_array(),
            position: eye.to_array(),
        };
        let states: Vec<FrameState> = [Vec3::new(1.8, 1.4, 1.6), Vec3::new(-1.6, 1.2, 1.9)]
            .into_iter()
            .map(|eye| {
                let mut st = FrameState::of_inputs(&technique, &s);
                st.camera = camera(eye);
                st
            })
            .collect();
        let made = pipelines();
        let mut views: Vec<Targets> = states
            .iter()
            .map(|st| Targets::new(&technique, &scene, st, sizes).unwrap_or_else(|e| panic!("{t}: {e}")))
            .collect();
        assert_eq!(pipelines(), made, "{t}: a view's targets made a pipeline");
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        for (v, st) in views.iter_mut().zip(&states) {
            v.prepare(&mut scene, st).unwrap_or_else(|e| panic!("{t}: {e}"));
            v.record(&scene, &mut encoder).unwrap_or_else(|e| panic!("{t}: {e}"));
        }
        gpu.queue.submit([encoder.finish()]);
        gpu.wait().unwrap();
        let halves: Vec<Vec<[f32; 4]>> = views
            .iter()
            .map(|v| v.inspect().read_visibilities().unwrap_or_else(|e| panic!("{t}: {e}")).rgba)
            .collect();
        assert!(halves[0] != halves[1], "{t}: the two cameras see the same (a test of nothing)");
        for (half, st) in halves.iter().zip(&states) {
            assert!(half.iter().any(|p| p[0] < 0.5), "{t}: no shadow in a half");
            let mut alone = Targets::new(&technique, &scene, st, sizes).unwrap();
            alone.run_frame(&mut scene, st).unwrap_or_else(|e| panic!("{t}: {e}"));
            let want = alone.inspect().read_visibilities().unwrap().rgba;
            assert!(*half == want, "{t}: a half of the split screen differs from its camera alone");
        }
    }
}

/// `Targets::recorded_passes` counts what `record` encodes: a pass per raster step, per
/// level of a fragment mip chain and per light, one compute pass for the compute steps of
/// a graph pass that follow one another (`joins` in targets.rs), and the lights' combine.
/// The bundled mipmapped techniques schedule their chain as compute (one pass for every
/// level); as fragment the chain is one render pass per level below the base (6 at a 64^2
/// map).
#[test]
fn the_passes_recorded_follow_the_steps_the_levels_and_the_lights() {
    let one = scene("contact", 32, 64);
    let three = scene("three-lights", 32, 64);
    let passes = |c: &sshc::Compiled, lights: &[SceneInputs]| {
        let loaded = Loaded::new(gpu(), c.graph.clone(), c.shaders.clone()).unwrap_or_else(|e| panic!("{e}"));
        let ex = loaded.bind_lights(lights).unwrap_or_else(|e| panic!("{e}"));
        ex.targets.recorded_passes()
    };
    let scheduled = |t: &str, schedule: &[(&str, &str)]| {
        sshc::compile_str(
            &support::technique_source(t),
            &sshc::CompileOptions {
                schedule: schedule.iter().map(|(p, s)| (p.to_string(), s.to_string())).collect(),
                ..Default::default()
            },
        )
        .unwrap_or_else(|d| panic!("{}", d.render(t, &support::technique_source(t))))
    };
    // hard: depth, shade; VSM: depth, moments, two blur steps, the chain, shade; CSSM:
    // depth, basis (two steps), four blur steps (its two textures' layers packed two steps
    // an axis), the chains of its two textures in one compute pass, shade
    for (t, want) in [("hard", 2), ("vsm", 6), ("cssm", 9)] {
        let c = compile(t);
        assert_eq!(passes(&c, &[inputs(&one, &c)]), want, "{t}, one light");
        assert_eq!(
            passes(&c, &all_lights(&three, &c)),
            3 * want + 1,
            "{t}, three lights and their combine"
        );
    }
    // the linear light's two samples: a depth pass each; each Geometry pass a compute step
    // and a draw per sample, but the first sample has no previous and the last no next
    // sample to find skins in: no compute pass for those (their draws still clear)
    let c = compile("linear-light");
    let linear = scene("linear", 32, 64);
    assert_eq!(passes(&c, &[inputs(&linear, &c)]), 2 + 3 + 3 + 1, "linear-light");
    // CSSM's basis and blur as compute: each graph pass's steps in one compute pass
    let compute = scheduled("cssm", &[("basis", "compute"), ("blur", "compute")]);
    assert_eq!(passes(&compute, &[inputs(&one, &compute)]), 5, "cssm, basis and blur as compute");
    let fragment = scheduled("vsm", &[("mips", "fragment")]);
    assert_eq!(passes(&fragment, &[inputs(&one, &fragment)]), 5 + 6, "vsm, its chain as fragment");
}
