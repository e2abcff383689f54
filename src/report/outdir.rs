//! An output folder belongs to one command on one set of inputs.
//!
//! Every command that writes a folder (`run`, `reproduce`, `study`, `work-precision`) first
//! claims it with [`OutDir::claim`]:
//!
//! - it holds a lock (an advisory `flock` on `.grainchain.lock` in the folder, or on
//!   `.grainchain-<part>.lock` for one part of a job that several processes share, such as a
//!   study's shards), so a second command writing into the same folder fails at once with a
//!   clear message; the operating system releases the lock when the process ends, however it
//!   ends, so a killed run never leaves a stale lock;
//! - a folder with files in it must hold a `manifest.json` written by the same command on the
//!   same inputs (a rerun, `--resume`, `--merge`); anything else is refused, naming what wrote
//!   it, unless `--force` clears it first;
//! - the manifest is written at once (so the shards of one study starting together agree) and,
//!   when the command has finished, [`OutDir::finish`] records every file it wrote with its size
//!   and FNV-1a checksum, and deletes files an earlier run of the same command listed but this
//!   one did not write (a second run never leaves the first one's files beside its own).
//!
//! Files whose names start with a dot (the lock files, atomic writes in progress) do not count.

use crate::error::{Error, OutDirError};
use crate::report::{fnv1a, AtomicFile};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fs::File;
use std::path::{Path, PathBuf};

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

/// `manifest.json`: which command wrote the folder, on which inputs, with which program, and
/// its files.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Manifest {
    /// The program ([`crate::PROGRAM`]: version and git revision).
    pub program: String,
    /// The command (`run`, `reproduce`, `study`, `work-precision`).
    pub command: String,
    /// Digest of each input, by name (a scene file, a sweep, the command's options).
    pub inputs: BTreeMap<String, String>,
    /// The files written, relative to the folder, with their sizes and checksums (empty until
    /// the command has finished).
    pub files: BTreeMap<String, FileEntry>,
}

/// A claimed output folder (see the module).
#[derive(Debug)]
pub struct OutDir {
    dir: PathBuf,
    manifest: Manifest,
    /// Files of an earlier run of the same command and inputs (deleted by `finish` unless
    /// written again).
    earlier: BTreeMap<String, FileEntry>,
    _lock: File,
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

/// Why manifest `m` does not belong to `command` on `inputs` (`None`: it does).
fn other_owner(m: &Manifest, command: &str, inputs: &BTreeMap<String, String>) -> Option<String> {
    if m.command != command {
        return Some(format!(
            "`grainchain {}` wrote it, this is `grainchain {command}`",
            m.command
        ));
    }
    let names: std::collections::BTreeSet<&String> = m.inputs.keys().chain(inputs.keys()).collect();
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

impl OutDir {
    /// Claim `dir` for `command` on `inputs` (input name to digest), holding the lock
    /// `.grainchain.lock`, or `.grainchain-<part>.lock` for a `part` of a job that several
    /// processes share (see the module). `force` clears a folder that belongs to something else.
    pub fn claim(
        dir: &Path,
        command: &str,
        inputs: BTreeMap<String, String>,
        part: Option<&str>,
        force: bool,
    ) -> Result<OutDir, Error> {
        Self::claim_adopting(dir, command, inputs, part, force, &[])
    }

    /// [`OutDir::claim`], also accepting a folder without a manifest whose only entries are
    /// named in `adopt`: inputs that check themselves, such as a study's `members/` gathered
    /// from shards by hand (every member file carries its batch's digest and checksum).
    pub fn claim_adopting(
        dir: &Path,
        command: &str,
        inputs: BTreeMap<String, String>,
        part: Option<&str>,
        force: bool,
        adopt: &[&str],
    ) -> Result<OutDir, Error> {
        let io = |path: &Path| {
            let path = path.to_path_buf();
            move |source| Error::Io { path, source }
        };
        std::fs::create_dir_all(dir).map_err(io(dir))?;
        let lock_path = dir.join(match part {
            Some(p) => format!(".grainchain-{p}.lock"),
            None => ".grainchain.lock".into(),
        });
        let lock = File::options()
            .create(true)
            .truncate(false)
            .write(true)
            .open(&lock_path)
            .map_err(io(&lock_path))?;
        if let Err(e) = lock.try_lock() {
            return Err(match e {
                std::fs::TryLockError::WouldBlock => OutDirError::Locked {
                    dir: dir.to_path_buf(),
                    lock: lock_path,
                }
                .into(),
                std::fs::TryLockError::Error(source) => Error::Io {
                    path: lock_path,
                    source,
                },
            });
        }
        let manifest_path = dir.join(MANIFEST);
        let entries = visible(dir)?;
        let adoptable = entries.iter().all(|p| {
            p.file_name()
                .is_some_and(|n| adopt.iter().any(|a| n == std::ffi::OsStr::new(a)))
        });
        let found = match std::fs::read_to_string(&manifest_path) {
            Ok(text) => Some(serde_json::from_str::<Manifest>(&text).map_err(|e| {
                OutDirError::BadManifest {
                    file: manifest_path.clone(),
                    message: e.to_string(),
                }
            })),
            Err(_) => None,
        };
        let owner = match (&found, entries.is_empty()) {
            (_, true) => None,
            (Some(Ok(m)), false) => other_owner(m, command, &inputs),
            (Some(Err(e)), false) => Some(e.to_string()),
            (None, false) if adoptable => None,
            (None, false) => Some(format!(
                "it holds {} file(s) and no {MANIFEST}, so grainchain did not write it",
                entries.len()
            )),
        };
        let mut earlier = BTreeMap::new();
        match owner {
            Some(why) if !force => {
                return Err(OutDirError::NotOurs {
                    dir: dir.to_path_buf(),
                    why,
                }
                .into())
            }
            Some(_) => {
                for p in entries {
                    let r = if p.is_dir() {
                        std::fs::remove_dir_all(&p)
                    } else {
                        std::fs::remove_file(&p)
                    };
                    r.map_err(io(&p))?;
                }
            }
            None => {
                if let Some(Ok(m)) = found {
                    earlier = m.files;
                }
            }
        }
        let manifest = Manifest {
            program: crate::PROGRAM.to_string(),
            command: command.to_string(),
            inputs,
            files: earlier.clone(),
        };
        let out = OutDir {
            dir: dir.to_path_buf(),
            manifest,
            earlier,
            _lock: lock,
        };
        out.write_manifest()?;
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
    /// sizes and checksums) in the manifest, and delete files an earlier run of the same command
    /// listed that this one did not write.
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
        for stale in self.earlier.keys().filter(|k| !files.contains_key(*k)) {
            let p = self.dir.join(stale);
            if p.is_file() {
                std::fs::remove_file(&p).map_err(|source| Error::Io { path: p, source })?;
            }
        }
        self.manifest.files = files;
        self.write_manifest()
    }
}

/// A TOML input file as parsed: tables are ordered maps, so comments, spacing, key order and
/// the spelling of numbers do not change it. Errors name the file (and line and column).
pub fn read_toml(path: &Path) -> Result<toml::Value, Error> {
    let text = std::fs::read_to_string(path).map_err(|source| {
        Error::Scene(crate::error::SceneError::Read {
            file: path.to_path_buf(),
            source,
        })
    })?;
    toml::from_str(&text).map_err(|e| {
        Error::Scene(crate::error::SceneError::Parse {
            file: path.to_path_buf(),
            message: crate::scene::file::describe_toml_error(&e, &text),
        })
    })
}

/// Digest of a TOML input file as parsed ([`read_toml`]): what an output folder's manifest
/// records of a scene or sweep file.
pub fn toml_digest(path: &Path) -> Result<String, Error> {
    Ok(fnv1a(&serde_json::to_vec(&read_toml(path)?)?))
}

/// The files directly in `dir` whose names end with one of `extensions` (the outputs a command
/// wrote there), as names relative to `dir`, sorted.
pub fn files_with(dir: &Path, extensions: &[&str]) -> Result<Vec<String>, Error> {
    let mut v: Vec<String> = visible(dir)?
        .into_iter()
        .filter(|p| p.is_file())
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

    #[test]
    fn a_folder_belongs_to_one_command_on_one_input() {
        let t = tempfile::tempdir().unwrap();
        let dir = t.path().join("out");
        let o = OutDir::claim(&dir, "run", inputs("aa"), None, false).unwrap();
        std::fs::write(dir.join("energies.csv"), "x\n").unwrap();
        std::fs::write(dir.join("pulses.csv"), "y\n").unwrap();
        o.finish(&["energies.csv", "pulses.csv"]).unwrap();
        // The same command on the same input: a rerun, which drops what it no longer writes.
        let o = OutDir::claim(&dir, "run", inputs("aa"), None, false).unwrap();
        o.finish(&["energies.csv"]).unwrap();
        assert!(!dir.join("pulses.csv").exists());
        // Another input or another command: refused, naming why; --force clears.
        let e = OutDir::claim(&dir, "run", inputs("bb"), None, false).unwrap_err();
        assert!(e.to_string().contains("input `scene` differs"), "{e}");
        let e = OutDir::claim(&dir, "study", inputs("aa"), None, false).unwrap_err();
        assert!(e.to_string().contains("`grainchain run` wrote it"), "{e}");
        let o = OutDir::claim(&dir, "study", inputs("aa"), None, true).unwrap();
        assert!(!dir.join("energies.csv").exists());
        drop(o);
        // A folder grainchain did not write.
        let foreign = t.path().join("foreign");
        std::fs::create_dir_all(&foreign).unwrap();
        std::fs::write(foreign.join("notes.txt"), "mine").unwrap();
        let e = OutDir::claim(&foreign, "run", inputs("aa"), None, false).unwrap_err();
        assert!(e.to_string().contains("no manifest.json"), "{e}");
        assert!(foreign.join("notes.txt").exists());
        // Inputs that check themselves are adopted (a study's members gathered by hand), but
        // nothing else beside them.
        let gathered = t.path().join("gathered");
        std::fs::create_dir_all(gathered.join("members")).unwrap();
        OutDir::claim_adopting(&gathered, "study", inputs("aa"), None, false, &["members"])
            .unwrap();
        let mixed = t.path().join("mixed");
        std::fs::create_dir_all(mixed.join("members")).unwrap();
        std::fs::write(mixed.join("notes.txt"), "mine").unwrap();
        let e = OutDir::claim_adopting(&mixed, "study", inputs("aa"), None, false, &["members"])
            .unwrap_err();
        assert!(e.to_string().contains("no manifest.json"), "{e}");
    }

    #[test]
    fn a_second_claim_while_the_first_holds_the_lock_fails_at_once() {
        let t = tempfile::tempdir().unwrap();
        let dir = t.path().join("out");
        let first = OutDir::claim(&dir, "run", inputs("aa"), None, false).unwrap();
        let e = OutDir::claim(&dir, "run", inputs("aa"), None, false).unwrap_err();
        assert!(
            e.to_string()
                .contains("another grainchain command is writing"),
            "{e}"
        );
        // Parts of one job (a study's shards) hold locks of their own.
        let a = OutDir::claim(&dir, "run", inputs("aa"), Some("shard-1-of-2"), false).unwrap();
        let b = OutDir::claim(&dir, "run", inputs("aa"), Some("shard-2-of-2"), false).unwrap();
        drop((first, a, b));
        OutDir::claim(&dir, "run", inputs("aa"), None, false).unwrap();
    }
}
