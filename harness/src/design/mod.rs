//! `grainchain design FILE`: search a design space of granular protectors in real materials
//! (`file`: the design file), seeded and resumable (`search`), against the known designs
//! (`baselines`), and write what a designer reads (`outputs`: DESIGN.md, CSV tables, the best
//! design as a scene file, plots; with `[tolerances]` the peaks' spreads, `tolerance`).
//!
//! A large search runs as islands: `--shard K/N` runs island K (seed + K - 1) and keeps its
//! journal in `evaluations/`; `--merge` writes the outputs from every island's journal, once
//! every island 1..N has finished (`search::merge_journals` checks each file it reads).

pub mod baselines;
pub mod draws_journal;
pub mod file;
mod outputs;
mod phases;
pub mod refine;
mod robust;
pub mod search;
pub mod tolerance;

pub use phases::Phases;
pub use robust::{FINALISTS_CSV, WINNERS_CSV};

pub use outputs::{BASELINES_HEADER, DESIGNS_HEADER, SENSITIVITIES_HEADER, TOLERANCES_HEADER};

use crate::error::{DesignFailure, Error};
use crate::report::outdir::{Claim, OutDir};
use crate::study::Shard;
use file::DesignSpec;
use indicatif::ProgressBar;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// How `grainchain design` runs.
#[derive(Clone, Debug)]
pub struct Options {
    /// The design file.
    pub file: PathBuf,
    /// The output folder.
    pub out: PathBuf,
    /// Threads for the evaluations.
    pub threads: usize,
    /// Run one island of a sharded search (its journal only), or `None` for the whole search.
    pub shard: Option<Shard>,
    /// Write the outputs from the islands' journals without searching.
    pub merge: bool,
    /// Go on from the journal of an interrupted run.
    pub resume: bool,
    /// Delete what grainchain wrote in a folder of another command or other inputs.
    pub force: bool,
    /// Draw the progress bar.
    pub progress: bool,
}

/// The folder of the islands' journals.
pub const EVALUATIONS: &str = "evaluations";

fn journal_path(out: &Path, shard: Shard) -> PathBuf {
    out.join(EVALUATIONS)
        .join(format!("island-{}-of-{}.csv", shard.k, shard.n))
}

/// Claim `out` for the design file (as `study::claim` does for a sweep).
fn claim(problem: &DesignSpec, opts: &Options) -> Result<OutDir, Error> {
    let part = opts.shard.map(|s| format!("shard-{}-of-{}", s.k, s.n));
    OutDir::claim_with(
        &opts.out,
        Claim {
            command: "design",
            inputs: BTreeMap::from([("design".to_string(), problem.digest.clone())]),
            part: part.as_deref(),
            force: opts.force,
            adopt: &[EVALUATIONS],
            protect: vec![opts.file.clone()],
        },
    )
}

/// What `grainchain design` did, for its closing line.
#[derive(Clone, Debug)]
pub struct Summary {
    /// Designs evaluated by this run.
    pub evaluated: u64,
    /// Designs known in all (journals included).
    pub known: usize,
    /// The best objective.
    pub best: Option<f64>,
    /// Whether outputs were written (not for a shard).
    pub wrote_outputs: bool,
    /// The threads the search ran on (`grainchain_engine::worker_threads` of the threads asked
    /// for and the population: one generation's designs are evaluated at once).
    pub threads: usize,
    /// Each phase's wall time, s, in the order they ran.
    pub phases: Vec<(String, f64)>,
    /// The Monte Carlo columns after the searches taken from the journal (`--resume`), and run.
    pub columns: (u64, u64),
}

/// The journal of the Monte Carlo columns a run writing outputs into `opts.out` evaluates after
/// its searches (read on `--resume`).
fn draws_journal(opts: &Options) -> Result<draws_journal::DrawsJournal, Error> {
    draws_journal::DrawsJournal::open(
        &opts
            .out
            .join(EVALUATIONS)
            .join(draws_journal::MONTE_CARLO_JOURNAL),
        opts.resume,
    )
}

/// The robust search's journal (the nominal search's is island 1 of 1).
const ROBUST_JOURNAL: &str = "robust-1-of-1.csv";

/// A search's progress bar: evaluations of at most `population * generations` designs.
fn search_bar(problem: &DesignSpec, phases: &Phases, label: &str) -> (ProgressBar, search::Tick) {
    let s = &problem.file.search;
    let pb = phases.bar((s.population * s.generations) as u64, label);
    let tick_bar = pb.clone();
    (pb, search::Tick(Arc::new(move || tick_bar.inc(1))))
}

/// `grainchain design` of a robust objective: the nominal search, the robust one, the
/// finalists and both winners ([`robust`]), and the nominal outputs with the robust section.
fn run_robust(problem: &DesignSpec, opts: &Options, dir: OutDir) -> Result<Summary, Error> {
    let threads = grainchain_engine::worker_threads(opts.threads, problem.file.search.population);
    std::fs::create_dir_all(opts.out.join(EVALUATIONS)).map_err(|source| Error::Io {
        path: opts.out.join(EVALUATIONS),
        source,
    })?;
    let phases = Phases::new(opts.progress).with_journal(draws_journal(opts)?);
    let nominal = problem.nominal();
    let seed = problem.file.search.seed;
    let (pb, tick) = search_bar(problem, &phases, "nominal search: evaluations (at most)");
    let first = phases.time("nominal search", || {
        search::run(
            &nominal,
            seed,
            opts.threads,
            &journal_path(&opts.out, Shard::ALL),
            opts.resume,
            &nominal.digest,
            tick,
        )
    })?;
    pb.finish_and_clear();
    let r = problem.robust.as_ref().expect("a robust objective");
    let (pb, tick) = search_bar(
        problem,
        &phases,
        &format!(
            "robust search: candidates on {} draws each (at most)",
            r.screen
        ),
    );
    let second = phases.time("robust search", || {
        search::run(
            problem,
            seed,
            opts.threads,
            &opts.out.join(EVALUATIONS).join(ROBUST_JOURNAL),
            opts.resume,
            &problem.digest,
            tick,
        )
    })?;
    pb.finish_and_clear();
    let merged = search::merge_journals(&nominal, &opts.out.join(EVALUATIONS))?;
    let extra = phases.time("finalists and winners", || {
        robust::report(problem, &merged, &second, opts.threads, &phases)
    })?;
    let written = phases.time("nominal outputs", || {
        outputs::write(
            &nominal,
            &merged,
            &opts.out,
            opts.threads,
            (Some(extra), &phases),
        )
    })?;
    dir.finish(&written)?;
    let (phases, columns) = phases.into_times();
    Ok(Summary {
        evaluated: first.evaluated + second.evaluated,
        known: merged.all.len() + second.all.len(),
        best: second.all.first().map(|s| s.objective),
        wrote_outputs: true,
        threads,
        phases,
        columns,
    })
}

/// Run `grainchain design`.
pub fn run(opts: &Options) -> Result<Summary, Error> {
    let problem = DesignSpec::load(&opts.file)?;
    let threads = grainchain_engine::worker_threads(opts.threads, problem.file.search.population);
    if problem.robust.is_some() && (opts.shard.is_some() || opts.merge) {
        // Before the folder is claimed: a refused command writes nothing.
        return Err(Error::Usage {
            name: if opts.merge { "merge" } else { "shard" },
            problem: format!(
                "{}: a robust objective's search runs whole, on one machine's threads (its two \
                 searches and the finalists share their draws): leave out --shard and --merge",
                problem.path.display()
            ),
        });
    }
    let dir = claim(&problem, opts)?;
    if problem.robust.is_some() {
        return run_robust(&problem, opts, dir);
    }
    let mut phases = Phases::new(opts.progress);
    let islands = opts.shard.unwrap_or(Shard::ALL);
    let mut evaluated = 0;
    if !opts.merge {
        std::fs::create_dir_all(opts.out.join(EVALUATIONS)).map_err(|source| Error::Io {
            path: opts.out.join(EVALUATIONS),
            source,
        })?;
        let s = &problem.file.search;
        let (pb, tick) = search_bar(&problem, &phases, "search: evaluations (at most)");
        let outcome = phases.time("search", || {
            search::run(
                &problem,
                s.seed.wrapping_add(islands.k as u64 - 1),
                opts.threads,
                &journal_path(&opts.out, islands),
                opts.resume,
                &problem.digest,
                tick,
            )
        })?;
        pb.finish_and_clear();
        evaluated = outcome.evaluated;
        if opts.shard.is_some() {
            dir.finish::<&str>(&[])?;
            let (phases, columns) = phases.into_times();
            return Ok(Summary {
                evaluated,
                known: outcome.all.len(),
                best: outcome.all.first().map(|s| s.objective),
                wrote_outputs: false,
                threads,
                phases,
                columns,
            });
        }
    }
    let merged = search::merge_journals(&problem, &opts.out.join(EVALUATIONS))?;
    if merged.all.is_empty() {
        return Err(Error::Design(DesignFailure::NoEvaluations {
            file: opts.file.clone(),
            dir: opts.out.join(EVALUATIONS),
            parts: "shards",
        }));
    }
    // Only a run that writes the outputs runs Monte Carlo columns (a shard has returned).
    if problem.tolerances.is_some() {
        phases = phases.with_journal(draws_journal(opts)?);
    }
    let written = phases.time("outputs", || {
        outputs::write(&problem, &merged, &opts.out, opts.threads, (None, &phases))
    })?;
    dir.finish(&written)?;
    let (phases, columns) = phases.into_times();
    Ok(Summary {
        evaluated,
        known: merged.all.len(),
        best: merged.all.first().map(|s| s.objective),
        wrote_outputs: true,
        threads,
        phases,
        columns,
    })
}
