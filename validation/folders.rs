//! Output folders can never lose a user's files (issue 24, items 1 and 10): every command that
//! writes a folder, pointed with `--force` at a project folder, leaves every byte of it as it was;
//! a folder grainchain owns accepts nothing foreign, no link out of it, no shard beside a full
//! study; the temporaries of a killed run and the outputs of a failed write are cleaned up by the
//! next run. The rules themselves are unit-tested in `harness/src/report/outdir.rs`; here the release
//! binary is run on real folders.

use crate::common::{err, s};
use grainchain::report::outdir::OutDir;
use grainchain::study::SweepFile;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const BIN: &str = env!("CARGO_BIN_EXE_grainchain");
const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// Run the binary in `dir`.
fn grainchain_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(BIN)
        .args(args)
        .current_dir(dir)
        .output()
        .expect("run grainchain")
}

fn grainchain(args: &[&str]) -> Output {
    grainchain_in(Path::new(ROOT), args)
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("grainchain-folders-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn root(p: &str) -> String {
    Path::new(ROOT).join(p).display().to_string()
}

/// Every entry below `dir`, hidden ones included, with its kind and permissions, and a file's
/// bytes or a link's target: the folder byte for byte.
fn listing(dir: &Path) -> Vec<(String, String)> {
    use std::os::unix::fs::PermissionsExt;
    fn walk(d: &Path, base: &Path, v: &mut Vec<(String, String)>) {
        for e in std::fs::read_dir(d).unwrap() {
            let p = e.unwrap().path();
            let rel = p.strip_prefix(base).unwrap().display().to_string();
            let m = std::fs::symlink_metadata(&p).unwrap();
            let mode = m.permissions().mode();
            if m.is_symlink() {
                let to = std::fs::read_link(&p).unwrap();
                v.push((rel, format!("link -> {}", to.display())));
            } else if m.is_dir() {
                v.push((rel, format!("dir {mode:o}")));
                walk(&p, base, v);
            } else {
                let bytes = std::fs::read(&p).unwrap();
                v.push((
                    rel,
                    format!("file {mode:o} {}", String::from_utf8_lossy(&bytes)),
                ));
            }
        }
    }
    let mut v = Vec::new();
    walk(dir, dir, &mut v);
    v.sort();
    v
}

/// A project folder: sources, a README, the scene being run, a nested folder, a link to a file
/// in it and a link out of it.
fn project(name: &str) -> (PathBuf, PathBuf) {
    let p = tmp(name);
    let outside = tmp(&format!("{name}-outside"));
    std::fs::create_dir_all(p.join("src")).unwrap();
    std::fs::create_dir_all(p.join("nested/deeper")).unwrap();
    std::fs::create_dir_all(&outside).unwrap();
    std::fs::write(p.join("src/lib.rs"), "pub fn f() {}\n").unwrap();
    std::fs::write(p.join("README.md"), "# My project\n").unwrap();
    std::fs::copy(
        Path::new(ROOT).join("scenes/single-solitary-wave.toml"),
        p.join("scene.toml"),
    )
    .unwrap();
    std::fs::write(p.join("nested/deeper/notes.txt"), "notes\n").unwrap();
    std::fs::write(p.join("nested/energies.csv"), "t,E\n0,1\n").unwrap();
    std::fs::write(p.join(".hidden"), "dot file\n").unwrap();
    std::fs::write(outside.join("precious.csv"), "mine\n").unwrap();
    std::os::unix::fs::symlink("README.md", p.join("readme-link")).unwrap();
    std::os::unix::fs::symlink(&outside, p.join("members")).unwrap();
    (p, outside)
}

/// The acceptance test (item 1): every command that writes a folder, with `--out` a
/// project folder (and a folder in it) and `--force`, is refused with exit code 2, says what is
/// there and what to do (not `--force`), and leaves every byte of the project as it was, with no
/// lock file. `work-precision --quick --only collision` takes a fraction of a second (the claim
/// comes before any work), so every command is run.
#[test]
fn force_into_a_project_folder_keeps_every_byte() {
    let (p, outside) = project("project");
    let before = listing(&p);
    let outside_before = listing(&outside);
    let scenes = root("scenes");
    let sweep = root("studies/smoke.toml");
    for out in [".", "nested", "nested/deeper"] {
        let commands: Vec<Vec<&str>> = vec![
            vec!["run", "scene.toml", "--out", out, "--force"],
            vec!["run", "scene.toml", "--out", out],
            vec!["export", "lammps", "scene.toml", "--out", out, "--force"],
            vec!["study", &sweep, "--out", out, "--force", "--threads", "1"],
            vec!["study", &sweep, "--out", out, "--shard", "1/2", "--force"],
            vec!["study", &sweep, "--out", out, "--merge", "--force"],
            vec![
                "reproduce",
                "--only",
                "fig1",
                "--scenes",
                &scenes,
                "--threads",
                "1",
                "--out",
                out,
                "--force",
            ],
            vec![
                "work-precision",
                "--quick",
                "--only",
                "collision",
                "--repeats",
                "1",
                "--out",
                out,
                "--force",
            ],
        ];
        for args in commands {
            let o = grainchain_in(&p, &args);
            assert_eq!(o.status.code(), Some(2), "{args:?}: {}", err(&o));
            let e = err(&o);
            assert!(
                e.contains("no manifest.json, so grainchain did not write it")
                    && e.contains("--force does not clear it")
                    && e.contains("choose another --out")
                    && !e.contains("pass --force"),
                "{args:?}: {e}"
            );
            assert_eq!(listing(&p), before, "{args:?} changed the project folder");
            assert_eq!(listing(&outside), outside_before, "{args:?}");
        }
    }
    // What is there is named (the first entries, links with where they lead).
    let o = grainchain_in(&p, &["run", "scene.toml", "--out", ".", "--force"]);
    assert!(
        err(&o).contains("README.md, members (a symbolic link to")
            && err(&o)
                .contains("nested/, readme-link (a symbolic link to README.md), scene.toml, src/"),
        "{}",
        err(&o)
    );
    let _ = std::fs::remove_dir_all(&p);
    let _ = std::fs::remove_dir_all(&outside);
}

/// Item 1: a refused `--out` keeps no lock file (also covered above, for every command), and a
/// command that fails before writing anything leaves no folder it created (`--merge` of a study
/// without members left a folder holding only manifest.json).
#[test]
fn a_failed_or_refused_command_leaves_nothing_behind() {
    let (p, outside) = project("refused");
    let before = listing(&p);
    let o = grainchain_in(&p, &["run", "scene.toml", "--out", "."]);
    assert_eq!(o.status.code(), Some(2), "{}", err(&o));
    assert_eq!(listing(&p), before);
    let out = tmp("never-made").join("deeper");
    let o = grainchain(&["study", "studies/smoke.toml", "--merge", "--out", s(&out)]);
    assert_eq!(o.status.code(), Some(1), "{}", err(&o));
    assert!(err(&o).contains("cannot merge"), "{}", err(&o));
    assert!(!out.parent().unwrap().exists(), "{:?}", listing(&out));
    let _ = std::fs::remove_dir_all(&p);
    let _ = std::fs::remove_dir_all(&outside);
}

/// Item 1: an input of the command is never deleted, even when a manifest lists it with its
/// exact bytes (a user who keeps a scene in the output folder and lists it, or a manifest of an
/// older build): neither by `--force` (another scene) nor by a rerun that does not write it.
#[test]
fn an_input_is_never_deleted() {
    let out = tmp("input");
    let o = grainchain(&["run", "scenes/single-solitary-wave.toml", "--out", s(&out)]);
    assert!(o.status.success(), "{}", err(&o));
    let list = |name: &str, from: &str| {
        let bytes = std::fs::read(Path::new(ROOT).join(from)).unwrap();
        std::fs::write(out.join(name), &bytes).unwrap();
        let path = out.join("manifest.json");
        let mut m: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        m["files"][name] = serde_json::json!({
            "size": bytes.len(),
            "fnv": grainchain::report::fnv1a(&bytes),
        });
        std::fs::write(&path, m.to_string()).unwrap();
    };
    list("spring.toml", "scenes/linear-spring-chain.toml");
    let before = listing(&out);
    let o = grainchain(&[
        "run",
        s(&out.join("spring.toml")),
        "--out",
        s(&out),
        "--force",
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", err(&o));
    assert!(
        err(&o).contains("spring.toml is an input of this command"),
        "{}",
        err(&o)
    );
    assert_eq!(listing(&out), before);
    // The same scene again, run from the folder: the rerun keeps its input.
    std::fs::remove_file(out.join("spring.toml")).unwrap();
    list("same.toml", "scenes/single-solitary-wave.toml");
    let o = grainchain(&["run", s(&out.join("same.toml")), "--out", s(&out)]);
    assert!(o.status.success(), "{}", err(&o));
    assert_eq!(
        std::fs::read(out.join("same.toml")).unwrap(),
        std::fs::read(Path::new(ROOT).join("scenes/single-solitary-wave.toml")).unwrap()
    );
    let _ = std::fs::remove_dir_all(&out);
}

/// Item 10: a folder whose manifest matches accepted foreign entries, which --force then did not
/// clear. They are refused now, named, with or without --force, and stay.
#[test]
fn foreign_entries_in_an_owned_folder_are_refused() {
    let out = tmp("foreign");
    let run = |scene: &str, force: bool| {
        let mut a = vec!["run", scene, "--out", s(&out)];
        if force {
            a.push("--force");
        }
        grainchain(&a)
    };
    let o = run("scenes/single-solitary-wave.toml", false);
    assert!(o.status.success(), "{}", err(&o));
    std::fs::write(out.join("thesis.tex"), "precious").unwrap();
    let before = listing(&out);
    for (scene, force) in [
        ("scenes/single-solitary-wave.toml", false),
        ("scenes/single-solitary-wave.toml", true),
        ("scenes/linear-spring-chain.toml", true),
    ] {
        let o = run(scene, force);
        assert_eq!(o.status.code(), Some(2), "{scene} {force}: {}", err(&o));
        assert!(
            err(&o).contains("grainchain did not write thesis.tex")
                && err(&o).contains("--force would not help"),
            "{}",
            err(&o)
        );
        assert_eq!(listing(&out), before);
    }
    // Moved away, the folder is the run's again; --force then deletes only its files.
    std::fs::remove_file(out.join("thesis.tex")).unwrap();
    let o = run("scenes/linear-spring-chain.toml", true);
    assert!(o.status.success(), "{}", err(&o));
    let _ = std::fs::remove_dir_all(&out);
}

/// Item 10: a rerun removes the `.partial` temporaries a run killed with SIGKILL left (and only
/// those: a hidden file of the user's that merely looks alike stays).
#[test]
fn a_rerun_removes_the_partials_of_a_killed_run() {
    let out = tmp("killed");
    let scene = "scenes/fig3-standard-container.toml";
    let partials = |d: &Path| -> Vec<String> {
        std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".partial"))
            .collect()
    };
    // The run streams its CSV files into temporaries from its start: kill it once they exist.
    let mut child = Command::new(BIN)
        .args(["run", scene, "--out", s(&out)])
        .current_dir(ROOT)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let t0 = std::time::Instant::now();
    while (!out.exists() || partials(&out).is_empty()) && t0.elapsed().as_secs() < 60 {
        std::thread::sleep(std::time::Duration::from_millis(1));
    }
    child.kill().unwrap(); // SIGKILL
    let status = child.wait().unwrap();
    let left = partials(&out);
    assert!(
        !status.success() && !left.is_empty(),
        "the run finished before it was killed ({status}); nothing to check"
    );
    std::fs::write(out.join(".my-notes.partial"), "mine").unwrap();
    let o = grainchain(&["run", scene, "--out", s(&out)]);
    assert!(o.status.success(), "{}", err(&o));
    assert_eq!(
        partials(&out),
        [".my-notes.partial"],
        "left by the kill: {left:?}"
    );
    let _ = std::fs::remove_dir_all(&out);
}

/// Item 10: a `members` link to a folder outside --out was adopted and written into; it is
/// refused now, named, and nothing is written through it.
#[test]
fn a_members_link_out_of_the_folder_is_refused() {
    let out = tmp("members-link");
    let outside = tmp("members-outside");
    std::fs::create_dir_all(&out).unwrap();
    std::fs::create_dir_all(&outside).unwrap();
    std::os::unix::fs::symlink(&outside, out.join("members")).unwrap();
    for extra in [&[][..], &["--shard", "1/2"][..], &["--merge"][..]] {
        let mut args = vec!["study", "studies/smoke.toml", "--out", s(&out)];
        args.extend(extra);
        let o = grainchain(&args);
        assert_eq!(o.status.code(), Some(2), "{extra:?}: {}", err(&o));
        assert!(
            err(&o).contains("members (a symbolic link to"),
            "{extra:?}: {}",
            err(&o)
        );
        assert_eq!(listing(&outside), [], "{extra:?} wrote through the link");
    }
    let _ = std::fs::remove_dir_all(&out);
    let _ = std::fs::remove_dir_all(&outside);
}

/// Item 10: a shard ran beside a full study of the same folder. Here the test process holds a
/// shard's claim (as a running `--shard 1/2` does) and a full study is refused at once; then it
/// holds the whole folder (as a full study or a merge does) and a shard is refused.
#[test]
fn a_shard_and_a_full_study_exclude_each_other() {
    let out = tmp("shard-full");
    let sf = SweepFile::load(Path::new(ROOT).join("studies/smoke.toml")).unwrap();
    let inputs = BTreeMap::from([("sweep".to_string(), sf.inputs_digest())]);
    let locked = |o: &Output| {
        assert_eq!(o.status.code(), Some(1), "{}", err(o));
        assert!(
            err(o).contains("another grainchain command is writing"),
            "{}",
            err(o)
        );
    };
    let shard = OutDir::claim(&out, "study", inputs.clone(), Some("shard-1-of-2"), false).unwrap();
    for args in [&[][..], &["--merge"][..]] {
        let mut a = vec!["study", "studies/smoke.toml", "--out", s(&out)];
        a.extend(args);
        locked(&grainchain(&a));
    }
    // The other shard runs beside it.
    let o = grainchain(&[
        "study",
        "studies/smoke.toml",
        "--out",
        s(&out),
        "--shard",
        "2/2",
        "--threads",
        "1",
    ]);
    assert!(o.status.success(), "{}", err(&o));
    drop(shard);
    let whole = OutDir::claim(&out, "study", inputs, None, false).unwrap();
    locked(&grainchain(&[
        "study",
        "studies/smoke.toml",
        "--out",
        s(&out),
        "--shard",
        "1/2",
    ]));
    drop(whole);
    let _ = std::fs::remove_dir_all(&out);
}

/// Item 10: a study that fails while writing its outputs (here: a file size limit, as a full
/// disk, hit by its first output table) leaves a manifest that says the outputs are incomplete;
/// `--merge` then repairs the folder: complete, every output listed, nothing refused.
#[test]
fn a_failed_output_write_is_marked_and_repaired() {
    let out = tmp("failed-write");
    // Member files are at most 27 kB, ensemble.csv about 83 kB: a 60-block limit (at least
    // 30 kB, whether the shell counts 512- or 1024-byte blocks) lets every member through and
    // stops the merge. SIGXFSZ is ignored, so the write fails with EFBIG like a full disk.
    let o = Command::new("bash")
        .args([
            "-c",
            "ulimit -f 60 && trap '' XFSZ && exec \"$0\" \"$@\"",
            BIN,
            "study",
            "studies/smoke.toml",
            "--out",
            s(&out),
            "--threads",
            "2",
        ])
        .current_dir(ROOT)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1), "{}", err(&o));
    let manifest = || -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(out.join("manifest.json")).unwrap()).unwrap()
    };
    assert_eq!(manifest()["complete"], false, "{}", err(&o));
    assert!(!out.join("STUDY.md").exists());
    let o = grainchain(&["study", "studies/smoke.toml", "--merge", "--out", s(&out)]);
    assert!(o.status.success(), "{}", err(&o));
    let m = manifest();
    assert_eq!(m["complete"], true);
    for f in ["ensemble.csv", "STUDY.md", "fits.csv"] {
        assert!(m["files"][f].is_object(), "{f} not listed: {m}");
    }
    let _ = std::fs::remove_dir_all(&out);
}

/// Issue 38, item 1: a user's file inside a subfolder grainchain writes (a study's `members/`,
/// a design's `evaluations/`) was overwritten, exit 0, where the same file at the folder's top
/// was refused. Now every such file is refused by name and keeps its bytes: in a folder holding
/// only `members/`, in a study folder re-run with `--force` and one member more, and in a
/// design's `evaluations/` (the whole search, one island with `--force --shard 1/2`, and an
/// island's convergence file).
#[test]
fn a_users_file_inside_a_subfolder_is_never_replaced() {
    let mine = b"my own notes, not a member\n";
    let refused = |o: &Output, file: &str| {
        assert_eq!(o.status.code(), Some(2), "{file}: {}", err(o));
        assert!(
            err(o).contains(&format!("{file} is in the way")),
            "{}",
            err(o)
        );
    };
    // A folder holding only members/, with a file named like the first member.
    let out = tmp("users-member");
    std::fs::create_dir_all(out.join("members")).unwrap();
    std::fs::write(out.join("members/a-m0.csv"), mine).unwrap();
    let o = grainchain(&["study", "studies/smoke.toml", "--out", s(&out)]);
    refused(&o, "members/a-m0.csv");
    assert_eq!(std::fs::read(out.join("members/a-m0.csv")).unwrap(), mine);
    let _ = std::fs::remove_dir_all(&out);

    // A finished study, a user's file named like a fourth member, the study re-run with 4
    // members and --force (its other inputs: --force deletes what grainchain wrote).
    let out = tmp("users-member-force");
    let dir = tmp("users-member-sweep");
    std::fs::create_dir_all(&dir).unwrap();
    let smoke = std::fs::read_to_string(root("studies/smoke.toml"))
        .unwrap()
        .replace("\"../scenes/", &format!("\"{}/", root("scenes")));
    let three = dir.join("three.toml");
    std::fs::write(&three, &smoke).unwrap();
    let four = dir.join("four.toml");
    std::fs::write(&four, smoke.replacen("members = 3", "members = 4", 1)).unwrap();
    let o = grainchain(&["study", s(&three), "--out", s(&out)]);
    assert_eq!(o.status.code(), Some(0), "{}", err(&o));
    std::fs::write(out.join("members/a-m3.csv"), mine).unwrap();
    let o = grainchain(&["study", s(&four), "--out", s(&out), "--force"]);
    refused(&o, "members/a-m3.csv");
    assert_eq!(std::fs::read(out.join("members/a-m3.csv")).unwrap(), mine);
    let _ = std::fs::remove_dir_all(&out);
    let _ = std::fs::remove_dir_all(&dir);

    // A design's evaluations/: the whole search's journal, an island's with --force, and an
    // island's convergence file (written when the island has finished: refused before it runs).
    for (name, extra) in [
        ("island-1-of-1.csv", &[][..]),
        ("island-1-of-2.csv", &["--force", "--shard", "1/2"][..]),
        ("island-2-of-2.convergence.csv", &["--shard", "2/2"][..]),
    ] {
        let out = tmp("users-evaluations");
        std::fs::create_dir_all(out.join("evaluations")).unwrap();
        std::fs::write(out.join("evaluations").join(name), mine).unwrap();
        let mut args = vec!["design", "designs/steel-ptfe.toml", "--out", s(&out)];
        args.extend(extra);
        let o = grainchain(&args);
        refused(&o, name);
        assert_eq!(
            std::fs::read(out.join("evaluations").join(name)).unwrap(),
            mine
        );
        let _ = std::fs::remove_dir_all(&out);
    }
}
