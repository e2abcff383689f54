//! Stage 2, execute: the plan's jobs on a few threads through the batch layer's pool
//! ([`crate::batch::Pool`]); results indexed by job, so they do not depend on scheduling.

use super::plan::{JobKey, Plan};
use super::Options;
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
