//! `grainchain work-precision`: run time against error for every integrator, into a claimed
//! folder, and the table of points on stdout.

use super::Caller;
use crate::error::Error;
use crate::report::fnv1a;
use crate::report::outdir::{files_with, OutDir};
use crate::work_precision::{self as wp, Benchmark};
use std::collections::BTreeMap;
use std::path::PathBuf;

/// What `grainchain work-precision` is asked for.
#[derive(Clone, Debug)]
pub struct Options {
    /// Output directory.
    pub out: PathBuf,
    /// Fewer points and shorter problems (a smoke run).
    pub quick: bool,
    /// Only these problems ([`Benchmark::NAMES`]); empty: all.
    pub only: Vec<String>,
    /// Timing repeats per point (the median is reported).
    pub repeats: usize,
    /// Delete the files grainchain wrote in a folder of another command or other inputs.
    pub force: bool,
}

/// `grainchain work-precision`: the problems asked for (a name not in [`Benchmark::NAMES`] is
/// [`Error::Usage`]), the folder claimed for these options, the study run with a spinner, its
/// CSV and SVG written and its points printed.
pub fn work_precision(opts: &Options, caller: &Caller) -> Result<wp::Study, Error> {
    let Options {
        out,
        quick,
        only,
        repeats,
        force,
    } = opts;
    if let Some(n) = only
        .iter()
        .find(|n| !Benchmark::NAMES.contains(&n.as_str()))
    {
        return Err(Error::Usage {
            name: "only",
            problem: format!(
                "no problem `{n}` (the problems: {})",
                Benchmark::NAMES.join(", ")
            ),
        });
    }
    let problems: Vec<Benchmark> = Benchmark::ALL
        .into_iter()
        .filter(|p| only.is_empty() || only.iter().any(|n| n == p.name()))
        .collect();
    let cfg = wp::Config {
        quick: *quick,
        repeats: *repeats,
        ..Default::default()
    };
    let options = format!("quick={quick} only={only:?} repeats={repeats}");
    let inputs = BTreeMap::from([("options".to_string(), fnv1a(options.as_bytes()))]);
    let dir = OutDir::claim(out, "work-precision", inputs, None, *force)?;
    let pb = caller.spinner();
    let study = wp::run(&cfg, &problems, |label| pb.set_message(label.to_string()));
    pb.finish_and_clear();
    let study = study?;
    study.write(out)?;
    if !study.points.is_empty() {
        caller.out(format_args!(
            "{:<14} {:<13} {:>11} {:>11} {:>10} {:>9}",
            "problem", "method", "setting", "error", "seconds", "evals"
        ));
    }
    for p in &study.points {
        if p.failure.is_empty() {
            caller.out(format_args!(
                "{:<14} {:<13} {:>11.3e} {:>11.3e} {:>10.4} {:>9}",
                p.problem, p.method, p.setting, p.error, p.seconds, p.force_evals
            ));
        } else {
            // `failed: ...` or `not evaluated: ...` (no number is printed then).
            caller.out(format_args!(
                "{:<14} {:<13} {:>11.3e} {}",
                p.problem, p.method, p.setting, p.failure
            ));
        }
    }
    if let Some(s) = &study.statistics {
        caller.out(format_args!("{}", s.table().trim_end()));
    }
    // After the statistics: the order problems' observed orders.
    let orders = study.orders_table();
    if !orders.is_empty() {
        caller.out(format_args!("{}", orders.trim_end()));
    }
    dir.finish(&files_with(out, &[".csv", ".svg"])?)?;
    caller.out(format_args!("wrote {}", out.display()));
    Ok(study)
}
