//! Fig. 5's data: `fig5_fits.csv`, `fig5_windows.csv`, `fig5_variants.csv`,
//! `fig5_collapse.csv` and `fig5.svg` (its text in REPORT.md is in `fig5.rs`).

use super::{ContainerFit, VariantResult};
use crate::error::Error;
use crate::report::plot::{LineChart, Scale, Series};
use crate::reproduce::render::text::{num, opt, opt_k, sig};
use crate::reproduce::table::Table;
use crate::reproduce::unit::Svg;
use grainchain_engine::paper;

/// `fig5_fits.csv`, `fig5_windows.csv`, `fig5_variants.csv`, `fig5_collapse.csv`.
pub(super) fn tables(variants: &[VariantResult], fits: &[ContainerFit]) -> Vec<Table> {
    vec![
        fits_table(fits),
        windows_table(fits),
        variants_table(variants),
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
fn variants_table(variants: &[VariantResult]) -> Table {
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
    for v in variants {
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

/// `fig5.svg`: log-log, time of each container multiplied by its fitted alpha, with the power law
/// fitted to (a). The legend gives alpha as REPORT.md does (or says the curve is not rescaled).
pub(super) fn svg(fits: &[ContainerFit]) -> Result<Svg, Error> {
    let mut series: Vec<Series> = fits
        .iter()
        .map(|c| Series {
            name: match c.collapse {
                Some(x) => format!("({}) alpha = {}", c.key, sig(x.alpha)),
                None => format!("({}) no alpha found (not rescaled)", c.key),
            },
            points: c.rescaled.clone(),
            ..Default::default()
        })
        .collect();
    if series.iter().all(|s| s.points.is_empty()) {
        return Err(crate::error::ReproduceError::NothingToPlot { figure: "fig5" }.into());
    }
    if let Some(a) = fits.iter().find(|c| c.key == "a") {
        if let Some(f) = a.fit {
            series.push(Series {
                name: format!("fit to (a): E_R = {:.4} t^-{:.4}", f.a, f.gamma),
                points: a.fit_curve.clone(),
                reference: true,
                ..Default::default()
            });
        }
    }
    let text = LineChart {
        title: "Fig. 5: E_R against rescaled time alpha t (log-log), power law fitted to (a)",
        x_label: "alpha t (snapshots)",
        y_label: "E_R (% of the striker's energy)",
        x_scale: Scale::Log,
        y_scale: Scale::Log,
        series,
        ..Default::default()
    }
    .to_svg()?;
    Ok(Svg {
        name: "fig5.svg",
        text,
    })
}
