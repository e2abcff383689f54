//! One simulation of a batch: a checked scene, the regions to record by name and the
//! whole-chain snapshots to keep, run through the [`Recorder`]. A job's numbers depend only on
//! its scene, never on the thread that runs it or when.

use crate::error::BatchError;
use crate::error::Error;
use grainchain_engine::Field;
use grainchain_engine::RunSummary;
use grainchain_engine::Scene;
use grainchain_engine::{Recorder, RegionSeries, Schedule};
use std::time::Instant;

/// One simulation to run.
pub struct Job {
    /// Shown in the progress bar and in error messages.
    pub label: String,
    /// The built scene to run (already edited by the plan: run length, step, variant).
    pub scene: Scene,
    /// Names of scene regions whose energy is recorded at every output index.
    pub regions: Vec<String>,
    /// Those of `regions` that the causal horizon (`run.horizon`) may cut into: recorded
    /// without protection (`Recorder::region_unprotected`; a study's energy budget of the outer
    /// sections). Every other region is exact.
    pub unprotected: Vec<String>,
    /// The output indices at which the `unprotected` regions are recorded (`None`: every
    /// output), with NaN at the others (`Recorder::region_sampled`): a study's budget of outer
    /// sections of tens of thousands of grains would otherwise cost more than running them.
    pub unprotected_at: Option<Vec<u64>>,
    /// Output indices at which the velocity and energy of every grain are recorded.
    pub snapshots: Vec<u64>,
    /// Fail when a disturbance reaches the (left, right) end of the chain: the outer chains must
    /// be long enough that nothing can come back.
    pub require_untouched_ends: (bool, bool),
    /// Record the gauges of region `container` at every output ([`GAUGES`]), the volume over
    /// this many outer grains on each side.
    pub gauges: Option<usize>,
    /// Count the reflections at the edges of region `container` and follow the pulses inside it
    /// (the paper's mechanism, [`super::mechanism`]).
    pub mechanism: bool,
}

/// A gauge of a container, recorded as a column of a job's [`RunData`] (and of member files).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Gauge {
    /// `volume`: mean displacement of the first `k` outer grains on the right minus that of the
    /// first `k` on the left (positive: the container has grown).
    Volume,
    /// `force-left`: the contact force between the container's left outer grain and the first
    /// outer grain on that side (the back-pressure of the outer medium; compression positive),
    /// at the output instant.
    ForceLeft,
    /// `force-right`: as [`Gauge::ForceLeft`], on the right.
    ForceRight,
}

impl Gauge {
    /// Every gauge, in the order of the member files' columns.
    pub const ALL: [Gauge; 3] = [Gauge::Volume, Gauge::ForceLeft, Gauge::ForceRight];

    /// The gauge's name: its column in member files, the one spelling every other is made from
    /// ([`Gauge::field`], [`Gauge::words`]).
    pub const fn name(self) -> &'static str {
        match self {
            Gauge::Volume => "volume",
            Gauge::ForceLeft => "force-left",
            Gauge::ForceRight => "force-right",
        }
    }

    /// The name as a field of a CSV header that uses `_` (a study's `gauges.csv`).
    pub fn field(self) -> String {
        self.name().replace('-', "_")
    }

    /// The name in words (a table head of STUDY.md).
    pub fn words(self) -> String {
        self.name().replace('-', " ")
    }

    /// The gauge of column `name` of a member file, if it is one.
    pub fn of_column(name: &str) -> Option<Gauge> {
        Gauge::ALL.into_iter().find(|g| g.name() == name)
    }

    /// Its position in [`Gauge::ALL`] (the order of every table of gauges).
    pub fn index(self) -> usize {
        Gauge::ALL
            .iter()
            .position(|g| *g == self)
            .expect("every gauge is in ALL")
    }
}

/// The gauges' column names ([`Gauge::name`]), in [`Gauge::ALL`] order.
pub const GAUGES: [&str; Gauge::ALL.len()] = {
    let mut names = [""; Gauge::ALL.len()];
    let mut i = 0;
    while i < names.len() {
        names[i] = Gauge::ALL[i].name();
        i += 1;
    }
    names
};

/// A whole-chain snapshot.
#[derive(Clone, Debug)]
pub struct Snap {
    /// Output index `k` of the snapshot (0 is the initial state).
    pub index: u64,
    /// Its time, `k` times the output interval.
    pub time: f64,
    /// Velocity of every grain, by internal (0-based) index, the striker included.
    pub velocity: Vec<f64>,
    /// Energy of every grain (kinetic plus half of each contact's potential), by internal index.
    pub energy: Vec<f64>,
}

/// What a job recorded.
#[derive(Clone, Debug)]
pub struct RunData {
    /// The job's label ([`Job::label`]), for error messages.
    pub label: String,
    /// The recorded regions under their scene names ([`Job::regions`]), read by name through
    /// [`RunData::region`].
    regions: Vec<RegionSeries>,
    /// The whole-chain snapshots at [`Job::snapshots`], in time order.
    pub snaps: Vec<Snap>,
    /// The gauges ([`Job::gauges`]) under their names ([`GAUGES`]), at every output.
    gauges: Vec<(&'static str, Vec<f64>)>,
    /// Printed grain number of internal grain 0.
    pub first_grain: i64,
    /// The run's bookkeeping (grains, ever-touched range, energy, method, counters).
    pub run: RunSummary,
    /// The paper's mechanism ([`Job::mechanism`]).
    pub mechanism: Option<super::mechanism::MemberMechanism>,
    /// Wall time of the job, set-up included.
    pub wall: f64,
}

/// One recorded region of a run.
#[derive(Clone, Copy, Debug)]
pub struct Region<'a> {
    /// Internal grain indices, inclusive.
    pub range: (usize, usize),
    /// Energy at every output index.
    pub energy: &'a [f64],
}

impl RunData {
    /// Number of recorded outputs (index 0, the initial state, included).
    pub fn recorded(&self) -> usize {
        self.regions.first().map_or(0, |r| r.energy.len())
    }

    /// The names of the recorded regions, in [`Job::regions`] order.
    pub fn region_names(&self) -> impl Iterator<Item = &str> {
        self.regions.iter().map(|r| r.name.as_str())
    }

    /// The column `name` of a member file: a recorded region's energy or a gauge
    /// ([`GAUGES`]).
    pub fn column(&self, name: &str) -> Result<&[f64], Error> {
        match self.gauges.iter().find(|g| g.0 == name) {
            Some(g) => Ok(&g.1),
            None => Ok(self.region(name)?.energy),
        }
    }

    /// The recorded region named `name`.
    pub fn region(&self, name: &str) -> Result<Region<'_>, Error> {
        let r = self
            .regions
            .iter()
            .find(|r| r.name == name)
            .ok_or_else(|| BatchError::RegionNotRecorded {
                job: self.label.clone(),
                region: name.to_string(),
            })?;
        Ok(Region {
            range: (r.first, r.last),
            energy: &r.energy,
        })
    }
}

/// Run `job`, calling `tick` after every output (a progress bar).
pub fn run_job(job: &Job, tick: &dyn Fn()) -> Result<RunData, Error> {
    let t0 = Instant::now();
    let mut recorder = Recorder::new();
    for name in &job.regions {
        let grains = region_grains(job, name)?;
        let (a, b) = (*grains.start(), *grains.end());
        recorder = if !job.unprotected.contains(name) {
            recorder.region(name.clone(), a, b)
        } else if let Some(at) = &job.unprotected_at {
            recorder.region_sampled(name.clone(), a, b, Schedule::At(at.clone()))
        } else {
            recorder.region_unprotected(name.clone(), a, b)
        };
    }
    let mut sim = job.scene.simulation()?;
    check_snapshots(job, sim.outputs())?;
    let n = sim.chain().len();
    let first_grain = sim.chain().grain_number(0);
    let snapshots = job.snapshots.iter().copied();
    let mut recorder = recorder.snapshots(&[Field::Velocity, Field::Energy], 0..n, snapshots);
    // The gauges' grains: k outer grains on each side, then the grain left of each face.
    if let Some(k) = job.gauges {
        let c = region_grains(job, "container")?;
        let (a, b) = (*c.start(), *c.end());
        if k == 0 || a < k || b + k >= n {
            return Err(Error::Input(grainchain_engine::InputError::Invalid {
                file: job.scene.path().to_path_buf(),
                key: "regions".into(),
                message: format!(
                    "the container's gauges need {k} grains (at least 1) on each side of region `container`"
                ),
            }));
        }
        recorder = recorder
            .probes(Field::Displacement, (a - k..a).chain(b + 1..=b + k))
            .probes(Field::Force, [a - 1, b]);
    }
    // The mechanism: reflections at the container's edges, and its grains' energies and
    // velocities at every output for the pulses' speeds (probes after the gauges').
    let inside = match job.mechanism {
        true => {
            let c = region_grains(job, "container")?;
            sim.watch_reflections(
                *c.start(),
                *c.end(),
                grainchain_engine::ReflectionRule::default(),
            )?;
            recorder = recorder
                .probes(Field::Energy, c.clone())
                .probes(Field::Velocity, c.clone());
            c.count()
        }
        false => 0,
    };
    let mut rec = recorder.record_with(&mut sim, |_| tick())?;
    let mechanism = match job.mechanism {
        true => {
            let probes = rec.probes.split_off(rec.probes.len() - 2 * inside);
            let (energy, velocity) = probes.split_at(inside);
            let rows = energy.first().map_or(0, |s| s.values.len());
            let by_output = |s: &[grainchain_engine::ProbeSeries]| -> Vec<Vec<f64>> {
                (0..rows)
                    .map(|t| s.iter().map(|g| g.values[t]).collect())
                    .collect()
            };
            let interval = sim.output_interval();
            let mut m = super::mechanism::MemberMechanism::new(sim.outputs());
            m.add_hits(&sim.end_reflections(), interval, sim.initial_energy());
            m.add_speeds(&by_output(energy), &by_output(velocity), interval);
            Some(m)
        }
        false => None,
    };
    let gauges = match job.gauges {
        Some(k) => {
            // The probes in the order added above: the displacements of the `k` outer grains on
            // the left, of the `k` on the right, then the forces on the left and right faces.
            let (left, rest) = rec.probes.split_at(k);
            let (right, forces) = rest.split_at(k);
            let [force_left, force_right] = forces else {
                unreachable!("two force probes were added")
            };
            let rows = left.first().map_or(0, |s| s.values.len());
            Gauge::ALL
                .into_iter()
                .map(|g| {
                    let values = match g {
                        Gauge::Volume => (0..rows)
                            .map(|t| {
                                let mean = |s: &[grainchain_engine::ProbeSeries]| {
                                    s.iter().map(|x| x.values[t]).sum::<f64>() / k as f64
                                };
                                mean(right) - mean(left)
                            })
                            .collect(),
                        Gauge::ForceLeft => force_left.values.clone(),
                        Gauge::ForceRight => force_right.values.clone(),
                    };
                    (g.name(), values)
                })
                .collect()
        }
        None => Vec::new(),
    };
    let snaps = rec
        .snapshots
        .into_iter()
        .map(|s| {
            let mut v = s.values.into_iter();
            Snap {
                index: s.index,
                time: s.time,
                velocity: v.next().unwrap_or_default(),
                energy: v.next().unwrap_or_default(),
            }
        })
        .collect();
    let data = RunData {
        label: job.label.clone(),
        regions: rec.regions,
        gauges,
        snaps,
        first_grain,
        run: sim.summary(),
        mechanism,
        wall: t0.elapsed().as_secs_f64(),
    };
    check_ends(job, &data, n)?;
    Ok(data)
}

/// The internal grain indices of the job's region `name` ([`Scene::region_grains`]), or the
/// error that the job's scene lacks it.
fn region_grains(job: &Job, name: &str) -> Result<std::ops::RangeInclusive<usize>, Error> {
    if job.scene.region(name).is_none() {
        return Err(Error::Input(grainchain_engine::InputError::Invalid {
            file: job.scene.path().to_path_buf(),
            key: "regions".into(),
            message: format!("`grainchain reproduce` needs a region named `{name}` in this scene"),
        }));
    }
    Ok(job.scene.region_grains(name)?)
}

/// Every listed snapshot is within the run's `outputs`.
fn check_snapshots(job: &Job, outputs: u64) -> Result<(), Error> {
    for &k in &job.snapshots {
        if k > outputs {
            return Err(BatchError::SnapshotBeyondRun {
                scene: job.scene.path().to_path_buf(),
                snapshot: k,
                outputs,
            }
            .into());
        }
    }
    Ok(())
}

/// Fail when a disturbance reached an end of the `n` grains that must stay untouched.
fn check_ends(job: &Job, data: &RunData, n: usize) -> Result<(), Error> {
    let (left, right) = job.require_untouched_ends;
    let ever = data.run.ever;
    if (left && ever.0 == 0) || (right && ever.1 == n) {
        let side = if left && ever.0 == 0 { "left" } else { "right" };
        return Err(BatchError::ReachedEnd {
            job: job.label.clone(),
            scene: job.scene.path().to_path_buf(),
            side,
        }
        .into());
    }
    Ok(())
}
