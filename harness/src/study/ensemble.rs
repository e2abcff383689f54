//! `reproduce --members N`: the containers of `reproduce` as an ensemble study, run in-process
//! (striker speed x (1 + k [`TWIN_EPS`]), multiple time stepping with ratio 16 and margin 20);
//! [`outputs::reproduce_section`] renders its section of REPORT.md.

use super::sweep::{ContainerEntry, MultirateSpec, Perturbation, Sweep};
use super::{outputs, Options, Shard, SweepFile};
use crate::batch::scenes::TWIN_EPS;
use crate::batch::ContainerSource;
use crate::error::Error;
use std::path::Path;
use std::time::Instant;

/// Run `containers` (from `scenes/containers/`) as an ensemble of `members` members of
/// `snapshots` snapshots each (default 4000), writing member files and the study's outputs to
/// `out`; the study and its wall time.
pub fn reproduce_ensemble(
    scenes: &Path,
    containers: &[ContainerSource],
    members: u64,
    snapshots: Option<u64>,
    out: &Path,
    threads: usize,
    progress: bool,
) -> Result<(outputs::Study, f64), Error> {
    let t0 = Instant::now();
    let sweep = Sweep {
        name: "reproduce-ensemble".into(),
        description: Some(format!(
            "The containers of `reproduce`, {members} members each (reproduce --members)."
        )),
        snapshots: snapshots.unwrap_or(4000),
        members,
        perturbation: Perturbation::StrikerSpeed { epsilon: TWIN_EPS },
        outer_chains: None,
        multirate: Some(MultirateSpec {
            ratio: 16,
            margin: 20,
        }),
        reference: containers.iter().any(|c| c.key == "a").then(|| "a".into()),
        levels: vec![0.3, 0.2, 0.1, 0.05],
        search: None,
        mechanism: false,
        containers: containers
            .iter()
            .map(|c| -> Result<ContainerEntry, Error> {
                // Absolute, so that it does not depend on where the sweep's path points.
                let scene = std::fs::canonicalize(&c.source.path).map_err(|source| Error::Io {
                    path: c.source.path.clone(),
                    source,
                })?;
                Ok(ContainerEntry::new(c.key.clone(), scene))
            })
            .collect::<Result<_, _>>()?,
        random: None,
    };
    let sf = SweepFile::from_sweep(scenes.join("reproduce-ensemble.toml"), sweep)?;
    let so = Options {
        out: out.to_path_buf(),
        shard: Shard::ALL,
        threads,
        resume: false,
        progress,
    };
    super::run_jobs(&sf, &so)?;
    let st = super::merge(&sf, std::slice::from_ref(&so.out), out)?;
    Ok((st, t0.elapsed().as_secs_f64()))
}
