//! The CSV tables of a `reproduce` run, one function per figure's tables.

use super::text::{num, opt, opt_k};
use crate::paper;
use crate::reproduce::analyse::Results;
use crate::reproduce::figures::{ContainerFit, Fig1, Fig3, PulseOut};
use crate::reproduce::table::{Cell, Table};
use crate::reproduce::{Figure, Options};

fn pulse_row(lead: Cell, p: &PulseOut, scale: f64) -> Vec<Cell> {
    vec![
        lead,
        p.first.into(),
        p.last.into(),
        num(p.position),
        num(p.peak_velocity),
        num(p.energy),
        num(scale * p.fraction),
    ]
}

/// Every CSV table of the run.
pub fn all(opts: &Options, out: &Results) -> Vec<Table> {
    let mut ts = Vec::new();
    if let Some(f) = &out.fig1 {
        ts.extend(fig1(f));
    }
    if let Some(f) = &out.fig3 {
        ts.extend(fig3(f));
    }
    if let Some(fits) = &out.fits {
        if opts.wants(Figure::Fig4) {
            ts.extend(fig4(out, fits));
        }
        if opts.wants(Figure::Fig5) {
            ts.push(fig5_fits(fits));
            ts.push(fig5_windows(fits));
            ts.push(fig5_variants(out));
            ts.push(fig5_collapse(fits));
        }
    }
    ts.push(runs(out));
    if !out.step_checks.is_empty() {
        ts.push(super::step_check::table(&out.step_checks));
    }
    ts
}

/// `fig1_snapshots.csv`, `fig1_pulses.csv`.
fn fig1(f: &Fig1) -> Vec<Table> {
    let mut ts = Vec::new();
    let mut t = Table::new(
        "fig1_snapshots.csv",
        &["grain", "velocity_before", "velocity_after"],
    );
    for (i, (a, b)) in f.before.velocity.iter().zip(&f.after.velocity).enumerate() {
        t.push(vec![(i as i64 + f.first_grain).into(), num(*a), num(*b)]);
    }
    ts.push(t);
    let mut t = Table::new(
        "fig1_pulses.csv",
        &[
            "rank",
            "first",
            "last",
            "position",
            "peak_velocity",
            "energy",
            "fraction_of_incident",
        ],
    );
    for (k, p) in f.transmitted.iter().enumerate() {
        t.push(pulse_row((k + 1).into(), p, 1.0));
    }
    ts.push(t);
    ts
}

/// `fig3_snapshot.csv`, `fig3_pulses.csv`.
fn fig3(f: &Fig3) -> Vec<Table> {
    let mut ts = Vec::new();
    let mut t = Table::new("fig3_snapshot.csv", &["grain", "velocity", "energy"]);
    for (i, (v, e)) in f.snap.velocity.iter().zip(&f.snap.energy).enumerate() {
        t.push(vec![(i as i64 + f.first_grain).into(), num(*v), num(*e)]);
    }
    ts.push(t);
    let mut t = Table::new(
        "fig3_pulses.csv",
        &[
            "side",
            "first",
            "last",
            "position",
            "peak_velocity",
            "energy",
            "percent_of_incident",
        ],
    );
    t.push(pulse_row("incident".into(), &f.incident, 100.0));
    for (side, p) in &f.outside {
        t.push(pulse_row((*side).into(), p, 100.0));
    }
    ts.push(t);
    ts
}

/// `fig4_energy.csv`, `fig4_outer_chain.csv`.
fn fig4(out: &Results, fits: &[ContainerFit]) -> Vec<Table> {
    let mut ts = Vec::new();
    let mut cols = vec!["snapshot".to_string()];
    cols.extend(fits.iter().map(|c| format!("E_{}", c.key)));
    let n = fits.iter().map(|c| c.er.len()).max().unwrap_or(0);
    let mut t = Table {
        name: "fig4_energy.csv".into(),
        columns: cols,
        rows: Vec::new(),
    };
    for k in 0..n {
        let mut r = vec![k.into()];
        r.extend(fits.iter().map(|c| opt(c.er.get(k).copied())));
        t.push(r);
    }
    ts.push(t);
    let mut t = Table::new(
        "fig4_outer_chain.csv",
        &[
            "comparison",
            "snapshots",
            "max_rel_diff",
            "at_snapshot",
            "first_bit_difference",
            "first_above_1e-4",
            "end_margin",
        ],
    );
    for v in out.variants.iter().filter(|v| v.variant.is_outer_chain()) {
        t.push(vec![
            v.variant.key().into(),
            v.snapshots.into(),
            num(v.diff.max_rel),
            v.diff.at.into(),
            opt_k(v.diff.first_bit_difference),
            opt_k(v.diff.first_above_level),
            opt_k(v.margin),
        ]);
    }
    ts.push(t);
    ts
}

/// `fig5_fits.csv`.
fn fig5_fits(fits: &[ContainerFit]) -> Table {
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
fn fig5_windows(fits: &[ContainerFit]) -> Table {
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
fn fig5_variants(out: &Results) -> Table {
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
        let g = v.fit.map(|f| f.gamma);
        let g0 = v.default_fit.map(|f| f.gamma);
        t.push(vec![
            v.variant.key().into(),
            v.snapshots.into(),
            v.window.0.into(),
            v.window.1.into(),
            opt(g),
            opt(v.fit.map(|f| f.ci_lo)),
            opt(v.fit.map(|f| f.ci_hi)),
            opt(g0),
            opt(g.zip(g0).map(|(a, b)| a - b)),
            num(v.diff.max_rel),
            opt_k(v.diff.first_bit_difference),
            opt_k(v.diff.first_above_level),
        ]);
    }
    t
}

/// `fig5_collapse.csv`.
fn fig5_collapse(fits: &[ContainerFit]) -> Table {
    let mut t = Table::new(
        "fig5_collapse.csv",
        &["container", "alpha", "ln_t", "ln_alpha_t", "ln_E_percent"],
    );
    for c in fits {
        let alpha = c.collapse.map_or(1.0, |x| x.alpha);
        let pct: Vec<f64> = c.er.iter().map(|x| 100.0 * x / c.e0).collect();
        let start = c.onset.unwrap_or(1).max(2) / 2;
        for p in crate::analysis::log_bins(
            &pct,
            start,
            pct.len() - 1,
            crate::analysis::decay::BINS_PER_DECADE,
        ) {
            t.push(vec![
                c.key.as_str().into(),
                num(alpha),
                num(p.ln_t),
                num(p.ln_t + alpha.ln()),
                num(p.ln_e),
            ]);
        }
    }
    t
}

/// `runs.csv`.
fn runs(out: &Results) -> Table {
    let mut t = Table::new(
        "runs.csv",
        &[
            "run",
            "grains",
            "first_touched",
            "last_touched",
            "end_margin",
            "method",
            "dt",
            "steps",
            "outputs",
            "grain_evaluations",
            "wall_s",
            "max_rel_energy_error",
        ],
    );
    for r in &out.runs {
        t.push(vec![
            r.label().into(),
            r.run.grains.into(),
            r.run.ever.0.into(),
            r.run.ever.1.into(),
            r.run.end_margin().into(),
            r.run.method.into(),
            num(r.run.dt),
            r.run.stats.steps.into(),
            r.recorded.into(),
            r.run.stats.grain_evals.into(),
            num(r.wall),
            num(r.run.max_energy_error),
        ]);
    }
    t
}
