//! `[tolerances]` of `grainchain design` (`design::tolerance`): the first-order spread of a
//! protector's peak from its exact derivatives agrees with a Monte Carlo where the peak is
//! linear in the tolerances, the Monte Carlo is the seed's at every thread count, bad
//! `[tolerances]` are refused by key, the p95 objective runs a search, and the outputs hold
//! the derivatives to the last bit.

use crate::common::{grainchain, record_one, s, Row};
use grainchain::design::file::{DesignFile, DesignSpec};
use grainchain::design::search;
use grainchain::design::tolerance::{first_order, monte_carlo, spread, Tolerances};
use grainchain_engine::protector::{gradients, Case, Need, Settings};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

/// Four sections of two beads, steel or PTFE (6 mm): 16 designs (`validation/design.rs`'s).
const SMALL: &str = r#"
[space]
beads = 8
sections = 4
materials = ["steel", "ptfe"]
diameters = [0.006]

[load]
striker = { material = "steel", diameter = 0.006 }
speeds = [1.0]

[search]
seed = 3
population = 8
generations = 12
stale = 12
"#;

/// SMALL with a `[tolerances]` table.
const TABLE: &str =
    "\n[tolerances]\ndiameter = 0.01\nE = 0.02\nrho = 0.005\nspeed = 0.02\nsamples = 100\n";

fn problem(text: &str) -> Result<DesignSpec, String> {
    let file: DesignFile = toml::from_str(text).map_err(|e| e.to_string())?;
    DesignSpec::check(PathBuf::from("tol.toml"), file).map_err(|e| e.to_string())
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!(
        "grainchain-tolerances-{name}-{}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The settings of the tolerance analysis: the search's (step of the default accuracy, its
/// time cap of 10 contact-time sums), the peak only.
fn peak_settings() -> Settings {
    Settings {
        need: Need::Peak,
        time_cap: search::SEARCH_CAP,
        ..Settings::default()
    }
}

/// An 8-bead column of steel then PTFE, each bead 3.7 % larger than the one before (no two
/// contacts share the shortest contact time, so the step has one derivative), a brass bead
/// among the PTFE ones.
fn column() -> Case {
    let mut case = Case::steel_then_ptfe(8);
    for (i, b) in case.beads.iter_mut().enumerate() {
        b.diameter *= 1.0 + 0.037 * i as f64;
    }
    case.beads[5].material = grainchain_engine::units::BRASS;
    case
}

/// At tolerances of 0.1 % the peak is linear in them (its second-order part is of order 1e-3
/// of the first), so the Monte Carlo's standard deviation, mean and 95th percentile are the
/// first-order ones up to the Monte Carlo's own sampling error.
#[test]
fn first_order_spread_agrees_with_a_monte_carlo_at_small_tolerances() {
    let case = column();
    let n = 4000;
    let tol = Tolerances {
        diameter: 1e-3,
        young: 1e-3,
        density: 1e-3,
        speed: 1e-3,
        samples: n,
        seed: 11,
    };
    let s = spread(
        &case.beads,
        &case.impact,
        &case.protected,
        &peak_settings(),
        &tol,
        2,
    )
    .unwrap();
    let (f, m) = (&s.first, &s.monte_carlo);
    assert!(s.gradients.evaluation.complete && m.bounds == 0, "{m:?}");
    assert!(s.gradients.tie.is_none() && !s.gradients.step_shared);
    let n1 = (n - 1) as f64;
    // The sample standard deviation of n normal numbers has a relative standard error of
    // 1 / sqrt(2 (n - 1)) = 1.1 % at n = 4000: the ratio within 4 of them (4.5 %).
    let ratio = m.sd / f.sd;
    let sd_ok = (ratio - 1.0).abs() <= 4.0 / (2.0 * n1).sqrt();
    // The mean's standard error is sigma / sqrt(n); the peak's curvature moves the mean by
    // about sigma^2 / P, 1e-3 sigma here: within 4 standard errors.
    let se_mean = f.sd / (n as f64).sqrt();
    let mean_ok = (m.mean - f.peak).abs() <= 4.0 * se_mean;
    // The 95th percentile of n normal numbers has a standard error of sqrt(0.95 0.05 / n) /
    // phi(1.645) sigma = 2.11 sigma / sqrt(n): within 4 of them.
    let p95_ok = (m.p95 - f.p95()).abs() <= 4.0 * 2.11 * se_mean;
    let ok = record_one(
        Row::new(
            "first-order spread of a protector's peak against a Monte Carlo",
            "8 beads (4 steel, 3 PTFE, 1 brass, graded 3.7 % per bead) at a steel wall, steel \
             striker 1 m/s; diameter, E, rho and speed each 0.1 %, 4000 columns",
            "linearisation from protector::gradients (exact derivatives)",
        )
        .expected(format!(
            "sd {:.6e} N, p95 {:.6} N (first order)",
            f.sd,
            f.p95()
        ))
        .measured(format!(
            "sd {:.6e} N (ratio {ratio:.4}), mean - P {:.3e} N, p95 {:.6} N",
            m.sd,
            m.mean - f.peak,
            m.p95
        ))
        .tolerance("sd ratio within 4 standard errors (4.5 %); mean and p95 within 4")
        .pass(sd_ok && mean_ok && p95_ok),
    );
    assert!(ok, "{f:?} {m:?}");
    // Not vacuous: the spread is far above the rounding of a peak (1e-12 of it).
    assert!(f.sd > 1e-6 * f.peak, "{}", f.sd);
}

/// The Monte Carlo draws every column first and evaluates them in order: the same bits on 1 and
/// 2 threads and again with the same seed, others with another seed.
#[test]
fn the_monte_carlo_is_the_seeds_on_every_thread_count() {
    let case = column();
    let tol = Tolerances {
        diameter: 0.01,
        young: 0.02,
        density: 0.01,
        speed: 0.02,
        samples: 150,
        seed: 5,
    };
    let run = |tol: &Tolerances, threads| {
        monte_carlo(
            &case.beads,
            &case.impact,
            &case.protected,
            &peak_settings(),
            tol,
            threads,
        )
        .unwrap()
    };
    let bits =
        |m: grainchain::design::tolerance::MonteCarlo| [m.mean, m.sd, m.p95].map(f64::to_bits);
    let one = run(&tol, 1);
    assert_eq!(bits(one), bits(run(&tol, 2)));
    assert_eq!(bits(one), bits(run(&tol, 1)));
    assert_ne!(bits(one), bits(run(&Tolerances { seed: 6, ..tol }, 2)));
    assert_eq!(one.samples, 150);
}

/// Bad `[tolerances]` (and a p95 objective without them) are refused naming the file and the
/// key; through the CLI with exit code 2 and nothing written.
#[test]
fn bad_tolerances_name_their_key() {
    let with = |table: &str| format!("{SMALL}\n[tolerances]\n{table}\n");
    let cases = [
        (with("diameter = -0.01"), "tolerances.diameter"),
        (with("diameter = 0.3"), "tolerances.diameter"),
        (with("E = nan"), "tolerances.E"),
        (with("rho = inf"), "tolerances.rho"),
        (with("speed = 0.21"), "tolerances.speed"),
        (with("speed = \"5 %\""), "speed"),
        (with("samples = 99"), "tolerances.samples"),
        (with("samples = 100001"), "tolerances.samples"),
        (with("samples = -1"), "samples"),
        (with("nu = 0.01"), "unknown field `nu`"),
        (
            SMALL.replace(
                "[search]",
                "[objective]\nminimize = \"p95-first-order\"\n\n[search]",
            ),
            "objective.minimize",
        ),
        (
            with("diameter = 0.01").replace("speeds = [1.0]", "speeds = [1.0]\nrestitution = 0.9"),
            "tolerances",
        ),
        // E = 8e12 is a material; 1.8 times it passes the largest modulus, 1e13 Pa.
        (
            with("E = 0.2").replace(
                "materials = [\"steel\", \"ptfe\"]",
                "materials = [\"steel\", { E = 8e12, nu = 0.3, rho = 8000 }]",
            ),
            "tolerances.E",
        ),
    ];
    for (text, key) in &cases {
        let Err(err) = problem(text) else {
            panic!("{key}: accepted\n{text}");
        };
        assert!(err.contains(key), "{key}: {err}");
        if key.starts_with("tolerances.") || key.starts_with("objective.") {
            assert!(err.contains("tol.toml"), "{key}: {err}");
        }
    }
    // The valid table passes, and a bead 4 standard deviations off stays a bead at the largest
    // tolerance.
    let ok = problem(&format!("{SMALL}{TABLE}")).unwrap();
    assert_eq!(
        ok.tolerances.unwrap().seed,
        3,
        "the search's seed by default"
    );
    problem(&with("diameter = 0.2\nE = 0.2\nrho = 0.2\nspeed = 0.2")).unwrap();
    let dir = tmp("bad");
    let path = dir.join("bad.toml");
    std::fs::write(&path, with("samples = 99")).unwrap();
    let out = dir.join("out");
    let (code, _, err) = grainchain(&["design", s(&path), "--out", s(&out)]);
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("bad.toml") && err.contains("tolerances.samples"),
        "{err}"
    );
    assert!(!out.join("DESIGN.md").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// The p95 objective: a tiny search runs, every design's objective is its peak plus 1.645
/// first-order standard deviations over the reference's peak (the best one checked by hand),
/// and the command writes the tolerance outputs, whose derivatives are the engine's to the bit.
#[test]
fn the_p95_objective_runs_a_tiny_search_and_its_outputs() {
    let text = format!(
        "{}{TABLE}",
        SMALL.replace(
            "[search]",
            "[objective]\nminimize = \"p95-first-order\"\n\n[search]"
        )
    );
    let p = problem(&text).unwrap();
    let dir = tmp("p95");
    let outcome = search::run(
        &p,
        3,
        1,
        &dir.join("island.csv"),
        false,
        &p.digest,
        search::Tick(Arc::new(|| {})),
    )
    .unwrap();
    let best = &outcome.all[0];
    let beads = p.beads(&best.genes);
    let settings = search::settings(&p);
    let g = gradients(&beads, &p.impacts[0], &p.protected, &settings).unwrap();
    let tol = p.tolerances.unwrap();
    let f = first_order(&beads, 1.0, g.evaluation.peak_force, &g.peak, &tol);
    let by_hand = f.p95() / outcome.reference[0].peak_force;
    assert_eq!(best.objective.to_bits(), by_hand.to_bits(), "{best:?}");
    // The margin is there: the objective is above the peak's ratio.
    assert!(best.objective > best.peak / outcome.reference[0].peak_force);

    // The command with its outputs.
    let file = dir.join("p95.toml");
    std::fs::write(&file, &text).unwrap();
    let out = dir.join("out");
    let (code, _, err) = grainchain(&["design", s(&file), "--out", s(&out), "--threads", "2"]);
    assert_eq!(code, Some(0), "{err}");
    let read = |name: &str| std::fs::read_to_string(out.join(name)).unwrap();
    let tolerances = read("tolerances.csv");
    assert_eq!(
        tolerances.lines().next(),
        Some(grainchain::design::TOLERANCES_HEADER)
    );
    // The ten best designs (or as many as were ranked) and the baselines (monodisperse, six
    // tapered, no containers below 9 beads, the pattern).
    let columns = (read("designs.csv").lines().count() - 1).min(10) + 8;
    assert_eq!(tolerances.lines().count(), 1 + columns, "{tolerances}");
    let sens = read("sensitivities.csv");
    let header: Vec<&str> = grainchain::design::SENSITIVITIES_HEADER
        .split(',')
        .collect();
    assert_eq!(sens.lines().next(), Some(header.join(",").as_str()));
    assert_eq!(sens.lines().count(), 1 + columns * 8);
    // Rank 1's rows: its derivatives read back to the engine's bits; the shares sum to at most 1
    // (the speed's share is the rest).
    let at = |c: &str| header.iter().position(|x| *x == c).unwrap();
    let mut share = 0.0;
    for (i, record) in csv::Reader::from_reader(sens.as_bytes())
        .records()
        .take(8)
        .enumerate()
    {
        let r = record.unwrap();
        assert_eq!((&r[0], &r[1]), ("design", "1"));
        let x = |c: &str| r[at(c)].parse::<f64>().unwrap().to_bits();
        assert_eq!(x("dpeak_ddiameter"), g.peak.diameter[i].to_bits());
        assert_eq!(x("dpeak_dyoung"), g.peak.young[i].to_bits());
        assert_eq!(x("dpeak_ddensity"), g.peak.density[i].to_bits());
        assert_eq!(x("dpeak_dpoisson"), g.peak.poisson[i].to_bits());
        assert_eq!(x("dpeak_dspeed"), g.peak.speed.to_bits());
        assert_eq!(x("diameter_m"), beads[i].diameter.to_bits());
        share += f.bead_share(i);
        assert_eq!(x("variance_share"), f.bead_share(i).to_bits());
    }
    // A sum of eight shares: rounding of a few operations.
    assert!(share > 0.0 && share <= 1.0 + 1e-12, "{share}");
    let md = read("DESIGN.md");
    assert!(md.contains("## Manufacturing tolerances"), "{md}");
    assert!(
        md.contains("### What dominates the best design's spread"),
        "{md}"
    );
    assert!(out.join("sensitivity.svg").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// What a run with derivatives costs against an evaluation on the 40-bead reference column
/// (printed, not asserted: timings depend on the machine's load); the two runs take the same
/// steps and find the same peak to rounding.
#[test]
fn a_gradient_costs_what_it_costs() {
    let case = Case::steel_then_ptfe(40);
    let s = Settings::default();
    let time = |f: &dyn Fn()| {
        let mut best = f64::INFINITY;
        for _ in 0..5 {
            let t = Instant::now();
            f();
            best = best.min(t.elapsed().as_secs_f64());
        }
        best
    };
    let e = case.evaluate(&s).unwrap();
    let g = gradients(&case.beads, &case.impact, &case.protected, &s).unwrap();
    assert_eq!(e.steps, g.evaluation.steps);
    // The same run, recorded: the peak to the rounding of a few thousand steps' sums.
    assert!((e.peak_force - g.evaluation.peak_force).abs() <= 1e-12 * e.peak_force);
    let te = time(&|| {
        case.evaluate(&s).unwrap();
    });
    let tg = time(&|| {
        gradients(&case.beads, &case.impact, &case.protected, &s).unwrap();
    });
    record_one(
        Row::new(
            "cost of the peak's derivatives (protector-40)",
            "20 steel + 20 PTFE 6 mm, blanes-moan4 with events at 20 steps per contact, best of 5",
            "timing",
        )
        .measured(format!(
            "evaluate {:.3} ms, gradients {:.3} ms: {:.1} evaluations ({} steps)",
            te * 1e3,
            tg * 1e3,
            tg / te,
            e.steps
        ))
        .info(),
    );
    eprintln!(
        "protector-40: evaluate {:.3} ms, gradients {:.3} ms, ratio {:.1}",
        te * 1e3,
        tg * 1e3,
        tg / te
    );
}

/// Issue 50, item 6: the search's journal and the output folder belong to what the search
/// reads, so `[refine]` and `[tolerances] samples` may change under them; the first-order p95
/// reads the standard deviations, the peak none of the table.
#[test]
fn the_search_digest_is_what_the_search_reads() {
    let digest = |text: &str| problem(text).unwrap().digest;
    let plain = digest(SMALL);
    let with = |table: &str| format!("{SMALL}{table}");
    let refine = "\n[refine]\ndiameters = [0.005, 0.007]\n";
    // The peak reads none of [tolerances] nor [refine].
    assert_eq!(digest(&with(TABLE)), plain);
    assert_eq!(digest(&with(&format!("{TABLE}{refine}"))), plain);
    // The first-order p95 reads the standard deviations, not the samples or the seed.
    let p95 = |table: &str| {
        digest(&format!(
            "{}{table}",
            SMALL.replace(
                "[search]",
                "[objective]\nminimize = \"p95-first-order\"\n\n[search]"
            )
        ))
    };
    let first = p95(TABLE);
    assert_ne!(first, plain);
    assert_eq!(p95(&TABLE.replace("samples = 100", "samples = 300")), first);
    assert_eq!(p95(&format!("{TABLE}seed = 9\n")), first);
    assert_ne!(p95(&TABLE.replace("E = 0.02", "E = 0.03")), first);
    // A robust objective's search reads its screening draws: their number and seed, not how
    // many confirm a finalist, how many finalists, or the fresh draws' samples. Its nominal
    // search is the plain file's.
    let robust = |table: &str| {
        problem(&format!(
            "{}{table}",
            SMALL.replace("[search]", "[objective]\nminimize = \"p95\"\n\n[search]")
        ))
        .unwrap()
    };
    let r = robust(TABLE);
    assert_ne!(r.digest, plain);
    assert_eq!(r.nominal().digest, plain);
    let more = format!(
        "{}confirm = 300\nfinalists = 3\n",
        TABLE.replace("samples = 100", "samples = 500")
    );
    assert_eq!(robust(&more).digest, r.digest);
    assert_ne!(robust(&format!("{TABLE}screen = 32\n")).digest, r.digest);
    assert_ne!(robust(&format!("{TABLE}seed = 9\n")).digest, r.digest);
    let row = Row::new(
        "tolerances: the search's digest is what it reads",
        "SMALL; the peak, the first-order p95, the Monte Carlo p95",
        "issue 50, item 6",
    )
    .expected(
        "[refine], samples (and a first-order search's seed; a robust one's confirm and \
         finalists) change no search digest; a standard deviation, a robust screen or seed does",
    )
    .measured("as expected")
    .pass(true);
    assert!(record_one(row));
}

/// Issue 50, item 6: the Monte Carlo after the search keeps a journal. A run of SMALL with
/// `[tolerances]` (100 samples); a late interruption, simulated by cutting the journal to half
/// its lines and a torn one; `--resume` runs only the columns missing and writes the same bytes.
/// Then `samples = 200` is written into the file: `--resume` (no `--force`) evaluates no design
/// and takes every column's first 100 draws from the journal (the first draws of a longer set
/// are the shorter set). A column met twice (a baseline among the best designs) is run once.
#[test]
fn the_monte_carlo_resumes_from_its_journal() {
    let dir = tmp("journal");
    let file = dir.join("tol.toml");
    let text = format!("{SMALL}{TABLE}");
    std::fs::write(&file, &text).unwrap();
    let out = dir.join("out");
    let run = |args: &[&str]| {
        let mut all = vec!["design", s(&file), "--out", s(&out), "--threads", "2"];
        all.extend(args);
        let (code, _, err) = grainchain(&all);
        assert_eq!(code, Some(0), "{err}");
        err
    };
    let journal = out.join("evaluations").join("monte-carlo.csv");
    let lines = || -> Vec<String> {
        std::fs::read_to_string(&journal)
            .unwrap()
            .lines()
            .map(String::from)
            .collect()
    };
    // The numbers of the note `design: Monte Carlo columns: X known already (...), Y run`
    // (none: nothing known, all run, the journal's lines but its two first).
    let counts = |err: &str| -> (usize, usize) {
        match err.lines().find(|l| l.contains("Monte Carlo columns:")) {
            None => (0, lines().len() - 2),
            Some(l) => {
                let words: Vec<&str> = l.split_whitespace().collect();
                let n = |i: usize| words[i].parse::<usize>().unwrap();
                (n(4), n(words.len() - 2))
            }
        }
    };
    let outputs = [
        "designs.csv",
        "baselines.csv",
        "tolerances.csv",
        "sensitivities.csv",
    ];
    let read = |name: &str| std::fs::read(out.join(name)).unwrap();
    let err = run(&[]);
    let first: Vec<Vec<u8>> = outputs.iter().map(|n| read(n)).collect();
    // Every column of the tolerance table at 100 draws, each distinct one in the journal once.
    let columns = std::str::from_utf8(&first[2]).unwrap().lines().count() - 1;
    let (known, ran) = counts(&err);
    assert_eq!(known + ran, columns * 100, "{err}");
    let all = lines();
    assert_eq!(all.len() - 2, ran);
    let kept = ran / 2;
    let mut cut: String = all[..2 + kept].iter().map(|l| format!("{l}\n")).collect();
    cut.push_str(&all[2 + kept][..20]);
    std::fs::write(&journal, cut).unwrap();

    let err = run(&["--resume"]);
    assert!(err.contains(" 0 designs evaluated"), "{err}");
    assert_eq!(
        counts(&err),
        (columns * 100 - (ran - kept), ran - kept),
        "{err}"
    );
    for (name, bytes) in outputs.iter().zip(&first) {
        assert!(read(name) == *bytes, "{name} differs after --resume");
    }

    std::fs::write(&file, text.replace("samples = 100", "samples = 200")).unwrap();
    let err = run(&["--resume"]);
    assert!(err.contains(" 0 designs evaluated"), "{err}");
    assert_eq!(counts(&err), (columns * 200 - ran, ran), "{err}");
    let tolerances = String::from_utf8(read("tolerances.csv")).unwrap();
    let header: Vec<&str> = grainchain::design::TOLERANCES_HEADER.split(',').collect();
    let at = header.iter().position(|c| *c == "samples").unwrap();
    for r in csv::Reader::from_reader(tolerances.as_bytes()).records() {
        assert_eq!(&r.unwrap()[at], "200");
    }
    let row = Row::new(
        "tolerances: the Monte Carlo resumes from its journal",
        format!("SMALL, {columns} columns x 100 draws, {ran} distinct"),
        "issue 50, item 6",
    )
    .expected("--resume runs only the columns missing, the same bytes; samples 100 -> 200 reuses the search")
    .measured(format!(
        "cut to {kept} of {ran} lines: the rest run, every output the same bytes; at 200 samples \
         0 designs evaluated, {} columns known",
        columns * 200 - ran
    ))
    .pass(true);
    let _ = std::fs::remove_dir_all(&dir);
    assert!(record_one(row));
}
