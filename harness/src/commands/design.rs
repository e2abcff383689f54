//! `grainchain design`: a design file's search (or one island of it, or the merge of the
//! islands' journals) into a claimed folder, and the closing line on stderr.

use super::Caller;
use crate::design::{self as ds, Summary};
use crate::error::Error;
use crate::study::Shard;
use std::path::PathBuf;

/// What `grainchain design` is asked for.
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// The design file (TOML).
    pub file: PathBuf,
    /// Output directory (default: `out/design-<file name>`).
    pub out: Option<PathBuf>,
    /// Run only island K of N.
    pub shard: Option<Shard>,
    /// Do not search: write the outputs from every island's journal.
    pub merge: bool,
    /// Go on from the journal of an interrupted search.
    pub resume: bool,
    /// Threads (default: all cores); at least 1.
    pub threads: Option<u64>,
    /// Delete the files grainchain wrote in a folder of another command or another design file.
    pub force: bool,
}

/// `grainchain design`: run the search ([`ds::run`]) with a progress bar if the caller speaks,
/// and say on stderr what it did and, after an island, how to merge. Threads must be at least 1
/// ([`Error::Usage`]).
pub fn design(opts: &Options, caller: &Caller) -> Result<Summary, Error> {
    if opts.threads == Some(0) {
        return Err(Error::Usage {
            name: "threads",
            problem: "must be at least 1".into(),
        });
    }
    let out = opts.out.clone().unwrap_or_else(|| {
        let stem = opts.file.file_stem().unwrap_or_default().to_string_lossy();
        PathBuf::from(format!("out/design-{stem}"))
    });
    let run = ds::Options {
        file: opts.file.clone(),
        out: out.clone(),
        threads: opts.threads.map_or_else(
            || std::thread::available_parallelism().map_or(1, |n| n.get()),
            |t| t as usize,
        ),
        shard: opts.shard,
        merge: opts.merge,
        resume: opts.resume,
        force: opts.force,
        progress: caller.speaks,
    };
    let t = std::time::Instant::now();
    let s = ds::run(&run)?;
    if s.phases.len() > 1 {
        let times: Vec<String> = s
            .phases
            .iter()
            .map(|(name, t)| format!("{name} {t:.1} s"))
            .collect();
        caller.note(format_args!("design phases: {}", times.join(", ")));
    }
    let (known, ran) = s.columns;
    if known > 0 {
        caller.note(format_args!(
            "design: Monte Carlo columns: {known} known already ({}/{}), {ran} run",
            ds::EVALUATIONS,
            ds::draws_journal::MONTE_CARLO_JOURNAL
        ));
    }
    let best = s
        .best
        .map_or_else(|| "none".to_string(), |b| format!("{b:.4}"));
    if s.wrote_outputs {
        caller.note(format_args!(
            "design {}: {} designs evaluated ({} known), best objective {best}, in {:.1} s on {} \
             threads; wrote {}/DESIGN.md",
            opts.file.display(),
            s.evaluated,
            s.known,
            t.elapsed().as_secs_f64(),
            s.threads,
            out.display()
        ));
    } else {
        caller.note(format_args!(
            "design {}: island evaluated {} designs ({} known), best objective {best}, in {:.1} \
             s on {} threads; when every island has run: grainchain design {} --merge --out {}",
            opts.file.display(),
            s.evaluated,
            s.known,
            t.elapsed().as_secs_f64(),
            s.threads,
            opts.file.display(),
            out.display()
        ));
    }
    Ok(s)
}
