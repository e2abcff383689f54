//! Ensemble studies (`grainchain study`): shards merge into exactly the single-machine outputs,
//! members do not depend on the thread count, member 0 is the scene file's own run, the energy
//! budget adds up, and bad sweep files fail with a clear message and exit code 2.
//!
//! The statistics themselves (quantiles, bands, jackknife, local slope of an exact power law,
//! level crossings) are checked against hand-computed values in `engine/src/analysis/ensemble.rs`.

use crate::common::s;
use grainchain::study::{self, Shard, SweepFile};
use grainchain_engine::Field;
use grainchain_engine::Recorder;
use grainchain_engine::Scene;
use std::path::{Path, PathBuf};
use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_grainchain");
const ROOT: &str = env!("CARGO_MANIFEST_DIR");

fn grainchain(args: &[&str]) -> (Option<i32>, String, String) {
    let out = Command::new(BIN)
        .args(args)
        .current_dir(ROOT)
        .output()
        .expect("run grainchain");
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("grainchain-study-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// The shard test: one run of `studies/smoke.toml` on 2 threads equals its 3 shards run
/// on 1 thread each into 3 different directories and merged, bit for bit: every member file and
/// every output table. (STUDY.md differs only in its cost section, which holds wall times.)
#[test]
fn one_run_equals_three_merged_shards() {
    let one = tmp("one");
    let (code, _, err) = grainchain(&[
        "study",
        "studies/smoke.toml",
        "--out",
        s(&one),
        "--threads",
        "2",
    ]);
    assert_eq!(code, Some(0), "{err}");
    let parts: Vec<PathBuf> = (1..=3).map(|k| tmp(&format!("part{k}"))).collect();
    for (k, d) in parts.iter().enumerate() {
        let shard = format!("{}/3", k + 1);
        let (code, out, err) = grainchain(&[
            "study",
            "studies/smoke.toml",
            "--out",
            s(d),
            "--shard",
            &shard,
            "--threads",
            "1",
        ]);
        assert_eq!(code, Some(0), "{err}");
        assert!(out.contains("--merge"), "{out}");
    }
    let from = format!("{},{}", s(&parts[1]), s(&parts[2]));
    let (code, _, err) = grainchain(&[
        "study",
        "studies/smoke.toml",
        "--merge",
        "--out",
        s(&parts[0]),
        "--from",
        &from,
    ]);
    assert_eq!(code, Some(0), "{err}");

    let sweep = SweepFile::load(Path::new(ROOT).join("studies/smoke.toml")).unwrap();
    let jobs = study::plan(&sweep);
    assert_eq!(jobs.len(), 12);
    for j in &jobs {
        let k = (0..3)
            .find(|&k| Shard { k: k + 1, n: 3 }.owns(j.index))
            .unwrap();
        let name = format!("members/{}.csv", j.stem());
        let a = std::fs::read(one.join(&name)).unwrap();
        let b = std::fs::read(parts[k].join(&name)).unwrap();
        assert!(
            a == b,
            "{name}: 2 threads and shard {}/3 on 1 thread differ",
            k + 1
        );
        // A shard writes only its own members.
        for (other, d) in parts.iter().enumerate() {
            if other != k {
                assert!(
                    !d.join(&name).exists(),
                    "{name} written by shard {}",
                    other + 1
                );
            }
        }
    }
    for f in [
        "ensemble.csv",
        "fits.csv",
        "slope.csv",
        "alpha.csv",
        "budget.csv",
        "random.csv",
    ] {
        let a = std::fs::read(one.join(f)).unwrap();
        let b = std::fs::read(parts[0].join(f)).unwrap();
        assert!(a == b, "{f}: single run and merged shards differ");
    }
    // Every number of every table in the one CSV form (ensemble.csv wrote tiny numbers with
    // ~45 zeros), missing values empty.
    for f in [
        "ensemble.csv",
        "fits.csv",
        "slope.csv",
        "alpha.csv",
        "budget.csv",
        "random.csv",
    ] {
        let text = std::fs::read_to_string(one.join(f)).unwrap();
        for (r, line) in text.lines().enumerate().skip(1) {
            for field in line.split(',') {
                assert!(!["NaN", "none", "inf"].contains(&field), "{f}: row {r}");
                if let Ok(x) = field.parse::<f64>() {
                    assert_eq!(grainchain::report::csv_number(x), field, "{f}: row {r}");
                }
            }
        }
    }
    // 300 snapshots end before a decade from the leak onset: STUDY.md says so instead of an
    // empty table.
    let md = std::fs::read_to_string(one.join("STUDY.md")).unwrap();
    assert!(
        md.contains("| a | none | the run (300 snapshots) ends before 2 x the leak onset"),
        "{md}"
    );
    for d in parts.iter().chain([&one]) {
        let _ = std::fs::remove_dir_all(d);
    }
}

/// Member 0 of a striker-speed ensemble is the scene file's own run: its container energy equals,
/// bit for bit, a run of the unchanged scene file (outer chains of 4000 grains where the study
/// uses 600: grains no wave reaches are never integrated, so the arithmetic is the same). And the
/// regions of the budget partition the chain: they add up to the total energy, which is
/// conserved within the run's own measured energy error. The sections outside the container are
/// sampled: numbers exactly at `budget_outputs`, empty cells elsewhere.
#[test]
fn member_zero_is_the_scene_and_the_budget_adds_up() {
    let sweep = SweepFile::load(Path::new(ROOT).join("studies/smoke.toml")).unwrap();
    let out = tmp("member0");
    // Job 0 alone: 12 jobs, shard 1/12.
    let opts = study::Options {
        out: out.clone(),
        shard: Shard { k: 1, n: 12 },
        threads: 1,
        resume: false,
        progress: false,
    };
    let r = study::run_jobs(&sweep, &opts).unwrap();
    assert_eq!(r.ran, 1);
    let text = std::fs::read_to_string(out.join("members/a-m0.csv")).unwrap();
    let mut rows = text.lines();
    let header: Vec<&str> = rows.next().unwrap().split(',').collect();
    assert_eq!(
        header,
        [
            "snapshot",
            "container",
            "outer-left",
            "outer-right",
            "striker",
            "beyond-striker",
            "volume",
            "force-left",
            "force-right"
        ]
    );
    // The budget's regions are the first five columns; the gauges follow.
    let budget = 0..5;
    // Empty cells (outputs a sampled section skips) read as NaN.
    let table: Vec<Vec<f64>> = rows
        .map(|l| {
            l.split(',')
                .skip(1)
                .map(|x| {
                    if x.is_empty() {
                        f64::NAN
                    } else {
                        x.parse().unwrap()
                    }
                })
                .collect()
        })
        .collect();
    assert_eq!(table.len(), 301);
    let at = study::budget_outputs(300);
    assert!(
        at.len() > 150 && at.len() < 300,
        "{} budget snapshots",
        at.len()
    );
    for (t, row) in table.iter().enumerate() {
        let sampled = at.contains(&t);
        assert!(row[0].is_finite(), "snapshot {t}: no container energy");
        assert!(
            row[5..].iter().all(|x| x.is_finite()),
            "snapshot {t}: gauges"
        );
        for x in &row[1..budget.end] {
            assert_eq!(
                x.is_finite(),
                sampled,
                "snapshot {t}: sampled {sampled}, cell {x}"
            );
        }
    }

    let mut scene = Scene::load(Path::new(ROOT).join("scenes/containers/a-standard.toml")).unwrap();
    scene
        .set_schedule(300.0 * scene.output_interval(), scene.output_interval())
        .unwrap();
    let c = scene
        .regions()
        .iter()
        .find(|r| r.name == "container")
        .unwrap();
    let mut sim = scene.simulation().unwrap();
    let (a, b) = (
        sim.chain().index_of(c.first).unwrap(),
        sim.chain().index_of(c.last).unwrap(),
    );
    // The gauges from whole snapshots of the grains around the container (another path
    // through the recorder than the member's probes): the volume over 20 outer grains on each
    // side (right minus left mean displacement) and the contact force at each face.
    let k = study::GAUGE_GRAINS;
    let rec = Recorder::new()
        .region("container", a, b)
        .snapshots(
            &[Field::Displacement, Field::Force],
            a - k..b + k + 1,
            0..=300,
        )
        .record(&mut sim)
        .unwrap();
    let direct = &rec.region("container").unwrap().energy;
    assert_eq!(direct.len(), 301);
    for (t, (row, d)) in table.iter().zip(direct).enumerate() {
        assert!(
            row[0] == *d,
            "snapshot {t}: member 0 {} vs the scene file {}",
            row[0],
            d
        );
        let snap = &rec.snapshots[t];
        let (u, f) = (&snap.values[0], &snap.values[1]);
        let n = u.len();
        let mean = |x: &[f64]| x.iter().sum::<f64>() / k as f64;
        let volume = mean(&u[n - k..]) - mean(&u[..k]);
        // Field::Force of a grain is its contact with the next one on the right.
        let (left, right) = (f[k - 1], f[n - k - 1]);
        assert!(
            row[5] == volume && row[6] == left && row[7] == right,
            "snapshot {t}: gauges {:?} vs the snapshot's {volume} {left} {right}",
            &row[5..]
        );
    }
    // Not all zeros: by snapshot 300 the container has grown, and each face has been pressed.
    assert!(table[300][5] > 0.0, "volume {}", table[300][5]);
    for col in [6, 7] {
        assert!(
            table.iter().any(|r| r[col] > 0.0),
            "column {col} never pressed"
        );
    }

    let meta: grainchain::batch::MemberMeta =
        serde_json::from_str(&std::fs::read_to_string(out.join("members/a-m0.json")).unwrap())
            .unwrap();
    assert!(meta.max_energy_error > 0.0 && meta.max_energy_error < 1e-3);
    // The causal horizon of the container scenes drops grains of the outer sections (recorded
    // unprotected) with their kinetic energy, which the member's bookkeeping gives: the
    // regions add up to E0 less at most that, and, at the end, to E0 less exactly that.
    let e0 = meta.initial_energy;
    let dropped = meta.dropped_energy / e0;
    assert!(dropped > 0.0, "the smoke study's horizon dropped nothing");
    for &t in &at {
        let row = &table[t];
        let total: f64 = row[budget.clone()].iter().sum();
        // The run's own energy error bounds |E(t) + dropped(t) - E0| / E0 at output times;
        // 1e-12 covers the different order of summation (five region sums here, one sum over
        // grains there).
        let dev = total / e0 - 1.0;
        let bound = meta.max_energy_error + 1e-12;
        assert!(
            dev <= bound && dev >= -dropped - bound,
            "snapshot {t}: regions add up to {total}, E0 = {e0}, deviation {dev:e} outside \
             [-{dropped:e} (dropped) - {bound:e}, {bound:e}]"
        );
    }
    let last: f64 = table.last().unwrap()[budget].iter().sum();
    let dev = (last / e0 + dropped - 1.0).abs();
    assert!(
        dev <= meta.max_energy_error + 1e-12,
        "at the end the regions plus the dropped energy add up to E0 (1 + {dev:e})"
    );
    let _ = std::fs::remove_dir_all(&out);
}

cases! {
/// Each file under validation/bad_sweeps/ (its first line says what is wrong) fails with exactly
/// this message and exit code 2, and writes nothing.
fn bad_sweep_files_fail_clearly(file: &str, message: &str) {
    let out = tmp(&format!("bad-{file}"));
    let path = format!("validation/bad_sweeps/{file}");
    let (code, _, err) = grainchain(&["study", &path, "--out", s(&out)]);
    assert_eq!(code, Some(2), "{file}: {err}");
    assert!(
        err.contains(&format!("{path}: {message}")),
        "{file}: expected `{path}: {message}` in:\n{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
    assert!(!out.exists(), "{file}: wrote {}", out.display());
}
case_1("members-zero.toml", "key `members`: must be at least 1"),
case_2("missing-scene.toml", "key `containers[0].scene`: no such file"),
case_3("unknown-key.toml", "key `member` (line 4, column 1): unknown field `member`"),
case_4("restitution-one.toml", "key `containers[0].dissipation.restitution`: must be in [0.05, 1), got 1"),
case_5("epsilon-large.toml", "key `perturbation.epsilon`: must be in (0, 1e-3): a tiny perturbation (got 0.5)"),
case_6("reference-unknown.toml", "key `reference`: `z` is not the key of a container of this study"),
case_7("level-above-one.toml", "key `levels[1]`: must be a fraction of the incident energy in (0, 1) (got 1.5)"),
case_8("random-sections-reversed.toml", "key `random.sections`: must be [min, max] with 1 <= min <= max <= 50"),
case_9("outer-too-close.toml", "key `containers[0].outer`: distance must be between 122 (the grains from the container to the striker and one more) and 1e6 grains (got 50)"),
case_10("search-without-e.toml", "key `search.scenes`: needs container `e` (a scene file named `e-*.toml`)"),
case_11("nothing-to-run.toml", "key `containers`: the study has nothing to run"),
case_12("snapshots-string.toml", "key `snapshots` (line 3, column 13): invalid type: string \"many\", expected u64"),
case_13("scene-file.toml", "this is a scene file, not a sweep file (run it with `grainchain run`; `grainchain study` takes a sweep file)"),
case_14("snapshots-huge.toml", "key `snapshots`: must be at most 1e9 output times (got 10000000000)"),
case_15("multirate-ratio-indivisible.toml", "key `multirate.ratio`: must divide the 160 steps of dt per output interval, got 7 (the steps of scene validation/bad_sweeps/../../scenes/containers/a-standard.toml)"),
case_16("container-multirate-ratio-huge.toml", "key `containers[0].multirate.ratio`: must divide the 160 steps of dt per output interval, got 1000000000000 (the steps of scene validation/bad_sweeps/../../scenes/containers/a-standard.toml)"),
case_17("members-huge.toml", "key `members`: 200000006 jobs whose member files would take at least 5012.0 GB (estimated), over the limit of 1.0 GB; run fewer members or snapshots, or pass --allow-large-output"),
}

/// Bad command lines: a shard outside 1..=N, a missing sweep file (exit code 2), and a merge
/// with members missing (exit code 1: the input is fine, the work is not done).
#[test]
fn bad_command_lines_fail_clearly() {
    for shard in ["4/3", "0/2", "1/0", "two"] {
        let (code, _, err) = grainchain(&["study", "studies/smoke.toml", "--shard", shard]);
        assert_eq!(code, Some(2), "--shard {shard}: {err}");
        assert!(err.contains("--shard"), "{err}");
    }
    let (code, _, err) = grainchain(&["study", "studies/no-such-sweep.toml"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("studies/no-such-sweep.toml: cannot read"),
        "{err}"
    );
    let out = tmp("merge-missing");
    let (code, _, err) = grainchain(&["study", "studies/smoke.toml", "--merge", "--out", s(&out)]);
    assert_eq!(code, Some(1), "{err}");
    assert!(
        err.contains("cannot merge: 12 of 12 members are missing, e.g. a-m0 (job 0)"),
        "{err}"
    );
    assert!(!out.join("STUDY.md").exists());
}

/// `reproduce --members N` runs the containers as an ensemble and reports gamma and alpha with
/// intervals over members in REPORT.md (a short run: the machinery, not the physics).
#[test]
fn reproduce_reports_an_ensemble() {
    let out = tmp("reproduce");
    let (code, _, err) = grainchain(&[
        "reproduce",
        "--only",
        "fig4",
        "--only",
        "fig5",
        "--snapshots",
        "300",
        "--threads",
        "2",
        "--members",
        "2",
        "--out",
        s(&out),
    ]);
    assert_eq!(code, Some(0), "{err}");
    let report = std::fs::read_to_string(out.join("REPORT.md")).unwrap();
    assert!(report.contains("## Ensemble: gamma and alpha with intervals over members"));
    // Every container of the five, with 2 members each.
    for key in ["a", "b", "c", "d", "e"] {
        assert!(out.join(format!("ensemble/members/{key}-m1.csv")).is_file());
        assert!(!out.join(format!("ensemble/members/{key}-m2.csv")).exists());
    }
    assert!(out.join("ensemble/STUDY.md").is_file());
    assert!(out.join("ensemble/members/a-m1.csv").is_file());
    let _ = std::fs::remove_dir_all(&out);
}

/// Copy the member files of `from` into a new study folder `to`.
fn copy_members(from: &Path, to: &Path) {
    std::fs::create_dir_all(to.join("members")).unwrap();
    for e in std::fs::read_dir(from.join("members")).unwrap() {
        let p = e.unwrap().path();
        std::fs::copy(&p, to.join("members").join(p.file_name().unwrap())).unwrap();
    }
}

/// Write `text` as the member CSV at `p` and update its JSON's row count and checksum to match.
fn resign(p: &Path, text: &str) {
    std::fs::write(p, text).unwrap();
    let meta = p.with_extension("json");
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&meta).unwrap()).unwrap();
    v["rows"] = (text.lines().count() - 1).into();
    v["csv_fnv"] = grainchain::report::fnv1a(text.as_bytes()).into();
    // The bookkeeping's own checksum signed too, as the buggy writer would.
    let m: grainchain::batch::MemberMeta = serde_json::from_value(v).unwrap();
    std::fs::write(&meta, m.to_signed_json().unwrap()).unwrap();
}

/// Damaged member files are refused by `--merge` (exit 2, naming the file and the problem) and
/// run again by `--resume`, after which the outputs equal the undamaged study's: a member cut
/// at a line end (the issue's `head -150`), one with a NaN, one whose JSON is gone, one whose
/// rows were all there but edited (a changed digit).
#[test]
fn damaged_members_are_refused_and_rerun() {
    let good = tmp("damage-good");
    let (code, _, err) = grainchain(&["study", "studies/smoke.toml", "--out", s(&good)]);
    assert_eq!(code, Some(0), "{err}");
    let csv = |d: &Path, stem: &str| d.join("members").join(format!("{stem}.csv"));
    type Damage = fn(&Path);
    let cases: [(&str, &str, Damage, &str); 9] = [
        // Issue 38, item 4: the bookkeeping edited by hand (its initial energy halved) changed
        // every table of the merge, exit 0; it carries a checksum of its own now.
        (
            "json-edited",
            "c-m2",
            |p| {
                let meta = p.with_extension("json");
                let mut v: serde_json::Value =
                    serde_json::from_str(&std::fs::read_to_string(&meta).unwrap()).unwrap();
                v["initial_energy"] = (v["initial_energy"].as_f64().unwrap() / 2.0).into();
                std::fs::write(&meta, serde_json::to_string_pretty(&v).unwrap()).unwrap();
            },
            "do not match the checksum it records",
        ),
        (
            "cut",
            "a-m1",
            |p| {
                let t = std::fs::read_to_string(p).unwrap();
                let head: Vec<&str> = t.lines().take(150).collect();
                std::fs::write(p, head.join("\n") + "\n").unwrap();
            },
            "do not match the checksum",
        ),
        (
            "nan",
            "c-m0",
            |p| {
                let t = std::fs::read_to_string(p).unwrap();
                let mut lines: Vec<String> = t.lines().map(String::from).collect();
                let cells: Vec<&str> = lines[6].split(',').collect();
                lines[6] = format!("{},NaN,{}", cells[0], cells[2..].join(","));
                std::fs::write(p, lines.join("\n") + "\n").unwrap();
            },
            "do not match the checksum",
        ),
        (
            "nojson",
            "r-002-m1",
            |p| {
                std::fs::remove_file(p.with_extension("json")).unwrap();
            },
            "its bookkeeping",
        ),
        (
            "digit",
            "a-m2",
            |p| {
                let t = std::fs::read_to_string(p).unwrap();
                let i = t.rfind(|c: char| c.is_ascii_digit() && c != '0').unwrap();
                let mut b = t.into_bytes();
                b[i] = if b[i] == b'1' { b'2' } else { b'1' };
                std::fs::write(p, b).unwrap();
            },
            "do not match the checksum",
        ),
        // Damage that a buggy writer could have signed itself: the checksum and row count in the
        // JSON updated to match, so only the content checks can catch it.
        (
            "nan-signed",
            "c-m1",
            |p| {
                let t = std::fs::read_to_string(p).unwrap();
                let mut lines: Vec<String> = t.lines().map(String::from).collect();
                let cells: Vec<&str> = lines[9].split(',').collect();
                lines[9] = format!("{},NaN,{}", cells[0], cells[2..].join(","));
                resign(p, &(lines.join("\n") + "\n"));
            },
            "row 10: column `container` is NaN, not a finite number",
        ),
        (
            "cut-signed",
            "r-001-m0",
            |p| {
                let t = std::fs::read_to_string(p).unwrap();
                let head: Vec<&str> = t.lines().take(150).collect();
                resign(p, &(head.join("\n") + "\n"));
            },
            "149 rows; its bookkeeping says 149 and the batch expects 301",
        ),
        // The budget's sections are sampled (`study::budget_outputs`): snapshot 9 is on the
        // schedule and must hold a number; snapshot 106 is not (101 ... 105, 107 are) and must
        // be empty.
        (
            "gap-signed",
            "a-m0",
            |p| {
                let t = std::fs::read_to_string(p).unwrap();
                let mut lines: Vec<String> = t.lines().map(String::from).collect();
                let cells: Vec<&str> = lines[10].split(',').collect();
                lines[10] = format!("{},{},,{}", cells[0], cells[1], cells[3..].join(","));
                resign(p, &(lines.join("\n") + "\n"));
            },
            "row 11: column `outer-left` is empty at snapshot 9, where it must hold a number",
        ),
        (
            "filled-signed",
            "r-003-m1",
            |p| {
                let t = std::fs::read_to_string(p).unwrap();
                let mut lines: Vec<String> = t.lines().map(String::from).collect();
                let cells: Vec<&str> = lines[107].split(',').collect();
                assert_eq!(cells[0], "106");
                lines[107] = format!("{},{},0.5,{}", cells[0], cells[1], cells[3..].join(","));
                resign(p, &(lines.join("\n") + "\n"));
            },
            "row 108: column `outer-left` is sampled and holds no value at snapshot 106, found `0.5`",
        ),
    ];
    for (name, stem, damage, says) in cases {
        let d = tmp(&format!("damage-{name}"));
        copy_members(&good, &d);
        damage(&csv(&d, stem));
        let (code, _, err) =
            grainchain(&["study", "studies/smoke.toml", "--merge", "--out", s(&d)]);
        assert_eq!(code, Some(2), "{name}: {err}");
        assert!(
            err.contains(&format!("{stem}.")) && err.contains("damaged member"),
            "{name}: {err}"
        );
        assert!(err.contains(says), "{name}: {err}");
        if name == "nojson" {
            // A CSV without its bookkeeping, gathered by hand (no record of it in this folder),
            // cannot be told from a user's file named like a member (issue 38): `--resume`
            // refuses to replace it, and runs the member once it is moved away.
            let (code, _, err) =
                grainchain(&["study", "studies/smoke.toml", "--resume", "--out", s(&d)]);
            assert_eq!(code, Some(2), "{name}: {err}");
            assert!(
                err.contains(&format!("members/{stem}.csv is in the way")),
                "{err}"
            );
            std::fs::remove_file(csv(&d, stem)).unwrap();
        }
        let (code, out, err) =
            grainchain(&["study", "studies/smoke.toml", "--resume", "--out", s(&d)]);
        assert_eq!(code, Some(0), "{name}: {err}");
        // (The CSV moved away above is a missing member, not one run again.)
        assert!(
            (out.contains("ran again") || name == "nojson") && out.contains("ran 1 of 12"),
            "{name}: {out}"
        );
        for f in ["ensemble.csv", "fits.csv", "alpha.csv", "random.csv"] {
            assert!(
                std::fs::read(good.join(f)).unwrap() == std::fs::read(d.join(f)).unwrap(),
                "{name}: {f} differs from the undamaged study after --resume"
            );
        }
        let _ = std::fs::remove_dir_all(&d);
    }
    let _ = std::fs::remove_dir_all(&good);
}

/// The run digest is of the parsed scene and sweep: a comment or a respelled number in a scene
/// file keeps it; a changed value or another build changes it, and a member of another build is
/// refused naming the build.
#[test]
fn digest_is_of_what_matters() {
    let d = tmp("digest");
    std::fs::create_dir_all(d.join("scenes")).unwrap();
    let scene =
        std::fs::read_to_string(Path::new(ROOT).join("scenes/containers/a-standard.toml")).unwrap();
    let sweep = |dir: &Path, text: &str| {
        std::fs::write(dir.join("scenes/a.toml"), text).unwrap();
        std::fs::write(
            dir.join("sweep.toml"),
            "name = \"d\"\nsnapshots = 40\nmembers = 1\nperturbation = { kind = \"striker-speed\", epsilon = 1e-12 }\n\
             outer_chains = 300\n[[containers]]\nkey = \"a\"\nscene = \"scenes/a.toml\"\n",
        )
        .unwrap();
        SweepFile::load(dir.join("sweep.toml")).unwrap()
    };
    let base = sweep(&d, &scene);
    let commented = sweep(
        &d,
        &format!("# a comment added to the scene\n{scene}\n# and one at the end\n"),
    );
    assert_eq!(
        base.digest, commented.digest,
        "a comment changed the digest"
    );
    let changed = sweep(&d, &scene.replacen("eta = 5657.0", "eta = 5658.0", 1));
    assert!(scene.contains("eta = 5657.0"));
    assert_ne!(
        base.digest, changed.digest,
        "a changed stiffness kept the digest"
    );

    // A member written by another build: refused with the build named.
    let out = tmp("digest-run");
    let sweep_path = d.join("sweep.toml");
    sweep(&d, &scene);
    let (code, _, err) = grainchain(&["study", s(&sweep_path), "--out", s(&out)]);
    assert_eq!(code, Some(0), "{err}");
    let meta = out.join("members/a-m0.json");
    let text = std::fs::read_to_string(&meta).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let this_build = v["program"].clone();
    v["program"] = "grainchain 0.0.1 (git 0123456789ab)".into();
    v["sweep"] = "0000000000000000".into();
    std::fs::write(&meta, v.to_string()).unwrap();
    let (code, _, err) = grainchain(&["study", s(&sweep_path), "--merge", "--out", s(&out)]);
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("written by grainchain 0.0.1 (git 0123456789ab), this is grainchain"),
        "{err}"
    );
    // The same with only a setting changed: the difference is named.
    v["program"] = this_build;
    v["settings"]["snapshots"] = 400.into();
    std::fs::write(&meta, v.to_string()).unwrap();
    let (code, _, err) = grainchain(&["study", s(&sweep_path), "--merge", "--out", s(&out)]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("`snapshots` is 400 there, 40 here"), "{err}");
    let _ = std::fs::remove_dir_all(&d);
    let _ = std::fs::remove_dir_all(&out);
}

/// Issue 24, items 9 and 11: a container with restitution 0.05 at every contact, 300 snapshots:
/// its E_R is still rising at the end, so there is no leak onset and no decay to fit. The study
/// printed "gamma of the mean over [30, 300]: -79.201"; now it gives no gamma and says why, on
/// the command line, in STUDY.md (no NaN anywhere) and in fits.csv (an empty cell and a note).
/// The same run asks for 100000 threads and says how many ran (one per job at most), and a
/// `--resume` that runs nothing says "0.0 s of member time" (it said -0.0: an empty sum of
/// floats).
#[test]
fn a_study_still_rising_gives_no_gamma_and_says_why() {
    let dir = tmp("rising");
    std::fs::create_dir_all(&dir).unwrap();
    let sweep = dir.join("rising.toml");
    std::fs::write(
        &sweep,
        format!(
            "name = \"rising\"\nsnapshots = 300\nmembers = 2\n\
             perturbation = {{ kind = \"striker-speed\", epsilon = 1e-12 }}\n\
             outer_chains = 600\n\n[[containers]]\nkey = \"a\"\nscene = \"{}\"\n\
             dissipation = {{ model = \"scale-respecting\", restitution = 0.05 }}\n",
            Path::new(ROOT)
                .join("scenes/containers/a-standard.toml")
                .display()
        ),
    )
    .unwrap();
    let out = dir.join("out");
    let (code, stdout, stderr) =
        grainchain(&["study", s(&sweep), "--out", s(&out), "--threads", "100000"]);
    assert_eq!(code, Some(0), "{stderr}");
    assert!(!stdout.contains("gamma of the mean over"), "{stdout}");
    assert!(
        stdout.contains("(a) no gamma of the mean: no leak onset"),
        "{stdout}"
    );
    assert!(stdout.contains(" on 2 threads "), "{stdout}");
    let md = std::fs::read_to_string(out.join("STUDY.md")).unwrap();
    assert!(!md.contains("NaN"), "{md}");
    assert!(
        md.contains("| a | [30, 300] | n/a (no leak onset: E_R has not fallen to half its peak"),
        "{md}"
    );
    let fits = std::fs::read_to_string(out.join("fits.csv")).unwrap();
    let mean = fits.lines().find(|l| l.starts_with("a,mean,")).unwrap();
    assert!(
        mean.starts_with("a,mean,30,300,,,,,0,\"no leak onset"),
        "{mean}"
    );
    // No decade either (they started at snapshot 100 without an onset: search.csv's
    // gamma_a_decades printed -477.35 from such a window).
    assert!(!fits.contains("a,decade,"), "{fits}");
    // Item 11: the member files hold tiny energies (below 1e-20: the container's energy drains
    // away through the dashpots) in exponent form, not as ~170-character decimals; the merge
    // above read them back (`read_member`: checksum, row count, finite numbers; the round trip
    // bit for bit is `batch::members::tests`).
    let (mut longest, mut tiny) = (0, 0);
    for m in ["a-m0.csv", "a-m1.csv"] {
        let text = std::fs::read_to_string(out.join("members").join(m)).unwrap();
        for cell in text.lines().skip(1).flat_map(|l| l.split(',').skip(1)) {
            longest = longest.max(cell.len());
            let x: f64 = cell.parse().unwrap_or(0.0);
            tiny += usize::from(x != 0.0 && x.abs() < 1e-20);
        }
    }
    assert!(tiny > 0, "no tiny energies: the check below tests nothing");
    // The shortest round trip in exponent form: at most 17 digits, sign, point, e-324.
    assert!(longest <= 25, "a member-file cell of {longest} characters");
    // Nothing left to run.
    let (code, stdout, stderr) = grainchain(&["study", s(&sweep), "--out", s(&out), "--resume"]);
    assert_eq!(code, Some(0), "{stderr}");
    assert!(stdout.contains("(0.0 s of member time)"), "{stdout}");
    let _ = std::fs::remove_dir_all(&dir);
}
