//! A robust objective (`minimize = "p95"`, `"mean"`, `"quantile"`: a Monte Carlo statistic of
//! the peak with common random numbers, `design/robust.rs`): its screening value is the type-7
//! quantile of the candidate's draws worked here, the give-up of the search never changes a
//! statistic it reports as exact and only reports lower bounds, every candidate is perturbed by
//! the same draws, the command's outputs are the same bytes on 1 and 2 threads and set both
//! winners side by side, and its keys are checked.

use crate::common::{grainchain, record_one, s, Row, Status};
use grainchain::design::file::{DesignFile, DesignSpec};
use grainchain::design::search;
use grainchain::design::tolerance::{Draws, SEARCH_STREAM};
use grainchain_engine::protector::evaluate;
use std::path::PathBuf;

/// Four sections of three beads, steel or PTFE (6 mm): 16 designs, a 1 % diameter and 5 %
/// modulus tolerance, few draws (shared with the Python tests).
const SMALL: &str = include_str!("designs/robust-small.toml");

fn problem(text: &str) -> Result<DesignSpec, String> {
    let file: DesignFile = toml::from_str(text).map_err(|e| e.to_string())?;
    DesignSpec::check(PathBuf::from("robust.toml"), file).map_err(|e| e.to_string())
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("grainchain-robust-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Every design of the space (4 sections, 2 choices).
fn every_design() -> Vec<Vec<usize>> {
    (0..16usize)
        .map(|k| (0..4).map(|i| (k >> (3 - i)) & 1).collect())
        .collect()
}

/// The screening objective of every design of the space against the 95th percentile of its 32
/// draws worked here (the draws' peaks sorted, position 0.95 x 31 = 29.45 interpolated between
/// the 30th and 31st, over the reference column's nominal peak); and with giving up at the
/// median objective: a design not given up has the same bits, one given up reports a lower
/// bound at or below its true objective and at or above the level it gave up at.
#[test]
fn the_screening_statistic_by_hand_and_giving_up_keeps_it_exact() {
    let p = problem(SMALL).unwrap();
    let reference = search::reference(&p).unwrap();
    let r = p.robust.as_ref().unwrap();
    let settings = search::settings(&p);
    let mut objectives = Vec::new();
    for genes in every_design() {
        let beads = p.beads(&genes);
        let mut peaks: Vec<f64> = (0..32)
            .map(|j| {
                let (c, imp) = r.draws.column(j, &beads, &p.impacts[0]);
                evaluate(&c, &imp, &p.protected, &settings)
                    .unwrap()
                    .peak_force
            })
            .collect();
        peaks.sort_by(f64::total_cmp);
        let by_hand = (peaks[29] + 0.45 * (peaks[30] - peaks[29])) / reference[0].peak_force;
        let scored = search::score(&p, &genes, &reference).unwrap();
        // The interpolation's weight 0.45 is 0.95 * 31 - 29 in floating point there: a few
        // roundings of numbers near 1.
        assert!(
            (scored.objective - by_hand).abs() <= 1e-14 * by_hand,
            "{genes:?}: {} against {by_hand}",
            scored.objective
        );
        assert!(!scored.given_up);
        objectives.push(scored.objective);
    }
    let mut sorted = objectives.clone();
    sorted.sort_by(f64::total_cmp);
    let level = sorted[8];
    let (mut exact, mut bounds) = (0, 0);
    for (genes, &whole) in every_design().iter().zip(&objectives) {
        let s = search::score_unless(&p, genes, &reference, level).unwrap();
        if s.given_up {
            bounds += 1;
            assert!(s.objective <= whole && s.objective >= level, "{genes:?}");
        } else {
            exact += 1;
            assert_eq!(s.objective.to_bits(), whole.to_bits(), "{genes:?}");
        }
    }
    assert!(bounds > 0 && exact > 0, "{bounds} {exact}");
    record_one(Row {
        check: "robust objective: screening p95 by hand, give-up exact".into(),
        parameters: "16 designs of 12 beads, 32 draws, 1 % d, 5 % E".into(),
        source: "type-7 quantile worked in the test; exact property".into(),
        expected: "equal to 1e-14; equal bits unless given up".into(),
        measured: format!("{exact} exact, {bounds} lower bounds"),
        tolerance: "1e-14 relative".into(),
        status: Status::Pass,
    });
}

/// Common random numbers: draw `j` multiplies bead `i` of every column by the same factors, and
/// the first draws of a longer set are the shorter set's (the finalists' draws extend the
/// screening's).
#[test]
fn every_candidate_meets_the_same_draws() {
    let p = problem(SMALL).unwrap();
    let tol = p.tolerances.unwrap();
    let long = Draws::new(12, &tol, 48, SEARCH_STREAM);
    let short = Draws::new(12, &tol, 32, SEARCH_STREAM);
    let (a, b) = (p.beads(&[0, 0, 0, 0]), p.beads(&[1, 0, 1, 1]));
    for j in 0..32 {
        let (ca, ia) = long.column(j, &a, &p.impacts[0]);
        let (cb, ib) = long.column(j, &b, &p.impacts[0]);
        assert_eq!(short.column(j, &a, &p.impacts[0]), (ca.clone(), ia.clone()));
        assert_eq!(ia.speed, ib.speed);
        // The factor read back as a quotient: two roundings (the product, the quotient) of a
        // number near 1 each way, at most 2 ulp apart.
        let same = |x: f64, y: f64| (x - y).abs() <= 4.5e-16;
        for i in 0..12 {
            assert!(same(
                ca[i].diameter / a[i].diameter,
                cb[i].diameter / b[i].diameter
            ));
            assert!(same(
                ca[i].material.young / a[i].material.young,
                cb[i].material.young / b[i].material.young
            ));
        }
    }
}

/// The command: both searches, the finalists and both winners, the same bytes on 1 and 2
/// threads; the robust winner's confirmed statistic is the least of the confirmed finalists',
/// each finalist confirmed only when its screening interval reaches the best one's, and
/// `winners.csv` holds the nominal and the robust winner on the fresh draws.
#[test]
fn both_winners_side_by_side_and_the_same_on_every_thread_count() {
    let dir = tmp("cli");
    let file = dir.join("robust.toml");
    std::fs::write(&file, SMALL).unwrap();
    let mut outs = Vec::new();
    for threads in ["1", "2"] {
        let out = dir.join(format!("out-{threads}"));
        let (code, _, err) =
            grainchain(&["design", s(&file), "--out", s(&out), "--threads", threads]);
        assert_eq!(code, Some(0), "{err}");
        outs.push(out);
    }
    for name in ["winners.csv", "finalists.csv", "designs.csv"] {
        let a = std::fs::read(outs[0].join(name)).unwrap();
        assert_eq!(a, std::fs::read(outs[1].join(name)).unwrap(), "{name}");
    }
    let mut fin = csv::Reader::from_path(outs[0].join("finalists.csv")).unwrap();
    let h = fin.headers().unwrap().clone();
    let col = |c: &str| h.iter().position(|x| x == c).unwrap();
    let rows: Vec<csv::StringRecord> = fin.records().map(Result::unwrap).collect();
    let num = |r: &csv::StringRecord, c: &str| r[col(c)].parse::<f64>().unwrap_or(f64::NAN);
    let best_high = num(&rows[0], "screened_high");
    let mut winner = None;
    for r in &rows {
        let confirmed = r[col("confirm_draws")] == *"48";
        // Confirmed exactly when the screening interval reaches the best one's.
        assert_eq!(confirmed, num(r, "screened_low") <= best_high, "{r:?}");
        if &r[col("winner")] == "true" {
            winner = Some(num(r, "confirmed"));
        }
    }
    let winner = winner.expect("a winner");
    for r in &rows {
        // Unconfirmed finalists have no confirmed value (NaN).
        let c = num(r, "confirmed");
        assert!(c.is_nan() || c >= winner, "{r:?}");
    }
    let w = std::fs::read_to_string(outs[0].join("winners.csv")).unwrap();
    let lines: Vec<&str> = w.lines().collect();
    assert_eq!(lines.len(), 3, "{w}");
    assert!(lines[1].starts_with("nominal,") && lines[2].starts_with("robust,"));
    let md = std::fs::read_to_string(outs[0].join("DESIGN.md")).unwrap();
    assert!(md.contains("## Robust design") && md.contains("Both winners"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A robust objective's keys are refused by name, and `--shard` is refused for it.
#[test]
fn robust_keys_are_checked_by_name() {
    let cases = [
        (
            SMALL.replace("screen = 32", "screen = 64"),
            "tolerances.screen",
        ),
        (
            SMALL.replace("screen = 32", "screen = 8"),
            "tolerances.screen",
        ),
        (
            SMALL.replace("finalists = 4", "finalists = 0"),
            "tolerances.finalists",
        ),
        (
            SMALL.replace("minimize = \"p95\"", "minimize = \"quantile\""),
            "objective.quantile",
        ),
        (
            SMALL.replace(
                "minimize = \"p95\"",
                "minimize = \"quantile\"\nquantile = 1.0",
            ),
            "objective.quantile",
        ),
        (
            SMALL.replace("minimize = \"p95\"", "minimize = \"mean\"\nquantile = 0.9"),
            "objective.quantile",
        ),
        (
            SMALL.replace("minimize = \"p95\"", "minimize = \"peak\""),
            "tolerances.screen",
        ),
        (
            SMALL.replace("[tolerances]", "[refine]\n\n[tolerances]"),
            "objective.minimize",
        ),
    ];
    for (text, key) in cases {
        let e = problem(&text).unwrap_err();
        assert!(e.contains(key), "{key}: {e}");
    }
    assert!(problem(&SMALL.replace(
        "minimize = \"p95\"",
        "minimize = \"quantile\"\nquantile = 0.9"
    ))
    .is_ok());
    // Damped contacts: a robust objective is the Monte Carlo's alone, so they are accepted;
    // the first-order analysis of a peak objective still refuses them.
    let damped = SMALL.replace("wall = \"steel\"", "wall = \"steel\"\nrestitution = 0.9");
    assert!(problem(&damped).is_ok());
    let peak = damped
        .replace("minimize = \"p95\"", "minimize = \"peak\"")
        .replace("screen = 32\nconfirm = 48\nfinalists = 4\n", "");
    let e = problem(&peak).unwrap_err();
    assert!(e.contains("tolerances") && e.contains("restitution"), "{e}");
    let dir = tmp("shard");
    let file = dir.join("robust.toml");
    std::fs::write(&file, SMALL).unwrap();
    let out = dir.join("out");
    let (code, _, err) = grainchain(&["design", s(&file), "--out", s(&out), "--shard", "1/2"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("shard") && err.contains("robust"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}
