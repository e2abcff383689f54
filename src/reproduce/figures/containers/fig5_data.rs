//! Fig. 5's data: `fig5_fits.csv`, `fig5_windows.csv`, `fig5_variants.csv`,
//! `fig5_collapse.csv` and `fig5.svg` (its text in REPORT.md is in `fig5.rs`).

use super::ContainerFit;
use crate::error::Error;
use crate::paper;
use crate::report::plot::PALETTE;
use crate::reproduce::figures::Results;
use crate::reproduce::render::plots::{perr, FONT, SIZE};
use crate::reproduce::render::text::{num, opt, opt_k};
use crate::reproduce::render::Svg;
use crate::reproduce::table::Table;
use plotters::prelude::*;

/// `fig5_fits.csv`, `fig5_windows.csv`, `fig5_variants.csv`, `fig5_collapse.csv`.
pub(super) fn tables(out: &Results, fits: &[ContainerFit]) -> Vec<Table> {
    vec![
        fits_table(fits),
        windows_table(fits),
        variants_table(out),
        collapse_table(fits),
    ]
}

/// `fig5_fits.csv`.
fn fits_table(fits: &[ContainerFit]) -> Table {
    let mut t = Table::new(
        "fig5_fits.csv",
        &[
            "container",
            "alpha",
            "alpha_paper",
            "collapse_rms",
            "overlap_lo",
            "overlap_hi",
            "onset",
            "fit_lo",
            "fit_hi",
            "bins",
            "gamma",
            "se",
            "ci_lo",
            "ci_hi",
            "A_percent",
        ],
    );
    for c in fits {
        let f = c.fit;
        t.push(vec![
            c.key.as_str().into(),
            opt(c.collapse.map(|x| x.alpha)),
            opt(paper::alpha(&c.key)),
            opt(c.collapse.map(|x| x.rms)),
            opt(c.collapse.map(|x| x.t_lo)),
            opt(c.collapse.map(|x| x.t_hi)),
            opt_k(c.onset),
            c.window.0.into(),
            c.window.1.into(),
            opt_k(f.map(|f| f.n)),
            opt(f.map(|f| f.gamma)),
            opt(f.map(|f| f.se)),
            opt(f.map(|f| f.ci_lo)),
            opt(f.map(|f| f.ci_hi)),
            opt(f.map(|f| f.a)),
        ]);
    }
    t
}

/// `fig5_windows.csv`.
fn windows_table(fits: &[ContainerFit]) -> Table {
    let mut t = Table::new(
        "fig5_windows.csv",
        &[
            "container",
            "fit_lo",
            "fit_hi",
            "bins",
            "gamma",
            "ci_lo",
            "ci_hi",
        ],
    );
    for c in fits {
        for (w, f) in &c.windows {
            t.push(vec![
                c.key.as_str().into(),
                w.0.into(),
                w.1.into(),
                opt_k(f.map(|f| f.n)),
                opt(f.map(|f| f.gamma)),
                opt(f.map(|f| f.ci_lo)),
                opt(f.map(|f| f.ci_hi)),
            ]);
        }
    }
    t
}

/// `fig5_variants.csv`.
fn variants_table(out: &Results) -> Table {
    let mut t = Table::new(
        "fig5_variants.csv",
        &[
            "variant",
            "snapshots",
            "fit_lo",
            "fit_hi",
            "gamma",
            "ci_lo",
            "ci_hi",
            "gamma_default",
            "delta_gamma",
            "max_rel_diff",
            "first_bit_difference",
            "first_above_1e-4",
        ],
    );
    for v in &out.variants {
        t.push(vec![
            v.variant.key().into(),
            v.snapshots.into(),
            v.window.0.into(),
            v.window.1.into(),
            opt(v.fit.map(|f| f.gamma)),
            opt(v.fit.map(|f| f.ci_lo)),
            opt(v.fit.map(|f| f.ci_hi)),
            opt(v.default_fit.map(|f| f.gamma)),
            opt(v.delta_gamma),
            num(v.diff.max_rel),
            opt_k(v.diff.first_bit_difference),
            opt_k(v.diff.first_above_level),
        ]);
    }
    t
}

/// `fig5_collapse.csv`.
fn collapse_table(fits: &[ContainerFit]) -> Table {
    let mut t = Table::new(
        "fig5_collapse.csv",
        &["container", "alpha", "ln_t", "ln_alpha_t", "ln_E_percent"],
    );
    for c in fits {
        for p in &c.collapse_points {
            t.push(vec![
                c.key.as_str().into(),
                num(c.alpha_or_one()),
                num(p.ln_t),
                num(p.ln_alpha_t),
                num(p.ln_e),
            ]);
        }
    }
    t
}

/// An axis range, (low, high).
type Span = (f64, f64);

/// The smallest and largest alpha t and `E_R` of the rescaled curves.
fn extent(fits: &[ContainerFit]) -> Result<(Span, Span), Error> {
    let all = fits.iter().flat_map(|c| &c.rescaled);
    let (x0, x1) = all.clone().fold((f64::INFINITY, 0.0f64), |(a, b), p| {
        (a.min(p.0), b.max(p.0))
    });
    let (y0, y1) = all.fold((f64::INFINITY, 0.0f64), |(a, b), p| {
        (a.min(p.1), b.max(p.1))
    });
    if !(x0.is_finite() && y0.is_finite() && x1 > x0 && y1 > y0) {
        return Err(crate::reproduce::ReproduceError::NothingToPlot { figure: "fig5" }.into());
    }
    Ok(((x0, x1), (y0, y1)))
}

/// `fig5.svg`: log-log, time of each container multiplied by its fitted alpha, with the power law
/// fitted to (a).
pub(super) fn svg(fits: &[ContainerFit]) -> Result<Svg, Error> {
    let name = "fig5.svg";
    let ((x0, x1), (y0, y1)) = extent(fits)?;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, SIZE).into_drawing_area();
        root.fill(&WHITE).map_err(perr(name))?;
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
        for (k, c) in fits.iter().enumerate() {
            let col = PALETTE[k % PALETTE.len()];
            chart
                .draw_series(LineSeries::new(
                    c.rescaled.iter().copied(),
                    col.stroke_width(1),
                ))
                .map_err(perr(name))?
                .label(format!("({}) alpha = {:.3}", c.key, c.alpha_or_one()))
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], col));
        }
        if let Some(a) = fits.iter().find(|c| c.key == "a") {
            if let Some(f) = a.fit {
                chart
                    .draw_series(LineSeries::new(
                        a.fit_curve.iter().copied(),
                        BLACK.stroke_width(3),
                    ))
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
    Ok(Svg { name, text: svg })
}
