//! Outputs a user can trust: an output folder belongs to one command on one set of inputs (a
//! second run of another scene into it is refused, a rerun of the same one replaces its files,
//! two runs at once cannot mix their files, `--force` clears), and the command lines that used to
//! be accepted with a meaningless effect are refused.

use crate::common::{err, s};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const BIN: &str = env!("CARGO_BIN_EXE_grainchain");
const ROOT: &str = env!("CARGO_MANIFEST_DIR");

fn grainchain(args: &[&str]) -> Output {
    Command::new(BIN)
        .args(args)
        .current_dir(ROOT)
        .output()
        .expect("run grainchain")
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("grainchain-outputs-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| !n.starts_with('.'))
        .collect();
    v.sort();
    v
}

/// A second `run` of another scene into a used folder is refused (exit 2, naming the folder and
/// why) and leaves it as it was; the same scene again replaces its files; `--force` clears the
/// folder and writes only the new run's files.
#[test]
fn a_used_folder_is_refused_unless_it_is_the_same_run() {
    let out = tmp("reuse");
    let o = grainchain(&["run", "scenes/single-solitary-wave.toml", "--out", s(&out)]);
    assert!(o.status.success(), "{}", err(&o));
    let first = names(&out);
    assert!(
        first.contains(&"pulses.csv".to_string()) && first.contains(&"manifest.json".to_string())
    );
    let energies = std::fs::read(out.join("energies.csv")).unwrap();

    let o = grainchain(&["run", "scenes/linear-spring-chain.toml", "--out", s(&out)]);
    assert_eq!(o.status.code(), Some(2), "{}", err(&o));
    assert!(
        err(&o).contains("not an output folder of this command") && err(&o).contains("--force"),
        "{}",
        err(&o)
    );
    assert_eq!(names(&out), first);
    assert_eq!(std::fs::read(out.join("energies.csv")).unwrap(), energies);

    let o = grainchain(&["run", "scenes/single-solitary-wave.toml", "--out", s(&out)]);
    assert!(o.status.success(), "the same run again: {}", err(&o));
    assert_eq!(names(&out), first);

    let o = grainchain(&[
        "run",
        "scenes/linear-spring-chain.toml",
        "--out",
        s(&out),
        "--force",
    ]);
    assert!(o.status.success(), "{}", err(&o));
    let second = names(&out);
    // The linear chain writes no pulses: nothing of the first run is left beside the second.
    assert!(!second.contains(&"pulses.csv".to_string()), "{second:?}");
    assert_ne!(std::fs::read(out.join("energies.csv")).unwrap(), energies);

    // A folder grainchain did not write is never touched without --force.
    let mine = tmp("mine");
    std::fs::create_dir_all(&mine).unwrap();
    std::fs::write(mine.join("thesis.tex"), "precious").unwrap();
    let o = grainchain(&["run", "scenes/single-solitary-wave.toml", "--out", s(&mine)]);
    assert_eq!(o.status.code(), Some(2), "{}", err(&o));
    assert!(err(&o).contains("no manifest.json"), "{}", err(&o));
    assert_eq!(
        std::fs::read_to_string(mine.join("thesis.tex")).unwrap(),
        "precious"
    );
    let _ = std::fs::remove_dir_all(&out);
    let _ = std::fs::remove_dir_all(&mine);
}

/// Two runs into one folder at once: the second fails at once with a clear message while the
/// first holds the folder, and the folder then holds exactly the first run's files.
#[test]
fn two_runs_at_once_do_not_mix() {
    let out = tmp("concurrent");
    // Fig. 3's scene runs for a few tenths of a second: long enough to start a second run while it
    // holds the lock (the second is started once the lock file exists).
    let first = Command::new(BIN)
        .args([
            "run",
            "scenes/fig3-standard-container.toml",
            "--out",
            s(&out),
        ])
        .current_dir(ROOT)
        .spawn()
        .unwrap();
    let lock = out.join(".grainchain.lock");
    let t0 = std::time::Instant::now();
    while !lock.exists() && t0.elapsed().as_secs() < 30 {
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    let second = grainchain(&[
        "run",
        "scenes/fig3-standard-container.toml",
        "--out",
        s(&out),
    ]);
    let first = first.wait_with_output().unwrap();
    assert!(first.status.success());
    // The second either found the lock held (the usual case) or, if the first had already
    // finished, ran as the same run again; it never mixes files.
    if !second.status.success() {
        assert!(
            err(&second).contains("another grainchain command is writing"),
            "{}",
            err(&second)
        );
    }
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("manifest.json")).unwrap()).unwrap();
    for (name, entry) in manifest["files"].as_object().unwrap() {
        let bytes = std::fs::read(out.join(name)).unwrap();
        assert_eq!(
            entry["size"].as_u64().unwrap(),
            bytes.len() as u64,
            "{name}"
        );
        assert_eq!(
            entry["fnv"].as_str().unwrap(),
            grainchain::report::fnv1a(&bytes),
            "{name}"
        );
    }
    let _ = std::fs::remove_dir_all(&out);
}

/// Command lines that were accepted with a meaningless effect are refused with exit code 2.
#[test]
fn meaningless_command_lines_are_refused() {
    let o = grainchain(&["reproduce", "--threads", "0", "--out", "/nonexistent/x"]);
    assert_eq!(o.status.code(), Some(2), "{}", err(&o));
    assert!(err(&o).contains("--threads"), "{}", err(&o));
    let o = grainchain(&["study", "studies/smoke.toml", "--merge", "--resume"]);
    assert_eq!(o.status.code(), Some(2), "{}", err(&o));
    assert!(err(&o).contains("--resume"), "{}", err(&o));
    let out = tmp("from");
    let o = grainchain(&[
        "study",
        "studies/smoke.toml",
        "--merge",
        "--out",
        s(&out),
        "--from",
        "/nonexistent/shard-folder",
    ]);
    assert_ne!(o.status.code(), Some(0), "{}", err(&o));
    assert!(
        err(&o).contains("/nonexistent/shard-folder/members"),
        "{}",
        err(&o)
    );
    let _ = std::fs::remove_dir_all(&out);
}

/// `work-precision --quick` printed `inf` for every solitary-wave point (its 300-grain run ended
/// before the wave reached the probe) and `0` for every container point (its 50 snapshots ended
/// before the wave entered the container), and exited 0. Every printed error is now a finite
/// number > 0, or the point says in words why it has none (`failed:` / `not evaluated:`).
#[test]
fn work_precision_quick_prints_only_meaningful_errors() {
    let out = tmp("wpq");
    let o = grainchain(&[
        "work-precision",
        "--quick",
        "--repeats",
        "1",
        "--out",
        s(&out),
    ]);
    assert!(o.status.success(), "{}", err(&o));
    let text = String::from_utf8_lossy(&o.stdout).into_owned();
    let mut rows = 0;
    // The points' table; the statistics problem's own table follows it.
    for line in text
        .lines()
        .skip(1)
        .take_while(|l| !l.starts_with("container-a-statistics"))
        .filter(|l| !l.starts_with("wrote "))
    {
        let cols: Vec<&str> = line.split_whitespace().collect();
        rows += 1;
        if cols[3] == "failed:" || cols[3] == "not" {
            panic!("a quick point has no error: {line}");
        }
        let error: f64 = cols[3]
            .parse()
            .unwrap_or_else(|_| panic!("error of {line}"));
        assert!(error.is_finite() && error > 0.0, "{line}");
    }
    // 8 points per problem (4 methods x 2 settings), container-a's scene-default and two
    // multirate points, and the order problems: 12 per collision (8, and the 2 splitting
    // methods with contact events x 2 settings), 24 for restitution (3 damping models x 2
    // splitting methods x 2 settings, with and without events), 9 for protector-40 (its
    // reference check, 2 splitting methods x 2 settings, with and without events).
    assert_eq!(rows, 27 + 12 + 12 + 24 + 9, "{text}");
    assert_csv_convention(&out.join("work_precision.csv"));
    let _ = std::fs::remove_dir_all(&out);
}

/// Small inconsistencies of issue 18 (item 11): `reproduce --members 1` printed intervals
/// "[NaN, NaN]" (a jackknife over one member) and is now refused (exit 2, saying why); `check`
/// said "16 output times" of a scene whose energies.csv has 17 rows (the initial state is one).
#[test]
fn counts_and_ensembles_say_what_they_mean() {
    let o = grainchain(&["reproduce", "--members", "1", "--out", "/nonexistent/never"]);
    assert_eq!(o.status.code(), Some(2), "{}", err(&o));
    assert!(
        err(&o).contains("an ensemble needs at least 2 members"),
        "{}",
        err(&o)
    );
    let o = grainchain(&["check", "scenes/single-solitary-wave.toml"]);
    assert!(o.status.success(), "{}", err(&o));
    let text = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(
        text.contains("16 output times after t = 0 (17 rows with the initial state)"),
        "{text}"
    );
    let out = tmp("rows");
    let o = grainchain(&["run", "scenes/single-solitary-wave.toml", "--out", s(&out)]);
    assert!(o.status.success(), "{}", err(&o));
    let rows = std::fs::read_to_string(out.join("energies.csv"))
        .unwrap()
        .lines()
        .count()
        - 1;
    assert_eq!(rows, 17);
    let _ = std::fs::remove_dir_all(&out);
}

/// Every field of a CSV file that is a number is in the one CSV form of grainchain
/// (`report::csv_number`: shortest round trip, exponent form below 1e-4 and from 1e15 on), and no
/// field is a spelled-out missing value (`NaN`, `none`, `inf`): missing is the empty field.
pub fn assert_csv_convention(path: &Path) {
    let text = std::fs::read_to_string(path).unwrap();
    for (r, line) in text.lines().enumerate().skip(1) {
        for field in line.split(',') {
            let lower = field.to_ascii_lowercase();
            assert!(
                !["nan", "none", "inf", "-inf"].contains(&lower.as_str()),
                "{}: row {r}: `{field}`",
                path.display()
            );
            if let Ok(x) = field.parse::<f64>() {
                assert_eq!(
                    grainchain::report::csv_number(x),
                    field,
                    "{}: row {r}",
                    path.display()
                );
            }
        }
    }
}

/// `run`'s CSV files follow the convention (they wrote `{:e}` everywhere: `5e3`, `0e0`, and NaN
/// for the speed of a one-point track).
#[test]
fn run_outputs_follow_the_csv_convention() {
    let out = tmp("csvform");
    let o = grainchain(&["run", "scenes/single-solitary-wave.toml", "--out", s(&out)]);
    assert!(o.status.success(), "{}", err(&o));
    let mut n = 0;
    for f in ["energies.csv", "snapshots.csv", "pulses.csv", "tracks.csv"] {
        if out.join(f).exists() {
            assert_csv_convention(&out.join(f));
            n += 1;
        }
    }
    assert!(n >= 3);
    let _ = std::fs::remove_dir_all(&out);
}

/// Issue 24, item 9: `units` refuses a diameter outside the physical range (it printed a mass of
/// 0 kg and a null time unit for 1e-300 m) naming the flag, exit 2; and it says which material
/// and eta it assumed.
#[test]
fn units_refuses_unphysical_diameters_and_names_its_material() {
    for d in ["1e-300", "1e300", "0", "-1", "nan"] {
        let o = grainchain(&["units", "--diameter", d]);
        assert_eq!(o.status.code(), Some(2), "--diameter {d}: {}", err(&o));
        assert!(err(&o).contains("--diameter"), "{}", err(&o));
    }
    let o = grainchain(&["units"]);
    assert!(o.status.success(), "{}", err(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["material"]["name"], "stainless steel (AISI 316-like)");
    assert_eq!(v["material"]["young"], 193e9);
    assert_eq!(v["eta_program"], 5657.0);
    assert!(v["time_s"].as_f64().is_some_and(|t| t > 0.0), "{v}");
}

/// Issue 24, item 11: `check` shows the step the run takes (0.05 fitted to an interval of 0.125
/// is 0.041666666666666664) and numbers of any size in a short form (dt = 1e300 was printed with
/// 301 digits, by `check` and by `run`'s note).
#[test]
fn check_shows_the_fitted_step_and_short_numbers() {
    let dir = tmp("fitted-step");
    std::fs::create_dir_all(&dir).unwrap();
    let scene = |dt: &str, interval: &str| {
        format!(
            "[chain]\n[[chain.sections]]\ncount = 20\nmass = 1.0\np = 1.5\neta = 5657.0\n\n\
             [striker]\nend = \"left\"\nmass = 1.0\nspeed = 1.0\n\n[integrator]\n\
             method = \"verlet\"\ndt = {dt}\n\n[run]\nduration = 1.0\noutput_interval = {interval}\n"
        )
    };
    let a = dir.join("a.toml");
    std::fs::write(&a, scene("0.05", "0.125")).unwrap();
    let o = grainchain(&["check", s(&a)]);
    let text = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(o.status.success(), "{}", err(&o));
    assert!(
        text.contains("verlet with dt 0.041666666666666664 (0.05 shortened"),
        "{text}"
    );
    let b = dir.join("b.toml");
    std::fs::write(&b, scene("1e300", "0.5")).unwrap();
    let o = grainchain(&["check", s(&b)]);
    let text = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(text.contains("with dt 0.5 (1e300 shortened"), "{text}");
    let o = grainchain(&["run", s(&b), "--out", s(&dir.join("out"))]);
    let all = format!("{text}{}", err(&o));
    assert!(all.contains("dt shortened from 1e300 to 0.5"), "{all}");
    // No number anywhere longer than the shortest round trip in exponent form.
    let longest = all
        .split(|c: char| !(c.is_ascii_digit() || c == '.'))
        .map(str::len)
        .max()
        .unwrap_or(0);
    assert!(longest <= 20, "a number of {longest} characters in\n{all}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 24, item 11: a blow-up time is printed as a number people can read (1.98e-20, not
/// 0.0000000000000000000198).
#[test]
fn blow_up_times_are_short() {
    let e = grainchain_engine::RunError::EnergyDrift {
        time: 1.98e-20,
        step: 3,
        rel: 2.0,
        bound: 1e-2,
        grain: 1,
    };
    assert!(
        e.to_string().contains("blow-up at t = 1.98e-20, step 3"),
        "{e}"
    );
}
