//! SVG plots of term counts (plotters, SVG backend): singular values against the predicted F_l
//! (Mahajan et al. 2008, Fig. 2 right and Fig. 5) and K against (l*)² (Fig. 3A, 7C).

use super::count::{Row, Spectrum};
use plotters::prelude::*;

const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
];

fn err(e: impl std::fmt::Display) -> String {
    format!("cannot draw the plot: {e}")
}

/// Draws the two-panel plot and returns the SVG text.
pub fn count_plot(title: &str, rows: &[Row], spectra: &[Spectrum]) -> Result<String, String> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (1280, 560)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let root = root.titled(title, ("sans-serif", 22)).map_err(err)?;
        let (left, right) = root.split_horizontally(660);
        draw_spectra(&left, spectra)?;
        draw_counts(&right, rows)?;
        root.present().map_err(err)?;
    }
    Ok(svg)
}

fn draw_spectra<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    spectra: &[Spectrum],
) -> Result<(), String> {
    // Normalize every curve by its largest measured σ so materials share one axis; show the terms
    // down to 1e-4 of σ_1, but no further than twice the K holding 99.9 % of each spectrum's
    // energy (long measured tails would squash the interesting part).
    let floor = 1e-4;
    let kmax = spectra
        .iter()
        .map(|s| {
            let top = s.measured.first().copied().unwrap_or(1.0).max(f64::MIN_POSITIVE);
            let above_floor = s.measured.iter().take_while(|v| **v / top >= floor).count();
            above_floor.min(2 * super::energy::terms_for_fraction(&s.measured, 0.999))
        })
        .max()
        .unwrap_or(1)
        .max(4) as f64;
    let mut chart = ChartBuilder::on(area)
        .caption("singular values (points) and predicted F_l (lines), / sigma_1", ("sans-serif", 16))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..kmax, (floor..1.5f64).log_scale())
        .map_err(err)?;
    chart.configure_mesh().x_desc("term k").y_desc("sigma_k / sigma_1").draw().map_err(err)?;
    for (i, s) in spectra.iter().enumerate() {
        let color = PALETTE[i % PALETTE.len()];
        let top = s.measured.first().copied().unwrap_or(1.0);
        if top <= 0.0 {
            continue;
        }
        let pts: Vec<(f64, f64)> = s
            .measured
            .iter()
            .enumerate()
            .map(|(k, v)| ((k + 1) as f64, v / top))
            .filter(|p| p.0 <= kmax && p.1 >= floor)
            .collect();
        chart
            .draw_series(pts.iter().map(|p| Circle::new(*p, 2, color.filled())))
            .map_err(err)?
            .label(s.label.clone())
            .legend(move |(x, y)| Circle::new((x + 10, y), 3, color.filled()));
        let pred: Vec<(f64, f64)> = s
            .predicted
            .iter()
            .enumerate()
            .map(|(k, v)| ((k + 1) as f64, v / top))
            .filter(|p| p.0 <= kmax && p.1 >= floor)
            .collect();
        if !pred.is_empty() {
            chart.draw_series(LineSeries::new(pred, color.stroke_width(1))).map_err(err)?;
        }
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 12))
        .draw()
        .map_err(err)?;
    Ok(())
}

fn draw_counts<DB: DrawingBackend>(area: &DrawingArea<DB, plotters::coord::Shift>, rows: &[Row]) -> Result<(), String> {
    // x = (l*)² for half-angle models, (l*+1)² for reflection lobes (eq. 10); y = K.
    let x_of = |r: &Row| {
        r.l_star.map(|l| match r.prediction {
            Some(super::predict::PredictionKind::ReflectionLobe) => ((l + 1) * (l + 1)) as f64,
            _ => (l * l) as f64,
        })
    };
    // Room on the right for the material labels.
    let xmax = rows.iter().filter_map(x_of).fold(4.0f64, f64::max) * 1.3;
    let ymax =
        rows.iter().flat_map(|r| [r.measured_k, r.predicted_k]).flatten().map(|k| k as f64).fold(4.0f64, f64::max)
            * 1.1;
    let mut chart = ChartBuilder::on(area)
        .caption("K at the energy fraction vs (l*)^2 [reflection lobes: (l*+1)^2]", ("sans-serif", 16))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(50)
        .build_cartesian_2d(0.0..xmax, 0.0..ymax)
        .map_err(err)?;
    chart.configure_mesh().x_desc("(l*)^2").y_desc("K").draw().map_err(err)?;
    let lines =
        [(1.0, "K = x (sphere, reflection lobe)"), (0.5, "K = x/2"), (0.25, "K = x/4 (hemisphere, half-angle)")];
    for (i, (slope, label)) in lines.iter().enumerate() {
        let color = PALETTE[(i + 5) % PALETTE.len()];
        chart
            // End inside the chart: plotters drops segments whose end point lies outside it.
            .draw_series(LineSeries::new(
                vec![(0.0, 0.0), (xmax.min(ymax / slope), (slope * xmax).min(ymax))],
                color.stroke_width(1),
            ))
            .map_err(err)?
            .label(*label)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color));
    }
    let measured: Vec<(f64, f64)> = rows.iter().filter_map(|r| Some((x_of(r)?, r.measured_k? as f64))).collect();
    let predicted: Vec<(f64, f64)> = rows.iter().filter_map(|r| Some((x_of(r)?, r.predicted_k? as f64))).collect();
    let blue = PALETTE[0];
    let orange = PALETTE[1];
    chart
        .draw_series(measured.iter().map(|p| Circle::new(*p, 4, blue.filled())))
        .map_err(err)?
        .label("measured K (SVD)")
        .legend(move |(x, y)| Circle::new((x + 10, y), 4, blue.filled()));
    chart
        .draw_series(predicted.iter().map(|p| Circle::new(*p, 6, orange.stroke_width(2))))
        .map_err(err)?
        .label("predicted K")
        .legend(move |(x, y)| Circle::new((x + 10, y), 5, orange.stroke_width(2)));
    for r in rows {
        if let (Some(x), Some(k)) = (x_of(r), r.measured_k.or(r.predicted_k)) {
            chart
                .draw_series(std::iter::once(Text::new(r.name.clone(), (x, k as f64), ("sans-serif", 11))))
                .map_err(err)?;
        }
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 12))
        .draw()
        .map_err(err)?;
    Ok(())
}
