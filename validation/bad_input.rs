//! Bad input: malformed scene files run through the real binary must fail with their exact
//! error message ("FILE: key `KEY`: message") and exit code 2, never panic, and never leave an
//! output file behind; a property test fuzzes the scene parser.

use crate::common;

use common::{record_one, Row};
use grainchain_engine::Scene;
use proptest::prelude::*;
use proptest::test_runner::{Config, FileFailurePersistence, RngSeed};
use std::path::Path;
use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_grainchain");
const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// Run the binary in the crate root; returns (exit code, stderr).
fn grainchain(args: &[&str]) -> (Option<i32>, String) {
    let out = Command::new(BIN)
        .args(args)
        .current_dir(ROOT)
        .output()
        .expect("run grainchain");
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

cases! {
/// Check 13a: each file under validation/bad_scenes/ (its first line says what is wrong with it)
/// gives exactly this message and exit code 2, from `check` and from `run`; `run` creates no
/// output directory.
fn bad_scene_file(file: &str, message: &str) {
    let path = format!("validation/bad_scenes/{file}");
    let want = format!("error: {path}: {message}\n");
    let (code, stderr) = grainchain(&["check", &path]);
    let out = tempfile::tempdir().unwrap();
    let out_dir = out.path().join("never-written");
    let (run_code, run_stderr) = grainchain(&["run", &path, "--out", out_dir.to_str().unwrap()]);
    let no_output = !out_dir.exists();
    let ok = code == Some(2)
        && stderr == want
        && run_code == Some(2)
        && run_stderr == want
        && no_output
        && !stderr.contains("panicked");
    record_one(
        Row::new(
            "bad scene file",
            file,
            "validation/bad_input.rs (exact message)",
        )
        .expected(format!("exit 2: {message}"))
        .measured(if ok {
            "exit 2, same message from check and run, no output written".to_string()
        } else {
            format!(
                "check exit {code:?}: {}; run exit {run_code:?}; output dir created: {}",
                stderr.trim(),
                !no_output
            )
        })
        .tolerance("exact text")
        .pass(ok),
    );
    assert_eq!(code, Some(2), "{file}: {stderr}");
    assert_eq!(stderr, want, "{file}");
    assert_eq!(run_code, Some(2), "{file}: {run_stderr}");
    assert_eq!(run_stderr, want, "{file}");
    assert!(no_output, "{file}: `run` created {}", out_dir.display());
}
case_1("dt-too-small.toml", "key `integrator.dt`: dt = 1e-14 needs more than 1e12 steps per output interval (0.5)"),
case_2("duplicate-key.toml", "key `chain.sections[0].mass` (line 6, column 1): duplicate key"),
case_3("duration-infinite.toml", "key `run.duration`: must be a finite number > 0, got inf"),
case_4("empty-file.toml", "key `chain` (line 1, column 1): missing field `chain`"),
case_5("exponent-below-one.toml", "key `chain.sections[0].p`: exponent must be a finite number >= 1, got 0.5"),
case_6("initial-grain-and-range.toml", "key `initial[0]`: give either `grain`, or both `first` and `last`"),
case_7("initial-outside-chain.toml", "key `initial[0].first`: grain 11 is outside the chain (grains 0 to 10)"),
case_8("initial-grain-outside-chain.toml", "key `initial[0].grain`: grain 11 is outside the chain (grains 0 to 10)"),
case_9("initial-without-value.toml", "key `initial[0]`: give a `velocity` or a `displacement`"),
case_10("interface-unknown.toml", "key `chain.interface` (line 3, column 13): unknown variant `middle`, expected one of `min-exponent`, `max-exponent`, `left`, `right`"),
case_11("interval-longer-than-duration.toml", "key `run.output_interval`: must be at most run.duration (1), got 2"),
case_12("mass-is-a-string.toml", "key `chain.sections[0].mass` (line 5, column 8): invalid type: string \"heavy\", expected f64"),
case_13("missing-run-duration.toml", "key `run` (line 14, column 1): missing field `duration`"),
case_14("nan-stiffness.toml", "key `chain.sections[0].eta`: must be a finite number > 0, got NaN"),
case_15("negative-count.toml", "key `chain.sections[0].count` (line 4, column 9): invalid value: integer `-5`, expected u64"),
case_16("negative-dt.toml", "key `integrator.dt`: must be a finite number > 0, got -0.0001"),
case_17("negative-mass.toml", "key `chain.sections[0].mass`: must be a finite number > 0, got -1"),
case_18("negative-precompression.toml", "key `chain.sections[0].delta0`: must be a finite number >= 0, got -0.1"),
case_19("no-sections.toml", "key `chain.sections`: the chain needs at least one section"),
case_20("precompression-unbalanced.toml", "key `chain`: precompression is not in equilibrium at grain 10: the contact forces on its two sides are 5.657 and 16.000412244689198; give every contact the same static force eta*delta0^p"),
case_21("precompression-without-walls.toml", "key `chain.left`: precompression (delta0 > 0) needs walls at both ends to hold it, and this end has none"),
case_22("pulse-threshold-out-of-range.toml", "key `output.pulses.threshold`: must be between 0 and 1, got 1.5"),
case_23("section-duplicate-name.toml", "key `chain.sections[1].name`: section `heavy` is named twice (names must be unique)"),
case_24("region-duplicate.toml", "key `regions[1].name`: region `r` is defined twice"),
case_25("region-name-comma.toml", "key `regions[0].name`: must be a non-empty name without commas"),
case_26("region-outside-chain.toml", "key `regions[0].last`: grain 20 is outside the chain (grains 0 to 10)"),
case_27("region-reversed.toml", "key `regions[0].last`: last (3) is before first (8)"),
case_28("sleep-negative.toml", "key `integrator.sleep.velocity`: must be a finite number >= 0, got -1"),
case_29("horizon-dopri5.toml", "key `run.horizon`: needs a fixed-step method that resets margin grains (verlet, blanes-moan4 or multirate), not dopri5"),
case_30("horizon-speed-negative.toml", "key `run.horizon.speed`: must be a finite number > 0, got -1"),
case_31("sleep-gear5.toml", "key `integrator.sleep`: the sleep rule needs a splitting method (verlet or blanes-moan4), not gear5"),
case_32("damping-negative.toml", "key `chain.sections[0].damping`: must be a finite number >= 0, got -0.5"),
case_33("contact-damping-gear5.toml", "key `chain.sections[0].contact_damping`: damping needs a splitting method (verlet or blanes-moan4), not gear5"),
case_34("contact-damping-negative.toml", "key `chain.sections[0].contact_damping.c`: must be a finite number >= 0, got -0.5"),
case_35("outer-without-outer-chains.toml", "key `chain.outer`: an outer medium needs a section named `outer-left` (the container contract of scenes/containers/)"),
case_36("contact-damping-model.toml", "key `chain.sections[0]` (line 3, column 1): unknown variant `coulomb`, expected one of `viscous`, `kuwabara-kono`, `scale-respecting`"),
case_37("damping-adaptive.toml", "key `chain.sections[1].damping`: damping needs a splitting method (verlet or blanes-moan4), not dopri5"),
case_38("snapshot-every-zero.toml", "key `output.snapshots.every`: must be at least 1"),
case_39("snapshot-no-fields.toml", "key `output.snapshots.fields`: name at least one field"),
case_40("snapshot-unknown-field.toml", "key `output.snapshots` (line 19, column 25): unknown variant `temperature`, expected one of `velocity`, `displacement`, `force`, `overlap`, `energy`, `mass`"),
case_41("striker-at-wall.toml", "key `striker.end`: that end of the chain is a wall; a striker needs a free end"),
case_42("striker-end-unknown.toml", "key `striker.end` (line 10, column 7): unknown variant `top`, expected `left` or `right`"),
case_43("striker-half-law.toml", "key `striker`: give both `p` and `eta` for the striker's contact, or neither"),
case_44("striker-speed-zero.toml", "key `striker.speed`: must be a finite number > 0, got 0"),
case_45("sweep-file.toml", "this is a sweep file, not a scene (run it with `grainchain study`)"),
case_46("syntax-error.toml", "key `striker` (line 9, column 9): unclosed table, expected `]`"),
case_47("tension-nonlinear.toml", "key `chain.sections[0].tension`: a two-sided (tension) contact must be linear (p = 1), got p = 1.5"),
case_48("tolerance-for-fixed-step.toml", "key `integrator.rtol`: tolerances apply to adaptive methods only; verlet takes a fixed dt"),
case_49("too-much-memory.toml", "key `chain.sections[0].count`: 50000001 grains would need about 10.0 GB of memory (estimated upper bound, 200 bytes per grain with verlet), over the limit of 1.0 GB; use fewer grains, or pass --allow-large-output"),
case_50("too-many-grains.toml", "key `chain.sections[0].count`: the chain may have at most 100000000 grains"),
case_51("unknown-method.toml", "key `integrator.method` (line 19, column 10): unknown variant `rk4`, expected one of `verlet`, `blanes-moan4`, `gear5`, `dopri5`, `multirate`"),
case_52("unknown-run-key.toml", "key `run.colour` (line 17, column 1): unknown field `colour`, expected one of `duration`, `output_interval`, `horizon`"),
case_53("unknown-section-key.toml", "key `chain.sections[0].mas` (line 3, column 1): unknown field `mas`"),
case_54("unknown-top-level-key.toml", "key `colour` (line 2, column 1): unknown field `colour`, expected one of `name`, `description`, `chain`, `striker`, `target`, `initial`, `integrator`, `run`, `regions`, `output`, `design`"),
case_55("si-mixed-units.toml", "key `chain.sections[1].material`: missing: this is an SI scene (`chain.sections[0].material`), where every section gives `material` and `diameter`; program units (`mass`, `p`, `eta`) and SI cannot be mixed"),
case_56("si-unknown-material.toml", "key `chain.sections[0].material`: unknown material `unobtainium` (known: steel, stainless-steel, brass, aluminium, ptfe, glass, tungsten-carbide; or give its constants E, nu, rho and an optional name)"),
case_57("si-material-constants.toml", "key `chain.sections[0].material`: Poisson's ratio nu must lie in (-1, 0.5], got 0.6"),
case_58("si-material-a-number.toml", "key `chain.sections[0]` (line 4, column 1): invalid type: integer `3`, expected a material's name (a string) or its constants `{ E = .., nu = .., rho = .. }`"),
case_59("si-missing-diameter.toml", "key `chain.sections[0].diameter`: missing: a sphere of a material needs its diameter in metres"),
case_60("si-diameter-out-of-range.toml", "key `chain.sections[0].diameter`: a diameter must lie in [1e-6, 1] m (Hertz's elastic spheres, from above colloids to boulders), got 6"),
case_61("si-missing-dt.toml", "key `integrator.dt`: missing: an SI scene gives its step in seconds (the default, 1e-4, is in program units; `chain.sections[0].material` makes this an SI scene)"),
case_62("si-restitution-above-one.toml", "key `chain.restitution`: must be a coefficient of restitution from 0.05 to 1 (elastic), got 1.5"),
case_63("si-striker-mass.toml", "key `striker.material`: missing: the striker of an SI scene is a sphere of a material (with `diameter`): this is an SI scene (`chain.sections[0].material`), where every section gives `material` and `diameter`; program units (`mass`, `p`, `eta`) and SI cannot be mixed"),
case_64("si-wall-in-program-scene.toml", "key `chain.right.material`: a wall's `material` needs an SI scene (sections given by `material` and `diameter`); this scene's sections are in program units (`mass`, `p`, `eta`), and the two cannot be mixed"),
case_65("target-and-right-wall.toml", "key `target`: the target is the chain's right end; give a `[target]` or a right wall (`chain.right`), not both"),
case_66("target-spring-negative.toml", "key `target.spring`: must be a finite number > 0, got -5"),
case_67("target-missing-mass.toml", "key `target.mass`: missing: the target's mass (program units; or an SI scene's `material`)"),
case_68("target-material-and-law.toml", "key `target.p`: not with `material` (the contact is Hertz's from the two materials)"),
case_69("target-and-right-striker.toml", "key `striker.end`: the right end holds the `[target]`; strike the chain from the left"),
case_70("wall-kind-unknown.toml", "key `chain.right` (line 3, column 18): unknown variant `sticky`, expected `free` or `wall`"),
case_71("zero-count.toml", "key `chain.sections[0].count`: must be at least 1"),
case_72("name-escapes.toml", "key `name`: must be a plain folder name, without `/`, `\\` or control characters (it names the output folder out/<name>)"),
case_73("name-empty.toml", "key `name`: must not be empty (it names the output folder out/<name>)"),
case_74("zero-stiffness.toml", "key `chain.sections[0].eta`: must be a finite number > 0, got 0"),
case_75("grains-at-the-limit-plus-a-striker.toml", "key `striker`: the chain may have at most 100000000 grains, sections, target and striker together; this one has 100000001"),
case_76("name-too-long.toml", "key `name`: is 201 bytes long; at most 200 (it names the output folder out/<name>, and a file name has at most 255 bytes)"),
case_77("snapshot-after-the-run.toml", "key `output.snapshots.at[1]`: output 3 is after the run's last output, 2 (run.duration / run.output_interval)"),
case_78("pulses-at-repeated.toml", "key `output.pulses.at[2]`: output indices must increase, each listed once: 2 follows 2"),
case_79("precompression-free-right-end.toml", "key `chain.right`: precompression (delta0 > 0) needs walls at both ends to hold it, and this end has none"),
case_80("missing-run-after-name.toml", "key `run` (line 1, column 1): missing field `run`"),
case_81("unknown-dotted-key.toml", "key `output.foo` (line 20, column 1): unknown field `foo`, expected one of `energies`, `snapshots`, `pulses`, `tracks`"),
case_82("header-too-deep.toml", "line 17 (`[a.a.a.a.a.a.a.a.a.a.a.a.a.a.a.a.a.a.a.a.a.a.a.a.a.a.a.a.a.a`): nested too deeply for the TOML reader (recursion limit)"),
case_83("not-utf8.toml", "cannot read: line 1: not UTF-8 text (byte 65 of the file)"),
case_84("si-density-huge.toml", "key `chain.sections[0].material`: density rho must lie in [1, 100000] kg/m^3 (the solids from aerogels to beyond osmium), got 1e300"),
case_85("si-material-name-of-the-table.toml", "key `chain.sections[0].material`: `steel` is a material of the table; give yours another name (or leave `name` out)"),
case_86("si-material-name-quote.toml", "key `chain.sections[0].material`: a material's name must be 1 to 40 characters without quotes, `|`, control characters or spaces at either end, got \"5\\\" steel\""),
case_87("events-gear5.toml", "key `integrator.events`: contact events need verlet or blanes-moan4, not gear5"),
}

/// A bad number on the command line is bad input too: `units --diameter` (exit code 2, naming
/// the flag), as for every flag clap checks.
#[test]
fn bad_command_line_number() {
    let mut rows_ok = true;
    for bad in ["-1", "0", "nan", "inf", "abc"] {
        let (code, stderr) = grainchain(&["units", "--diameter", bad]);
        let ok = code == Some(2) && stderr.contains("--diameter");
        rows_ok &= ok;
        record_one(
            Row::new(
                "bad command-line number",
                format!("units --diameter {bad}"),
                "exit code 2 for bad input",
            )
            .expected("exit 2, the message names --diameter")
            .measured(format!(
                "exit {code:?}: {}",
                stderr.lines().next().unwrap_or("")
            ))
            .tolerance("exact exit code")
            .pass(ok),
        );
    }
    assert!(rows_ok);
}

/// A scene whose outputs would fill a disk: `check` prints the estimate, `run` refuses it with
/// exit code 2 naming the key, and writes nothing.
#[test]
fn oversized_outputs_are_refused() {
    let file = "validation/large_scenes/huge-snapshots.toml";
    let out = std::env::temp_dir().join(format!("grainchain-huge-{}", std::process::id()));
    let check = Command::new(BIN)
        .args(["check", file])
        .current_dir(ROOT)
        .output()
        .unwrap();
    let check_out = String::from_utf8_lossy(&check.stdout).into_owned();
    let (code, stderr) = grainchain(&["run", file, "--out", out.to_str().unwrap()]);
    // 1,001 snapshot times x 2,000,001 grains x (2 x 12 + 2 x 25) bytes = 148.1 GB (the estimate's
    // bytes per row: NUMBER_BYTES and INTEGER_BYTES in engine/src/scene/mod.rs).
    let ok = check.status.code() == Some(0)
        && check_out.contains("snapshots.csv 148.1 GB")
        && check_out.contains("needs --allow-large-output")
        && code == Some(2)
        && stderr.starts_with(&format!(
            "error: {file}: key `output.snapshots`: the outputs would take about 148.1 GB"
        ))
        && !out.exists();
    record_one(
        Row::new(
            "oversized outputs",
            "2e6 grains, a velocity snapshot at each of 1,000 outputs",
            "run refuses what check estimates above 1 GB",
        )
        .expected("check: 148.1 GB; run: exit 2 naming output.snapshots, nothing written")
        .measured(format!(
            "check: {}; run: exit {code:?}: {}",
            check_out.lines().nth(1).unwrap_or("").trim(),
            stderr.lines().next().unwrap_or("")
        ))
        .tolerance("exact")
        .pass(ok),
    );
    assert!(ok, "{check_out}\n{stderr}");
}

/// A run stopped by SIGTERM or SIGINT removes its partial files and exits with 130.
#[cfg(unix)]
#[test]
fn interrupted_run_leaves_no_partial_files() {
    use std::time::{Duration, Instant};
    let mut all_ok = true;
    for signal in ["TERM", "INT"] {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out");
        // Container (a): ~12 s, so the signal lands while energies.csv is being written.
        let mut child = Command::new(BIN)
            .args(["run", "scenes/containers/a-standard.toml", "--out"])
            .arg(&out)
            .current_dir(ROOT)
            .stderr(std::process::Stdio::null())
            .spawn()
            .unwrap();
        let partials = || -> usize {
            std::fs::read_dir(&out).map_or(0, |d| {
                d.filter(|e| {
                    e.as_ref()
                        .is_ok_and(|e| e.file_name().to_string_lossy().ends_with(".partial"))
                })
                .count()
            })
        };
        let t0 = Instant::now();
        while partials() == 0 && t0.elapsed() < Duration::from_secs(30) {
            std::thread::sleep(Duration::from_millis(20));
        }
        let seen = partials();
        Command::new("kill")
            .args([&format!("-{signal}"), &child.id().to_string()])
            .status()
            .unwrap();
        let code = child.wait().unwrap().code();
        let left = partials();
        let ok = seen > 0 && code == Some(130) && left == 0;
        all_ok &= ok;
        record_one(
            Row::new(
                "interrupted run",
                format!("SIG{signal} during container (a)"),
                "no half-written output file",
            )
            .expected("exit 130, no .partial file left")
            .measured(format!(
                "{seen} partial file(s) open; exit {code:?}; {left} left"
            ))
            .tolerance("exact")
            .pass(ok),
        );
    }
    assert!(all_ok);
}

/// `check` interrupted says only "interrupted": it has no output file, so it must not claim to
/// have removed partial ones (it said "partial output files removed").
#[cfg(unix)]
#[test]
fn interrupted_check_claims_no_files() {
    use std::time::Duration;
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("large.toml");
    // 4.5e6 grains: under the memory limit (739 MB estimated) and long enough to check (about
    // 0.4 s to build the chain) for the signal to land while it runs.
    std::fs::write(
        &scene,
        "[chain]\n[[chain.sections]]\ncount = 4500000\nmass = 1.0\np = 1.5\neta = 5657.0\n\n\
         [striker]\nend = \"left\"\nmass = 1.0\nspeed = 1.0\n\n\
         [run]\nduration = 1.0\noutput_interval = 0.5\n",
    )
    .unwrap();
    let child = Command::new(BIN)
        .arg("check")
        .arg(&scene)
        .current_dir(ROOT)
        .stderr(std::process::Stdio::piped())
        .stdout(std::process::Stdio::null())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(100));
    Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(
        out.status.code(),
        Some(130),
        "the signal came too late: {stderr}"
    );
    assert_eq!(stderr, "interrupted\n");
}

/// A file that does not exist and a directory: read errors are bad input too (exit code 2).
#[test]
fn unreadable_scene() {
    let (code, stderr) = grainchain(&["check", "validation/bad_scenes/no-such-file.toml"]);
    let (dcode, dstderr) = grainchain(&["check", "validation/bad_scenes"]);
    let ok = code == Some(2)
        && stderr.starts_with("error: validation/bad_scenes/no-such-file.toml: cannot read: ")
        && dcode == Some(2)
        && dstderr.starts_with("error: validation/bad_scenes: cannot read: ");
    record_one(
        Row::new(
            "bad scene file",
            "missing file, directory",
            "exit code 2 for bad input",
        )
        .expected("exit 2: FILE: cannot read: ...")
        .measured(format!(
            "exit {code:?}: {}; exit {dcode:?}: {}",
            stderr.trim(),
            dstderr.trim()
        ))
        .tolerance("exact prefix")
        .pass(ok),
    );
    assert!(ok, "{stderr} / {dstderr}");
}

/// Every key of the schema, with valid values: the fuzzer's starting point.
const FULL: &str = r#"name = "fuzz"
description = "every key"
[chain]
interface = "min-exponent"
left = { kind = "free" }
right = { kind = "wall", p = 1.5, eta = 5657.0 }
[[chain.sections]]
name = "a"
count = 20
mass = 1.0
p = 1.5
eta = 5657.0
[[chain.sections]]
name = "b"
count = 10
mass = 0.5
p = 1.0
eta = 100.0
tension = false
[striker]
end = "left"
mass = 2.0
speed = 1.0
p = 1.5
eta = 5657.0
[[initial]]
first = 3
last = 4
velocity = 0.1
displacement = 0.0
[integrator]
method = "dopri5"
dt = 1e-3
rtol = 1e-8
atol = 1e-10
skip_untouched = true
max_energy_error = 1e-2
sleep = { velocity = 1e-9, overlap = 1e-9 }
[run]
duration = 1.0
output_interval = 0.25
[[regions]]
name = "r"
first = 1
last = 20
[output]
energies = true
snapshots = { fields = ["velocity", "energy"], every = 1, at = [1, 2], first = 1, last = 30 }
pulses = { every = 1, threshold = 1e-4, valley = 0.25 }
"#;

/// Values that stress the checks: special floats, extreme and negative integers, wrong types.
fn nasty_value() -> impl Strategy<Value = String> {
    prop_oneof![
        Just("nan".to_string()),
        Just("inf".to_string()),
        Just("-inf".to_string()),
        Just("-0.0".to_string()),
        Just("0".to_string()),
        Just("1e308".to_string()),
        Just("5e-324".to_string()),
        Just("-1".to_string()),
        Just("9223372036854775807".to_string()),
        Just("-9223372036854775808".to_string()),
        Just("18446744073709551615".to_string()),
        Just("true".to_string()),
        Just("\"\"".to_string()),
        Just("\"\u{e9}\u{1F600}\"".to_string()),
        Just("[]".to_string()),
        Just("{}".to_string()),
        Just("[1, \"a\"]".to_string()),
        Just("{ kind = \"wall\" }".to_string()),
        Just("1979-05-27".to_string()),
        any::<f64>().prop_map(|x| format!("{x:?}")),
        any::<i64>().prop_map(|x| x.to_string()),
        (0u64..200).prop_map(|x| x.to_string()),
        "[a-z\\-]{0,12}".prop_map(|s| format!("\"{s}\"")),
    ]
}

/// One mutation of a scene text.
#[derive(Clone, Debug)]
enum Mutation {
    /// Replace the value of line `i` (if it is `key = value`).
    Value(usize, String),
    DeleteLine(usize),
    DuplicateLine(usize),
    /// Cut the text at this fraction of its length.
    Truncate(f64),
    /// Insert text at the start of line `i`.
    Insert(usize, String),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        4 => (0usize..60, nasty_value()).prop_map(|(i, v)| Mutation::Value(i, v)),
        1 => (0usize..60).prop_map(Mutation::DeleteLine),
        1 => (0usize..60).prop_map(Mutation::DuplicateLine),
        1 => (0.0f64..1.0).prop_map(Mutation::Truncate),
        1 => (0usize..60, "(?s).{0,20}").prop_map(|(i, s)| Mutation::Insert(i, s)),
    ]
}

fn apply(text: &str, m: &Mutation) -> String {
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let n = lines.len();
    if n == 0 {
        return text.to_string();
    }
    match m {
        Mutation::Value(i, v) => {
            let l = &mut lines[i % n];
            if let Some(eq) = l.find('=') {
                *l = format!("{}= {v}", &l[..eq]);
            }
        }
        Mutation::DeleteLine(i) => {
            lines.remove(i % n);
        }
        Mutation::DuplicateLine(i) => {
            let l = lines[i % n].clone();
            lines.insert(i % n, l);
        }
        Mutation::Truncate(f) => {
            let mut cut = (text.len() as f64 * f) as usize;
            while !text.is_char_boundary(cut) {
                cut -= 1;
            }
            return text[..cut].to_string();
        }
        Mutation::Insert(i, s) => {
            let l = &mut lines[i % n];
            *l = format!("{s}{l}");
        }
    }
    lines.join("\n")
}

/// What every outcome of parsing must satisfy: no panic (proptest reports one as a failure),
/// and an error names the file in the documented form.
fn parse_ok_or_clear_error(text: &str) -> Result<(), TestCaseError> {
    match Scene::parse(text, Path::new("fuzz.toml")) {
        Ok(scene) => {
            // Building the simulation checks the rest; keep allocations small.
            if scene.grains() <= 100_000 {
                let _ = scene.simulation();
            }
        }
        Err(e) => {
            let msg = e.to_string();
            prop_assert!(
                msg.starts_with("fuzz.toml: "),
                "message without the file: {msg}"
            );
            prop_assert!(!msg.contains('\n'), "multi-line message: {msg}");
        }
    }
    Ok(())
}

fn fuzz_config(cases: u32) -> Config {
    Config {
        cases,
        // Fixed seed: the same cases every run (no time-based seeds in this suite).
        rng_seed: RngSeed::Fixed(0x6772_6169_6e63_6861),
        failure_persistence: Some(Box::new(FileFailurePersistence::SourceParallel(
            "proptest-regressions",
        ))),
        ..Config::default()
    }
}

proptest! {
    #![proptest_config(fuzz_config(5000))]

    /// Check 13b: up to three mutations of a scene that uses every key.
    #[test]
    fn fuzz_mutated_scene(ms in prop::collection::vec(mutation(), 1..4)) {
        let mut text = FULL.to_string();
        for m in &ms {
            text = apply(&text, m);
        }
        parse_ok_or_clear_error(&text)?;
    }

    /// Check 13b: arbitrary text, and TOML-looking noise.
    #[test]
    fn fuzz_arbitrary_text(
        text in prop_oneof![
            "(?s).{0,200}",
            "(\\[\\[?[a-z.]{0,12}\\]\\]?\n|[a-z_.]{1,10} = [-0-9.e\"a-z\\[\\]{},]{0,12}\n){0,12}",
        ]
    ) {
        parse_ok_or_clear_error(&text)?;
    }
}

/// The fuzz targets ran (proptest reports failures by panicking inside the two tests above);
/// record a row for the report. Crashes found while writing the suite are kept as regression
/// cases in `parser_regressions`.
#[test]
fn fuzz_summary_row() {
    record_one(
        Row::new(
            "scene parser fuzzing",
            "5000 mutated full scenes + 5000 arbitrary texts, fixed seed",
            "never panic; errors name the file (one line)",
        )
        .expected("no panic")
        .measured("see fuzz_mutated_scene / fuzz_arbitrary_text (a panic fails them)")
        .tolerance("none")
        .info(),
    );
}

// Issue 24, items 2-4: unknown keys in every table (ends, walls and media included), the
// combinations that are refused (Kuwabara-Kono damping on a two-sided contact), and a causal
// horizon slower than the run's bound.

/// `check` and `run` of `path` both exit with code 2 and print exactly `message` after the
/// file's name, and `run` creates no output folder. Returns what went wrong, if anything.
fn refused_by_check_and_run(path: &str, message: &str) -> Option<String> {
    let want = format!("error: {path}: {message}\n");
    let (code, stderr) = grainchain(&["check", path]);
    let out = tempfile::tempdir().unwrap();
    let out_dir = out.path().join("never-written");
    let (run_code, run_stderr) = grainchain(&["run", path, "--out", out_dir.to_str().unwrap()]);
    if code != Some(2) || stderr != want {
        return Some(format!("check: exit {code:?}: {stderr}(wanted {want})"));
    }
    if run_code != Some(2) || run_stderr != want {
        return Some(format!(
            "run: exit {run_code:?}: {run_stderr}(wanted {want})"
        ));
    }
    out_dir
        .exists()
        .then(|| format!("run created {}", out_dir.display()))
}

cases! {
/// Each of these files was accepted by eb2d8c3 with the key ignored or the combination run as
/// something else; each must fail with exactly this message and exit code 2 from `check` and
/// from `run`, and `run` must write nothing.
fn issue24_bad_scene_file(file: &str, message: &str) {
    let path = format!("validation/bad_scenes/{file}");
    let problem = refused_by_check_and_run(&path, message);
    record_one(
        Row::new(
            "bad scene file (issue 24)",
            file,
            "validation/bad_input.rs (exact message)",
        )
        .expected(format!("exit 2: {message}"))
        .measured(
            problem.clone().unwrap_or_else(|| {
                "exit 2, same message from check and run, no output written".into()
            }),
        )
        .tolerance("exact text")
        .pass(problem.is_none()),
    );
    assert_eq!(problem, None, "{file}");
}
case_1("wall-unknown-key.toml", "key `chain.right.contact_dampng` (line 3, column 9): unknown field `contact_dampng`, expected one of `p`, `eta`, `delta0`, `tension`, `contact_damping`, `material`, `restitution`"),
case_2("wall-table-unknown-key.toml", "key `chain.left.tenson` (line 4, column 1): unknown field `tenson`, expected one of `p`, `eta`, `delta0`, `tension`, `contact_damping`, `material`, `restitution`"),
case_3("free-end-with-law.toml", "key `chain.right.p` (line 3, column 9): unknown field `p`: a free end (`kind = \"free\"`) has no other key"),
case_4("outer-long-distance.toml", "key `chain.outer.distance` (line 3, column 9): unknown field `distance`: the medium `long` has no other key"),
case_5("tension-kuwabara-kono.toml", "key `chain.sections[0].contact_damping.model`: `kuwabara-kono` (c delta^0.5 d(delta)/dt) is not defined with `tension = true`: a two-sided contact's overlap delta goes negative, where delta^0.5 has no value; use `viscous` (or `scale-respecting`: q = (p - 1)/2 = 0 on the linear law of a two-sided contact), or leave out `tension`"),
case_6("wall-tension-kuwabara-kono.toml", "key `chain.left.contact_damping.model`: `kuwabara-kono` (c delta^0.5 d(delta)/dt) is not defined with `tension = true`: a two-sided contact's overlap delta goes negative, where delta^0.5 has no value; use `viscous` (or `scale-respecting`: q = (p - 1)/2 = 0 on the linear law of a two-sided contact), or leave out `tension`"),
case_7("horizon-unsafe-without-speed.toml", "key `run.horizon.unsafe`: applies to an explicit `speed` below the bound only (without `speed` the horizon takes the bound)"),
}

cases! {
/// A sweep's container with `outer = { medium = "long", distance = 300 }`, and an outer medium
/// of the search with a key its medium does not have: `study --check` and `study` fail with
/// exactly this message and exit code 2, and `study` writes nothing.
fn issue24_bad_sweep_file(file: &str, message: &str) {
    let path = format!("validation/bad_sweeps/{file}");
    let want = format!("error: {path}: {message}\n");
    let (code, stderr) = grainchain(&["study", &path, "--check"]);
    let out = tempfile::tempdir().unwrap();
    let out_dir = out.path().join("never-written");
    let (run_code, run_stderr) = grainchain(&["study", &path, "--out", out_dir.to_str().unwrap()]);
    assert_eq!((code, stderr.as_str()), (Some(2), want.as_str()), "{file}");
    assert_eq!(
        (run_code, run_stderr.as_str()),
        (Some(2), want.as_str()),
        "{file}"
    );
    assert!(
        !out_dir.exists(),
        "{file}: `study` created {}",
        out_dir.display()
    );
}
case_1("outer-long-distance.toml", "key `containers[0].outer.distance` (line 10, column 9): unknown field `distance`: the medium `long` has no other key"),
case_2("search-medium-unknown-key.toml", "key `search.media.distance` (line 10, column 9): unknown field `distance`: the medium `long` has no other key"),
}

/// The bound of the issue's 60-grain chain (validation/bad_scenes/horizon-speed-*.toml),
/// computed here from its definition (`run::Horizon::speed_bound`): the long-wave sound speed
/// `sqrt(k / m)` of a Hertz contact (p = 3/2, eta = 5657) at the largest overlap the energy
/// allows, `eta delta^(p+1) / (p+1) = E0`, `k = p eta delta^(p-1)`; E0 = 1/2 (the striker, mass
/// 1 at speed 1), m = 1.
fn issue_chain_bound() -> f64 {
    let (p, eta, e0, m) = (1.5f64, 5657.0f64, 0.5f64, 1.0f64);
    let delta = ((p + 1.0) * e0 / eta).powf(1.0 / (p + 1.0));
    (p * eta * delta.powf(p - 1.0) / m).sqrt()
}

/// The number after `after` in `text`, up to the next space.
fn number_after(text: &str, after: &str) -> f64 {
    let rest = &text[text
        .find(after)
        .unwrap_or_else(|| panic!("no `{after}` in {text}"))
        + after.len()..];
    rest.split(' ').next().unwrap().parse().unwrap()
}

cases! {
/// Item 2: the issue's chain with a horizon slower than its bound (0.5 and 1e-300 grains per
/// time unit against 39.7) is refused by `check` and by `run` (exit 2, nothing written), the
/// message naming the key, the value and the bound; the bound it names is the one computed
/// here from its definition.
fn slow_horizon_is_refused(file: &str, speed: &str) {
    let path = format!("validation/bad_scenes/{file}");
    let (_, stderr) = grainchain(&["check", &path]);
    let prefix = format!("key `run.horizon.speed`: {speed} is below this run's bound of ");
    assert!(stderr.contains(&prefix), "{stderr}");
    let bound = number_after(&stderr, "bound of ");
    let expected = issue_chain_bound();
    // powf and sqrt in another order than the program's: a few ulps apart at most.
    let close = ((bound - expected) / expected).abs() < 1e-12;
    // The issue's number, to the digits it gives.
    let issue = (bound - 39.7).abs() < 0.05;
    let message = stderr
        .trim_end()
        .strip_prefix(&format!("error: {path}: "))
        .unwrap_or(&stderr)
        .to_string();
    let problem = refused_by_check_and_run(&path, &message);
    record_one(
        Row::new(
            "horizon slower than its bound (issue 24, item 2)",
            format!("60 Hertz grains, region 0-5, speed {speed}"),
            "refused by check and run; the bound sqrt(k/m) at the largest overlap E0 allows",
        )
        .expected(format!(
            "exit 2 naming run.horizon.speed, {speed} and {}",
            common::g(expected)
        ))
        .measured(format!(
            "bound {bound}; {}",
            problem
                .clone()
                .unwrap_or_else(|| "exit 2 from check and run, nothing written".into())
        ))
        .tolerance("1e-12 relative (round-off of powf)")
        .pass(close && issue && problem.is_none()),
    );
    assert!(close && issue, "bound {bound}, expected {expected}");
    assert_eq!(problem, None);
}
case_1("horizon-speed-below-bound.toml", "0.5"),
case_2("horizon-speed-tiny.toml", "1e-300"),
}

/// The energy and momentum columns of region `head` in an `energies.csv`, as text (compared
/// bit for bit: every number is written in its shortest round-trip form).
fn head_columns(dir: &Path) -> Vec<(String, String)> {
    let text = std::fs::read_to_string(dir.join("energies.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (e, p) = (col("E_head"), col("P_head"));
    lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (f[e].to_string(), f[p].to_string())
        })
        .collect()
}

/// Run `scene` (text) with `grainchain run` into a fresh folder; returns the exit code,
/// stderr, the folder and summary.json.
fn run_text(
    dir: &Path,
    name: &str,
    scene: &str,
) -> (Option<i32>, String, std::path::PathBuf, serde_json::Value) {
    let file = dir.join(format!("{name}.toml"));
    std::fs::write(&file, scene).unwrap();
    let out = dir.join(name);
    let (code, stderr) = grainchain(&[
        "run",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let summary = std::fs::read_to_string(out.join("summary.json"))
        .map(|t| serde_json::from_str(&t).unwrap())
        .unwrap_or(serde_json::Value::Null);
    (code, stderr, out, summary)
}

/// Item 2: with `unsafe = true` the slow horizon runs, `check` and `run` print the warning
/// and summary.json records it (and the numbers are indeed wrong: the region's energy differs
/// from the run without a horizon by more than half of E0, as the issue measured); a speed at
/// the bound or above runs as before, without a warning, its region bit for bit that of the
/// run without a horizon (the horizon's exactness).
#[test]
fn unsafe_horizon_runs_with_a_warning_and_the_bound_runs_exactly() {
    let base = std::fs::read_to_string(
        Path::new(ROOT).join("validation/bad_scenes/horizon-speed-below-bound.toml"),
    )
    .unwrap();
    let with = |horizon: &str| base.replace("horizon = { speed = 0.5, pad = 0 }", horizon);
    assert!(
        with("").len() < base.len(),
        "the scene's horizon line moved"
    );
    let dir = tempfile::tempdir().unwrap();
    let (code, _, none, _) = run_text(dir.path(), "none", &with(""));
    assert_eq!(code, Some(0));
    let reference = head_columns(&none);

    // unsafe = true: runs, warns, records.
    let unsafe_scene = with("horizon = { speed = 0.5, pad = 0, unsafe = true }");
    let file = dir.path().join("unsafe-check.toml");
    std::fs::write(&file, &unsafe_scene).unwrap();
    let (check_code, check_err) = grainchain(&["check", file.to_str().unwrap()]);
    let (code, stderr, out, summary) = run_text(dir.path(), "unsafe", &unsafe_scene);
    let warning = "run.horizon.speed = 0.5 is below this run's bound of ";
    let warnings = summary["warnings"].as_array().cloned().unwrap_or_default();
    let recorded = warnings.len() == 1
        && warnings[0]
            .as_str()
            .is_some_and(|w| w.starts_with(warning) && w.contains("unsafe = true"));
    let bound = summary["horizon_bound"].as_f64().unwrap_or(f64::NAN);
    let e0 = summary["initial_energy"].as_f64().unwrap();
    let worst = head_columns(&out)
        .iter()
        .zip(&reference)
        .map(|(a, b)| (a.0.parse::<f64>().unwrap() - b.0.parse::<f64>().unwrap()).abs() / e0)
        .fold(0.0, f64::max);
    let ok = check_code == Some(0)
        && check_err.contains(warning)
        && code == Some(0)
        && stderr.contains(warning)
        && recorded
        && ((bound - issue_chain_bound()) / bound).abs() < 1e-12
        && summary["horizon_speed"].as_f64() == Some(0.5);
    record_one(
        Row::new(
            "horizon slower than its bound, unsafe = true (issue 24, item 2)",
            "60 Hertz grains, region 0-5, speed 0.5",
            "runs; the warning printed by check and run and recorded in summary.json",
        )
        .expected("exit 0, one warning naming run.horizon.speed, 0.5 and the bound")
        .measured(format!(
            "check exit {check_code:?}, run exit {code:?}, warnings {warnings:?}; region energy off by up to {} E0",
            common::g(worst)
        ))
        .tolerance("exact")
        .pass(ok),
    );
    assert!(
        ok,
        "check {check_code:?}: {check_err}\nrun {code:?}: {stderr}\n{summary}"
    );
    // The issue's measurement: off by 99 % of E0 from t = 2.5 on (more than a half here).
    assert!(
        worst > 0.5,
        "the unsafe horizon changed the region by only {worst} E0"
    );

    // At the bound (its exact bits, as the refusal prints them) and above: no warning, exact.
    for speed in [format!("{bound}"), "40.0".to_string()] {
        let (code, stderr, out, summary) = run_text(
            dir.path(),
            "at-bound",
            &with(&format!("horizon = {{ speed = {speed}, pad = 0 }}")),
        );
        assert_eq!(code, Some(0), "speed {speed}: {stderr}");
        assert!(!stderr.contains("warning"), "speed {speed}: {stderr}");
        assert_eq!(summary["warnings"], serde_json::json!([]), "speed {speed}");
        assert_eq!(
            summary["horizon_speed"].as_f64().unwrap().to_bits(),
            speed.parse::<f64>().unwrap().to_bits()
        );
        assert!(
            summary["dropped_grains"].as_u64().unwrap() > 0,
            "speed {speed}: the horizon dropped nothing"
        );
        assert_eq!(
            head_columns(&out),
            reference,
            "speed {speed}: the region differs from the run without a horizon"
        );
        std::fs::remove_dir_all(&out).unwrap();
    }
}

/// Where a key can go into one table of a TOML text.
#[derive(Clone, Debug)]
enum Place {
    /// A line `KEY = VALUE` at this byte offset (the start of a line): the root table (offset
    /// 0) or a `[table]` / `[[array]]` table (the line after its header).
    Line(usize),
    /// Right after the `{` of an inline table at this offset (`empty`: it is `{}`).
    Inline(usize, bool),
    /// A table defined only by its sub-tables' headers: appended as `[path]` at the end.
    Append,
}

/// One table of a file: where a key goes, and the dotted path the scene errors name it by
/// (`chain.sections[2]`, `run.horizon`, `` for the root; `None` for an inline table nested in
/// an array or another inline table, whose key alone is checked).
#[derive(Clone, Debug)]
struct Table {
    place: Place,
    path: Option<String>,
}

/// Every table of a TOML text: the root, each `[table]` and `[[array]]` entry (path with its
/// index among the entries, as the errors number them), each inline table, each table defined
/// only by sub-tables. A small scanner (strings and comments skipped, brackets counted) rather
/// than a TOML library, so that the file keeps its text and the errors their lines. Dotted and
/// quoted keys are not used by the shipped files; meeting one fails the test, so that a file
/// using them extends the scanner instead of going untested.
fn tables(text: &str) -> Vec<Table> {
    let b = text.as_bytes();
    let mut found = vec![Table {
        place: Place::Line(0),
        path: Some(String::new()),
    }];
    let mut headers: Vec<(String, bool)> = Vec::new();
    let mut table = String::new();
    let mut line_key = String::new();
    let mut stack: Vec<u8> = Vec::new();
    let mut i = 0;
    let mut at_line_start = true;
    let line_end = |i: usize| text[i..].find('\n').map_or(text.len(), |e| i + e);
    while i < b.len() {
        if at_line_start && stack.is_empty() {
            at_line_start = false;
            let end = line_end(i);
            let line = text[i..end].trim();
            if line.starts_with('[') {
                let array = line.starts_with("[[");
                let name = line
                    .trim_start_matches('[')
                    .split(']')
                    .next()
                    .unwrap()
                    .trim();
                assert!(
                    !name.contains(['"', '\'']),
                    "quoted table name `{name}`: extend the scanner"
                );
                let index = headers.iter().filter(|(n, a)| *a && n == name).count();
                headers.push((name.to_string(), array));
                table = if array {
                    format!("{name}[{index}]")
                } else {
                    name.to_string()
                };
                found.push(Table {
                    place: Place::Line((end + 1).min(text.len())),
                    path: Some(table.clone()),
                });
                i = end;
                continue;
            }
            if !line.starts_with('#') {
                if let Some(eq) = line.find('=') {
                    line_key = line[..eq].trim().to_string();
                    assert!(
                        !line_key.contains(['.', '"', '\'']),
                        "dotted or quoted key `{line_key}`: extend the scanner"
                    );
                }
            }
        }
        match b[i] {
            b'\n' => at_line_start = true,
            b'#' => {
                i = line_end(i);
                continue;
            }
            q @ (b'"' | b'\'') => {
                let triple = text[i..].starts_with(if q == b'"' { "\"\"\"" } else { "'''" });
                let close = if triple { 3 } else { 1 };
                let mut j = i + close;
                while j < b.len() {
                    if q == b'"' && b[j] == b'\\' {
                        j += 2;
                        continue;
                    }
                    if b[j] == q && (!triple || text[j..].starts_with(&text[i..i + 3])) {
                        break;
                    }
                    j += 1;
                }
                i = j + close;
                continue;
            }
            b'[' => stack.push(b'['),
            b'{' => {
                let empty = text[i + 1..].trim_start().starts_with('}');
                let path = stack.is_empty().then(|| {
                    if table.is_empty() {
                        line_key.clone()
                    } else {
                        format!("{table}.{line_key}")
                    }
                });
                found.push(Table {
                    place: Place::Inline(i + 1, empty),
                    path,
                });
                stack.push(b'{');
            }
            b']' | b'}' => {
                stack.pop();
            }
            _ => {}
        }
        i += 1;
    }
    // Tables named only as the prefix of a header (`chain` of `[[chain.sections]]` without a
    // `[chain]`).
    let defined: Vec<&str> = headers.iter().map(|(n, _)| n.as_str()).collect();
    let mut implicit: Vec<String> = Vec::new();
    for (name, _) in &headers {
        let parts: Vec<&str> = name.split('.').map(str::trim).collect();
        for k in 1..parts.len() {
            let prefix = parts[..k].join(".");
            if !defined.contains(&prefix.as_str()) && !implicit.contains(&prefix) {
                implicit.push(prefix);
            }
        }
    }
    for prefix in implicit {
        found.push(Table {
            place: Place::Append,
            path: Some(prefix),
        });
    }
    found
}

/// `text` with `key = value` in table `t`.
fn with_key(text: &str, t: &Table, key: &str, value: &str) -> String {
    match t.place {
        Place::Line(at) => {
            let newline = if at > 0 && !text[..at].ends_with('\n') {
                "\n"
            } else {
                ""
            };
            format!("{}{newline}{key} = {value}\n{}", &text[..at], &text[at..])
        }
        Place::Inline(at, empty) => {
            let sep = if empty { " " } else { "," };
            format!("{} {key} = {value}{sep}{}", &text[..at], &text[at..])
        }
        Place::Append => format!(
            "{text}\n[{}]\n{key} = {value}\n",
            t.path.as_deref().unwrap()
        ),
    }
}

/// A key that is in no table of the scene and sweep schemas (every key name of both, read from
/// the schemas the key reference is generated from, `keys::key_names`).
fn unknown_key() -> impl Strategy<Value = String> {
    let known = super::keys::key_names();
    "[a-z][a-z0-9_-]{0,11}".prop_filter("a key of the schema", move |k| !known.contains(k))
}

/// A value of any TOML type (an unknown key is refused whatever its value).
fn any_value() -> impl Strategy<Value = String> {
    prop_oneof![
        any::<i32>().prop_map(|x| x.to_string()),
        (-1e6f64..1e6).prop_map(|x| format!("{x:?}")),
        any::<bool>().prop_map(|x| x.to_string()),
        "[a-z ]{0,8}".prop_map(|s| format!("\"{s}\"")),
        Just("[1, 2]".to_string()),
        Just("{ x = 1 }".to_string()),
        Just("{}".to_string()),
    ]
}

/// The shipped scenes and sweeps, relative to the crate root, with the command that checks
/// each.
fn shipped_files() -> Vec<(String, bool)> {
    let mut files = Vec::new();
    for (dir, sweep) in [
        ("scenes", false),
        ("scenes/containers", false),
        ("studies", true),
    ] {
        let mut names: Vec<String> = std::fs::read_dir(Path::new(ROOT).join(dir))
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".toml"))
            .collect();
        names.sort();
        files.extend(names.into_iter().map(|n| (format!("{dir}/{n}"), sweep)));
    }
    files
}

/// A folder for the mutated copies: `studies/` for the sweeps, beside a copy of the crate's
/// `scenes/containers/` so that a sweep's paths (`../scenes/...`) resolve from the copy as from
/// the original (a copy whose unknown key were ignored would pass its check), and `scenes/`
/// for the scenes (a scene's copy is written as `scenes/<name with / as ->`, never into the
/// container copies the sweeps read).
fn mirror() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let containers = dir.path().join("scenes/containers");
    std::fs::create_dir_all(&containers).unwrap();
    std::fs::create_dir(dir.path().join("studies")).unwrap();
    for e in std::fs::read_dir(Path::new(ROOT).join("scenes/containers")).unwrap() {
        let e = e.unwrap();
        std::fs::copy(e.path(), containers.join(e.file_name())).unwrap();
    }
    dir
}

/// Where the copy of shipped `file` goes in a [`mirror`].
fn copy_of(dir: &Path, file: &str, sweep: bool) -> std::path::PathBuf {
    if sweep {
        dir.join(file)
    } else {
        dir.join("scenes").join(file.replace('/', "-"))
    }
}

/// `check` (a scene) or `study --check` (a sweep) of `file`: exit code and stderr.
fn check_file(file: &Path, sweep: bool) -> (Option<i32>, String) {
    let f = file.to_str().unwrap();
    if sweep {
        grainchain(&["study", f, "--check"])
    } else {
        grainchain(&["check", f])
    }
}

/// The copies the property test mutates check as the shipped files do (exit 0): what it finds
/// is the inserted key's doing, and each file has the tables the scanner finds.
#[test]
fn unknown_key_harness_copies_pass_their_check() {
    let dir = mirror();
    let mut count = 0;
    for (file, sweep) in shipped_files() {
        let copy = copy_of(dir.path(), &file, sweep);
        std::fs::write(
            &copy,
            std::fs::read_to_string(Path::new(ROOT).join(&file)).unwrap(),
        )
        .unwrap();
        let (code, stderr) = check_file(&copy, sweep);
        assert_eq!(code, Some(0), "{file}: {stderr}");
        count += tables(&std::fs::read_to_string(&copy).unwrap()).len();
    }
    // Every shipped file has at least its root and one more table.
    let files = shipped_files().len();
    record_one(
        Row::new(
            "unknown keys in every table (issue 24, item 3)",
            format!("{count} tables (root, [tables], [[array]] entries, inline tables) of the {files} shipped scenes and sweeps, a random unknown key each, 3 cases"),
            "validation/bad_input.rs unknown_key_in_any_table_is_refused",
        )
        .expected("exit 2 from check / study --check, naming file, table path and key")
        .measured("see unknown_key_in_any_table_is_refused (a miss fails it); the unmutated copies pass their check")
        .tolerance("exact")
        .info(),
    );
    assert!(count > 2 * files, "{count} tables");
}

proptest! {
    // Each case checks every table of every shipped file (about 300 runs of the binary, a few
    // milliseconds each, since a refused file stops at parsing): 3 cases, a few seconds.
    #![proptest_config(fuzz_config(3))]

    /// Issue 24, item 3: a random unknown key (random value) in any table of any shipped scene
    /// or sweep (the root, `[table]`s, each `[[array]]` entry, each inline table: ends, walls,
    /// media, perturbations, snapshot and horizon settings ...) is refused by `check` /
    /// `study --check` with exit code 2, naming the file and the key with its table's path.
    #[test]
    fn unknown_key_in_any_table_is_refused(
        keys in prop::collection::vec((unknown_key(), any_value()), 64)
    ) {
        let dir = mirror();
        let mut n = 0;
        for (file, sweep) in shipped_files() {
            let text = std::fs::read_to_string(Path::new(ROOT).join(&file)).unwrap();
            let copy = copy_of(dir.path(), &file, sweep);
            for t in tables(&text) {
                let (key, value) = &keys[n % keys.len()];
                n += 1;
                std::fs::write(&copy, with_key(&text, &t, key, value)).unwrap();
                let (code, stderr) = check_file(&copy, sweep);
                let named = match t.path.as_deref() {
                    Some("") => format!("key `{key}`"),
                    Some(p) => format!("key `{p}.{key}`"),
                    None => format!("`{key}`"),
                };
                let head = format!("error: {}: ", copy.display());
                prop_assert_eq!(code, Some(2), "{} {:?} += {} = {}: {}", file, t, key, value, stderr);
                prop_assert!(
                    stderr.starts_with(&head) && stderr.contains(&named)
                        && stderr.contains(&format!("unknown field `{key}`")),
                    "{} {:?} += {} = {}: wanted {} and {}: {}", file, t, key, value, head, named, stderr
                );
            }
        }
    }
}

/// Issue 38, items 8-11: inputs beyond a scene file's keys. Each gives exit 2 and a message that
/// names what to change, and writes nothing:
/// - a path to a device that never ends (`/dev/zero`) is refused after the input limit, not read
///   until the memory runs out;
/// - `reproduce` where no `scenes/` folder is names `--scenes`; `--snapshots` beyond a scene's
///   most output times names `--snapshots`, not a scene's key;
/// - design files with extreme materials (a density of 1e300, a modulus of 1e-300) name the
///   material; candidates of 1 um and 1 m name the diameters and the step bound (they ran for
///   minutes); 1000 diameters over the 255 pairs blame the diameters, not the materials.
#[test]
fn inputs_beyond_the_scene_keys_are_refused_with_their_name() {
    let d = tempfile::tempdir().unwrap();
    let design = |name: &str, materials: &str, diameters: &str| {
        let p = d.path().join(format!("{name}.toml"));
        std::fs::write(
            &p,
            format!(
                "[space]\nbeads = 8\nmaterials = {materials}\ndiameters = {diameters}\n\n\
                 [load]\nstriker = {{ material = \"steel\", diameter = 0.006 }}\nspeeds = [1.0]\n"
            ),
        )
        .unwrap();
        p.to_str().unwrap().to_string()
    };
    let many: Vec<String> = (0..1000)
        .map(|i| format!("{}", 0.001 + 1e-6 * i as f64))
        .collect();
    let out = d.path().join("never-written");
    let out = out.to_str().unwrap();
    let cases: Vec<(String, Vec<String>, &Path, &str)> = vec![
        (
            "/dev/zero as a scene".into(),
            vec!["check".into(), "/dev/zero".into()],
            Path::new(ROOT),
            "error: /dev/zero: cannot read: longer than 100.0 MB",
        ),
        (
            "reproduce outside the repository".into(),
            vec!["reproduce".into(), "--out".into(), out.into()],
            d.path(),
            "error: scenes: key `--scenes`: cannot read the paper's scene folder",
        ),
        (
            "reproduce --snapshots 1e11".into(),
            vec![
                "reproduce".into(),
                "--snapshots".into(),
                "100000000000".into(),
                "--out".into(),
                out.into(),
            ],
            Path::new(ROOT),
            "error: invalid value '100000000000' for '--snapshots <SNAPSHOTS>'",
        ),
        (
            "design, density 1e300".into(),
            vec![
                "design".into(),
                design(
                    "rho",
                    "[\"steel\", { E = 1e9, nu = 0.3, rho = 1e300 }]",
                    "[0.006]",
                ),
                "--out".into(),
                out.into(),
            ],
            Path::new(ROOT),
            "key `space.materials[1]`: density rho must lie in [1, 100000] kg/m^3",
        ),
        (
            "design, modulus 1e-300".into(),
            vec![
                "design".into(),
                design(
                    "e",
                    "[\"steel\", { E = 1e-300, nu = 0.3, rho = 1000 }]",
                    "[0.006]",
                ),
                "--out".into(),
                out.into(),
            ],
            Path::new(ROOT),
            "key `space.materials[1]`: Young's modulus E must lie in [1e3, 1e13] Pa",
        ),
        (
            "design, diameters 1 um and 1 m".into(),
            vec![
                "design".into(),
                design("d", "[\"steel\"]", "[1e-6, 1.0]"),
                "--out".into(),
                out.into(),
            ],
            Path::new(ROOT),
            "key `space.diameters`: a column of these candidates could need up to",
        ),
        (
            "design, 1000 diameters".into(),
            vec![
                "design".into(),
                design("many", "[\"steel\"]", &format!("[{}]", many.join(", "))),
                "--out".into(),
                out.into(),
            ],
            Path::new(ROOT),
            "key `space.diameters`: at most 255 (material, diameter) pairs",
        ),
    ];
    let mut all = true;
    for (what, args, dir, want) in &cases {
        let o = Command::new(BIN)
            .args(args)
            .current_dir(dir)
            .output()
            .expect("run grainchain");
        let stderr = String::from_utf8_lossy(&o.stderr);
        let ok = o.status.code() == Some(2)
            && stderr.contains(want)
            && !stderr.contains("panicked")
            && !Path::new(out).exists();
        all &= ok;
        record_one(
            Row::new(
                "input beyond a scene's keys",
                what,
                "validation/bad_input.rs",
            )
            .expected(format!("exit 2: {want}"))
            .measured(format!(
                "exit {:?}: {}",
                o.status.code(),
                stderr.lines().next().unwrap_or("")
            ))
            .tolerance("exact exit code, message contains the text, nothing written")
            .pass(ok),
        );
    }
    assert!(all, "see the rows of `input beyond a scene's keys`");
}

/// Issue 39, item 1 (the reads): `check`, `run` and `export lammps` read their scene file once,
/// so a scene given as a named pipe (or `<(cat scene.toml)`, the same thing to the program) is
/// read as a file. 3b774f2 read it three times: `check` refused it with "missing field `chain`"
/// (the second read found the pipe empty), and a named FIFO hung (the second open waited for a
/// writer). Each command gets 60 s (the scene runs in milliseconds) before it counts as hung.
#[test]
fn a_scene_given_as_a_named_pipe_is_read_once() {
    let d = tempfile::tempdir().unwrap();
    let scene = std::fs::read(Path::new(ROOT).join("scenes/single-solitary-wave.toml")).unwrap();
    let out = d.path().join("out");
    let export = d.path().join("deck");
    // Each command's arguments around the scene's path.
    let cases: [(&str, &[&str], Vec<&str>); 3] = [
        ("check", &["check"], vec![]),
        ("run", &["run"], vec!["--out", out.to_str().unwrap()]),
        (
            "export lammps",
            &["export", "lammps"],
            vec!["--out", export.to_str().unwrap()],
        ),
    ];
    let mut all = true;
    for (i, (what, before, after)) in cases.iter().enumerate() {
        let fifo = d.path().join(format!("scene-{i}.toml"));
        let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
        // SAFETY: a valid NUL-terminated path; mkfifo only creates the node.
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0, "mkfifo");
        let mut child = Command::new(BIN)
            .args(*before)
            .arg(&fifo)
            .args(after)
            .current_dir(ROOT)
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .expect("run grainchain");
        // The writer: one open, the whole file, closed (a second read finds no writer).
        let (path, bytes) = (fifo.clone(), scene.clone());
        std::thread::spawn(move || {
            if let Ok(mut f) = std::fs::OpenOptions::new().write(true).open(&path) {
                use std::io::Write;
                let _ = f.write_all(&bytes);
            }
        });
        let start = std::time::Instant::now();
        let status = loop {
            if let Some(s) = child.try_wait().unwrap() {
                break Some(s);
            }
            if start.elapsed().as_secs() > 60 {
                child.kill().unwrap();
                child.wait().unwrap();
                break None;
            }
            std::thread::sleep(std::time::Duration::from_millis(20));
        };
        let mut stderr = String::new();
        use std::io::Read;
        child
            .stderr
            .take()
            .unwrap()
            .read_to_string(&mut stderr)
            .unwrap();
        let ok = status.is_some_and(|s| s.success());
        all &= ok;
        record_one(
            Row::new(
                "a scene given as a named pipe",
                *what,
                "validation/bad_input.rs",
            )
            .expected("exit 0: the file read once")
            .measured(match status {
                Some(s) => format!("exit {:?} {}", s.code(), stderr.trim()),
                None => "hung (killed after 60 s)".to_string(),
            })
            .tolerance("exact exit code")
            .pass(ok),
        );
    }
    assert!(all, "see the rows of `a scene given as a named pipe`");
}

/// Issue 39, item 2: a bad material or diameter has one message, the engine's validator's
/// (`Material::named`, `Material::explicit`, `diameter_problem`), whether a scene file, a design
/// file or the protector's library call gives it; each adds only where (file and key, or which
/// bead). Python's errors carry the same text (`python/tests/test_protector.py`).
#[test]
fn a_bad_material_or_diameter_has_one_message_everywhere() {
    use grainchain::design::file::{DesignFile, DesignSpec};
    use grainchain_engine::protector::{evaluate, Bead, Impact, Protected, Settings};
    use grainchain_engine::units::{diameter_problem, Material, STEEL};
    let scene = |material: &str, diameter: &str| {
        format!(
            "[chain]\nright = {{ kind = \"wall\", material = \"steel\" }}\n\n[[chain.sections]]\n\
             count = 4\nmaterial = {material}\ndiameter = {diameter}\n\n[striker]\nend = \"left\"\n\
             material = \"steel\"\ndiameter = 0.006\nspeed = 1.0\n\n[integrator]\ndt = 1e-8\n\n\
             [run]\nduration = 1e-6\noutput_interval = 1e-7\n"
        )
    };
    let design = |material: &str, diameter: &str| {
        format!(
            "[space]\nbeads = 2\nmaterials = [{material}]\ndiameters = [{diameter}]\n\n[load]\n\
             striker = {{ material = \"steel\", diameter = 0.006 }}\nspeeds = [1.0]\n"
        )
    };
    let scene_error = |text: String| {
        Scene::parse(&text, Path::new("m.toml"))
            .err()
            .map(|e| e.to_string())
    };
    let design_error = |text: String| {
        let file: DesignFile = toml::from_str(&text).expect("the design file parses");
        DesignSpec::check("d.toml".into(), file)
            .err()
            .map(|e| e.to_string())
    };
    let impact = Impact {
        striker: Bead {
            material: STEEL,
            diameter: 6e-3,
        },
        speed: 1.0,
        restitution: None,
        restitution_pairs: Vec::new(),
    };
    let library_error = |bead: Bead| {
        evaluate(
            &[bead],
            &impact,
            &Protected::Wall(STEEL),
            &Settings::default(),
        )
        .err()
        .map(|e| e.to_string())
    };
    let mut checked = 0;
    // (the material as a file gives it, the material as the library takes it, the validator's
    // verdict)
    let materials = [
        (
            "{ E = 1e9, nu = 0.3, rho = 1e300 }",
            Some(Material::custom(1e300, 1e9, 0.3)),
            Material::explicit(None, 1e9, 0.3, 1e300),
        ),
        (
            "{ E = 1e-300, nu = 0.3, rho = 1000 }",
            Some(Material::custom(1000.0, 1e-300, 0.3)),
            Material::explicit(None, 1e-300, 0.3, 1000.0),
        ),
        (
            "{ E = 1e9, nu = 0.7, rho = 1000 }",
            Some(Material::custom(1000.0, 1e9, 0.7)),
            Material::explicit(None, 1e9, 0.7, 1000.0),
        ),
        (
            "{ E = 1e9, nu = 0.3, rho = 1000, name = \"ptfe\" }",
            None,
            Material::explicit(Some("ptfe"), 1e9, 0.3, 1000.0),
        ),
        (
            "{ E = 1e9, nu = 0.3, rho = 1000, name = \"\" }",
            None,
            Material::explicit(Some(""), 1e9, 0.3, 1000.0),
        ),
        ("\"unobtainium\"", None, Material::named("unobtainium")),
    ];
    for (toml, material, verdict) in materials {
        let want = verdict.expect_err(toml);
        assert_eq!(
            scene_error(scene(toml, "0.006")),
            Some(format!("m.toml: key `chain.sections[0].material`: {want}")),
            "{toml}"
        );
        assert_eq!(
            design_error(design(toml, "0.006")),
            Some(format!("d.toml: key `space.materials[0]`: {want}")),
            "{toml}"
        );
        if let Some(material) = material {
            let bead = Bead {
                material,
                diameter: 6e-3,
            };
            assert_eq!(
                library_error(bead),
                Some(format!("bead 1: {want}")),
                "{toml}"
            );
        }
        checked += 1;
    }
    // (the diameter as a file gives it, as a number)
    for (toml, d) in [
        ("0.0", 0.0),
        ("6.0", 6.0),
        ("1e-300", 1e-300),
        ("nan", f64::NAN),
        ("-inf", f64::NEG_INFINITY),
    ] {
        let want = diameter_problem(d).expect(toml);
        assert_eq!(
            scene_error(scene("\"steel\"", toml)),
            Some(format!("m.toml: key `chain.sections[0].diameter`: {want}")),
            "{toml}"
        );
        assert_eq!(
            design_error(design("\"steel\"", toml)),
            Some(format!("d.toml: key `space.diameters[0]`: {want}")),
            "{toml}"
        );
        let bead = Bead {
            material: STEEL,
            diameter: d,
        };
        assert_eq!(
            library_error(bead),
            Some(format!("bead 1: {want}")),
            "{toml}"
        );
        checked += 1;
    }
    // The good ones pass all three (the test above could not fail by refusing everything).
    assert_eq!(
        scene_error(scene(
            "{ E = 1e9, nu = 0.3, rho = 1000, name = \"soft\" }",
            "0.006"
        )),
        None
    );
    assert_eq!(
        design_error(design("{ E = 1e9, nu = 0.3, rho = 1000 }", "0.006")),
        None
    );
    record_one(
        Row::new(
            "one message per bad material or diameter",
            format!("{checked} bad values in a scene file, a design file and protector::evaluate"),
            "validation/bad_input.rs",
        )
        .expected("the engine's validator's message, with only the file and key (or bead) added")
        .measured("the same text from all three")
        .tolerance("exact text")
        .pass(true),
    );
}

/// One name, two sets of constants: outputs tell materials apart by name alone, so a design file
/// that names two different materials alike is refused, among its candidates and between a
/// candidate and the striker or the wall; the same material given twice is not.
#[test]
fn a_design_file_names_each_material_once() {
    use grainchain::design::file::{DesignFile, DesignSpec};
    let check = |materials: &str, striker: &str, wall: &str| {
        let text = format!(
            "[space]\nbeads = 2\nmaterials = [{materials}]\ndiameters = [0.006]\n\n[load]\n\
             striker = {{ material = {striker}, diameter = 0.006 }}\nspeeds = [1.0]\nwall = {wall}\n"
        );
        let file: DesignFile = toml::from_str(&text).expect("the design file parses");
        DesignSpec::check("d.toml".into(), file)
            .err()
            .map(|e| e.to_string())
    };
    let soft = r#"{ E = 1.5e9, nu = 0.46, rho = 2200, name = "soft" }"#;
    let other = r#"{ E = 3e9, nu = 0.4, rho = 1200, name = "soft" }"#;
    let clash = |e: Option<String>, key: &str, like: &str| {
        let e = e.expect("refused");
        assert!(
            e.contains(&format!("key `{key}`"))
                && e.contains(&format!("like {like}, with other constants")),
            "{e}"
        );
    };
    clash(
        check(&format!("{soft}, {other}"), "\"steel\"", "\"steel\""),
        "space.materials[1]",
        "space.materials[0]",
    );
    clash(
        check(soft, other, "\"steel\""),
        "load.striker.material",
        "space.materials[0]",
    );
    clash(
        check(soft, "\"steel\"", other),
        "load.wall",
        "space.materials[0]",
    );
    // The same material twice, by name and by constants, is one material.
    assert_eq!(check(&format!("{soft}, \"ptfe\""), soft, soft), None);
}
