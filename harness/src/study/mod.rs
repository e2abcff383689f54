//! Ensemble studies: `E_R(t)` of containers as a converged statistic (`grainchain study`).
//!
//! A study is one sweep file ([`SweepFile`]): containers given by scene files, each run as an
//! ensemble of members that differ by a tiny stated perturbation, and optionally random
//! containers drawn from a seeded distribution ([`ContainerScene::random_container`]). The work is a list of **jobs**, one
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
//!    is missing, and compute the statistics ([`Study`]). A single-machine run does stage 1 for
//!    all jobs and then this same stage, so its outputs equal those of merged shards bit for bit
//!    (the CSV numbers are written in shortest round-trip form and read back exactly).

mod ensemble;
mod outputs;
mod random;
pub mod search;
mod sweep;

use crate::batch::scenes::{self, SceneSource};
use crate::batch::{
    member_status, read_member, run_job, write_member, Job, MemberId, MemberStatus, Pool,
};
use crate::batch::{ContainerScene, Stepping};
use crate::error::{Error, StudyError};
use crate::report::outdir::{Claim, OutDir};
pub use ensemble::reproduce_ensemble;
use grainchain_engine::Scene;
pub use outputs::{reproduce_section, AlphaRow, KeyResult, SlopeRow, Study, WindowFit};
pub use random::Design;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
pub use sweep::{
    budget_outputs, ContainerEntry, KeyKind, MultirateSpec, Perturbation, RandomSpec, Shard, Sweep,
    SweepFile, Walls,
};

/// What a job is.
#[derive(Clone, Debug, PartialEq)]
pub enum JobKind {
    /// Container `index` of the sweep's `[[containers]]`.
    Container(usize),
    /// Random container `i` (1-based).
    Random(u64),
    /// Reading `i` (1-based) of `[search]`, on its scene `j`.
    Search(u64, usize),
}

impl JobKind {
    /// The kind of key the job's container has.
    pub fn key_kind(&self) -> KeyKind {
        match self {
            JobKind::Container(_) => KeyKind::Container,
            JobKind::Random(_) => KeyKind::Random,
            JobKind::Search(..) => KeyKind::Search,
        }
    }
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
    /// `<key>-m<member>`.
    stem: String,
}

impl StudyJob {
    /// File stem of the job's member files.
    pub fn stem(&self) -> &str {
        &self.stem
    }

    /// The member this job writes.
    fn id(&self) -> MemberId<'_> {
        MemberId {
            stem: &self.stem,
            key: &self.key,
            member: self.member,
        }
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
                stem: format!("{}-m{m}", entry.key),
            });
        }
    }
    if let Some(r) = &s.random {
        for i in 1..=r.count {
            for m in 0..r.members {
                let key = KeyKind::random(i);
                jobs.push(StudyJob {
                    index: jobs.len(),
                    stem: format!("{key}-m{m}"),
                    key,
                    member: m,
                    kind: JobKind::Random(i),
                });
            }
        }
    }
    if let Some(x) = &s.search {
        for i in 1..=x.count {
            for (j, scene) in x.scenes.iter().enumerate() {
                let key = KeyKind::search(i, &search::scene_key(scene));
                for m in 0..x.members {
                    jobs.push(StudyJob {
                        index: jobs.len(),
                        stem: format!("{key}-m{m}"),
                        key: key.clone(),
                        member: m,
                        kind: JobKind::Search(i, j),
                    });
                }
            }
        }
    }
    jobs
}

/// The scene of a job: the container file (or the template with random container `i`), the run
/// length and outer chains of the sweep, the member's perturbation, and one energy region per
/// section outside the container (the energy budget). Also the random design, if any.
///
/// Everything here is known before anything runs, so `study --check` and `study` (before it
/// claims its folder, [`check_scenes`]) call it and give the same verdict. A setting the sweep
/// imposes is blamed on the sweep's key (`sweep_key_error`), naming the scene it does not fit.
pub fn job_scene(
    sweep: &SweepFile,
    job: &StudyJob,
) -> Result<(Scene, Vec<String>, Option<random::Design>), Error> {
    let s = &sweep.sweep;
    let path = match job.kind {
        JobKind::Container(c) => sweep.resolve(&s.containers[c].scene),
        JobKind::Random(_) => sweep.resolve(&s.random.as_ref().expect("planned").template),
        JobKind::Search(_, j) => sweep.resolve(&s.search.as_ref().expect("planned").scenes[j]),
    };
    // Read and parsed once, with the sweep file (its digest is taken from the same parse).
    let loaded;
    let src = match sweep.source(&path) {
        Some(src) => src,
        None => {
            loaded = SceneSource::read(&path)?;
            &loaded
        }
    };
    let entry = match job.kind {
        JobKind::Container(c) => Some((c, &s.containers[c])),
        _ => None,
    };
    let reading = match job.kind {
        JobKind::Search(i, _) => Some(search::reading(s.search.as_ref().expect("planned"), i)),
        _ => None,
    };
    // Which sweep key sets the outer chains (a search reading's medium other than `long`
    // replaces them as a container's `outer` does), and which the multirate settings.
    let outer_key = match (&reading, entry) {
        (Some(r), _) if r.medium.has_ends() => Some("search.media".to_string()),
        (_, Some((c, e))) if e.free_ends => Some(format!("containers[{c}].free_ends")),
        (_, Some((c, e))) if e.outer.is_some_and(|o| o.has_ends()) => {
            Some(format!("containers[{c}].outer"))
        }
        _ => s.outer_chains.map(|_| "outer_chains".to_string()),
    };
    let (multirate, multirate_key) = match entry {
        Some((c, e)) if e.multirate.is_some() => {
            (e.multirate, format!("containers[{c}].multirate"))
        }
        _ => (s.multirate, "multirate".to_string()),
    };
    // A scene with its own outer medium has chosen its outer chains and what lies beyond them:
    // a sweep setting that would resize or replace them is refused naming both keys (neither
    // silently winning is what the user asked for).
    if let Some(own) = src.own_outer() {
        if let Some(key) = &outer_key {
            return Err(invalid_sweep(
                sweep,
                key,
                format!(
                    "scene {} gives its own outer medium (`chain.outer`: {}), which sets its outer \
                     chains; `{key}` cannot change them too: remove one of the two",
                    path.display(),
                    own.label()
                ),
            ));
        }
        if own.damps() && multirate.is_some() {
            return Err(invalid_sweep(
                sweep,
                &multirate_key,
                format!(
                    "scene {} has a damped outer medium (`chain.outer`: {}), which needs a \
                     single-rate splitting method; multirate applies no damping",
                    path.display(),
                    own.label()
                ),
            ));
        }
    }
    let mut design = None;
    let mut regions = vec!["container".to_string()];
    let scene = (|| {
        let blame = |key: &str| {
            let key = key.to_string();
            move |e: Error| sweep_key_error(sweep, &key, e)
        };
        let mut c = src.container();
        if let JobKind::Random(i) = job.kind {
            design = Some(
                c.random_container(s.random.as_ref().expect("planned"), i)
                    .map_err(blame("random"))?,
            );
        }
        scenes::set_snapshots(c.file_mut(), s.snapshots);
        // A container's own `free_ends` (or `outer`, below) is more specific than the sweep's
        // `outer_chains` for every container, and wins (as a container's `multirate` wins over
        // the sweep's): studies/outer-medium.toml gives long chains to its `long` containers
        // that way.
        if matches!(entry, Some((_, e)) if e.free_ends) {
            let key = outer_key.as_deref().unwrap_or("free_ends");
            c.outer_chains(FREE_END_OUTER, 0).map_err(blame(key))?;
        } else if let Some(n) = s.outer_chains {
            c.outer_chains(n, n).map_err(blame("outer_chains"))?;
        }
        if multirate.is_some() {
            c.mark_fast_region().map_err(blame(&multirate_key))?;
        }
        if let Some(r) = &reading {
            c.reading(r).map_err(blame("search"))?;
        }
        let mut time_scale = None;
        if let Some((i, e)) = entry {
            if let Some(m) = e.outer {
                c.outer_medium(m)
                    .map_err(blame(&format!("containers[{i}].outer")))?;
            }
            if let Some(d) = e.dissipation {
                c.dissipation(d.model, d.restitution)
                    .map_err(blame(&format!("containers[{i}].dissipation")))?;
            }
            if let Some(v) = e.speed {
                check_speed(sweep, &c, i, v)?;
                time_scale = Some(
                    c.striker_speed(v)
                        .map_err(blame(&format!("containers[{i}].speed")))?,
                );
            }
        }
        // The one decision of the job's integrator, from all its dimensions.
        let damped = reading.as_ref().is_some_and(|r| r.medium.damps())
            || entry.is_some_and(|(_, e)| {
                e.outer.is_some_and(|o| o.damps()) || e.dissipation.is_some()
            });
        let stepping = Stepping::decide(multirate.map(|m| (m.ratio, m.margin)), damped);
        c.integrator(stepping, time_scale);
        c.perturb(s.perturbation, job.member)
            .map_err(blame("perturbation"))?;
        regions.extend(c.budget_regions()?);
        c.build()
    })();
    let scene = scene.map_err(|e| blame_sweep(sweep, job, e))?;
    check_gauges(sweep, job, &scene, outer_key.as_deref())?;
    // Long outer chains must stay untouched to the end of the run (nothing may come back from
    // their ends): a multirate margin that carries the fast region (always integrated) to an
    // end would fail every run, so it fails here, before anything runs.
    if let Some(fast) = scene.multirate_grains() {
        if !reaches_ends(s, job) && (*fast.start() == 0 || *fast.end() + 1 >= scene.grains()) {
            let m = multirate.map_or(0, |m| m.margin);
            return Err(invalid_sweep(
                sweep,
                &format!("{multirate_key}.margin"),
                format!(
                    "{m} grains carry the multirate fast region to an end of the chain of scene \
                     {} ({} grains as the study runs it), whose long outer chains must stay \
                     untouched; use a margin that leaves them outside",
                    path.display(),
                    scene.grains()
                ),
            ));
        }
    }
    Ok((scene, regions, design))
}

/// The most a container's `speed` may stretch the Hertz time scale of its scene (the factor
/// `(v0 / speed)^(1/5)` by which the snapshots grow while the step stays the scene's): 1000,
/// a speed 1e-15 of the scene's. studies/speed.toml's slowest speed (1e-5, a millionth of the
/// scene's 10) stretches it 15.8 times (its cost per member: docs/studies.md, "The sweeps"); a
/// factor of 1e6 (speed 1e-30) would be 2.5e8 steps per snapshot, months of running with
/// nothing refusing it.
pub const MAX_TIME_SCALE: f64 = 1000.0;

/// `containers[c].speed` against the scene's striker speed ([`MAX_TIME_SCALE`]).
fn check_speed(sweep: &SweepFile, scene: &ContainerScene, c: usize, v: f64) -> Result<(), Error> {
    let Some(v0) = scene.speed() else {
        return Ok(()); // ContainerScene::striker_speed names what is missing
    };
    let scale = scenes::hertz_time_scale(v0, v);
    if scale > MAX_TIME_SCALE {
        return Err(invalid_sweep(
            sweep,
            &format!("containers[{c}].speed"),
            format!(
                "{v:e} is too slow for scene {} (striker speed {v0}): its snapshots, at the \
                 scene's step, would take {scale:.3e} times the scene's steps each; at most \
                 {MAX_TIME_SCALE} times, a speed of at least {:e}",
                scene.source().path.display(),
                v0 / MAX_TIME_SCALE.powi(5)
            ),
        ));
    }
    Ok(())
}

/// The container's gauges need [`GAUGE_GRAINS`] grains on each side of region `container`
/// (what the run checks when it records them, `batch::run_job`): checked here, before anything
/// runs or any folder is claimed, and blamed on the sweep key that set the outer chains.
fn check_gauges(
    sweep: &SweepFile,
    job: &StudyJob,
    scene: &Scene,
    outer_key: Option<&str>,
) -> Result<(), Error> {
    let c = scene.region_grains("container")?;
    let (a, b) = (*c.start(), *c.end());
    let k = GAUGE_GRAINS;
    if a >= k && b + k < scene.grains() {
        return Ok(());
    }
    let message = format!(
        "the container's gauges need {k} grains on each side of region `container`; scene {} \
         as the study runs it ({}) has {} on the left and {} on the right",
        scene.path().display(),
        job.key,
        a,
        scene.grains() - 1 - b
    );
    Err(match outer_key {
        Some(key) => invalid_sweep(sweep, key, message),
        None => Error::Input(grainchain_engine::InputError::Invalid {
            file: scene.path().to_path_buf(),
            key: "regions".into(),
            message,
        }),
    })
}

fn invalid_sweep(sweep: &SweepFile, key: &str, message: String) -> Error {
    Error::Input(grainchain_engine::InputError::Invalid {
        file: sweep.path.clone(),
        key: key.into(),
        message,
    })
}

/// An error of an edit the sweep's `key` asked for, reported against the sweep file and that
/// key, naming the scene and the scene key that refused it.
fn sweep_key_error(sweep: &SweepFile, key: &str, e: Error) -> Error {
    match e {
        Error::Input(grainchain_engine::InputError::Invalid {
            file,
            key: k,
            message,
        }) => invalid_sweep(
            sweep,
            key,
            format!("{message} (scene {}, key `{k}`)", file.display()),
        ),
        e => e,
    }
}

/// Build the scene of member 0 of every container (the settings a sweep file imposes do not
/// depend on the member), so that a bad setting is reported before an output folder is made.
pub fn check_scenes(sweep: &SweepFile) -> Result<(), Error> {
    for j in plan(sweep).iter().filter(|j| j.member == 0) {
        job_scene(sweep, j)?;
    }
    Ok(())
}

/// A scene error caused by a setting the sweep file imposes on the scene is the sweep file's:
/// the multirate ratio (`multirate.ratio` or `containers[i].multirate.ratio`, which replace the
/// scene's own) is reported against the sweep key, naming the scene it does not fit; so is the
/// step a container's `speed` sets (`integrator.dt`: the scene's step scaled to the new
/// interval).
/// (`snapshots` cannot fail here: [`SweepFile::load`] bounds it by the scenes' own limit.)
fn blame_sweep(sweep: &SweepFile, job: &StudyJob, e: Error) -> Error {
    let s = &sweep.sweep;
    let Error::Input(grainchain_engine::InputError::Invalid { file, key, message }) = &e else {
        return e;
    };
    let (sweep_key, what) = match (key.as_str(), &job.kind) {
        ("integrator.multirate.ratio", &JobKind::Container(c))
            if s.containers[c].multirate.is_some() =>
        {
            (format!("containers[{c}].multirate.ratio"), "steps")
        }
        ("integrator.multirate.ratio", _) if s.multirate.is_some() => {
            ("multirate.ratio".to_string(), "steps")
        }
        ("integrator.dt", &JobKind::Container(c)) if s.containers[c].speed.is_some() => {
            (format!("containers[{c}].speed"), "step")
        }
        _ => return e,
    };
    let at = if what == "step" { " at this speed" } else { "" };
    Error::Input(grainchain_engine::InputError::Invalid {
        file: sweep.path.clone(),
        key: sweep_key,
        message: format!("{message} (the {what} of scene {}{at})", file.display()),
    })
}

/// Outer grains on each side over which a study member's `volume` gauge is taken
/// ([`crate::batch::GAUGES`]): 20, as in the measurement that opened issue 16.
pub const GAUGE_GRAINS: usize = 20;

/// Grains of `outer-left` in the free-end geometry (the paper's Fig. 3: container at grains
/// 121-300 of 420).
pub const FREE_END_OUTER: u64 = 120;

/// Whether the job's chain has ends that waves reach (the Fig. 3 geometry or an outer medium
/// other than long chains).
fn reaches_ends(s: &sweep::Sweep, job: &StudyJob) -> bool {
    match job.kind {
        JobKind::Container(c) => {
            s.containers[c].free_ends || s.containers[c].outer.is_some_and(|o| o.has_ends())
        }
        JobKind::Search(i, _) => search::reading(s.search.as_ref().expect("planned"), i)
            .medium
            .has_ends(),
        JobKind::Random(_) => false,
    }
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
    /// Jobs skipped because their member files were already there, whole and of this sweep
    /// (`resume`).
    pub kept: usize,
    /// Members found damaged or of another sweep or build and run again (`resume`): the reason
    /// for each.
    pub rerun: Vec<String>,
    /// Wall time of the jobs run, summed over threads.
    pub job_seconds: f64,
    /// Wall time of the whole stage, in seconds.
    pub wall: f64,
}

/// Stage 1: run this shard's jobs and write their member files into `out/members/`.
pub fn run_jobs(sweep: &SweepFile, opts: &Options) -> Result<RunReport, Error> {
    let t0 = std::time::Instant::now();
    let dir = opts.out.join("members");
    // Members are written into the output folder, never through a link out of it.
    if std::fs::symlink_metadata(&dir).is_ok_and(|m| !m.is_dir()) {
        return Err(crate::error::OutDirError::NotOurs {
            dir: opts.out.clone(),
            why: format!(
                "{} is not a folder (a symbolic link or a file), and members are written only \
                 into a folder inside the output folder",
                dir.display()
            ),
            advice: "remove it, or choose another --out".into(),
        }
        .into());
    }
    let all = plan(sweep);
    let mine: Vec<&StudyJob> = all.iter().filter(|j| opts.shard.owns(j.index)).collect();
    let mut kept = 0;
    let mut rerun = Vec::new();
    let shape = sweep.shape();
    let todo: Vec<&StudyJob> = mine
        .into_iter()
        .filter(|j| {
            if !opts.resume {
                return true;
            }
            match member_status(&dir, j.id(), sweep.id(), &shape) {
                MemberStatus::Complete => {
                    kept += 1;
                    false
                }
                MemberStatus::Missing => true,
                MemberStatus::Unusable(e) => {
                    rerun.push(e.to_string());
                    true
                }
            }
        })
        .collect();
    // Build every scene first, so a bad scene fails before anything runs.
    let mut built = Vec::with_capacity(todo.len());
    for j in &todo {
        let (scene, regions, design) = job_scene(sweep, j)?;
        // The energy budget's outer sections are whole sections of tens of thousands of grains;
        // protecting them would keep the causal horizon from dropping anything, so they are
        // recorded unprotected (STUDY.md says so), and only at the budget's outputs (the
        // points of its plot, about 700 of 100,000: at every output their energy cost a long
        // member 60 s on top of its run's 104 s). The container is exact, at every output.
        let unprotected = regions
            .iter()
            .filter(|r| *r != "container")
            .cloned()
            .collect();
        let job = Job {
            label: format!("{} member {}", j.key, j.member),
            scene,
            regions,
            unprotected,
            unprotected_at: Some(
                shape
                    .sampled_at
                    .iter()
                    .flatten()
                    .map(|&t| t as u64)
                    .collect(),
            ),
            snapshots: Vec::new(),
            require_untouched_ends: if reaches_ends(&sweep.sweep, j) {
                (false, false)
            } else {
                (true, true)
            },
            gauges: Some(GAUGE_GRAINS),
            mechanism: sweep.sweep.mechanism,
        };
        built.push((job, design));
    }
    let ticks = built.iter().map(|b| b.0.scene.outputs() + 1).sum();
    let labels: Vec<String> = built.iter().map(|b| b.0.label.clone()).collect();
    let pool = Pool {
        threads: opts.threads,
        progress: opts.progress,
        title: format!("study {}", opts.shard),
    };
    // The finished members stay on disk when a job fails (--resume goes on from there).
    let walls = pool.run(&labels, ticks, |k, tick| {
        let (job, (rj, design)) = (todo[k], &built[k]);
        let d = run_job(rj, tick)?;
        let design = design.as_ref().map(serde_json::to_value).transpose()?;
        let columns: Vec<String> = (rj.regions.iter().map(String::as_str))
            .chain(crate::batch::GAUGES)
            .map(String::from)
            .collect();
        write_member(&dir, job.id(), sweep.id(), &columns, &d, design)?;
        Ok(d.wall)
    })?;
    Ok(RunReport {
        ran: todo.len(),
        kept,
        rerun,
        job_seconds: walls.iter().sum(),
        wall: t0.elapsed().as_secs_f64(),
    })
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
    let shape = sweep.shape();
    let mut members = Vec::with_capacity(jobs.len());
    let mut missing = Vec::new();
    for j in &jobs {
        match read_member(dirs, j.id(), sweep.id(), &shape)? {
            Some(m) => members.push(m),
            None => missing.push(j),
        }
    }
    if !missing.is_empty() && partial && !members.is_empty() {
        let mut study = outputs::analyse(sweep, members, &key_kinds(sweep))?;
        study.missing = missing.iter().map(|j| j.stem().to_string()).collect();
        outputs::write(&study, out)?;
        return Ok(study);
    }
    if !missing.is_empty() {
        let list: Vec<String> = missing
            .iter()
            .take(6)
            .map(|j| format!("{} (job {})", j.stem(), j.index))
            .collect();
        return Err(StudyError::MissingMembers {
            missing: missing.len(),
            total: jobs.len(),
            examples: list,
        }
        .into());
    }
    let study = outputs::analyse(sweep, members, &key_kinds(sweep))?;
    outputs::write(&study, out)?;
    Ok(study)
}

/// Each key's kind as the job list makes it (member files hold only the key).
fn key_kinds(sweep: &SweepFile) -> std::collections::HashMap<String, KeyKind> {
    plan(sweep)
        .into_iter()
        .map(|j| (j.key, j.kind.key_kind()))
        .collect()
}

/// Claim the output folder `out` for the study of the sweep file at `sweep`, as `grainchain
/// study` does (`report::outdir`): the folder belongs to this sweep's inputs (not the build:
/// members of another build are refused one by one, and a resume runs them again); a shard
/// holds the folder's lock shared and its own exclusively, so shards run side by side and a
/// full run or a merge excludes them all; a folder holding only `members/` (gathered from
/// shards by hand) is adopted, each member checked on its own; the sweep file and the scene
/// files it names are never deleted, even inside `out`.
pub fn claim(
    sf: &SweepFile,
    sweep: &Path,
    out: &Path,
    shard: Option<Shard>,
    force: bool,
) -> Result<OutDir, Error> {
    let inputs = BTreeMap::from([("sweep".to_string(), sf.inputs_digest())]);
    let part = shard.map(|s| format!("shard-{}-of-{}", s.k, s.n));
    let mut protect = vec![sweep.to_path_buf()];
    protect.extend(sf.sweep.containers.iter().map(|c| sf.resolve(&c.scene)));
    protect.extend(sf.sweep.random.iter().map(|r| sf.resolve(&r.template)));
    if let Some(x) = &sf.sweep.search {
        protect.extend(x.scenes.iter().map(|p| sf.resolve(p)));
    }
    OutDir::claim_with(
        out,
        Claim {
            command: "study",
            inputs,
            part: part.as_deref(),
            force,
            adopt: &["members"],
            protect,
        },
    )
}
