//! REPORT.md: the Fig. 1 section.

use super::text::sig;
use crate::reproduce::figures::Fig1;
use std::fmt::Write;

/// `## Fig. 1`: the interface, the energy balance and the transmitted waves.
pub(super) fn section(f: &Fig1) -> String {
    let mut s = String::new();
    let w = &mut s;
    let _ = writeln!(w, "## Fig. 1: heavy-to-light interface\n");
    let _ = writeln!(
        w,
        "Scene `fig1-heavy-to-light.toml`: {} heavy grains (m = 10) then {} light ones (m = 1), Hertz, \
         a striker of the heavy mass. Snapshots {} (t = {}) and {} (t = {}); `fig1_snapshots.csv`, `fig1.svg`. \
         Pulse rule: threshold {:e} of the largest grain energy in the light section, valley {}.\n",
        f.heavy,
        f.light,
        f.before.index,
        f.before.time,
        f.after.index,
        f.after.time,
        f.rule.threshold,
        f.rule.valley
    );
    let _ = writeln!(
        w,
        "- Striker energy {}; incident solitary wave {} (grains {}-{}).",
        sig(f.striker_energy),
        sig(f.incident.energy),
        f.incident.first,
        f.incident.last
    );
    let _ = writeln!(
        w,
        "- Light section at the end: {} % of the incident energy; heavy section {} % (control run without the interface: {} %, the striker's own rebound); reflected: {} %.",
        sig(100.0 * f.light_after / f.incident.energy),
        sig(100.0 * f.heavy_after / f.incident.energy),
        sig(100.0 * f.heavy_control / f.incident.energy),
        sig(100.0 * f.reflected / f.incident.energy)
    );
    let _ = writeln!(
        w,
        "- The furthest disturbance stayed {} grains from the light section's end.\n",
        f.margin
    );
    let _ = writeln!(
        w,
        "| wave | grains | energy, % of incident | peak velocity |"
    );
    let _ = writeln!(w, "|---|---|---|---|");
    for (k, p) in f.transmitted.iter().enumerate().take(12) {
        let _ = writeln!(
            w,
            "| {} | {}-{} | {} | {} |",
            k + 1,
            p.first,
            p.last,
            sig(100.0 * p.fraction),
            sig(p.peak_velocity)
        );
    }
    if f.transmitted.len() > 12 {
        let _ = writeln!(
            w,
            "| ... | {} more in `fig1_pulses.csv` | | |",
            f.transmitted.len() - 12
        );
    }
    let _ = writeln!(w);
    s
}
