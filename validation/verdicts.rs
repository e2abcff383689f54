//! `check` is the run's own validation (issue 24, items 5-7): for every bad scene and sweep file,
//! `check` (`study --check`) and `run` (`study`) give the same verdict, the same message, exit
//! code 2, and no output folder; errors name what the user wrote (the key, the grain numbers
//! of the file); and no integer key, at the largest value its TOML type allows, panics or
//! prints a wrapped number (the test profile has overflow checks on, so a wrap would panic).
//!
//! Every run here is refused before it simulates, or is a few milliseconds of simulation, so
//! the file stays fast.

use crate::common;

use common::{grainchain, record_one, s, Row};
use std::path::{Path, PathBuf};

/// The largest TOML integer (64-bit signed), as text.
const I64_MAX: &str = "9223372036854775807";
/// The smallest TOML integer.
const I64_MIN: &str = "-9223372036854775808";
/// The largest u64: above the TOML integer.
const U64_MAX: &str = "18446744073709551615";

fn tmp() -> tempfile::TempDir {
    tempfile::tempdir().expect("temp dir")
}

/// The `*.toml` files directly in `dir` (relative to the crate root), sorted.
fn files(dir: &str) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join(dir))
        .expect("read dir")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file() && p.extension().is_some_and(|x| x == "toml"))
        .map(|p| format!("{dir}/{}", p.file_name().unwrap().to_string_lossy()))
        .collect();
    v.sort();
    v
}

/// (exit code, stderr) of the check, the same of the run, and whether the run made its folder.
type Verdicts = ((Option<i32>, String), (Option<i32>, String), bool);

/// The verdict of `check` and of `run` (into a temp folder that must not be created) of a
/// scene file: (exit code, stderr) of each.
fn scene_verdicts(path: &str) -> Verdicts {
    let out = tmp();
    let dir = out.path().join("never-written");
    let (c, _, ce) = grainchain(&["check", path]);
    let (r, _, re) = grainchain(&["run", path, "--out", s(&dir)]);
    ((c, ce), (r, re), dir.exists())
}

/// The verdict of `study --check` and of `study` (into a temp folder).
fn sweep_verdicts(path: &str) -> Verdicts {
    let out = tmp();
    let dir = out.path().join("never-written");
    let (c, _, ce) = grainchain(&["study", path, "--check"]);
    let (r, _, re) = grainchain(&["study", path, "--out", s(&dir), "--threads", "1"]);
    ((c, ce), (r, re), dir.exists())
}

/// The verdict test: every file of validation/bad_scenes/ and validation/bad_sweeps/
/// (the bad inputs of items 5-7 among them) fails `check` and `run` alike: exit 2, one and the
/// same message, no output folder, no panic. None of them is a failure only a run can find
/// (a blow-up, say): such a file would be listed here with its reason.
#[test]
fn check_and_run_give_the_same_verdict() {
    let mut bad = Vec::new();
    let scenes = files("validation/bad_scenes");
    let sweeps = files("validation/bad_sweeps");
    assert!(
        scenes.len() >= 60 && sweeps.len() >= 25,
        "{scenes:?} {sweeps:?}"
    );
    for (kind, list) in [("scene", &scenes), ("sweep", &sweeps)] {
        for f in list {
            let ((c, ce), (r, re), made) = if kind == "scene" {
                scene_verdicts(f)
            } else {
                sweep_verdicts(f)
            };
            let ok = c == Some(2)
                && r == Some(2)
                && ce == re
                // The sweep, or the scene at fault (scene-damped-outer-multirate.toml).
                && ce.starts_with("error: validation/bad_s")
                && !made
                && !ce.contains("panicked")
                && !re.contains("panicked");
            if !ok {
                bad.push(format!(
                    "{f}: check exit {c:?} `{}`; run exit {r:?} `{}`; output folder made: {made}",
                    ce.trim(),
                    re.trim()
                ));
            }
        }
    }
    record_one(
        Row::new(
            "check and run: one verdict",
            format!("{} bad scenes, {} bad sweeps", scenes.len(), sweeps.len()),
            "validation/verdicts.rs",
        )
        .expected("exit 2 from both, the same message, no output folder")
        .measured(if bad.is_empty() {
            "all alike".to_string()
        } else {
            bad.join("; ")
        })
        .tolerance("exact text")
        .pass(bad.is_empty()),
    );
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}

/// Check and run of a scene give exit 2 with exactly `message` (after `error: <file>: `).
fn assert_scene_error(path: &str, message: &str) {
    let ((c, ce), (r, re), made) = scene_verdicts(path);
    let want = format!("error: {path}: {message}\n");
    assert_eq!((c, ce.as_str()), (Some(2), want.as_str()), "check {path}");
    assert_eq!((r, re.as_str()), (Some(2), want.as_str()), "run {path}");
    assert!(!made, "{path}: run made its output folder");
}

/// `study --check` and `study` of a sweep give exit 2 with exactly `message`.
fn assert_sweep_error(path: &str, message: &str) {
    let ((c, ce), (r, re), made) = sweep_verdicts(path);
    let want = format!("error: {path}: {message}\n");
    assert_eq!(
        (c, ce.as_str()),
        (Some(2), want.as_str()),
        "study --check {path}"
    );
    assert_eq!((r, re.as_str()), (Some(2), want.as_str()), "study {path}");
    assert!(!made, "{path}: the study made its output folder");
}

/// Item 5: the scene's own multirate beside a damped outer medium is blamed on `chain.outer`
/// (what the user wrote), naming the method, not on the generated layer's `contact_damping`.
#[test]
fn damped_outer_medium_is_blamed_on_chain_outer() {
    let message = "key `chain.outer`: a damped outer medium (dashpot at 300 (50 grains; c 1)) \
                   needs a method that applies damping (verlet or blanes-moan4), but \
                   `integrator.method` is multirate (with `integrator.multirate`)";
    assert_scene_error("validation/bad_scenes/outer-damped-multirate.toml", message);
    // The same scene in a study: the scene's key, not its generated layer's.
    let ((c, ce), (r, re), made) =
        sweep_verdicts("validation/bad_sweeps/scene-damped-outer-multirate.toml");
    let want = format!(
        "error: validation/bad_sweeps/../bad_scenes/outer-damped-multirate.toml: {message}\n"
    );
    assert_eq!((c, ce.as_str()), (Some(2), want.as_str()));
    assert_eq!((r, re.as_str()), (Some(2), want.as_str()));
    assert!(!made);
}

/// Item 5: an `outer-right` of 400 grains with `distance = 300` is a clear error under
/// `chain.outer`, not a wrapped count (a panic with overflow checks on).
#[test]
fn outer_distance_shorter_than_outer_right_does_not_wrap() {
    assert_scene_error(
        "validation/bad_scenes/outer-distance-short.toml",
        "key `chain.outer`: distance (300) must cover the grains from the container to the \
         striker (`outer-right`, 400), the striker and one grain beyond it: at least 402 grains",
    );
}

/// Item 5: a region at grain 8000 (in the beyond-striker chain the medium cuts) is reported as
/// grain 8000, with the chain's range in the file's numbers (3701-4480: outer-left's 4000
/// grains cut to 300 move every number by 3700; 300 + 180 + 300 grains remain).
#[test]
fn region_numbers_are_the_files() {
    assert_scene_error(
        "validation/bad_scenes/outer-region-cut.toml",
        "key `regions[1].first`: grain 8000 is outside the chain (grains 3701 to 4480 as this \
         file numbers them, after `chain.outer` resized the outer chains)",
    );
}

/// Item 5: a wall at an end of the chain is not silently replaced by the medium's free end.
#[test]
fn outer_medium_refuses_a_wall_at_the_end() {
    assert_scene_error(
        "validation/bad_scenes/outer-wall-end.toml",
        "key `chain.outer`: the outer medium ends the chain with free ends beyond its outer \
         chains, but `chain.left` is a wall: remove the wall or the outer medium",
    );
    // The same through a sweep's `outer`, blamed on the sweep's key.
    let p = "validation/bad_sweeps/outer-wall-end.toml";
    assert_sweep_error(
        p,
        "key `containers[0].outer`: the outer medium ends the chain with free ends beyond its \
         outer chains, but `chain.left` is a wall: remove the wall or the outer medium (scene \
         validation/bad_sweeps/scenes/a-wall-left.toml, key `chain.outer`)",
    );
}

/// Item 5: a sweep setting that would resize or replace a scene's own outer medium, or run a
/// damped one multirate, is refused naming both keys (it used to override it silently, or
/// to say "`outer-left` must be the first section" when it was).
#[test]
fn sweep_settings_do_not_override_the_scenes_outer_medium() {
    let own = "scene validation/bad_sweeps/scenes/a-own-dashpot.toml gives its own outer medium \
               (`chain.outer`: dashpot at 300 (50 grains; c 1)), which sets its outer chains;";
    assert_sweep_error(
        "validation/bad_sweeps/own-outer-and-outer-chains.toml",
        &format!(
            "key `outer_chains`: {own} `outer_chains` cannot change them too: remove one of the two"
        ),
    );
    assert_sweep_error(
        "validation/bad_sweeps/own-outer-and-free-ends.toml",
        &format!(
            "key `containers[0].free_ends`: {own} `containers[0].free_ends` cannot change them \
             too: remove one of the two"
        ),
    );
    assert_sweep_error(
        "validation/bad_sweeps/own-outer-and-multirate.toml",
        "key `multirate`: scene validation/bad_sweeps/scenes/a-own-dashpot.toml has a damped \
         outer medium (`chain.outer`: dashpot at 300 (50 grains; c 1)), which needs a \
         single-rate splitting method; multirate applies no damping",
    );
    assert_sweep_error(
        "validation/bad_sweeps/multirate-with-dissipation.toml",
        "key `containers[0].multirate`: cannot apply with `containers[0].dissipation`: damping \
         needs a single-rate splitting method (multirate applies none); remove one of the two",
    );
}

/// Container (a) with `chain.outer` and outer-left of `outer_left` grains (every grain number
/// moved with it), written into `dir`.
fn container_with_outer(dir: &Path, outer: &str, outer_left: u64) -> PathBuf {
    let a = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/containers/a-standard.toml"),
    )
    .unwrap();
    let shift = outer_left as i64 - 4000;
    let n = |g: i64| (g + shift).to_string();
    let text = a
        .replacen(
            "right = { kind = \"free\" }",
            &format!("right = {{ kind = \"free\" }}\nouter = {outer}"),
            1,
        )
        .replacen("count = 4000", &format!("count = {outer_left}"), 1)
        .replace("grain = 4301", &format!("grain = {}", n(4301)))
        .replace("first = 4001", &format!("first = {}", n(4001)))
        .replace("last = 4180", &format!("last = {}", n(4180)))
        .replace("last = 4301", &format!("last = {}", n(4301)));
    let p = dir.join("scene.toml");
    std::fs::write(&p, text).unwrap();
    p
}

/// Item 5: the memory guard judges the chain after the outer edit: an `outer-left` of 1e7
/// grains cut to 300 by `free-ends` is 780 grains (300 + 180 + 120 + 1 + 179), not 2.1 GB.
#[test]
fn memory_guard_judges_the_chain_after_the_outer_medium() {
    let d = tmp();
    let p = container_with_outer(
        d.path(),
        "{ medium = \"free-ends\", distance = 300 }",
        10_000_000,
    );
    let (c, out, err) = grainchain(&["check", s(&p)]);
    assert_eq!(c, Some(0), "{err}");
    assert!(out.contains("ok (780 grains,"), "{out}");
    // Without the medium the same file is refused (the guard still guards).
    let text = std::fs::read_to_string(&p)
        .unwrap()
        .replace("outer = { medium = \"free-ends\", distance = 300 }\n", "");
    std::fs::write(&p, text).unwrap();
    let (c, _, err) = grainchain(&["check", s(&p)]);
    assert_eq!(c, Some(2), "{err}");
    assert!(
        err.contains("key `chain.sections[0].count`: 10004301 grains"),
        "{err}"
    );
}

/// Item 6: `study --check` runs the study's per-job validation: `outer_chains = 10` fails both
/// alike ("gauges need 20 grains"), and the study claims no folder (no lone manifest.json).
#[test]
fn gauges_are_checked_before_the_study_claims_its_folder() {
    assert_sweep_error(
        "validation/bad_sweeps/outer-chains-below-gauges.toml",
        "key `outer_chains`: the container's gauges need 20 grains on each side of region \
         `container`; scene validation/bad_sweeps/../../scenes/containers/a-standard.toml as the \
         study runs it (a) has 10 on the left and 131 on the right",
    );
}

/// Item 6: integers above the TOML integer (2^63 - 1) in `multirate.margin`, `horizon.pad`
/// and `snapshots.every` fail `check` exactly as they fail `run` (`run` reads the file as TOML
/// values for its folder's digest, which refuses them; `check` read only the typed form).
#[test]
fn integers_above_the_toml_integer_fail_check_as_run() {
    let d = tmp();
    let a = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/containers/a-standard.toml"),
    )
    .unwrap();
    for (key, from, to) in [
        (
            "integrator.multirate",
            "margin = 20 }",
            format!("margin = {U64_MAX} }}"),
        ),
        (
            "run.horizon",
            "horizon = {}",
            format!("horizon = {{ pad = {U64_MAX} }}"),
        ),
        (
            "output",
            "energies = true",
            format!(
                "energies = true\nsnapshots = {{ fields = [\"velocity\"], every = {U64_MAX} }}"
            ),
        ),
    ] {
        let p = d.path().join("big.toml");
        std::fs::write(&p, a.replacen(from, &to, 1)).unwrap();
        let ((c, ce), (r, re), made) = scene_verdicts(s(&p));
        assert_eq!(c, Some(2), "{key}: {ce}");
        assert_eq!(r, Some(2), "{key}: {re}");
        assert_eq!(ce, re, "{key}");
        assert!(!made);
        assert!(
            ce.contains(&format!("key `{key}")) && ce.contains("TOML integers go up to"),
            "{key}: {ce}"
        );
    }
}

/// Item 7: sweep errors name the sweep's key: `search.count` (not `random.count`), a
/// container's `speed` (not the scene's `integrator.dt`), also for a speed whose snapshots
/// would take 2.5e8 steps each, which `--check` passed.
#[test]
fn sweep_errors_name_the_sweeps_key() {
    assert_sweep_error(
        "validation/bad_sweeps/search-count-huge.toml",
        "key `search.count`: 40000000000 jobs whose member files would take at least 522400.0 GB \
         (estimated), over the limit of 1.0 GB; run fewer members or snapshots, or pass \
         --allow-large-output",
    );
    for (file, speed, scale) in [
        ("speed-too-slow.toml", "1e-30", "1.585e6"),
        ("speed-underflow.toml", "1e-300", "1.585e60"),
    ] {
        assert_sweep_error(
            &format!("validation/bad_sweeps/{file}"),
            &format!(
                "key `containers[0].speed`: {speed} is too slow for scene \
                 validation/bad_sweeps/../../scenes/containers/a-standard.toml (striker speed \
                 10): its snapshots, at the scene's step, would take {scale} times the scene's \
                 steps each; at most 1000 times, a speed of at least 1e-14"
            ),
        );
    }
}

/// A small scene (60 Hertz grains, a striker, verlet, 4 outputs) with every integer key.
fn small_scene(pad: &str, margin: &str, ratio: &str, every: &str, at: &str) -> String {
    format!(
        "[chain]\n[[chain.sections]]\ncount = 60\nmass = 1.0\np = 1.5\neta = 5657.0\n\n\
         [striker]\nend = \"left\"\nmass = 1.0\nspeed = 1.0\n\n\
         [integrator]\nmethod = \"multirate\"\ndt = 1e-3\n\
         multirate = {{ ratio = {ratio}, fast = \"r\", margin = {margin} }}\n\n\
         [run]\nduration = 2.0\noutput_interval = 0.5\nhorizon = {{ pad = {pad} }}\n\n\
         [[regions]]\nname = \"r\"\nfirst = 1\nlast = 5\n\n\
         [output]\nsnapshots = {{ fields = [\"velocity\"], every = {every}, at = [{at}] }}\n\
         pulses = {{ every = {every}, at = [{at}] }}\n"
    )
}

/// The integer-maximum test: each integer key of a scene file at the largest value
/// its type takes from TOML (2^63 - 1, and -2^63 for the signed grain numbers; u64 max is
/// above the TOML integer and refused as such, `integers_above_the_toml_integer_...`) gives
/// exit 2 naming the key, or checks and runs correctly: never a panic (the test profile's
/// overflow checks turn a wrap into one) or a wrapped number in a message.
#[test]
fn scene_integer_keys_at_their_maximum() {
    let d = tmp();
    let base = |pad: &str, margin: &str, ratio: &str, every: &str, at: &str| {
        small_scene(pad, margin, ratio, every, at)
    };
    let ok = base("8", "2", "2", "1", "1");
    let mut cases: Vec<(String, String, Option<&str>)> = vec![
        // (what, scene text, the key of the expected error or None: runs)
        (
            "horizon.pad".into(),
            base(I64_MAX, "2", "2", "1", "1"),
            Some("run.horizon.pad"),
        ),
        // A margin past the chain is clamped to its ends (documented): runs.
        (
            "multirate.margin".into(),
            base("8", I64_MAX, "2", "1", "1"),
            None,
        ),
        (
            "multirate.ratio".into(),
            base("8", "2", I64_MAX, "1", "1"),
            Some("integrator.multirate.ratio"),
        ),
        (
            "output every".into(),
            base("8", "2", "2", I64_MAX, "1"),
            None,
        ),
        // An output after the run's last is refused (issue 38: it recorded nothing).
        (
            "output at".into(),
            base("8", "2", "2", "1", I64_MAX),
            Some("output.snapshots.at[0]"),
        ),
    ];
    // Tracks need per-step velocities (not multirate): verlet.
    cases.push((
        "output.tracks.every".into(),
        format!("{ok}tracks = {{ every = {I64_MAX} }}\n")
            .replace("method = \"multirate\"", "method = \"verlet\"")
            .replace("multirate = { ratio = 2, fast = \"r\", margin = 2 }\n", ""),
        None,
    ));
    for (key, from, to) in [
        (
            "chain.sections[0].count",
            "count = 60",
            format!("count = {I64_MAX}"),
        ),
        (
            "regions[0].first",
            "first = 1\nlast = 5",
            format!("first = {I64_MIN}\nlast = 5"),
        ),
        (
            "regions[0].last",
            "first = 1\nlast = 5",
            format!("first = 1\nlast = {I64_MAX}"),
        ),
    ] {
        cases.push((key.into(), ok.replacen(from, &to, 1), Some(key)));
    }
    for (key, v) in [("initial[0].grain", I64_MAX), ("initial[0].grain", I64_MIN)] {
        cases.push((
            key.into(),
            format!("{ok}\n[[initial]]\ngrain = {v}\nvelocity = 1.0\n"),
            Some(key),
        ));
    }
    for (key, first, last) in [
        ("initial[0].first", I64_MIN, "3"),
        ("initial[0].last", "1", I64_MAX),
    ] {
        cases.push((
            key.into(),
            format!("{ok}\n[[initial]]\nfirst = {first}\nlast = {last}\nvelocity = 1.0\n"),
            Some(key),
        ));
    }
    for (key, first, last) in [
        ("output.snapshots.first", I64_MIN, "5"),
        ("output.snapshots.last", "1", I64_MAX),
    ] {
        cases.push((
            key.into(),
            ok.replacen(
                "every = 1, at = [1] }",
                &format!("every = 1, at = [1], first = {first}, last = {last} }}"),
                1,
            ),
            Some(key),
        ));
    }
    // The outer medium's counts, on container (a).
    let a = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/containers/a-standard.toml"),
    )
    .unwrap();
    for m in [
        format!("{{ medium = \"free-ends\", distance = {I64_MAX} }}"),
        format!("{{ medium = \"dashpot\", distance = 300, layer = {I64_MAX}, c = 1.0 }}"),
    ] {
        cases.push((
            format!("chain.outer {m}"),
            a.replacen(
                "right = { kind = \"free\" }",
                &format!("right = {{ kind = \"free\" }}\nouter = {m}"),
                1,
            ),
            Some("chain.outer"),
        ));
    }
    let bad = at_maximum(d.path(), &cases, scene_verdicts);
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}

/// The integer-maximum test for sweep files: each integer key at 2^63 - 1 gives exit 2 naming
/// the key from `study --check` and `study` alike, or runs (a seed is any number). A margin
/// past the chain would carry the fast region to the ends of the long outer chains, which a
/// study's run requires untouched: refused before running, under the margin's key.
#[test]
fn sweep_integer_keys_at_their_maximum() {
    let d = tmp();
    let root = env!("CARGO_MANIFEST_DIR");
    let a = format!("{root}/scenes/containers/a-standard.toml");
    let sweep = |top: &str, container: &str, tables: &str| {
        format!(
            "name = \"max\"\nperturbation = {{ kind = \"striker-speed\", epsilon = 1e-12 }}\n\
             {top}\n\n[[containers]]\nkey = \"a\"\nscene = \"{a}\"\n{container}\n{tables}"
        )
    };
    let std_top = "snapshots = 20\nmembers = 1\nouter_chains = 200";
    let random = |field: &str, v: &str| {
        let mut t = vec![
            ("count", "1".to_string()),
            ("members", "1".to_string()),
            ("seed", "7".to_string()),
            ("sections", "[2, 3]".to_string()),
            ("grains", "[10, 20]".to_string()),
            ("wall_grains", "20".to_string()),
        ];
        for x in t.iter_mut() {
            if x.0 == field {
                x.1 = v.to_string();
            }
        }
        let mut s = format!(
            "[random]\ntemplate = \"{a}\"\nmasses = [1.0]\nexponents = [1.5]\nwalls = [\"ends\"]\n"
        );
        for (k, v) in t {
            s.push_str(&format!("{k} = {v}\n"));
        }
        s
    };
    let search = |field: &str| {
        let mut s = format!(
            "[search]\nscenes = [\"{root}/scenes/containers/a-standard.toml\", \
             \"{root}/scenes/containers/c-uniform-sides.toml\", \
             \"{root}/scenes/containers/d-long-sections.toml\", \
             \"{root}/scenes/containers/e-no-walls.toml\"]\n"
        );
        for k in ["count", "seed", "members"] {
            let v = if k == field { I64_MAX } else { "1" };
            s.push_str(&format!("{k} = {v}\n"));
        }
        s
    };
    let m = I64_MAX;
    let cases: Vec<(String, String, Option<&str>)> = vec![
        ("snapshots".into(), sweep(&format!("snapshots = {m}\nmembers = 1"), "", ""), Some("snapshots")),
        ("members".into(), sweep(&format!("snapshots = 20\nmembers = {m}"), "", ""), Some("members")),
        ("outer_chains".into(), sweep(&format!("snapshots = 20\nmembers = 1\nouter_chains = {m}"), "", ""), Some("outer_chains")),
        ("multirate.ratio".into(), sweep(&format!("{std_top}\nmultirate = {{ ratio = {m}, margin = 20 }}"), "", ""), Some("multirate.ratio")),
        ("multirate.margin".into(), sweep(&format!("{std_top}\nmultirate = {{ ratio = 8, margin = {m} }}"), "", ""), Some("multirate.margin")),
        ("containers[0].multirate.ratio".into(), sweep(std_top, &format!("multirate = {{ ratio = {m}, margin = 20 }}"), ""), Some("containers[0].multirate.ratio")),
        ("containers[0].multirate.margin".into(), sweep(std_top, &format!("multirate = {{ ratio = 8, margin = {m} }}"), ""), Some("containers[0].multirate.margin")),
        ("containers[0].outer distance".into(), sweep("snapshots = 20\nmembers = 1", &format!("outer = {{ medium = \"free-ends\", distance = {m} }}"), ""), Some("containers[0].outer")),
        ("containers[0].outer layer".into(), sweep("snapshots = 20\nmembers = 1", &format!("outer = {{ medium = \"ground-damped\", distance = 300, layer = {m}, rate = 0.1 }}"), ""), Some("containers[0].outer")),
        ("perturbation.seed".into(), sweep(std_top, "", "").replace("{ kind = \"striker-speed\", epsilon = 1e-12 }", &format!("{{ kind = \"displacement\", amplitude = 1e-12, seed = {m} }}")), None),
        ("random.count".into(), sweep(std_top, "", &random("count", m)), Some("random.count")),
        ("random.members".into(), sweep(std_top, "", &random("members", m)), Some("random.members")),
        ("random.seed".into(), sweep(std_top, "", &random("seed", m)), None),
        ("random.sections".into(), sweep(std_top, "", &random("sections", &format!("[{m}, {m}]"))), Some("random.sections")),
        ("random.grains".into(), sweep(std_top, "", &random("grains", &format!("[{m}, {m}]"))), Some("random.grains")),
        ("random.wall_grains".into(), sweep(std_top, "", &random("wall_grains", m)), Some("random.wall_grains")),
        ("search.count".into(), sweep(std_top, "", &search("count")), Some("search.count")),
        ("search.members".into(), sweep(std_top, "", &search("members")), Some("search.members")),
    ];
    let bad = at_maximum(d.path(), &cases, sweep_verdicts);
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}

/// The integer-maximum cases `(what, file text, key)` judged by `verdicts` (written to a file in
/// `dir`): with a key, exit 2 from both commands with the same message naming it and no folder
/// made; without, both run. Never a panic, and never a number near i64's minimum where the file
/// wrote none (a wrapped one). Returns the cases that fail.
fn at_maximum(
    dir: &Path,
    cases: &[(String, String, Option<&str>)],
    verdicts: fn(&str) -> Verdicts,
) -> Vec<String> {
    let mut bad = Vec::new();
    for (what, text, key) in cases {
        let p = dir.join("max.toml");
        std::fs::write(&p, text).unwrap();
        let ((c, ce), (r, re), made) = verdicts(s(&p));
        let wrapped = (!text.contains(I64_MIN)
            && (ce.contains("-922337203685477") || re.contains("-922337203685477")))
            || ce.contains("panicked")
            || re.contains("panicked");
        let fine = match key {
            Some(k) => c == Some(2) && ce == re && ce.contains(&format!("key `{k}`")) && !made,
            None => c == Some(0) && r == Some(0),
        };
        if !fine || wrapped {
            bad.push(format!(
                "{what}: check {c:?} `{}`; run {r:?} `{}`",
                ce.trim(),
                re.trim()
            ));
        }
    }
    bad
}
