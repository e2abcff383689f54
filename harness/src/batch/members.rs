//! Member files: one finished job of a batch on disk, `members/<stem>.csv` (the energy of each
//! recorded region at every snapshot) and `members/<stem>.json` (its bookkeeping: the batch's
//! digest and settings, the program that wrote it, the CSV's row count and checksum). A study
//! writes them as its jobs finish and reads them all back to merge, so a single-machine run and
//! merged shards compute from the same bytes.
//!
//! A member is read back only if it is whole and belongs to this batch: its CSV matches the
//! length and checksum recorded in its JSON (a file cut short or edited is refused), has the
//! expected header and number of rows, and holds only finite numbers; its JSON names the same
//! digest. A member that fails any of this is an error naming the file and the problem, and a
//! resumed batch runs it again.

use super::job::RunData;
use crate::error::BatchError;
use crate::error::Error;
use crate::report::atomic::AtomicFile;
use crate::report::fnv1a;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The bookkeeping of a finished member, written beside its CSV.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct MemberMeta {
    /// Digest of the batch the member belongs to (a study's run digest).
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
    /// Kinetic energy of the grains the causal horizon dropped over the run (`run.horizon`):
    /// what the unprotected outer sections of the budget miss at the end.
    #[serde(default)]
    pub dropped_energy: f64,
    /// Integration steps the run took (accepted steps).
    pub steps: u64,
    /// Wall time of the job, set-up included (not a result: merged outputs do not depend on it).
    pub wall: f64,
    /// Random containers: the design.
    #[serde(default)]
    pub design: Option<serde_json::Value>,
    /// The program that wrote the member ([`crate::program()`]; empty in files of older builds).
    #[serde(default)]
    pub program: String,
    /// Rows of the CSV after its header (snapshots 0..=N).
    #[serde(default)]
    pub rows: usize,
    /// FNV-1a 64 of the CSV's bytes, as 16 hex digits.
    #[serde(default)]
    pub csv_fnv: String,
    /// What decides the member's numbers, normalised (the batch's run settings and its parsed
    /// scene files): a member of another digest is refused with the first difference found here.
    #[serde(default)]
    pub settings: serde_json::Value,
    /// The paper's mechanism, when the batch counts it ([`super::job::Job::mechanism`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mechanism: Option<super::mechanism::MemberMechanism>,
    /// FNV-1a 64 of this file's text with this field's value empty
    /// ([`MemberMeta::to_signed_json`]): a bookkeeping edited by hand (its `initial_energy`
    /// halved changed every table of a merge, issue 38) is refused like a changed CSV. The
    /// last field, so the last of its kind in the text.
    #[serde(default)]
    pub json_fnv: String,
}

/// How `json_fnv`'s value starts in the text.
const JSON_FNV: &str = "\"json_fnv\": \"";

impl MemberMeta {
    /// The bookkeeping's text, signed: written with `json_fnv` empty, then that field set to
    /// the FNV-1a of the text so written. The checksum is of the text, not of the values read
    /// back (serde_json's float reading may differ from the written text by an ulp).
    pub fn to_signed_json(&self) -> Result<String, serde_json::Error> {
        let blank = MemberMeta {
            json_fnv: String::new(),
            ..self.clone()
        };
        let text = serde_json::to_string_pretty(&blank)?;
        let at = text.rfind(JSON_FNV).expect("the field is written") + JSON_FNV.len();
        Ok(format!(
            "{}{}{}",
            &text[..at],
            fnv1a(text.as_bytes()),
            &text[at..]
        ))
    }
}

/// Whether a bookkeeping's text matches the checksum it records (see `json_fnv`).
fn signed_as_written(text: &str) -> bool {
    let Some(at) = text.rfind(JSON_FNV).map(|i| i + JSON_FNV.len()) else {
        return false;
    };
    let Some(len) = text[at..].find('"') else {
        return false;
    };
    let blank = format!("{}{}", &text[..at], &text[at + len..]);
    len > 0 && fnv1a(blank.as_bytes()) == text[at..at + len]
}

/// What a batch is: its digest and the normalised settings it was computed from.
#[derive(Clone, Copy, Debug)]
pub struct BatchId<'a> {
    /// The digest members must carry.
    pub digest: &'a str,
    /// The normalised settings (recorded in each member, compared on a mismatch).
    pub settings: &'a serde_json::Value,
}

/// Which member: its file stem, container key and number.
#[derive(Clone, Copy, Debug)]
pub struct MemberId<'a> {
    /// File stem (`a-m3`).
    pub stem: &'a str,
    /// Container key (`a`, `r-007`).
    pub key: &'a str,
    /// Member number, from 0.
    pub member: u64,
}

/// What a member's CSV must hold: `rows` rows after its header (snapshots 0 to `rows - 1`), a
/// finite number in every cell of the columns named in `every_row`, and in every other column a
/// finite number at the rows in `sampled_at` and an empty cell at the others (`sampled_at`
/// `None`: a number in every cell of every column). A study's energy budget of the outer sections
/// is sampled ([`grainchain_engine::Recorder::region_sampled`]); its container is not.
#[derive(Clone, Debug)]
pub struct Shape {
    /// Rows after the header.
    pub rows: usize,
    /// Columns with a number in every row.
    pub every_row: Vec<String>,
    /// The rows (snapshots) of the other columns, sorted; `None`: every row.
    pub sampled_at: Option<Vec<usize>>,
}

/// A number of a member file: the shorter of `{}` and `{:e}` of the `f64`, each the shortest text
/// that parses back to the same number (a tiny energy such as 1.7e-150 was written as a
/// 170-character decimal); `read_in` parses both forms back bit for bit.
fn member_number(x: f64) -> String {
    let plain = format!("{x}");
    let exp = format!("{x:e}");
    if exp.len() < plain.len() {
        exp
    } else {
        plain
    }
}

/// Write member `id` of `batch` into `dir`: `<stem>.csv` (the energy of each region in `names`,
/// looked up by name in `data`, at every snapshot, in shortest round-trip text; an empty cell
/// where a sampled region was not recorded, NaN in `data`: [`Shape`]) and
/// `<stem>.json` (its bookkeeping, with an optional `design`), each written atomically, the CSV
/// first.
pub fn write_member(
    dir: &Path,
    id: MemberId<'_>,
    batch: BatchId<'_>,
    names: &[String],
    data: &RunData,
    design: Option<serde_json::Value>,
) -> Result<(), Error> {
    let (run, wall) = (&data.run, data.wall);
    // The member file's columns, each region looked up by its name.
    let energies = names
        .iter()
        .map(|n| data.column(n))
        .collect::<Result<Vec<&[f64]>, Error>>()?;
    let mut text = String::from("snapshot");
    for n in names {
        text.push(',');
        text.push_str(n);
    }
    text.push('\n');
    let rows = energies.iter().map(|e| e.len()).min().unwrap_or(0);
    for t in 0..rows {
        text.push_str(&t.to_string());
        for e in &energies {
            text.push(',');
            if !e[t].is_nan() {
                text.push_str(&member_number(e[t]));
            }
        }
        text.push('\n');
    }
    // Replace only a member grainchain wrote: `members/` is adopted (members gathered by hand
    // from shards carry no record in this folder), so what is in the way is checked here: a
    // member whose bookkeeping reads as one (damaged or foreign, being run again) may be
    // replaced; any other file is the user's (issue 38: a user's `a-m0.csv` was overwritten).
    let (csv, json) = (
        dir.join(format!("{}.csv", id.stem)),
        dir.join(format!("{}.json", id.stem)),
    );
    let out = dir.parent().unwrap_or(dir);
    let a_member = std::fs::read_to_string(&json)
        .ok()
        .is_some_and(|t| serde_json::from_str::<MemberMeta>(&t).is_ok())
        || crate::report::recorded(out, &format!("members/{}.csv", id.stem));
    for f in [&csv, &json] {
        if !a_member && std::fs::symlink_metadata(f).is_ok() {
            return Err(crate::error::OutDirError::NotOurs {
                dir: out.to_path_buf(),
                why: format!(
                    "members/{} is in the way: it is not a member grainchain wrote (no \
                     bookkeeping members/{}.json that reads as one), and grainchain replaces \
                     only what it wrote",
                    f.file_name()
                        .map_or_else(String::new, |n| n.to_string_lossy().into_owned()),
                    id.stem
                ),
                advice: "move or remove it, then run the command again".into(),
            }
            .into());
        }
    }
    AtomicFile::write_all(&csv, text.as_bytes())?;
    let meta = MemberMeta {
        sweep: batch.digest.to_string(),
        key: id.key.to_string(),
        member: id.member,
        initial_energy: run.initial_energy,
        max_energy_error: run.max_energy_error,
        end_margin: run.end_margin(),
        dropped_energy: run.stats.dropped_energy,
        steps: run.stats.steps,
        wall,
        design,
        program: crate::program().to_string(),
        rows,
        csv_fnv: fnv1a(text.as_bytes()),
        settings: batch.settings.clone(),
        mechanism: data.mechanism.clone(),
        json_fnv: String::new(),
    };
    AtomicFile::write_all(&json, meta.to_signed_json()?.as_bytes())
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

/// The first difference between two JSON values, as `path: there -> here` (`None`: equal).
fn first_difference(
    path: &str,
    there: &serde_json::Value,
    here: &serde_json::Value,
) -> Option<String> {
    use serde_json::Value;
    match (there, here) {
        (Value::Object(a), Value::Object(b)) => {
            let keys: std::collections::BTreeSet<&String> = a.keys().chain(b.keys()).collect();
            keys.into_iter().find_map(|k| {
                let p = if path.is_empty() {
                    k.clone()
                } else {
                    format!("{path}.{k}")
                };
                first_difference(
                    &p,
                    a.get(k).unwrap_or(&Value::Null),
                    b.get(k).unwrap_or(&Value::Null),
                )
            })
        }
        (Value::Array(a), Value::Array(b)) if a.len() == b.len() => a
            .iter()
            .zip(b)
            .enumerate()
            .find_map(|(i, (x, y))| first_difference(&format!("{path}[{i}]"), x, y)),
        _ if there == here => None,
        _ => Some(format!("`{path}` is {there} there, {here} here")),
    }
}

/// Why member `meta` does not belong to `batch` (`None`: it does).
fn foreign(meta: &MemberMeta, batch: BatchId<'_>) -> Option<String> {
    if meta.sweep == batch.digest {
        return None;
    }
    if meta.program != crate::program() {
        let there = if meta.program.is_empty() {
            "an older build that recorded no version"
        } else {
            &meta.program
        };
        return Some(format!("written by {there}, this is {}", crate::program()));
    }
    Some(match first_difference("", &meta.settings, batch.settings) {
        Some(d) => format!("written for other settings: {d}"),
        None => format!(
            "written for another digest ({} there, {} here)",
            meta.sweep, batch.digest
        ),
    })
}

/// Read and check member `id`'s files in `dir` (`Ok(None)`: they are not there). A member that
/// is damaged or belongs to another batch is an error naming the file and the problem.
fn read_in(
    dir: &Path,
    id: MemberId<'_>,
    batch: BatchId<'_>,
    shape: &Shape,
) -> Result<Option<Member>, BatchError> {
    let expected_rows = shape.rows;
    let csv_path = dir.join(format!("{}.csv", id.stem));
    let meta_path = dir.join(format!("{}.json", id.stem));
    let (csv_there, meta_there) = (csv_path.is_file(), meta_path.is_file());
    if !csv_there && !meta_there {
        return Ok(None);
    }
    let damaged = |file: &Path, problem: String| BatchError::DamagedMember {
        file: file.to_path_buf(),
        problem,
    };
    if !meta_there {
        return Err(damaged(
            &csv_path,
            format!("its bookkeeping {} is missing", meta_path.display()),
        ));
    }
    if !csv_there {
        return Err(damaged(
            &meta_path,
            format!("its data {} is missing", csv_path.display()),
        ));
    }
    let text =
        std::fs::read_to_string(&meta_path).map_err(|e| damaged(&meta_path, e.to_string()))?;
    let meta: MemberMeta = serde_json::from_str(&text).map_err(|e| BatchError::MemberMeta {
        file: meta_path.clone(),
        message: e.to_string(),
    })?;
    if let Some(why) = foreign(&meta, batch) {
        return Err(BatchError::ForeignMember {
            file: meta_path,
            why,
        });
    }
    if !signed_as_written(&text) {
        return Err(damaged(
            &meta_path,
            "its bytes do not match the checksum it records (`json_fnv`: changed after it was \
             written)"
                .into(),
        ));
    }
    let bytes = std::fs::read(&csv_path).map_err(|e| damaged(&csv_path, e.to_string()))?;
    if meta.csv_fnv != fnv1a(&bytes) {
        return Err(damaged(
            &csv_path,
            format!(
                "its bytes do not match the checksum recorded in {} (cut short or changed after it was written)",
                meta_path.display()
            ),
        ));
    }
    let text = String::from_utf8(bytes).map_err(|_| damaged(&csv_path, "not UTF-8 text".into()))?;
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap_or("").split(',').collect();
    if header.first() != Some(&"snapshot") || header.len() < 2 {
        return Err(damaged(
            &csv_path,
            "the header must be `snapshot` followed by the regions".into(),
        ));
    }
    let regions: Vec<String> = header[1..].iter().map(|s| s.to_string()).collect();
    // Per column: whether it is sampled (numbers only at `shape.sampled_at`).
    let sampled: Vec<bool> = regions
        .iter()
        .map(|r| shape.sampled_at.is_some() && !shape.every_row.contains(r))
        .collect();
    let at = shape.sampled_at.as_deref().unwrap_or(&[]);
    let mut energy = vec![Vec::with_capacity(expected_rows); regions.len()];
    let mut rows = 0usize;
    for (t, line) in lines.enumerate() {
        let row = t + 2;
        let cells: Vec<&str> = line.split(',').collect();
        if cells.len() != header.len() {
            return Err(damaged(
                &csv_path,
                format!(
                    "row {row}: {} values, the header has {}",
                    cells.len(),
                    header.len()
                ),
            ));
        }
        if cells[0] != t.to_string() {
            return Err(damaged(
                &csv_path,
                format!("row {row}: snapshot `{}`, expected {t}", cells[0]),
            ));
        }
        let on_schedule = at.binary_search(&t).is_ok();
        for (r, e) in energy.iter_mut().enumerate() {
            let cell = cells[r + 1];
            if sampled[r] && !on_schedule {
                if !cell.is_empty() {
                    return Err(damaged(
                        &csv_path,
                        format!(
                            "row {row}: column `{}` is sampled and holds no value at snapshot {t}, found `{cell}`",
                            regions[r]
                        ),
                    ));
                }
                e.push(f64::NAN);
                continue;
            }
            if cell.is_empty() {
                return Err(damaged(
                    &csv_path,
                    format!(
                        "row {row}: column `{}` is empty at snapshot {t}, where it must hold a number",
                        regions[r]
                    ),
                ));
            }
            let x: f64 = cell.parse().map_err(|_| BatchError::MemberValue {
                file: csv_path.clone(),
                row,
                column: regions[r].clone(),
            })?;
            if !x.is_finite() {
                return Err(damaged(
                    &csv_path,
                    format!(
                        "row {row}: column `{}` is {x}, not a finite number",
                        regions[r]
                    ),
                ));
            }
            e.push(x);
        }
        rows += 1;
    }
    if rows != meta.rows || rows != expected_rows {
        return Err(damaged(
            &csv_path,
            format!(
                "{rows} rows; its bookkeeping says {} and the batch expects {expected_rows}",
                meta.rows
            ),
        ));
    }
    Ok(Some(Member {
        key: id.key.to_string(),
        member: id.member,
        regions,
        energy,
        meta,
    }))
}

/// Read member `id` back from the first of `dirs` whose `members/` holds its files (`None`: no
/// directory has it), checked: its `shape` (rows, and where numbers must be), the length and
/// checksum its JSON records, finite numbers, this `batch`'s digest. Cells a sampled column
/// leaves empty are NaN in [`Member::energy`].
pub fn read_member(
    dirs: &[PathBuf],
    id: MemberId<'_>,
    batch: BatchId<'_>,
    shape: &Shape,
) -> Result<Option<Member>, Error> {
    for d in dirs {
        if let Some(m) = read_in(&d.join("members"), id, batch, shape)? {
            return Ok(Some(m));
        }
    }
    Ok(None)
}

/// What a resumed batch finds of member `id` in `dir`.
#[derive(Debug)]
pub enum MemberStatus {
    /// Not there: run it.
    Missing,
    /// Whole and of this batch: keep it.
    Complete,
    /// There but damaged or of another batch: run it again (the error says why).
    Unusable(BatchError),
}

/// Check member `id` in `dir` (a resumed batch keeps it only when [`MemberStatus::Complete`]).
pub fn member_status(
    dir: &Path,
    id: MemberId<'_>,
    batch: BatchId<'_>,
    shape: &Shape,
) -> MemberStatus {
    match read_in(dir, id, batch, shape) {
        Ok(None) => MemberStatus::Missing,
        Ok(Some(_)) => MemberStatus::Complete,
        Err(e) => MemberStatus::Unusable(e),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Tiny and huge energies are written short, and every number reads back (the `parse` of
    /// `read_in`) bit for bit.
    #[test]
    fn member_numbers_are_short_and_exact() {
        assert_eq!(member_number(1.7e-150), "1.7e-150");
        assert_eq!(member_number(0.25), "0.25");
        assert_eq!(member_number(0.0), "0");
        assert_eq!(member_number(1e300), "1e300");
        let mut x = 0.123_456_789_012_345_67_f64;
        let mut worst = 0;
        for k in 0..4000 {
            // Values spread over every exponent, subnormals included.
            let v = if k % 2 == 0 { x } else { -x };
            let text = member_number(v);
            assert_eq!(
                text.parse::<f64>().unwrap().to_bits(),
                v.to_bits(),
                "{text}"
            );
            worst = worst.max(text.len());
            x *= 0.83;
        }
        // The longest is the shortest round trip (17 significant digits), a sign, a point and a
        // three-digit exponent: 25 characters.
        assert!(worst <= 25, "{worst}");
        let sub = f64::from_bits(1);
        assert_eq!(member_number(sub).parse::<f64>().unwrap().to_bits(), 1);
    }
}
