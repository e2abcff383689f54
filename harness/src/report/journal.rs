//! The journal of a claimed output folder: every file grainchain commits into a folder claimed
//! by this process ([`crate::report::outdir`]) is recorded here first, with its size and
//! checksum, by [`crate::report::AtomicFile`]. Below both (the atomic writer records into it,
//! the folder's claim reads it and writes its manifest with the atomic writer), so neither
//! depends on the other.

use crate::error::{Error, OutDirError};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fs::File;
use std::io::Write as _;
use std::path::{Component, Path, PathBuf};
use std::sync::Mutex;

/// The name of the manifest in an output folder.
pub const MANIFEST: &str = "manifest.json";

/// One file of the manifest.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct FileEntry {
    /// Size in bytes.
    pub size: u64,
    /// FNV-1a 64 of its bytes, as 16 hex digits.
    pub fnv: String,
}

/// One line of a folder's journal: a file grainchain committed there.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct Written {
    path: String,
    size: u64,
    fnv: String,
}

/// A folder claimed by this process: its journal, and the subfolders its command adopts (which
/// check what is in them themselves, such as a study's members).
struct Claimed {
    dir: PathBuf,
    journal: PathBuf,
    adopt: Vec<String>,
}

/// Folders claimed by this process ([`record_commit`]).
static CLAIMED: Mutex<Vec<Claimed>> = Mutex::new(Vec::new());

/// Record a file about to be committed at `dest` (size and FNV-1a) in the journal of the
/// claimed folder it lies in, if any (called by [`AtomicFile::commit`] before the rename).
///
/// A file already at `dest` is replaced only if grainchain wrote one there (a record of `dest`
/// in the folder's journals or manifest): the promise is that it replaces only what it wrote,
/// in every subfolder as at the top (issue 38: a user's `members/a-m0.csv` was overwritten).
/// In a folder the command adopts (members gathered by hand carry no record here) the command
/// checks what it replaces itself (`batch::write_member`).
pub(crate) fn record_commit(dest: &Path, size: u64, fnv: &str) -> Result<(), Error> {
    let claimed = CLAIMED.lock().unwrap_or_else(|e| e.into_inner());
    let Some((c, rel)) = claimed.iter().find_map(|c| {
        let rel = dest.strip_prefix(&c.dir).ok()?;
        Some((c, relative_name(rel)?))
    }) else {
        return Ok(());
    };
    let (dir, journal) = (&c.dir, &c.journal);
    if rel == MANIFEST || rel.starts_with(".grainchain") {
        return Ok(());
    }
    let adopted = c
        .adopt
        .iter()
        .any(|a| rel.split('/').next() == Some(a.as_str()));
    if !adopted && std::fs::symlink_metadata(dest).is_ok() && !recorded(dir, &rel) {
        return Err(OutDirError::NotOurs {
            dir: dir.clone(),
            why: format!(
                "{rel} is in the way: grainchain did not write it (no record of it in the \
                 folder's journal or manifest), and it replaces only what it wrote"
            ),
            advice: "move or remove it, then run the command again".into(),
        }
        .into());
    }
    let line = line(
        rel,
        &FileEntry {
            size,
            fnv: fnv.to_string(),
        },
    )?;
    let io = |source| Error::Io {
        path: journal.clone(),
        source,
    };
    let mut f = File::options()
        .create(true)
        .append(true)
        .open(journal)
        .map_err(io)?;
    f.write_all(line.as_bytes()).map_err(io)?;
    f.sync_data().map_err(io)
}

/// Whether grainchain wrote a file at `rel` in `dir`: a record of it in one of the folder's
/// journals or in its manifest's files. Read only when a commit would replace a file.
pub(crate) fn recorded(dir: &Path, rel: &str) -> bool {
    read_journals(dir).contains_key(rel)
        || std::fs::read(dir.join(MANIFEST))
            .ok()
            .and_then(|b| serde_json::from_slice::<serde_json::Value>(&b).ok())
            .is_some_and(|m| m["files"].get(rel).is_some())
}

/// `rel` as the `/`-separated name the manifest uses, if it is a plain relative path (no `..`,
/// no root, not empty).
fn relative_name(rel: &Path) -> Option<String> {
    let mut parts = Vec::new();
    for c in rel.components() {
        match c {
            Component::Normal(s) => parts.push(s.to_str()?.to_string()),
            Component::CurDir => {}
            _ => return None,
        }
    }
    (!parts.is_empty()).then(|| parts.join("/"))
}

/// One journal line (with its newline): the file `path` (relative to the folder) as `entry`
/// records it.
pub(crate) fn line(path: String, entry: &FileEntry) -> Result<String, Error> {
    Ok(serde_json::to_string(&Written {
        path,
        size: entry.size,
        fnv: entry.fnv.clone(),
    })? + "\n")
}

/// Record commits into `dir` in `journal` from now on ([`record_commit`]).
pub(crate) fn register(dir: &Path, journal: &Path, adopt: &[&str]) {
    CLAIMED
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .push(Claimed {
            dir: dir.to_path_buf(),
            journal: journal.to_path_buf(),
            adopt: adopt.iter().map(|a| a.to_string()).collect(),
        });
}

/// Stop recording into `journal`.
pub(crate) fn unregister(journal: &Path) {
    let mut claimed = CLAIMED.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(i) = claimed.iter().position(|c| c.journal == journal) {
        claimed.remove(i);
    }
}

/// The journals of a folder (every part's), read: each record by path, in the order written.
/// Lines that do not read (one being appended by a part running beside) are skipped.
pub(crate) fn read_journals(dir: &Path) -> BTreeMap<String, Vec<FileEntry>> {
    let mut out: BTreeMap<String, Vec<FileEntry>> = BTreeMap::new();
    for p in journal_files(dir) {
        let Ok(text) = std::fs::read_to_string(&p) else {
            continue;
        };
        for w in text
            .lines()
            .filter_map(|l| serde_json::from_str::<Written>(l).ok())
        {
            out.entry(w.path).or_default().push(FileEntry {
                size: w.size,
                fnv: w.fnv,
            });
        }
    }
    out
}

/// The journal files of `dir`: `.grainchain.written` and `.grainchain-<part>.written`.
pub(crate) fn journal_files(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .flatten()
        .filter(|e| {
            let n = e.file_name().to_string_lossy().into_owned();
            e.file_type().is_ok_and(|t| t.is_file())
                && (n == ".grainchain.written"
                    || (n.starts_with(".grainchain-") && n.ends_with(".written")))
        })
        .map(|e| e.path())
        .collect();
    v.sort();
    v
}

pub(crate) fn journal_name(part: Option<&str>) -> String {
    match part {
        Some(p) => format!(".grainchain-{p}.written"),
        None => ".grainchain.written".into(),
    }
}
