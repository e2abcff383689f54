//! The Monte Carlo's journal (`evaluations/monte-carlo.csv`): every tolerance column evaluated
//! after the searches (the `[tolerances]` analysis, a robust objective's finalists and winners)
//! is appended as it finishes, keyed by what its evaluation reads, so that `--resume` after a
//! late interruption runs only the columns that had not finished, and gives the same bits. A
//! column met twice in one run (the nominal winner is the robust one) is run once.
//!
//! A line is `key,<the evaluation's fields>,fnv`: `key` is FNV-1a of the column, impact, protected
//! body and settings exactly as evaluated (Rust's `{:?}`, whose numbers read back to the same
//! bits), the fields are [`Evaluation`] through `csv` (its header is the file's second line), and
//! `fnv` is FNV-1a of the line before it. The first line names the program: a journal of
//! another build starts afresh, since its engine may give other bits.

use crate::error::{Error, JournalError};
use grainchain_engine::protector::{Bead, Evaluation, Impact, Protected, Settings};
use std::collections::HashMap;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Mutex, RwLock};

/// The journal's file name in `evaluations/`.
pub const MONTE_CARLO_JOURNAL: &str = "monte-carlo.csv";

/// How its first line starts (then the program that wrote it).
const FIRST: &str = "# grainchain monte carlo journal, ";

/// The journal of one run of `grainchain design`: what earlier runs finished (read on
/// `--resume`) and this one, and the file each new evaluation is appended to.
#[derive(Debug)]
pub struct DrawsJournal {
    path: PathBuf,
    known: RwLock<HashMap<String, Evaluation>>,
    /// The file appended to, and the first failure to append a line (none written after it).
    file: Mutex<(std::fs::File, Option<std::io::Error>)>,
    /// Evaluations taken from the journal, and run, by this process.
    reused: AtomicU64,
    ran: AtomicU64,
}

/// The header: `key`, [`Evaluation`]'s fields as `csv` names them, `fnv`.
fn header() -> String {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.serialize(Evaluation::default())
        .expect("an evaluation serialises");
    let bytes = w.into_inner().expect("in memory");
    let text = String::from_utf8(bytes).expect("csv writes UTF-8");
    let names = text.lines().next().expect("a header line");
    format!("key,{names},fnv")
}

/// An evaluation's fields as one CSV record (no line end).
fn fields(e: &Evaluation) -> String {
    let mut w = csv::WriterBuilder::new()
        .has_headers(false)
        .from_writer(Vec::new());
    w.serialize(e).expect("an evaluation serialises");
    let bytes = w.into_inner().expect("in memory");
    String::from_utf8(bytes)
        .expect("csv writes UTF-8")
        .trim_end()
        .to_string()
}

/// A line of the journal, with its line end.
fn line(key: &str, e: &Evaluation) -> String {
    let body = format!("{key},{}", fields(e));
    let fnv = crate::report::fnv1a(body.as_bytes());
    format!("{body},{fnv}\n")
}

/// Read a line back: its key and evaluation, or what is wrong with it.
fn parse(text: &str) -> Result<(String, Evaluation), String> {
    let (body, fnv) = text
        .rsplit_once(',')
        .ok_or("not a line of the journal (no checksum)")?;
    if crate::report::fnv1a(body.as_bytes()) != fnv {
        return Err("its checksum does not match: changed after it was written".into());
    }
    let (key, rest) = body.split_once(',').ok_or("no key")?;
    let mut r = csv::ReaderBuilder::new()
        .has_headers(false)
        .from_reader(rest.as_bytes());
    let e: Evaluation = r
        .deserialize()
        .next()
        .ok_or("no fields")?
        .map_err(|e| format!("its fields do not read: {e}"))?;
    Ok((key.to_string(), e))
}

/// The key of a column's evaluation: FNV-1a of everything it reads, exactly.
pub fn key(column: &[Bead], impact: &Impact, protected: &Protected, settings: &Settings) -> String {
    crate::report::fnv1a(format!("{column:?};{impact:?};{protected:?};{settings:?}").as_bytes())
}

impl DrawsJournal {
    /// Open the journal at `path`: read it when `resume` (the lines of this program; a last line
    /// cut by an interruption is dropped, any other damaged line refused), write it again with
    /// what it held, and append from there. Without `resume` it starts empty. A file in its
    /// place that grainchain did not write is refused, never replaced.
    pub fn open(path: &Path, resume: bool) -> Result<DrawsJournal, Error> {
        let io = |source| Error::Io {
            path: path.to_path_buf(),
            source,
        };
        let first = format!("{FIRST}{}", crate::program());
        let head = header();
        let mut known = HashMap::new();
        match std::fs::read(path) {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
            Err(source) => return Err(io(source)),
            Ok(bytes) => {
                if !bytes.starts_with(FIRST.as_bytes()) {
                    return Err(crate::error::OutDirError::NotOurs {
                        dir: path.parent().map(Path::to_path_buf).unwrap_or_default(),
                        why: format!(
                            "{} is in the way: it is not a Monte Carlo journal grainchain wrote \
                             (its first line does not start `{}`), and grainchain replaces \
                             only what it wrote",
                            path.display(),
                            FIRST.trim_end_matches(", ")
                        ),
                        advice: "move or remove it, then run the command again".into(),
                    }
                    .into());
                }
                if resume {
                    known = read(path, &bytes, &first, &head)?;
                }
            }
        }
        let mut keys: Vec<(&String, &Evaluation)> = known.iter().collect();
        keys.sort_by(|a, b| a.0.cmp(b.0));
        let mut text = format!("{first}\n{head}\n");
        for (k, e) in keys {
            text.push_str(&line(k, e));
        }
        crate::report::AtomicFile::write_unrecorded(path, text.as_bytes())?;
        let file = std::fs::OpenOptions::new()
            .append(true)
            .open(path)
            .map_err(io)?;
        Ok(DrawsJournal {
            path: path.to_path_buf(),
            known: RwLock::new(known),
            file: Mutex::new((file, None)),
            reused: AtomicU64::new(0),
            ran: AtomicU64::new(0),
        })
    }

    /// The evaluation of `key`, if an earlier run or this one finished it.
    pub fn get(&self, key: &str) -> Option<Evaluation> {
        let known = self.known.read().unwrap_or_else(|p| p.into_inner());
        let e = known.get(key).copied();
        if e.is_some() {
            self.reused.fetch_add(1, Ordering::Relaxed);
        }
        e
    }

    /// Append the evaluation of `key`, one whole line per write. A failure to write is kept for
    /// [`DrawsJournal::check`], and nothing is written after it (the evaluations go on: the
    /// journal only saves work for a later `--resume`).
    pub fn put(&self, key: &str, e: &Evaluation) {
        self.ran.fetch_add(1, Ordering::Relaxed);
        self.known
            .write()
            .unwrap_or_else(|p| p.into_inner())
            .insert(key.to_string(), *e);
        let text = line(key, e);
        let mut guard = self.file.lock().unwrap_or_else(|p| p.into_inner());
        let (file, failed) = &mut *guard;
        if failed.is_none() {
            *failed = file.write_all(text.as_bytes()).err();
        }
    }

    /// The first failure to write the journal, as an error naming it.
    pub fn check(&self) -> Result<(), Error> {
        let mut guard = self.file.lock().unwrap_or_else(|p| p.into_inner());
        match guard.1.take() {
            None => Ok(()),
            Some(source) => Err(Error::Io {
                path: self.path.clone(),
                source,
            }),
        }
    }

    /// Evaluations this process took from the journal (an earlier run's, or its own), and ran.
    pub fn counts(&self) -> (u64, u64) {
        (
            self.reused.load(Ordering::Relaxed),
            self.ran.load(Ordering::Relaxed),
        )
    }
}

/// The lines of a journal's `bytes` (at `path`) of this program; one of another program's is
/// nothing to resume.
fn read(
    path: &Path,
    bytes: &[u8],
    first: &str,
    head: &str,
) -> Result<HashMap<String, Evaluation>, Error> {
    let damaged = |line: usize, problem: String| -> Error {
        JournalError::Damaged {
            file: path.to_path_buf(),
            line: Some(line),
            problem,
            advice: "run the command again without --resume, which starts this journal afresh"
                .into(),
        }
        .into()
    };
    let mut pieces: Vec<&[u8]> = bytes.split(|&b| b == b'\n').collect();
    // After a final line end the last piece is empty; else it is a line cut by an interruption.
    pieces.pop();
    let mut known = HashMap::new();
    for (i, p) in pieces.iter().enumerate() {
        let text = std::str::from_utf8(p)
            .map_err(|_| damaged(i + 1, "not UTF-8 text: damaged after it was written".into()))?;
        match i {
            0 if text != first => return Ok(HashMap::new()),
            0 => {}
            1 if text != head => {
                return Err(damaged(2, format!("not the journal's header `{head}`")))
            }
            1 => {}
            _ => {
                let (k, e) = parse(text).map_err(|why| damaged(i + 1, why))?;
                known.insert(k, e);
            }
        }
    }
    Ok(known)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every field reads back to the same bits, the odd values included.
    #[test]
    fn a_line_reads_back_to_the_same_bits() {
        let e = Evaluation {
            peak_force: 4.069_912_345_678_9,
            peak_time: 1.234e-5,
            impulse: f64::NAN,
            duration: f64::INFINITY,
            target_energy: 0.0,
            rebound: -0.1,
            rebound_final: true,
            mass: 1.0 / 3.0,
            length: 5e-300,
            time: 3.0,
            steps: 9_296,
            dt: 2.5e-8,
            complete: false,
            given_up: true,
        };
        let l = line("0123456789abcdef", &e);
        let (k, back) = parse(l.trim_end()).unwrap();
        assert_eq!(k, "0123456789abcdef");
        assert!(back.impulse.is_nan());
        let same = |a: &Evaluation, b: &Evaluation| {
            let bits = |x: &Evaluation| {
                [
                    x.peak_force,
                    x.peak_time,
                    x.duration,
                    x.target_energy,
                    x.rebound,
                    x.mass,
                    x.length,
                    x.time,
                    x.dt,
                ]
                .map(f64::to_bits)
            };
            bits(a) == bits(b)
                && (a.rebound_final, a.steps, a.complete, a.given_up)
                    == (b.rebound_final, b.steps, b.complete, b.given_up)
        };
        assert!(same(&e, &back));
        // One character changed: refused by the checksum.
        let bad = l.replacen("9296", "9297", 1);
        assert!(parse(bad.trim_end()).unwrap_err().contains("checksum"));
    }

    /// A resumed journal keeps whole lines, drops a cut last line and refuses a damaged one.
    #[test]
    fn resume_keeps_what_finished() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join(MONTE_CARLO_JOURNAL);
        let e = Evaluation {
            peak_force: 2.5,
            ..Evaluation::default()
        };
        {
            let j = DrawsJournal::open(&path, false).unwrap();
            j.put("a", &e);
            j.put("b", &e);
            j.check().unwrap();
        }
        // A cut last line, as a kill mid-write leaves.
        let mut f = std::fs::OpenOptions::new()
            .append(true)
            .open(&path)
            .unwrap();
        f.write_all(b"c,2.5,0").unwrap();
        drop(f);
        let j = DrawsJournal::open(&path, true).unwrap();
        assert_eq!(j.get("a"), Some(e));
        assert_eq!(j.get("b"), Some(e));
        assert_eq!(j.get("c"), None);
        assert_eq!(j.counts(), (2, 0));
        drop(j);
        // Without --resume it starts empty.
        let j = DrawsJournal::open(&path, false).unwrap();
        assert_eq!(j.get("a"), None);
        drop(j);
        // A damaged line in the middle is refused, naming the line.
        let j = DrawsJournal::open(&path, false).unwrap();
        j.put("a", &e);
        j.put("b", &e);
        drop(j);
        let text = std::fs::read_to_string(&path).unwrap();
        std::fs::write(&path, text.replacen("2.5", "2.6", 1)).unwrap();
        let err = DrawsJournal::open(&path, true).unwrap_err().to_string();
        assert!(err.contains("line 3") && err.contains("checksum"), "{err}");
        // A file grainchain did not write is never replaced.
        std::fs::write(&path, "mine\n").unwrap();
        let err = DrawsJournal::open(&path, false).unwrap_err().to_string();
        assert!(err.contains("in the way"), "{err}");
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "mine\n");
    }
}
