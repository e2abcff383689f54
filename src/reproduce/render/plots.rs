//! The figures as SVG (plotters, SVG backend only; text is left to the SVG viewer's fonts).

use crate::error::Error;
use crate::reproduce::analyse::Results;
use crate::reproduce::figures::{ContainerFit, Fig1, Fig3};
use crate::reproduce::{Figure, Options};
use plotters::prelude::*;

const SIZE: (u32, u32) = (960, 540);
const FONT: (&str, u32) = ("sans-serif", 18);
use crate::report::plot::PALETTE;

fn perr<E: std::fmt::Debug>(name: &str) -> impl Fn(E) -> Error + '_ {
    move |e| {
        crate::reproduce::ReproduceError::Drawing {
            name: name.to_string(),
            message: format!("{e:?}"),
        }
        .into()
    }
}

/// An SVG file's name and text.
pub struct Svg {
    pub name: &'static str,
    pub text: String,
}

/// Every figure of `out`.
pub fn all(opts: &Options, out: &Results) -> Result<Vec<Svg>, Error> {
    let mut svgs = Vec::new();
    if let Some(f) = &out.fig1 {
        svgs.push(fig1(f)?);
    }
    if let Some(f) = &out.fig3 {
        svgs.push(fig3(f)?);
    }
    if let Some(fits) = &out.fits {
        if opts.wants(Figure::Fig4) {
            svgs.push(fig4(fits)?);
        }
        if opts.wants(Figure::Fig5) {
            svgs.push(fig5(fits)?);
        }
    }
    Ok(svgs)
}

fn save(name: &'static str, text: String) -> Result<Svg, Error> {
    Ok(Svg { name, text })
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

/// Velocity against grain number, one line per snapshot.
fn velocity_plot(
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

fn fig1(f: &Fig1) -> Result<Svg, Error> {
    let svg = velocity_plot(
        "fig1.svg",
        "Fig. 1: solitary wave through a heavy-to-light interface (mass ratio 10)",
        f.first_grain,
        &[
            (
                format!("t = {} (snapshot {})", f.before.time, f.before.index),
                &f.before.velocity,
            ),
            (
                format!("t = {} (snapshot {})", f.after.time, f.after.index),
                &f.after.velocity,
            ),
        ],
        &[(f.interface as f64 - 0.5, "interface")],
    )?;
    save("fig1.svg", svg)
}

fn fig3(f: &Fig3) -> Result<Svg, Error> {
    let svg = velocity_plot(
        "fig3.svg",
        &format!(
            "Fig. 3: snapshot {} of the standard container (reconstructed layout)",
            f.snap.index
        ),
        f.first_grain,
        &[(format!("snapshot {}", f.snap.index), &f.snap.velocity)],
        &[
            (f.container.0 as f64 - 0.5, "container edges"),
            (f.container.1 as f64 + 0.5, "container edges"),
        ],
    )?;
    save("fig3.svg", svg)
}

/// Fig. 4: remaining energy against snapshots, linear axes.
fn fig4(fits: &[ContainerFit]) -> Result<Svg, Error> {
    let name = "fig4.svg";
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, SIZE).into_drawing_area();
        root.fill(&WHITE).map_err(perr(name))?;
        let n = fits.iter().map(|c| c.er.len()).max().unwrap_or(2) as f64 - 1.0;
        let ymax = fits
            .iter()
            .flat_map(|c| c.er.iter().map(move |x| 100.0 * x / c.e0))
            .fold(0.0, f64::max)
            * 1.05;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                "Fig. 4: energy remaining in the container (reconstructed layouts)",
                FONT,
            )
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(0f64..n, 0f64..ymax.max(1.0))
            .map_err(perr(name))?;
        chart
            .configure_mesh()
            .x_desc("time (snapshots)")
            .y_desc("E_R (% of the striker's energy)")
            .draw()
            .map_err(perr(name))?;
        for (k, c) in fits.iter().enumerate() {
            let col = PALETTE[k % PALETTE.len()];
            chart
                .draw_series(LineSeries::new(
                    c.er.iter()
                        .enumerate()
                        .map(|(t, &e)| (t as f64, 100.0 * e / c.e0)),
                    col.stroke_width(1),
                ))
                .map_err(perr(name))?
                .label(format!("({}) {}", c.key, c.label))
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], col));
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()
            .map_err(perr(name))?;
        root.present().map_err(perr(name))?;
    }
    save(name, svg)
}

fn alpha(c: &ContainerFit) -> f64 {
    c.collapse.map_or(1.0, |x| x.alpha)
}

/// A container's curve for Fig. 5: (alpha t, E_R in %) from its maximum on (before it, only the
/// incident wave's super-exponentially small precursor has entered).
fn rescaled(c: &ContainerFit) -> Vec<(f64, f64)> {
    let a = alpha(c);
    let peak =
        c.er.iter()
            .enumerate()
            .fold(
                (0, f64::NEG_INFINITY),
                |b, (t, &e)| if e > b.1 { (t, e) } else { b },
            )
            .0;
    c.er.iter()
        .enumerate()
        .skip(peak.max(1))
        .filter(|(_, &e)| e > 0.0)
        .map(|(t, &e)| (a * t as f64, 100.0 * e / c.e0))
        .collect()
}

/// The power law `f` over `window`, 21 log-spaced points.
fn fit_line(window: (usize, usize), f: crate::analysis::PowerFit) -> Vec<(f64, f64)> {
    let (lo, hi) = (window.0.max(1) as f64, window.1 as f64);
    (0..=20)
        .map(|j| {
            let t = lo * (hi / lo).powf(j as f64 / 20.0);
            (t, f.a * t.powf(-f.gamma))
        })
        .collect()
}

/// Fig. 5: log-log, time of each container multiplied by its fitted alpha, with the power law
/// fitted to (a).
fn fig5(fits: &[ContainerFit]) -> Result<Svg, Error> {
    let name = "fig5.svg";
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, SIZE).into_drawing_area();
        root.fill(&WHITE).map_err(perr(name))?;
        let pts: Vec<Vec<(f64, f64)>> = fits.iter().map(rescaled).collect();
        let all = pts.iter().flatten();
        let (x0, x1) = all.clone().fold((f64::INFINITY, 0.0f64), |(a, b), p| {
            (a.min(p.0), b.max(p.0))
        });
        let (y0, y1) = all.fold((f64::INFINITY, 0.0f64), |(a, b), p| {
            (a.min(p.1), b.max(p.1))
        });
        if !(x0.is_finite() && y0.is_finite() && x1 > x0 && y1 > y0) {
            return Err(crate::reproduce::ReproduceError::NothingToPlot { figure: "fig5" }.into());
        }
        let mut chart = ChartBuilder::on(&root)
            .caption(
                "Fig. 5: E_R against rescaled time alpha t (log-log), power law fitted to (a)",
                FONT,
            )
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(
                (x0 * 0.9..x1 * 1.1).log_scale(),
                (y0 * 0.8..y1 * 1.25).log_scale(),
            )
            .map_err(perr(name))?;
        chart
            .configure_mesh()
            .x_desc("alpha t (snapshots)")
            .y_desc("E_R (% of the striker's energy)")
            .draw()
            .map_err(perr(name))?;
        for (k, (c, p)) in fits.iter().zip(&pts).enumerate() {
            let col = PALETTE[k % PALETTE.len()];
            chart
                .draw_series(LineSeries::new(p.iter().copied(), col.stroke_width(1)))
                .map_err(perr(name))?
                .label(format!("({}) alpha = {:.3}", c.key, alpha(c)))
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], col));
        }
        if let Some(a) = fits.iter().find(|c| c.key == "a") {
            if let Some(f) = a.fit {
                let line = fit_line(a.window, f);
                chart
                    .draw_series(LineSeries::new(line, BLACK.stroke_width(3)))
                    .map_err(perr(name))?
                    .label(format!("fit to (a): E_R = {:.4} t^-{:.4}", f.a, f.gamma))
                    .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK));
            }
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::LowerLeft)
            .draw()
            .map_err(perr(name))?;
        root.present().map_err(perr(name))?;
    }
    save(name, svg)
}
