//! The one thread pool of every batch (`reproduce`'s figure runs, a study's members): jobs
//! numbered `0..n` handed out in order to a few threads, results kept by job number (so they do
//! not depend on scheduling), one progress bar on stderr that names the running jobs.

use crate::error::BatchError;
use crate::error::Error;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::collections::BTreeSet;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// How a batch runs: threads and its progress bar.
#[derive(Clone, Debug)]
pub struct Pool {
    /// Worker threads asked for (`grainchain_engine::worker_threads`: at least 1, at most one
    /// per job and what the machine runs at once).
    pub threads: usize,
    /// Draw the progress bar on stderr (hidden anyway when stderr is not a terminal).
    pub progress: bool,
    /// The bar's title (`reproduce`, `study 1/3`).
    pub title: String,
}

impl Pool {
    /// Run the jobs named `labels` (one per job): `work(k, tick)` runs job `k` and calls `tick`
    /// after each of its `ticks` units of progress (the bar's length is their sum). After the
    /// first failure no new job starts and the running ones finish; the error of the failed job
    /// with the lowest number is returned. Otherwise the results, in job order.
    pub fn run<T: Send>(
        &self,
        labels: &[String],
        ticks: u64,
        work: impl Fn(usize, &dyn Fn()) -> Result<T, Error> + Sync,
    ) -> Result<Vec<T>, Error> {
        let target = if self.progress {
            ProgressDrawTarget::stderr()
        } else {
            ProgressDrawTarget::hidden()
        };
        let pb = ProgressBar::with_draw_target(Some(ticks), target);
        pb.set_style(
            ProgressStyle::with_template(&format!(
                "{} [{{bar:30}}] {{percent:>3}}% {{elapsed}}/{{duration}} | {{msg}}",
                self.title
            ))
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
        );
        let running: Mutex<BTreeSet<&str>> = Mutex::new(BTreeSet::new());
        let show = |r: &BTreeSet<&str>| {
            pb.set_message(r.iter().copied().collect::<Vec<_>>().join(", "));
        };
        let n = labels.len();
        let next = AtomicUsize::new(0);
        let results: Vec<Mutex<Option<Result<T, Error>>>> =
            (0..n).map(|_| Mutex::new(None)).collect();
        let threads = grainchain_engine::worker_threads(self.threads, n);
        std::thread::scope(|s| {
            for _ in 0..threads {
                s.spawn(|| loop {
                    let k = next.fetch_add(1, Ordering::SeqCst);
                    if k >= n {
                        break;
                    }
                    {
                        let mut r = running.lock().unwrap_or_else(|e| e.into_inner());
                        r.insert(&labels[k]);
                        show(&r);
                    }
                    let res = work(k, &|| pb.inc(1));
                    let failed = res.is_err();
                    *results[k].lock().unwrap_or_else(|e| e.into_inner()) = Some(res);
                    {
                        let mut r = running.lock().unwrap_or_else(|e| e.into_inner());
                        r.remove(labels[k].as_str());
                        show(&r);
                    }
                    if failed {
                        // Stop handing out new jobs; running ones finish.
                        next.store(n, Ordering::SeqCst);
                    }
                });
            }
        });
        pb.finish_and_clear();
        let results: Vec<Option<Result<T, Error>>> = results
            .into_iter()
            .map(|r| r.into_inner().unwrap_or_else(|e| e.into_inner()))
            .collect();
        // The first failed job (in job order); jobs skipped after a failure are not errors.
        let mut out = Vec::with_capacity(n);
        let mut skipped = None;
        for (k, r) in results.into_iter().enumerate() {
            match r {
                Some(Ok(d)) => out.push(d),
                Some(Err(e)) => return Err(e),
                None => skipped = skipped.or(Some(k)),
            }
        }
        if let Some(k) = skipped {
            return Err(BatchError::NotRun {
                job: labels[k].clone(),
            }
            .into());
        }
        Ok(out)
    }
}
