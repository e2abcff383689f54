//! Files that appear complete or not at all: written to a temporary file in the destination
//! directory, then renamed over the destination on [`AtomicFile::commit`]. Dropping an uncommitted
//! file (an error, a panic) deletes the temporary; a process stopped by a signal calls
//! [`remove_partials`] (the CLI does, on SIGINT and SIGTERM), which deletes every temporary still
//! open.

use crate::error::Error;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// Temporary files of every open [`AtomicFile`] of this process.
static PARTIALS: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Delete the temporary file of every [`AtomicFile`] not yet committed or dropped: for a signal
/// handler, before the process exits without unwinding. Returns how many were deleted.
pub fn remove_partials() -> usize {
    let list = match PARTIALS.lock() {
        Ok(l) => l,
        Err(poisoned) => poisoned.into_inner(),
    };
    list.iter()
        .filter(|p| std::fs::remove_file(p).is_ok())
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

/// A file written in full or not at all (see the module).
pub struct AtomicFile {
    path: PathBuf,
    writer: BufWriter<tempfile::NamedTempFile>,
    _registered: Registered,
}

impl AtomicFile {
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
            .suffix(".partial")
            .tempfile_in(dir)
            .map_err(io)?;
        let registered = Registered::new(tmp.path());
        Ok(AtomicFile {
            path,
            writer: BufWriter::new(tmp),
            _registered: registered,
        })
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Flush and move into place.
    pub fn commit(self) -> Result<(), Error> {
        let AtomicFile {
            path,
            writer,
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
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.writer.write(buf)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.writer.flush()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `remove_partials` deletes every open temporary of the process, so the tests that hold
    /// one open must not overlap it.
    static SERIAL: Mutex<()> = Mutex::new(());

    #[test]
    fn remove_partials_deletes_open_temporaries_only() {
        let _one = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
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
        // Other tests of this process may have open files too: at least this one goes.
        assert!(remove_partials() >= 1);
        assert_eq!(files(), vec!["done.csv".to_string()]);
        drop(open);
    }

    #[test]
    fn uncommitted_file_leaves_nothing() {
        let _one = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
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
