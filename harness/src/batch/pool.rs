//! The one thread pool of every batch (`reproduce`'s figure runs, a study's members): jobs
//! numbered `0..n` started in that order on a rayon pool of a few threads, results kept by job
//! number (so they do not depend on scheduling), one progress bar on stderr that names the
//! running jobs.

use crate::error::BatchError;
use crate::error::Error;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::collections::BTreeSet;
use std::sync::atomic::{AtomicBool, Ordering};
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
    /// after each of its `ticks` units of progress (the bar's length is their sum). Jobs start
    /// in job order (a plan puts its long runs first). After the first failure no new job
    /// starts and the running ones finish; the error of the failed job with the lowest number
    /// is returned. Otherwise the results, in job order.
    pub fn run<T: Send>(
        &self,
        labels: &[String],
        ticks: u64,
        work: impl Fn(usize, &dyn Fn()) -> Result<T, Error> + Sync,
    ) -> Result<Vec<T>, Error> {
        let n = labels.len();
        let pool = grainchain_engine::thread_pool(self.threads, n)
            .map_err(|e| BatchError::Threads(e.to_string()))?;
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
        let failed = AtomicBool::new(false);
        let results: Vec<Mutex<Option<Result<T, Error>>>> =
            (0..n).map(|_| Mutex::new(None)).collect();
        let one = |k: usize| {
            if failed.load(Ordering::SeqCst) {
                // Not started after a failure; running ones finish.
                return;
            }
            {
                let mut r = running.lock().unwrap_or_else(|e| e.into_inner());
                r.insert(&labels[k]);
                show(&r);
            }
            let res = work(k, &|| pb.inc(1));
            if res.is_err() {
                failed.store(true, Ordering::SeqCst);
            }
            *results[k].lock().unwrap_or_else(|e| e.into_inner()) = Some(res);
            let mut r = running.lock().unwrap_or_else(|e| e.into_inner());
            r.remove(labels[k].as_str());
            show(&r);
        };
        // FIFO: every thread, the one running the scope included, takes the oldest job left,
        // so jobs start in job order (rayon's `par_iter` would split the range between threads).
        pool.scope_fifo(|s| {
            for k in 0..n {
                let one = &one;
                s.spawn_fifo(move |_| one(k));
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

#[cfg(test)]
mod tests {
    use super::*;

    fn pool(threads: usize) -> Pool {
        Pool {
            threads,
            progress: false,
            title: "test".into(),
        }
    }

    fn labels(n: usize) -> Vec<String> {
        (0..n).map(|k| format!("job {k}")).collect()
    }

    /// Results come back in job order at every thread count, every tick counted.
    #[test]
    fn results_are_in_job_order() {
        for threads in [1, 2, 4] {
            let out = pool(threads)
                .run(&labels(20), 40, |k, tick| {
                    tick();
                    tick();
                    Ok(k * k)
                })
                .unwrap();
            assert_eq!(out, (0..20).map(|k| k * k).collect::<Vec<_>>());
        }
    }

    /// On one thread the jobs start in job order, and after a failure no new job starts; the
    /// failed job's error is returned.
    #[test]
    fn jobs_start_in_order_and_stop_at_the_first_failure() {
        let started = Mutex::new(Vec::new());
        let res = pool(1).run(&labels(10), 10, |k, _| {
            started.lock().unwrap().push(k);
            if k == 4 {
                Err(BatchError::NotRun { job: "four".into() }.into())
            } else {
                Ok(k)
            }
        });
        assert_eq!(res.unwrap_err().to_string(), "four: not run");
        assert_eq!(*started.lock().unwrap(), vec![0, 1, 2, 3, 4]);
    }

    /// On several threads the error of the failed job with the lowest number is returned, even
    /// when a later job fails first.
    #[test]
    fn the_lowest_failed_job_is_reported() {
        let zero_started = AtomicBool::new(false);
        let res = pool(4).run(&labels(8), 8, |k, _| {
            if k == 0 {
                zero_started.store(true, Ordering::SeqCst);
                // Let the others fail first.
                std::thread::sleep(std::time::Duration::from_millis(50));
            } else {
                // No failure before job 0 has started (else it would rightly be skipped).
                while !zero_started.load(Ordering::SeqCst) {
                    std::thread::yield_now();
                }
            }
            if k % 3 == 0 {
                Err(BatchError::NotRun {
                    job: format!("failed {k}"),
                }
                .into())
            } else {
                Ok(k)
            }
        });
        assert_eq!(res.unwrap_err().to_string(), "failed 0: not run");
    }
}
