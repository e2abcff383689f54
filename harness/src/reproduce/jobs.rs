//! Stage 2, execute: the plan's jobs on a few threads through the batch layer's pool
//! ([`crate::batch::Pool`]); results indexed by job, so they do not depend on scheduling.

use super::options::Options;
use super::plan::{JobKey, Plan};
use crate::batch::{run_job, Pool, RunData};
use crate::error::Error;

/// The results of a plan's jobs, each under its key, in plan order.
pub struct Runs {
    /// Every job's key and recording, in plan order.
    pub runs: Vec<(JobKey, RunData)>,
}

impl Runs {
    /// The recording of the job `key` (`None`: the plan did not have it, e.g. the fine runs
    /// without `--check-step`).
    pub fn get(&self, key: &JobKey) -> Option<&RunData> {
        self.runs.iter().find(|(k, _)| k == key).map(|(_, d)| d)
    }

    /// The recording of the job `key`, which the plan has.
    pub(crate) fn need(&self, key: &JobKey) -> Result<&RunData, Error> {
        self.get(key)
            .ok_or_else(|| crate::error::ReproduceError::NotInPlan { job: key.label() }.into())
    }

    /// Every simulation, for the runs table, in plan order.
    pub(crate) fn entries(&self) -> Vec<RunEntry> {
        self.runs.iter().map(|(k, d)| RunEntry::of(k, d)).collect()
    }
}

/// One simulation of a `reproduce` run, for its runs table.
#[derive(Clone, Debug)]
pub struct RunEntry {
    /// Which simulation of the plan it was.
    pub key: JobKey,
    /// The run's bookkeeping ([`grainchain_engine::RunSummary`]).
    pub run: grainchain_engine::RunSummary,
    /// Output times recorded (t = 0 included).
    pub recorded: usize,
    /// Wall time of the job, set-up included.
    pub wall: f64,
}

impl RunEntry {
    fn of(key: &JobKey, d: &RunData) -> Self {
        RunEntry {
            key: key.clone(),
            run: d.run.clone(),
            recorded: d.recorded(),
            wall: d.wall,
        }
    }

    /// Its name in the runs table ([`JobKey::label`]).
    pub fn label(&self) -> String {
        self.key.label()
    }
}

/// Run every job of `plan`.
pub fn execute(opts: &Options, plan: &Plan) -> Result<Runs, Error> {
    let pool = Pool {
        threads: opts.threads,
        progress: opts.progress,
        title: "reproduce".into(),
    };
    let labels: Vec<String> = plan.jobs.iter().map(|j| j.label.clone()).collect();
    let ticks = plan.jobs.iter().map(|j| j.scene.outputs() + 1).sum();
    let data = pool.run(&labels, ticks, |k, tick| run_job(&plan.jobs[k], tick))?;
    let runs = plan.keys.iter().cloned().zip(data).collect();
    Ok(Runs { runs })
}
