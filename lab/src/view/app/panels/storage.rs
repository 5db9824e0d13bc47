//! The precisions and schedules panel: each stored channel's precision and each pass's
//! schedule (fragment or compute).

use super::{Action, UiData};
use crate::view::script::Event;

const PRECISIONS: [&str; 5] = ["auto", "unorm8", "unorm16", "f16", "f32"];

pub(super) fn storage(ui: &mut egui::Ui, d: &UiData, actions: &mut Vec<Action>) {
    for name in &d.controls.storage {
        let now = d.state.precisions.get(name).cloned().unwrap_or_else(|| "auto".into());
        let mut pick = now.clone();
        egui::ComboBox::from_label(name).selected_text(&pick).show_ui(ui, |ui| {
            for p in PRECISIONS {
                ui.selectable_value(&mut pick, p.to_string(), p);
            }
        });
        if pick != now {
            actions.push(Action::Event(Event::Precision {
                name: name.clone(),
                value: pick,
            }));
        }
    }
    for (pass, compute) in &d.controls.schedules {
        let now = if *compute { "compute" } else { "fragment" };
        let mut pick = now.to_string();
        egui::ComboBox::from_label(format!("{pass} schedule"))
            .selected_text(&pick)
            .show_ui(ui, |ui| {
                for s in ["fragment", "compute"] {
                    ui.selectable_value(&mut pick, s.to_string(), s);
                }
            });
        if pick != now {
            actions.push(Action::Event(Event::Schedule {
                pass: pass.clone(),
                value: pick,
            }));
        }
    }
}
