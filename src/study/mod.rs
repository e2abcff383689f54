//! Ensemble studies: `E_R(t)` of containers as a converged statistic (`grainchain study`).
//!
//! A study is one sweep file ([`sweep`]): containers given by scene files, each run as an
//! ensemble of members that differ by a tiny stated perturbation, and optionally random
//! containers drawn from a seeded distribution ([`random`]). The work is a list of **jobs**, one
//! per (container, member), in a fixed order: the sweep's containers in file order, members
//! 0..n, then random containers 1..count with their members.
//!
//! **Stages.**
//! 1. *Run* ([`run_jobs`]): the jobs of one shard (`--shard K/N` takes every job `j` with
//!    `j mod N = K - 1`; default all) run on all threads; each finished job writes
//!    `members/<key>-m<k>.csv` (energy of the container and of every section outside it, at every
//!    snapshot) and `members/<key>-m<k>.json` (the run's bookkeeping), atomically. A job's numbers
//!    depend only on its scene, never on the thread or shard that ran it.
//! 2. *Merge* ([`merge`]): read the member files of every job (from the output directory and any
//!    `--from` directories), check that they belong to this sweep file (its digest) and that none
//!    is missing, and compute the statistics ([`outputs`]). A single-machine run does stage 1 for
//!    all jobs and then this same stage, so its outputs equal those of merged shards bit for bit
//!    (the CSV numbers are written in shortest round-trip form and read back exactly).

pub mod outputs;
pub mod random;
pub mod sweep;

use crate::error::Error;
use crate::report::atomic::AtomicFile;
use crate::reproduce::jobs::{run_job, Job, RunData};
use crate::reproduce::scenes::{self, SceneSource};
use crate::scene::file::{RegionFile, SceneFile};
use crate::scene::Scene;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde::{Deserialize, Serialize};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
pub use sweep::{Shard, SweepFile};

/// What a job is.
#[derive(Clone, Debug, PartialEq)]
pub enum JobKind {
    /// Container `index` of the sweep's `[[containers]]`.
    Container(usize),
    /// Random container `i` (1-based).
    Random(u64),
}

/// One (container, member) run of a study.
#[derive(Clone, Debug)]
pub struct StudyJob {
    /// Position in the study's job list.
    pub index: usize,
    /// Container key (`a`, `r-007`).
    pub key: String,
    /// Member number, from 0 (member 0 of a striker-speed perturbation is the scene itself).
    pub member: u64,
    /// Which container the job runs.
    pub kind: JobKind,
}

impl StudyJob {
    /// File stem of the job's member files.
    pub fn stem(&self) -> String {
        format!("{}-m{}", self.key, self.member)
    }
}

/// Every job of the study, in study order.
pub fn plan(sweep: &SweepFile) -> Vec<StudyJob> {
    let s = &sweep.sweep;
    let mut jobs = Vec::new();
    for (c, entry) in s.containers.iter().enumerate() {
        for m in 0..s.members {
            jobs.push(StudyJob {
                index: jobs.len(),
                key: entry.key.clone(),
                member: m,
                kind: JobKind::Container(c),
            });
        }
    }
    if let Some(r) = &s.random {
        for i in 1..=r.count {
            for m in 0..r.members {
                jobs.push(StudyJob {
                    index: jobs.len(),
                    key: format!("r-{i:03}"),
                    member: m,
                    kind: JobKind::Random(i),
                });
            }
        }
    }
    jobs
}

/// The scene of a job: the container file (or the template with random container `i`), the run
/// length and outer chains of the sweep, the member's perturbation, and one energy region per
/// section outside the container (the energy budget). Also the random design, if any.
pub fn job_scene(
    sweep: &SweepFile,
    job: &StudyJob,
) -> Result<(Scene, Vec<String>, Option<random::Design>), Error> {
    let s = &sweep.sweep;
    let path = match job.kind {
        JobKind::Container(c) => sweep.resolve(&s.containers[c].scene),
        JobKind::Random(_) => sweep.resolve(&s.random.as_ref().expect("planned").template),
    };
    let src = SceneSource::load(&path)?;
    let mut design = None;
    let mut regions = vec!["container".to_string()];
    let scene = src.scene(|f| {
        if let JobKind::Random(i) = job.kind {
            design = Some(random::random_container(
                &src,
                f,
                s.random.as_ref().expect("planned"),
                i,
            )?);
        }
        scenes::set_snapshots(f, s.snapshots);
        if free_ends(s, job) {
            scenes::set_outer_left(&src, f, FREE_END_OUTER)?;
            scenes::set_beyond_striker(&src, f, 0)?;
        } else if let Some(n) = s.outer_chains {
            scenes::set_outer_left(&src, f, n)?;
            scenes::set_beyond_striker(&src, f, n)?;
        }
        random::perturb(&src, f, s.perturbation, job.member)?;
        let multirate = match job.kind {
            JobKind::Container(c) => s.containers[c].multirate.or(s.multirate),
            JobKind::Random(_) => s.multirate,
        };
        if let Some(m) = multirate {
            use_multirate(&src, f, m.ratio, m.margin)?;
        }
        regions.extend(budget_regions(&src, f)?);
        Ok(())
    })?;
    Ok((scene, regions, design))
}

/// Grains of `outer-left` in the free-end geometry (the paper's Fig. 3: container at grains
/// 121-300 of 420).
pub const FREE_END_OUTER: u64 = 120;

fn free_ends(s: &sweep::Sweep, job: &StudyJob) -> bool {
    matches!(job.kind, JobKind::Container(c) if s.containers[c].free_ends)
}

/// Integrate a container scene with multiple time stepping: the fast region runs from the
/// container's first grain to the striker (the path of the strong incident wave, and the
/// container), widened by `margin` grains on each side (region `fast`, added to the scene); the
/// outer chains beyond it step at `ratio` times the scene's dt.
pub fn use_multirate(
    src: &SceneSource,
    f: &mut SceneFile,
    ratio: u64,
    margin: u64,
) -> Result<(), Error> {
    let (c_first, c_last) = random::container_region(src, f)?;
    let mut first = 1i64;
    let mut striker = None;
    for s in &f.chain.sections {
        if s.name.as_deref() == Some("striker") {
            striker = Some(first + s.count as i64 - 1);
        }
        first += s.count as i64;
    }
    let striker = striker.ok_or_else(|| src.missing("a section named `striker`"))?;
    let region = RegionFile {
        name: "fast".into(),
        first: c_first.min(striker),
        last: c_last.max(striker),
    };
    f.regions.push(region);
    let i = f.integrator.get_or_insert_with(Default::default);
    i.method = Some(crate::Method::Multirate);
    i.multirate = Some(crate::scene::file::MultirateFile {
        ratio,
        fast: "fast".into(),
        margin: Some(margin),
    });
    Ok(())
}

/// Add a region per section lying wholly outside the `container` region (named after the
/// section) and return their names.
fn budget_regions(src: &SceneSource, f: &mut SceneFile) -> Result<Vec<String>, Error> {
    if f.striker.is_some() {
        return Err(src.missing("the striker as an `[[initial]]` velocity (not `[striker]`)"));
    }
    let (cf, cl) = random::container_region(src, f)?;
    let mut first = 1i64;
    let mut names = Vec::new();
    let mut add = Vec::new();
    for s in &f.chain.sections {
        let last = first + s.count as i64 - 1;
        if let Some(name) = &s.name {
            if (last < cf || first > cl) && !f.regions.iter().any(|r| &r.name == name) {
                names.push(name.clone());
                add.push(RegionFile {
                    name: name.clone(),
                    first,
                    last,
                });
            }
        }
        first = last + 1;
    }
    f.regions.extend(add);
    Ok(names)
}

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

fn write_member(
    dir: &Path,
    job: &StudyJob,
    sweep: &SweepFile,
    names: &[String],
    data: &RunData,
    design: Option<&random::Design>,
) -> Result<(), Error> {
    let (run, wall) = (&data.run, data.wall);
    // The member file's columns, each region looked up by its name.
    let energies = names
        .iter()
        .map(|n| data.region(n).map(|r| r.energy))
        .collect::<Result<Vec<&[f64]>, Error>>()?;
    let csv_path = dir.join(format!("{}.csv", job.stem()));
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
        sweep: sweep.digest.clone(),
        key: job.key.clone(),
        member: job.member,
        initial_energy: run.initial_energy,
        max_energy_error: run.max_energy_error,
        end_margin: run.end_margin(),
        steps: run.stats.steps,
        wall,
        design: design.map(serde_json::to_value).transpose()?,
    };
    AtomicFile::write_all(
        dir.join(format!("{}.json", job.stem())),
        serde_json::to_string_pretty(&meta)?.as_bytes(),
    )
}

/// Options of `grainchain study`.
#[derive(Clone, Debug)]
pub struct Options {
    /// Output directory; member files go to `<out>/members/`.
    pub out: PathBuf,
    /// Which part of the jobs to run (`--shard K/N`; [`Shard::ALL`] for all).
    pub shard: Shard,
    /// Worker threads (at least 1, at most one per job).
    pub threads: usize,
    /// Keep member files already written for this sweep file (same digest) instead of running
    /// their jobs again: a study that was stopped goes on where it stopped.
    pub resume: bool,
    /// Draw a progress bar on stderr.
    pub progress: bool,
}

/// What [`run_jobs`] did.
#[derive(Clone, Debug, Default)]
pub struct RunReport {
    /// Jobs run.
    pub ran: usize,
    /// Jobs skipped because their member files were already there (`resume`).
    pub kept: usize,
    /// Wall time of the jobs run, summed over threads.
    pub job_seconds: f64,
    /// Wall time of the whole stage, in seconds.
    pub wall: f64,
}

fn existing(dir: &Path, job: &StudyJob, digest: &str) -> bool {
    let meta = dir.join(format!("{}.json", job.stem()));
    let csv = dir.join(format!("{}.csv", job.stem()));
    csv.is_file()
        && std::fs::read_to_string(&meta)
            .ok()
            .and_then(|t| serde_json::from_str::<MemberMeta>(&t).ok())
            .is_some_and(|m| m.sweep == digest)
}

/// Stage 1: run this shard's jobs and write their member files into `out/members/`.
pub fn run_jobs(sweep: &SweepFile, opts: &Options) -> Result<RunReport, Error> {
    let t0 = std::time::Instant::now();
    let dir = opts.out.join("members");
    let all = plan(sweep);
    let mine: Vec<&StudyJob> = all.iter().filter(|j| opts.shard.owns(j.index)).collect();
    let mut kept = 0;
    let todo: Vec<&StudyJob> = mine
        .into_iter()
        .filter(|j| {
            let keep = opts.resume && existing(&dir, j, &sweep.digest);
            kept += keep as usize;
            !keep
        })
        .collect();
    // Build every scene first, so a bad scene fails before anything runs.
    let mut built = Vec::with_capacity(todo.len());
    for j in &todo {
        let (scene, regions, design) = job_scene(sweep, j)?;
        let job = Job {
            label: format!("{} member {}", j.key, j.member),
            scene,
            regions,
            snapshots: Vec::new(),
            require_untouched_ends: if free_ends(&sweep.sweep, j) {
                (false, false)
            } else {
                (true, true)
            },
        };
        built.push((job, design));
    }
    let total: u64 = built.iter().map(|b| b.0.scene.outputs() + 1).sum();
    let target = if opts.progress {
        ProgressDrawTarget::stderr()
    } else {
        ProgressDrawTarget::hidden()
    };
    let pb = ProgressBar::with_draw_target(Some(total), target);
    pb.set_style(
        ProgressStyle::with_template(&format!(
            "study {} [{{bar:30}}] {{percent:>3}}% {{elapsed}}/{{duration}} | {{msg}}",
            opts.shard
        ))
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> "),
    );
    let next = AtomicUsize::new(0);
    let done = AtomicUsize::new(0);
    let first_error: Mutex<Option<(usize, Error)>> = Mutex::new(None);
    let seconds = Mutex::new(0.0f64);
    let threads = opts.threads.clamp(1, todo.len().max(1));
    std::thread::scope(|s| {
        for _ in 0..threads {
            s.spawn(|| loop {
                let k = next.fetch_add(1, Ordering::SeqCst);
                if k >= todo.len() {
                    break;
                }
                let job = todo[k];
                let (rj, design) = &built[k];
                let res = run_job(rj, &|| pb.inc(1)).and_then(|d| {
                    write_member(&dir, job, sweep, &rj.regions, &d, design.as_ref())?;
                    Ok(d.wall)
                });
                match res {
                    Ok(w) => {
                        *seconds.lock().unwrap_or_else(|e| e.into_inner()) += w;
                        let n = done.fetch_add(1, Ordering::SeqCst) + 1;
                        pb.set_message(format!("{n}/{} members", todo.len()));
                    }
                    Err(e) => {
                        let mut fe = first_error.lock().unwrap_or_else(|e| e.into_inner());
                        if fe.as_ref().is_none_or(|(i, _)| k < *i) {
                            *fe = Some((k, e));
                        }
                        // Stop handing out jobs; the finished ones are kept on disk (--resume).
                        next.store(todo.len(), Ordering::SeqCst);
                    }
                }
            });
        }
    });
    pb.finish_and_clear();
    if let Some((_, e)) = first_error.into_inner().unwrap_or_else(|e| e.into_inner()) {
        return Err(e);
    }
    Ok(RunReport {
        ran: todo.len(),
        kept,
        job_seconds: seconds.into_inner().unwrap_or_else(|e| e.into_inner()),
        wall: t0.elapsed().as_secs_f64(),
    })
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

fn read_member(dirs: &[PathBuf], job: &StudyJob, digest: &str) -> Result<Option<Member>, Error> {
    for d in dirs {
        let dir = d.join("members");
        let csv_path = dir.join(format!("{}.csv", job.stem()));
        let meta_path = dir.join(format!("{}.json", job.stem()));
        if !csv_path.is_file() || !meta_path.is_file() {
            continue;
        }
        let text = std::fs::read_to_string(&meta_path).map_err(|source| Error::Io {
            path: meta_path.clone(),
            source,
        })?;
        let meta: MemberMeta = serde_json::from_str(&text)
            .map_err(|e| Error::Other(format!("{}: {e}", meta_path.display())))?;
        if meta.sweep != digest {
            return Err(Error::Other(format!(
                "{}: written for another version of the sweep file (digest {} here, {} there); \
                 run that job again or remove the file",
                meta_path.display(),
                digest,
                meta.sweep
            )));
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
                    Error::Other(format!(
                        "{what}: row {}: column `{}` is not a number",
                        row + 2,
                        regions[r]
                    ))
                })?;
                e.push(x);
            }
        }
        return Ok(Some(Member {
            key: job.key.clone(),
            member: job.member,
            regions,
            energy,
            meta,
        }));
    }
    Ok(None)
}

/// Stage 2: read every member of the study from `dirs` (the first holding a job's files wins)
/// and write the study's outputs into `out`.
pub fn merge(sweep: &SweepFile, dirs: &[PathBuf], out: &Path) -> Result<outputs::Study, Error> {
    merge_with(sweep, dirs, out, false)
}

/// [`merge`], or with `partial` a look at a study whose shards are still running: the members
/// present are used (each container with the members it has; containers without any are left
/// out) and STUDY.md lists the missing ones at the top.
pub fn merge_with(
    sweep: &SweepFile,
    dirs: &[PathBuf],
    out: &Path,
    partial: bool,
) -> Result<outputs::Study, Error> {
    let jobs = plan(sweep);
    let mut members = Vec::with_capacity(jobs.len());
    let mut missing = Vec::new();
    for j in &jobs {
        match read_member(dirs, j, &sweep.digest)? {
            Some(m) => members.push(m),
            None => missing.push(j),
        }
    }
    if !missing.is_empty() && partial && !members.is_empty() {
        let mut study = outputs::analyse(sweep, members)?;
        study.missing = missing.iter().map(|j| j.stem()).collect();
        outputs::write(&study, out)?;
        return Ok(study);
    }
    if !missing.is_empty() {
        let list: Vec<String> = missing
            .iter()
            .take(6)
            .map(|j| format!("{} (job {})", j.stem(), j.index))
            .collect();
        return Err(Error::Other(format!(
            "cannot merge: {} of {} members are missing, e.g. {}; run their shards first \
             (job j belongs to shard K/N when j mod N = K - 1)",
            missing.len(),
            jobs.len(),
            list.join(", ")
        )));
    }
    let study = outputs::analyse(sweep, members)?;
    outputs::write(&study, out)?;
    Ok(study)
}
