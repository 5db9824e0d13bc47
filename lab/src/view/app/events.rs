//! Events, scripted (`--script`) or from the panels: one event applied, the script run
//! until it must wait (`Wait`, `WaitReady`, `WaitCompiled`, `WaitTruth`, bounded by
//! `--wait-limit`), and how a `--frames` run ends.

use super::App;
use crate::view::script::Event;
use crate::view::state::{self, Mode, Orbit};
use serde_json::json;
use sshc_runtime::graph::ParamType;
use std::time::Instant;

impl App {
    /// Apply one scripted or panel event; returns false where the script must wait.
    pub(super) fn apply(&mut self, e: Event) -> Result<(), String> {
        self.log.write(self.frame, json!({"event": "script", "step": e}));
        match e {
            Event::Wait(n) => self.waiting = n,
            Event::WaitReady => self.wait_ready = true,
            Event::WaitCompiled => self.wait_answers = Some(self.answers + 1),
            Event::WaitTruth(n) => {
                if !matches!(self.state.mode, Mode::Truth | Mode::Error { .. } | Mode::StdError { .. }) {
                    return Err(
                        "error: WaitTruth: no mode that shows the truth is on (Show(Truth), Show(Error(..)) or Show(StdError(..)))".into(),
                    );
                }
                self.wait_truth = Some(n);
            }
            Event::Orbit { yaw, pitch } => {
                self.orbit.turn(yaw.to_radians(), pitch.to_radians());
                self.orbit_moved();
            }
            Event::Pan { x, y } => {
                self.orbit.pan(x, y);
                self.orbit_moved();
            }
            Event::Zoom(f) => {
                if !(f.is_finite() && f > 0.0) {
                    return Err(format!("error: Zoom({f}): a zoom is a positive factor"));
                }
                self.orbit.zoom(f);
                self.orbit_moved();
            }
            Event::MoveLight { light, by } => {
                let l = self.light(light)?;
                self.set_light(l, state::moved(&self.state.lights[l], by))?;
            }
            Event::LightSize { light, size } => {
                let l = self.light(light)?;
                self.set_light(l, self.state.lights[l].resized(size))?;
            }
            Event::Set { name, value } => self.set(&name, value)?,
            Event::Precision { name, value } => {
                self.state.precisions.insert(name, value);
                self.recompile();
            }
            Event::Schedule { pass, value } => {
                self.state.schedules.insert(pass, value);
                self.recompile();
            }
            Event::Show(m) => {
                if let (Mode::Texture { name, .. }, Some(ex)) = (&m, &self.ex)
                    && ex.graph().texture(name).is_none()
                    && !ex.inspect().debug_outputs().iter().any(|o| o.texture == *name)
                {
                    let mut known: Vec<String> = ex.graph().textures.iter().map(|t| t.name.clone()).collect();
                    known.extend(ex.inspect().debug_outputs().into_iter().map(|o| o.texture));
                    return Err(format!(
                        "error: Show: the graph has no texture `{name}`; it has {}",
                        known.join(", ")
                    ));
                }
                self.state.mode = m;
            }
            Event::Split(split) => {
                self.state.split = split;
                self.watch_files();
                self.recompile_split();
            }
            Event::Technique(t) => {
                self.state.technique = t;
                self.state.params.clear();
                self.state.fixed.clear();
                self.state.precisions.clear();
                self.state.schedules.clear();
                self.watch_files();
                self.recompile();
            }
            Event::Edit { path, from, to } => {
                let text = crate::session::read(&path)?;
                if !text.contains(&from) {
                    return Err(format!("error: Edit: `{from}` is not in {}", path.display()));
                }
                crate::session::write_new(&path, text.replacen(&from, &to, 1))?;
                self.saved_at = Some(Instant::now());
            }
            Event::Screenshot(p) => self.screenshot = Some(p),
            Event::Panels(on) => self.show_panels = on,
            Event::ShowChannel { name, level, lo, hi, map } => {
                let Some(ex) = &self.ex else {
                    return Err(format!(
                        "error: ShowChannel: `{name}`: no technique is compiled yet (a WaitReady first)"
                    ));
                };
                let found = ex
                    .graph()
                    .textures
                    .iter()
                    .find_map(|t| t.channels.iter().find(|c| c.name == name).map(|c| (t, c)));
                let Some((texture, channel)) = found else {
                    let known: Vec<&str> = ex
                        .graph()
                        .textures
                        .iter()
                        .flat_map(|t| t.channels.iter().map(|c| c.name.as_str()))
                        .collect();
                    return Err(format!(
                        "error: ShowChannel: the graph has no channel `{name}`; it has {}",
                        known.join(", ")
                    ));
                };
                self.state.mode = Mode::Texture {
                    name: texture.name.clone(),
                    layer: channel.layer,
                    level,
                    channel: channel.component,
                    lo,
                    hi,
                    map,
                };
            }
            Event::State(s) => {
                let recompile = s.technique != self.state.technique
                    || s.fixed != self.state.fixed
                    || s.precisions != self.state.precisions
                    || s.schedules != self.state.schedules
                    || s.shadow_map != self.state.shadow_map;
                let size = self.view_size();
                self.state = *s;
                self.set_camera_size(size.0, size.1);
                self.orbit = Orbit::of(&self.state.camera);
                if let Some(ex) = &mut self.ex {
                    for (k, v) in &self.state.params {
                        ex.state.params.set(k, *v).map_err(|e| format!("error: {e}"))?;
                    }
                }
                self.moved = true;
                if recompile {
                    self.recompile();
                }
                self.recompile_split();
            }
            Event::Reset => {
                let size = self.view_size();
                self.state.camera = self.file.0.clone();
                self.state.lights = self.file.1.clone();
                self.set_camera_size(size.0, size.1);
                self.orbit = Orbit::of(&self.state.camera);
                let defaults: Vec<String> = self.state.params.keys().cloned().collect();
                self.state.params.clear();
                if let Some(ex) = &mut self.ex {
                    for k in defaults {
                        if let Some(p) = ex.graph().params.iter().find(|p| p.name == k) {
                            let v = p.value;
                            let _ = ex.state.params.set(&k, v);
                        }
                    }
                }
                self.moved = true;
            }
        }
        Ok(())
    }

    fn light(&self, l: usize) -> Result<usize, String> {
        if l < self.state.lights.len() {
            Ok(l)
        } else {
            Err(format!("error: light {l}: the scene has {} light(s)", self.state.lights.len()))
        }
    }

    /// Light `l` replaced, checked as a scene file's light is (so that `sshc render`
    /// reading it back checks the same value).
    pub(super) fn set_light(&mut self, l: usize, light: crate::scene::Light) -> Result<(), String> {
        self.state.lights[l] = crate::scene::checked_light(l, light).map_err(|e| format!("error: {e}"))?;
        self.moved = true;
        Ok(())
    }

    pub(super) fn orbit_moved(&mut self) {
        self.orbit.apply(&mut self.state.camera);
        self.moved = true;
    }

    /// Set a param: a runtime uniform in place, a fixed one by recompiling.
    fn set(&mut self, name: &str, value: f64) -> Result<(), String> {
        let decl = self
            .ex
            .as_ref()
            .and_then(|ex| ex.graph().params.iter().find(|p| p.name == name).cloned());
        match decl {
            Some(d) if d.offset.is_some() => {
                if let Some(ex) = &mut self.ex {
                    ex.state.params.set(name, value).map_err(|e| format!("error: {e}"))?;
                }
                self.state.params.insert(name.to_string(), value);
            }
            Some(d) => {
                let text = match d.ty {
                    ParamType::F32 => state::param_literal(value),
                    ParamType::I32 => format!("{}", value.round() as i64),
                    ParamType::Bool => (value != 0.0).to_string(),
                };
                self.state.fixed.insert(name.to_string(), text);
                self.recompile();
            }
            None => return Err(format!("error: Set: the technique has no param `{name}`")),
        }
        Ok(())
    }

    /// Run the script until it must wait.
    pub(super) fn step_script(&mut self) -> Result<(), String> {
        let waiting_for = if self.wait_truth.is_some() {
            Some("WaitTruth: the truth's rounds")
        } else if self.wait_answers.is_some() {
            Some(
                "WaitCompiled: a compilation's answer (it waits for the next one asked for: a save, an Edit, a Precision, a Schedule or a fixed param's Set; WaitReady waits for one in flight)",
            )
        } else if self.wait_ready {
            Some("WaitReady: the compilation in flight")
        } else {
            None
        };
        match (waiting_for, self.wait_since) {
            (None, _) => self.wait_since = None,
            (Some(_), None) => self.wait_since = Some(Instant::now()),
            (Some(what), Some(t)) if t.elapsed().as_secs() >= self.args.wait_limit => {
                return Err(format!("error: waited {} s (--wait-limit) for {what}", self.args.wait_limit));
            }
            _ => {}
        }
        if let Some(n) = self.wait_truth {
            if self.truth_stale || self.truth.as_ref().is_none_or(|t| t.rounds < n) {
                return Ok(());
            }
            self.wait_truth = None;
            self.waiting = 1;
        }
        if let Some(n) = self.wait_answers {
            if self.answers < n {
                return Ok(());
            }
            self.wait_answers = None;
            self.waiting = 1;
        }
        if self.wait_ready {
            if [&self.worker, &self.worker_b].into_iter().flatten().any(|w| w.pending.is_some()) {
                return Ok(());
            }
            self.wait_ready = false;
            // one frame more, so that what is shown is the answer's
            self.waiting = 1;
        }
        while self.waiting == 0 && !self.wait_ready && self.wait_answers.is_none() && self.wait_truth.is_none() && self.screenshot.is_none()
        {
            let Some(e) = self.script.pop_front() else { break };
            self.apply(e)?;
        }
        Ok(())
    }
}

/// How a `--frames` run ends (issue 51): where the technique (or its scene) did not compile
/// or bind, with a failing status and its diagnostics (file:line:column), printed on
/// standard error by `main`, so that a script can tell; the window showed them too.
pub(super) fn frames_end(diagnostics: Option<&str>) -> Result<(), String> {
    match diagnostics {
        Some(d) => Err(format!(
            "{}\nerror: `sshc view --frames`: the technique does not compile (above); the window drew the diagnostics, not the technique",
            d.trim_end()
        )),
        None => Ok(()),
    }
}
