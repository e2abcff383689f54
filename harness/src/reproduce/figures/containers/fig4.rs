//! Fig. 4's outputs: `fig4_energy.csv`, `fig4_outer_chain.csv`, `fig4.svg` and its section of
//! REPORT.md.

use super::ContainerFit;
use super::VariantResult;
use crate::error::Error;
use crate::report::plot::{LineChart, Series};
use crate::reproduce::jobs::RunEntry;
use crate::reproduce::options::VARIANT_SNAPSHOTS;
use crate::reproduce::plan::{ContainerRun, JobKey};
use crate::reproduce::render::text::{num, opt, opt_k, sig};
use crate::reproduce::table::Table;
use crate::reproduce::unit::Svg;
use std::fmt::Write;

fn is_container_run(k: &JobKey) -> bool {
    matches!(
        k,
        JobKey::Container {
            run: ContainerRun::Main,
            ..
        }
    )
}

/// `## Fig. 4`: the end margins of the container runs and the outer-chain variants.
pub(super) fn section(runs: &[RunEntry], variants: &[VariantResult]) -> String {
    let mut s = String::new();
    let w = &mut s;
    let _ = writeln!(w, "## Fig. 4: energy remaining in containers (a)-(e)\n");
    let _ = writeln!(
        w,
        "Scenes `containers/*.toml` (linear walls m = 2); `fig4_energy.csv` (every snapshot), `fig4.svg`. \
         E_R is the energy of the grains of region `container` (each grain's kinetic energy plus half of \
         each of its contacts' potential).\n"
    );
    let _ = writeln!(w, "**Nothing comes back from the outer chains.** Every container run fails if a disturbance reaches either end of its chain; the margins (grains between the furthest disturbance and the nearer end) were:\n");
    let _ = writeln!(
        w,
        "| run | grains | margin | method | dt | wall time (s) | max relative energy error |"
    );
    let _ = writeln!(w, "|---|---|---|---|---|---|---|");
    for r in runs.iter().filter(|r| is_container_run(&r.key)) {
        let _ = writeln!(
            w,
            "| {} | {} | {} | {} | {} | {:.1} | {:.1e} |",
            r.label(),
            r.run.grains,
            r.run.end_margin(),
            r.run.method,
            sig(r.run.dt),
            r.wall,
            r.run.max_energy_error
        );
    }
    let _ = writeln!(w);
    let _ = writeln!(w, "Outer-chain treatment, container (a), first {} snapshots at most (`fig4_outer_chain.csv`):\n", VARIANT_SNAPSHOTS);
    for v in variants.iter().filter(|v| v.variant.is_outer_chain()) {
        let _ = writeln!(
            w,
            "- **{}** ({}): max relative difference of E_R from the default {} (at snapshot {}); first differing bit at snapshot {}.{}",
            v.variant.key(),
            v.variant.change(),
            sig(v.diff.max_rel),
            v.diff.at,
            v.diff.first_bit_difference.map_or("never".into(), |k| k.to_string()),
            v.margin.map_or(String::new(), |m| format!(" End margin {m} grains."))
        );
    }
    let _ = writeln!(
        w,
        "\nOuter chains of two lengths that no disturbance reaches give the same curve bit for bit (untouched \
         grains are skipped exactly, so a longer chain cannot change anything); free ends 120 grains from the \
         container are reached, and the curve departs from the long-chain one from the snapshot shown.\n"
    );
    s
}

/// `fig4_energy.csv`, `fig4_outer_chain.csv`.
pub(super) fn tables(variants: &[VariantResult], fits: &[ContainerFit]) -> Vec<Table> {
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
    for v in variants.iter().filter(|v| v.variant.is_outer_chain()) {
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

/// `fig4.svg`: remaining energy against snapshots, linear axes.
pub(super) fn svg(fits: &[ContainerFit]) -> Result<Svg, Error> {
    let text = LineChart {
        title: "Fig. 4: energy remaining in the container (reconstructed layouts)",
        x_label: "time (snapshots)",
        y_label: "E_R (% of the striker's energy)",
        series: fits
            .iter()
            .map(|c| Series {
                name: format!("({}) {}", c.key, c.label),
                points: c
                    .percent
                    .iter()
                    .enumerate()
                    .map(|(t, &p)| (t as f64, p))
                    .collect(),
                ..Default::default()
            })
            .collect(),
        ..Default::default()
    }
    .to_svg()?;
    Ok(Svg {
        name: "fig4.svg",
        text,
    })
}
