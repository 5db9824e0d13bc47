//! The egui panels: the window of controls (technique, params, precisions and schedules,
//! lights, what is shown, GPU times) and the diagnostics; what they read, and what they ask
//! for, applied after they are drawn. Each group of controls is a file.

mod lights;
mod params;
mod show;
mod storage;
mod times;

use crate::run::Bound;
use crate::view::app::timing::Times;
use crate::view::refine::Estimate;
use crate::view::script::Event;
use crate::view::state::ViewState;
use crate::view::worker::Controls;
use lights::lights;
use params::params;
use show::show;
use std::path::PathBuf;
use storage::storage;
use times::times;

/// What the panels asked for, applied after they are drawn.
pub(super) enum Action {
    Event(Event),
    Screenshot,
    CopyCommand,
}

/// What the panels read.
pub(super) struct UiData<'a> {
    pub(super) state: &'a ViewState,
    pub(super) ex: Option<&'a Bound>,
    pub(super) controls: &'a Controls,
    pub(super) diagnostics: Option<&'a str>,
    pub(super) status: &'a str,
    pub(super) times: &'a Times,
    pub(super) techniques: &'a [PathBuf],
    pub(super) command: &'a str,
    pub(super) truth: Option<&'a Estimate>,
    pub(super) rms: Option<(f64, f64)>,
}

/// The panels: technique, params, storage and schedules, lights, what is shown, times.
pub(super) fn panels(ctx: &egui::Context, d: &UiData, actions: &mut Vec<Action>) {
    // the panels start folded on a small window, which they would cover
    let wide = ctx.content_rect().width() >= 600.0;
    egui::Window::new("sshc").default_width(280.0).default_open(wide).show(ctx, |ui| {
        ui.label(d.status);
        let mut technique = d.state.technique.clone();
        egui::ComboBox::from_label("technique")
            .selected_text(technique.display().to_string())
            .show_ui(ui, |ui| {
                for t in d.techniques {
                    ui.selectable_value(&mut technique, t.clone(), t.display().to_string());
                }
            });
        if technique != d.state.technique {
            actions.push(Action::Event(Event::Technique(technique)));
        }
        ui.horizontal(|ui| {
            if ui.button("reset view").clicked() {
                actions.push(Action::Event(Event::Reset));
            }
            if ui.button("screenshot").clicked() {
                actions.push(Action::Screenshot);
            }
            if ui.button("copy as command").clicked() {
                actions.push(Action::CopyCommand);
            }
        });
        if !d.command.is_empty() {
            ui.add(egui::Label::new(egui::RichText::new(d.command).monospace().small()).wrap());
        }
        if let Some(ex) = d.ex {
            egui::CollapsingHeader::new("params")
                .default_open(true)
                .show(ui, |ui| params(ui, d, ex, actions));
            egui::CollapsingHeader::new("precisions and schedules").show(ui, |ui| storage(ui, d, actions));
            egui::CollapsingHeader::new("lights").show(ui, |ui| lights(ui, d, actions));
            egui::CollapsingHeader::new("show")
                .default_open(true)
                .show(ui, |ui| show(ui, d, ex, actions));
            egui::CollapsingHeader::new("GPU times and memory").show(ui, |ui| times(ui, d, ex));
        }
    });
    if let Some(diag) = d.diagnostics {
        egui::Window::new("diagnostics").default_width(560.0).show(ctx, |ui| {
            egui::ScrollArea::vertical().max_height(320.0).show(ui, |ui| {
                ui.label(egui::RichText::new(diag).monospace().color(egui::Color32::from_rgb(255, 140, 120)));
            });
        });
    }
}
