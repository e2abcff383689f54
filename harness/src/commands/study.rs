//! `grainchain study`: a sweep file checked, its jobs (or one shard of them) run into member
//! files in a claimed folder, and the members merged into the study's outputs.

use super::Caller;
use crate::error::Error;
use crate::report::outdir::files_with;
use crate::study::{self as st, Shard};
use grainchain_engine::format::seconds;
use std::path::PathBuf;

/// What `grainchain study` is asked for.
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// The sweep file (TOML).
    pub sweep: PathBuf,
    /// Output directory (default: `out/study-<sweep name>`).
    pub out: Option<PathBuf>,
    /// Run only part K of N and write its member files.
    pub shard: Option<Shard>,
    /// Do not run anything: merge the member files of every shard.
    pub merge: bool,
    /// More directories holding member files (`members/`) of shards.
    pub from: Vec<PathBuf>,
    /// Keep member files already written for this sweep file and run only the missing jobs.
    pub resume: bool,
    /// With `merge`: use the members present even if some are missing.
    pub partial: bool,
    /// Only check the sweep file and build every job's scene (nothing runs, nothing is written).
    pub check: bool,
    /// Threads (default: all cores); at least 1.
    pub threads: Option<u64>,
    /// Delete the files grainchain wrote in a folder of another command or another sweep.
    pub force: bool,
    /// Plan or run even if the member files (or the job list) are estimated over the limit.
    pub allow_large_output: bool,
}

/// What [`study`] did.
#[derive(Clone, Debug, Default)]
pub struct Done {
    /// The output directory.
    pub out: PathBuf,
    /// The study's jobs (every shard's).
    pub jobs: usize,
    /// What the jobs' stage did (nothing ran for `merge` or `check`).
    pub run: st::RunReport,
    /// Whether the members were merged into the study's outputs.
    pub merged: bool,
    /// Members missing from a partial merge.
    pub missing: Vec<String>,
}

/// `grainchain study` (and Python's `study`): check the `from` folders and the sweep file (its
/// size unless allowed, its scenes), then either only build every job's scene (`check`), or
/// claim the folder, run this shard's jobs (unless `merge`) and, but for a shard, merge every
/// member into the outputs; each step says what it did.
pub fn study(opts: &Options, caller: &Caller) -> Result<Done, Error> {
    let sweep = &opts.sweep;
    if opts.threads == Some(0) {
        return Err(Error::Usage {
            name: "threads",
            problem: "must be at least 1".into(),
        });
    }
    for d in &opts.from {
        if !d.join("members").is_dir() {
            return Err(Error::Io {
                path: d.join("members"),
                source: std::io::Error::new(
                    std::io::ErrorKind::NotFound,
                    "--from: no member folder here (give the --out folder of a shard)",
                ),
            });
        }
    }
    let sf = st::SweepFile::load(sweep)?;
    if let Some(e) = sf
        .size_refusal(sweep, caller.words)
        .filter(|_| !opts.allow_large_output)
    {
        return Err(e.into());
    }
    let out = opts
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("out/study-{}", sf.sweep.name)));
    let jobs = st::plan(&sf).len();
    let mut done = Done {
        out: out.clone(),
        jobs,
        ..Done::default()
    };
    if opts.check {
        // The study's own checks before it claims its folder (`check_scenes`), and every job's
        // scene as the study builds it: `--check` passes what the study does not refuse before
        // running.
        st::check_scenes(&sf)?;
        for j in st::plan(&sf) {
            st::job_scene(&sf, &j)?;
        }
        let s = &sf.sweep;
        caller.out(format_args!(
            "{}: ok ({} jobs: {} containers x {} members{}, {} snapshots each; run digest {})",
            sweep.display(),
            jobs,
            s.containers.len(),
            s.members,
            s.random.as_ref().map_or(String::new(), |r| format!(
                ", {} random x {}",
                r.count, r.members
            )) + &s.search.as_ref().map_or(String::new(), |x| format!(
                ", {} readings x {} containers x {}",
                x.count,
                x.scenes.len(),
                x.members
            )),
            s.snapshots,
            sf.digest
        ));
        return Ok(done);
    }
    // The folder belongs to this sweep (its inputs, not the build: members of another build are
    // refused one by one, and --resume runs them again). Shards of one study share it (the
    // folder's lock shared, each its own exclusively); a full run or a merge holds the folder's
    // exclusively, so it never runs beside a shard.
    if !opts.merge {
        // A bad setting of the sweep file is reported before the folder is made.
        st::check_scenes(&sf)?;
    }
    let dir = st::claim(&sf, sweep, &out, opts.shard, opts.force)?;
    if !opts.merge {
        let threads = opts.threads.map_or_else(
            || std::thread::available_parallelism().map_or(2, |n| n.get()),
            |t| t as usize,
        );
        let run = st::Options {
            out: out.clone(),
            shard: opts.shard.unwrap_or(Shard::ALL),
            threads,
            resume: opts.resume,
            progress: caller.speaks,
        };
        let r = st::run_jobs(&sf, &run)?;
        for why in &r.rerun {
            caller.out(format_args!("ran again: {why}"));
        }
        caller.out(format_args!(
            "study {}: shard {}: ran {} of {} members ({} kept from an earlier run) in {:.1} s \
             on {} threads ({} s of member time)",
            sf.sweep.name,
            run.shard,
            r.ran,
            jobs,
            r.kept,
            r.wall,
            // The pool's threads (`worker_threads`: at most one per job run and what the
            // machine runs at once): say how many ran.
            grainchain_engine::worker_threads(threads, r.ran),
            seconds(r.job_seconds)
        ));
        done.run = r;
        if opts.shard.is_some() {
            caller.out(format_args!(
                "wrote {}/members; when every shard has run: grainchain study {} --merge --out {}",
                out.display(),
                sweep.display(),
                out.display()
            ));
            return Ok(done);
        }
    }
    let mut dirs = vec![out.clone()];
    dirs.extend(opts.from.iter().cloned());
    let merged = st::merge_with(&sf, &dirs, &out, opts.partial)?;
    dir.finish(&files_with(&out, &[".csv", ".svg", ".md"])?)?;
    if !merged.missing.is_empty() {
        caller.out(format_args!(
            "partial merge: {} members missing ({})",
            merged.missing.len(),
            merged.missing.join(", ")
        ));
    }
    for k in &merged.containers {
        if let Some(e) = k.fit.est {
            caller.out(format_args!(
                "({}) gamma of the mean over [{}, {}]: {:.3} [{:.3}, {:.3}] ({} members)",
                k.key, k.fit.t_lo, k.fit.t_hi, e.value, e.ci_lo, e.ci_hi, e.n
            ));
        } else {
            caller.out(format_args!(
                "({}) no gamma of the mean: {}",
                k.key,
                k.fit.why_missing()
            ));
        }
    }
    caller.out(format_args!("wrote {} (STUDY.md)", out.display()));
    done.merged = true;
    done.missing = merged.missing;
    Ok(done)
}
