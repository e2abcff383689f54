//! An output folder belongs to one command on one set of inputs, and grainchain deletes only
//! files it wrote there.
//!
//! Every command that writes a folder (`run`, `reproduce`, `study`, `work-precision`) first
//! claims it with [`OutDir::claim`] / [`OutDir::claim_with`]:
//!
//! - it holds a lock (an advisory `flock` on `.grainchain.lock` in the folder), so a second
//!   command writing into the same folder fails at once with a clear message; the operating
//!   system releases the lock when the process ends, however it ends, so a killed run never
//!   leaves a stale lock. One part of a job that several processes share (a study's shards)
//!   holds `.grainchain.lock` shared and `.grainchain-<part>.lock` exclusively: the parts run
//!   side by side, a second copy of one part is refused, and a command on the whole folder (a
//!   full study, a merge) and a part exclude each other;
//! - every file grainchain commits into a claimed folder ([`crate::report::AtomicFile`]) is
//!   recorded first, with its size and checksum, in a hidden journal (`.grainchain.written`, or
//!   `.grainchain-<part>.written`), and `manifest.json` lists the outputs of a finished command;
//!   together they are what grainchain wrote there. The manifest says `"complete": false` from
//!   the claim until the command has finished (a command that failed, or was killed, while
//!   writing its outputs leaves such a manifest; the same command again, or `--merge`, repairs
//!   it);
//! - a folder with files in it must hold a `manifest.json` written by the same command on the
//!   same inputs (a rerun, `--resume`, `--merge`), and nothing beside what grainchain wrote
//!   there (and what the command adopts, such as a study's `members/`): an entry it did not
//!   write, a symbolic link, or a file it wrote that was changed since is refused, naming it;
//! - a file is committed over an existing one only if grainchain wrote one there (a record in
//!   the journal or manifest), in every subfolder as at the top; in an adopted subfolder the
//!   command checks what it replaces (a member whose bookkeeping reads as one; a design
//!   journal with its header): a user's file in the way is an error naming it;
//! - a folder of another command or of other inputs is refused unless `--force`, which deletes
//!   exactly the files the manifest and journal record, each only if it is unchanged (size and
//!   checksum as written), is not an input of the command, and lies in the folder (no link is
//!   followed), and then the folders they leave empty; anything else in the folder makes
//!   `--force` refuse too, before it deletes anything. A folder without a manifest is never
//!   cleared: it is used only if nothing in it but hidden entries (or what the command adopts);
//! - a refused claim leaves the folder as it was: a lock file it created is removed, and so is a
//!   folder it created; a command that fails before it writes anything leaves no folder it
//!   created either;
//! - a claim of the whole folder removes the temporaries (`.<name>.XXXXXX.partial`,
//!   [`crate::report::atomic::is_partial`]) an earlier process killed while writing left in it;
//! - the manifest is written at once (so the shards of one study starting together agree) and,
//!   when the command has finished, [`OutDir::finish`] records every file it wrote with its size
//!   and FNV-1a checksum, and deletes files an earlier run of the same command wrote there but
//!   this one did not (a second run never leaves the first one's files beside its own), unless
//!   they were changed since: those are the user's and are left (the next claim names them).
//!
//! Only folders grainchain wrote into (or adopts) are looked into: any other folder with something
//! in it counts as one foreign entry, so a claim of `--out /` or `--out ~` is refused at once.
//!
//! Entries whose names start with a dot (the lock files, the journals, atomic writes in
//! progress, a user's `.git`) do not count, and grainchain deletes none of them but its own
//! temporaries.

use crate::error::{Error, OutDirError};
use crate::report::journal::{self, journal_files, journal_name, read_journals};
pub use crate::report::journal::{FileEntry, MANIFEST};
use crate::report::{atomic::is_partial, fnv1a, AtomicFile};
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, BTreeSet};
use std::fs::File;
use std::path::{Path, PathBuf};

/// The lock of the whole folder.
const LOCK: &str = ".grainchain.lock";

/// `manifest.json`: which command wrote the folder, on which inputs, with which program, and
/// its files.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Manifest {
    /// The program ([`crate::program()`]: version and git revision).
    pub program: String,
    /// The command (`run`, `reproduce`, `study`, `work-precision`).
    pub command: String,
    /// Digest of each input, by name (a scene file, a sweep, the command's options).
    pub inputs: BTreeMap<String, String>,
    /// Whether the command finished and `files` lists its outputs: `false` from the claim until
    /// [`OutDir::finish`] (a failed or killed command leaves it so). Manifests of older builds,
    /// which have no such key, read as complete.
    #[serde(default = "yes")]
    pub complete: bool,
    /// The files written, relative to the folder, with their sizes and checksums (those of an
    /// earlier finished run while a new one runs, empty before the first has finished).
    pub files: BTreeMap<String, FileEntry>,
}

fn yes() -> bool {
    true
}

/// What to claim a folder for ([`OutDir::claim_with`]).
#[derive(Clone, Debug, Default)]
pub struct Claim<'a> {
    /// The command (`run`, `reproduce`, `study`, `work-precision`).
    pub command: &'a str,
    /// Digest of each input, by name.
    pub inputs: BTreeMap<String, String>,
    /// One part of a job several processes share (`shard-1-of-3`), or `None` for the whole
    /// folder (see the module).
    pub part: Option<&'a str>,
    /// Delete what grainchain wrote in a folder of another command or other inputs.
    pub force: bool,
    /// Top-level folders accepted without a record of them, and without a manifest: inputs that
    /// check themselves, such as a study's `members/` gathered from shards by hand (every member
    /// file carries its batch's digest and checksum). Only real folders, never a link.
    pub adopt: &'a [&'a str],
    /// The command's input files and folders: nothing at or under them is ever deleted.
    pub protect: Vec<PathBuf>,
}

/// A claimed output folder (see the module).
#[derive(Debug)]
pub struct OutDir {
    dir: PathBuf,
    manifest: Manifest,
    /// Files of an earlier run of the same command and inputs (deleted by `finish` unless
    /// written again).
    earlier: BTreeMap<String, FileEntry>,
    /// Every record of the folder's journals at the claim, by path.
    journal: BTreeMap<String, Vec<FileEntry>>,
    /// The command's inputs, canonical.
    protect: Vec<PathBuf>,
    /// Whether this claim holds the whole folder (not one part of it).
    whole: bool,
    /// This claim's journal.
    journal_path: PathBuf,
    /// The folders this claim created, outermost first.
    created: Vec<PathBuf>,
    /// [`OutDir::finish`] ran.
    finished: bool,
    _locks: Vec<Lock>,
}

/// A lock file held (see the module).
#[derive(Debug)]
struct Lock {
    file: File,
    path: PathBuf,
    /// This claim created the file (a refused claim removes it again).
    created: bool,
}

impl Lock {
    /// Take the lock `path` (shared or exclusive) without waiting.
    fn take(dir: &Path, path: PathBuf, shared: bool) -> Result<Lock, Error> {
        let io = |path: &Path| {
            let path = path.to_path_buf();
            move |source| Error::Io { path, source }
        };
        // A lock file removed under a claim again and again: give up as if it were held.
        for _ in 0..100 {
            let (file, created) = match File::options().write(true).create_new(true).open(&path) {
                Ok(f) => (f, true),
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                    match File::options().write(true).open(&path) {
                        Ok(f) => (f, false),
                        // Removed in between by a refused claim: take it again.
                        Err(e) if e.kind() == std::io::ErrorKind::NotFound => continue,
                        Err(e) => return Err(io(&path)(e)),
                    }
                }
                Err(e) => return Err(io(&path)(e)),
            };
            let got = if shared {
                file.try_lock_shared()
            } else {
                file.try_lock()
            };
            match got {
                Ok(()) => {}
                Err(std::fs::TryLockError::WouldBlock) => {
                    return Err(OutDirError::Locked {
                        dir: dir.to_path_buf(),
                        lock: path,
                    }
                    .into())
                }
                Err(std::fs::TryLockError::Error(source)) => {
                    return Err(Error::Io { path, source })
                }
            }
            // A refused claim removes a lock file it created while holding it; whoever had
            // opened that file before holds a lock nobody else sees, so the lock counts only if
            // the file is still the one at `path`.
            if same_file(&file, &path) {
                return Ok(Lock {
                    file,
                    path,
                    created,
                });
            }
        }
        Err(OutDirError::Locked {
            dir: dir.to_path_buf(),
            lock: path,
        }
        .into())
    }

    /// Release; remove the file if this claim created it and no other process holds it.
    fn release_created(self) {
        if self.created && self.file.try_lock().is_ok() {
            let _ = std::fs::remove_file(&self.path);
        }
    }
}

#[cfg(unix)]
fn same_file(file: &File, path: &Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    match (file.metadata(), std::fs::metadata(path)) {
        (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
        _ => false,
    }
}

#[cfg(not(unix))]
fn same_file(_: &File, path: &Path) -> bool {
    path.exists()
}

/// What is in a folder: every entry below it that is not a folder, by `/`-separated relative
/// name, walked without following links and without entering hidden folders; hidden entries
/// are left out, apart from grainchain's temporaries (`partials`). Only folders that something
/// grainchain wrote lies in (or that the command adopts) are entered: any other folder with
/// something in it is one entry (`folders`), so `--out /` or `--out ~` is not walked.
#[derive(Debug, Default)]
struct Contents {
    /// Regular files.
    files: BTreeSet<String>,
    /// Symbolic links, with where they lead.
    links: BTreeMap<String, PathBuf>,
    /// Anything else (sockets, devices, fifos).
    other: BTreeSet<String>,
    /// Folders not entered that hold something that counts.
    folders: BTreeSet<String>,
    /// Grainchain's temporaries ([`is_partial`]), in the folders walked.
    partials: Vec<PathBuf>,
}

impl Contents {
    /// The contents of `dir`, entering the folders `enter` accepts (by relative name).
    fn of(dir: &Path, enter: &dyn Fn(&str) -> bool) -> Result<Contents, Error> {
        let mut c = Contents::default();
        c.walk(dir, "", enter)?;
        Ok(c)
    }

    fn walk(
        &mut self,
        dir: &Path,
        prefix: &str,
        enter: &dyn Fn(&str) -> bool,
    ) -> Result<(), Error> {
        let io = |path: &Path| {
            let path = path.to_path_buf();
            move |source| Error::Io { path, source }
        };
        for e in std::fs::read_dir(dir).map_err(io(dir))? {
            let e = e.map_err(io(dir))?;
            let name = e.file_name().to_string_lossy().into_owned();
            let path = e.path();
            let ty = e.file_type().map_err(io(&path))?;
            if name.starts_with('.') {
                if ty.is_file() && is_partial(&name) {
                    self.partials.push(path);
                }
                continue;
            }
            let rel = format!("{prefix}{name}");
            if ty.is_symlink() {
                let to = std::fs::read_link(&path).unwrap_or_default();
                self.links.insert(rel, to);
            } else if ty.is_dir() && enter(&rel) {
                self.walk(&path, &format!("{rel}/"), enter)?;
            } else if ty.is_dir() {
                let counts = std::fs::read_dir(&path)
                    .map_err(io(&path))?
                    .flatten()
                    .any(|e| !e.file_name().to_string_lossy().starts_with('.'));
                if counts {
                    self.folders.insert(rel);
                }
            } else if ty.is_file() {
                self.files.insert(rel);
            } else {
                self.other.insert(rel);
            }
        }
        Ok(())
    }

    fn is_empty(&self) -> bool {
        self.names().next().is_none()
    }

    /// Every entry (files, links, others, folders not entered), by name.
    fn names(&self) -> impl Iterator<Item = &String> {
        self.files
            .iter()
            .chain(self.links.keys())
            .chain(self.other.iter())
            .chain(self.folders.iter())
    }

    /// An entry as a person reads it (a link with where it leads).
    fn describe(&self, rel: &str) -> String {
        match self.links.get(rel) {
            Some(to) => format!("{rel} (a symbolic link to {})", to.display()),
            None if self.other.contains(rel) => format!("{rel} (not a regular file)"),
            None if self.folders.contains(rel) => format!("{rel}/"),
            None => rel.to_string(),
        }
    }
}

/// The entries of `dir` that count (names not starting with a dot).
fn visible(dir: &Path) -> Result<Vec<PathBuf>, Error> {
    let io = |source| Error::Io {
        path: dir.to_path_buf(),
        source,
    };
    let mut v = Vec::new();
    for e in std::fs::read_dir(dir).map_err(io)? {
        let e = e.map_err(io)?;
        if !e.file_name().to_string_lossy().starts_with('.') {
            v.push(e.path());
        }
    }
    v.sort();
    Ok(v)
}

/// Up to six names, then how many more.
fn list(names: &[String]) -> String {
    let mut s = names.iter().take(6).cloned().collect::<Vec<_>>().join(", ");
    if names.len() > 6 {
        s.push_str(&format!(" and {} more", names.len() - 6));
    }
    s
}

/// The top-level name of a relative name.
fn top(rel: &str) -> &str {
    rel.split('/').next().unwrap_or(rel)
}

/// Whether the file at `p` is one of `records` (its size first, then its checksum).
fn unchanged(p: &Path, records: &[&FileEntry]) -> Result<bool, Error> {
    let len = std::fs::symlink_metadata(p)
        .map_err(|source| Error::Io {
            path: p.to_path_buf(),
            source,
        })?
        .len();
    if !records.iter().any(|r| r.size == len) {
        return Ok(false);
    }
    let bytes = std::fs::read(p).map_err(|source| Error::Io {
        path: p.to_path_buf(),
        source,
    })?;
    let tag = fnv1a(&bytes);
    Ok(records.iter().any(|r| r.size == len && r.fnv == tag))
}

/// Why manifest `m` does not belong to `command` on `inputs` (`None`: it does).
fn other_owner(m: &Manifest, command: &str, inputs: &BTreeMap<String, String>) -> Option<String> {
    if m.command != command {
        return Some(format!(
            "`grainchain {}` wrote it, this is `grainchain {command}`",
            m.command
        ));
    }
    let names: BTreeSet<&String> = m.inputs.keys().chain(inputs.keys()).collect();
    names.into_iter().find_map(|k| {
        let (there, here) = (m.inputs.get(k), inputs.get(k));
        (there != here).then(|| match (there, here) {
            (Some(a), Some(b)) => format!("input `{k}` differs (digest {a} there, {b} here)"),
            (Some(_), None) => {
                format!("it was written with input `{k}`, which this command has not")
            }
            (None, _) => format!("input `{k}` is new"),
        })
    })
}

/// The folders `create_dir_all(dir)` would create, outermost first.
fn missing_folders(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = dir
        .ancestors()
        .take_while(|a| !a.as_os_str().is_empty() && std::fs::symlink_metadata(a).is_err())
        .map(Path::to_path_buf)
        .collect();
    v.reverse();
    v
}

impl OutDir {
    /// Claim `dir` for `command` on `inputs` (input name to digest), for a `part` of a job that
    /// several processes share or the whole folder (see the module); `force` deletes what
    /// grainchain wrote in a folder of another command or other inputs.
    pub fn claim(
        dir: &Path,
        command: &str,
        inputs: BTreeMap<String, String>,
        part: Option<&str>,
        force: bool,
    ) -> Result<OutDir, Error> {
        Self::claim_with(
            dir,
            Claim {
                command,
                inputs,
                part,
                force,
                ..Claim::default()
            },
        )
    }

    /// Claim `dir` as `claim` says (see the module). A refused claim leaves the folder as it
    /// found it (a folder it had to create is removed again).
    pub fn claim_with(dir: &Path, claim: Claim<'_>) -> Result<OutDir, Error> {
        let created = missing_folders(dir);
        std::fs::create_dir_all(dir).map_err(|source| Error::Io {
            path: dir.to_path_buf(),
            source,
        })?;
        let r = Self::claim_locked(dir, claim).map(|mut o| {
            o.created = created.clone();
            o
        });
        if r.is_err() {
            for d in created.iter().rev() {
                if std::fs::remove_dir(d).is_err() {
                    break;
                }
            }
        }
        r
    }

    fn claim_locked(dir: &Path, claim: Claim<'_>) -> Result<OutDir, Error> {
        let whole = claim.part.is_none();
        let mut locks = vec![Lock::take(dir, dir.join(LOCK), !whole)?];
        if let Some(p) = claim.part {
            match Lock::take(dir, dir.join(format!(".grainchain-{p}.lock")), false) {
                Ok(l) => locks.push(l),
                Err(e) => {
                    locks.into_iter().for_each(Lock::release_created);
                    return Err(e);
                }
            }
        }
        match Self::inspect(dir, &claim, whole) {
            Ok(found) => Self::take_over(dir, claim, found, whole, locks),
            Err(e) => {
                // Parts first: the folder's lock is removed only if no part holds it.
                locks.into_iter().rev().for_each(Lock::release_created);
                Err(e)
            }
        }
    }

    /// Decide whether the folder may be claimed, and what `--force` deletes; nothing is changed.
    fn inspect(dir: &Path, claim: &Claim<'_>, whole: bool) -> Result<Found, Error> {
        let refuse = |why: String, advice: String| -> Error {
            OutDirError::NotOurs {
                dir: dir.to_path_buf(),
                why,
                advice,
            }
            .into()
        };
        // Folders entered: those grainchain wrote into (by its records) and those adopted.
        let has_manifest = std::fs::symlink_metadata(dir.join(MANIFEST)).is_ok_and(|m| m.is_file());
        let recorded: BTreeSet<String> = if has_manifest {
            let m = std::fs::read_to_string(dir.join(MANIFEST))
                .ok()
                .and_then(|t| serde_json::from_str::<Manifest>(&t).ok());
            let journal = read_journals(dir);
            let paths = m.iter().flat_map(|m| m.files.keys()).chain(journal.keys());
            paths
                .flat_map(|p| {
                    let parts: Vec<&str> = p.split('/').collect();
                    (1..parts.len())
                        .map(|i| parts[..i].join("/"))
                        .collect::<Vec<_>>()
                })
                .collect()
        } else {
            BTreeSet::new()
        };
        let enter = |rel: &str| recorded.contains(rel) || claim.adopt.contains(&top(rel));
        let contents = Contents::of(dir, &enter)?;
        // The journals are read (again) after the walk: a part running beside records a file
        // before it appears, so every file the walk saw has its record by now.
        let journal = read_journals(dir);
        let protect: Vec<PathBuf> = claim
            .protect
            .iter()
            .filter_map(|p| std::fs::canonicalize(p).ok())
            .collect();
        let mut found = Found {
            earlier: BTreeMap::new(),
            journal,
            protect,
            delete: Vec::new(),
            partials: if whole {
                contents.partials.clone()
            } else {
                Vec::new()
            },
        };
        if contents.is_empty() {
            return Ok(found);
        }
        // A top-level folder the command adopts (a real folder, never a link).
        let adopted = |rel: &str| {
            rel.contains('/')
                && claim.adopt.contains(&top(rel))
                && std::fs::symlink_metadata(dir.join(top(rel))).is_ok_and(|m| m.is_dir())
        };
        let manifest_path = dir.join(MANIFEST);
        if !contents.files.contains(MANIFEST) {
            let strays: Vec<String> = contents
                .names()
                .filter(|n| !(adopted(n) && contents.files.contains(*n)))
                .map(|n| contents.describe(n))
                .collect();
            if strays.is_empty() {
                return Ok(found);
            }
            let tops: BTreeSet<&str> = contents.names().map(|n| top(n)).collect();
            let tops: Vec<String> = tops.into_iter().map(|t| contents.describe(t)).collect();
            return Err(refuse(
                format!(
                    "not an output folder of grainchain: it holds {} and no {MANIFEST}, so \
                     grainchain did not write it",
                    list(&tops)
                ),
                "grainchain never deletes what it did not write, so --force does not clear \
                 it either; choose another --out (a new or empty folder)"
                    .into(),
            ));
        }
        let m =
            match std::fs::read_to_string(&manifest_path)
                .map_err(|e| e.to_string())
                .and_then(|t| serde_json::from_str::<Manifest>(&t).map_err(|e| e.to_string()))
            {
                Ok(m) => m,
                Err(message) => return Err(refuse(
                    OutDirError::BadManifest {
                        file: manifest_path,
                        message,
                    }
                    .to_string(),
                    "grainchain cannot tell which files in it are its own, so --force does not \
                     clear it either; choose another --out"
                        .into(),
                )),
            };
        let owned = |rel: &str| {
            rel == MANIFEST || m.files.contains_key(rel) || found.journal.contains_key(rel)
        };
        // Entries grainchain did not write: a link anywhere, anything not a regular file, a file
        // without a record (unless under a folder the command adopts).
        let foreign: Vec<String> = contents
            .names()
            .filter(|n| !contents.files.contains(*n) || !(owned(n) || adopted(n)))
            .map(|n| contents.describe(n))
            .collect();
        // Files grainchain wrote whose bytes changed since.
        let records = |rel: &str| -> Vec<&FileEntry> {
            m.files
                .get(rel)
                .into_iter()
                .chain(found.journal.get(rel).into_iter().flatten())
                .collect()
        };
        let owner = other_owner(&m, claim.command, &claim.inputs);
        let mut changed = Vec::new();
        let mut inputs = Vec::new();
        let mut delete = Vec::new();
        for rel in contents.files.iter().filter(|n| *n != MANIFEST && owned(n)) {
            let p = dir.join(rel);
            // A rerun checks the outputs the manifest lists (it writes them again); a forced
            // claim every file it would delete.
            let check = if owner.is_some() {
                !adopted(rel) || found.journal.contains_key(rel.as_str())
            } else {
                m.files.contains_key(rel.as_str())
            };
            if !check {
                continue;
            }
            if !unchanged(&p, &records(rel))? {
                changed.push(rel.clone());
            } else if std::fs::canonicalize(&p)
                .is_ok_and(|c| found.protect.iter().any(|i| c.starts_with(i)))
            {
                inputs.push(rel.clone());
            } else {
                delete.push(rel.clone());
            }
        }
        let mut blockers = Vec::new();
        if !foreign.is_empty() {
            blockers.push(format!("grainchain did not write {}", list(&foreign)));
        }
        if !changed.is_empty() {
            blockers.push(format!(
                "{} changed since grainchain wrote {} (size or checksum differ from its record)",
                list(&changed),
                if changed.len() == 1 { "it" } else { "them" }
            ));
        }
        if !inputs.is_empty() && owner.is_some() {
            blockers.push(format!(
                "{} {} an input of this command",
                list(&inputs),
                if inputs.len() == 1 { "is" } else { "are" }
            ));
        }
        let keep_out = "grainchain deletes only files it wrote and nobody changed since, so \
                        --force would not help: move these out of the folder, or choose \
                        another --out";
        match owner {
            None => {
                if !blockers.is_empty() {
                    return Err(refuse(
                        format!(
                            "an output folder of this command, but {}",
                            blockers.join("; ")
                        ),
                        keep_out.into(),
                    ));
                }
                found.earlier = m.files;
                Ok(found)
            }
            Some(why) if !blockers.is_empty() => Err(refuse(
                format!(
                    "not an output folder of this command: {why}; and {}",
                    blockers.join("; ")
                ),
                keep_out.into(),
            )),
            Some(why) if !claim.force => Err(refuse(
                format!("not an output folder of this command: {why}"),
                format!(
                    "choose another --out, or pass --force to delete the {} file(s) grainchain \
                     wrote there",
                    delete.len()
                ),
            )),
            Some(_) => {
                found.delete = delete;
                // Its files are gone; its records with them.
                found.journal = BTreeMap::new();
                Ok(found)
            }
        }
    }

    /// Carry out what [`OutDir::inspect`] found, write the manifest, start recording.
    fn take_over(
        dir: &Path,
        claim: Claim<'_>,
        found: Found,
        whole: bool,
        locks: Vec<Lock>,
    ) -> Result<OutDir, Error> {
        let io = |path: &Path| {
            let path = path.to_path_buf();
            move |source| Error::Io { path, source }
        };
        for p in &found.partials {
            match std::fs::remove_file(p) {
                Err(e) if e.kind() != std::io::ErrorKind::NotFound => return Err(io(p)(e)),
                _ => {}
            }
        }
        let mut emptied = BTreeSet::new();
        for rel in &found.delete {
            let p = dir.join(rel);
            match std::fs::remove_file(&p) {
                Err(e) if e.kind() != std::io::ErrorKind::NotFound => return Err(io(&p)(e)),
                _ => {}
            }
            let mut up = Path::new(rel.as_str()).parent();
            while let Some(d) = up.filter(|d| !d.as_os_str().is_empty()) {
                emptied.insert(d.to_path_buf());
                up = d.parent();
            }
        }
        // Deepest first; a folder with anything left in it stays.
        for d in emptied.iter().rev() {
            let _ = std::fs::remove_dir(dir.join(d));
        }
        if !found.delete.is_empty() && whole {
            for j in journal_files(dir) {
                let _ = std::fs::remove_file(j);
            }
        }
        let manifest = Manifest {
            program: crate::program().to_string(),
            command: claim.command.to_string(),
            inputs: claim.inputs,
            complete: false,
            files: found.earlier.clone(),
        };
        let out = OutDir {
            dir: dir.to_path_buf(),
            manifest,
            earlier: found.earlier,
            journal: found.journal,
            protect: found.protect,
            whole,
            journal_path: dir.join(journal_name(claim.part)),
            created: Vec::new(),
            finished: false,
            _locks: locks,
        };
        out.write_manifest()?;
        journal::register(dir, &out.journal_path, claim.adopt);
        Ok(out)
    }

    /// The folder.
    pub fn path(&self) -> &Path {
        &self.dir
    }

    fn write_manifest(&self) -> Result<(), Error> {
        let text = serde_json::to_string_pretty(&self.manifest)?;
        AtomicFile::write_all(self.dir.join(MANIFEST), text.as_bytes())
    }

    /// The command has finished: record every file it wrote (paths relative to the folder, with
    /// sizes and checksums) in the manifest, mark it complete, and delete the top-level files an
    /// earlier run of the same command wrote that this one did not (only those unchanged since,
    /// and never an input of the command).
    pub fn finish<S: AsRef<str>>(mut self, written: &[S]) -> Result<(), Error> {
        let mut files = BTreeMap::new();
        for rel in written {
            let rel = rel.as_ref();
            let p = self.dir.join(rel);
            let bytes = std::fs::read(&p).map_err(|source| Error::Io {
                path: p.clone(),
                source,
            })?;
            files.insert(
                rel.to_string(),
                FileEntry {
                    size: bytes.len() as u64,
                    fnv: fnv1a(&bytes),
                },
            );
        }
        // Earlier outputs, and top-level files a failed run of the same command wrote.
        let earlier: BTreeSet<&String> = self
            .earlier
            .keys()
            .chain(self.journal.keys().filter(|k| !k.contains('/')))
            .filter(|k| !files.contains_key(*k) && *k != MANIFEST)
            .collect();
        for stale in earlier {
            let p = self.dir.join(stale);
            if !std::fs::symlink_metadata(&p).is_ok_and(|m| m.is_file()) {
                continue;
            }
            let records: Vec<&FileEntry> = (self.earlier.get(stale).into_iter())
                .chain(self.journal.get(stale).into_iter().flatten())
                .collect();
            let input = std::fs::canonicalize(&p)
                .is_ok_and(|c| self.protect.iter().any(|i| c.starts_with(i)));
            if !input && unchanged(&p, &records)? {
                std::fs::remove_file(&p).map_err(|source| Error::Io { path: p, source })?;
            }
        }
        self.manifest.files = files;
        self.manifest.complete = true;
        self.write_manifest()?;
        self.finished = true;
        if self.whole {
            self.compact_journal()?;
        }
        Ok(())
    }

    /// Fold every part's journal into the folder's, keeping for each file still there and not
    /// listed in the manifest its last record of the file's size (files written by parts, such
    /// as a study's members); a record of a file changed to another size is dropped (the file
    /// is the user's now). Only with the whole folder's lock: no part is writing.
    fn compact_journal(&self) -> Result<(), Error> {
        let journals = journal_files(&self.dir);
        if journals.is_empty() {
            return Ok(());
        }
        let mut text = String::new();
        for (rel, records) in read_journals(&self.dir) {
            if self.manifest.files.contains_key(&rel) {
                continue;
            }
            let Ok(m) = std::fs::symlink_metadata(self.dir.join(&rel)) else {
                continue;
            };
            if let Some(r) = records
                .iter()
                .rev()
                .find(|r| m.is_file() && r.size == m.len())
            {
                text += &journal::line(rel, r)?;
            }
        }
        let main = self.dir.join(journal_name(None));
        AtomicFile::write_all(&main, text.as_bytes())?;
        for j in journals.into_iter().filter(|j| *j != main) {
            let _ = std::fs::remove_file(j);
        }
        Ok(())
    }
}

impl Drop for OutDir {
    /// Stop recording; and a command that failed before it wrote anything into a folder it
    /// created leaves no folder (its manifest and lock file are removed, then the folder).
    fn drop(&mut self) {
        journal::unregister(&self.journal_path);
        if self.finished || !self.whole || self.created.is_empty() || self.journal_path.exists() {
            return;
        }
        let _ = std::fs::remove_file(self.dir.join(MANIFEST));
        for l in &self._locks {
            let _ = std::fs::remove_file(&l.path);
        }
        for d in self.created.iter().rev() {
            if std::fs::remove_dir(d).is_err() {
                break;
            }
        }
    }
}

/// What a claim found ([`OutDir::inspect`]).
#[derive(Debug)]
struct Found {
    earlier: BTreeMap<String, FileEntry>,
    journal: BTreeMap<String, Vec<FileEntry>>,
    protect: Vec<PathBuf>,
    /// Files `--force` deletes (relative names).
    delete: Vec<String>,
    /// Temporaries of killed processes to remove.
    partials: Vec<PathBuf>,
}

/// A TOML input file as parsed: tables are ordered maps, so comments, spacing, key order and
/// the spelling of numbers do not change it. Errors name the file (and line and column).
pub fn read_toml(path: &Path) -> Result<toml::Value, Error> {
    let text = grainchain_engine::file::read_text(path)?;
    toml::from_str(&text).map_err(|e| {
        Error::Input(grainchain_engine::InputError::Parse {
            file: path.to_path_buf(),
            message: grainchain_engine::file::describe_toml_error(&e, &text),
        })
    })
}

/// Digest of a TOML input file as parsed ([`read_toml`]): what an output folder's manifest
/// records of a scene or sweep file.
pub fn toml_digest(path: &Path) -> Result<String, Error> {
    value_digest(&read_toml(path)?)
}

/// [`toml_digest`] of a file already parsed ([`grainchain_engine::file::Parsed::value`]): a
/// command reads and parses its input once (a pipe or a FIFO can be read only once; issue 39).
pub fn value_digest(value: &toml::Value) -> Result<String, Error> {
    Ok(fnv1a(&serde_json::to_vec(value)?))
}

/// The files directly in `dir` whose names end with one of `extensions` (the outputs a command
/// wrote there), as names relative to `dir`, sorted.
pub fn files_with(dir: &Path, extensions: &[&str]) -> Result<Vec<String>, Error> {
    let mut v: Vec<String> = visible(dir)?
        .into_iter()
        // Regular files only: a link is never taken for an output.
        .filter(|p| std::fs::symlink_metadata(p).is_ok_and(|m| m.is_file()))
        .filter_map(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
        .filter(|n| n != MANIFEST && extensions.iter().any(|x| n.ends_with(x)))
        .collect();
    v.sort();
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn inputs(d: &str) -> BTreeMap<String, String> {
        BTreeMap::from([("scene".to_string(), d.to_string())])
    }

    fn claim(dir: &Path, command: &str, d: &str, force: bool) -> Result<OutDir, Error> {
        OutDir::claim(dir, command, inputs(d), None, force)
    }

    /// A study's claim: `members/` adopted.
    fn adopting(dir: &Path, d: &str) -> Result<OutDir, Error> {
        OutDir::claim_with(
            dir,
            Claim {
                command: "study",
                inputs: inputs(d),
                adopt: &["members"],
                ..Claim::default()
            },
        )
    }

    /// Every entry below `dir` (hidden ones too), with a file's bytes or a link's target.
    fn listing(dir: &Path) -> Vec<(String, String)> {
        let mut v = Vec::new();
        fn walk(d: &Path, base: &Path, v: &mut Vec<(String, String)>) {
            for e in std::fs::read_dir(d).unwrap() {
                let p = e.unwrap().path();
                let rel = p.strip_prefix(base).unwrap().display().to_string();
                let m = std::fs::symlink_metadata(&p).unwrap();
                if m.is_symlink() {
                    v.push((
                        rel,
                        format!("-> {}", std::fs::read_link(&p).unwrap().display()),
                    ));
                } else if m.is_dir() {
                    v.push((rel, "dir".into()));
                    walk(&p, base, v);
                } else {
                    v.push((
                        rel,
                        String::from_utf8_lossy(&std::fs::read(&p).unwrap()).into(),
                    ));
                }
            }
        }
        walk(dir, dir, &mut v);
        v.sort();
        v
    }

    fn manifest(dir: &Path) -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(dir.join(MANIFEST)).unwrap()).unwrap()
    }

    #[test]
    fn a_folder_belongs_to_one_command_on_one_input() {
        let t = tempfile::tempdir().unwrap();
        let dir = t.path().join("out");
        let o = claim(&dir, "run", "aa", false).unwrap();
        std::fs::write(dir.join("energies.csv"), "x\n").unwrap();
        std::fs::write(dir.join("pulses.csv"), "y\n").unwrap();
        o.finish(&["energies.csv", "pulses.csv"]).unwrap();
        // The same command on the same input: a rerun, which drops what it no longer writes.
        let o = claim(&dir, "run", "aa", false).unwrap();
        o.finish(&["energies.csv"]).unwrap();
        assert!(!dir.join("pulses.csv").exists());
        // Another input or another command: refused, naming why; --force deletes its files.
        let e = claim(&dir, "run", "bb", false).unwrap_err();
        assert!(e.to_string().contains("input `scene` differs"), "{e}");
        assert!(
            e.to_string()
                .contains("pass --force to delete the 1 file(s)"),
            "{e}"
        );
        let e = claim(&dir, "study", "aa", false).unwrap_err();
        assert!(e.to_string().contains("`grainchain run` wrote it"), "{e}");
        let o = claim(&dir, "study", "aa", true).unwrap();
        assert!(!dir.join("energies.csv").exists());
        drop(o);
        // A folder grainchain did not write: refused, with or without --force.
        let foreign = t.path().join("foreign");
        std::fs::create_dir_all(&foreign).unwrap();
        std::fs::write(foreign.join("notes.txt"), "mine").unwrap();
        for force in [false, true] {
            let e = claim(&foreign, "run", "aa", force).unwrap_err().to_string();
            assert!(e.contains("it holds notes.txt and no manifest.json"), "{e}");
            assert!(e.contains("--force does not clear it"), "{e}");
        }
        assert_eq!(listing(&foreign), [("notes.txt".into(), "mine".into())]);
        // Inputs that check themselves are adopted (a study's members gathered by hand), but
        // nothing else beside them.
        let gathered = t.path().join("gathered");
        std::fs::create_dir_all(gathered.join("members")).unwrap();
        std::fs::write(gathered.join("members/a-m0.csv"), "m").unwrap();
        drop(adopting(&gathered, "aa").unwrap());
        // ... also once the study has a manifest (`--merge` then `--resume`).
        adopting(&gathered, "aa")
            .unwrap()
            .finish(&[] as &[&str])
            .unwrap();
        drop(adopting(&gathered, "aa").unwrap());
        let mixed = t.path().join("mixed");
        std::fs::create_dir_all(mixed.join("members")).unwrap();
        std::fs::write(mixed.join("notes.txt"), "mine").unwrap();
        let e = adopting(&mixed, "aa").unwrap_err();
        assert!(e.to_string().contains("no manifest.json"), "{e}");
    }

    /// Issue 24, item 1: `--force` deletes exactly the files grainchain wrote and nobody changed,
    /// never an input, and refuses (deleting nothing, not advising --force) when anything else
    /// is in the folder.
    #[test]
    fn force_deletes_only_what_grainchain_wrote() {
        let t = tempfile::tempdir().unwrap();
        let dir = t.path().join("out");
        let o = claim(&dir, "run", "aa", false).unwrap();
        AtomicFile::write_all(dir.join("energies.csv"), b"e\n").unwrap();
        AtomicFile::write_all(dir.join("sub/deep.csv"), b"d\n").unwrap();
        o.finish(&["energies.csv"]).unwrap();
        // A file the user put there.
        std::fs::write(dir.join("notes.txt"), "mine").unwrap();
        let before = listing(&dir);
        for force in [false, true] {
            let e = claim(&dir, "run", "bb", force).unwrap_err().to_string();
            assert!(e.contains("grainchain did not write notes.txt"), "{e}");
            assert!(e.contains("--force would not help"), "{e}");
            assert!(!e.contains("pass --force"), "{e}");
            assert_eq!(listing(&dir), before);
        }
        // The same command on the same input: foreign entries are refused too.
        let e = claim(&dir, "run", "aa", false).unwrap_err().to_string();
        assert!(e.contains("grainchain did not write notes.txt"), "{e}");
        std::fs::remove_file(dir.join("notes.txt")).unwrap();
        // A file grainchain wrote and the user changed since is theirs: refused, naming it.
        std::fs::write(dir.join("energies.csv"), "edited\n").unwrap();
        let before = listing(&dir);
        for (d, force) in [("aa", false), ("bb", true)] {
            let e = claim(&dir, "run", d, force).unwrap_err().to_string();
            assert!(
                e.contains("energies.csv changed since grainchain wrote it"),
                "{e}"
            );
            assert_eq!(listing(&dir), before);
        }
        std::fs::write(dir.join("energies.csv"), "e\n").unwrap();
        // An input of the command is never deleted (a manifest that lists it).
        let e = OutDir::claim_with(
            &dir,
            Claim {
                command: "run",
                inputs: inputs("bb"),
                force: true,
                protect: vec![dir.join("sub/deep.csv")],
                ..Claim::default()
            },
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("sub/deep.csv is an input of this command"),
            "{e}"
        );
        assert!(dir.join("sub/deep.csv").exists());
        // Otherwise --force deletes them, and the folder they leave empty.
        let o = claim(&dir, "run", "bb", true).unwrap();
        let names: Vec<String> = listing(&dir)
            .into_iter()
            .map(|(n, _)| n)
            .filter(|n| !n.starts_with('.'))
            .collect();
        assert_eq!(names, [MANIFEST]);
        drop(o);
    }

    /// Issue 24, item 2: a refused claim leaves no lock file (or folder) it created.
    #[test]
    fn a_refused_claim_leaves_the_folder_as_it_was() {
        let t = tempfile::tempdir().unwrap();
        std::fs::write(t.path().join("README.md"), "mine").unwrap();
        let before = listing(t.path());
        claim(t.path(), "run", "aa", true).unwrap_err();
        assert_eq!(listing(t.path()), before);
        // A lock file that was there before stays (it is not this claim's).
        std::fs::write(t.path().join(LOCK), "").unwrap();
        let before = listing(t.path());
        claim(t.path(), "run", "aa", true).unwrap_err();
        assert_eq!(listing(t.path()), before);
    }

    /// Issue 24, item 3: the temporaries a killed process left (exactly `.<name>.XXXXXX.partial`)
    /// are removed by the next claim of the whole folder, and nothing else hidden is.
    #[test]
    fn partials_of_a_killed_run_are_removed_by_the_next_claim() {
        let t = tempfile::tempdir().unwrap();
        let dir = t.path().join("out");
        let o = adopting(&dir, "aa").unwrap();
        AtomicFile::write_all(dir.join("members/a-m0.csv"), b"m").unwrap();
        o.finish(&[] as &[&str]).unwrap();
        let left = [
            ".energies.csv.Ab12Cd.partial",
            "members/.a-m1.csv.zz99ZZ.partial",
        ];
        let mine = [
            ".notes.partial",
            ".energies.csv.Ab12Cd.partial.keep",
            ".git/.x.Ab12Cd.partial",
            ".env",
        ];
        for f in left.iter().chain(&mine) {
            std::fs::create_dir_all(dir.join(f).parent().unwrap()).unwrap();
            std::fs::write(dir.join(f), "half").unwrap();
        }
        // A part of the job does not remove them (another part may be writing).
        drop(OutDir::claim(&dir, "study", inputs("aa"), Some("shard-1-of-2"), false).unwrap());
        assert!(left.iter().all(|f| dir.join(f).exists()));
        drop(adopting(&dir, "aa").unwrap());
        for f in left {
            assert!(!dir.join(f).exists(), "{f}");
        }
        for f in mine {
            assert!(dir.join(f).exists(), "{f}");
        }
    }

    /// Issue 24, item 4: a command that fails while writing its outputs leaves a manifest that
    /// says so, with every file it wrote recorded; the same command again repairs it, and
    /// `--force` of another command deletes those files too.
    #[test]
    fn a_failed_write_is_recorded_and_repaired() {
        let t = tempfile::tempdir().unwrap();
        let dir = t.path().join("out");
        let o = claim(&dir, "study", "aa", false).unwrap();
        AtomicFile::write_all(dir.join("ensemble.csv"), b"half of the outputs").unwrap();
        AtomicFile::write_all(dir.join("old.csv"), b"not written again").unwrap();
        drop(o); // the write of the next output failed (disk full): no finish
        assert_eq!(manifest(&dir)["complete"], false);
        assert_eq!(manifest(&dir)["files"], serde_json::json!({}));
        let o = claim(&dir, "study", "aa", false).unwrap();
        AtomicFile::write_all(dir.join("ensemble.csv"), b"all of it").unwrap();
        AtomicFile::write_all(dir.join("fits.csv"), b"f").unwrap();
        o.finish(&["ensemble.csv", "fits.csv"]).unwrap();
        let m = manifest(&dir);
        assert_eq!(m["complete"], true);
        assert_eq!(m["files"].as_object().unwrap().len(), 2);
        assert!(!dir.join("old.csv").exists());
        // A failed write, then another command with --force: nothing of it is left.
        let o = claim(&dir, "study", "aa", false).unwrap();
        AtomicFile::write_all(dir.join("half.csv"), b"h").unwrap();
        drop(o);
        drop(claim(&dir, "run", "zz", true).unwrap());
        for f in ["ensemble.csv", "fits.csv", "half.csv"] {
            assert!(!dir.join(f).exists(), "{f}");
        }
    }

    /// Issue 24, item 5: a link in the folder is never adopted, written through or followed by
    /// --force; the refusal names it.
    #[test]
    fn a_link_out_of_the_folder_is_refused() {
        let t = tempfile::tempdir().unwrap();
        let outside = t.path().join("outside");
        std::fs::create_dir_all(&outside).unwrap();
        std::fs::write(outside.join("precious.csv"), "mine").unwrap();
        let dir = t.path().join("out");
        std::fs::create_dir_all(&dir).unwrap();
        std::os::unix::fs::symlink(&outside, dir.join("members")).unwrap();
        let e = adopting(&dir, "aa").unwrap_err().to_string();
        assert!(e.contains("members (a symbolic link to"), "{e}");
        // In a folder of grainchain's, with a manifest that even lists a file behind the link.
        std::fs::remove_file(dir.join("members")).unwrap();
        let o = adopting(&dir, "aa").unwrap();
        AtomicFile::write_all(dir.join("members/precious.csv"), b"mine").unwrap();
        o.finish(&[] as &[&str]).unwrap();
        std::fs::remove_dir_all(dir.join("members")).unwrap();
        std::os::unix::fs::symlink(&outside, dir.join("members")).unwrap();
        for (d, force) in [("aa", false), ("bb", true)] {
            let e = adopting(&dir, d)
                .err()
                .or_else(|| claim(&dir, "run", d, force).err())
                .unwrap()
                .to_string();
            assert!(e.contains("members (a symbolic link to"), "{e}");
        }
        let e = claim(&dir, "run", "bb", true).unwrap_err().to_string();
        assert!(e.contains("members (a symbolic link to"), "{e}");
        assert_eq!(
            std::fs::read_to_string(outside.join("precious.csv")).unwrap(),
            "mine"
        );
    }

    #[test]
    fn a_second_claim_while_the_first_holds_the_lock_fails_at_once() {
        let t = tempfile::tempdir().unwrap();
        let dir = t.path().join("out");
        let first = claim(&dir, "run", "aa", false).unwrap();
        let e = claim(&dir, "run", "aa", false).unwrap_err();
        assert!(
            e.to_string()
                .contains("another grainchain command is writing"),
            "{e}"
        );
        drop(first);
        claim(&dir, "run", "aa", false).unwrap();
    }

    /// Issue 24, item 6: parts of one job (a study's shards) run side by side, a second copy of
    /// one part is refused, and the whole folder's claim (a full study, a merge) and a part
    /// exclude each other.
    #[test]
    fn a_whole_claim_and_a_part_exclude_each_other() {
        let t = tempfile::tempdir().unwrap();
        let dir = t.path().join("out");
        let part = |p| OutDir::claim(&dir, "study", inputs("aa"), Some(p), false);
        let locked = |r: Result<OutDir, Error>| {
            let e = r.unwrap_err().to_string();
            assert!(e.contains("another grainchain command is writing"), "{e}");
        };
        let a = part("shard-1-of-2").unwrap();
        let b = part("shard-2-of-2").unwrap();
        locked(part("shard-1-of-2"));
        locked(claim(&dir, "study", "aa", false));
        drop((a, b));
        let whole = claim(&dir, "study", "aa", false).unwrap();
        locked(part("shard-1-of-2"));
        drop(whole);
        drop(part("shard-2-of-2").unwrap());
    }
}
