//! Line charts and histograms as SVG (plotters, SVG backend only: no system font libraries; text
//! is written as SVG `<text>`), drawn in the one style of [`crate::report::style`].

use crate::error::{Error, PlotError};
use crate::report::style::{
    self, clip_polyline, densify, draw_legend, legend_place, legend_size, Axis, LegendEntry,
    LegendPlace, DESC_SIZE, FONT, MARGIN, SIZE, TICK_SIZE, TITLE_SIZE,
};

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::Path;

pub(crate) use crate::report::style::Scale;

/// One curve.
#[derive(Clone, Debug, Default)]
pub struct Series {
    /// Legend entry. An empty name continues the previous series: same colour, no legend entry.
    pub name: String,
    /// The `(x, y)` points, drawn in order; non-finite points, and non-positive ones on a log
    /// axis, are left out.
    pub points: Vec<(f64, f64)>,
    /// Draw markers at the points as well as the line.
    pub markers: bool,
    /// Dashed line (e.g. a fit or a reference); its legend entry is dashed too.
    pub dashed: bool,
    /// Drawn in the colour of the series before it (a band or a fit of that curve), with a
    /// legend entry of its own if it has a name.
    pub same_color: bool,
    /// A fit or reference curve: drawn thick in [`style::REFERENCE`] (dark grey), taking no
    /// colour from the palette.
    pub reference: bool,
}

/// A chart description.
#[derive(Default)]
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
    /// The curves, coloured in turn from [`crate::report::style::PALETTE`].
    pub series: Vec<Series>,
    /// Points with x below this are not drawn (a data-chosen start, e.g. the leak onset).
    pub x_from: Option<f64>,
    /// Points with y below this are not drawn. On a log y axis, values below
    /// [`style::LOG_FLOOR`] times the largest are never drawn, whatever this says.
    pub y_from: Option<f64>,
    /// Positions marked across the plot (interfaces, container edges): vertical lines at these
    /// x in [`style::EDGE`], dashed, one legend entry per distinct label.
    pub edges: Vec<(f64, String)>,
}

/// The data of a chart in plot space, clipped to its axes, ready to draw.
struct Prepared {
    x: Axis,
    y: Axis,
    series: Vec<Drawn>,
    /// Edge lines, plot-space x.
    edges: Vec<f64>,
    legend: Vec<LegendEntry>,
    place: LegendPlace,
    empty: bool,
}

/// One series in plot space: its colour index, dashed or not, the pieces of its line inside the
/// frame and its visible markers.
struct Drawn {
    color: RGBColor,
    width: u32,
    dashed: bool,
    runs: Vec<Vec<(f64, f64)>>,
    marks: Vec<(f64, f64)>,
}

/// The plot frame's size in pixels for a canvas with a legend of width `legend_w` outside (0:
/// inside), and the y label area width.
fn frame(x: &Axis, y: &Axis, legend_w: u32) -> ((u32, u32), u32, u32) {
    let y_area = (y.label_width().ceil() as u32 + DESC_SIZE + 22).max(50);
    // Room on the right for half the last x tick label.
    let right = (x
        .labels()
        .last()
        .map_or(0.0, |l| style::text_width(l, TICK_SIZE as f64) / 2.0) as u32
        + 6)
    .max(MARGIN);
    let x_area = TICK_SIZE + DESC_SIZE + 24;
    let top = TITLE_SIZE + 2 * MARGIN;
    let w = SIZE.0.saturating_sub(MARGIN + y_area + right + legend_w);
    let h = SIZE.1.saturating_sub(top + x_area + MARGIN);
    ((w, h), y_area, right)
}

impl LineChart<'_> {
    fn prepare(&self) -> Prepared {
        let xa = |v: f64| v.is_finite() && (self.x_scale == Scale::Linear || v > 0.0);
        let ya = |v: f64| v.is_finite() && (self.y_scale == Scale::Linear || v > 0.0);
        let kept = |p: &(f64, f64)| {
            xa(p.0)
                && ya(p.1)
                && self.x_from.is_none_or(|f| p.0 >= f)
                && self.y_from.is_none_or(|f| p.1 >= f)
        };
        let all = || {
            self.series
                .iter()
                .flat_map(|s| s.points.iter())
                .filter(|p| kept(p))
        };
        // Markers are drawn whole: their data stay a few percent inside the frame.
        let pad = if self.series.iter().any(|s| s.markers) {
            0.03
        } else {
            0.0
        };
        let y_range = style::data_range(all().map(|p| p.1), self.y_scale, self.y_from);
        let y_floor = y_range.map_or(f64::NEG_INFINITY, |r| r.0);
        let y = Axis::padded(y_range, self.y_scale, pad);
        // The x range of the points drawn: those above the y floor.
        let x = Axis::padded(
            style::data_range(
                all()
                    .filter(|p| p.1 >= y_floor)
                    .map(|p| p.0)
                    .chain(self.edges.iter().map(|e| e.0).filter(|&v| xa(v))),
                self.x_scale,
                self.x_from,
            ),
            self.x_scale,
            pad,
        );
        let (xr, yr) = (x.range(), y.range());
        let mut series = Vec::new();
        let mut legend = Vec::new();
        let mut k = 0usize;
        let mut occupied = Vec::new();
        let unit = |p: (f64, f64)| {
            (
                (p.0 - xr.start) / (xr.end - xr.start),
                (p.1 - yr.start) / (yr.end - yr.start),
            )
        };
        let mut empty = true;
        for (i, s) in self.series.iter().enumerate() {
            if i > 0 && !s.name.is_empty() && !s.same_color && !s.reference {
                k += 1;
            }
            let pts: Vec<(f64, f64)> = s
                .points
                .iter()
                .filter(|p| kept(p))
                .map(|p| (x.to_plot(p.0), y.to_plot(p.1)))
                .collect();
            let runs = clip_polyline(&pts, &xr, &yr);
            let inside = |p: &&(f64, f64)| {
                p.0 >= xr.start && p.0 <= xr.end && p.1 >= yr.start && p.1 <= yr.end
            };
            let marks: Vec<(f64, f64)> = if s.markers {
                pts.iter().filter(inside).copied().collect()
            } else {
                Vec::new()
            };
            for r in &runs {
                let u: Vec<(f64, f64)> = r.iter().map(|&p| unit(p)).collect();
                occupied.extend(densify(&u, 0.005));
            }
            occupied.extend(marks.iter().map(|&p| unit(p)));
            empty &= runs.is_empty() && marks.is_empty();
            if !s.name.is_empty() {
                legend.push(LegendEntry {
                    label: s.name.clone(),
                    color: if s.reference {
                        style::REFERENCE
                    } else {
                        style::color(k)
                    },
                    width: if s.reference { 3 } else { 2 },
                    dashed: s.dashed,
                    marker: s.markers,
                });
            }
            series.push(Drawn {
                color: if s.reference {
                    style::REFERENCE
                } else {
                    style::color(k)
                },
                width: if s.reference { 3 } else { 2 },
                dashed: s.dashed,
                runs,
                marks,
            });
        }
        let mut edges = Vec::new();
        for (v, label) in &self.edges {
            if !x.drawable(*v) {
                continue;
            }
            let px = x.to_plot(*v);
            if px < xr.start || px > xr.end {
                continue;
            }
            edges.push(px);
            let u = unit((px, yr.start)).0;
            occupied.extend(densify(&[(u, 0.0), (u, 1.0)], 0.005));
            if !label.is_empty() && !legend.iter().any(|l: &LegendEntry| &l.label == label) {
                legend.push(LegendEntry {
                    label: label.clone(),
                    color: style::EDGE,
                    width: 1,
                    dashed: true,
                    marker: false,
                });
            }
        }
        let (inside_frame, _, _) = frame(&x, &y, 0);
        let mut place = legend_place(&legend, &occupied, inside_frame);
        if empty {
            place = LegendPlace::UpperRight;
            legend.clear();
        }
        Prepared {
            x,
            y,
            edges,
            series,
            legend,
            place,
            empty,
        }
    }

    /// Render to an SVG string.
    pub fn to_svg(&self) -> Result<String, Error> {
        let e = |x: &dyn std::fmt::Display| PlotError {
            title: self.title.to_string(),
            message: x.to_string(),
        };
        let p = self.prepare();
        let legend_w = if p.place == LegendPlace::Outside {
            legend_size(&p.legend).0 + MARGIN
        } else {
            0
        };
        let (_, y_area, right) = frame(&p.x, &p.y, legend_w);
        let mut buf = String::new();
        {
            let root = SVGBackend::with_string(&mut buf, SIZE).into_drawing_area();
            root.fill(&WHITE).map_err(|x| e(&x))?;
            let mut chart = ChartBuilder::on(&root)
                .caption(self.title, (FONT, TITLE_SIZE))
                .margin_top(MARGIN)
                .margin_left(MARGIN)
                .margin_bottom(MARGIN)
                .margin_right(right + legend_w)
                .x_label_area_size(TICK_SIZE + DESC_SIZE + 24)
                .y_label_area_size(y_area)
                .build_cartesian_2d(p.x.coord(), p.y.coord())
                .map_err(|x| e(&x))?;
            chart
                .configure_mesh()
                .x_desc(self.x_label)
                .y_desc(self.y_label)
                .label_style((FONT, TICK_SIZE))
                .axis_desc_style((FONT, DESC_SIZE))
                .bold_line_style(style::GRID.stroke_width(1))
                .light_line_style(style::GRID_MINOR.stroke_width(1))
                .axis_style(BLACK.stroke_width(1))
                .draw()
                .map_err(|x| e(&x))?;
            let yr = p.y.range();
            for &ex in &p.edges {
                chart
                    .draw_series(DashedLineSeries::new(
                        [(ex, yr.start), (ex, yr.end)],
                        style::DASH.0,
                        style::DASH.1,
                        style::edge_style(),
                    ))
                    .map_err(|x| e(&x))?;
            }
            for d in &p.series {
                let color = d.color;
                let line = color.stroke_width(d.width);
                for r in &d.runs {
                    if d.dashed {
                        chart
                            .draw_series(DashedLineSeries::new(
                                r.iter().copied(),
                                style::DASH.0,
                                style::DASH.1,
                                line,
                            ))
                            .map_err(|x| e(&x))?;
                    } else {
                        chart
                            .draw_series(LineSeries::new(r.iter().copied(), line))
                            .map_err(|x| e(&x))?;
                    }
                }
                chart
                    .draw_series(d.marks.iter().map(|&q| Circle::new(q, 3, color.filled())))
                    .map_err(|x| e(&x))?;
            }
            let (px, py) = chart.plotting_area().get_pixel_range();
            if p.empty {
                root.draw(&Text::new(
                    "no point to draw (values not finite, or not positive on a log axis)"
                        .to_string(),
                    ((px.start + px.end) / 2, (py.start + py.end) / 2),
                    (FONT, DESC_SIZE)
                        .into_font()
                        .color(&BLACK)
                        .pos(Pos::new(HPos::Center, VPos::Center)),
                ))
                .map_err(|x| e(&x))?;
            }
            if !p.legend.is_empty() {
                let (w, h) = legend_size(&p.legend);
                let (w, h) = (w as i32, h as i32);
                let m = MARGIN as i32;
                let at = match p.place {
                    LegendPlace::UpperRight => (px.end - w - m, py.start + m),
                    LegendPlace::UpperLeft => (px.start + m, py.start + m),
                    LegendPlace::LowerRight => (px.end - w - m, py.end - h - m),
                    LegendPlace::LowerLeft => (px.start + m, py.end - h - m),
                    LegendPlace::Outside => (SIZE.0 as i32 - m - w, py.start),
                };
                draw_legend(&root, &p.legend, at).map_err(|x| e(&x))?;
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
    let svg = histogram_svg(title, x_label, values, bin)?;
    super::AtomicFile::write_all(path, svg.as_bytes())
}

/// The SVG text of [`histogram`].
pub fn histogram_svg(
    title: &str,
    x_label: &str,
    values: &[f64],
    bin: f64,
) -> Result<String, Error> {
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
    let x = Axis::new(Scale::Linear, k0 as f64 * bin, k1 as f64 * bin, false);
    let y = Axis::new(Scale::Linear, 0.0, top as f64 + 1.0, true);
    let (_, y_area, right) = frame(&x, &y, 0);
    let mut buf = String::new();
    {
        let root = SVGBackend::with_string(&mut buf, SIZE).into_drawing_area();
        root.fill(&WHITE).map_err(|x| e(&x))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, (FONT, TITLE_SIZE))
            .margin_top(MARGIN)
            .margin_left(MARGIN)
            .margin_bottom(MARGIN)
            .margin_right(right)
            .x_label_area_size(TICK_SIZE + DESC_SIZE + 24)
            .y_label_area_size(y_area)
            .build_cartesian_2d(x.coord(), y.coord())
            .map_err(|x| e(&x))?;
        chart
            .configure_mesh()
            .x_desc(x_label)
            .y_desc("count")
            .label_style((FONT, TICK_SIZE))
            .axis_desc_style((FONT, DESC_SIZE))
            .bold_line_style(style::GRID.stroke_width(1))
            .axis_style(BLACK.stroke_width(1))
            .draw()
            .map_err(|x| e(&x))?;
        chart
            .draw_series(
                counts
                    .iter()
                    .enumerate()
                    .filter(|c| *c.1 > 0)
                    .map(|(i, &c)| {
                        let x0 = (k0 + i as i64) as f64 * bin;
                        Rectangle::new(
                            [(x0, 0.0), (x0 + bin, c as f64)],
                            style::color(0).mix(0.7).filled(),
                        )
                    }),
            )
            .map_err(|x| e(&x))?;
        root.present().map_err(|x| e(&x))?;
    }
    Ok(buf)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn texts(svg: &str) -> Vec<String> {
        svg.split("<text")
            .skip(1)
            .map(|t| {
                let body = &t[t.find('>').unwrap() + 1..t.find("</text>").unwrap()];
                body.trim().to_string()
            })
            .collect()
    }

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
                ..Default::default()
            }],
            ..Default::default()
        };
        let svg = c.to_svg().unwrap();
        assert!(svg.starts_with("<svg") && svg.contains("</svg>") && svg.contains("error"));
        let t = texts(&svg);
        for l in ["1e-5", "1e-4", "1e-3", "1", "10"] {
            assert_eq!(t.iter().filter(|x| *x == l).count(), 1, "{l}: {t:?}");
        }
    }

    #[test]
    fn log_axis_keeps_twelve_decades_and_the_callers_start() {
        let pts: Vec<(f64, f64)> = (1..=300)
            .map(|t| (t as f64, if t < 50 { 1e-45 } else { 1e-3 / t as f64 }))
            .collect();
        let c = LineChart {
            title: "band",
            x_scale: Scale::Log,
            y_scale: Scale::Log,
            series: vec![Series {
                name: "mean".into(),
                points: pts,
                ..Default::default()
            }],
            x_from: Some(60.0),
            ..Default::default()
        };
        let p = c.prepare();
        assert!(p.y.hi / p.y.lo <= 1e12 * 1.000001);
        assert!(p.x.lo >= 60.0 && p.x.hi == 300.0, "{} {}", p.x.lo, p.x.hi);
        assert!(!p.empty);
    }

    #[test]
    fn a_chart_without_points_says_so() {
        let c = LineChart {
            title: "nothing",
            x_scale: Scale::Log,
            y_scale: Scale::Log,
            series: vec![Series {
                name: "a".into(),
                points: vec![(f64::INFINITY, 1.0), (0.0, 1.0)],
                ..Default::default()
            }],
            ..Default::default()
        };
        assert!(texts(&c.to_svg().unwrap()).contains(
            &"no point to draw (values not finite, or not positive on a log axis)".to_string()
        ));
    }

    #[test]
    fn edges_are_dashed_black_lines_with_one_legend_entry() {
        let c = LineChart {
            title: "edges",
            series: vec![Series {
                name: "v".into(),
                points: vec![(0.0, 0.0), (10.0, 1.0)],
                ..Default::default()
            }],
            edges: vec![
                (3.5, "container edges".into()),
                (7.5, "container edges".into()),
            ],
            ..Default::default()
        };
        let p = c.prepare();
        assert_eq!(p.edges, vec![3.5, 7.5]);
        assert_eq!(p.legend.len(), 2);
        assert!(p.legend[1].dashed && p.legend[1].color == style::EDGE);
        assert!(c.to_svg().unwrap().contains("stroke=\"#000000\""));
    }

    #[test]
    fn dashed_series_have_dashed_legend_entries() {
        let c = LineChart {
            title: "d",
            series: vec![Series {
                name: "band".into(),
                points: vec![(0.0, 0.0), (1.0, 1.0)],
                dashed: true,
                ..Default::default()
            }],
            ..Default::default()
        };
        let p = c.prepare();
        assert!(p.legend[0].dashed);
    }
}
