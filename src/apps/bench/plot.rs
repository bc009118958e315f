//! `speed_vs_error.png`: GPU ms (median, log scale) against FLIP, one curve per strategy
//! and orbit distance, points along a curve being the ε sweep. Drawn with plotters into
//! memory, then written atomically.

use std::path::Path;

use plotters::prelude::*;

use super::report::{Environment, Row, Strategy, culling_name};
use crate::io::png::write_png;
use crate::render::Culling;

const SIZE: (u32, u32) = (1200, 800);

/// The font of the plot's text: egui's bundled Ubuntu Light, so that no system font is
/// needed.
fn register_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        // A bundled, valid font: registration cannot fail.
        let _ = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            epaint_default_fonts::UBUNTU_LIGHT,
        );
    });
}

/// One curve: label, colour, marker (0 near, 1 mid, 2 far), points (GPU ms, FLIP) in
/// ε order.
type Curve = (String, RGBColor, usize, Vec<(f64, f64)>);

fn curves(rows: &[Row]) -> Vec<Curve> {
    let strategies = [
        (Strategy::Spt, Culling::Compute, RGBColor(31, 119, 180)),
        (Strategy::Spt, Culling::Vertex, RGBColor(44, 160, 44)),
        (Strategy::Random, Culling::Compute, RGBColor(214, 39, 40)),
    ];
    let mut out = Vec::new();
    for (k, path) in ["orbit-near", "orbit-mid", "orbit-far"].iter().enumerate() {
        for (strategy, culling, color) in strategies {
            let mut points: Vec<(f64, f64, f64)> = rows
                .iter()
                .filter(|r| {
                    r.path == *path
                        && r.culling == culling
                        && (r.strategy == strategy
                            || (strategy == Strategy::Spt && r.strategy == Strategy::NoLod))
                })
                .filter_map(|r| r.m.gpu_ms_median.map(|ms| (r.eps_px, ms, r.m.flip)))
                .collect();
            points.sort_by(|a, b| a.0.total_cmp(&b.0));
            if !points.is_empty() {
                out.push((
                    format!(
                        "{} ({} culling), {}",
                        strategy.name(),
                        culling_name(culling),
                        &path[6..]
                    ),
                    color,
                    k,
                    points.iter().map(|p| (p.1, p.2)).collect(),
                ));
            }
        }
    }
    out
}

pub fn write(path: &Path, env: &Environment, rows: &[Row]) -> anyhow::Result<()> {
    register_font();
    let curves = curves(rows);
    let all: Vec<(f64, f64)> = curves.iter().flat_map(|c| c.3.iter().copied()).collect();
    if all.is_empty() {
        anyhow::bail!("no GPU times to plot (the adapter has no timestamp queries)");
    }
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, 0.0f64, f64::MAX, f64::MIN);
    for &(x, y) in &all {
        (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
    }
    let (x0, x1) = ((x0 * 0.8).max(1e-3), x1 * 1.25);
    // FLIP is in [0, 1], lower is better: from 0 to a margin above the worst.
    let (y0, y1) = (0.0, (y1 * 1.1).max(y0 + 1e-3));
    let mut pixels = vec![0u8; (SIZE.0 * SIZE.1 * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut pixels, SIZE).into_drawing_area();
        let draw = |e: DrawingAreaErrorKind<_>| anyhow::anyhow!("plot: {e:?}");
        root.fill(&WHITE).map_err(draw)?;
        let (title, footer) = root.split_vertically(SIZE.1 - 30);
        let mut chart = ChartBuilder::on(&title)
            .caption(
                format!(
                    "{}: speed against error, {}×{}",
                    env.model, env.size.0, env.size.1
                ),
                ("sans-serif", 26),
            )
            .margin(16)
            .x_label_area_size(50)
            .y_label_area_size(70)
            .build_cartesian_2d((x0..x1).log_scale(), y0..y1)
            .map_err(draw)?;
        chart
            .configure_mesh()
            .x_desc("GPU ms per frame (median, log scale)")
            .y_desc(format!(
                "FLIP against the {}, 4×4 supersampled (lower is better)",
                env.reference
            ))
            .label_style(("sans-serif", 16))
            .x_labels(8)
            .light_line_style(RGBColor(235, 235, 235))
            .draw()
            .map_err(draw)?;
        for (label, color, marker, points) in &curves {
            let style = color.stroke_width(2);
            chart
                .draw_series(LineSeries::new(points.iter().copied(), style))
                .map_err(draw)?
                .label(label.as_str())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], style));
            let marker = *marker;
            chart
                .draw_series(points.iter().map(move |&p| -> DynElement<_, _> {
                    match marker {
                        0 => Circle::new(p, 5, style.filled()).into_dyn(),
                        1 => TriangleMarker::new(p, 6, style.filled()).into_dyn(),
                        _ => Cross::new(p, 5, style).into_dyn(),
                    }
                }))
                .map_err(draw)?;
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .label_font(("sans-serif", 15))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()
            .map_err(draw)?;
        footer
            .draw(&Text::new(
                format!(
                    "Points along a curve: ε = 0 (leaves), 0.25 … 8 px. Markers: circles near, triangles mid, crosses far. {}",
                    env.label()
                ),
                (16, 6),
                ("sans-serif", 14),
            ))
            .map_err(draw)?;
        root.present().map_err(draw)?;
    }
    let rgba: Vec<u8> = pixels
        .chunks_exact(3)
        .flat_map(|p| [p[0], p[1], p[2], 255])
        .collect();
    write_png(path, SIZE.0, SIZE.1, &rgba)
}
