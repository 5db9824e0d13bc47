//! A host renderer with sshc's shadows in it (docs/embedding.md walks through it).
//!
//! The host opens its own wgpu device, uploads the bundled bunny and a floor as its own
//! indexed meshes (the bunny instanced nine times, the middle one turning), lets sshc
//! render the shadows of a sphere light orbiting above, samples sshc's visibility texture in
//! its own lighting pass,
//! and writes each frame as `OUT_DIR/frame-NNN.png`, and all of them side by side as
//! `OUT_DIR/strip.png` (when that is at most 16384 pixels wide). It prints the median CPU time of
//! sshc's share of each frame (the light and camera updates and the recording), in µs.
//!
//! ```text
//! cargo run --release -p sshc-runtime --example host -- OUT_DIR [--frames N] [--technique T.ron]
//! ```

use clap::Parser;
use glam::{Mat4, Vec3};
use sshc_runtime::gpu::{
    Camera, Fit, FrameState, Geometry, Gpu, INSTALL_HINT, Instance, LightInputs, Mesh, Requirements, Scene, Sizes, Targets, Technique,
};
use sshc_runtime::graph::ValidGraph;
use sshc_runtime::light::Light;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Parser)]
#[command(about = "A host renderer that samples sshc's shadows in its own lighting pass")]
struct Args {
    /// Folder for frame-NNN.png (created if missing).
    out_dir: PathBuf,
    /// Frames to render (the light goes once around in 24).
    #[arg(long, default_value_t = 8)]
    frames: u32,
    /// The technique to compile (a file of `techniques/`).
    #[arg(long, default_value = "techniques/pcss.ron")]
    technique: PathBuf,
    /// Image side, pixels.
    #[arg(long, default_value_t = 256)]
    size: u32,
}

const SHADOW_MAP: u32 = 1024;
/// The host's render target.
const COLOR: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

fn main() {
    if let Err(e) = run(Args::parse()) {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}

fn run(args: Args) -> Result<(), String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    // The technique, compiled on the fly (a host could load a compiled graph instead).
    let technique = if args.technique.is_absolute() {
        args.technique.clone()
    } else {
        root.join(&args.technique)
    };
    let source = std::fs::read_to_string(&technique).map_err(|e| format!("{}: {e}", technique.display()))?;
    let compiled = sshc::compile_str(&source, &Default::default()).map_err(|d| d.render(&technique.display().to_string(), &source))?;

    // 1. The host's device, with what the graph needs.
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
        backends: wgpu::Backends::VULKAN,
        ..wgpu::InstanceDescriptor::new_without_display_handle()
    });
    let adapter =
        pollster::block_on(instance.request_adapter(&Default::default())).map_err(|e| format!("no GPU adapter: {e}; {INSTALL_HINT}"))?;
    let needs = Requirements::of(&compiled.graph);
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("host"),
        required_features: needs.features() | (adapter.features() & wgpu::Features::TIMESTAMP_QUERY),
        required_limits: needs.limits(wgpu::Limits::default()),
        ..Default::default()
    }))
    .map_err(|e| format!("the adapter cannot give what `{}` needs: {e}", compiled.graph.technique))?;
    let gpu = Gpu::from_host(&adapter, device.clone(), queue.clone());

    // 2. The host's meshes: the bunny (instanced on a 3 x 3 grid) and a floor.
    let bunny = load_obj(&root.join("scenes/bunny.obj"), 0.1)?;
    let floor = Mesh {
        name: "floor".into(),
        positions: vec![[-3.0, 0.0, -3.0], [3.0, 0.0, -3.0], [3.0, 0.0, 3.0], [-3.0, 0.0, 3.0]],
        normals: vec![[0.0, 1.0, 0.0]; 4],
        indices: vec![0, 2, 1, 0, 3, 2],
    };
    let mut instances = vec![Instance {
        name: "floor".into(),
        mesh: 1,
        transform: Mat4::IDENTITY.to_cols_array(),
        casts: false,
        receives: true,
        moves: false,
    }];
    for k in 0..9 {
        let at = Vec3::new((k % 3) as f32 - 1.0, 0.0, (k / 3) as f32 - 1.0) * 1.4;
        instances.push(Instance {
            name: format!("bunny {k}"),
            mesh: 0,
            transform: (Mat4::from_translation(at) * Mat4::from_rotation_y(k as f32 * 0.7)).to_cols_array(),
            casts: true,
            receives: true,
            moves: true,
        });
    }
    let geometry = Geometry {
        meshes: vec![bunny, floor],
        instances,
    };
    // the middle bunny turns; the others stay
    let mut transforms: Vec<[f32; 16]> = geometry.instances.iter().map(|i| i.transform).collect();
    let turning = 5;

    // 3. sshc's stages, each made once: the technique (pipelines), the scene (meshes,
    // instances), the targets (textures at the sizes), and the frame's state (plain data).
    let size = (args.size, args.size);
    let camera = camera(size);
    let graph = ValidGraph::try_from(compiled.graph.clone()).map_err(|e| e.to_string())?;
    let technique = Technique::new(&gpu, graph, compiled.shaders.clone()).map_err(|e| e.to_string())?;
    let mut scene = Scene::upload(&gpu, &geometry, &[&technique]).map_err(|e| e.to_string())?;
    let first = LightInputs::fit(&light(0.0), scene.boxes(), Fit::Casters, SHADOW_MAP, 0).map_err(|e| e.to_string())?;
    let mut state = FrameState::new(&technique, camera, vec![first]);
    let sizes = Sizes {
        camera: size,
        shadow: SHADOW_MAP,
    };
    let mut shadows = Targets::new(&technique, &scene, &state, sizes).map_err(|e| e.to_string())?;

    // 4. The host's own lighting pass, reading sshc's visibility.
    let host = HostPass::new(&device, &queue, &geometry, &camera, size, shadows.visibility());

    std::fs::create_dir_all(&args.out_dir).map_err(|e| format!("{}: {e}", args.out_dir.display()))?;
    let mut sshc_us = Vec::new();
    // the strip of every frame side by side, when it stays a picture (at most 16384 wide)
    let strip_width = args.size.checked_mul(args.frames).filter(|w| (1..=16384).contains(w));
    let mut strip = strip_width.map(|w| image::RgbaImage::new(w, args.size));
    for f in 0..args.frames {
        let light = light(f as f32 / 24.0 * std::f32::consts::TAU);
        transforms[turning] = Mat4::from_rotation_y(f as f32 * 0.4).to_cols_array();
        let mut encoder = device.create_command_encoder(&Default::default());
        // sshc's share of the frame: the light and a bunny move, then the passes are recorded
        let t = Instant::now();
        scene.set_transforms(&transforms).map_err(|e| e.to_string())?;
        state.lights[0] = shadows.fit_light(&scene, 0, &light, Fit::Casters).map_err(|e| e.to_string())?;
        shadows.prepare(&mut scene, &state).map_err(|e| e.to_string())?;
        shadows.record(&scene, &mut encoder).map_err(|e| e.to_string())?;
        sshc_us.push(t.elapsed().as_secs_f64() * 1e6);
        host.record(&mut encoder, light.center().unwrap_or(Vec3::Y).extend(1.0).to_array(), &transforms);
        queue.submit([encoder.finish()]);
        let path = args.out_dir.join(format!("frame-{f:03}.png"));
        let frame = host.save(&device, &path)?;
        if let Some(strip) = &mut strip {
            image::imageops::replace(strip, &frame, i64::from(f) * i64::from(args.size), 0);
        }
    }
    match &strip {
        Some(strip) => {
            let path = args.out_dir.join("strip.png");
            strip.save(&path).map_err(|e| format!("{}: {e}", path.display()))?;
        }
        None if args.frames > 0 => println!("no strip.png: {} frames of {} pixels are wider than 16384", args.frames, args.size),
        None => {}
    }
    sshc_us.sort_by(f64::total_cmp);
    let median = sshc_us.get(sshc_us.len() / 2).copied().unwrap_or(f64::NAN);
    println!(
        "{} frames of `{}` on {} into {}: sshc's updates (light, transforms) and recording took {median:.1} µs a frame (median)",
        args.frames,
        compiled.graph.technique,
        gpu.describe(),
        args.out_dir.display()
    );
    Ok(())
}

/// The camera, looking down at the grid of bunnies.
fn camera(size: (u32, u32)) -> Camera {
    let eye = Vec3::new(3.2, 3.4, 4.2);
    let view = glam::camera::rh::view::look_at_mat4(eye, Vec3::new(0.0, 0.2, 0.0), Vec3::Y);
    let proj = glam::camera::rh::proj::directx::perspective(40f32.to_radians(), size.0 as f32 / size.1 as f32, 0.5, 20.0);
    Camera {
        view_proj: (proj * view).to_cols_array(),
        position: eye.to_array(),
    }
}

/// A sphere light of radius 0.15 on a circle above the scene, at angle `a`. The host says
/// only what it is; sshc fits its view to the instances every frame.
fn light(a: f32) -> Light {
    Light::Sphere {
        center: Vec3::new(2.5 * a.cos(), 4.0, 2.5 * a.sin()),
        radius: 0.15,
    }
}

/// An OBJ file's triangles as an indexed mesh, scaled, with smooth normals (the area-
/// weighted mean of the faces around each vertex).
fn load_obj(path: &Path, scale: f32) -> Result<Mesh, String> {
    let (models, _) = tobj::load_obj(
        path,
        &tobj::LoadOptions {
            triangulate: true,
            single_index: true,
            ..Default::default()
        },
    )
    .map_err(|e| format!("{}: {e}", path.display()))?;
    let mut mesh = Mesh {
        name: path.display().to_string(),
        ..Default::default()
    };
    for m in &models {
        let base = mesh.positions.len() as u32;
        mesh.positions
            .extend(m.mesh.positions.chunks_exact(3).map(|p| [p[0] * scale, p[1] * scale, p[2] * scale]));
        mesh.indices.extend(m.mesh.indices.iter().map(|i| base + i));
    }
    let mut normals = vec![Vec3::ZERO; mesh.positions.len()];
    for t in mesh.indices.chunks_exact(3) {
        let p = [0, 1, 2].map(|k| Vec3::from(mesh.positions[t[k] as usize]));
        let n = (p[1] - p[0]).cross(p[2] - p[0]);
        for i in t {
            normals[*i as usize] += n;
        }
    }
    mesh.normals = normals.iter().map(|n| n.normalize_or(Vec3::Y).to_array()).collect();
    Ok(mesh)
}

const HOST_WGSL: &str = "
struct View { view_proj: mat4x4<f32>, light: vec4<f32> }
@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var visibility: texture_2d<f32>;

struct Out { @builtin(position) pos: vec4<f32>, @location(0) world: vec3<f32>, @location(1) normal: vec3<f32> }

@vertex
fn vs(@location(0) p: vec3<f32>, @location(1) n: vec3<f32>,
      @location(2) m0: vec4<f32>, @location(3) m1: vec4<f32>, @location(4) m2: vec4<f32>, @location(5) m3: vec4<f32>) -> Out {
    let model = mat4x4<f32>(m0, m1, m2, m3);
    let world = model * vec4<f32>(p, 1.0);
    var o: Out;
    o.pos = view.view_proj * world;
    o.world = world.xyz;
    o.normal = (model * vec4<f32>(n, 0.0)).xyz;
    return o;
}

@fragment
fn fs(i: Out) -> @location(0) vec4<f32> {
    // sshc's visibility at this pixel: the host's target and sshc's camera share a size
    let v = textureLoad(visibility, vec2<i32>(i.pos.xy), 0).r;
    let l = normalize(view.light.xyz - i.world);
    let diffuse = max(dot(normalize(i.normal), l), 0.0);
    let albedo = vec3<f32>(0.85, 0.8, 0.72);
    return vec4<f32>(albedo * (0.15 + 0.85 * diffuse * v), 1.0);
}
";

/// The host's lighting pass and its read-back.
struct HostPass {
    pipeline: wgpu::RenderPipeline,
    group: wgpu::BindGroup,
    uniform: wgpu::Buffer,
    queue: wgpu::Queue,
    vertices: Vec<wgpu::Buffer>,
    indices: Vec<(wgpu::Buffer, u32)>,
    /// Per instance: its mesh, and its transform's slot in `transforms`.
    draws: Vec<usize>,
    transforms: wgpu::Buffer,
    color: wgpu::Texture,
    color_view: wgpu::TextureView,
    depth: wgpu::TextureView,
    readback: wgpu::Buffer,
    size: (u32, u32),
    view_proj: [f32; 16],
}

impl HostPass {
    fn new(device: &wgpu::Device, queue: &wgpu::Queue, g: &Geometry, camera: &Camera, size: (u32, u32), vis: &wgpu::Texture) -> HostPass {
        use wgpu::util::DeviceExt;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("host lighting"),
            source: wgpu::ShaderSource::Wgsl(HOST_WGSL.into()),
        });
        let vertex_attrs = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3];
        let instance_attrs = wgpu::vertex_attr_array![2 => Float32x4, 3 => Float32x4, 4 => Float32x4, 5 => Float32x4];
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("host lighting"),
            layout: None,
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs"),
                compilation_options: Default::default(),
                buffers: &[
                    Some(wgpu::VertexBufferLayout {
                        array_stride: 24,
                        step_mode: wgpu::VertexStepMode::Vertex,
                        attributes: &vertex_attrs,
                    }),
                    Some(wgpu::VertexBufferLayout {
                        array_stride: 64,
                        step_mode: wgpu::VertexStepMode::Instance,
                        attributes: &instance_attrs,
                    }),
                ],
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
                targets: &[Some(COLOR.into())],
            }),
            multiview_mask: None,
            cache: None,
        });
        let uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("host view"),
            size: 80,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let vis_view = vis.create_view(&Default::default());
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("host lighting"),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: uniform.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&vis_view),
                },
            ],
        });
        let bytes = |v: &[f32]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
        let vertices = g
            .meshes
            .iter()
            .map(|m| {
                let data: Vec<f32> = m
                    .positions
                    .iter()
                    .zip(&m.normals)
                    .flat_map(|(p, n)| p.iter().chain(n).copied())
                    .collect();
                device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some(&m.name),
                    contents: &bytes(&data),
                    usage: wgpu::BufferUsages::VERTEX,
                })
            })
            .collect();
        let indices = g
            .meshes
            .iter()
            .map(|m| {
                let data: Vec<u8> = m.indices.iter().flat_map(|i| i.to_le_bytes()).collect();
                let b = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some(&m.name),
                    contents: &data,
                    usage: wgpu::BufferUsages::INDEX,
                });
                (b, m.indices.len() as u32)
            })
            .collect();
        let transforms: Vec<f32> = g.instances.iter().flat_map(|i| i.transform).collect();
        let transforms = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("host transforms"),
            contents: &bytes(&transforms),
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
        });
        let texture = |format, usage| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: None,
                size: wgpu::Extent3d {
                    width: size.0,
                    height: size.1,
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
        let color = texture(COLOR, wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC);
        let depth = texture(wgpu::TextureFormat::Depth32Float, wgpu::TextureUsages::RENDER_ATTACHMENT).create_view(&Default::default());
        let readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("host read-back"),
            size: (padded_row(size.0) * size.1) as u64,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        HostPass {
            pipeline,
            group,
            uniform,
            queue: queue.clone(),
            vertices,
            indices,
            draws: g.instances.iter().map(|i| i.mesh).collect(),
            transforms,
            color_view: color.create_view(&Default::default()),
            color,
            depth,
            readback,
            size,
            view_proj: camera.view_proj,
        }
    }

    /// The host's lighting pass and the copy of its image, after sshc's passes.
    fn record(&self, encoder: &mut wgpu::CommandEncoder, light: [f32; 4], transforms: &[[f32; 16]]) {
        let mut u: Vec<u8> = self.view_proj.iter().flat_map(|x| x.to_le_bytes()).collect();
        u.extend(light.iter().flat_map(|x| x.to_le_bytes()));
        self.queue.write_buffer(&self.uniform, 0, &u);
        let t: Vec<u8> = transforms.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
        self.queue.write_buffer(&self.transforms, 0, &t);
        {
            let mut rp = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("host lighting"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &self.color_view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color {
                            r: 0.55,
                            g: 0.65,
                            b: 0.8,
                            a: 1.0,
                        }),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &self.depth,
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
            rp.set_pipeline(&self.pipeline);
            rp.set_bind_group(0, &self.group, &[]);
            for (i, &mesh) in self.draws.iter().enumerate() {
                let (indices, count) = &self.indices[mesh];
                rp.set_vertex_buffer(0, self.vertices[mesh].slice(..));
                rp.set_vertex_buffer(1, self.transforms.slice(64 * i as u64..64 * (i as u64 + 1)));
                rp.set_index_buffer(indices.slice(..), wgpu::IndexFormat::Uint32);
                rp.draw_indexed(0..*count, 0, 0..1);
            }
        }
        encoder.copy_texture_to_buffer(
            self.color.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &self.readback,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(padded_row(self.size.0)),
                    rows_per_image: Some(self.size.1),
                },
            },
            wgpu::Extent3d {
                width: self.size.0,
                height: self.size.1,
                depth_or_array_layers: 1,
            },
        );
    }

    /// Wait for the frame, write its image and return it.
    fn save(&self, device: &wgpu::Device, path: &Path) -> Result<image::RgbaImage, String> {
        let slice = self.readback.slice(..);
        slice.map_async(wgpu::MapMode::Read, |_| {});
        device.poll(wgpu::PollType::wait_indefinitely()).map_err(|e| e.to_string())?;
        let data = slice.get_mapped_range().map_err(|e| e.to_string())?;
        let row = padded_row(self.size.0) as usize;
        let mut pixels = Vec::with_capacity((self.size.0 * self.size.1 * 4) as usize);
        for y in 0..self.size.1 as usize {
            pixels.extend_from_slice(&data[y * row..y * row + self.size.0 as usize * 4]);
        }
        drop(data);
        self.readback.unmap();
        let img = image::RgbaImage::from_raw(self.size.0, self.size.1, pixels).ok_or("a frame of the wrong size")?;
        img.save(path).map_err(|e| format!("{}: {e}", path.display()))?;
        Ok(img)
    }
}

/// Bytes of one row in a texture-to-buffer copy (a multiple of 256).
fn padded_row(width: u32) -> u32 {
    (width * 4).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT)
}
