//! The GPU times and memory panel: the frame's times, each pass's GPU time as a bar, and
//! the memory each resource holds.

use super::UiData;
use crate::run::Bound;
use crate::view::app::timing::median;

pub(super) fn times(ui: &mut egui::Ui, d: &UiData, ex: &Bound) {
    ui.label(format!(
        "frame {:.1} ms; panels {:.2} ms and presentation {:.2} ms of CPU (medians of the last {})",
        median(&d.times.frame_ms),
        median(&d.times.ui_ms),
        median(&d.times.present_ms),
        d.times.frame_ms.len()
    ));
    let total: f64 = d.times.passes.iter().map(|p| p.1).sum();
    ui.label(format!("sshc's passes: {total:.3} ms on the GPU"));
    let widest = d.times.passes.iter().map(|p| p.1).fold(0.0, f64::max).max(1e-9);
    for (name, t) in &d.times.passes {
        ui.horizontal(|ui| {
            let (rect, _) = ui.allocate_exact_size(egui::vec2(120.0, 12.0), egui::Sense::hover());
            let w = rect.width() * (*t / widest) as f32;
            ui.painter().rect_filled(
                egui::Rect::from_min_size(rect.min, egui::vec2(w, rect.height())),
                2.0,
                egui::Color32::from_rgb(90, 160, 230),
            );
            ui.label(format!("{name} {t:.3} ms"));
        });
    }
    let mem = ex.inspect().memory();
    let sum: u64 = mem.iter().map(|m| m.1).sum();
    ui.label(format!("memory: {:.1} MiB", sum as f64 / 1048576.0));
    for (name, bytes) in mem {
        ui.label(format!("  {name}: {:.2} MiB", bytes as f64 / 1048576.0));
    }
}
