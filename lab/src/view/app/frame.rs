//! One frame: the workers' answers and the files' saves taken, the script stepped, the
//! camera and lights put in the frame's state, the technique's passes recorded and drawn
//! into the window with the panels over them, a screenshot written, the frame presented
//! and timed, the panels' actions applied, and a scripted run ended.

use super::App;
use super::capture::{copy_out, with_words, write_png, write_visibility};
use super::compile::{first_size, same_file};
use super::events::frames_end;
use super::panels::{Action, UiData, panels};
use super::shown::shown;
use super::timing::{median, push};
use crate::view::present::{Part, Present};
use crate::view::state::{self, Mode, Orbit};
use crate::view::worker::{Answer, Worker};
use serde_json::json;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::{Duration, Instant};
use winit::event_loop::ActiveEventLoop;

impl App {
    /// Put the camera and lights as they are now in the frame's state.
    fn update_state(&mut self) -> Result<(), String> {
        if !(self.moved || self.resized) {
            return Ok(());
        }
        self.truth_stale = true;
        self.last_move = self.frame;
        self.sync_scene();
        let scene = &self.scene;
        for ex in [&mut self.ex, &mut self.ex_b].into_iter().flatten() {
            if self.resized {
                // only the camera-sized targets are made again: the geometry, its edges,
                // the shadow maps and the pipelines stay (issue 49); the camera and lights
                // of the new aspect follow below
                ex.targets.resize(scene.camera_size()).map_err(|e| format!("error: {e}"))?;
            }
            if ex.targets.cascades() > 1 {
                // the cascades follow the camera: refitted to its slices in place
                self.args.cascading.refit(ex, scene)?;
                continue;
            }
            // plain state: checked and written by the next frame's prepare
            ex.state.camera = crate::bind::camera(scene);
            // each light's view depends on the geometry and that light alone
            for (l, light) in scene.lights.iter().enumerate() {
                let inputs = crate::bind::light_inputs(scene, light, ex.graph())?;
                match ex.state.lights.get_mut(l) {
                    Some(slot) => *slot = inputs,
                    None => {
                        return Err(format!(
                            "error: light {l}: the view was bound with {} light(s)",
                            ex.state.lights.len()
                        ));
                    }
                }
            }
        }
        self.resized = false;
        self.moved = false;
        Ok(())
    }

    pub(super) fn redraw(&mut self, event_loop: &ActiveEventLoop) -> Result<(), String> {
        if let Some(w) = &mut self.worker {
            // the first graph: wait for it (a window with nothing in it tells nothing)
            let answer = if self.ex.is_none() && self.diagnostics.is_none() {
                w.wait()
            } else {
                w.poll()
            };
            if let Some(a) = answer {
                self.take_answer(a);
            }
        }
        if let Some(a) = self.worker_b.as_mut().and_then(Worker::poll) {
            match a {
                Answer::Ready(r) => {
                    let mut ex = r.bound;
                    if let Some(split) = &mut self.state.split {
                        split.params.retain(|k, v| ex.state.params.set(k, *v).is_ok());
                    }
                    self.resized |= self.view_size() != first_size(&ex);
                    self.moved = true;
                    self.ex_b = Some(ex);
                    self.log.write(self.frame, json!({"event": "compiled", "ok": true, "split": true, "technique": self.state.split.as_ref().map(|s| &s.technique)}));
                }
                Answer::Failed { diagnostics, .. } => {
                    self.log.write(
                        self.frame,
                        json!({"event": "compiled", "ok": false, "split": true, "diagnostics": diagnostics}),
                    );
                    self.diagnostics = Some(format!("the split's right half:\n{diagnostics}"));
                }
            }
        }
        if let Some(watch) = &self.watch {
            let changed = watch.changed(Duration::from_millis(50));
            for p in &changed {
                self.log.write(self.frame, json!({"event": "file changed", "path": p}));
            }
            let scene_changed = changed.iter().any(|p| same_file(p, &self.state.scene));
            if scene_changed {
                match crate::session::load_scene(&self.state.scene, None, None) {
                    Ok(s) => {
                        let size = self.view_size();
                        self.file = (s.camera.clone(), s.lights.clone());
                        self.scene = s;
                        self.state.camera = state::with_size(&self.file.0, size.0, size.1);
                        self.state.lights = self.file.1.clone();
                        self.orbit = Orbit::of(&self.state.camera);
                    }
                    Err(e) => {
                        self.log.write(self.frame, json!({"event": "scene", "ok": false, "diagnostics": e}));
                        self.diagnostics = Some(e);
                    }
                }
            }
            if !changed.is_empty() {
                self.recompile();
                self.recompile_split();
            }
        }
        self.step_script()?;
        self.update_state()?;
        let Some(gfx) = &mut self.gfx else { return Ok(()) };
        let acquire = Instant::now();
        let frame = match gfx.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(f) | wgpu::CurrentSurfaceTexture::Suboptimal(f) => f,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                gfx.surface.configure(&gfx.device, &gfx.config);
                return Ok(());
            }
            other => {
                // a timeout or an occluded window: try again next frame
                let _ = other;
                return Ok(());
            }
        };
        let mut present_ms = acquire.elapsed().as_secs_f64() * 1e3;
        let target = frame.texture.create_view(&Default::default());
        let mut encoder = gfx.device.create_command_encoder(&Default::default());
        let size = (gfx.config.width, gfx.config.height);
        let mut shown_any = false;
        if let Some(ex) = &mut self.ex {
            ex.encode(&mut encoder).map_err(|e| format!("error: {e}"))?;
            // a summed-area table is a storage buffer: read back and shown as a texture
            if let Mode::Texture { name, layer, level, .. } = &self.state.mode
                && ex.graph().texture(name).is_some_and(|t| t.format.is_table())
            {
                let img = ex.inspect().read_texture(name, *layer, *level).map_err(|e| format!("error: {e}"))?;
                self.table = Some(upload(&gfx.device, &gfx.queue, &img));
            } else {
                self.table = None;
            }
            let truth = self.truth_textures.as_ref();
            let (mut texture, mut pick) = shown(&self.state.mode, ex, truth);
            if let Some(t) = &self.table {
                texture = Some(t);
                pick.layer = 0;
                pick.level = 0;
            }
            let part = if self.ex_b.is_some() { Part::Left } else { Part::Whole };
            if let Some(t) = texture {
                gfx.present.draw(&mut encoder, &target, size, t, pick, part);
                shown_any = true;
            }
            if let Some(b) = &mut self.ex_b {
                b.encode(&mut encoder).map_err(|e| format!("error: split: {e}"))?;
                if let (Some(t), pick) = shown(&self.state.mode, b, truth) {
                    gfx.present.draw(&mut encoder, &target, size, t, pick, Part::Right);
                }
            }
        }
        if !shown_any {
            Present::clear(&mut encoder, &target);
        }
        let mut actions = Vec::new();
        let ui_start = Instant::now();
        let raw = gfx.egui_winit.take_egui_input(&gfx.window);
        let ui = UiData {
            state: &self.state,
            ex: self.ex.as_ref(),
            controls: &self.controls,
            diagnostics: self.diagnostics.as_deref(),
            status: &self.status,
            times: &self.times,
            techniques: &self.techniques,
            command: &self.command,
            truth: self.truth.as_ref(),
            rms: self.rms,
        };
        let show_panels = self.show_panels;
        let out = gfx.egui.run_pass(raw, |ctx| {
            if show_panels {
                panels(ctx, &ui, &mut actions);
            }
        });
        gfx.egui_winit.handle_platform_output(&gfx.window, out.platform_output);
        let jobs = gfx.egui.tessellate(out.shapes, out.pixels_per_point);
        push(&mut self.times.ui_ms, ui_start.elapsed().as_secs_f64() * 1e3);
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [size.0, size.1],
            pixels_per_point: out.pixels_per_point,
        };
        let mut textures = out.textures_delta;
        for (id, deltas) in textures.set.drain() {
            for delta in &deltas {
                gfx.egui_wgpu.update_texture(&gfx.device, &gfx.queue, id, delta);
            }
        }
        let extra = gfx.egui_wgpu.update_buffers(&gfx.device, &gfx.queue, &mut encoder, &jobs, &screen);
        {
            let pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("sshc view: panels"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &target,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Load,
                        store: wgpu::StoreOp::Store,
                    },
                })],
                ..Default::default()
            });
            gfx.egui_wgpu.render(&mut pass.forget_lifetime(), &jobs, &screen);
        }
        for id in textures.free.drain() {
            gfx.egui_wgpu.free_texture(&id);
        }
        let shot = self.screenshot.take().map(|p| {
            let buffer = copy_out(&gfx.device, &mut encoder, &frame.texture);
            (p, buffer)
        });
        gfx.queue.submit(extra.into_iter().chain([encoder.finish()]));
        if let Some((path, buffer)) = shot {
            let Some(buffer) = buffer else {
                return Err("error: the window's surface cannot be read back (no COPY_SRC usage): no screenshot".into());
            };
            write_png(&gfx.device, &buffer, size, gfx.config.format, &path)?;
            let vis = match &self.ex {
                Some(ex) => write_visibility(ex, &path)?,
                None => None,
            };
            self.command = with_words(self.state.command(&path.display().to_string()), &self.args.cascading);
            self.log.write(
                self.frame,
                json!({"event": "screenshot", "path": path, "visibility": vis, "state": self.state, "command": self.command,
                       "split_command": self.state.right().map(|r| with_words(r.command(&path.display().to_string()), &self.args.cascading)),
                       "gpu_ms": median(&self.times.gpu_ms), "ui_ms": median(&self.times.ui_ms), "present_ms": median(&self.times.present_ms), "frame_ms": median(&self.times.frame_ms),
                       "frames_timed": self.times.gpu_ms.len(),
                       "pass_ms": self.times.pass_ms.iter().map(|(k, v)| (k.clone(), median(v))).collect::<BTreeMap<_, _>>()}),
            );
        }
        gfx.window.pre_present_notify();
        let presenting = Instant::now();
        gfx.queue.present(frame);
        present_ms += presenting.elapsed().as_secs_f64() * 1e3;
        push(&mut self.times.present_ms, present_ms);
        if let Some((compile_ms, pipelines_ms, bind_ms)) = self.fresh.take() {
            // the new graph's first frame, to the GPU's end of it
            gfx.device
                .poll(wgpu::PollType::wait_indefinitely())
                .map_err(|e| format!("error: {e}"))?;
            let since_save = self.saved_at.take().map(|t| t.elapsed().as_secs_f64() * 1e3);
            self.log.write(
                self.frame,
                json!({"event": "first frame", "technique": self.state.technique, "compile_ms": compile_ms, "pipelines_ms": pipelines_ms,
                       "bind_ms": bind_ms, "save_to_frame_ms": since_save}),
            );
        }
        self.frame += 1;
        self.refine()?;
        if let Some(ex) = &mut self.ex
            && let Ok(Some((n, t))) = ex.targets.frame_times()
            && self.times.gpu_frame != Some(n)
        {
            self.times.gpu_frame = Some(n);
            self.times.passes = t.passes.into_iter().filter_map(|(n, ms)| Some((n, ms?))).collect();
            push(&mut self.times.gpu_ms, self.times.passes.iter().map(|p| p.1).sum());
            for (name, ms) in &self.times.passes {
                push(self.times.pass_ms.entry(name.clone()).or_default(), *ms);
            }
        }
        let now = Instant::now();
        if let Some(last) = self.times.last.replace(now) {
            push(&mut self.times.frame_ms, (now - last).as_secs_f64() * 1e3);
        }
        for a in actions {
            match a {
                Action::Event(e) => {
                    if let Err(e) = self.apply(e) {
                        self.status = e;
                    }
                }
                Action::Screenshot => {
                    let name = format!("sshc-view-{}.png", self.frame);
                    self.screenshot = Some(PathBuf::from(name));
                }
                Action::CopyCommand => {
                    self.command = with_words(self.state.command("view.png"), &self.args.cascading);
                    println!("{}", self.command);
                    if let Some(gfx) = &self.gfx {
                        gfx.egui.copy_text(self.command.clone());
                    }
                    self.log.write(self.frame, json!({"event": "command", "command": self.command}));
                }
            }
        }
        if self.waiting > 0 {
            self.waiting -= 1;
        }
        let script_done = self.args.script.is_some()
            && self.script.is_empty()
            && self.waiting == 0
            && !self.wait_ready
            && self.wait_answers.is_none()
            && self.wait_truth.is_none()
            && self.screenshot.is_none();
        let frames_done = self.args.frames.is_some_and(|n| self.frame >= n);
        if frames_done && let Some(p) = self.args.screenshot.take() {
            // one frame more, which writes it
            self.screenshot = Some(p);
            self.args.frames = Some(self.frame + 1);
            return Ok(());
        }
        if script_done || (frames_done && self.screenshot.is_none()) {
            self.log.write(self.frame, json!({"event": "exit"}));
            let end = if script_done {
                Ok(())
            } else {
                frames_end(self.diagnostics.as_deref())
            };
            self.finish(event_loop, end);
        }
        Ok(())
    }
}

/// An image of the runtime's as an `Rgba32Float` texture.
fn upload(device: &wgpu::Device, queue: &wgpu::Queue, img: &sshc_runtime::gpu::Image) -> wgpu::Texture {
    let t = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("sshc view: read back"),
        size: wgpu::Extent3d {
            width: img.width,
            height: img.height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba32Float,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    let bytes: Vec<u8> = img.rgba.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
    queue.write_texture(
        t.as_image_copy(),
        &bytes,
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(img.width * 16),
            rows_per_image: None,
        },
        t.size(),
    );
    t
}
