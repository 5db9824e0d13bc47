//! Compilation: the workers asked for the technique (and the split's right half) with the
//! state's compile options, their answers taken, and the files watched for saves.

use super::App;
use crate::run::Bound;
use crate::view::state::ViewState;
use crate::view::worker::{Answer, Watch};
use serde_json::json;
use std::path::Path;

impl App {
    /// The compile options of the state: its fixed params, precisions and schedules; a
    /// graph for any scene (lights move).
    fn options(&self) -> sshc::CompileOptions {
        options(&self.state)
    }

    /// Compile the split's right half (or drop it).
    pub(super) fn recompile_split(&mut self) {
        let scene = self.current_scene();
        match (self.state.right(), &mut self.worker_b) {
            (Some(right), Some(w)) => {
                w.request(&right.technique, options(&right), scene, self.args.cascading);
            }
            (None, _) => self.ex_b = None,
            (Some(_), None) => {}
        }
    }

    pub(super) fn recompile(&mut self) {
        let (technique, options, scene) = (self.state.technique.clone(), self.options(), self.current_scene());
        if let Some(w) = &mut self.worker {
            w.request(&technique, options, scene, self.args.cascading);
            self.status = format!("compiling {}", technique.display());
        }
    }

    pub(super) fn watch_files(&mut self) {
        let mut files = vec![self.state.technique.clone(), self.state.scene.clone()];
        files.extend(self.state.split.as_ref().map(|s| s.technique.clone()));
        match Watch::new(&files) {
            Ok(w) => self.watch = Some(w),
            Err(e) => self.status = e,
        }
    }

    /// Take the worker's answer, if it has come.
    pub(super) fn take_answer(&mut self, answer: Answer) {
        self.answers += 1;
        match answer {
            Answer::Ready(r) => {
                let mut ex = r.bound;
                // the worker bound the scene as it was asked; the view may have moved since
                self.resized |= self.view_size() != first_size(&ex);
                self.moved = true;
                // runtime params the new graph still has keep their values
                self.state.params.retain(|k, v| ex.state.params.set(k, *v).is_ok());
                self.ex = Some(ex);
                self.fresh = Some((r.compile_ms, r.pipelines_ms, r.bind_ms));
                // GPU times are the new graph's from here
                self.times.gpu_ms.clear();
                self.times.pass_ms.clear();
                self.times.gpu_frame = None;
                self.controls = r.controls;
                self.diagnostics = None;
                self.status = format!(
                    "ready: compiled in {:.0} ms, pipelines {:.0} ms, bound in {:.0} ms",
                    r.compile_ms, r.pipelines_ms, r.bind_ms
                );
                self.log.write(
                    self.frame,
                    json!({"event": "compiled", "ok": true, "technique": self.state.technique, "compile_ms": r.compile_ms,
                           "pipelines_ms": r.pipelines_ms, "bind_ms": r.bind_ms, "warnings": self.controls.warnings}),
                );
            }
            Answer::Failed { diagnostics, .. } => {
                // a save that does not compile has no first frame
                self.saved_at = None;
                self.status = "the file does not compile: the previous graph keeps rendering".into();
                self.log.write(
                    self.frame,
                    json!({"event": "compiled", "ok": false, "technique": self.state.technique, "diagnostics": diagnostics}),
                );
                self.diagnostics = Some(diagnostics);
            }
        }
    }
}

/// The compile options of a state: its fixed params, precisions and schedules; a graph for
/// any scene (lights move).
fn options(state: &ViewState) -> sshc::CompileOptions {
    sshc::CompileOptions {
        set: state.fixed.clone().into_iter().collect(),
        precision: state.precisions.clone().into_iter().collect(),
        schedule: state.schedules.clone().into_iter().collect(),
        // the Shade's debug outputs, to look at (nothing where it declares none)
        debug: true,
        ..Default::default()
    }
}

pub(super) fn first_size(ex: &Bound) -> (u32, u32) {
    ex.targets.camera_size()
}

pub(super) fn same_file(a: &Path, b: &Path) -> bool {
    let c = |p: &Path| std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf());
    c(a) == c(b)
}
