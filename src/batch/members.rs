//! Member files: one finished job of a batch on disk, `members/<stem>.csv` (the energy of each
//! recorded region at every snapshot) and `members/<stem>.json` (its bookkeeping and the digest
//! of the batch it belongs to). A study writes them as its jobs finish and reads them all back
//! to merge, so a single-machine run and merged shards compute from the same bytes.

use super::job::RunData;
use super::BatchError;
use crate::error::Error;
use crate::report::atomic::AtomicFile;
use serde::{Deserialize, Serialize};
use std::io::Write;
use std::path::{Path, PathBuf};

/// The bookkeeping of a finished member, written beside its CSV.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct MemberMeta {
    /// Digest of the sweep file the member belongs to.
    pub sweep: String,
    /// Container key (`a`, `r-007`).
    pub key: String,
    /// Member number, from 0.
    pub member: u64,
    /// Energy at t = 0 (the striker's, plus the perturbation's).
    pub initial_energy: f64,
    /// Largest relative energy error at output times.
    pub max_energy_error: f64,
    /// Grains between the furthest disturbance and the nearer chain end at the end of the run.
    pub end_margin: usize,
    /// Integration steps the run took (accepted steps).
    pub steps: u64,
    /// Wall time of the job, set-up included (not a result: merged outputs do not depend on it).
    pub wall: f64,
    /// Random containers: the design.
    #[serde(default)]
    pub design: Option<serde_json::Value>,
}

/// Write member `stem` of a batch into `dir`: `<stem>.csv` (the energy of each region in `names`,
/// looked up by name in `data`, at every snapshot, in shortest round-trip text) and
/// `<stem>.json` (its bookkeeping, with the batch's `digest`, `key`, `member` and an optional
/// `design`), each written atomically.
#[allow(clippy::too_many_arguments)]
pub fn write_member(
    dir: &Path,
    stem: &str,
    digest: &str,
    (key, member): (&str, u64),
    names: &[String],
    data: &RunData,
    design: Option<serde_json::Value>,
) -> Result<(), Error> {
    let (run, wall) = (&data.run, data.wall);
    // The member file's columns, each region looked up by its name.
    let energies = names
        .iter()
        .map(|n| data.region(n).map(|r| r.energy))
        .collect::<Result<Vec<&[f64]>, Error>>()?;
    let csv_path = dir.join(format!("{stem}.csv"));
    let mut f = AtomicFile::create(&csv_path)?;
    let io = |source| Error::Io {
        path: csv_path.clone(),
        source,
    };
    let mut line = String::from("snapshot");
    for n in names {
        line.push(',');
        line.push_str(n);
    }
    writeln!(f, "{line}").map_err(io)?;
    let len = energies.iter().map(|e| e.len()).min().unwrap_or(0);
    for t in 0..len {
        line.clear();
        line.push_str(&t.to_string());
        for e in &energies {
            // `{}` of f64 is the shortest text that parses back to the same number.
            line.push(',');
            line.push_str(&format!("{}", e[t]));
        }
        writeln!(f, "{line}").map_err(io)?;
    }
    f.commit()?;
    let meta = MemberMeta {
        sweep: digest.to_string(),
        key: key.to_string(),
        member,
        initial_energy: run.initial_energy,
        max_energy_error: run.max_energy_error,
        end_margin: run.end_margin(),
        steps: run.stats.steps,
        wall,
        design,
    };
    AtomicFile::write_all(
        dir.join(format!("{stem}.json")),
        serde_json::to_string_pretty(&meta)?.as_bytes(),
    )
}

/// A member read back from disk.
#[derive(Clone, Debug)]
pub struct Member {
    /// Container key (`a`, `r-007`).
    pub key: String,
    /// Member number, from 0.
    pub member: u64,
    /// Region names: `container` first, then the sections outside it.
    pub regions: Vec<String>,
    /// `energy[r][t]`.
    pub energy: Vec<Vec<f64>>,
    /// The member's bookkeeping (its `.json` file).
    pub meta: MemberMeta,
}

/// Read member `stem` back from the first of `dirs` whose `members/` holds both its files
/// (`None`: no directory has it). A member written for another `digest` is an error.
pub fn read_member(
    dirs: &[PathBuf],
    stem: &str,
    (key, member): (&str, u64),
    digest: &str,
) -> Result<Option<Member>, Error> {
    for d in dirs {
        let dir = d.join("members");
        let csv_path = dir.join(format!("{stem}.csv"));
        let meta_path = dir.join(format!("{stem}.json"));
        if !csv_path.is_file() || !meta_path.is_file() {
            continue;
        }
        let text = std::fs::read_to_string(&meta_path).map_err(|source| Error::Io {
            path: meta_path.clone(),
            source,
        })?;
        let meta: MemberMeta = serde_json::from_str(&text).map_err(|e| BatchError::MemberMeta {
            file: meta_path.clone(),
            message: e.to_string(),
        })?;
        if meta.sweep != digest {
            return Err(BatchError::ForeignMember {
                file: meta_path,
                here: digest.to_string(),
                there: meta.sweep,
            }
            .into());
        }
        let what = csv_path.display().to_string();
        let cerr = |source| Error::Csv {
            what: what.clone(),
            source,
        };
        let mut rd = csv::Reader::from_path(&csv_path).map_err(cerr)?;
        let header = rd.headers().map_err(cerr)?.clone();
        let regions: Vec<String> = header.iter().skip(1).map(String::from).collect();
        let mut energy = vec![Vec::new(); regions.len()];
        for (row, rec) in rd.records().enumerate() {
            let rec = rec.map_err(cerr)?;
            for (r, e) in energy.iter_mut().enumerate() {
                let x: f64 = rec.get(r + 1).and_then(|s| s.parse().ok()).ok_or_else(|| {
                    BatchError::MemberValue {
                        file: csv_path.clone(),
                        row: row + 2,
                        column: regions[r].clone(),
                    }
                })?;
                e.push(x);
            }
        }
        return Ok(Some(Member {
            key: key.to_string(),
            member,
            regions,
            energy,
            meta,
        }));
    }
    Ok(None)
}

/// Whether member `stem` is already in `dir` for this `digest` (a resumed batch keeps it).
pub fn member_exists(dir: &Path, stem: &str, digest: &str) -> bool {
    let meta = dir.join(format!("{stem}.json"));
    let csv = dir.join(format!("{stem}.csv"));
    csv.is_file()
        && std::fs::read_to_string(&meta)
            .ok()
            .and_then(|t| serde_json::from_str::<MemberMeta>(&t).ok())
            .is_some_and(|m| m.sweep == digest)
}
