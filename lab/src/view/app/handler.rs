//! winit's events: the window opened when the application resumes, resizes, Tab, the
//! mouse's buttons, drags (the camera orbited and panned, light 0 moved) and wheel, a
//! redraw each frame, and everything dropped before the event loop ends.

use super::App;
use crate::view::state;
use serde_json::json;
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::ActiveEventLoop;
use winit::window::WindowId;

/// The mouse, for camera and light drags.
#[derive(Default)]
pub(super) struct Mouse {
    at: Option<(f64, f64)>,
    left: bool,
    right: bool,
    shift: bool,
    ctrl: bool,
}

impl App {
    fn mouse_moved(&mut self, x: f64, y: f64) {
        let Some((px, py)) = self.mouse.at.replace((x, y)) else { return };
        let (dx, dy) = ((x - px) as f32, (y - py) as f32);
        let Some(gfx) = &self.gfx else { return };
        if gfx.egui.egui_wants_pointer_input() {
            return;
        }
        let h = gfx.config.height.max(1) as f32;
        if self.mouse.left && (self.mouse.shift || self.mouse.ctrl) && !self.state.lights.is_empty() {
            // drag the light: across the view and away (shift), or up and down (ctrl)
            let eye = self.orbit.position();
            let forward = (self.orbit.target - eye).normalize_or_zero();
            let flat = glam::Vec3::new(forward.x, 0.0, forward.z).normalize_or_zero();
            let right = flat.cross(glam::Vec3::Y);
            let scale = self.orbit.distance * 2.0 / h;
            let by = if self.state.lights[0].is_distant() {
                glam::Vec3::new(dx * 2.0 / h, -dy * 2.0 / h, 0.0)
            } else if self.mouse.ctrl {
                glam::Vec3::Y * -dy * scale
            } else {
                (right * dx - flat * dy) * scale
            };
            if let Err(e) = self.set_light(0, state::moved(&self.state.lights[0], by)) {
                self.status = e;
            }
        } else if self.mouse.left {
            self.orbit.turn(-dx * 3.0 / h, dy * 3.0 / h);
            self.orbit_moved();
        } else if self.mouse.right {
            self.orbit.pan(dx / h, dy / h);
            self.orbit_moved();
        }
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.gfx.is_none()
            && let Err(e) = self.open(event_loop)
        {
            self.finish(event_loop, Err(e));
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        if let Some(gfx) = &mut self.gfx {
            let r = gfx.egui_winit.on_window_event(&gfx.window, &event);
            if r.consumed && !matches!(event, WindowEvent::RedrawRequested | WindowEvent::Resized(_)) {
                return;
            }
        }
        match event {
            WindowEvent::CloseRequested => {
                self.log.write(self.frame, json!({"event": "exit"}));
                self.finish(event_loop, Ok(()));
            }
            WindowEvent::Resized(size) => {
                if let Some(gfx) = &mut self.gfx
                    && size.width > 0
                    && size.height > 0
                    && (size.width, size.height) != (gfx.config.width, gfx.config.height)
                {
                    gfx.config.width = size.width;
                    gfx.config.height = size.height;
                    gfx.surface.configure(&gfx.device, &gfx.config);
                    self.set_camera_size(size.width, size.height);
                    self.resized = true;
                }
            }
            WindowEvent::KeyboardInput { event, .. }
                if event.state == ElementState::Pressed
                    && !event.repeat
                    && event.logical_key == winit::keyboard::Key::Named(winit::keyboard::NamedKey::Tab) =>
            {
                self.show_panels = !self.show_panels;
            }
            WindowEvent::ModifiersChanged(m) => {
                self.mouse.shift = m.state().shift_key();
                self.mouse.ctrl = m.state().control_key();
            }
            WindowEvent::MouseInput { state, button, .. } => {
                let down = state == ElementState::Pressed;
                match button {
                    MouseButton::Left => self.mouse.left = down,
                    MouseButton::Right | MouseButton::Middle => self.mouse.right = down,
                    MouseButton::Back | MouseButton::Forward | MouseButton::Other(_) => {}
                }
            }
            WindowEvent::CursorMoved { position, .. } => self.mouse_moved(position.x, position.y),
            WindowEvent::MouseWheel { delta, .. } => {
                let lines = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                self.orbit.zoom(0.9f32.powf(lines));
                self.orbit_moved();
            }
            WindowEvent::RedrawRequested => {
                if let Err(e) = self.redraw(event_loop) {
                    self.log.write(self.frame, json!({"event": "error", "error": e}));
                    if self.args.script.is_some() || self.args.frames.is_some() {
                        // scripted: an error ends the run with it
                        self.finish(event_loop, Err(e));
                    } else {
                        self.status = e;
                    }
                }
            }
            _ => {}
        }
    }

    /// The surface, the device and every handle to it (the workers') and the window go
    /// while the event loop (and its X connection) still lives: a swapchain destroyed
    /// after its display connection has closed, or a device left to the driver's exit
    /// handlers, can crash the driver.
    fn exiting(&mut self, _event_loop: &ActiveEventLoop) {
        self.table = None;
        self.truth_textures = None;
        self.ex = None;
        self.ex_b = None;
        self.worker = None;
        self.worker_b = None;
        self.gfx = None;
    }

    fn about_to_wait(&mut self, _event_loop: &ActiveEventLoop) {
        if let Some(gfx) = &self.gfx {
            gfx.window.request_redraw();
        }
    }
}
