//! Line charts as SVG (plotters, SVG backend only: no system font libraries; text is written as
//! SVG `<text>` and sized by plotters' built-in estimate).

use crate::error::{Error, PlotError};

use plotters::prelude::*;
use std::path::Path;

/// One curve.
pub struct Series {
    /// Legend entry. An empty name continues the previous series: same colour, no legend entry.
    pub name: String,
    /// The `(x, y)` points, drawn in order; non-finite points, and non-positive ones on a log
    /// axis, are left out.
    pub points: Vec<(f64, f64)>,
    /// Draw markers at the points as well as the line.
    pub markers: bool,
    /// Dashed line (e.g. a fit or a reference).
    pub dashed: bool,
}

/// Axis scale.
#[derive(Clone, Copy, PartialEq, Eq)]
pub enum Scale {
    /// A linear axis.
    Linear,
    /// A base-10 logarithmic axis (the range extends to whole decades).
    Log,
}

/// A chart description.
pub struct LineChart<'a> {
    /// Title above the chart.
    pub title: &'a str,
    /// Label of the x axis.
    pub x_label: &'a str,
    /// Label of the y axis.
    pub y_label: &'a str,
    /// Scale of the x axis.
    pub x_scale: Scale,
    /// Scale of the y axis.
    pub y_scale: Scale,
    /// The curves, coloured in turn from [`PALETTE`].
    pub series: Vec<Series>,
}

/// The colours of successive series (shared by every SVG grainchain draws).
pub const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(23, 190, 207),
    RGBColor(140, 86, 75),
    RGBColor(127, 127, 127),
];

fn range(vals: impl Iterator<Item = f64>, scale: Scale) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in vals.filter(|v| v.is_finite() && (scale == Scale::Linear || *v > 0.0)) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (1.0, 10.0);
    }
    match scale {
        Scale::Log => {
            let (a, b) = (lo.log10().floor(), hi.log10().ceil());
            (10f64.powf(a), 10f64.powf(if b > a { b } else { a + 1.0 }))
        }
        Scale::Linear => {
            let pad = if hi > lo { 0.05 * (hi - lo) } else { 1.0 };
            (lo - pad, hi + pad)
        }
    }
}

impl LineChart<'_> {
    /// Render to an SVG string.
    pub fn to_svg(&self) -> Result<String, Error> {
        let mut buf = String::new();
        {
            let root = SVGBackend::with_string(&mut buf, (900, 600)).into_drawing_area();
            let e = |x: &dyn std::fmt::Display| PlotError {
                title: self.title.to_string(),
                message: x.to_string(),
            };
            root.fill(&WHITE).map_err(|x| e(&x))?;
            let xs = range(
                self.series
                    .iter()
                    .flat_map(|s| s.points.iter().map(|p| p.0)),
                self.x_scale,
            );
            let ys = range(
                self.series
                    .iter()
                    .flat_map(|s| s.points.iter().map(|p| p.1)),
                self.y_scale,
            );
            let mut b = ChartBuilder::on(&root);
            b.caption(self.title, ("sans-serif", 22))
                .margin(15)
                .x_label_area_size(50)
                .y_label_area_size(80);
            macro_rules! draw {
                ($chart:expr) => {{
                    let mut chart = $chart;
                    chart
                        .configure_mesh()
                        .x_desc(self.x_label)
                        .y_desc(self.y_label)
                        .draw()
                        .map_err(|x| e(&x))?;
                    // A series without a name continues the previous one: same colour, no legend
                    // entry (bands drawn around a curve).
                    let mut k = 0usize;
                    for (i, s) in self.series.iter().enumerate() {
                        if i > 0 && !s.name.is_empty() {
                            k += 1;
                        }
                        let color = PALETTE[k % PALETTE.len()];
                        let pts: Vec<(f64, f64)> = s
                            .points
                            .iter()
                            .copied()
                            .filter(|(x, y)| {
                                x.is_finite()
                                    && y.is_finite()
                                    && (self.x_scale == Scale::Linear || *x > 0.0)
                                    && (self.y_scale == Scale::Linear || *y > 0.0)
                            })
                            .collect();
                        let style = ShapeStyle::from(&color).stroke_width(2);
                        if s.dashed {
                            let a = chart
                                .draw_series(DashedLineSeries::new(pts.clone(), 8, 5, style))
                                .map_err(|x| e(&x))?;
                            if !s.name.is_empty() {
                                a.label(s.name.as_str()).legend(move |(x, y)| {
                                    PathElement::new(vec![(x, y), (x + 20, y)], color)
                                });
                            }
                        } else {
                            let a = chart
                                .draw_series(LineSeries::new(pts.clone(), style))
                                .map_err(|x| e(&x))?;
                            if !s.name.is_empty() {
                                a.label(s.name.as_str()).legend(move |(x, y)| {
                                    PathElement::new(vec![(x, y), (x + 20, y)], color)
                                });
                            }
                        }
                        if s.markers {
                            chart
                                .draw_series(pts.iter().map(|&p| Circle::new(p, 3, color.filled())))
                                .map_err(|x| e(&x))?;
                        }
                    }
                    chart
                        .configure_series_labels()
                        .background_style(WHITE.mix(0.8))
                        .border_style(BLACK)
                        .draw()
                        .map_err(|x| e(&x))?;
                }};
            }
            match (self.x_scale, self.y_scale) {
                (Scale::Log, Scale::Log) => {
                    draw!(b
                        .build_cartesian_2d((xs.0..xs.1).log_scale(), (ys.0..ys.1).log_scale())
                        .map_err(|x| e(&x))?)
                }
                (Scale::Log, Scale::Linear) => {
                    draw!(b
                        .build_cartesian_2d((xs.0..xs.1).log_scale(), ys.0..ys.1)
                        .map_err(|x| e(&x))?)
                }
                (Scale::Linear, Scale::Log) => {
                    draw!(b
                        .build_cartesian_2d(xs.0..xs.1, (ys.0..ys.1).log_scale())
                        .map_err(|x| e(&x))?)
                }
                (Scale::Linear, Scale::Linear) => {
                    draw!(b
                        .build_cartesian_2d(xs.0..xs.1, ys.0..ys.1)
                        .map_err(|x| e(&x))?)
                }
            }
            root.present().map_err(|x| e(&x))?;
        }
        Ok(buf)
    }

    /// Render and write atomically.
    pub fn write(&self, path: impl AsRef<Path>) -> Result<(), Error> {
        let svg = self.to_svg()?;
        super::AtomicFile::write_all(path, svg.as_bytes())
    }
}

/// A histogram of `values` with bins of width `bin` aligned to multiples of `bin`, written
/// atomically as SVG.
pub fn histogram(
    title: &str,
    x_label: &str,
    values: &[f64],
    bin: f64,
    path: impl AsRef<Path>,
) -> Result<(), Error> {
    let e = |x: &dyn std::fmt::Display| PlotError {
        title: title.to_string(),
        message: x.to_string(),
    };
    let finite: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
    let lo = finite.iter().fold(f64::INFINITY, |a, &b| a.min(b));
    let hi = finite.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b));
    let (k0, k1) = if finite.is_empty() {
        (0i64, 1i64)
    } else {
        ((lo / bin).floor() as i64, (hi / bin).floor() as i64 + 1)
    };
    let mut counts = vec![0u32; (k1 - k0) as usize];
    for v in &finite {
        let k = ((v / bin).floor() as i64 - k0).clamp(0, counts.len() as i64 - 1);
        counts[k as usize] += 1;
    }
    let top = counts.iter().copied().max().unwrap_or(1).max(1);
    let mut buf = String::new();
    {
        let root = SVGBackend::with_string(&mut buf, (900, 600)).into_drawing_area();
        root.fill(&WHITE).map_err(|x| e(&x))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 22))
            .margin(15)
            .x_label_area_size(50)
            .y_label_area_size(60)
            .build_cartesian_2d(k0 as f64 * bin..k1 as f64 * bin, 0u32..top + 1)
            .map_err(|x| e(&x))?;
        chart
            .configure_mesh()
            .x_desc(x_label)
            .y_desc("count")
            .draw()
            .map_err(|x| e(&x))?;
        chart
            .draw_series(counts.iter().enumerate().map(|(i, &c)| {
                let x0 = (k0 + i as i64) as f64 * bin;
                Rectangle::new([(x0, 0), (x0 + bin, c)], PALETTE[0].mix(0.7).filled())
            }))
            .map_err(|x| e(&x))?;
        root.present().map_err(|x| e(&x))?;
    }
    super::AtomicFile::write_all(path, buf.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn renders_log_log_svg() {
        let c = LineChart {
            title: "t",
            x_label: "time",
            y_label: "error",
            x_scale: Scale::Log,
            y_scale: Scale::Log,
            series: vec![Series {
                name: "a".into(),
                points: vec![(1.0, 1e-3), (10.0, 1e-5), (0.0, 1.0)],
                markers: true,
                dashed: false,
            }],
        };
        let svg = c.to_svg().unwrap();
        assert!(svg.starts_with("<svg") && svg.contains("</svg>") && svg.contains("error"));
    }
}
