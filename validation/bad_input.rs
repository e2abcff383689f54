//! Bad input: malformed scene files run through the real binary must fail with their exact
//! error message ("FILE: key `KEY`: message") and exit code 2, never panic, and never leave an
//! output file behind; a property test fuzzes the scene parser.

use crate::common;

use common::{record_one, Row};
use grainchain::scene::Scene;
use proptest::prelude::*;
use proptest::test_runner::{Config, FileFailurePersistence, RngSeed};
use rstest::rstest;
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

/// Check 13a: each file under validation/bad_scenes/ (its first line says what is wrong with it)
/// gives exactly this message and exit code 2, from `check` and from `run`; `run` creates no
/// output directory.
#[rstest]
#[case(
    "dt-too-small.toml",
    "key `integrator.dt`: dt = 1e-14 needs more than 1e12 steps per output interval (0.5)"
)]
#[case(
    "duplicate-key.toml",
    "key `chain.sections[0].mass` (line 6, column 1): duplicate key"
)]
#[case(
    "duration-infinite.toml",
    "key `run.duration`: must be a finite number > 0, got inf"
)]
#[case(
    "empty-file.toml",
    "key `chain` (line 1, column 1): missing field `chain`"
)]
#[case(
    "exponent-below-one.toml",
    "key `chain.sections[0].p`: exponent must be a finite number >= 1, got 0.5"
)]
#[case(
    "initial-grain-and-range.toml",
    "key `initial[0]`: give either `grain`, or both `first` and `last`"
)]
#[case(
    "initial-outside-chain.toml",
    "key `initial[0].first`: grain 11 is outside the chain (grains 0 to 10)"
)]
#[case(
    "initial-grain-outside-chain.toml",
    "key `initial[0].grain`: grain 11 is outside the chain (grains 0 to 10)"
)]
#[case(
    "initial-without-value.toml",
    "key `initial[0]`: give a `velocity` or a `displacement`"
)]
#[case("interface-unknown.toml", "key `chain.interface` (line 3, column 13): unknown variant `middle`, expected one of `min-exponent`, `max-exponent`, `left`, `right`")]
#[case(
    "interval-longer-than-duration.toml",
    "key `run.output_interval`: must be at most run.duration (1), got 2"
)]
#[case(
    "mass-is-a-string.toml",
    "key `chain.sections[0].mass` (line 5, column 8): invalid type: string \"heavy\", expected f64"
)]
#[case(
    "missing-run-duration.toml",
    "key `run` (line 14, column 1): missing field `duration`"
)]
#[case(
    "nan-stiffness.toml",
    "key `chain.sections[0].eta`: must be a finite number > 0, got NaN"
)]
#[case(
    "negative-count.toml",
    "key `chain.sections[0].count` (line 4, column 9): invalid value: integer `-5`, expected u64"
)]
#[case(
    "negative-dt.toml",
    "key `integrator.dt`: must be a finite number > 0, got -0.0001"
)]
#[case(
    "negative-mass.toml",
    "key `chain.sections[0].mass`: must be a finite number > 0, got -1"
)]
#[case(
    "negative-precompression.toml",
    "key `chain.sections[0].delta0`: must be a finite number >= 0, got -0.1"
)]
#[case(
    "no-sections.toml",
    "key `chain.sections`: the chain needs at least one section"
)]
#[case("precompression-unbalanced.toml", "key `chain`: precompression is not in equilibrium at grain 10: the contact forces on its two sides are 5.657 and 16.000412244689198; give every contact the same static force eta*delta0^p")]
#[case(
    "precompression-without-walls.toml",
    "key `chain.left`: precompression (delta0 > 0) needs walls at both ends to hold it"
)]
#[case(
    "pulse-threshold-out-of-range.toml",
    "key `output.pulses.threshold`: must be between 0 and 1, got 1.5"
)]
#[case(
    "section-duplicate-name.toml",
    "key `chain.sections[1].name`: section `heavy` is named twice (names must be unique)"
)]
#[case(
    "region-duplicate.toml",
    "key `regions[1].name`: region `r` is defined twice"
)]
#[case(
    "region-name-comma.toml",
    "key `regions[0].name`: must be a non-empty name without commas"
)]
#[case(
    "region-outside-chain.toml",
    "key `regions[0].last`: grain 20 is outside the chain (grains 0 to 10)"
)]
#[case(
    "region-reversed.toml",
    "key `regions[0].last`: last (3) is before first (8)"
)]
#[case(
    "sleep-negative.toml",
    "key `integrator.sleep.velocity`: must be a finite number >= 0, got -1"
)]
#[case(
    "horizon-dopri5.toml",
    "key `run.horizon`: needs a fixed-step method that resets margin grains (verlet, blanes-moan4 or multirate), not dopri5"
)]
#[case(
    "horizon-speed-negative.toml",
    "key `run.horizon.speed`: must be a finite number > 0, got -1"
)]
#[case(
    "sleep-gear5.toml",
    "key `integrator.sleep`: the sleep rule needs a splitting method (verlet or blanes-moan4), not gear5"
)]
#[case(
    "damping-negative.toml",
    "key `chain.sections[0].damping`: must be a finite number >= 0, got -0.5"
)]
#[case(
    "contact-damping-gear5.toml",
    "key `chain.sections[0].contact_damping`: damping needs a splitting method (verlet or blanes-moan4), not gear5"
)]
#[case(
    "contact-damping-negative.toml",
    "key `chain.sections[0].contact_damping.c`: must be a finite number >= 0, got -0.5"
)]
#[case(
    "outer-without-outer-chains.toml",
    "key `chain.outer`: an outer medium needs a section named `outer-left` (the container contract of scenes/containers/)"
)]
#[case(
    "contact-damping-model.toml",
    "key `chain.sections[0]` (line 3, column 1): unknown variant `coulomb`, expected one of `viscous`, `kuwabara-kono`, `scale-respecting`"
)]
#[case(
    "damping-adaptive.toml",
    "key `chain.sections[1].damping`: damping needs a splitting method (verlet or blanes-moan4), not dopri5"
)]
#[case(
    "snapshot-every-zero.toml",
    "key `output.snapshots.every`: must be at least 1"
)]
#[case(
    "snapshot-no-fields.toml",
    "key `output.snapshots.fields`: name at least one field"
)]
#[case("snapshot-unknown-field.toml", "key `output.snapshots` (line 19, column 25): unknown variant `temperature`, expected one of `velocity`, `displacement`, `force`, `overlap`, `energy`, `mass`")]
#[case(
    "striker-at-wall.toml",
    "key `striker.end`: that end of the chain is a wall; a striker needs a free end"
)]
#[case(
    "striker-end-unknown.toml",
    "key `striker.end` (line 10, column 7): unknown variant `top`, expected `left` or `right`"
)]
#[case(
    "striker-half-law.toml",
    "key `striker`: give both `p` and `eta` for the striker's contact, or neither"
)]
#[case(
    "striker-speed-zero.toml",
    "key `striker.speed`: must be a finite number > 0, got 0"
)]
#[case(
    "sweep-file.toml",
    "this is a sweep file, not a scene (run it with `grainchain study`)"
)]
#[case(
    "syntax-error.toml",
    "key `striker` (line 9, column 9): unclosed table, expected `]`"
)]
#[case("tension-nonlinear.toml", "key `chain.sections[0].tension`: a two-sided (tension) contact must be linear (p = 1), got p = 1.5")]
#[case(
    "tolerance-for-fixed-step.toml",
    "key `integrator.rtol`: tolerances apply to adaptive methods only; verlet takes a fixed dt"
)]
#[case(
    "too-much-memory.toml",
    "key `chain.sections[0].count`: 50000001 grains would need about 10.5 GB of memory (estimated, 210 bytes per grain), over the limit of 1.0 GB; use fewer grains, or pass --allow-large-output"
)]
#[case(
    "too-many-grains.toml",
    "key `chain.sections[0].count`: the chain may have at most 100000000 grains"
)]
#[case("unknown-method.toml", "key `integrator.method` (line 19, column 10): unknown variant `rk4`, expected one of `verlet`, `blanes-moan4`, `gear5`, `dopri5`, `multirate`")]
#[case("unknown-run-key.toml", "key `run.colour` (line 17, column 1): unknown field `colour`, expected one of `duration`, `output_interval`, `horizon`")]
#[case(
    "unknown-section-key.toml",
    "key `chain.sections[0]` (line 3, column 1): missing field `mass`"
)]
#[case("unknown-top-level-key.toml", "key `colour` (line 2, column 1): unknown field `colour`, expected one of `name`, `description`, `chain`, `striker`, `initial`, `integrator`, `run`, `regions`, `output`")]
#[case(
    "wall-kind-unknown.toml",
    "key `chain.right` (line 3, column 18): unknown variant `sticky`, expected `free` or `wall`"
)]
#[case("zero-count.toml", "key `chain.sections[0].count`: must be at least 1")]
#[case(
    "name-escapes.toml",
    "key `name`: must be a plain folder name, without `/`, `\\` or control characters (it names the output folder out/<name>)"
)]
#[case(
    "name-empty.toml",
    "key `name`: must not be empty (it names the output folder out/<name>)"
)]
#[case(
    "zero-stiffness.toml",
    "key `chain.sections[0].eta`: must be a finite number > 0, got 0"
)]
fn bad_scene_file(#[case] file: &str, #[case] message: &str) {
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
    // bytes per row: NUMBER_BYTES and INTEGER_BYTES in src/scene/mod.rs).
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
    // 4.5e6 grains: under the memory limit (945 MB estimated) and long enough to check (about
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
            if scene.grains <= 100_000 {
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
