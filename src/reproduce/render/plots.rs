//! What the units' SVG figures share (plotters, SVG backend only; text is left to the SVG
//! viewer's fonts): size, font, the error of a failed drawing, and the velocity-against-grain
//! chart of Fig. 1 and 3.

use crate::error::Error;
use crate::report::plot::PALETTE;
use plotters::prelude::*;

/// Size of every figure, in pixels.
pub(crate) const SIZE: (u32, u32) = (960, 540);
/// Font of captions and labels.
pub(crate) const FONT: (&str, u32) = ("sans-serif", 18);

/// The error of a failed drawing of `name`.
pub(crate) fn perr<E: std::fmt::Debug>(name: &str) -> impl Fn(E) -> Error + '_ {
    move |e| {
        crate::reproduce::ReproduceError::Drawing {
            name: name.to_string(),
            message: format!("{e:?}"),
        }
        .into()
    }
}

fn range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
        (a.min(x), b.max(x))
    });
    if !(lo.is_finite() && hi.is_finite()) || lo == hi {
        return (lo.min(0.0) - 1.0, hi.max(0.0) + 1.0);
    }
    let pad = 0.05 * (hi - lo);
    (lo - pad, hi + pad)
}

/// Velocity against grain number, one line per snapshot, with vertical lines at `marks`.
pub(crate) fn velocity_plot(
    name: &str,
    caption: &str,
    first_grain: i64,
    series: &[(String, &[f64])],
    marks: &[(f64, &str)],
) -> Result<String, Error> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, SIZE).into_drawing_area();
        root.fill(&WHITE).map_err(perr(name))?;
        let n = series.iter().map(|s| s.1.len()).max().unwrap_or(1);
        let x0 = first_grain as f64;
        let x1 = first_grain as f64 + n as f64 - 1.0;
        let (y0, y1) = range(series.iter().flat_map(|s| s.1.iter().copied()));
        let mut chart = ChartBuilder::on(&root)
            .caption(caption, FONT)
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(perr(name))?;
        chart
            .configure_mesh()
            .x_desc("grain number")
            .y_desc("velocity (program units)")
            .draw()
            .map_err(perr(name))?;
        let mut labelled: Vec<&str> = Vec::new();
        for &(x, label) in marks {
            let series = chart
                .draw_series(LineSeries::new(
                    vec![(x, y0), (x, y1)],
                    BLACK.mix(0.4).stroke_width(1),
                ))
                .map_err(perr(name))?;
            if !labelled.contains(&label) {
                labelled.push(label);
                series
                    .label(label)
                    .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK.mix(0.4)));
            }
        }
        for (k, (label, v)) in series.iter().enumerate() {
            let c = PALETTE[k % PALETTE.len()];
            chart
                .draw_series(LineSeries::new(
                    v.iter()
                        .enumerate()
                        .map(|(i, &y)| (first_grain as f64 + i as f64, y)),
                    c.stroke_width(1),
                ))
                .map_err(perr(name))?
                .label(label.clone())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c));
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperLeft)
            .draw()
            .map_err(perr(name))?;
        root.present().map_err(perr(name))?;
    }
    Ok(svg)
}
