//! `grainchain design`: the search finds the optimum of a design space small enough to brute
//! force, the same seed gives the same result on 1 and 2 threads, an interrupted search resumes
//! from its journal, and bad design files are refused with their file and key.

use crate::common::{grainchain, record_one, s, Row};
use grainchain::design::file::{DesignFile, DesignSpec};
use grainchain::design::search;
use std::path::PathBuf;
use std::sync::Arc;

/// Four sections of two beads, steel or PTFE (6 mm): 16 designs.
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

fn problem(text: &str) -> DesignSpec {
    let file: DesignFile = toml::from_str(text).unwrap();
    DesignSpec::check(PathBuf::from("small.toml"), file).unwrap()
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("grainchain-design-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn search(
    p: &DesignSpec,
    threads: usize,
    journal: &std::path::Path,
    resume: bool,
) -> search::Outcome {
    search::run(
        p,
        p.file.search.seed,
        threads,
        journal,
        resume,
        &p.digest,
        search::Tick(Arc::new(|| {})),
    )
    .unwrap()
}

/// The genetic algorithm finds the best of 16 designs, all of which the test evaluates itself.
#[test]
fn the_search_finds_the_brute_force_optimum() {
    let p = problem(SMALL);
    let reference = search::reference(&p).unwrap();
    let mut best: Option<search::Scored> = None;
    for code in 0..16usize {
        let genes: Vec<usize> = (0..4).map(|k| (code >> k) & 1).collect();
        let s = search::score(&p, &genes, &reference).unwrap();
        if best.as_ref().is_none_or(|b| s.objective < b.objective) {
            best = Some(s);
        }
    }
    let best = best.unwrap();
    let dir = tmp("optimum");
    let found = search(&p, 1, &dir.join("island.csv"), false);
    let ok = record_one(
        Row::new(
            "search finds the optimum",
            "8 beads in 4 sections of steel or PTFE (16 designs), steel wall, 1 m/s",
            "every design evaluated by the test (brute force)",
        )
        .expected(format!("{:?}, objective {:.6}", best.genes, best.objective))
        .measured(format!(
            "{:?}, objective {:.6}, after {} evaluations",
            found.all[0].genes, found.all[0].objective, found.evaluated
        ))
        .tolerance("the same design")
        .pass(found.all[0].genes == best.genes),
    );
    assert!(ok, "found {:?}, brute force {:?}", found.all[0], best);
}

/// The same seed gives the same designs and numbers on 1 and 2 threads, and a search resumed
/// from a journal cut mid-line gives the same result running only what the journal lacked.
#[test]
fn the_same_seed_gives_the_same_search_and_a_resume_repeats_nothing() {
    let p = problem(&SMALL.replace("beads = 8\nsections = 4", "beads = 12\nsections = 6"));
    let dir = tmp("seed");
    let one = search(&p, 1, &dir.join("one.csv"), false);
    let two = search(&p, 2, &dir.join("two.csv"), false);
    assert_eq!(one.all, two.all);
    assert_eq!(one.convergence, two.convergence);
    // Every design is run and journaled once at every thread count: the same count and the same
    // lines, in the order the threads finished them (two threads asking for one new design ran it
    // twice and journaled it twice, a count that depended on the race).
    assert_eq!(one.evaluated, two.evaluated);
    let lines = |f: &str| {
        let text = std::fs::read_to_string(dir.join(f)).unwrap();
        let mut v: Vec<String> = text.lines().map(str::to_string).collect();
        v.sort();
        v
    };
    assert_eq!(lines("one.csv"), lines("two.csv"));
    // Cut the journal after half its lines, mid-line, as an interrupted run leaves it.
    let text = std::fs::read_to_string(dir.join("one.csv")).unwrap();
    let keep: Vec<&str> = text.lines().collect();
    let half = keep.len() / 2;
    let mut cut = keep[..half].join("\n");
    cut.push('\n');
    cut.push_str(&keep[half][..keep[half].len() / 2]);
    std::fs::write(dir.join("one.csv"), cut).unwrap();
    let resumed = search(&p, 1, &dir.join("one.csv"), true);
    assert_eq!(resumed.all, one.all);
    let kept = half - 2; // the digest and header lines
    assert_eq!(resumed.evaluated as usize, one.all.len() - kept);
}

/// Giving up keeps the best design and the Pareto front: every design the search gave up on
/// (its journal line a lower bound), run again to the cap, is matched or beaten by a design no
/// heavier that the search knows exactly, so the best and the front of objective against mass
/// are the same with its exact numbers in place of the bounds.
#[test]
fn giving_up_keeps_the_best_and_the_front() {
    // 12 beads in 6 sections of steel, PTFE or brass at 4 or 6 mm (729 designs), no heavier
    // than the steel column: a space with a front, where most designs lose.
    let text = SMALL
        .replace("beads = 8\nsections = 4", "beads = 12\nsections = 6")
        .replace(r#"["steel", "ptfe"]"#, r#"["steel", "ptfe", "brass"]"#)
        .replace(
            "diameters = [0.006]",
            "diameters = [0.006, 0.004]\n\n[constraints]\nmax_mass = 0.0107",
        )
        .replace("population = 8", "population = 24");
    let p = problem(&text);
    assert!(p.file.search.give_up, "giving up is the default");
    let dir = tmp("give-up");
    let found = search(&p, 2, &dir.join("island.csv"), false);
    let reference = search::reference(&p).unwrap();
    let mut exact = found.all.clone();
    let mut checked = 0;
    for s in exact.iter_mut().filter(|s| s.given_up) {
        let e = search::score(&p, &s.genes, &reference).unwrap();
        assert!(!e.given_up && e.objective >= s.objective, "{e:?} vs {s:?}");
        *s = e;
        checked += 1;
    }
    exact.sort_by(|a, b| {
        a.objective
            .total_cmp(&b.objective)
            .then(a.genes.cmp(&b.genes))
    });
    let genes = |v: Vec<&search::Scored>| v.iter().map(|s| s.genes.clone()).collect::<Vec<_>>();
    let front_bounds = genes(search::pareto(&found.all));
    let front_exact = genes(search::pareto(&exact));
    let ok = record_one(
        Row::new(
            "search: giving up keeps the best and the front",
            "12 beads in 6 sections, 3 materials x 2 sizes, a mass limit; population 24",
            "the designs given up on, each run again to the search's cap",
        )
        .expected("the same best design and Pareto front")
        .measured(format!(
            "{checked} of {} designs given up; best {:?} / {:?}; front {} / {} designs",
            found.all.len(),
            found.all[0].genes,
            exact[0].genes,
            front_bounds.len(),
            front_exact.len()
        ))
        .tolerance("the same designs")
        .pass(found.all[0].genes == exact[0].genes && front_bounds == front_exact),
    );
    assert!(ok, "front {front_bounds:?} vs {front_exact:?}");
    // Not vacuous: most designs of this space lose to one the search already has.
    assert!(checked >= 20, "only {checked} designs given up");
}

/// Bad design files: the CLI names the file and the key and exits with 2.
#[test]
fn bad_design_files_name_their_key() {
    let dir = tmp("bad");
    let cases = [
        (
            "beads = 8\nsections = 4",
            "beads = 8\nsections = 3",
            "space.sections",
        ),
        (
            "materials = [\"steel\", \"ptfe\"]",
            "materials = [\"steel\", \"cheese\"]",
            "space.materials[1]",
        ),
        (
            "diameters = [0.006]",
            "diameters = [-0.006]",
            "space.diameters[0]",
        ),
        ("speeds = [1.0]", "speeds = []", "load.speeds"),
        (
            "speeds = [1.0]",
            "speeds = [1.0]\nrestitution = 1.5",
            "load.restitution",
        ),
        // Restitution by pair of materials: a material no contact is made of, a coefficient
        // out of range, a pair given twice (in either order), and the gradients' tables with a
        // damped pair.
        (
            "speeds = [1.0]",
            "speeds = [1.0]\nrestitution_pairs = [{ between = [\"steel\", \"glass\"], restitution = 0.9 }]",
            "load.restitution_pairs[0].between[1]",
        ),
        (
            "speeds = [1.0]",
            "speeds = [1.0]\nrestitution_pairs = [{ between = [\"steel\", \"ptfe\"], restitution = 0.01 }]",
            "load.restitution_pairs[0].restitution",
        ),
        (
            "speeds = [1.0]",
            "speeds = [1.0]\nrestitution_pairs = [{ between = [\"steel\", \"ptfe\"], restitution = 0.9 }, \
             { between = [\"ptfe\", \"steel\"], restitution = 0.8 }]",
            "load.restitution_pairs[1]",
        ),
        (
            "speeds = [1.0]",
            "speeds = [1.0]\nrestitution_pairs = [{ between = [\"steel\"], restitution = 0.9 }]",
            "key `load.restitution_pairs` (line 11, column 34): invalid length 1, expected an array of length 2",
        ),
        (
            "speeds = [1.0]",
            "speeds = [1.0]\nrestitution_pairs = [{ between = [\"steel\", \"ptfe\"], restitution = 0.9 }]\n\
             [refine]\ndiameters = [0.004, 0.008]",
            "key `refine`",
        ),
        ("population = 8", "population = 2", "search.population"),
        // `[search] accuracy`: outside [1e-9, 1e-2], not finite, not a number.
        ("seed = 3", "seed = 3\naccuracy = 0.0", "search.accuracy"),
        ("seed = 3", "seed = 3\naccuracy = 0.1", "search.accuracy"),
        ("seed = 3", "seed = 3\naccuracy = 1e-10", "search.accuracy"),
        ("seed = 3", "seed = 3\naccuracy = -1e-5", "search.accuracy"),
        ("seed = 3", "seed = 3\naccuracy = nan", "search.accuracy"),
        ("seed = 3", "seed = 3\naccuracy = inf", "search.accuracy"),
        ("seed = 3", "seed = 3\naccuracy = \"fine\"", "accuracy"),
        ("seed = 3", "seed = 3\ncolour = 1", "unknown field `colour`"),
        // Issue 50, item 6: an impact energy that rounds to 0 or overflows in doubles blames
        // the speed (it said "up to NaN steps" of the beads and exited 1), a target too light
        // its mass, `[[tolerances]]` says to write one table, a third refinement bound is
        // refused (it was dropped), and an objective [refine] cannot follow blames the objective.
        ("speeds = [1.0]", "speeds = [1e-200]", "load.speeds[0]"),
        ("speeds = [1.0]", "speeds = [1.0, 1e200]", "load.speeds[1]"),
        (
            "speeds = [1.0]",
            "speeds = [1.0]\ntarget = { mass = 1e-300, material = \"steel\" }",
            "load.target.mass",
        ),
        (
            "stale = 12",
            "stale = 12\n[[tolerances]]\ndiameter = 0.01",
            "write `[tolerances]`",
        ),
        (
            "stale = 12",
            "stale = 12\n[refine]\ndiameters = [0.004, 0.006, 0.008]",
            "refine.diameters",
        ),
        (
            "stale = 12",
            "stale = 12\n[objective]\nminimize = \"duration\"\n[refine]\ndiameters = [0.004, 0.008]",
            "objective.minimize",
        ),
    ];
    for (from, to, key) in cases {
        let path = dir.join("bad.toml");
        std::fs::write(&path, SMALL.replace(from, to)).unwrap();
        let out = dir.join("out");
        let (code, _, err) = grainchain(&[
            "design",
            path.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        assert_eq!(code, Some(2), "{to}: {err}");
        assert!(err.contains("bad.toml") && err.contains(key), "{to}: {err}");
        assert!(!out.join("DESIGN.md").exists());
    }
}

/// Issue 50, item 6: under a file-size limit (`ulimit -f`) a design died by SIGXFSZ with no
/// message and left a `.partial` file; now the write fails with a message naming the file and
/// exits 1, and nothing partial is left.
#[cfg(unix)]
#[test]
fn a_file_size_limit_is_an_error_with_a_message() {
    let dir = tmp("fsize");
    let file = dir.join("small.toml");
    std::fs::write(&file, SMALL).unwrap();
    let out = dir.join("out");
    let bin = env!("CARGO_BIN_EXE_grainchain");
    // 8 blocks of 512 bytes: the journal outgrows it.
    let o = std::process::Command::new("sh")
        .arg("-c")
        .arg(format!(
            "ulimit -f 8 && exec '{bin}' design '{}' --out '{}'",
            file.display(),
            out.display()
        ))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("File too large") && err.contains("out"),
        "{err}"
    );
    let partial = walk(&out)
        .into_iter()
        .filter(|p| p.to_string_lossy().contains("partial"))
        .collect::<Vec<_>>();
    assert!(partial.is_empty(), "{partial:?}");
}

/// Every file under `dir`.
fn walk(dir: &std::path::Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).into_iter().flatten().flatten() {
        let p = e.path();
        if p.is_dir() {
            out.extend(walk(&p));
        } else {
            out.push(p);
        }
    }
    out
}

/// Islands: two shards of a small search, each keeping only its journal, then `--merge` writes
/// the outputs from both journals; a merge without journals is refused; the best design is a
/// scene that checks.
#[test]
fn islands_merge_into_one_set_of_outputs() {
    let dir = tmp("islands");
    let file = dir.join("small.toml");
    std::fs::write(&file, SMALL).unwrap();
    let out = dir.join("out");
    let (f, o) = (file.to_str().unwrap(), out.to_str().unwrap());
    let (code, _, err) = grainchain(&["design", f, "--out", o, "--merge"]);
    assert_eq!(code, Some(1), "a merge with no journal: {err}");
    assert!(err.contains("no evaluations"), "{err}");
    for k in ["1/2", "2/2"] {
        let (code, _, err) = grainchain(&["design", f, "--out", o, "--shard", k, "--threads", "1"]);
        assert_eq!(code, Some(0), "shard {k}: {err}");
    }
    assert!(!out.join("DESIGN.md").exists(), "a shard writes no outputs");
    let journals = |k: usize| {
        let text =
            std::fs::read_to_string(out.join("evaluations").join(format!("island-{k}-of-2.csv")))
                .unwrap();
        text.lines().skip(2).map(str::to_string).collect::<Vec<_>>()
    };
    let (one, two) = (journals(1), journals(2));
    assert!(!one.is_empty() && !two.is_empty());
    let (code, _, err) = grainchain(&["design", f, "--out", o, "--merge", "--threads", "1"]);
    assert_eq!(code, Some(0), "merge: {err}");
    let designs = std::fs::read_to_string(out.join("designs.csv")).unwrap();
    let mut union: Vec<&str> = one
        .iter()
        .chain(&two)
        .map(|l| l.split(',').next().unwrap())
        .collect();
    union.sort();
    union.dedup();
    // Every valid design of either island is ranked once (all 16 designs here are valid).
    assert_eq!(designs.lines().count() - 1, union.len(), "{designs}");
    let (code, _, err) = grainchain(&["check", out.join("best.toml").to_str().unwrap()]);
    assert_eq!(code, Some(0), "best.toml: {err}");
}

/// Issue 38, item 5: `design --threads 1000` on a small search started 1000 threads (14 s
/// against 0.7 s on 2); `study` capped its threads, `design` did not. Now every pool takes
/// `worker_threads`: at most one per job and what the machine runs at once, and `design` says
/// how many it ran on.
#[test]
fn design_threads_are_capped_like_every_pool() {
    let machine = std::thread::available_parallelism().map_or(1, |n| n.get());
    assert_eq!(grainchain_engine::worker_threads(0, 5), 1);
    assert_eq!(grainchain_engine::worker_threads(1000, 4), 4.min(machine));
    assert_eq!(grainchain_engine::worker_threads(1000, 0), 1);
    assert_eq!(
        grainchain_engine::worker_threads(usize::MAX, usize::MAX),
        machine
    );
    let dir = tmp("threads");
    let file = dir.join("small.toml");
    std::fs::write(&file, SMALL.replace("population = 8", "population = 4")).unwrap();
    let out = dir.join("out");
    let (f, o) = (file.to_str().unwrap(), out.to_str().unwrap());
    let (code, _, err) = grainchain(&["design", f, "--out", o, "--threads", "1000"]);
    assert_eq!(code, Some(0), "{err}");
    let said = format!(" on {} threads;", 4.min(machine));
    assert!(err.contains(&said), "expected `{said}` in: {err}");
    let _ = std::fs::remove_dir_all(&dir);
}

// Issue 38, item 4: the files a design's `--merge` and `--resume` read (every island's journal,
// its convergence file, the set of islands) are checked, and damage is refused by file and line.

/// A folder holding SMALL as `small.toml`: the design file and the output folder `out` in it.
fn design_folder(name: &str) -> (PathBuf, PathBuf) {
    let dir = tmp(name);
    let file = dir.join("small.toml");
    std::fs::write(&file, SMALL).unwrap();
    (file, dir.join("out"))
}

/// `grainchain design FILE --out OUT ARGS --threads 1`: its exit code and stderr.
fn design(file: &std::path::Path, out: &std::path::Path, args: &[&str]) -> (Option<i32>, String) {
    let mut all = vec![s(file), "--out", s(out), "--threads", "1"];
    all.extend(args);
    all.insert(0, "design");
    let (code, _, err) = grainchain(&all);
    (code, err)
}

/// Island `k` of `n`'s journal in `out`.
fn journal(out: &std::path::Path, k: usize, n: usize) -> PathBuf {
    out.join("evaluations")
        .join(format!("island-{k}-of-{n}.csv"))
}

/// Lines of a file without their line ends.
fn lines(path: &std::path::Path) -> Vec<String> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .map(String::from)
        .collect()
}

/// Lines written back, each with its line end.
fn write_lines(path: &std::path::Path, lines: &[String]) {
    std::fs::write(
        path,
        lines.iter().map(|l| format!("{l}\n")).collect::<String>(),
    )
    .unwrap();
}

/// A line cut inside the journal (line 5 cut to half, the lines after it whole) was merged with
/// that line dropped, exit 0. Only an interruption cuts a line, and only the last: the cut line
/// is refused by `--merge` and `--resume`, naming the file and the line. A cut last line (the
/// island interrupted) is refused by `--merge` too (the island has not finished), and dropped
/// and run again by `--resume`, after which the merge is that of the undamaged islands.
#[test]
fn a_journal_line_cut_inside_the_file_is_refused() {
    let (f, o) = design_folder("cut-line");
    for k in ["1/2", "2/2"] {
        let (code, err) = design(&f, &o, &["--shard", k]);
        assert_eq!(code, Some(0), "shard {k}: {err}");
    }
    let (code, err) = design(&f, &o, &["--merge"]);
    assert_eq!(code, Some(0), "{err}");
    let good = std::fs::read(o.join("designs.csv")).unwrap();
    let path = journal(&o, 1, 2);
    let whole = lines(&path);
    assert!(whole.len() > 6, "{whole:?}");
    let mut cut = whole.clone();
    cut[4].truncate(whole[4].len() / 2);
    write_lines(&path, &cut);
    let (code, err) = design(&f, &o, &["--merge"]);
    assert_eq!(code, Some(2), "a line cut inside the journal: {err}");
    assert!(err.contains("island-1-of-2.csv: line 5:"), "{err}");
    let (code, err) = design(&f, &o, &["--shard", "1/2", "--resume"]);
    assert_eq!(
        code,
        Some(2),
        "--resume of a line cut inside the journal: {err}"
    );
    assert!(err.contains("island-1-of-2.csv: line 5:"), "{err}");
    // The last line cut, as an interruption leaves it (no line end).
    let last = whole.len() - 1;
    let text = whole[..last].join("\n") + "\n" + &whole[last][..whole[last].len() / 2];
    std::fs::write(&path, text).unwrap();
    let (code, err) = design(&f, &o, &["--merge"]);
    assert_eq!(code, Some(2), "a merge of an interrupted island: {err}");
    assert!(
        err.contains(&format!("island-1-of-2.csv: line {}:", last + 1))
            && err.contains("--shard 1/2 --resume"),
        "{err}"
    );
    let (code, err) = design(&f, &o, &["--shard", "1/2", "--resume"]);
    assert_eq!(code, Some(0), "--resume drops the cut last line: {err}");
    let (code, err) = design(&f, &o, &["--merge"]);
    assert_eq!(code, Some(0), "{err}");
    assert!(std::fs::read(o.join("designs.csv")).unwrap() == good);
    let _ = std::fs::remove_dir_all(o.parent().unwrap());
}

/// A journal line whose objective was edited by hand (0.001, better than any design) was
/// crowned the best design, exit 0. Every line carries its own checksum now: the edited line is
/// refused by `--merge` and `--resume`, naming the file and the line.
#[test]
fn a_hand_edited_objective_is_refused() {
    let (f, o) = design_folder("edited");
    let (code, err) = design(&f, &o, &[]);
    assert_eq!(code, Some(0), "{err}");
    let path = journal(&o, 1, 1);
    let mut edited = lines(&path);
    let n = edited.len();
    let mut cells: Vec<String> = edited[n - 1].split(',').map(String::from).collect();
    cells[1] = "0.001".into();
    edited[n - 1] = cells.join(",");
    write_lines(&path, &edited);
    for args in [&["--merge"][..], &["--resume"][..]] {
        let (code, err) = design(&f, &o, args);
        assert_eq!(code, Some(2), "{args:?}: {err}");
        assert!(
            err.contains(&format!("island-1-of-1.csv: line {n}:")) && err.contains("checksum"),
            "{args:?}: {err}"
        );
    }
    let _ = std::fs::remove_dir_all(o.parent().unwrap());
}

/// One byte that is not UTF-8 in a journal line hid the whole journal (read as text): the merge
/// said "no evaluations ... run the search first". The journal is read as bytes now, and the
/// line is refused by `--merge` and `--resume`, naming the file and the line.
#[test]
fn a_non_utf8_journal_line_is_refused() {
    let (f, o) = design_folder("utf8");
    let (code, err) = design(&f, &o, &[]);
    assert_eq!(code, Some(0), "{err}");
    let path = journal(&o, 1, 1);
    let mut bytes = std::fs::read(&path).unwrap();
    // The first byte of line 4 (after three line ends).
    let at = bytes
        .iter()
        .enumerate()
        .filter(|(_, b)| **b == b'\n')
        .nth(2)
        .unwrap()
        .0
        + 1;
    bytes[at] = 0xff;
    std::fs::write(&path, bytes).unwrap();
    for args in [&["--merge"][..], &["--resume"][..]] {
        let (code, err) = design(&f, &o, args);
        assert_eq!(code, Some(2), "{args:?}: {err}");
        assert!(
            err.contains("island-1-of-1.csv: line 4:") && err.contains("UTF-8"),
            "{args:?}: {err}"
        );
    }
    let _ = std::fs::remove_dir_all(o.parent().unwrap());
}

/// `--merge` with islands 2 and 3 of 3 never run succeeded, exit 0, from island 1 alone. A merge
/// needs every island 1..N of N, journal and convergence file (written when the island has
/// finished), of this design file: it refuses naming what is missing, and merges once the
/// islands have run.
#[test]
fn a_merge_needs_every_island() {
    let (f, o) = design_folder("islands-missing");
    let (code, err) = design(&f, &o, &["--shard", "1/3"]);
    assert_eq!(code, Some(0), "{err}");
    let (code, err) = design(&f, &o, &["--merge"]);
    assert_eq!(code, Some(1), "islands 2 and 3 missing: {err}");
    assert!(
        err.contains("island-2-of-3.csv")
            && err.contains("island-3-of-3.csv")
            && err.contains("--shard 2/3"),
        "{err}"
    );
    for k in ["2/3", "3/3"] {
        let (code, err) = design(&f, &o, &["--shard", k]);
        assert_eq!(code, Some(0), "shard {k}: {err}");
    }
    // Island 3 interrupted before it finished: a journal, no convergence file.
    let convergence = o.join("evaluations/island-3-of-3.convergence.csv");
    std::fs::remove_file(&convergence).unwrap();
    let (code, err) = design(&f, &o, &["--merge"]);
    assert_eq!(code, Some(1), "island 3 unfinished: {err}");
    assert!(
        err.contains("island-3-of-3.convergence.csv") && err.contains("--shard 3/3 --resume"),
        "{err}"
    );
    let (code, err) = design(&f, &o, &["--shard", "3/3", "--resume"]);
    assert_eq!(code, Some(0), "{err}");
    let (code, err) = design(&f, &o, &["--merge"]);
    assert_eq!(code, Some(0), "every island: {err}");
    // Island 2 of another design file (the folder taken over with --force, island 2's journal
    // left from the first file): not an island of this search.
    let other = o.parent().unwrap().join("other.toml");
    std::fs::write(&other, SMALL.replace("seed = 3", "seed = 4")).unwrap();
    for k in ["1/3", "3/3"] {
        let (code, err) = design(&other, &o, &["--shard", k, "--force"]);
        assert_eq!(code, Some(0), "shard {k}: {err}");
    }
    let (code, err) = design(&other, &o, &["--merge"]);
    assert_eq!(code, Some(2), "island 2 of another design file: {err}");
    assert!(
        err.contains("island-2-of-3.csv") && err.contains("another design file"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(o.parent().unwrap());
}

/// A journal is complete as its island left it: a whole line removed after the island finished
/// (the island's best design gone from the merge) was merged without it, exit 0, and so was a
/// convergence file edited by hand. The convergence file, written when the island finishes,
/// records the journal's evaluations and their checksum, and its own checksum: both changes are
/// refused, naming the file.
#[test]
fn a_journal_changed_after_its_island_finished_is_refused() {
    let (f, o) = design_folder("changed");
    for k in ["1/2", "2/2"] {
        let (code, err) = design(&f, &o, &["--shard", k]);
        assert_eq!(code, Some(0), "shard {k}: {err}");
    }
    let path = journal(&o, 2, 2);
    let whole = lines(&path);
    // The island's best design: the least objective (an empty objective is infinite).
    let objective = |l: &String| {
        l.split(',')
            .nth(1)
            .and_then(|x| x.parse::<f64>().ok())
            .unwrap_or(f64::INFINITY)
    };
    let best = (2..whole.len())
        .min_by(|&a, &b| objective(&whole[a]).total_cmp(&objective(&whole[b])))
        .unwrap();
    let mut fewer = whole.clone();
    fewer.remove(best);
    write_lines(&path, &fewer);
    let (code, err) = design(&f, &o, &["--merge"]);
    assert_eq!(code, Some(2), "a line removed: {err}");
    assert!(
        err.contains("island-2-of-2.csv") && err.contains("island-2-of-2.convergence.csv"),
        "{err}"
    );
    write_lines(&path, &whole);
    let convergence = o.join("evaluations/island-2-of-2.convergence.csv");
    let mut rows = lines(&convergence);
    let n = rows.len();
    let mut cells: Vec<String> = rows[n - 1].split(',').map(String::from).collect();
    cells[1] = "0.001".into();
    rows[n - 1] = cells.join(",");
    write_lines(&convergence, &rows);
    let (code, err) = design(&f, &o, &["--merge"]);
    assert_eq!(code, Some(2), "a convergence file edited: {err}");
    assert!(
        err.contains("island-2-of-2.convergence.csv") && err.contains("checksum"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(o.parent().unwrap());
}

/// A journal of an older grainchain (no checksum column, no record in its convergence file) is
/// refused by `--merge` and `--resume` with the advice to run the search again, never read
/// unchecked or dropped in silence.
#[test]
fn an_older_journal_is_refused_with_advice_to_rerun() {
    let (f, o) = design_folder("older");
    let (code, err) = design(&f, &o, &[]);
    assert_eq!(code, Some(0), "{err}");
    // The older format: the nine columns up to `given_up`, and the convergence file's digest
    // line, header and rows.
    let old = "genes,objective,peak_n,impulse_ns,duration_s,mass_kg,length_m,complete,given_up";
    let path = journal(&o, 1, 1);
    let mut text = lines(&path);
    let columns = text[1].split(',').count();
    for l in &mut text[1..] {
        let cells: Vec<&str> = l.split(',').collect();
        *l = cells[..9].join(",");
    }
    assert_eq!(text[1], old, "{columns} columns");
    write_lines(&path, &text);
    let convergence = o.join("evaluations/island-1-of-1.convergence.csv");
    let rows: Vec<String> = lines(&convergence)
        .into_iter()
        .filter(|l| !l.starts_with("# journal"))
        .collect();
    write_lines(&convergence, &rows);
    for args in [&["--merge"][..], &["--resume"][..]] {
        let (code, err) = design(&f, &o, args);
        assert_eq!(code, Some(2), "{args:?}: {err}");
        assert!(
            err.contains("island-1-of-1.csv")
                && err.contains("older grainchain")
                && err.contains("run the search again"),
            "{args:?}: {err}"
        );
    }
    let _ = std::fs::remove_dir_all(o.parent().unwrap());
}

/// `[search] accuracy` in the design file's checks: a fine accuracy whose finer runs would pass
/// the step limit is blamed on `search.accuracy` (the candidates pass at the default), with the
/// advice to ask for less; its default leaves the file's digest as it was before the key
/// existed (journals stay the file's).
#[test]
fn accuracy_is_checked_against_the_step_limit_and_keeps_the_default_digest() {
    // Steel and PTFE of 6 mm, 200 beads: the step bound of the reported (finer) runs at the
    // default accuracy is 2.9e6, below 1e8; at 1e-9 the steps are 40 times more: 1.15e8.
    let text = SMALL.replace("beads = 8\nsections = 4", "beads = 200\nsections = 8");
    let file: DesignFile =
        toml::from_str(&text.replace("seed = 3", "seed = 3\naccuracy = 1e-9")).unwrap();
    let err = DesignSpec::check(PathBuf::from("fine.toml"), file)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("fine.toml") && err.contains("search.accuracy") && err.contains("coarser"),
        "{err}"
    );
    let default = problem(&text);
    let explicit = problem(&text.replace("seed = 3", "seed = 3\naccuracy = 1e-5"));
    let other = problem(&text.replace("seed = 3", "seed = 3\naccuracy = 1e-6"));
    assert_eq!(default.digest, explicit.digest);
    assert_ne!(default.digest, other.digest);
    assert_eq!(search::settings(&default).steps_per_contact, 20.0);
    // 20 * 10^(2/5) = 50.2377: the search's step follows the key.
    let steps = search::settings(&other).steps_per_contact;
    assert!((steps - 50.237_728_6).abs() < 1e-6, "{steps}");
}

/// The outputs carry every reported number's error and bound flag: `designs.csv` and
/// `baselines.csv` have the columns (filled for the reported rows: errors of the peak finite
/// and >= 0, `bound` true or false), DESIGN.md writes `±`, and best.toml's `[design]` table
/// holds the best design's numbers, a scene that still checks.
#[test]
fn outputs_carry_errors_and_bounds() {
    let (file, out) = design_folder("errors");
    let (code, err) = design(&file, &out, &[]);
    assert_eq!(code, Some(0), "{err}");
    let read = |name: &str| std::fs::read_to_string(out.join(name)).unwrap();
    for (name, header, reported) in [
        ("designs.csv", grainchain::design::DESIGNS_HEADER, 10),
        (
            "baselines.csv",
            grainchain::design::BASELINES_HEADER,
            usize::MAX,
        ),
    ] {
        let text = read(name);
        assert_eq!(text.lines().next(), Some(header), "{name}");
        let columns: Vec<&str> = header.split(',').collect();
        let at = |c: &str| columns.iter().position(|x| *x == c).unwrap();
        let mut rows = 0;
        for record in csv::Reader::from_reader(text.as_bytes())
            .records()
            .take(reported)
        {
            let cells = record.unwrap();
            let line = format!("{cells:?}");
            assert_eq!(cells.len(), columns.len(), "{name}: {line}");
            let error: f64 = cells[at("peak_n_error")].parse().expect(&line);
            assert!(error.is_finite() && error >= 0.0, "{name}: {line}");
            assert!(["true", "false"].contains(&&cells[at("bound")]), "{line}");
            // The bound flag and `complete` say the same (a reported peak is a bound exactly
            // when a run reached its cap).
            assert_eq!(
                &cells[at("bound")] == "true",
                &cells[at("complete")] == "false"
            );
            rows += 1;
        }
        assert!(rows > 0, "{name}");
    }
    let md = read("DESIGN.md");
    assert!(md.contains(" ± "), "{md}");
    let best = read("best.toml");
    for key in [
        "[design]",
        "peak_force_error = ",
        "peak_bound = ",
        "steps_per_contact = 40.0",
    ] {
        assert!(best.contains(key), "{key}: {best}");
    }
    let (code, _, err) = grainchain(&["check", out.join("best.toml").to_str().unwrap()]);
    assert_eq!(code, Some(0), "best.toml: {err}");
}

/// Dissipation by pair of materials reaches every output: DESIGN.md says which contacts are
/// damped and how, and best.toml gives each contact of the best design its pair's restitution
/// (a run of equal beads whose joint differs is split in two sections, the striker, the wall
/// and the target have their own keys), so that `grainchain run best.toml` finds the design's
/// peak. The scene runs at a finer step than the design's reported run (its step is fitted to
/// the output interval), so the two differ by at most the reported run's error and the scene's,
/// which is smaller: twice the stated error bounds it. The test is sensitive: the same best.toml
/// with every contact at 0.9 gives a peak 19 % higher (8.78 N against 7.39 N, measured when
/// the test was written).
#[test]
fn dissipation_by_pair_reaches_best_toml() {
    let dir = tmp("pairs");
    let file = dir.join("pairs.toml");
    let pairs = "speeds = [1.0]\nrestitution = 0.9\nrestitution_pairs = [\
                 { between = [\"steel\", \"steel\"], restitution = 1.0 }, \
                 { between = [\"ptfe\", \"steel\"], restitution = 0.6 }]";
    std::fs::write(&file, SMALL.replace("speeds = [1.0]", pairs)).unwrap();
    let out = dir.join("out");
    let (code, err) = design(&file, &out, &[]);
    assert_eq!(code, Some(0), "{err}");
    let md = std::fs::read_to_string(out.join("DESIGN.md")).unwrap();
    assert!(
        md.contains(
            "Dissipation: every contact's coefficient of restitution is 0.9 but for these pairs' \
             own: steel on steel 1, ptfe on steel 0.6"
        ),
        "{md}"
    );
    let best = std::fs::read_to_string(out.join("best.toml")).unwrap();
    let value: toml::Value = toml::from_str(&best).unwrap();
    let number = |k: &str| value["design"][k].as_float().unwrap();
    let (peak, error) = (number("peak_force"), number("peak_force_error"));
    let run = dir.join("run");
    let (code, _, err) = grainchain(&["run", s(&out.join("best.toml")), "--out", s(&run)]);
    assert_eq!(code, Some(0), "{err}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("summary.json")).unwrap()).unwrap();
    let scene = summary["load"]["peak"].as_f64().unwrap();
    assert!(
        (scene - peak).abs() <= 2.0 * error,
        "best.toml's run {scene} N against the design's {peak} N ± {error}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
