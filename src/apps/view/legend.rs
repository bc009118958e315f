//! The panel's legends: which colour is which ASPRS class, which return, which height.
//! The colours are those of `shaders/common.wgsl` (`class_color`, `returns_color`,
//! `elevation_color`), linear RGB; a test keeps the two in step.

use crate::render::Mode;
use crate::render::camera::heights;
use crate::tree::TreeMeta;

/// The stops of `elevation_color`, lowest first, evenly spaced over the height range.
pub const ELEVATION_RAMP: [[f32; 3]; 5] = [
    [0.02, 0.08, 0.6],
    [0.0, 0.55, 0.65],
    [0.1, 0.55, 0.05],
    [0.9, 0.75, 0.02],
    [0.7, 0.02, 0.01],
];

/// (classes, name, linear RGB) as `class_color` draws them.
pub const CLASS_COLORS: [(&str, &str, [f32; 3]); 12] = [
    ("2", "ground", [0.35, 0.17, 0.04]),
    ("3", "low vegetation", [0.35, 0.75, 0.15]),
    ("4", "medium vegetation", [0.1, 0.45, 0.03]),
    ("5", "high vegetation", [0.01, 0.2, 0.01]),
    ("6", "building", [0.8, 0.12, 0.03]),
    ("7, 18", "noise", [0.9, 0.0, 0.9]),
    ("9", "water", [0.02, 0.15, 0.85]),
    ("10", "rail", [0.3, 0.2, 0.12]),
    ("11", "road surface", [0.12, 0.12, 0.12]),
    ("13–16", "wires, towers", [0.02, 0.7, 0.8]),
    ("17", "bridge deck", [0.9, 0.7, 0.02]),
    ("other", "unclassified", [0.45, 0.45, 0.45]),
];

/// (name, linear RGB) as `returns_color` draws them.
pub const RETURN_COLORS: [(&str, [f32; 3]); 4] = [
    ("single (1 of 1)", [0.9, 0.7, 0.02]),
    ("first of several", [0.05, 0.6, 0.05]),
    ("intermediate", [0.03, 0.15, 0.8]),
    ("last of several", [0.75, 0.03, 0.02]),
];

fn swatch(ui: &mut egui::Ui, [r, g, b]: [f32; 3], label: String) {
    ui.horizontal(|ui| {
        let (rect, _) = ui.allocate_exact_size(egui::vec2(14.0, 14.0), egui::Sense::hover());
        ui.painter().rect_filled(
            rect,
            2.0,
            egui::Color32::from(egui::Rgba::from_rgb(r, g, b)),
        );
        ui.label(label);
    });
}

/// The elevation ramp as a bar, with the model's lowest and highest node heights along
/// the view's `up` at its ends.
fn elevation_bar(ui: &mut egui::Ui, meta: &TreeMeta, up: glam::DVec3) {
    let [low, high] = heights(meta, up);
    let base = glam::DVec3::from(meta.origin).dot(up);
    let (lo, hi) = (base + low as f64, base + high as f64);
    ui.horizontal(|ui| {
        ui.label(format!("{lo:.2}"));
        let (rect, _) = ui.allocate_exact_size(egui::vec2(120.0, 12.0), egui::Sense::hover());
        let steps = 48;
        for k in 0..steps {
            let t = (k as f32 + 0.5) / steps as f32 * 4.0;
            let i = (t as usize).min(3);
            let f = t - i as f32;
            let [a, b] = [ELEVATION_RAMP[i], ELEVATION_RAMP[i + 1]];
            let c: [f32; 3] = std::array::from_fn(|j| a[j] + (b[j] - a[j]) * f);
            let x0 = rect.left() + rect.width() * k as f32 / steps as f32;
            let x1 = rect.left() + rect.width() * (k + 1) as f32 / steps as f32;
            let cell = egui::Rect::from_x_y_ranges(x0..=x1, rect.y_range());
            let color = egui::Color32::from(egui::Rgba::from_rgb(c[0], c[1], c[2]));
            ui.painter().rect_filled(cell, 0.0, color);
        }
        ui.label(format!("{hi:.2}"));
    });
}

/// The legend of `mode` for a model described by `meta`, seen with `up` up, if it has
/// one.
pub fn show(ui: &mut egui::Ui, mode: Mode, model: Option<(&TreeMeta, glam::DVec3)>) {
    match mode {
        Mode::Elevation => {
            if let Some((meta, up)) = model {
                elevation_bar(ui, meta, up);
            }
        }
        Mode::Classification => {
            ui.collapsing("ASPRS classes", |ui| {
                for (codes, name, color) in CLASS_COLORS {
                    swatch(ui, color, format!("{codes}: {name}"));
                }
            });
        }
        Mode::Returns => {
            ui.collapsing("Returns", |ui| {
                for (name, color) in RETURN_COLORS {
                    swatch(ui, color, name.to_owned());
                }
            });
        }
        Mode::Intensity => {
            ui.label("black to white: the 1st to the 99th percentile of the intensities");
        }
        _ => {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every legend colour is written, as WGSL, in the shader that draws it.
    #[test]
    fn the_legend_colours_are_the_shaders() {
        let wgsl = include_str!("../../../shaders/common.wgsl");
        let colors = CLASS_COLORS
            .iter()
            .map(|c| c.2)
            .chain(RETURN_COLORS.iter().map(|c| c.1))
            .chain(ELEVATION_RAMP);
        for [r, g, b] in colors {
            let text = format!("vec3<f32>({r:?}, {g:?}, {b:?})");
            assert!(wgsl.contains(&text), "{text} is not in common.wgsl");
        }
    }
}
