//! REPORT.md: the Fig. 4 section.

use super::text::sig;
use crate::reproduce::analyse::Results;
use crate::reproduce::plan::{ContainerRun, JobKey};
use crate::reproduce::VARIANT_SNAPSHOTS;
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
pub(super) fn section(out: &Results) -> String {
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
    for r in out.runs.iter().filter(|r| is_container_run(&r.key)) {
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
    for v in out.variants.iter().filter(|v| v.variant.is_outer_chain()) {
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
