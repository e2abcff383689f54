//! Golden figure data: `grainchain reproduce` in its golden configuration, compared with the
//! files under `golden/` (CSV) and `golden/snapshots/` (insta).
//!
//! **Golden configuration.** Fig. 1 and Fig. 3 exactly as `reproduce` runs them. Fig. 4/5 with
//! runs of [`GOLDEN_SNAPSHOTS`] = 800 snapshots instead of the paper's 4000 (`--snapshots 800`):
//! a run's cost grows with the square of its length, and 4000 snapshots of five containers take
//! about a CPU-minute, too much for `cargo test`. The fits and rescalings in `golden/fig5_fits.csv`
//! are therefore those of 800-snapshot runs, not the ones in REPORT.md.
//!
//! **What is compared, and why not everything pointwise.** The container dynamics are chaotic:
//! a change of 1e-12 in the striker's speed changes E_R by more than 1e-4 from snapshot ~190 on,
//! and the velocities inside the container and in wakes by O(1) (REPORT.md). A change of
//! integrator or step (which the lead engineer may make in the scene files) does the same. So the
//! golden files flag the rows that are converged, and only rows converged both now and when the
//! golden file was made are compared pointwise:
//! - snapshot rows whose velocity moves by at most 1e-3 of the incident wave's peak speed when
//!   the step is divided by 8 (widened by 3 grains: a chaotic region's edge can agree by chance);
//! - E_R rows before the first snapshot at which halving the step moves E_R by 1e-4.
//!
//! The chaotic rest is compared by log-binned means, and the fits and rescalings with tolerances
//! set from their measured spread across integrators.
//!
//! On a mismatch the test fails naming file, column, row and size, and writes `<file>.new` beside
//! the golden file (insta writes `.snap.new`). CONTRIBUTING.md says how to review and accept.
//! `GRAINCHAIN_UPDATE_GOLDEN=1 cargo test --test validation golden_figures::` rewrites the CSV files instead.

// Comparisons are written `!(x <= tol)` on purpose: a NaN must fail them.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

mod review;

use grainchain::batch::scenes::{self, SceneSource};
use grainchain::batch::{run_job, Job, RunData};
use grainchain::reproduce::{self, Options, Outcome, STEP_FACTOR};
use grainchain::reproduce::{Cell, Table};
use review::{Plot, Review};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

const GOLDEN_SNAPSHOTS: u64 = 800;

/// How each golden file is drawn in a review of a change (`review.rs`).
const PLOTS: &[Plot] = &[
    Plot {
        file: "fig1_snapshots.csv",
        x: Some("grain"),
        log: false,
    },
    Plot {
        file: "fig1_pulses.csv",
        x: Some("rank"),
        log: false,
    },
    Plot {
        file: "fig3_snapshot.csv",
        x: Some("grain"),
        log: false,
    },
    Plot {
        file: "fig3_pulses.csv",
        x: None,
        log: false,
    },
    Plot {
        file: "fig4_energy.csv",
        x: Some("snapshot"),
        log: true,
    },
    Plot {
        file: "fig5_fits.csv",
        x: None,
        log: false,
    },
];

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The scene directory: `scenes/`, or `GRAINCHAIN_GOLDEN_SCENES` (to check that the tolerances
/// accept another integrator setting, as CONTRIBUTING.md describes).
fn scene_dir() -> PathBuf {
    std::env::var_os("GRAINCHAIN_GOLDEN_SCENES")
        .map(PathBuf::from)
        .unwrap_or_else(|| root().join("scenes"))
}

fn golden_dir() -> PathBuf {
    root().join("golden")
}

/// Collected failures of all comparisons (the test reports all of them, then fails).
#[derive(Default)]
struct Failures(Vec<String>);

impl Failures {
    fn add(&mut self, s: String) {
        self.0.push(s);
    }
}

/// Read the golden table, or `None` (and a failure) when it is missing or unreadable.
fn golden(name: &str, f: &mut Failures) -> Option<Table> {
    let p = golden_dir().join(name);
    match Table::read(&p) {
        Ok(t) => Some(t),
        Err(e) => {
            f.add(format!("golden/{name}: cannot read the golden file ({e})"));
            None
        }
    }
}

/// Column `col` of `t` as numbers.
fn col(t: &Table, c: &str) -> Vec<f64> {
    let k = t
        .column(c)
        .unwrap_or_else(|| panic!("{}: no column {c}", t.name));
    t.rows
        .iter()
        .map(|r| r[k].num().unwrap_or(f64::NAN))
        .collect()
}

/// Converged rows of a snapshot: `|v - v_fine| <= 1e-3 v_ref` (`v_fine` at a step divided by
/// [`STEP_FACTOR`], `v_ref` the incident wave's peak speed), minus every row within 3 grains of an
/// unconverged one (a chaotic region's edge can agree by chance).
fn converged(v: &[f64], fine: &[f64], v_ref: f64) -> Vec<bool> {
    let bad: Vec<usize> = (0..v.len())
        .filter(|&i| !((v[i] - fine[i]).abs() <= 1e-3 * v_ref))
        .collect();
    let mut ok = vec![true; v.len()];
    for b in bad {
        for x in ok
            .iter_mut()
            .take((b + 4).min(v.len()))
            .skip(b.saturating_sub(3))
        {
            *x = false;
        }
    }
    ok
}

/// `t` with 0/1 columns appended.
fn with_flags(t: &Table, flags: &[(&str, &[bool])]) -> Table {
    let mut t = t.clone();
    for (name, f) in flags {
        t.columns.push(name.to_string());
        for (r, &x) in t.rows.iter_mut().zip(f.iter()) {
            r.push(Cell::Num(if x { 1.0 } else { 0.0 }));
        }
    }
    t
}

/// Rows flagged converged both now and in the golden file (none if the golden file lacks the
/// flag column, which the row-count checks then report).
fn both(new: &Table, old: &Table, flag: &str) -> BTreeSet<usize> {
    if old.column(flag).is_none() {
        return BTreeSet::new();
    }
    let (a, b) = (col(new, flag), col(old, flag));
    (0..a.len().min(b.len()))
        .filter(|&i| a[i] == 1.0 && b[i] == 1.0)
        .collect()
}

/// Compare column `c` of `new` with `old` on `rows` with an absolute tolerance.
#[allow(clippy::too_many_arguments)]
fn compare_abs(
    name: &str,
    new: &Table,
    old: &Table,
    c: &str,
    key: &str,
    rows: &BTreeSet<usize>,
    tol: f64,
    why: &str,
    f: &mut Failures,
) -> bool {
    let (a, b, k) = (col(new, c), col(old, c), col(new, key));
    let mut worst: Option<(usize, f64)> = None;
    for &i in rows {
        if i >= a.len() || i >= b.len() {
            f.add(format!(
                "golden/{name}: row {} missing (now {} rows, golden {})",
                i + 1,
                a.len(),
                b.len()
            ));
            return false;
        }
        let d = (a[i] - b[i]).abs();
        if !(d <= tol) && worst.is_none_or(|(_, w)| d > w) {
            worst = Some((i, d));
        }
    }
    if let Some((i, d)) = worst {
        let n_bad = rows
            .iter()
            .filter(|&&i| !((a[i] - b[i]).abs() <= tol))
            .count();
        f.add(format!(
            "golden/{name}: column `{c}`, row {} ({key} = {}): {} vs golden {} (|diff| {d:.3e} > tolerance {tol:.3e}: {why}); {n_bad} of {} compared rows differ",
            i + 1,
            k[i],
            a[i],
            b[i],
            rows.len()
        ));
        return false;
    }
    true
}

/// Write `<name>.new` beside the golden file, or the golden file itself when updating.
fn leave_new(t: &Table, update: bool) {
    let dir = golden_dir();
    let bytes = t.to_csv().expect("csv");
    let path = if update {
        dir.join(&t.name)
    } else {
        dir.join(format!("{}.new", t.name))
    };
    grainchain::report::atomic::AtomicFile::write_all(&path, &bytes).expect("write golden");
}

fn show(c: &Cell) -> String {
    match c {
        Cell::Num(x) => x.to_string(),
        Cell::Text(t) => t.clone(),
    }
}

fn run_one(job: Job) -> RunData {
    run_job(&job, &|| {}).expect("run")
}

/// The scene's listed snapshots at a step divided by [`STEP_FACTOR`]: velocities of every grain.
fn fine_snapshots(file: &str, regions: &[&str], snaps: &[u64]) -> Vec<Vec<f64>> {
    let src = SceneSource::load(scene_dir().join(file)).unwrap();
    let scene = src
        .scene(|f| {
            scenes::refine_step(f, STEP_FACTOR);
            Ok(())
        })
        .unwrap();
    let d = run_one(Job {
        label: format!("{file} dt/8"),
        scene,
        regions: regions.iter().map(|s| s.to_string()).collect(),
        unprotected: vec![],
        unprotected_at: None,
        snapshots: snaps.to_vec(),
        require_untouched_ends: (false, false),
        gauges: None,
        mechanism: false,
    });
    d.snaps.into_iter().map(|s| s.velocity).collect()
}

/// E_R of a container at half its step, for [`GOLDEN_SNAPSHOTS`].
fn half_step(path: &Path) -> Vec<f64> {
    let src = SceneSource::load(path).unwrap();
    let scene = src
        .scene(|f| {
            scenes::set_snapshots(f, GOLDEN_SNAPSHOTS);
            scenes::refine_step(f, 2.0);
            Ok(())
        })
        .unwrap();
    run_one(Job {
        label: "half step".into(),
        scene,
        regions: vec!["container".into()],
        unprotected: vec![],
        unprotected_at: None,
        snapshots: vec![],
        require_untouched_ends: (true, true),
        gauges: None,
        mechanism: false,
    })
    .region("container")
    .unwrap()
    .energy
    .to_vec()
}

fn table<'a>(o: &'a Outcome, name: &str) -> &'a Table {
    o.tables
        .iter()
        .find(|t| t.name == name)
        .unwrap_or_else(|| panic!("reproduce wrote no {name}"))
}

#[test]
fn golden_figures() {
    let update = std::env::var("GRAINCHAIN_UPDATE_GOLDEN").is_ok_and(|v| v == "1");
    let out = tempfile::tempdir().unwrap();
    let opts = Options {
        out: out.path().to_path_buf(),
        scenes: scene_dir(),
        only: Vec::new(),
        snapshots: Some(GOLDEN_SNAPSHOTS),
        check_step: false,
        threads: 2,
        progress: false,
        appendix: Vec::new(),
        files: Default::default(),
    };
    let o = reproduce::run(&opts).expect("reproduce");
    let mut fails = Failures::default();
    let mut notes = Vec::new();
    let mut review = Review::default();

    // ---------------- Fig. 1
    let f1 = o.fig1.as_ref().unwrap();
    let fine1 = fine_snapshots(
        "fig1-heavy-to-light.toml",
        &["heavy", "light"],
        &[f1.before.index, f1.after.index],
    );
    let vref1 = f1.incident.peak_velocity.abs();
    let t0 = table(&o, "fig1_snapshots.csv");
    let flags_b = converged(&col(t0, "velocity_before"), &fine1[0], vref1);
    let flags_a = converged(&col(t0, "velocity_after"), &fine1[1], vref1);
    let t = with_flags(
        t0,
        &[
            ("converged_before", &flags_b),
            ("converged_after", &flags_a),
        ],
    );
    let mut ok = true;
    if let Some(g) = golden("fig1_snapshots.csv", &mut fails) {
        review.file("fig1_snapshots.csv", &t, &g, "grain");
        for (c, flag) in [
            ("velocity_before", "converged_before"),
            ("velocity_after", "converged_after"),
        ] {
            let rows = both(&t, &g, flag);
            notes.push(format!(
                "fig1_snapshots.csv {c}: {} of {} rows compared",
                rows.len(),
                t.rows.len()
            ));
            // The incident wave and the leading transmitted waves alone light some 50 grains and
            // the resting grains ahead of them hundreds more; fewer would make the check vacuous.
            if rows.len() < 300 {
                fails.add(format!("golden/fig1_snapshots.csv: column `{c}`: only {} rows converged both now and in the golden file", rows.len()));
                ok = false;
            }
            // Compared rows are within 1e-3 v_ref of a run at dt/8, now and when the golden file
            // was made; two such settings are within 2e-3 v_ref of each other.
            let held = compare_abs(
                "fig1_snapshots.csv",
                &t,
                &g,
                c,
                "grain",
                &rows,
                2e-3 * vref1,
                "2e-3 of the incident peak speed: two settings each within 1e-3 of converged",
                &mut fails,
            );
            review.check(
                "fig1_snapshots.csv",
                c,
                format!(
                    "|change| <= {:.3e} (2e-3 of the incident peak speed) on {} converged rows",
                    2e-3 * vref1,
                    rows.len()
                ),
                held,
            );
            ok &= held;
        }
    } else {
        ok = false;
    }
    if !ok || update {
        leave_new(&t, update);
    }

    let t = table(&o, "fig1_pulses.csv");
    let mut ok = true;
    if let Some(g) = golden("fig1_pulses.csv", &mut fails) {
        review.file("fig1_pulses.csv", t, &g, "rank");
        // The eight leading waves carry more than 0.9 % of the incident energy each; their
        // energies and positions agree to 2e-5 relative and 1e-3 grain across verlet 1e-4,
        // blanes-moan4 1e-3 / 1.25e-3 and dt/8 (measured). Tolerances: 1e-3 relative and 0.01
        // grain, 50x and 10x that. The tail of the train is not compared: its pulses split and
        // merge with threshold crossings in a chaotic wake (their number changes with the step).
        let n = 8.min(t.rows.len()).min(g.rows.len());
        if n < 8 {
            fails.add(format!(
                "golden/fig1_pulses.csv: fewer than 8 transmitted waves (now {}, golden {})",
                t.rows.len(),
                g.rows.len()
            ));
            ok = false;
        }
        let rows: BTreeSet<usize> = (0..n).collect();
        let (e_new, e_old) = (col(t, "energy"), col(&g, "energy"));
        let energy_ok = ok;
        for &i in &rows {
            let r = (e_new[i] - e_old[i]).abs() / e_old[i];
            if !(r <= 1e-3) {
                fails.add(format!(
                    "golden/fig1_pulses.csv: column `energy`, row {} (rank {}): {} vs golden {} (relative {r:.3e} > 1e-3: converged to 2e-5 across integrators)",
                    i + 1, i + 1, e_new[i], e_old[i]
                ));
                ok = false;
            }
        }
        review.check(
            "fig1_pulses.csv",
            "energy",
            "relative change <= 1e-3 on the 8 leading waves".into(),
            ok == energy_ok,
        );
        let held = compare_abs(
            "fig1_pulses.csv",
            t,
            &g,
            "position",
            "rank",
            &rows,
            0.01,
            "0.01 grain: leading-wave positions agree to 1e-3 grain across integrators",
            &mut fails,
        );
        review.check(
            "fig1_pulses.csv",
            "position",
            "|change| <= 0.01 grain on the 8 leading waves".into(),
            held,
        );
        ok &= held;
    } else {
        ok = false;
    }
    if !ok || update {
        leave_new(t, update);
    }

    // ---------------- Fig. 3
    let f3 = o.fig3.as_ref().unwrap();
    let fine3 = fine_snapshots(
        "fig3-standard-container.toml",
        &["container"],
        &[f3.incident_index, f3.snap.index],
    );
    let vref3 = f3.incident.peak_velocity.abs();
    let t0 = table(&o, "fig3_snapshot.csv");
    let flags = converged(&col(t0, "velocity"), &fine3[1], vref3);
    let t = with_flags(t0, &[("converged", &flags)]);
    let mut ok = true;
    if let Some(g) = golden("fig3_snapshot.csv", &mut fails) {
        review.file("fig3_snapshot.csv", &t, &g, "grain");
        let rows = both(&t, &g, "converged");
        // The left outer chain (leaked waves and resting grains, ~80 grains) and the right one
        // beyond grain ~330 converge; the container does not (chaos).
        notes.push(format!(
            "fig3_snapshot.csv: {} of {} rows compared",
            rows.len(),
            t.rows.len()
        ));
        if rows.len() < 100 {
            fails.add(format!(
                "golden/fig3_snapshot.csv: only {} rows converged both now and in the golden file",
                rows.len()
            ));
            ok = false;
        }
        // Velocity only: grain energies follow from velocities and overlaps, and the leaked
        // waves' energies are compared in fig3_pulses.csv.
        let held = compare_abs(
            "fig3_snapshot.csv",
            &t,
            &g,
            "velocity",
            "grain",
            &rows,
            2e-3 * vref3,
            "2e-3 of the incident peak speed: two settings each within 1e-3 of converged",
            &mut fails,
        );
        review.check(
            "fig3_snapshot.csv",
            "velocity",
            format!(
                "|change| <= {:.3e} (2e-3 of the incident peak speed) on {} converged rows",
                2e-3 * vref3,
                rows.len()
            ),
            held,
        );
        ok &= held;
    } else {
        ok = false;
    }
    if !ok || update {
        leave_new(&t, update);
    }

    let t = table(&o, "fig3_pulses.csv");
    let mut ok = true;
    if let Some(g) = golden("fig3_pulses.csv", &mut fails) {
        review.file("fig3_pulses.csv", t, &g, "side");
        let pick = |t: &Table, side: &str| -> Option<(usize, f64)> {
            let (s, first, pct) = (
                t.column("side").unwrap(),
                col(t, "first"),
                col(t, "percent_of_incident"),
            );
            let mut best: Option<usize> = None;
            for (i, r) in t.rows.iter().enumerate() {
                if r[s] == Cell::Text(side.into()) {
                    let better = match best {
                        None => true,
                        Some(b) => {
                            if side == "right" {
                                first[i] > first[b]
                            } else {
                                first[i] < first[b]
                            }
                        }
                    };
                    if better {
                        best = Some(i);
                    }
                }
            }
            best.map(|i| (i, pct[i]))
        };
        // Measured against dt/8: the incident and the left leading wave within 5e-3 percentage
        // points across verlet 1e-4 and blanes-moan4 2.5e-4 / 3.125e-4; the right leading wave
        // within 0.02 points for blanes-moan4 but 0.47 for verlet 1e-4, which is not accurate
        // enough for it. Tolerances: 0.05 points (10x) for incident and left, 0.1 (5x the
        // blanes-moan4 spread) for right: a change to verlet at 1e-4 is flagged, rightly.
        for (side, tol) in [("incident", 0.05), ("left", 0.05), ("right", 0.1)] {
            let held = matches!((pick(t, side), pick(&g, side)), (Some((_, a)), Some((_, b))) if (a - b).abs() <= tol);
            review.check(
                "fig3_pulses.csv",
                "percent_of_incident",
                format!("outermost `{side}` pulse within {tol} percentage points"),
                held,
            );
            match (pick(t, side), pick(&g, side)) {
                (Some((_, a)), Some((_, b))) if (a - b).abs() <= tol => {}
                (Some((i, a)), Some((_, b))) => {
                    fails.add(format!(
                        "golden/fig3_pulses.csv: column `percent_of_incident`, row {} (outermost `{side}` pulse): {a} vs golden {b} (|diff| {:.3e} > {tol} percentage points: measured spread across accurate integrators)",
                        i + 1, (a - b).abs()
                    ));
                    ok = false;
                }
                (a, b) => {
                    fails.add(format!(
                        "golden/fig3_pulses.csv: `{side}` pulse present now: {}, in golden: {}",
                        a.is_some(),
                        b.is_some()
                    ));
                    ok = false;
                }
            }
        }
    } else {
        ok = false;
    }
    if !ok || update {
        leave_new(t, update);
    }

    // ---------------- Fig. 4: E_R, thinned to every 4th snapshot for review.
    let fits = o.fits.as_ref().unwrap();
    let e0 = fits[0].e0;
    let full = table(&o, "fig4_energy.csv");
    let mut flags: Vec<(String, Vec<bool>)> = Vec::new();
    for c in fits {
        let file = std::fs::read_dir(scene_dir().join("containers"))
            .unwrap()
            .filter_map(|e| e.ok())
            .map(|e| e.path())
            .find(|p| {
                p.file_name()
                    .is_some_and(|n| n.to_string_lossy().starts_with(&format!("{}-", c.key)))
            })
            .unwrap();
        let half = half_step(&file);
        // Converged: before the first snapshot at which halving the step moves E_R by more than
        // 1e-4 (rows below 1e-3 of the striker's energy hold only the precursor tail and are not
        // compared pointwise).
        let h = (0..c.er.len())
            .find(|&k| c.er[k] >= 1e-3 * e0 && !(((half[k] - c.er[k]) / c.er[k]).abs() <= 1e-4))
            .unwrap_or(c.er.len());
        notes.push(format!(
            "fig4 E_{}: step-converged until snapshot {h}",
            c.key
        ));
        flags.push((
            format!("converged_{}", c.key),
            (0..c.er.len())
                .map(|k| k < h && c.er[k] >= 1e-3 * e0)
                .collect(),
        ));
    }
    let flag_refs: Vec<(&str, &[bool])> = flags
        .iter()
        .map(|(n, f)| (n.as_str(), f.as_slice()))
        .collect();
    let t = with_flags(full, &flag_refs).thinned(4);
    let mut ok = true;
    if let Some(g) = golden("fig4_energy.csv", &mut fails) {
        review.file("fig4_energy.csv", &t, &g, "snapshot");
        let snaps = col(&t, "snapshot");
        if snaps != col(&g, "snapshot") {
            fails.add("golden/fig4_energy.csv: column `snapshot` differs (different run length or thinning)".into());
            ok = false;
        } else {
            for c in fits {
                let name = format!("E_{}", c.key);
                let flag = format!("converged_{}", c.key);
                let (a, b) = (col(&t, &name), col(&g, &name));
                let rows = both(&t, &g, &flag);
                let before = fails.0.len();
                // Converged rows: every setting measured (verlet 1e-4, blanes-moan4 1e-3,
                // 1.25e-3) agrees with dt/8 to 1e-4 there; 1e-3 relative is 10x that.
                for &i in &rows {
                    let r = (a[i] - b[i]).abs() / b[i];
                    if !(r <= 1e-3) {
                        fails.add(format!(
                            "golden/fig4_energy.csv: column `{name}`, row {} (snapshot {}, step-converged): {} vs golden {} (relative {r:.3e} > 1e-3: converged to 1e-4 there)",
                            i + 1, snaps[i], a[i], b[i]
                        ));
                        ok = false;
                        break;
                    }
                }
                // After the converged rows (now or in the golden file), the curve is chaotic:
                // compare means over log-spaced bins (10 per decade). Across integrator settings
                // and twins the bin means of 800-snapshot runs differed by up to 30 % (container
                // c, verlet 1e-4 against dt/8; measured), so 40 %: this catches a change of the
                // decay, not chaos.
                review.check(
                    "fig4_energy.csv",
                    &name,
                    format!(
                        "relative change <= 1e-3 on {} step-converged rows",
                        rows.len()
                    ),
                    fails.0.len() == before,
                );
                let before = fails.0.len();
                let start = rows.iter().next_back().map_or(1.0, |&i| snaps[i] + 1.0);
                let mut lo = start;
                while lo < GOLDEN_SNAPSHOTS as f64 {
                    let hi = lo * 10f64.powf(0.1);
                    let idx: Vec<usize> = (0..a.len())
                        .filter(|&i| snaps[i] >= lo && snaps[i] < hi)
                        .collect();
                    if !idx.is_empty() {
                        let ma = idx.iter().map(|&i| a[i]).sum::<f64>() / idx.len() as f64;
                        let mb = idx.iter().map(|&i| b[i]).sum::<f64>() / idx.len() as f64;
                        let r = (ma - mb).abs() / mb;
                        if !(r <= 0.4) {
                            fails.add(format!(
                                "golden/fig4_energy.csv: column `{name}`, rows with snapshot in [{lo:.0}, {hi:.0}) (chaotic part): mean {ma} vs golden {mb} (relative {r:.3} > 0.4: chaotic spread across integrators up to 0.3)"
                            ));
                            ok = false;
                        }
                    }
                    lo = hi;
                }
                review.check(
                    "fig4_energy.csv",
                    &name,
                    "mean over each tenth of a decade after them within 40 % (chaotic part)".into(),
                    fails.0.len() == before,
                );
            }
        }
    } else {
        ok = false;
    }
    if !ok || update {
        leave_new(&t, update);
    }

    // ---------------- Fig. 5: fits of the 800-snapshot runs.
    let t = table(&o, "fig5_fits.csv");
    let mut ok = true;
    if let Some(g) = golden("fig5_fits.csv", &mut fails) {
        review.file("fig5_fits.csv", t, &g, "container");
        let (ga, gb) = (col(t, "gamma"), col(&g, "gamma"));
        let (aa, ab) = (col(t, "alpha"), col(&g, "alpha"));
        let key = t.column("container").unwrap();
        for i in 0..t.rows.len().min(g.rows.len()) {
            let k = &t.rows[i][key];
            if k != &g.rows[i][key] {
                fails.add(format!(
                    "golden/fig5_fits.csv: row {} is container {k:?}, golden {:?}",
                    i + 1,
                    g.rows[i][key]
                ));
                ok = false;
                continue;
            }
            // Measured across verlet 1e-4, blanes-moan4 1e-3, 1.25e-3 and dt/8 on 800-snapshot
            // runs: gamma within 0.06, alpha within 26 % (container c). Tolerances 0.15 and 40 %.
            if !((ga[i] - gb[i]).abs() <= 0.15) {
                fails.add(format!(
                    "golden/fig5_fits.csv: column `gamma`, row {} (container {}): {} vs golden {} (|diff| {:.3} > 0.15: spread across integrators up to 0.06)",
                    i + 1, show(k), ga[i], gb[i], (ga[i] - gb[i]).abs()
                ));
                ok = false;
            }
            if !((aa[i] - ab[i]).abs() / ab[i] <= 0.4) {
                fails.add(format!(
                    "golden/fig5_fits.csv: column `alpha`, row {} (container {}): {} vs golden {} (relative {:.3} > 0.4: spread across integrators up to 0.26)",
                    i + 1, show(k), aa[i], ab[i], (aa[i] - ab[i]).abs() / ab[i]
                ));
                ok = false;
            }
        }
        let (gamma_ok, alpha_ok) = (
            (0..t.rows.len().min(g.rows.len())).all(|i| (ga[i] - gb[i]).abs() <= 0.15),
            (0..t.rows.len().min(g.rows.len())).all(|i| (aa[i] - ab[i]).abs() / ab[i] <= 0.4),
        );
        review.check(
            "fig5_fits.csv",
            "gamma",
            "|change| <= 0.15".into(),
            gamma_ok,
        );
        review.check(
            "fig5_fits.csv",
            "alpha",
            "relative change <= 0.4".into(),
            alpha_ok,
        );
        if t.rows.len() != g.rows.len() {
            fails.add(format!(
                "golden/fig5_fits.csv: {} containers, golden has {}",
                t.rows.len(),
                g.rows.len()
            ));
            ok = false;
        }
    } else {
        ok = false;
    }
    if !ok || update {
        leave_new(t, update);
    }

    // ---------------- Exactness of the embedded striker and the long outer chains (not golden
    // data: an invariant). The free-end variant of (a) (120-grain outer chains with free ends, the
    // striker at the chain's end: the paper's Fig. 3 geometry) must give the default's E_R bit for
    // bit until a disturbance has gone from the container to a free end and back: it leaves the
    // container at the earliest when the incident wave arrives (E_R > 0), then crosses 2 x 120
    // grains at no more than the incident wave's speed, which crossed the 120 grains between
    // striker and container in as many snapshots as it took to arrive.
    let free = o
        .variants
        .iter()
        .find(|v| v.variant.key().starts_with("free ends"))
        .expect("free-end variant");
    let arrival = fits[0].er.iter().position(|&e| e > 0.0).unwrap();
    let earliest = arrival + 2 * arrival;
    match free.diff.first_bit_difference {
        Some(k) if k < earliest => fails.add(format!(
            "free-end variant of (a) departs from the long-chain run at snapshot {k}, before a disturbance could have come back from a free end (snapshot {earliest}): the embedded striker or the long outer chains are not exact"
        )),
        k => notes.push(format!(
            "free-end variant identical bit for bit until snapshot {k:?} (bound {earliest})"
        )),
    }

    for n in &notes {
        eprintln!("golden: {n}");
    }

    // ---------------- Headline numbers (insta), rounded to what is reproducible.
    let h = &o.headline;
    let f1h = h.fig1.as_ref().unwrap();
    let f3h = h.fig3.as_ref().unwrap();
    let mut text = String::new();
    use std::fmt::Write;
    let _ = writeln!(
        text,
        "golden configuration: Fig. 4/5 runs of {GOLDEN_SNAPSHOTS} snapshots"
    );
    let _ = writeln!(
        text,
        "fig1 incident wave energy: {:.4}",
        f1h.incident_energy
    );
    let _ = writeln!(
        text,
        "fig1 transmitted waves >= 1 % of incident: {}",
        f1h.transmitted_above_1_percent
    );
    let _ = writeln!(
        text,
        "fig1 transmitted waves >= 0.1 % of incident: {}",
        f1h.transmitted_above_0_1_percent
    );
    let _ = writeln!(
        text,
        "fig1 leading wave, fraction of incident: {:.3}",
        f1h.leading_fraction
    );
    let _ = writeln!(
        text,
        "fig1 reflected energy below 0.1 % of incident: {}",
        f1h.reflected_fraction.abs() < 1e-3
    );
    let _ = writeln!(
        text,
        "fig3 incident wave energy: {:.0}",
        f3h.incident_energy
    );
    let _ = writeln!(
        text,
        "fig3 leading wave left, % of incident: {:.1}",
        f3h.left_lead_percent.unwrap_or(f64::NAN)
    );
    let _ = writeln!(
        text,
        "fig3 leading wave right, % of incident: {:.1}",
        f3h.right_lead_percent.unwrap_or(f64::NAN)
    );
    for c in &h.fig5 {
        // One decimal: gamma and alpha of 800-snapshot runs move by up to 0.06 and 26 % with the
        // integrator (chaos); a legitimate change of integrator can flip the last digit, which
        // is then reviewed and accepted (CONTRIBUTING.md).
        let _ = writeln!(
            text,
            "fig5 ({}) gamma {:.1}, alpha {:.1}",
            c.container,
            c.gamma.unwrap_or(f64::NAN),
            c.alpha.unwrap_or(f64::NAN)
        );
    }
    if update || !review.moved() {
        Review::remove_old(&golden_dir(), PLOTS);
    } else {
        review.write(&golden_dir(), PLOTS);
        eprintln!(
            "golden: the figure data moved ({}); the review is golden/REVIEW.md (and golden/*.review.svg)",
            if fails.0.is_empty() { "every comparison holds" } else { "some comparisons fail" }
        );
    }
    if update {
        for f in &fails.0 {
            eprintln!("golden (updated): {f}");
        }
        fails.0.clear();
    } else {
        for f in &fails.0 {
            eprintln!("golden mismatch: {f}");
        }
    }
    let mut settings = insta::Settings::clone_current();
    settings.set_snapshot_path(golden_dir().join("snapshots"));
    settings.set_prepend_module_to_snapshot(false);
    settings.bind(|| insta::assert_snapshot!("headline", text));

    assert!(
        fails.0.is_empty(),
        "golden figure data changed ({} problems); new data written beside the golden files as .new, the review in golden/REVIEW.md:\n  {}",
        fails.0.len(),
        fails.0.join("\n  ")
    );
}
