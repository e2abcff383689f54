//! Records the git revision of the checkout being built (`GRAINCHAIN_GIT`: a short hash, with
//! `-dirty` when the code differs from HEAD; `unknown` outside a git checkout or without git),
//! for the binary and the Python module to say which revision built them.
//!
//! This crate is tiny and only the command-line tool and the Python module depend on it, so a
//! commit or a checkout rebuilds it, the tool's `main.rs` and the link, never the engine or the
//! harness (issue 37: the revision used to live in the harness crate, which a commit rebuilt).
//! It does not watch `.git/index`: a plain `git status` rewrites the index in a fresh clone,
//! which made the next cargo command rebuild. "The code" is the folders and manifests below;
//! an edit there reruns this script (and rebuilds the tool anyway), an edit of the docs does
//! not make a build dirty.

use std::process::Command;

/// What the binary is built from, relative to the repository's top.
const CODE: &[&str] = &[
    "src",
    "harness",
    "engine",
    "revision",
    "python/src",
    "python/Cargo.toml",
    "Cargo.toml",
    "Cargo.lock",
];

fn git(args: &[&str]) -> Option<String> {
    let out = Command::new("git")
        .args(["-C", ".."])
        .args(args)
        .env("GIT_OPTIONAL_LOCKS", "0")
        .output()
        .ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
}

fn main() {
    let rev = git(&["rev-parse", "--short=12", "HEAD"]);
    let mut status = vec!["status", "--porcelain", "--untracked-files=no", "--"];
    status.extend(CODE);
    let dirty = git(&status).is_some_and(|s| !s.is_empty());
    let id = match rev {
        Some(r) if dirty => format!("{r}-dirty"),
        Some(r) => r,
        None => "unknown".into(),
    };
    println!("cargo:rustc-env=GRAINCHAIN_GIT={id}");
    println!("cargo:rerun-if-changed=build.rs");
    // Run again when HEAD moves (a commit moves the branch's ref, a checkout HEAD itself) or
    // the code changes: the id is then never stale for the code it is compiled into.
    for path in CODE {
        println!("cargo:rerun-if-changed=../{path}");
    }
    let Some(dir) = git(&["rev-parse", "--absolute-git-dir"]) else {
        return;
    };
    // A missing file would make cargo run this script every time: only files that exist.
    let mut watch = vec![format!("{dir}/HEAD"), format!("{dir}/packed-refs")];
    if let Some(r) = git(&["symbolic-ref", "-q", "HEAD"]) {
        watch.push(format!("{dir}/{r}"));
    }
    for f in watch.iter().filter(|f| std::path::Path::new(f).exists()) {
        println!("cargo:rerun-if-changed={f}");
    }
}
