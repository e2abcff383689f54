//! Files that appear complete or not at all: written to a temporary file in the destination
//! directory (`.<name>.XXXXXX.partial`, [`is_partial`]), then renamed over the destination on
//! [`AtomicFile::commit`]. Dropping an uncommitted file (an error, a panic) deletes the
//! temporary; a process stopped by a signal calls [`remove_partials`] (the CLI does, on SIGINT
//! and SIGTERM), which deletes every temporary still open. A process killed outright (SIGKILL,
//! a power cut) cannot: the next command that claims the folder removes them
//! ([`crate::report::outdir`]).
//!
//! A commit into a claimed output folder is recorded there first (its path, size and checksum,
//! in the folder's journal, `report::journal`), so the folder knows every file grainchain wrote into it, also when
//! the command fails before it lists its outputs in `manifest.json`.

use crate::error::Error;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// Temporary files of every open [`AtomicFile`] of this process.
static PARTIALS: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Delete the temporary file of every [`AtomicFile`] not yet committed or dropped: for a signal
/// handler, before the process exits without unwinding. Returns how many were deleted.
pub fn remove_partials() -> usize {
    remove_partials_where(|_| true)
}

/// [`remove_partials`] restricted to the temporaries `select` accepts (tests use it to leave the
/// files of tests running beside them alone).
fn remove_partials_where(select: impl Fn(&Path) -> bool) -> usize {
    let list = match PARTIALS.lock() {
        Ok(l) => l,
        Err(poisoned) => poisoned.into_inner(),
    };
    list.iter()
        .filter(|p| select(p) && std::fs::remove_file(p).is_ok())
        .count()
}

/// Keeps a temporary file in [`PARTIALS`] while it lives.
struct Registered(PathBuf);

impl Registered {
    fn new(p: &Path) -> Self {
        if let Ok(mut l) = PARTIALS.lock() {
            l.push(p.to_path_buf());
        }
        Registered(p.to_path_buf())
    }
}

impl Drop for Registered {
    fn drop(&mut self) {
        if let Ok(mut l) = PARTIALS.lock() {
            if let Some(i) = l.iter().position(|p| *p == self.0) {
                l.swap_remove(i);
            }
        }
    }
}

/// Random characters `tempfile` puts between the prefix and the suffix of a temporary's name.
const RANDOM_CHARS: usize = 6;

/// Whether `name` is the name of an [`AtomicFile`]'s temporary: `.<name>.XXXXXX.partial`, with
/// six ASCII letters or digits and a non-empty `<name>`. Nothing else is ever taken for one.
pub fn is_partial(name: &str) -> bool {
    let Some(stem) = name
        .strip_prefix('.')
        .and_then(|n| n.strip_suffix(".partial"))
    else {
        return false;
    };
    match stem.len().checked_sub(RANDOM_CHARS + 1) {
        Some(cut) if cut > 0 && stem.is_char_boundary(cut) => {
            let (base, tail) = stem.split_at(cut);
            !base.is_empty()
                && tail.starts_with('.')
                && tail[1..].bytes().all(|b| b.is_ascii_alphanumeric())
        }
        _ => false,
    }
}

/// A file written in full or not at all (see the module).
pub struct AtomicFile {
    path: PathBuf,
    writer: BufWriter<tempfile::NamedTempFile>,
    /// Bytes written so far and their FNV-1a state (recorded on commit).
    size: u64,
    fnv: fnv::FnvHasher,
    /// Whether the commit is recorded in the claimed folder's journal (see
    /// [`AtomicFile::write_unrecorded`]).
    record: bool,
    _registered: Registered,
}

impl AtomicFile {
    /// Open a temporary file (`.<name>.XXXX.partial`) beside `path`, creating the directory if
    /// needed; nothing appears at `path` until [`AtomicFile::commit`].
    pub fn create(path: impl AsRef<Path>) -> Result<Self, Error> {
        let path = path.as_ref().to_path_buf();
        let dir = path
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        let io = |source| Error::Io {
            path: path.clone(),
            source,
        };
        std::fs::create_dir_all(dir).map_err(io)?;
        let name = path
            .file_name()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let tmp = tempfile::Builder::new()
            .prefix(&format!(".{name}."))
            .rand_bytes(RANDOM_CHARS)
            .suffix(".partial")
            .tempfile_in(dir)
            .map_err(io)?;
        let registered = Registered::new(tmp.path());
        Ok(AtomicFile {
            path,
            writer: BufWriter::new(tmp),
            size: 0,
            fnv: fnv::FnvHasher::default(),
            record: true,
            _registered: registered,
        })
    }

    /// The destination path (where the file appears on commit).
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Flush and move into place.
    pub fn commit(self) -> Result<(), Error> {
        let AtomicFile {
            path,
            writer,
            size,
            fnv,
            record,
            _registered,
        } = self;
        let io = |source| Error::Io {
            path: path.clone(),
            source,
        };
        let tmp = writer.into_inner().map_err(|e| io(e.into_error()))?;
        // tempfile creates 0600 files; results are meant to be shared like any other output.
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            tmp.as_file()
                .set_permissions(std::fs::Permissions::from_mode(0o644))
                .map_err(io)?;
        }
        tmp.as_file().sync_all().map_err(io)?;
        // Recorded before it appears: a process killed between the two leaves a record of a file
        // that is not there, never a file of grainchain's that no record names.
        if record {
            super::journal::record_commit(
                &path,
                size,
                &format!("{:016x}", std::hash::Hasher::finish(&fnv)),
            )?;
        }
        tmp.persist(&path).map_err(|e| io(e.error))?;
        Ok(())
    }

    /// Write a whole file atomically.
    pub fn write_all(path: impl AsRef<Path>, bytes: &[u8]) -> Result<(), Error> {
        let mut f = AtomicFile::create(path)?;
        f.write_all(bytes).map_err(|source| Error::Io {
            path: f.path.clone(),
            source,
        })?;
        f.commit()
    }

    /// Write a whole file atomically without recording it in the claimed folder's journal: for
    /// a file the command checks by its own content and changes after writing it, which the
    /// folder must then not take for an output changed by someone else (a design's journal,
    /// rewritten by `--resume` and then appended to, and its island's convergence file, in the
    /// adopted `evaluations/`; `design::search`). The caller checks that what it replaces is
    /// its own.
    pub fn write_unrecorded(path: impl AsRef<Path>, bytes: &[u8]) -> Result<(), Error> {
        let mut f = AtomicFile::create(path)?;
        f.record = false;
        f.write_all(bytes).map_err(|source| Error::Io {
            path: f.path.clone(),
            source,
        })?;
        f.commit()
    }
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = self.writer.write(buf)?;
        self.size += n as u64;
        std::hash::Hasher::write(&mut self.fnv, &buf[..n]);
        Ok(n)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.writer.flush()
    }
}

/// A CSV file of `header` and `rows` (each a line without its newline), written atomically.
pub fn csv_file(
    path: &std::path::Path,
    header: &str,
    rows: impl Iterator<Item = String>,
) -> Result<(), crate::error::Error> {
    use std::io::Write;
    let mut f = AtomicFile::create(path)?;
    let io = |source| crate::error::Error::Io {
        path: path.to_path_buf(),
        source,
    };
    writeln!(f, "{header}").map_err(io)?;
    for r in rows {
        writeln!(f, "{r}").map_err(io)?;
    }
    f.commit()
}

/// Write the CSV file `path` atomically from row structs through `csv`: the header is the
/// structs' field names, so a column's name and its value cannot drift apart.
pub fn csv_rows<T: serde::Serialize>(
    path: &std::path::Path,
    rows: &[T],
) -> Result<(), crate::error::Error> {
    let err = |source: csv::Error| crate::error::Error::Csv {
        what: path.display().to_string(),
        source,
    };
    let mut w = csv::Writer::from_writer(Vec::new());
    for r in rows {
        w.serialize(r).map_err(err)?;
    }
    let bytes = w.into_inner().map_err(|e| crate::error::Error::Io {
        path: path.to_path_buf(),
        source: e.into_error(),
    })?;
    AtomicFile::write_all(path, &bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn remove_partials_deletes_open_temporaries_only() {
        let dir = tempfile::tempdir().unwrap();
        let mut done = AtomicFile::create(dir.path().join("done.csv")).unwrap();
        done.write_all(b"x").unwrap();
        done.commit().unwrap();
        let mut open = AtomicFile::create(dir.path().join("open.csv")).unwrap();
        open.write_all(b"half").unwrap();
        open.flush().unwrap();
        let files = || {
            let mut v: Vec<String> = std::fs::read_dir(dir.path())
                .unwrap()
                .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .collect();
            v.sort();
            v
        };
        assert_eq!(files().len(), 2);
        // Only this test's directory: tests running beside it in this process have their own
        // open temporaries, which the unrestricted `remove_partials` would delete under them.
        assert_eq!(remove_partials_where(|p| p.starts_with(dir.path())), 1);
        assert_eq!(files(), vec!["done.csv".to_string()]);
        drop(open);
    }

    #[test]
    fn partial_names_are_exactly_the_temporaries() {
        let dir = tempfile::tempdir().unwrap();
        let open = AtomicFile::create(dir.path().join("energies.csv")).unwrap();
        let name = std::fs::read_dir(dir.path())
            .unwrap()
            .next()
            .unwrap()
            .unwrap();
        assert!(is_partial(&name.file_name().to_string_lossy()));
        drop(open);
        for yes in [".energies.csv.a1B2c3.partial", ".x.ZZZZZZ.partial"] {
            assert!(is_partial(yes), "{yes}");
        }
        for no in [
            "energies.csv.a1B2c3.partial",
            "..a1B2c3.partial",
            ".energies.csv.a1B2c.partial",
            ".energies.csv.a1B2c3d.partial",
            ".energies.csv.a1-2c3.partial",
            ".energies.csva1B2c3.partial",
            ".notes.partial",
            ".energies.csv.a1B2c3.partial.bak",
            ".grainchain.lock",
        ] {
            assert!(!is_partial(no), "{no}");
        }
    }

    #[test]
    fn uncommitted_file_leaves_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.csv");
        {
            let mut f = AtomicFile::create(&p).unwrap();
            f.write_all(b"half").unwrap();
        }
        assert!(!p.exists());
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
        let mut f = AtomicFile::create(&p).unwrap();
        f.write_all(b"whole").unwrap();
        f.commit().unwrap();
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "whole");
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let mode = std::fs::metadata(&p).unwrap().permissions().mode() & 0o777;
            assert_eq!(mode, 0o644);
        }
    }
}
