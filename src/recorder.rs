//! Recording a run without writing a callback: ask for time series (totals, region energies and
//! momenta by region name, fields of single grains) and snapshots (fields, grains, output indices), optionally a level at
//! which to stop, and get typed results back.
//!
//! ```
//! use grainchain::observables::Field;
//! use grainchain::recorder::Recorder;
//! use grainchain::{ChainBuilder, ContactLaw, SimulationBuilder};
//!
//! let chain = ChainBuilder::new().grains(200, 1.0, ContactLaw::hertz(5657.0)).build()?;
//! let mut sim = SimulationBuilder::new(chain).schedule(4.0, 0.125).velocity(0, 1.0).build()?;
//! let rec = Recorder::new()
//!     .region("front", 0, 19)
//!     .snapshots(&[Field::Velocity], 0..200, [16, 32])
//!     // Stop once the energy left in the first 20 grains is below 1 % of its peak.
//!     .stop_below("front", 0.01)
//!     .record(&mut sim)?;
//! let front = rec.region("front").unwrap();
//! assert!(!rec.finished && front.energy.last().unwrap() < &(0.01 * 0.5));
//! assert_eq!(rec.time.len(), front.energy.len());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use crate::observables::{region_energy, region_momentum, Field, Totals};
use crate::run::{ControlFlow, Frame, RunError, Simulation};
use std::ops::Range;

/// What to record (a builder).
#[derive(Clone, Debug, Default)]
pub struct Recorder {
    regions: Vec<(String, usize, usize)>,
    snapshots: Option<(Vec<Field>, Range<usize>, Vec<u64>)>,
    probes: Vec<(Field, usize)>,
    stop: Option<(String, f64)>,
}

/// Energy and momentum of one region at every recorded output.
#[derive(Clone, Debug, PartialEq)]
pub struct RegionSeries {
    pub name: String,
    /// Internal grain indices, inclusive.
    pub first: usize,
    pub last: usize,
    pub energy: Vec<f64>,
    pub momentum: Vec<f64>,
}

/// One snapshot: `values[f][g]` is field `f` (in the order asked for) of the `g`-th grain of the
/// range.
#[derive(Clone, Debug, PartialEq)]
pub struct SnapshotRecord {
    pub index: u64,
    pub time: f64,
    pub values: Vec<Vec<f64>>,
}

/// One field of one grain at every recorded output.
#[derive(Clone, Debug, PartialEq)]
pub struct ProbeSeries {
    /// The field.
    pub field: Field,
    /// Internal grain index.
    pub grain: usize,
    /// The value at every recorded output.
    pub values: Vec<f64>,
}

/// What a recorded run produced.
#[derive(Clone, Debug, PartialEq)]
pub struct Record {
    /// Time of every recorded output (index k at `time[k]`, from t = 0).
    pub time: Vec<f64>,
    /// Totals (energies and momentum) at every output.
    pub totals: Vec<Totals>,
    pub regions: Vec<RegionSeries>,
    pub snapshots: Vec<SnapshotRecord>,
    /// The grains of the snapshots (internal indices) and their fields.
    pub snapshot_grains: Range<usize>,
    pub snapshot_fields: Vec<Field>,
    /// The probes, in the order asked for.
    pub probes: Vec<ProbeSeries>,
    /// False when the stop rule ended the run early.
    pub finished: bool,
}

impl Record {
    /// A region's series by name.
    pub fn region(&self, name: &str) -> Option<&RegionSeries> {
        self.regions.iter().find(|r| r.name == name)
    }

    /// The series of `field` at `grain`, if it was asked for.
    pub fn probe(&self, field: Field, grain: usize) -> Option<&ProbeSeries> {
        self.probes
            .iter()
            .find(|p| p.field == field && p.grain == grain)
    }
}

impl Recorder {
    pub fn new() -> Self {
        Self::default()
    }

    /// Record the energy and momentum of grains `first..=last` (internal indices) as `name`.
    pub fn region(mut self, name: impl Into<String>, first: usize, last: usize) -> Self {
        self.regions.push((name.into(), first, last));
        self
    }

    /// Record `fields` of `grains` at the output indices `at`.
    pub fn snapshots(
        mut self,
        fields: &[Field],
        grains: Range<usize>,
        at: impl IntoIterator<Item = u64>,
    ) -> Self {
        self.snapshots = Some((fields.to_vec(), grains, at.into_iter().collect()));
        self
    }

    /// Record `field` of each of `grains` (internal indices) at every output: a few grains'
    /// time series without snapshots of the grains between them.
    pub fn probes(mut self, field: Field, grains: impl IntoIterator<Item = usize>) -> Self {
        self.probes.extend(grains.into_iter().map(|g| (field, g)));
        self
    }

    /// Stop the run once the energy of region `name` has fallen below `fraction` of the largest
    /// value it has had (after it has been positive).
    pub fn stop_below(mut self, name: impl Into<String>, fraction: f64) -> Self {
        self.stop = Some((name.into(), fraction));
        self
    }

    /// Run `sim` (to its end or the stop rule) and return what was asked for. Errors: a run
    /// error, or a region or snapshot range outside the chain, or a stop rule naming no region.
    pub fn record(&self, sim: &mut Simulation) -> Result<Record, RunError> {
        self.record_with(sim, |_| {})
    }

    /// [`Recorder::record`], calling `progress` after each output is recorded (for progress bars).
    pub fn record_with(
        &self,
        sim: &mut Simulation,
        mut progress: impl FnMut(&Frame),
    ) -> Result<Record, RunError> {
        let n = sim.chain().len();
        let bad = |m: String| Err(RunError::Settings(m));
        for (name, a, b) in &self.regions {
            if a > b || *b >= n {
                return bad(format!(
                    "recorder: region `{name}` ({a}..={b}) is not inside the chain of {n} grains"
                ));
            }
        }
        let stop = match &self.stop {
            Some((name, f)) => match self.regions.iter().position(|r| &r.0 == name) {
                Some(k) => Some((k, *f)),
                None => return bad(format!("recorder: stop rule names no region `{name}`")),
            },
            None => None,
        };
        let (fields, grains, at) = self.snapshots.clone().unwrap_or((vec![], 0..0, vec![]));
        if grains.end > n {
            return bad(format!(
                "recorder: snapshot grains {grains:?} are not inside the chain of {n} grains"
            ));
        }
        if let Some((_, g)) = self.probes.iter().find(|(_, g)| *g >= n) {
            return bad(format!(
                "recorder: probe grain {g} is not inside the chain of {n} grains"
            ));
        }
        let mut rec = Record {
            time: vec![],
            totals: vec![],
            regions: self
                .regions
                .iter()
                .map(|(name, a, b)| RegionSeries {
                    name: name.clone(),
                    first: *a,
                    last: *b,
                    energy: vec![],
                    momentum: vec![],
                })
                .collect(),
            snapshots: vec![],
            snapshot_grains: grains.clone(),
            snapshot_fields: fields.clone(),
            probes: self
                .probes
                .iter()
                .map(|&(field, grain)| ProbeSeries {
                    field,
                    grain,
                    values: vec![],
                })
                .collect(),
            finished: false,
        };
        let mut peak = 0.0f64;
        rec.finished = sim.run_until(|fr: &Frame| {
            rec.time.push(fr.state.t);
            rec.totals.push(fr.totals);
            for r in &mut rec.regions {
                r.energy.push(region_energy(
                    fr.chain, fr.state, fr.window, r.first, r.last,
                ));
                r.momentum.push(region_momentum(
                    fr.chain, fr.state, fr.window, r.first, r.last,
                ));
            }
            for p in &mut rec.probes {
                p.values.push(p.field.value(fr.chain, fr.state, p.grain));
            }
            if at.contains(&fr.index) {
                rec.snapshots.push(SnapshotRecord {
                    index: fr.index,
                    time: fr.state.t,
                    values: fields
                        .iter()
                        .map(|f| {
                            grains
                                .clone()
                                .map(|i| f.value(fr.chain, fr.state, i))
                                .collect()
                        })
                        .collect(),
                });
            }
            progress(fr);
            if let Some((k, fraction)) = stop {
                let e = *rec.regions[k].energy.last().unwrap();
                peak = peak.max(e);
                if peak > 0.0 && e < fraction * peak {
                    return ControlFlow::Break(());
                }
            }
            ControlFlow::Continue(())
        })?;
        Ok(rec)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::chain::{ChainBuilder, ContactLaw};
    use crate::run::SimulationBuilder;

    fn sim() -> Simulation {
        let chain = ChainBuilder::new()
            .grains(50, 1.0, ContactLaw::hertz(5657.0))
            .build()
            .unwrap();
        SimulationBuilder::new(chain)
            .schedule(1.0, 0.25)
            .velocity(0, 1.0)
            .build()
            .unwrap()
    }

    #[test]
    fn records_what_was_asked_and_the_callback_would_see() {
        let rec = Recorder::new()
            .region("all", 0, 49)
            .snapshots(&[Field::Velocity, Field::Mass], 0..3, [0, 4])
            .probes(Field::Velocity, [0, 2])
            .record(&mut sim())
            .unwrap();
        assert!(rec.finished);
        assert_eq!(rec.time, vec![0.0, 0.25, 0.5, 0.75, 1.0]);
        // A free chain: the region of all grains holds the total energy and momentum.
        let all = rec.region("all").unwrap();
        for (k, t) in rec.totals.iter().enumerate() {
            // Summed in a different order (grain by grain against kinetic + potential): equal to
            // round-off of 50 terms.
            approx::assert_relative_eq!(all.energy[k], t.total, max_relative = 1e-14);
            assert_eq!(all.momentum[k], t.momentum);
        }
        assert_eq!(rec.snapshots.len(), 2);
        assert_eq!(rec.snapshots[0].values[0], vec![1.0, 0.0, 0.0]);
        assert_eq!(rec.snapshots[1].values[1], vec![1.0, 1.0, 1.0]);
        // Probes: the same values as the snapshots, at every output.
        let v0 = &rec.probe(Field::Velocity, 0).unwrap().values;
        assert_eq!(v0.len(), 5);
        assert_eq!(v0[0], rec.snapshots[0].values[0][0]);
        assert_eq!(v0[4], rec.snapshots[1].values[0][0]);
        assert!(rec.probe(Field::Velocity, 1).is_none());
    }

    #[test]
    fn bad_requests_are_errors() {
        let e = Recorder::new().region("x", 10, 60).record(&mut sim());
        assert!(matches!(e, Err(RunError::Settings(m)) if m.contains("region `x`")));
        let e = Recorder::new().stop_below("y", 0.1).record(&mut sim());
        assert!(matches!(e, Err(RunError::Settings(m)) if m.contains("no region `y`")));
        let e = Recorder::new()
            .snapshots(&[Field::Velocity], 0..51, [1])
            .record(&mut sim());
        assert!(matches!(e, Err(RunError::Settings(_))));
        let e = Recorder::new()
            .probes(Field::Velocity, [50])
            .record(&mut sim());
        assert!(matches!(e, Err(RunError::Settings(m)) if m.contains("probe grain 50")));
    }
}
