//! REPORT.md: the shared sections (header, the paper comparison table, the runs) around the
//! units' parts.

use super::step_check;
use super::text::sig;
use crate::reproduce::jobs::RunEntry;
use crate::reproduce::options::Options;
use crate::reproduce::unit::Part;
use std::fmt::Write;

const RECONSTRUCTION: &str =
    "**The container layouts are a reconstruction.** The paper's Fig. 2 is lost; \
    the layouts used here are the reading of its text in `docs/containers.md` (in the grainchain \
    repository), kept as scene files in `scenes/` (`fig3-standard-container.toml`, \
    `containers/*.toml`). Every number below that depends on a container is a number for that \
    reconstruction, not for the paper's lost layouts.";

/// REPORT.md: the header, the paper comparison (every unit's rows), every unit's sections, the
/// step-size check, the runs, then `opts.appendix`.
pub(super) fn markdown(opts: &Options, wall: f64, runs_: &[RunEntry], parts: &[Part]) -> String {
    let mut s = header(opts, wall, runs_);
    s.push_str(&compare(parts));
    for p in parts {
        s.push_str(&p.section);
    }
    let checks: Vec<_> = parts.iter().flat_map(|p| &p.checks).collect();
    if !checks.is_empty() {
        s.push_str(&step_check::section(&checks));
    }
    s.push_str(&runs(runs_));
    for section in &opts.appendix {
        s.push_str(section);
    }
    s
}

/// `## Every number the paper states, beside ours`: the units' rows under one header.
fn compare(parts: &[Part]) -> String {
    let mut s = String::new();
    let w = &mut s;
    let _ = writeln!(w, "## Every number the paper states, beside ours\n");
    let _ = writeln!(
        w,
        "| figure | quantity | paper | ours | difference | why they differ |"
    );
    let _ = writeln!(w, "|---|---|---|---|---|---|");
    for p in parts {
        s.push_str(&p.compare);
    }
    s.push('\n');
    s
}

/// Title, the reconstruction caveat, how the report was made.
fn header(opts: &Options, wall: f64, runs: &[RunEntry]) -> String {
    let mut s = String::new();
    let w = &mut s;
    let _ = writeln!(w, "# Reproducing Hong (2005), PRL 94, 108001\n");
    let _ = writeln!(w, "{RECONSTRUCTION}\n");
    let _ = writeln!(
        w,
        "Written by `grainchain reproduce` in {:.1} s of wall time ({} simulations on {} threads). \
         Scenes: `{}`. Open choices of the reconstruction (defaults): interface rule `min-exponent`, \
         compression-only linear walls, time counted in snapshots from the strike, outer chains long \
         enough that nothing comes back.\n",
        wall,
        runs.len(),
        // The pool starts at most one thread per simulation (`batch::Pool`).
        opts.threads.clamp(1, runs.len().max(1)),
        opts.scenes.display()
    );
    if let Some(n) = opts.snapshots {
        let _ = writeln!(
            w,
            "**Shortened run:** Fig. 4/5 ran for {n} snapshots (`--snapshots {n}`), not the scene files' \
             length; fits and rescalings below are over that shorter run and are not the paper's.\n"
        );
    }
    s
}

/// `## Runs` and the determinism note.
fn runs(runs: &[RunEntry]) -> String {
    let mut s = String::new();
    let w = &mut s;
    let _ = writeln!(w, "## Runs\n");
    let _ = writeln!(w, "| run | grains | touched | method | dt | steps | wall time (s) | max relative energy error |");
    let _ = writeln!(w, "|---|---|---|---|---|---|---|---|");
    for r in runs {
        let _ = writeln!(
            w,
            "| {} | {} | {}-{} | {} | {} | {} | {:.2} | {:.1e} |",
            r.label(),
            r.run.grains,
            r.run.ever.0,
            r.run.ever.1,
            r.run.method,
            sig(r.run.dt),
            r.run.stats.steps,
            r.wall,
            r.run.max_energy_error
        );
    }
    let _ = writeln!(
        w,
        "\nDeterminism: the same scenes give the same bits on every run and thread count. The force kernels give \
         the same bits with and without AVX2 (ARCHITECTURE.md); the only platform-dependent math is libm `pow` \
         (in the contact potentials, exponents 2, 2.5 and 3 here, and for exponents other than 1, 1.5 and 2 in \
         forces). Another libm may differ in the last bit of a potential; that changes E_R by ~1e-16 relative, \
         far inside every golden tolerance (the trajectory itself does not use the potentials)."
    );
    s
}
