//! The show panel: the mode (shaded, visibility, truth, cascades, error, the truth's
//! standard error), the debug outputs, a texture's layer, level, channel, range and colour
//! map, and the split view.

use super::{Action, UiData};
use crate::run::Bound;
use crate::view::script::Event;
use crate::view::state::{ColourMap, Mode};
use std::collections::BTreeMap;

pub(super) fn show(ui: &mut egui::Ui, d: &UiData, ex: &Bound, actions: &mut Vec<Action>) {
    let mut mode = d.state.mode.clone();
    ui.horizontal(|ui| {
        ui.selectable_value(&mut mode, Mode::Shaded, "shaded");
        ui.selectable_value(&mut mode, Mode::Visibility, "visibility");
        ui.selectable_value(&mut mode, Mode::Truth, "truth");
        if ex.targets.cascades() > 1 {
            ui.selectable_value(&mut mode, Mode::Cascades, "cascades");
        }
    });
    ui.horizontal(|ui| {
        let error = match mode {
            Mode::Error { range } => range,
            _ => 0.25,
        };
        ui.selectable_value(&mut mode, Mode::Error { range: error }, "error");
        let se = match mode {
            Mode::StdError { range } => range,
            _ => 0.05,
        };
        ui.selectable_value(&mut mode, Mode::StdError { range: se }, "truth's std. error");
    });
    if let Mode::Error { range } | Mode::StdError { range } = &mut mode {
        ui.add(egui::Slider::new(range, 0.001..=1.0).logarithmic(true).text("full colour at"));
    }
    if let Some(t) = d.truth {
        let (mean, max) = t.std_errors();
        ui.label(format!(
            "truth: {} rounds of {} samples in {:.1} s; std. error mean {mean:.4}, max {max:.4}",
            t.rounds,
            crate::view::refine::SAMPLES_PER_ROUND,
            t.seconds
        ));
    }
    if let Some((all, pen)) = d.rms {
        ui.label(format!(
            "RMS error: {all:.4} over the pixels facing the light, {pen:.4} over the penumbra"
        ));
    }
    // the Shade's debug outputs: each over the view, its values fitted to viridis
    let debug = ex.inspect().debug_outputs();
    if !debug.is_empty() {
        ui.horizontal(|ui| {
            ui.label("debug:");
            for o in &debug {
                let on = matches!(&mode, Mode::Texture { name, .. } if *name == o.texture);
                if ui.selectable_label(on, &o.name).clicked() && !on {
                    let (lo, hi) = ex
                        .inspect()
                        .read_debug(0, &o.name)
                        .ok()
                        .and_then(|img| crate::image_io::finite_range(img.rgba.iter().map(|p| p[0])))
                        .map_or((0.0, 1.0), |(lo, hi)| (lo, if hi > lo { hi } else { lo + 1.0 }));
                    mode = Mode::Texture {
                        name: o.texture.clone(),
                        layer: 0,
                        level: 0,
                        channel: 0,
                        lo,
                        hi,
                        map: ColourMap::Viridis,
                    };
                }
            }
        });
    }
    let current = match &mode {
        Mode::Texture { name, .. } => name.clone(),
        Mode::Shaded | Mode::Visibility | Mode::Cascades | Mode::Truth | Mode::Error { .. } | Mode::StdError { .. } => "a texture".into(),
    };
    let mut name = current.clone();
    egui::ComboBox::from_label("texture").selected_text(&name).show_ui(ui, |ui| {
        for t in &ex.graph().textures {
            ui.selectable_value(&mut name, t.name.clone(), &t.name);
        }
    });
    if name != current {
        mode = Mode::Texture {
            name,
            layer: 0,
            level: 0,
            channel: 0,
            lo: 0.0,
            hi: 1.0,
            map: ColourMap::Viridis,
        };
    }
    if let Mode::Texture {
        name,
        layer,
        level,
        channel,
        lo,
        hi,
        map,
    } = &mut mode
        && let Some(decl) = ex.graph().texture(name)
    {
        if decl.format.is_table() {
            ui.label("a summed-area table (prefix sums in a storage buffer): read back every frame");
        }
        let layers = decl.array_layers().max(1);
        let levels = if decl.mips {
            32 - ex.targets.shadow_size().leading_zeros()
        } else {
            1
        };
        ui.add(egui::Slider::new(layer, 0..=layers - 1).text("layer"));
        ui.add(egui::Slider::new(level, 0..=levels - 1).text("level"));
        ui.add(egui::Slider::new(channel, 0..=3).text("channel"));
        ui.horizontal(|ui| {
            ui.add(egui::DragValue::new(lo).speed(0.01).prefix("lo "));
            ui.add(egui::DragValue::new(hi).speed(0.01).prefix("hi "));
            // the channel's finite values, read back once
            if ui.button("fit").clicked()
                && let Ok(img) = ex.inspect().read_texture(name, *layer, *level)
            {
                let c = (*channel).min(3) as usize;
                let (a, b) = img
                    .rgba
                    .iter()
                    .map(|p| p[c])
                    .filter(|v| v.is_finite())
                    .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)));
                if a <= b {
                    (*lo, *hi) = (a, if b > a { b } else { a + 1.0 });
                }
            }
        });
        egui::ComboBox::from_label("colour map")
            .selected_text(map.name())
            .show_ui(ui, |ui| {
                for m in ColourMap::ALL {
                    ui.selectable_value(map, m, m.name());
                }
            });
    }
    if mode != d.state.mode {
        actions.push(Action::Event(Event::Show(mode)));
    }
    ui.separator();
    match &d.state.split {
        None => {
            if ui
                .button("split: keep these settings on the right")
                .on_hover_text("the right half keeps the technique and settings of now; change the left half to compare")
                .clicked()
            {
                actions.push(Action::Event(Event::Split(Some(d.state.as_split()))));
            }
        }
        Some(split) => {
            ui.label(format!("right half: {}", split.technique.display()));
            let mut t = split.technique.clone();
            egui::ComboBox::from_label("right technique")
                .selected_text(t.display().to_string())
                .show_ui(ui, |ui| {
                    for p in d.techniques {
                        ui.selectable_value(&mut t, p.clone(), p.display().to_string());
                    }
                });
            if t != split.technique {
                actions.push(Action::Event(Event::Split(Some(crate::view::state::Split {
                    technique: t,
                    params: BTreeMap::new(),
                    fixed: BTreeMap::new(),
                    precisions: BTreeMap::new(),
                    schedules: BTreeMap::new(),
                }))));
            }
            if ui.button("end the split").clicked() {
                actions.push(Action::Event(Event::Split(None)));
            }
        }
    }
}
