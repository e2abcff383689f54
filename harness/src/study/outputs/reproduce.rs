//! `reproduce --members`: the ensemble section of REPORT.md, rendered from the study of the
//! containers (the CLI runs the study and hands this section to `reproduce`).

use super::Study;
use crate::batch::scenes::TWIN_EPS;
use grainchain_engine::paper;

/// `## Ensemble`: gamma and alpha with intervals over members.
pub fn reproduce_section(st: &Study, wall: f64, threads: usize) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    let n = st.containers.first().map_or(0, |k| k.members);
    // The pool starts at most one thread per member run (`batch::Pool`).
    let jobs: usize = st.containers.iter().map(|k| k.members).sum();
    let threads = threads.clamp(1, jobs.max(1));
    let _ = writeln!(
        s,
        "\n## Ensemble: gamma and alpha with intervals over members\n\n`reproduce --members {n}`: \
         every container as {n} members whose striker speeds differ by k x {TWIN_EPS:e} \
         (k = 0..{}), integrated with multiple time stepping (outer chains at 16 dt; checked \
         against single-rate ensembles in studies/multirate-check.toml). Intervals: 95 %, \
         delete-one jackknife over members. {wall:.1} s on {threads} threads. All tables and \
         figures of the ensemble: `ensemble/STUDY.md`.\n",
        n.saturating_sub(1)
    );
    let _ = writeln!(
        s,
        "| container | gamma of the ensemble mean [95 %] | window | alpha by collapse | alpha at E_R = 10 % [95 %] | paper alpha |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|");
    for k in &st.containers {
        let g = k.fit.est.map_or_else(
            || format!("n/a ({})", k.fit.why_missing()),
            |e| format!("{:.3} [{:.3}, {:.3}]", e.value, e.ci_lo, e.ci_hi),
        );
        let col = st
            .collapse
            .iter()
            .find(|c| c.0 == k.key)
            .and_then(|c| c.1)
            .map_or(
                if k.key == "a" {
                    "1 (reference)".into()
                } else {
                    "n/a".into()
                },
                |c| format!("{:.3}", c.alpha),
            );
        let lv = st
            .alpha
            .iter()
            .find(|a| a.key == k.key && a.level == 0.1)
            .map_or("n/a".into(), |a| match a.alpha {
                Some(x) if a.ci_lo.is_finite() => {
                    format!("{x:.3} [{:.3}, {:.3}]", a.ci_lo, a.ci_hi)
                }
                Some(x) => format!("{x:.3}"),
                None => "not reached".into(),
            });
        let _ = writeln!(
            s,
            "| ({}) | {g} | [{}, {}] | {col} | {lv} | {} |",
            k.key,
            k.fit.t_lo,
            k.fit.t_hi,
            paper::alpha(&k.key).map_or("n/a".into(), |a| format!("{a}"))
        );
    }
    let _ = writeln!(
        s,
        "\nPaper: gamma = {} for every container. The local slope of each ensemble mean \
         (`ensemble/slope.svg`) is not constant over the window: see `ensemble/STUDY.md`.",
        paper::GAMMA
    );
    // The verdict on these containers, one level down (a section of this section).
    s.push_str(&super::report::universality(st).replacen("\n## ", "\n### ", 1));
    s
}
