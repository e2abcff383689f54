//! REPORT.md: the Fig. 3 section.

use super::text::sig;
use crate::reproduce::figures::Fig3;
use std::fmt::Write;

/// `## Fig. 3`: definitions, the container energy and the pulses outside.
pub(super) fn section(f: &Fig3) -> String {
    let mut s = String::new();
    let w = &mut s;
    let _ = writeln!(
        w,
        "## Fig. 3: leaks of the standard container (a), walls m = 10\n"
    );
    let _ = writeln!(
        w,
        "Scene `fig3-standard-container.toml` (container at grains {}-{}, free ends {} grains away on the left, \
         the striker at the right end). Snapshot {} (`fig3_snapshot.csv`, `fig3.svg`).\n",
        f.container.0,
        f.container.1,
        f.container.0 - f.first_grain,
        f.snap.index
    );
    let _ = writeln!(
        w,
        "- **Incident energy** = the energy of the solitary wave launched by the striker, measured as the \
         largest pulse right of the container at snapshot {}: {} ({} % of the striker's {}; the rest is the \
         striker's slow rebound).",
        f.incident_index,
        sig(f.incident.energy),
        sig(100.0 * f.incident.energy / f.striker_energy),
        sig(f.striker_energy)
    );
    let _ = writeln!(
        w,
        "- **Leading waves** = the outermost pulses left and right of the container at snapshot {}, pulses found \
         over the whole chain with threshold {:e} and valley {}, excluding pulses touching an end of the chain \
         (the striker's rebound).",
        f.snap.index, f.rule.threshold, f.rule.valley
    );
    let _ = writeln!(
        w,
        "- Energy still in the container: {} % of the incident energy. The furthest disturbance stayed {} grains from the left end.\n",
        sig(100.0 * f.container_energy / f.incident.energy),
        f.margin
    );
    let _ = writeln!(
        w,
        "| side | grains | energy, % of incident | peak velocity |"
    );
    let _ = writeln!(w, "|---|---|---|---|");
    for (side, p) in &f.outside {
        let _ = writeln!(
            w,
            "| {side} | {}-{} | {} | {} |",
            p.first,
            p.last,
            sig(100.0 * p.fraction),
            sig(p.peak_velocity)
        );
    }
    let _ = writeln!(w);
    s
}
