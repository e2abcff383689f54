//! The one plotting style of every grainchain figure: canvas and font sizes, a palette in which
//! the grid, interfaces and container edges, references and data never share a colour, axes with
//! ticks at round numbers labelled to fit their range, log axes bounded to the data that matter,
//! and legends placed where they hide no data (the emptiest corner of the plot, else outside it).
//!
//! A figure built on this module (see [`crate::report::plot::LineChart`]) works in *plot space*:
//! an [`Axis`] maps data values to plot space (`log10` on a log axis, identity on a linear one),
//! gives plotters its tick positions ([`Axis::range`], [`Axis::ticks`], [`Axis::minor`]) and
//! the text of each tick ([`Axis::label`]). Text is sized by the estimate [`text_width`], the
//! same one the figure tests use to check that every label stays inside the canvas.

use plotters::coord::ranged1d::{KeyPointHint, NoDefaultFormatting, Ranged, ValueFormatter};
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// Canvas size of every figure, in pixels.
pub const SIZE: (u32, u32) = (900, 600);
/// Font family (the SVG viewer's sans-serif: no font is embedded or needed to write the SVG).
pub const FONT: &str = "sans-serif";
/// Title size.
pub const TITLE_SIZE: u32 = 20;
/// Axis description size.
pub const DESC_SIZE: u32 = 16;
/// Tick label size.
pub const TICK_SIZE: u32 = 14;
/// Legend text size.
pub const LEGEND_SIZE: u32 = 14;
/// Margin around the chart, and the inset of a legend from the plot frame, in pixels.
pub const MARGIN: u32 = 12;

/// The colours of successive data series. No grey: greys belong to the grid, black to the frame,
/// interfaces and container edges ([`EDGE`]) and dark grey to fits and references
/// ([`REFERENCE`]).
pub const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(23, 190, 207),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
];
/// Grid lines at labelled ticks (light grey; nothing else is drawn in it).
pub const GRID: RGBColor = RGBColor(215, 215, 215);
/// Grid lines between labelled ticks (lighter grey).
pub const GRID_MINOR: RGBColor = RGBColor(238, 238, 238);
/// Interfaces, container edges and other positions marked across the plot: black, drawn dashed
/// ([`edge_style`]), so they read neither as grid nor as data.
pub const EDGE: RGBColor = RGBColor(0, 0, 0);
/// Fits and reference curves: dark grey, drawn thick and solid ([`reference_style`]).
pub const REFERENCE: RGBColor = RGBColor(64, 64, 64);
/// Dash and gap of dashed series and edges, in pixels.
pub const DASH: (u32, u32) = (8, 5);

/// The style of interface and container-edge lines (draw them with
/// `DashedLineSeries::new(points, DASH.0, DASH.1, edge_style())`).
pub fn edge_style() -> ShapeStyle {
    EDGE.stroke_width(1)
}

/// The style of fits and references.
pub fn reference_style() -> ShapeStyle {
    REFERENCE.stroke_width(3)
}

/// Colour of the `k`-th data series.
pub fn color(k: usize) -> RGBColor {
    PALETTE[k % PALETTE.len()]
}

/// Estimated width of `text` at font size `size` (pixels): 0.6 em per character, on the wide
/// side of sans-serif digits and lower-case letters, so what fits by this estimate fits on
/// screen.
pub fn text_width(text: &str, size: f64) -> f64 {
    0.6 * size * text.chars().count() as f64
}

/// A log axis spans at most this many decades below its largest value: values below
/// `LOG_FLOOR` times the maximum are not drawn.
pub const LOG_FLOOR: f64 = 1e-12;

/// Axis scale.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Scale {
    /// A linear axis.
    #[default]
    Linear,
    /// A base-10 logarithmic axis.
    Log,
}

/// The range of the values a figure draws on one axis: non-finite values, non-positive ones
/// on a log axis and values below `from` are left out, and on a log axis also values below
/// [`LOG_FLOOR`] times the largest. `from` is the caller's data-chosen start (the leak onset of
/// an energy curve, say). None when no value is left.
pub fn data_range(
    values: impl IntoIterator<Item = f64>,
    scale: Scale,
    from: Option<f64>,
) -> Option<(f64, f64)> {
    let keep: Vec<f64> = values
        .into_iter()
        .filter(|v| v.is_finite() && (scale == Scale::Linear || *v > 0.0))
        .filter(|v| from.is_none_or(|f| *v >= f))
        .collect();
    let hi = keep.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let floor = if scale == Scale::Log {
        hi * LOG_FLOOR
    } else {
        f64::NEG_INFINITY
    };
    let lo = keep
        .iter()
        .copied()
        .filter(|v| *v >= floor)
        .fold(f64::INFINITY, f64::min);
    (lo <= hi).then_some((lo, hi))
}

/// One axis: its scale, its range and labelled ticks in plot space (`log10` of the value on a
/// log axis), its unlabelled minor ticks and the tick labels.
#[derive(Clone, Debug)]
pub struct Axis {
    /// The scale.
    pub scale: Scale,
    /// Smallest value shown (data space).
    pub lo: f64,
    /// Largest value shown (data space).
    pub hi: f64,
    ticks: Vec<f64>,
    minor: Vec<f64>,
    labels: Vec<String>,
}

impl Axis {
    /// An axis showing at least `lo..hi` (data space), its ends rounded outward to round
    /// numbers: multiples of the tick step on a linear axis, `m 10^e` with a whole `m` on a log
    /// axis (which never spans more than 12 decades: `lo` is raised if needed). `integer` asks
    /// for whole-number ticks only (counts). Degenerate or empty ranges are widened.
    pub fn new(scale: Scale, lo: f64, hi: f64, integer: bool) -> Axis {
        match scale {
            Scale::Linear => Axis::linear(lo, hi, integer),
            Scale::Log => Axis::log(lo, hi),
        }
    }

    /// An axis fitted to `values` by [`data_range`] (a default range when none is left).
    pub fn fit(values: impl IntoIterator<Item = f64>, scale: Scale, from: Option<f64>) -> Axis {
        let (lo, hi) = data_range(values, scale, from).unwrap_or(match scale {
            Scale::Linear => (0.0, 1.0),
            Scale::Log => (1.0, 10.0),
        });
        Axis::new(scale, lo, hi, false)
    }

    /// An axis over `range` (from [`data_range`]; a default one when None) widened by `pad`
    /// of its span on each side (in plot space: a factor on a log axis; a linear end at zero
    /// stays at zero), then rounded as [`Axis::new`] does.
    pub fn padded(range: Option<(f64, f64)>, scale: Scale, pad: f64) -> Axis {
        let Some((lo, hi)) = range else {
            return Axis::fit(std::iter::empty(), scale, None);
        };
        let (lo, hi) = match scale {
            Scale::Log => {
                let f = if hi > lo { (hi / lo).powf(pad) } else { 1.0 };
                (lo / f, hi * f)
            }
            Scale::Linear => {
                let d = (hi - lo) * pad;
                (
                    if lo == 0.0 { lo } else { lo - d },
                    if hi == 0.0 { hi } else { hi + d },
                )
            }
        };
        Axis::new(scale, lo, hi, false)
    }

    fn linear(lo: f64, hi: f64, integer: bool) -> Axis {
        let (lo, hi) = if !(lo.is_finite() && hi.is_finite()) {
            (0.0, 1.0)
        } else if hi > lo {
            (lo, hi)
        } else if lo == 0.0 {
            (-1.0, 1.0)
        } else {
            (lo - 0.1 * lo.abs(), hi + 0.1 * hi.abs())
        };
        let mut step = nice_step((hi - lo) / 6.0);
        if integer {
            step = step.max(1.0).round();
        }
        let k0 = (lo / step + 1e-9).floor() as i64;
        let k1 = (hi / step - 1e-9).ceil() as i64;
        let ticks: Vec<f64> = (k0..=k1).map(|k| clean(k as f64 * step)).collect();
        let labels = linear_labels(&ticks, step);
        Axis {
            scale: Scale::Linear,
            lo: ticks[0],
            hi: *ticks.last().unwrap(),
            ticks,
            minor: Vec::new(),
            labels,
        }
    }

    fn log(lo: f64, hi: f64) -> Axis {
        let (mut lo, mut hi) = if lo > 0.0 && hi >= lo && hi.is_finite() {
            (lo, hi)
        } else {
            (1.0, 10.0)
        };
        if hi / lo < 1.1 {
            (lo, hi) = (lo / 1.1, hi * 1.1);
        }
        // Ends at round numbers: one significant digit over a decade or more, two below.
        let digits = if hi / lo >= 10.0 { 1 } else { 2 };
        hi = snap(hi, digits, true);
        lo = snap(lo, digits, false);
        if lo < hi * LOG_FLOOR * (1.0 - 1e-9) {
            lo = snap(hi * LOG_FLOOR, 1, true);
        }
        let (bottom, top) = (Grid::down(lo), Grid::up(hi));
        let within = |g: &Grid| g.value() >= lo * (1.0 - 1e-9) && g.value() <= hi * (1.0 + 1e-9);
        // The sparsest mantissa set giving at least three ticks (two whole decades suffice).
        let sets: [&[i32]; 3] = [&[1], &[1, 2, 5], &[1, 2, 3, 4, 5, 6, 7, 8, 9]];
        let mut chosen: Vec<Grid> = Vec::new();
        let mut set_index = 0;
        let mut enough = false;
        for (i, set) in sets.iter().enumerate() {
            chosen = Grid::between(bottom, top, set);
            chosen.retain(within);
            set_index = i;
            // Two whole decades are enough on an axis of two decades or more (60..8000 gets 100
            // and 1000, not a linear axis of 2000..8000 that leaves its left half unlabelled).
            enough = chosen.len() >= 3 || (i == 0 && chosen.len() >= 2 && hi / lo >= 99.0);
            if enough {
                break;
            }
        }
        if !enough {
            // Less than a factor of ~3: round numbers of a linear axis, placed on the log scale.
            let lin = Axis::linear(lo, hi, false);
            let keep: Vec<usize> = (0..lin.ticks.len())
                .filter(|&i| lin.ticks[i] >= lo * (1.0 - 1e-9) && lin.ticks[i] <= hi * (1.0 + 1e-9))
                .collect();
            return Axis {
                scale: Scale::Log,
                lo,
                hi,
                ticks: keep.iter().map(|&i| lin.ticks[i].log10()).collect(),
                minor: Vec::new(),
                labels: keep.iter().map(|&i| lin.labels[i].clone()).collect(),
            };
        }
        if set_index == 0 && chosen.len() > 8 {
            let stride = chosen.len().div_ceil(7) as i32;
            chosen.retain(|g| g.e.rem_euclid(stride) == 0);
        }
        let minor: Vec<f64> = if set_index == 2 || (set_index == 0 && hi / lo > 1e8) {
            Vec::new()
        } else {
            Grid::between(bottom, top, sets[2])
                .into_iter()
                .filter(|g| within(g) && !chosen.contains(g))
                .map(|g| g.value().log10())
                .collect()
        };
        let plain = chosen.iter().all(|g| (-3..=5).contains(&g.e));
        let labels = chosen
            .iter()
            .map(|g| {
                if plain {
                    let v = g.value();
                    format!("{:.*}", (-g.e).max(0) as usize, v)
                } else if g.m == 1 {
                    format!("1e{}", g.e)
                } else {
                    format!("{}e{}", g.m, g.e)
                }
            })
            .collect();
        Axis {
            scale: Scale::Log,
            lo,
            hi,
            ticks: chosen.iter().map(|g| g.value().log10()).collect(),
            minor,
            labels,
        }
    }

    /// A data value in plot space.
    pub fn to_plot(&self, v: f64) -> f64 {
        match self.scale {
            Scale::Linear => v,
            Scale::Log => v.log10(),
        }
    }

    /// Whether a data value can be drawn on this axis (finite; positive on a log axis).
    pub fn drawable(&self, v: f64) -> bool {
        v.is_finite() && (self.scale == Scale::Linear || v > 0.0)
    }

    /// The axis range in plot space.
    pub fn range(&self) -> std::ops::Range<f64> {
        self.to_plot(self.lo)..self.to_plot(self.hi)
    }

    /// Labelled ticks, plot space.
    pub fn ticks(&self) -> &[f64] {
        &self.ticks
    }

    /// Unlabelled minor ticks (light grid lines), plot space.
    pub fn minor(&self) -> &[f64] {
        &self.minor
    }

    /// The tick labels, one per tick.
    pub fn labels(&self) -> &[String] {
        &self.labels
    }

    /// The label of the tick at plot-space position `x` (the nearest tick; empty when `x` is not
    /// a tick, so plotters never prints a label of its own).
    pub fn label(&self, x: f64) -> String {
        let span = (self.range().end - self.range().start).abs().max(1e-300);
        self.ticks
            .iter()
            .position(|t| (t - x).abs() <= 1e-6 * span)
            .map(|i| self.labels[i].clone())
            .unwrap_or_default()
    }

    /// Width of the widest tick label (pixels, [`text_width`] at [`TICK_SIZE`]).
    pub fn label_width(&self) -> f64 {
        self.labels
            .iter()
            .map(|l| text_width(l, TICK_SIZE as f64))
            .fold(0.0, f64::max)
    }
}

/// An [`Axis`] as a plotters coordinate (plot space): plotters draws its grid at the axis's ticks
/// and minor ticks and prints exactly the axis's labels, nothing of its own.
pub struct Coord {
    axis: Axis,
    inner: RangedCoordf64,
}

impl Axis {
    /// This axis as a plotters coordinate, for `ChartBuilder::build_cartesian_2d`.
    pub fn coord(&self) -> Coord {
        Coord {
            axis: self.clone(),
            inner: self.range().into(),
        }
    }
}

impl Ranged for Coord {
    type FormatOption = NoDefaultFormatting;
    type ValueType = f64;
    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        self.inner.map(value, limit)
    }
    fn key_points<Hint: KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        if hint.weight().allow_light_points() {
            self.axis.minor.clone()
        } else {
            self.axis.ticks.clone()
        }
    }
    fn range(&self) -> std::ops::Range<f64> {
        self.axis.range()
    }
}

impl ValueFormatter<f64> for Coord {
    fn format_ext(&self, value: &f64) -> String {
        self.axis.label(*value)
    }
}

/// `m 10^e` with `m` in 1..=9.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Grid {
    m: i32,
    e: i32,
}

impl Grid {
    fn value(self) -> f64 {
        // Through the decimal text, so 10^-15 is the double nearest 1e-15.
        format!("{}e{}", self.m, self.e).parse().unwrap()
    }
    fn split(v: f64) -> (f64, i32) {
        let e = v.log10().floor() as i32;
        let m = v / format!("1e{e}").parse::<f64>().unwrap();
        // log10 can land one decade off near powers of ten.
        if m >= 10.0 - 1e-9 {
            (m / 10.0, e + 1)
        } else if m < 1.0 - 1e-9 {
            (m * 10.0, e - 1)
        } else {
            (m, e)
        }
    }
    fn down(v: f64) -> Grid {
        let (m, e) = Grid::split(v);
        Grid {
            m: ((m + 1e-9).floor() as i32).clamp(1, 9),
            e,
        }
    }
    fn up(v: f64) -> Grid {
        let (m, e) = Grid::split(v);
        let m = (m - 1e-9).ceil() as i32;
        if m >= 10 {
            Grid { m: 1, e: e + 1 }
        } else {
            Grid { m: m.max(1), e }
        }
    }
    fn key(self) -> (i32, i32) {
        (self.e, self.m)
    }
    fn between(lo: Grid, hi: Grid, set: &[i32]) -> Vec<Grid> {
        let mut out = Vec::new();
        for e in lo.e..=hi.e {
            for &m in set {
                let g = Grid { m, e };
                if g.key() >= lo.key() && g.key() <= hi.key() {
                    out.push(g);
                }
            }
        }
        out
    }
}

/// `v > 0` rounded up (`up`) or down to `digits` significant digits.
fn snap(v: f64, digits: i32, up: bool) -> f64 {
    let (m, e) = Grid::split(v);
    let q = 10f64.powi(digits - 1);
    let m = if up {
        (m * q - 1e-9).ceil()
    } else {
        (m * q + 1e-9).floor()
    };
    format!("{m}e{}", e - digits + 1).parse().unwrap()
}

/// The round step (1, 2 or 5 times a power of ten) nearest above `raw`.
fn nice_step(raw: f64) -> f64 {
    let (m, e) = Grid::split(raw.max(1e-300));
    let m = [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .find(|&c| c >= m - 1e-9)
        .unwrap();
    let s: f64 = format!("{m}e{e}").parse().unwrap();
    s
}

/// `v` without the rounding noise of `k * step` (to 12 significant digits), and never `-0`.
fn clean(v: f64) -> f64 {
    let c: f64 = format!("{v:.11e}").parse().unwrap();
    if c == 0.0 {
        0.0
    } else {
        c
    }
}

/// Labels of linear ticks at multiples of `step`: as many decimals as the step needs (none for
/// whole steps), in scientific notation when the numbers are large (>= 1e6) or small (< 1e-3).
fn linear_labels(ticks: &[f64], step: f64) -> Vec<String> {
    let big = ticks.iter().fold(0.0f64, |a, t| a.max(t.abs()));
    let step_exp = Grid::split(step).1;
    if big >= 1e6 || (big > 0.0 && big < 1e-3) {
        let e = Grid::split(big).1;
        let scale: f64 = format!("1e{e}").parse().unwrap();
        let decimals = (e - step_exp).max(0) as usize;
        ticks
            .iter()
            .map(|&t| {
                if t == 0.0 {
                    "0".to_string()
                } else {
                    format!("{:.*}e{e}", decimals, t / scale)
                }
            })
            .collect()
    } else {
        let decimals = (-step_exp).max(0) as usize;
        ticks.iter().map(|&t| format!("{t:.decimals$}")).collect()
    }
}

/// One legend entry: how the series is drawn and its text.
#[derive(Clone, Debug)]
pub struct LegendEntry {
    /// The text.
    pub label: String,
    /// Line colour.
    pub color: RGBColor,
    /// Line width in pixels (0: no line, markers only).
    pub width: u32,
    /// Dashed line, drawn dashed in the legend too.
    pub dashed: bool,
    /// A marker at the middle of the sample line.
    pub marker: bool,
}

/// Where the legend goes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LegendPlace {
    /// Inside the plot frame at the upper right corner.
    UpperRight,
    /// Upper left.
    UpperLeft,
    /// Lower right.
    LowerRight,
    /// Lower left.
    LowerLeft,
    /// Outside the plot frame, to the right of it (the caller leaves [`legend_size`]`.0` of
    /// canvas for it).
    Outside,
}

const SAMPLE: i32 = 30;

/// Size of the legend box (pixels).
pub fn legend_size(entries: &[LegendEntry]) -> (u32, u32) {
    let w = entries
        .iter()
        .map(|e| text_width(&e.label, LEGEND_SIZE as f64))
        .fold(0.0, f64::max);
    let line = LEGEND_SIZE + 6;
    (
        (w.ceil() as u32) + SAMPLE as u32 + 24,
        line * entries.len() as u32 + 10,
    )
}

/// The corner of the plot frame (`plot` pixels wide and high) whose legend box hides no data,
/// trying upper right, upper left, lower right, lower left; [`LegendPlace::Outside`] when every
/// corner would. `occupied` holds the drawn data in the unit square (0 = left or bottom, 1 =
/// right or top) densely enough that lines between points count (see [`densify`]).
pub fn legend_place(
    entries: &[LegendEntry],
    occupied: &[(f64, f64)],
    plot: (u32, u32),
) -> LegendPlace {
    if entries.is_empty() {
        return LegendPlace::UpperRight;
    }
    let (w, h) = legend_size(entries);
    // The box plus the inset and a few pixels of clearance, as fractions of the frame.
    let fw = (w + MARGIN + 6) as f64 / plot.0.max(1) as f64;
    let fh = (h + MARGIN + 6) as f64 / plot.1.max(1) as f64;
    if fw >= 0.6 || fh >= 0.8 {
        return LegendPlace::Outside;
    }
    for place in [
        LegendPlace::UpperRight,
        LegendPlace::UpperLeft,
        LegendPlace::LowerRight,
        LegendPlace::LowerLeft,
    ] {
        let (right, top) = match place {
            LegendPlace::UpperRight => (true, true),
            LegendPlace::UpperLeft => (false, true),
            LegendPlace::LowerRight => (true, false),
            _ => (false, false),
        };
        let hit = occupied.iter().any(|&(x, y)| {
            let in_x = if right { x >= 1.0 - fw } else { x <= fw };
            let in_y = if top { y >= 1.0 - fh } else { y <= fh };
            in_x && in_y
        });
        if !hit {
            return place;
        }
    }
    LegendPlace::Outside
}

/// The points of a polyline (unit-square coordinates) with extra points every `step` along
/// each segment, for [`legend_place`].
pub fn densify(line: &[(f64, f64)], step: f64) -> Vec<(f64, f64)> {
    let mut out = Vec::with_capacity(line.len());
    for w in line.windows(2) {
        let (a, b) = (w[0], w[1]);
        let n = (((b.0 - a.0).hypot(b.1 - a.1) / step).ceil() as usize).clamp(1, 1000);
        for j in 0..n {
            let s = j as f64 / n as f64;
            out.push((a.0 + s * (b.0 - a.0), a.1 + s * (b.1 - a.1)));
        }
    }
    out.extend(line.last());
    out
}

/// Draw the legend box with its top-left corner at pixel `(x, y)` of `area`: each entry's sample
/// drawn as the series is (dashed for a dashed series, a marker for a series with markers).
pub fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[LegendEntry],
    (x, y): (i32, i32),
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let (w, h) = legend_size(entries);
    area.draw(&Rectangle::new(
        [(x, y), (x + w as i32, y + h as i32)],
        WHITE.filled(),
    ))?;
    area.draw(&Rectangle::new(
        [(x, y), (x + w as i32, y + h as i32)],
        BLACK.stroke_width(1),
    ))?;
    let line = (LEGEND_SIZE + 6) as i32;
    let font = (FONT, LEGEND_SIZE)
        .into_font()
        .color(&BLACK)
        .pos(Pos::new(HPos::Left, VPos::Center));
    for (i, e) in entries.iter().enumerate() {
        let cy = y + 5 + line * i as i32 + line / 2;
        let (x0, x1) = (x + 8, x + 8 + SAMPLE);
        let style = e.color.stroke_width(e.width.max(1));
        if e.width > 0 {
            if e.dashed {
                let mut a = x0;
                while a < x1 {
                    let b = (a + DASH.0 as i32).min(x1);
                    area.draw(&PathElement::new(vec![(a, cy), (b, cy)], style))?;
                    a = b + DASH.1 as i32;
                }
            } else {
                area.draw(&PathElement::new(vec![(x0, cy), (x1, cy)], style))?;
            }
        }
        if e.marker {
            area.draw(&Circle::new(((x0 + x1) / 2, cy), 3, e.color.filled()))?;
        }
        area.draw(&Text::new(e.label.clone(), (x1 + 8, cy), font.clone()))?;
    }
    Ok(())
}

/// The pieces of the polyline `pts` (plot space) inside the box `x × y`, cut at the box's edges
/// (Liang-Barsky per segment), so nothing is drawn outside the frame.
pub fn clip_polyline(
    pts: &[(f64, f64)],
    x: &std::ops::Range<f64>,
    y: &std::ops::Range<f64>,
) -> Vec<Vec<(f64, f64)>> {
    let inside = |p: (f64, f64)| x.contains(&p.0) || p.0 == x.end;
    let inside = |p: (f64, f64)| inside(p) && (y.contains(&p.1) || p.1 == y.end);
    let mut runs: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut cur: Vec<(f64, f64)> = Vec::new();
    if pts.len() == 1 && inside(pts[0]) {
        return vec![pts.to_vec()];
    }
    for w in pts.windows(2) {
        let (a, b) = (w[0], w[1]);
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        let mut visible = true;
        for (p, q) in [
            (-dx, a.0 - x.start),
            (dx, x.end - a.0),
            (-dy, a.1 - y.start),
            (dy, y.end - a.1),
        ] {
            if p == 0.0 {
                if q < 0.0 {
                    visible = false;
                }
            } else {
                let r = q / p;
                if p < 0.0 {
                    t0 = t0.max(r);
                } else {
                    t1 = t1.min(r);
                }
            }
        }
        if !visible || t0 > t1 {
            if !cur.is_empty() {
                runs.push(std::mem::take(&mut cur));
            }
            continue;
        }
        let pa = (a.0 + t0 * dx, a.1 + t0 * dy);
        let pb = (a.0 + t1 * dx, a.1 + t1 * dy);
        if cur.last() != Some(&pa) {
            if !cur.is_empty() {
                runs.push(std::mem::take(&mut cur));
            }
            cur.push(pa);
        }
        cur.push(pb);
        if t1 < 1.0 {
            runs.push(std::mem::take(&mut cur));
        }
    }
    if !cur.is_empty() {
        runs.push(cur);
    }
    runs
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_ticks_are_round_and_integers_have_no_decimals() {
        let a = Axis::new(Scale::Linear, 3.0, 297.0, false);
        assert_eq!(a.labels(), ["0", "50", "100", "150", "200", "250", "300"]);
        let a = Axis::new(Scale::Linear, -3.83, -2.61, false);
        assert_eq!(a.labels().first().unwrap(), "-4.0");
        assert_eq!(a.labels().last().unwrap(), "-2.5");
        assert!(a.labels().iter().all(|l| l.len() <= 4));
        let a = Axis::new(Scale::Linear, 0.0, 1.0, false);
        assert_eq!(a.labels(), ["0.0", "0.2", "0.4", "0.6", "0.8", "1.0"]);
        let a = Axis::new(Scale::Linear, 0.0, 2.3e-5, false);
        assert_eq!(a.labels()[1], "0.5e-5");
        let a = Axis::new(Scale::Linear, 0.0, 3.0, true);
        assert_eq!(a.labels(), ["0", "1", "2", "3"]);
        let a = Axis::new(Scale::Linear, -0.3, 0.3, false);
        assert!(a.labels().contains(&"0.0".to_string()));
    }

    #[test]
    fn log_ticks_fit_the_range() {
        let a = Axis::new(Scale::Log, 1.3e-10, 4e-5, false);
        assert_eq!(
            a.labels(),
            ["1e-10", "1e-9", "1e-8", "1e-7", "1e-6", "1e-5"]
        );
        assert_eq!((a.lo, a.hi), (1e-10, 4e-5));
        let a = Axis::new(Scale::Log, 100.0, 300.0, false);
        assert_eq!(a.labels(), ["100", "200", "300"]);
        let a = Axis::new(Scale::Log, 1.0, 1000.0, false);
        assert_eq!(a.labels(), ["1", "10", "100", "1000"]);
        let a = Axis::new(Scale::Log, 206.0, 300.0, false);
        assert_eq!(a.labels(), ["200", "220", "240", "260", "280", "300"]);
        let a = Axis::new(Scale::Log, 190.5, 287.0, false);
        assert_eq!((a.lo, a.hi), (190.0, 290.0));
        assert_eq!(a.labels(), ["200", "220", "240", "260", "280"]);
        let a = Axis::new(Scale::Log, 0.011, 0.09, false);
        assert_eq!(a.labels().len(), 8);
        assert_eq!(a.labels()[0], "0.02");
        // Fig. 5's rescaled time, 60..8000: two whole decades, labelled where they fall (this
        // fell back to a linear 2000..8000 that left the left half of the axis unlabelled).
        let a = Axis::new(Scale::Log, 61.0, 7800.0, false);
        assert_eq!(a.labels(), ["100", "1000"]);
    }

    #[test]
    fn log_axes_span_at_most_twelve_decades() {
        let a = Axis::fit([1e-45, 1e-30, 5e-3], Scale::Log, None);
        assert!(a.hi / a.lo <= 1.000001e12, "{} {}", a.lo, a.hi);
        let a = Axis::new(Scale::Log, 1e-45, 5e-3, false);
        assert!(a.hi / a.lo <= 1.000001e12);
        assert!(a.labels().len() <= 8);
        assert_eq!(
            data_range([1e-45, 1e-3, 2e-3, 1e-2], Scale::Log, Some(1e-3)),
            Some((1e-3, 1e-2))
        );
    }

    #[test]
    fn legend_goes_to_an_empty_corner_or_outside() {
        let e = vec![LegendEntry {
            label: "a".into(),
            color: color(0),
            width: 2,
            dashed: false,
            marker: false,
        }];
        let falling = densify(&[(0.0, 1.0), (1.0, 0.0)], 0.01);
        assert_eq!(
            legend_place(&e, &falling, (800, 500)),
            LegendPlace::UpperRight
        );
        let rising = densify(&[(0.0, 0.0), (1.0, 1.0)], 0.01);
        assert_eq!(
            legend_place(&e, &rising, (800, 500)),
            LegendPlace::UpperLeft
        );
        let full: Vec<(f64, f64)> = (0..=20)
            .flat_map(|i| (0..=20).map(move |j| (i as f64 / 20.0, j as f64 / 20.0)))
            .collect();
        assert_eq!(legend_place(&e, &full, (800, 500)), LegendPlace::Outside);
    }

    #[test]
    fn clipping_cuts_at_the_frame() {
        let runs = clip_polyline(
            &[(-1.0, 0.5), (0.5, 0.5), (2.0, 0.5)],
            &(0.0..1.0),
            &(0.0..1.0),
        );
        assert_eq!(runs, vec![vec![(0.0, 0.5), (0.5, 0.5), (1.0, 0.5)]]);
        let runs = clip_polyline(
            &[(0.2, -5.0), (0.4, 0.5), (0.6, -5.0)],
            &(0.0..1.0),
            &(0.0..1.0),
        );
        assert_eq!(runs.len(), 1);
        assert!(runs[0].iter().all(|p| p.1 >= 0.0));
    }
}
