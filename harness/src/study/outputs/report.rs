//! STUDY.md: one small function per section, each a pure function of the study's results.

use super::*;
use crate::batch::Gauge;
use crate::study::random::Design;
use grainchain_engine::analysis::decay::{
    BINS_PER_DECADE, SLOPE_BINS_PER_DECADE, SLOPE_HALF_WIDTH, SLOPE_TOLERANCE,
};
use grainchain_engine::analysis::ensemble::{self, Estimate};
use grainchain_engine::analysis::statistics::{self, mean_sd};
use grainchain_engine::analysis::student_t_975;
use std::fmt::Write as _;

fn f3(x: Option<f64>) -> String {
    x.filter(|x| x.is_finite())
        .map_or_else(|| "n/a".into(), |x| format!("{x:.3}"))
}

/// Pearson r with `digits` decimals, or why there is none (`ensemble::pearson_checked`).
fn r_text(x: &[f64], y: &[f64], digits: usize) -> String {
    match ensemble::pearson_checked(x, y) {
        Ok(r) => format!("{r:.digits$}"),
        Err(why) => format!("n/a ({why})"),
    }
}

/// A fit's gamma with its interval, or why there is none.
fn fit_text(w: &WindowFit) -> String {
    match w.est {
        Some(_) => est_text(w.est),
        None => format!("n/a ({})", w.why_missing()),
    }
}

fn est_text(e: Option<Estimate>) -> String {
    match e {
        Some(e) if e.se.is_finite() => {
            format!("{:.3} [{:.3}, {:.3}]", e.value, e.ci_lo, e.ci_hi)
        }
        Some(e) => format!("{:.3} (no interval: {} member)", e.value, e.n),
        None => "n/a".into(),
    }
}

/// STUDY.md: one section per function below, each a pure function of the study's results.
pub fn report(study: &Study) -> String {
    let mut s = String::new();
    header(&mut s, study);
    cost(&mut s, study);
    if !study.containers.is_empty() {
        gamma_of_mean(&mut s, study);
        gamma_per_decade(&mut s, study);
        local_slope(&mut s, study);
    }
    if study.containers.iter().any(|k| !k.level_slopes.is_empty()) {
        slope_at_levels(&mut s, study);
    }
    if !study.alpha.is_empty() {
        alpha_by_level(&mut s, study);
    }
    if !study.containers.is_empty() {
        budget(&mut s, study);
    }
    if !study.random.is_empty() {
        random_containers(&mut s, study);
    }
    if study.containers.iter().any(|k| k.gauges.is_some()) {
        outer_medium(&mut s, study);
    }
    if !study.search.is_empty() {
        search(&mut s, study);
    }
    if !study.containers.is_empty() {
        s.push_str(&universality(study));
    }
    if !study.mechanism.is_empty() {
        s.push_str(&super::mechanism::section(&study.mechanism));
    }
    let _ = writeln!(
        s,
        "\nFiles: ensemble.csv (band per snapshot), fits.csv (gamma of the mean, per decade, per \
         member), slope.csv, alpha.csv, budget.csv, gauges.csv, random.csv, search.csv; er_band.svg, \
         er_band-<group>.svg, slope.svg, budget-<key>.svg, volume-<group>.svg, \
         er_vs_volume.svg, gamma_hist.svg."
    );
    s
}

/// A markdown table header: `| first | a | b |` and its rule.
fn table_head(s: &mut String, first: &str, columns: impl IntoIterator<Item = String>) {
    let mut head = format!("| {first} |");
    let mut rule = String::from("|---|");
    for c in columns {
        let _ = write!(head, " {c} |");
        rule.push_str("---|");
    }
    let _ = writeln!(s, "{head}\n{rule}");
}

fn header(s: &mut String, study: &Study) {
    let _ = writeln!(s, "# Study `{}`\n", study.name);
    if let Some(d) = &study.description {
        let _ = writeln!(s, "{d}\n");
    }
    if !study.missing.is_empty() {
        let _ = writeln!(
            s,
            "**PARTIAL: {} members missing** ({}); every number below uses the members present \
             (the member counts are in the cost table).\n",
            study.missing.len(),
            study.missing.join(", ")
        );
    }
    let _ = writeln!(
        s,
        "Sweep digest `{}`. Every member runs {} snapshots; members differ by: {}. Container \
         layouts of scenes/containers/ are a RECONSTRUCTION (docs/containers.md). \
         Intervals are 95 %, from the spread over members (delete-one jackknife, Student t; \
         engine/src/analysis/ensemble.rs), not from the residuals of one curve.\n",
        study.digest, study.snapshots, study.perturbation
    );
}

fn cost(s: &mut String, study: &Study) {
    let _ = writeln!(s, "## Cost\n");
    let _ = writeln!(
        s,
        "Sum of the members' wall times: {:.1} s (set-up included; on a machine of C cores the \
         study takes about this / C).\n",
        study.job_seconds
    );
    let _ = writeln!(
        s,
        "| key | members | wall per member (s) | max energy error | min end margin (grains) |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|");
    for k in all(study) {
        let _ = writeln!(
            s,
            "| {} | {} | {:.2} | {:.1e} | {} |",
            k.key, k.members, k.wall_per_member, k.max_energy_error, k.min_end_margin
        );
    }
    if !study.searched.is_empty() {
        let n: usize = study.searched.iter().map(|k| k.members).sum();
        let wall: f64 = (study.searched.iter())
            .map(|k| k.wall_per_member * k.members as f64)
            .sum();
        let err = (study.searched.iter()).fold(0.0f64, |a, k| a.max(k.max_energy_error));
        let _ = writeln!(
            s,
            "| search ({} keys) | {n} | {:.2} | {err:.1e} | |",
            study.searched.len(),
            wall / n as f64
        );
    }
}

fn gamma_of_mean(s: &mut String, study: &Study) {
    let _ = writeln!(s, "\n## gamma of the ensemble mean\n");
    let _ = writeln!(
        s,
        "Fit of `E_R / E0 = A t^-gamma` to the ensemble mean over the window (log bins, {} \
         per decade). Member gammas: each member's own fit over the same window, mean +- \
         standard deviation. Paper: gamma = {}.\n",
        BINS_PER_DECADE,
        grainchain_engine::paper::GAMMA
    );
    let _ = writeln!(
        s,
        "| key | window | gamma of the mean [95 %] | member gammas (mean +- sd) |"
    );
    let _ = writeln!(s, "|---|---|---|---|");
    for k in &study.containers {
        let mg: Vec<f64> = k.member_gamma.iter().flatten().copied().collect();
        let m = if mg.len() >= 2 {
            let (m, sd) = mean_sd(&mg);
            format!("{m:.3} +- {sd:.3}")
        } else {
            f3(mg.first().copied())
        };
        let _ = writeln!(
            s,
            "| {} | [{}, {}] | {} | {} |",
            k.key,
            k.fit.t_lo,
            k.fit.t_hi,
            fit_text(&k.fit),
            m
        );
    }
}

fn gamma_per_decade(s: &mut String, study: &Study) {
    let _ = writeln!(s, "\n## gamma per decade of time\n");
    let _ = writeln!(s, "| key | window | gamma [95 %] |");
    let _ = writeln!(s, "|---|---|---|");
    for k in &study.containers {
        // Say why a container has no row (its table was empty without a word).
        if k.decades.is_empty() {
            let start = match k.onset {
                Some(a) => format!("2 x the leak onset (snapshot {})", a.max(1)),
                None => {
                    let _ = writeln!(
                        s,
                        "| {} | none | no leak onset in the run ({} snapshots): E_R has not \
                         fallen to half its peak, so there is no decay to fit |",
                        k.key, study.snapshots
                    );
                    continue;
                }
            };
            let _ = writeln!(
                s,
                "| {} | none | the run ({} snapshots) ends before {start}: no window spans the \
                 0.3 decade a fit needs |",
                k.key, study.snapshots
            );
        }
        for d in &k.decades {
            let _ = writeln!(
                s,
                "| {} | [{}, {}] | {} |",
                k.key,
                d.t_lo,
                d.t_hi,
                est_text(d.est)
            );
        }
    }
}

fn local_slope(s: &mut String, study: &Study) {
    let _ = writeln!(s, "\n## Local slope\n");
    let _ = writeln!(
        s,
        "d ln E_R / d ln t of the ensemble mean from its peak on ({SLOPE_BINS_PER_DECADE} log \
         bins per decade, least squares over +-{SLOPE_HALF_WIDTH} bins; slope.csv, slope.svg). \
         A power law is a flat stretch. Longest stretch within +-{SLOPE_TOLERANCE} of a \
         constant:\n"
    );
    let _ = writeln!(
        s,
        "| key | from t | to t | decades | constant slope | slope at the end [95 %] |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|");
    for k in &study.containers {
        let end = k.slope.last().map_or("n/a".into(), |e| {
            if e.se.is_finite() {
                format!("{:.3} [{:.3}, {:.3}]", e.slope, e.ci_lo, e.ci_hi)
            } else {
                format!("{:.3}", e.slope)
            }
        });
        let _ = match k.constant {
            Some((a, b, c)) => writeln!(
                s,
                "| {} | {:.0} | {:.0} | {:.2} | {:.3} | {} |",
                k.key,
                a,
                b,
                (b / a).log10(),
                c,
                end
            ),
            None => writeln!(s, "| {} | n/a | n/a | n/a | n/a | {} |", k.key, end),
        };
    }
}

fn slope_at_levels(s: &mut String, study: &Study) {
    let _ = writeln!(s, "\n## Local slope at equal E_R\n");
    let _ = writeln!(
        s,
        "The local slope where the ensemble mean first falls to each level (fraction of E0): \
         equal E_R rather than equal time, so a time rescaling between containers drops out. \
         Under one universal power law these are all -gamma.\n"
    );
    let levels = study.containers[0].level_slopes.iter().map(|x| x.0);
    table_head(s, "key", levels.map(|l| format!("{} %", 100.0 * l)));
    for k in &study.containers {
        let mut line = format!("| {} |", k.key);
        for (_, v) in &k.level_slopes {
            let _ = write!(
                line,
                " {} |",
                v.map_or("not reached".into(), |v| format!("{v:.3}"))
            );
        }
        let _ = writeln!(s, "{line}");
    }
}

fn alpha_by_level(s: &mut String, study: &Study) {
    let _ = writeln!(s, "\n## alpha by level\n");
    let _ = writeln!(
        s,
        "alpha = t_ref / t_key at which the ensemble means first fall to a level (fraction \
         of E0) after their peaks, reference `{}`; so that E_key(t) = E_ref(alpha t). \
         Collapse: the alpha of `reproduce` (least RMS mismatch of ln E of the mean curves \
         from the leak onset). Paper: (c) 2, (d) 0.22, (e) 9.\n",
        study.reference.as_deref().unwrap_or("")
    );
    let mut levels: Vec<f64> = Vec::new();
    for a in &study.alpha {
        if !levels.contains(&a.level) {
            levels.push(a.level);
        }
    }
    let columns = levels.iter().map(|l| format!("{} %", 100.0 * l));
    table_head(s, "key", columns.chain(["collapse".to_string()]));
    for (key, col) in &study.collapse {
        let mut line = format!("| {key} |");
        for l in &levels {
            let a = study.alpha.iter().find(|a| &a.key == key && a.level == *l);
            let cell = match a {
                Some(a) if a.alpha.is_some() && a.ci_lo.is_finite() => format!(
                    "{:.3} [{:.3}, {:.3}]",
                    a.alpha.unwrap_or(f64::NAN),
                    a.ci_lo,
                    a.ci_hi
                ),
                Some(a) if a.alpha.is_some() => format!("{:.3}", a.alpha.unwrap_or(f64::NAN)),
                _ => "not reached".into(),
            };
            let _ = write!(line, " {cell} |");
        }
        let _ = write!(line, " {} |", f3(col.map(|c| c.alpha)));
        let _ = writeln!(s, "{line}");
    }
}

fn budget(s: &mut String, study: &Study) {
    let _ = writeln!(s, "\n## Energy budget at the end of the run\n");
    let _ = writeln!(
        s,
        "Mean fraction of the incident energy per region at the last snapshot (budget.csv, \
         budget-<key>.svg; the sections outside the container are recorded at snapshot 0, \
         every snapshot to 100, then 200 per decade). Potential energy of a contact is split between its grains. Under \
         a causal horizon (`run.horizon` of the container scenes) the sections outside the \
         container are recorded unprotected: once the horizon cuts into one, its energy is that \
         of the chain with the grains beyond the horizon held still, without the kinetic energy \
         they had when dropped, not the long-chain run's. The container's energy, and every \
         statistic above, is exact.\n"
    );
    for k in &study.containers {
        let parts: Vec<String> = k
            .regions
            .iter()
            .enumerate()
            .map(
                |(r, n)| match k.budget[r].last().filter(|x| x.is_finite()) {
                    Some(x) => format!("{n} {x:.4}"),
                    None => format!("{n} n/a (not recorded)"),
                },
            )
            .collect();
        let _ = writeln!(s, "- ({}) {}", k.key, parts.join(", "));
    }
}

/// The wall layout of a random container as a number (0 none, 1 ends, 2 ends and middle).
fn walls_code(k: &KeyResult) -> f64 {
    k.design.as_ref().map_or(f64::NAN, |d| match d.walls {
        crate::study::sweep::Walls::None => 0.0,
        crate::study::sweep::Walls::Ends => 1.0,
        crate::study::sweep::Walls::EndsAndMiddle => 2.0,
    })
}

/// Mean of the finite values, as text ("n/a (no interval)" if none: single members).
fn finite_mean(x: impl Iterator<Item = f64>) -> String {
    let w: Vec<f64> = x.filter(|x| x.is_finite()).collect();
    if w.is_empty() {
        "n/a (no interval)".into()
    } else {
        format!("{:.3}", w.iter().sum::<f64>() / w.len() as f64)
    }
}

fn random_containers(s: &mut String, study: &Study) {
    let g: Vec<(&KeyResult, f64)> = study
        .random
        .iter()
        .filter_map(|k| k.fit.est.map(|e| (k, e.value)))
        .collect();
    let _ = writeln!(s, "\n## Random containers\n");
    if g.len() >= 2 {
        random_gamma(s, study, &g);
    }
    random_end_slope(s, study);
    random_level_slopes(s, study);
    let failed = study.random.len() - g.len();
    if failed > 0 {
        let _ = writeln!(
            s,
            "\n{failed} random containers gave no fit (see fits.csv)."
        );
    }
}

/// The distribution of gamma over random containers and its correlation with the design.
fn random_gamma(s: &mut String, study: &Study, g: &[(&KeyResult, f64)]) {
    let gs: Vec<f64> = g.iter().map(|x| x.1).collect();
    let (m, sd) = mean_sd(&gs);
    let mut sorted = gs.clone();
    sorted.sort_by(f64::total_cmp);
    let half_widths = study
        .random
        .iter()
        .filter_map(|k| k.fit.est)
        .map(|e| 0.5 * (e.ci_hi - e.ci_lo));
    let _ = writeln!(
        s,
        "{} containers (random.csv, gamma_hist.svg); gamma of each ensemble mean over \
         [N/10, N]: mean {:.3}, standard deviation {:.3}, median {:.3}, range [{:.3}, \
         {:.3}]. The mean of the per-container jackknife half-widths is {}: a spread \
         of gamma well above it is a property of the designs, not noise.\n",
        gs.len(),
        m,
        sd,
        statistics::quantile(&gs, 0.5),
        sorted[0],
        sorted[sorted.len() - 1],
        finite_mean(half_widths)
    );
    let _ = writeln!(
        s,
        "Correlation of gamma with the design (Pearson r over containers):\n"
    );
    let _ = writeln!(s, "| design parameter | r |");
    let _ = writeln!(s, "|---|---|");
    let param = |f: &dyn Fn(&Design) -> f64| -> Vec<f64> {
        g.iter()
            .map(|(k, _)| k.design.as_ref().map_or(f64::NAN, f))
            .collect()
    };
    let walls: Vec<f64> = g.iter().map(|(k, _)| walls_code(k)).collect();
    for (name, x) in [
        ("interior sections", param(&|d| d.sections as f64)),
        ("grains", param(&|d| d.grains as f64)),
        ("ln(mass ratio)", param(&|d| d.mass_ratio.ln())),
        ("fraction p = 1", param(&|d| d.frac_p1)),
        ("fraction p = 1.5", param(&|d| d.frac_p15)),
        ("fraction p = 2", param(&|d| d.frac_p2)),
        ("walls (0 none, 1 ends, 2 ends and middle)", walls),
    ] {
        let _ = writeln!(s, "| {name} | {} |", r_text(&x, &gs, 2));
    }
    let n = gs.len() as f64;
    if gs.len() >= ensemble::MIN_PEARSON_POINTS {
        let t = student_t_975(n - 2.0);
        let _ = writeln!(
            s,
            "\nWith {} containers, |r| above about {:.2} is unlikely by chance (two-sided 5 %, \
             r = t / sqrt(n - 2 + t^2)).",
            gs.len(),
            t / (n - 2.0 + t * t).sqrt()
        );
    }
}

/// The local slope at the end of the random containers' runs.
fn random_end_slope(s: &mut String, study: &Study) {
    let ends: Vec<(f64, f64)> = study
        .random
        .iter()
        .filter_map(|k| k.slope.last().map(|e| (e.slope, 0.5 * (e.ci_hi - e.ci_lo))))
        .collect();
    if ends.len() < 2 {
        return;
    }
    let v: Vec<f64> = ends.iter().map(|e| e.0).collect();
    let (m, sd) = mean_sd(&v);
    let _ = writeln!(
        s,
        "\nLocal slope at the end of the runs (the last slope point, t near N): mean \
         {:.3}, standard deviation {:.3} over {} containers, range [{:.3}, {:.3}]; mean \
         jackknife half-width {}.",
        m,
        sd,
        v.len(),
        v.iter().copied().fold(f64::INFINITY, f64::min),
        v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        finite_mean(ends.iter().map(|e| e.1))
    );
}

/// The local slope of the random containers at equal E_R levels, against the wall layout.
fn random_level_slopes(s: &mut String, study: &Study) {
    let levels: Vec<f64> = study
        .random
        .first()
        .map(|k| k.level_slopes.iter().map(|x| x.0).collect())
        .unwrap_or_default();
    for (j, &level) in levels.iter().enumerate() {
        let xs: Vec<(&KeyResult, f64)> = study
            .random
            .iter()
            .filter_map(|k| k.level_slopes.get(j).and_then(|x| x.1).map(|v| (k, v)))
            .collect();
        if xs.len() < 3 {
            continue;
        }
        let vals: Vec<f64> = xs.iter().map(|x| x.1).collect();
        let (m, sd) = mean_sd(&vals);
        let walls: Vec<f64> = xs.iter().map(|(k, _)| walls_code(k)).collect();
        let _ = writeln!(
            s,
            "\nLocal slope where the mean first falls to {} % of E0 (equal E_R instead of \
             equal time, which takes the time scale alpha out): {} containers reach it; \
             mean {:.3}, standard deviation {:.3}; correlation with the wall layout r = \
             {}.",
            100.0 * level,
            xs.len(),
            m,
            sd,
            r_text(&walls, &vals, 2)
        );
    }
}

fn outer_medium(s: &mut String, study: &Study) {
    let with: Vec<(&KeyResult, &Gauges)> = study
        .containers
        .iter()
        .filter_map(|k| k.gauges.as_ref().map(|g| (k, g)))
        .collect();
    let (lo, hi) = with[0].1.window;
    let _ = writeln!(s, "\n## The outer medium: volume and back-pressure\n");
    let _ = writeln!(
        s,
        "Means over the late window [{lo}, {hi}] (snapshots) of each member's E_R / E0, of the \
         container's volume (mean displacement of the first {} outer grains on the right minus \
         that on the left: positive when the container has grown) and of the force on each face \
         of the container (the contact to the first outer grain, compression positive, sampled \
         at every output), then mean +- standard error over members (gauges.csv, \
         volume-<group>.svg, er_vs_volume.svg).\n",
        crate::study::GAUGE_GRAINS
    );
    table_head(
        s,
        "key",
        ["members", "E_R / E0"]
            .map(String::from)
            .into_iter()
            .chain(Gauge::ALL.map(|g| g.words())),
    );
    // One member has no standard error: the mean alone, said so.
    let pm = |(m, se): (f64, f64)| {
        if se.is_finite() {
            format!("{m:.4} +- {se:.4}")
        } else {
            format!("{} (one member: no error)", f3(Some(m)))
        }
    };
    for (k, g) in &with {
        let cells: Vec<String> = Gauge::ALL.iter().map(|x| pm(g.mean(*x))).collect();
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} |",
            k.key,
            g.members.len(),
            pm(g.mean_er()),
            cells.join(" | ")
        );
    }
    // Correlations of late E_R with the volume and with the mean force on the two faces: rows
    // of (E_R / E0, volume, mean force).
    let corr = |rows: &[(f64, f64, f64)]| {
        let e: Vec<f64> = rows.iter().map(|m| m.0).collect();
        let v: Vec<f64> = rows.iter().map(|m| m.1).collect();
        let f: Vec<f64> = rows.iter().map(|m| m.2).collect();
        (r_text(&e, &v, 3), r_text(&e, &f, 3))
    };
    let row = |er: f64, volume: f64, left: f64, right: f64| (er, volume, 0.5 * (left + right));
    let _ = writeln!(
        s,
        "\nPearson r of late E_R / E0 with the volume and with the mean force on the faces, over \
         the members of each group of keys (`<group>-<medium>`: one container in several outer \
         media) and over the group's key means (one point per medium):\n"
    );
    table_head(
        s,
        "group",
        [
            "members",
            "r(E_R, volume)",
            "r(E_R, force)",
            "keys",
            "r of key means (volume)",
            "r of key means (force)",
        ]
        .map(String::from),
    );
    let mut groups: Vec<&str> = with.iter().map(|(k, _)| group_of(&k.key)).collect();
    groups.dedup();
    let mut everyone = Vec::new();
    for grp in groups {
        let keys: Vec<&Gauges> = (with.iter())
            .filter(|(k, _)| group_of(&k.key) == grp)
            .map(|(_, g)| *g)
            .collect();
        let rows: Vec<(f64, f64, f64)> = (keys.iter())
            .flat_map(|g| {
                (0..g.er.len()).map(|m| {
                    row(
                        g.er[m],
                        g.of(m, Gauge::Volume),
                        g.of(m, Gauge::ForceLeft),
                        g.of(m, Gauge::ForceRight),
                    )
                })
            })
            .collect();
        let means: Vec<(f64, f64, f64)> = (keys.iter())
            .map(|g| {
                row(
                    g.mean_er().0,
                    g.mean(Gauge::Volume).0,
                    g.mean(Gauge::ForceLeft).0,
                    g.mean(Gauge::ForceRight).0,
                )
            })
            .collect();
        everyone.extend(rows.iter().copied());
        let (rv, rf) = corr(&rows);
        let (mv, mf) = corr(&means);
        let _ = writeln!(
            s,
            "| {grp} | {} | {rv:.3} | {rf:.3} | {} | {mv:.3} | {mf:.3} |",
            rows.len(),
            keys.len()
        );
    }
    let (rv, rf) = corr(&everyone);
    let _ = writeln!(
        s,
        "| all | {} | {rv:.3} | {rf:.3} | {} | | |",
        everyone.len(),
        with.len()
    );
    let _ = writeln!(
        s,
        "\nA negative r with the volume means: the more room the outer medium lets the container \
         take, the less energy stays in it; a positive r with the force: the harder the medium \
         presses back, the more stays in."
    );
}

fn search(s: &mut String, study: &Study) {
    use crate::study::search::{ALPHA_FACTOR, GAMMA_SCALE};
    let readings = study.search.iter().map(|r| r.index).max().unwrap_or(0);
    let _ = writeln!(s, "\n## The lost layouts, searched\n");
    let _ = writeln!(
        s,
        "{readings} readings of the lost Fig. 2 (reading 1: the reconstruction of \
         scenes/containers/), each run on containers (a)-(e) with {} members, scored with `t` from \
         the strike and from the incident wave's arrival (the first snapshot with 1 % of E0 in \
         the container). Distance: the RMS of (gamma - {}) / {GAMMA_SCALE} and of \
         ln(alpha / alpha_paper) / ln {ALPHA_FACTOR} for (c), (d), (e) (paper: 2, 0.22, 9); \
         gamma of (a)'s mean over [max(N/10, onset), N], alpha the collapse of each mean curve \
         onto (a)'s. Fig. 3's leading waves are not scored (search.csv has every row).\n",
        study.search.first().map_or(0, |r| r.members),
        grainchain_engine::paper::GAMMA
    );
    let mut rows: Vec<&SearchRow> = study.search.iter().collect();
    rows.sort_by(|a, b| a.score.distance.total_cmp(&b.score.distance));
    table_head(
        s,
        "rank",
        [
            "reading",
            "walls, masses, exponents, interface, medium",
            "t from",
            "gamma (a)",
            "alpha (c)",
            "alpha (d)",
            "alpha (e)",
            "distance",
        ]
        .map(String::from),
    );
    for (rank, r) in rows.iter().enumerate() {
        if rank >= 12 && r.index != 1 {
            continue;
        }
        let sc = &r.score;
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {:.2} |",
            rank + 1,
            r.index,
            r.reading.describe(),
            r.origin.name(),
            f3(sc.gamma),
            f3(sc.alpha[0]),
            f3(sc.alpha[1]),
            f3(sc.alpha[2]),
            sc.distance
        );
    }
    if let Some(best) = rows
        .iter()
        .filter(|r| r.score.alpha[2].is_some())
        .max_by(|a, b| {
            let e = |r: &SearchRow| r.score.alpha[2].unwrap_or(f64::NAN);
            e(a).total_cmp(&e(b))
        })
    {
        let _ = writeln!(
            s,
            "\nLargest alpha (e) of any reading: {} (reading {}, {}, t from the {}); the paper's \
             is 9.",
            f3(best.score.alpha[2]),
            best.index,
            best.reading.describe(),
            best.origin.name()
        );
    }
}

/// Whether two estimates agree: their difference is within the root sum of squares of their
/// 95 % half-widths (NaN intervals never agree).
fn agree(a: &Estimate, b: &Estimate) -> bool {
    let h = |e: &Estimate| 0.5 * (e.ci_hi - e.ci_lo);
    (a.value - b.value).abs() <= (h(a).powi(2) + h(b).powi(2)).sqrt()
}

/// "Is the decay universal?": the paper's claim tested on this study's containers in three
/// parts (one power law in time, one gamma for every container, the paper's value), and a
/// verdict that follows from the table by the stated rule. Also appended to `reproduce`'s
/// REPORT.md by `reproduce --members`.
pub fn universality(study: &Study) -> String {
    let mut s = String::new();
    let g = grainchain_engine::paper::GAMMA;
    let _ = writeln!(s, "\n## Is the decay universal?\n");
    let _ = writeln!(
        s,
        "The paper's claim, E_R ~ t^-{g} for every container, tested in three parts on this \
         study's containers. (1) One power law: gamma of every decade of time from the leak \
         onset agrees with every other decade's. (2) One gamma: the gamma of the ensemble mean \
         over the main window agrees between every two containers. (3) The paper's value: the \
         main window's interval contains {g}. Two estimates agree when their difference is \
         within the root sum of squares of their 95 % half-widths. (Members 2 or more: with \
         one, the intervals are unknown and nothing agrees.)\n"
    );
    table_head(
        &mut s,
        "key",
        [
            "decades",
            "gamma per decade",
            "(1) one power law",
            "main gamma [95 %]",
            "(3) contains 0.7055",
        ]
        .map(String::from),
    );
    let mut one_law = Vec::new();
    let mut paper_value = Vec::new();
    for k in &study.containers {
        let d: Vec<Estimate> = k.decades.iter().filter_map(|w| w.est).collect();
        let law = if d.len() < 2 {
            None
        } else {
            Some(d.iter().all(|a| d.iter().all(|b| agree(a, b))))
        };
        let value = k.fit.est.map(|e| e.ci_lo <= g && g <= e.ci_hi);
        one_law.push((k.key.as_str(), law));
        paper_value.push((k.key.as_str(), value));
        let per: Vec<String> = d.iter().map(|e| format!("{:.3}", e.value)).collect();
        let yes = |x: Option<bool>| match x {
            Some(true) => "yes",
            Some(false) => "no",
            None => "untested",
        };
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} |",
            k.key,
            d.len(),
            per.join(", "),
            yes(law),
            fit_text(&k.fit),
            yes(value)
        );
    }
    let mains: Vec<(&str, Estimate)> = (study.containers.iter())
        .filter_map(|k| Some((k.key.as_str(), k.fit.est?)))
        .collect();
    let mut disagree = Vec::new();
    for (i, a) in mains.iter().enumerate() {
        for b in &mains[i + 1..] {
            if !agree(&a.1, &b.1) {
                disagree.push(format!("{}/{}", a.0, b.0));
            }
        }
    }
    let one_gamma = disagree.is_empty() && mains.len() >= 2;
    let _ = writeln!(
        s,
        "\n(2) One gamma for every container: {}.",
        if mains.len() < 2 {
            "untested (one container)".to_string()
        } else if one_gamma {
            "yes".to_string()
        } else {
            format!(
                "no, {} of {} pairs disagree ({}{})",
                disagree.len(),
                mains.len() * (mains.len() - 1) / 2,
                disagree
                    .iter()
                    .take(8)
                    .cloned()
                    .collect::<Vec<_>>()
                    .join(", "),
                if disagree.len() > 8 { ", .." } else { "" }
            )
        }
    );
    fn holds<'a>(v: &[(&'a str, Option<bool>)]) -> Vec<&'a str> {
        v.iter()
            .filter(|x| x.1 == Some(true))
            .map(|x| x.0)
            .collect()
    }
    let (laws, values) = (holds(&one_law), holds(&paper_value));
    let n = study.containers.len();
    // Nothing tested (no container with a decay to fit, or single members): no verdict.
    let tested = one_law.iter().chain(&paper_value).any(|x| x.1.is_some());
    let verdict = if !tested {
        "**untested**: no container gave a gamma with an interval in this run (the tables above \
         say why)"
            .to_string()
    } else if laws.len() == n && values.len() == n && (one_gamma || n == 1) {
        "**supported** on every container of this study".to_string()
    } else if laws.is_empty() && values.is_empty() {
        "**not supported**: no container decays as one power law, and no container's gamma \
         interval contains the paper's value"
            .to_string()
    } else {
        format!(
            "**supported only under conditions**: one power law over every decade for {}; \
             the paper's value inside the main window's interval for {}; one gamma for every \
             container: {}",
            if laws.is_empty() {
                "no container".to_string()
            } else {
                laws.join(", ")
            },
            if values.is_empty() {
                "no container".to_string()
            } else {
                values.join(", ")
            },
            if one_gamma { "yes" } else { "no" }
        )
    };
    let _ = writeln!(s, "\nVerdict on this study's containers: {verdict}.");
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// STUDY.md printed `NaN` for r of a group with one key (no spread) and r = 1.000 from two
    /// members (`format!("{:.3}", ensemble::pearson(..))`); now it says why there is none.
    #[test]
    fn correlations_say_why_they_are_missing() {
        let one_key = r_text(&[0.2, 0.2, 0.2], &[1.0, 2.0, 4.0], 3);
        assert_eq!(one_key, "n/a (no spread: every point has the same value)");
        let two = r_text(&[0.1, 0.3], &[1.0, 2.0], 3);
        assert_eq!(two, "n/a (2 points, fewer than the 3 a correlation needs)");
        assert_eq!(r_text(&[1.0, 2.0, 3.0], &[1.0, 3.0, 2.0], 3), "0.500");
    }
}
