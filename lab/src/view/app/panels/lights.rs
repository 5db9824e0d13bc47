//! The lights panel: each light's kind and size.

use super::{Action, UiData};
use crate::view::script::Event;

pub(super) fn lights(ui: &mut egui::Ui, d: &UiData, actions: &mut Vec<Action>) {
    ui.label("shift-drag: move light 0 across; ctrl-drag: up and down");
    for (i, l) in d.state.lights.iter().enumerate() {
        ui.label(format!("light {i}: {}", l.kind_name()));
        if let Some(mut s) = l.size() {
            let before = s;
            let max = if l.is_distant() { 20.0 } else { (before * 4.0).max(1.0) };
            ui.add(egui::Slider::new(&mut s, 0.0..=max).text("size"));
            if s != before {
                actions.push(Action::Event(Event::LightSize { light: i, size: s }));
            }
        }
    }
}
