//! `reproduce --members`: the containers as an ensemble study (`grainchain study` in-process),
//! run after the jobs of the plan; `render::ensemble` writes its section of REPORT.md.

use super::plan::ContainerSource;
use super::{Options, TWIN_EPS};
use crate::error::Error;
use std::time::Instant;

/// The containers as an ensemble study (`grainchain study` in-process).
pub fn run(
    opts: &Options,
    containers: &[ContainerSource],
) -> Result<(crate::study::outputs::Study, f64), Error> {
    use crate::study::sweep::{ContainerEntry, MultirateSpec, Perturbation, Sweep};
    let t0 = Instant::now();
    let sweep = Sweep {
        name: "reproduce-ensemble".into(),
        description: Some(format!(
            "The containers of `reproduce`, {} members each (reproduce --members).",
            opts.members
        )),
        snapshots: opts.snapshots.unwrap_or(4000),
        members: opts.members,
        perturbation: Perturbation::StrikerSpeed { epsilon: TWIN_EPS },
        outer_chains: None,
        multirate: Some(MultirateSpec {
            ratio: 16,
            margin: 20,
        }),
        reference: containers.iter().any(|c| c.key == "a").then(|| "a".into()),
        levels: vec![0.3, 0.2, 0.1, 0.05],
        containers: containers
            .iter()
            .map(|c| -> Result<ContainerEntry, Error> {
                Ok(ContainerEntry {
                    key: c.key.clone(),
                    // Absolute, so that it does not depend on where the sweep's path points.
                    scene: std::fs::canonicalize(&c.source.path).map_err(|source| Error::Io {
                        path: c.source.path.clone(),
                        source,
                    })?,
                    multirate: None,
                    free_ends: false,
                })
            })
            .collect::<Result<_, _>>()?,
        random: None,
    };
    let sf =
        crate::study::SweepFile::from_sweep(opts.scenes.join("reproduce-ensemble.toml"), sweep)?;
    let dir = opts.out.join("ensemble");
    let so = crate::study::Options {
        out: dir.clone(),
        shard: crate::study::Shard::ALL,
        threads: opts.threads,
        resume: false,
        progress: opts.progress,
    };
    crate::study::run_jobs(&sf, &so)?;
    let st = crate::study::merge(&sf, std::slice::from_ref(&dir), &dir)?;
    Ok((st, t0.elapsed().as_secs_f64()))
}
