//! REPORT.md, assembled from one pure function per section.

use super::text::sig;
use super::{compare, fig1, fig3, fig4, fig5, step_check};
use crate::reproduce::analyse::Results;
use crate::reproduce::{Figure, Options};
use std::fmt::Write;

const RECONSTRUCTION: &str = "**The container layouts are a reconstruction.** The paper's Fig. 2 is lost; \
    the layouts used here are the reading of its text in `../shared/reference/containers.md`, kept as \
    scene files in `scenes/` (`fig3-standard-container.toml`, `containers/*.toml`). Every number below \
    that depends on a container is a number for that reconstruction, not for the paper's lost layouts.";

/// REPORT.md.
pub fn markdown(opts: &Options, out: &Results) -> String {
    let mut s = header(opts, out);
    s.push_str(&compare::section(opts, out));
    if let Some(f) = &out.fig1 {
        s.push_str(&fig1::section(f));
    }
    if let Some(f) = &out.fig3 {
        s.push_str(&fig3::section(f));
    }
    if let Some(fits) = &out.fits {
        s.push_str(&fig4::section(out));
        if opts.wants(Figure::Fig5) {
            s.push_str(&fig5::section(out, fits));
        }
    }
    if !out.step_checks.is_empty() {
        s.push_str(&step_check::section(&out.step_checks));
    }
    s.push_str(&runs(out));
    for section in &opts.appendix {
        s.push_str(section);
    }
    s
}

/// Title, the reconstruction caveat, how the report was made.
fn header(opts: &Options, out: &Results) -> String {
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
        out.wall,
        out.runs.len(),
        opts.threads,
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
fn runs(out: &Results) -> String {
    let mut s = String::new();
    let w = &mut s;
    let _ = writeln!(w, "## Runs\n");
    let _ = writeln!(w, "| run | grains | touched | method | dt | steps | wall time (s) | max relative energy error |");
    let _ = writeln!(w, "|---|---|---|---|---|---|---|---|");
    for r in &out.runs {
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
