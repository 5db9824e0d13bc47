//! The params panel: a slider or checkbox per param, a runtime uniform set in place, a
//! fixed one recompiled when its drag ends.

use super::{Action, UiData};
use crate::run::Bound;
use crate::view::script::Event;
use sshc_runtime::graph::ParamType;

pub(super) fn params(ui: &mut egui::Ui, d: &UiData, ex: &Bound, actions: &mut Vec<Action>) {
    for p in &ex.graph().params {
        let uniform = p.offset.is_some();
        let mut v = d.state.params.get(&p.name).copied().unwrap_or(p.value);
        if !uniform && let Some(f) = d.state.fixed.get(&p.name).and_then(|s| s.parse::<f64>().ok()) {
            v = f;
        }
        let before = v;
        let (lo, hi) = p.range.unwrap_or(if v == 0.0 {
            (0.0, 1.0)
        } else {
            (v.min(0.0) * 4.0, v.max(0.0) * 4.0)
        });
        let label = if uniform { p.name.clone() } else { format!("{} (fixed)", p.name) };
        let r = match p.ty {
            ParamType::Bool => {
                let mut b = v != 0.0;
                let r = ui.checkbox(&mut b, &label);
                v = f64::from(u8::from(b));
                r
            }
            ParamType::I32 => ui.add(egui::Slider::new(&mut v, lo..=hi).step_by(1.0).text(&label)),
            ParamType::F32 => ui.add(egui::Slider::new(&mut v, lo..=hi).text(&label)),
        };
        let r = match &p.doc {
            Some(doc) => r.on_hover_text(doc),
            None => r,
        };
        // a fixed param recompiles when the drag ends, not at every step
        let commit = if uniform {
            v != before
        } else {
            v != before && !r.dragged() || r.drag_stopped()
        };
        if commit {
            actions.push(Action::Event(Event::Set {
                name: p.name.clone(),
                value: v,
            }));
        }
    }
}
