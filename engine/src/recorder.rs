//! Recording a run without writing a callback: ask for time series (totals, region energies and
//! momenta by region name, fields of single grains) and snapshots (fields, grains, output indices), optionally a level at
//! which to stop, and get typed results back.
//!
//! ```
//! use grainchain_engine::Field;
//! use grainchain_engine::Recorder;
//! use grainchain_engine::{ChainBuilder, ContactLaw, SimulationBuilder};
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
//!
//! Two forms share one recorder. [`Recorder::record`] keeps everything in memory (a [`Record`]);
//! [`Recorder::stream`] hands each time-series row, snapshot, pulse detection and ended pulse
//! track to a [`Sink`] as it is produced, so a long run needs no memory for what it writes
//! (`grainchain run` writes its CSV files that way). [`Record`] is itself a [`Sink`]. The
//! recorder decides what is computed; a sink only stores or formats it.

use crate::chain::Chain;
use crate::observables::Schedule;
use crate::observables::{
    detect_pulses, grain_energies, region_energy_with, region_momentum, Field, Pulse, PulseRule,
    Totals, Track, TrackRule, Tracker,
};
use crate::run::{ControlFlow, Frame, RunError, Simulation};
use std::ops::Range;

/// The grains of a region: internal indices, or sections of the chain by name.
#[derive(Clone, Debug)]
enum Grains {
    Indices(usize, usize),
    Sections(String, String),
}

/// What to record (a builder).
#[derive(Clone, Debug)]
pub struct Recorder {
    regions: Vec<(String, Grains)>,
    /// Regions recorded but not protected from the causal horizon.
    unprotected: Vec<String>,
    /// Regions recorded only at the outputs of their schedule (NaN at the others).
    sampled: Vec<(String, Schedule)>,
    snapshots: Option<(Vec<Field>, Range<usize>, Schedule)>,
    probes: Vec<(Field, usize)>,
    stop: Option<(String, f64)>,
    series: bool,
    pulses: Option<(PulseRule, Schedule)>,
    tracks: Option<(PulseRule, TrackRule, u64)>,
}

impl Default for Recorder {
    fn default() -> Self {
        Recorder {
            regions: Vec::new(),
            unprotected: Vec::new(),
            sampled: Vec::new(),
            snapshots: None,
            probes: Vec::new(),
            stop: None,
            series: true,
            pulses: None,
            tracks: None,
        }
    }
}

/// Energy and momentum of one region at every recorded output.
#[derive(Clone, Debug, PartialEq)]
pub struct RegionSeries {
    /// The region's name, as given to [`Recorder::region`] or [`Recorder::sections`].
    pub name: String,
    /// Internal grain indices, inclusive.
    pub first: usize,
    /// Internal index of the region's last grain (inclusive).
    pub last: usize,
    /// Energy of the region's grains (kinetic plus their shares of the contact potentials, as in
    /// `observables`), in the scene's units: `energy[k]` is at [`Record::time`]`[k]`
    /// (NaN at the outputs a sampled region skips: [`Recorder::region_sampled`]).
    pub energy: Vec<f64>,
    /// Momentum (sum of `m v`) of the region's grains, aligned with `energy`.
    pub momentum: Vec<f64>,
    /// Energy the region's grains have lost to contact damping so far, aligned with `energy`
    /// (empty for a chain without damped contacts).
    pub dissipated: Vec<f64>,
}

/// One snapshot: `values[f][g]` is field `f` (in the order asked for) of the `g`-th grain of the
/// range.
#[derive(Clone, Debug, PartialEq)]
pub struct SnapshotRecord {
    /// Output index: the state at `index * interval` (0 is the initial state).
    pub index: u64,
    /// Simulated time of the snapshot.
    pub time: f64,
    /// `values[f][g]`: field [`Record::snapshot_fields`]`[f]` of grain
    /// `Record::snapshot_grains.start + g` (internal index).
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

/// The pulses of one detection. Grain indices and positions of `pulses` count from `origin`
/// (internal index): grain `origin + p.first` is the first grain of pulse `p`.
#[derive(Clone, Debug, PartialEq)]
pub struct PulseRecord {
    /// Output index of the detection (0 is the initial state, k is t = k * interval).
    pub index: u64,
    /// Simulated time of the detection.
    pub time: f64,
    /// Internal index of the first grain searched (the first grain ever touched): the pulses'
    /// grain indices and positions are offsets from it.
    pub origin: usize,
    /// The pulses found, left to right (offsets from `origin`).
    pub pulses: Vec<Pulse>,
}

/// What a recorded run produced.
#[derive(Clone, Debug, PartialEq)]
pub struct Record {
    /// Time of every recorded output (index k at `time[k]`, from t = 0).
    pub time: Vec<f64>,
    /// Totals (energies and momentum) at every output.
    pub totals: Vec<Totals>,
    /// Energy dissipated by contact damping in the whole chain at every output (empty for a
    /// chain without damped contacts): `totals[k].total + dissipated[k]` is the initial energy to
    /// the integrator's error (with what the sleep rule, absorbing layers and the horizon took).
    pub dissipated: Vec<f64>,
    /// The regions' series, in the order the regions were asked for (empty series when the
    /// time series was switched off).
    pub regions: Vec<RegionSeries>,
    /// The snapshots, in output order.
    pub snapshots: Vec<SnapshotRecord>,
    /// The grains of the snapshots (internal indices) and their fields.
    pub snapshot_grains: Range<usize>,
    /// The fields of the snapshots, in the order of [`SnapshotRecord::values`].
    pub snapshot_fields: Vec<Field>,
    /// The probes, in the order asked for.
    pub probes: Vec<ProbeSeries>,
    /// The pulse detections asked for with [`Recorder::pulses`].
    pub pulses: Vec<PulseRecord>,
    /// The pulse tracks asked for with [`Recorder::tracks`], in the order they ended (at the
    /// end of the run: by id). Grain indices are internal.
    pub tracks: Vec<Track>,
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

/// One time-series row: totals and the regions' energies and momenta (in the order the regions
/// were asked for) at one output.
#[derive(Clone, Copy, Debug)]
pub struct Row<'a> {
    /// Output index (0 is the initial state, k is t = k * interval).
    pub index: u64,
    /// Simulated time of the output.
    pub time: f64,
    /// Kinetic, potential and total energy and momentum of the whole chain.
    pub totals: Totals,
    /// Energy of each region, in the order of the names handed to [`Sink::start`].
    pub region_energy: &'a [f64],
    /// Momentum of each region, in the same order.
    pub region_momentum: &'a [f64],
    /// Energy dissipated by contact damping so far in the whole chain (`None`: no damped
    /// contacts).
    pub dissipated: Option<f64>,
    /// Energy each region's grains have lost to contact damping so far (empty: no damped
    /// contacts).
    pub region_dissipated: &'a [f64],
    /// The probes' values (in the order asked for with [`Recorder::probes`]).
    pub probes: &'a [f64],
    /// The watched load ([`crate::Simulation::watch_load`]), if any.
    pub load: Option<crate::LoadSample>,
}

impl Row<'_> {
    /// The columns of `energies.csv` for rows like this one, with `regions` the names handed
    /// to [`Sink::start`]: `index,time,kinetic,potential,total,momentum`, then `dissipated`
    /// with contact damping, `E_<region>` and `P_<region>` for each region, `D_<region>` with
    /// damping, and `load,load_peak,load_impulse` with a watched load. (`grainchain run` and
    /// the Python `run` write the same table.)
    pub fn columns(&self, regions: &[String]) -> Vec<String> {
        let mut h: Vec<String> = ["index", "time", "kinetic", "potential", "total", "momentum"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        if self.dissipated.is_some() {
            h.push("dissipated".into());
        }
        h.extend(regions.iter().map(|r| format!("E_{r}")));
        h.extend(regions.iter().map(|r| format!("P_{r}")));
        if self.dissipated.is_some() {
            h.extend(regions.iter().map(|r| format!("D_{r}")));
        }
        if self.load.is_some() {
            h.extend(["load", "load_peak", "load_impulse"].map(String::from));
        }
        h
    }

    /// This row's values in the order of [`Row::columns`], appended to `out`.
    pub fn values(&self, out: &mut Vec<f64>) {
        let t = self.totals;
        out.extend([
            self.index as f64,
            self.time,
            t.kinetic,
            t.potential,
            t.total,
            t.momentum,
        ]);
        out.extend(self.dissipated);
        out.extend(self.region_energy);
        out.extend(self.region_momentum);
        out.extend(self.region_dissipated);
        if let Some(l) = self.load {
            out.extend([l.force, l.peak, l.impulse]);
        }
    }
}

/// One snapshot as it is taken: `values[f][g]` is field `fields[f]` of grain `grains.start + g`
/// (internal index; `chain.grain_number` gives the printed number).
#[derive(Clone, Debug)]
pub struct Snapshot<'a> {
    /// Output index (0 is the initial state, k is t = k * interval).
    pub index: u64,
    /// Simulated time of the snapshot.
    pub time: f64,
    /// The chain, for printed grain numbers and masses.
    pub chain: &'a Chain,
    /// Internal indices of the grains recorded.
    pub grains: Range<usize>,
    /// The fields recorded, in the order of `values`.
    pub fields: &'a [Field],
    /// `values[f][g]`: field `fields[f]` of grain `grains.start + g`.
    pub values: &'a [Vec<f64>],
}

/// The pulses of one detection as they are found; indices count from `origin` as in
/// [`PulseRecord`].
#[derive(Clone, Copy, Debug)]
pub struct Pulses<'a> {
    /// Output index of the detection (0 is the initial state, k is t = k * interval).
    pub index: u64,
    /// Simulated time of the detection.
    pub time: f64,
    /// The chain, for printed grain numbers.
    pub chain: &'a Chain,
    /// Internal index of the first grain searched (the first grain ever touched): the pulses'
    /// grain indices and positions are offsets from it.
    pub origin: usize,
    /// The pulses found, left to right (offsets from `origin`).
    pub pulses: &'a [Pulse],
}

/// Receives what a [`Recorder`] produces, as it is produced ([`Recorder::stream`]). Every method
/// but `row` has a default that ignores its input; an error stops the run and is returned.
pub trait Sink {
    /// The error a sink can fail with (a run error must convert into it).
    type Error: From<RunError>;
    /// The names of the regions, once, before the first row.
    fn start(&mut self, _regions: &[String]) -> Result<(), Self::Error> {
        Ok(())
    }
    /// A time-series row, at every output (unless switched off with [`Recorder::time_series`]).
    fn row(&mut self, row: &Row<'_>) -> Result<(), Self::Error>;
    /// A snapshot, at the outputs its schedule names.
    fn snapshot(&mut self, _snap: &Snapshot<'_>) -> Result<(), Self::Error> {
        Ok(())
    }
    /// A pulse detection, at the outputs its schedule names.
    fn pulses(&mut self, _pulses: &Pulses<'_>) -> Result<(), Self::Error> {
        Ok(())
    }
    /// A pulse track that has ended (its pulse was not found at a detection, or the run ended).
    fn track(&mut self, _track: &Track, _chain: &Chain) -> Result<(), Self::Error> {
        Ok(())
    }
    /// Called after everything of one output was handed over (for progress bars).
    fn output_done(&mut self, _frame: &Frame) -> Result<(), Self::Error> {
        Ok(())
    }
}

impl Sink for Record {
    type Error = RunError;
    fn row(&mut self, row: &Row<'_>) -> Result<(), RunError> {
        self.time.push(row.time);
        self.totals.push(row.totals);
        self.dissipated.extend(row.dissipated);
        for (k, r) in self.regions.iter_mut().enumerate() {
            r.energy.push(row.region_energy[k]);
            r.momentum.push(row.region_momentum[k]);
            if let Some(&d) = row.region_dissipated.get(k) {
                r.dissipated.push(d);
            }
        }
        for (p, &x) in self.probes.iter_mut().zip(row.probes) {
            p.values.push(x);
        }
        Ok(())
    }
    fn snapshot(&mut self, snap: &Snapshot<'_>) -> Result<(), RunError> {
        self.snapshots.push(SnapshotRecord {
            index: snap.index,
            time: snap.time,
            values: snap.values.to_vec(),
        });
        Ok(())
    }
    fn pulses(&mut self, p: &Pulses<'_>) -> Result<(), RunError> {
        self.pulses.push(PulseRecord {
            index: p.index,
            time: p.time,
            origin: p.origin,
            pulses: p.pulses.to_vec(),
        });
        Ok(())
    }
    fn track(&mut self, track: &Track, _chain: &Chain) -> Result<(), RunError> {
        self.tracks.push(track.clone());
        Ok(())
    }
}

/// A [`Record`] that also reports each output to a progress callback.
struct WithProgress<'a, F>(&'a mut Record, F);

impl<F: FnMut(&Frame)> Sink for WithProgress<'_, F> {
    type Error = RunError;
    fn row(&mut self, row: &Row<'_>) -> Result<(), RunError> {
        self.0.row(row)
    }
    fn snapshot(&mut self, snap: &Snapshot<'_>) -> Result<(), RunError> {
        self.0.snapshot(snap)
    }
    fn pulses(&mut self, p: &Pulses<'_>) -> Result<(), RunError> {
        self.0.pulses(p)
    }
    fn track(&mut self, track: &Track, chain: &Chain) -> Result<(), RunError> {
        self.0.track(track, chain)
    }
    fn output_done(&mut self, frame: &Frame) -> Result<(), RunError> {
        (self.1)(frame);
        Ok(())
    }
}

impl Recorder {
    /// Nothing to record yet (the time series of totals is on by default).
    pub fn new() -> Self {
        Self::default()
    }

    /// Record the energy and momentum of grains `first..=last` (internal indices) as `name`.
    pub fn region(mut self, name: impl Into<String>, first: usize, last: usize) -> Self {
        self.regions
            .push((name.into(), Grains::Indices(first, last)));
        self
    }

    /// Record the energy and momentum of grains `first..=last` as `name` without protecting
    /// them from the causal horizon ([`crate::run::Horizon`]): where the horizon cuts into the
    /// region, its values are those of the chain with the grains beyond the horizon held still
    /// (their kinetic energy when dropped no longer counted), not the long-chain run's. For a
    /// coarse energy budget of long outer sections, which protecting would keep whole.
    pub fn region_unprotected(self, name: impl Into<String>, first: usize, last: usize) -> Self {
        let name = name.into();
        let mut r = self.region(name.clone(), first, last);
        r.unprotected.push(name);
        r
    }

    /// Record the energy and momentum of grains `first..=last` as `name` only at the outputs of
    /// `schedule`, without protecting them from the causal horizon (as
    /// [`Recorder::region_unprotected`]); at the other outputs the region's energy and momentum
    /// are NaN. For the coarse energy budget of long outer sections: computing the energy of tens
    /// of thousands of grains at every output costs more than the run's integration of them.
    pub fn region_sampled(
        self,
        name: impl Into<String>,
        first: usize,
        last: usize,
        schedule: Schedule,
    ) -> Self {
        let name = name.into();
        let mut r = self.region_unprotected(name.clone(), first, last);
        r.sampled.push((name, schedule));
        r
    }

    /// Record the energy and momentum of the chain's section `section`, named after it.
    pub fn section(self, section: &str) -> Self {
        self.sections(section, section, section)
    }

    /// Record the energy and momentum of the grains from the first of section `from` to the last
    /// of section `to` as `name` (e.g. a container from its left wall to its right wall). The
    /// names are looked up when the run starts; an unknown one is an error listing the chain's
    /// sections.
    pub fn sections(mut self, name: impl Into<String>, from: &str, to: &str) -> Self {
        self.regions.push((
            name.into(),
            Grains::Sections(from.to_string(), to.to_string()),
        ));
        self
    }

    /// The regions as internal index ranges of `chain`, checked to lie inside it.
    fn resolve(&self, chain: &Chain) -> Result<Vec<(String, usize, usize)>, RunError> {
        let n = chain.len();
        let mut out = Vec::with_capacity(self.regions.len());
        for (name, g) in &self.regions {
            let (a, b) = match g {
                Grains::Indices(a, b) => (*a, *b),
                Grains::Sections(from, to) => {
                    let r = chain.grains_between(from, to).map_err(|e| {
                        RunError::Settings(format!("recorder: region `{name}`: {e}"))
                    })?;
                    (*r.start(), *r.end())
                }
            };
            if a > b || b >= n {
                return Err(RunError::Settings(format!(
                    "recorder: region `{name}` ({a}..={b}) is not inside the chain of {n} grains"
                )));
            }
            out.push((name.clone(), a, b));
        }
        Ok(out)
    }

    /// Record `fields` of `grains` at the output indices `at`.
    pub fn snapshots(
        self,
        fields: &[Field],
        grains: Range<usize>,
        at: impl IntoIterator<Item = u64>,
    ) -> Self {
        self.snapshots_on(fields, grains, Schedule::At(at.into_iter().collect()))
    }

    /// Record `fields` of `grains` at the outputs of `schedule`.
    pub fn snapshots_on(
        mut self,
        fields: &[Field],
        grains: Range<usize>,
        schedule: Schedule,
    ) -> Self {
        self.snapshots = Some((fields.to_vec(), grains, schedule));
        self
    }

    /// Whether to record the time series (totals and regions) at every output (default: yes).
    /// A stop rule works either way.
    pub fn time_series(mut self, on: bool) -> Self {
        self.series = on;
        self
    }

    /// Detect pulses ([`detect_pulses`], over the grains ever touched) at the outputs of
    /// `schedule`.
    pub fn pulses(mut self, rule: PulseRule, schedule: Schedule) -> Self {
        self.pulses = Some((rule, schedule));
        self
    }

    /// Follow pulses (detected with `rule` at every `every`-th output) from one detection to the
    /// next (`observables::tracking`), with their true peak velocity from the
    /// per-step peak speeds ([`Simulation::watch_peak_speeds`]; the run must use verlet,
    /// blanes-moan4 or dopri5).
    pub fn tracks(mut self, rule: PulseRule, track: TrackRule, every: u64) -> Self {
        self.tracks = Some((rule, track, every.max(1)));
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
        progress: impl FnMut(&Frame),
    ) -> Result<Record, RunError> {
        let (fields, grains) = match &self.snapshots {
            Some((f, g, _)) => (f.clone(), g.clone()),
            None => (vec![], 0..0),
        };
        let mut rec = Record {
            time: vec![],
            totals: vec![],
            dissipated: vec![],
            regions: self
                .resolve(sim.chain())?
                .iter()
                .map(|(name, a, b)| RegionSeries {
                    name: name.clone(),
                    first: *a,
                    last: *b,
                    energy: vec![],
                    momentum: vec![],
                    dissipated: vec![],
                })
                .collect(),
            snapshots: vec![],
            snapshot_grains: grains,
            snapshot_fields: fields,
            probes: self
                .probes
                .iter()
                .map(|&(field, grain)| ProbeSeries {
                    field,
                    grain,
                    values: vec![],
                })
                .collect(),
            pulses: vec![],
            tracks: vec![],
            finished: false,
        };
        rec.finished = self.stream(sim, &mut WithProgress(&mut rec, progress))?;
        Ok(rec)
    }

    /// Run `sim` (to its end or the stop rule), handing what was asked for to `sink` as it is
    /// produced. Returns whether the run reached its end. Errors: those of
    /// [`Recorder::record`], a method without per-step velocities when tracks are asked for, and
    /// the sink's own.
    pub fn stream<S: Sink>(&self, sim: &mut Simulation, sink: &mut S) -> Result<bool, S::Error> {
        let mut pass = Pass::new(self, sim)?;
        sink.start(&pass.names())?;
        let mut failed = None;
        let finished = sim.run_until(|fr: &Frame| match pass.output(fr, sink) {
            Ok(c) => c,
            Err(e) => {
                failed = Some(e);
                ControlFlow::Break(())
            }
        })?;
        if let Some(e) = failed {
            return Err(e);
        }
        if let Some(tracker) = pass.tracker.as_mut() {
            for tr in tracker.finish() {
                sink.track(&tr, sim.chain())?;
            }
        }
        Ok(finished)
    }
}

/// One recorded run: the recorder's requests checked against the chain, and the buffers reused
/// at every output (nothing is allocated per output once they have grown).
struct Pass<'r> {
    rec: &'r Recorder,
    /// Regions as internal index ranges, in the order asked for.
    regions: Vec<(String, usize, usize)>,
    /// Per region: the outputs it is recorded at (`None`: every output).
    sampled: Vec<Option<&'r Schedule>>,
    /// The stop rule: region (position in `regions`) and fraction of its peak energy.
    stop: Option<(usize, f64)>,
    energy: Vec<f64>,
    momentum: Vec<f64>,
    /// Per region: the energy its grains lost to contact damping (empty: none damped).
    dissipated: Vec<f64>,
    probes: Vec<f64>,
    values: Vec<Vec<f64>>,
    e_buf: Vec<f64>,
    v_buf: Vec<f64>,
    tracker: Option<Tracker>,
    /// Per-grain peak speed since the grain was last outside every pulse at a tracking
    /// detection.
    peaks: Vec<f64>,
    /// Tracks ended at the last detection (handed to the sink at once).
    ended: Vec<Track>,
    /// Largest energy of the stop region so far.
    peak: f64,
}

impl<'r> Pass<'r> {
    fn new(rec: &'r Recorder, sim: &mut Simulation) -> Result<Pass<'r>, RunError> {
        let n = sim.chain().len();
        let bad = |m: String| Err(RunError::Settings(m));
        let regions = rec.resolve(sim.chain())?;
        let sampled: Vec<Option<&Schedule>> = regions
            .iter()
            .map(|(name, _, _)| rec.sampled.iter().find(|s| &s.0 == name).map(|s| &s.1))
            .collect();
        let stop = match &rec.stop {
            Some((name, _)) if rec.sampled.iter().any(|s| &s.0 == name) => {
                return bad(format!(
                    "recorder: the stop rule's region `{name}` is sampled, not recorded at every output"
                ))
            }
            Some((name, f)) => match regions.iter().position(|r| &r.0 == name) {
                Some(k) => Some((k, *f)),
                None => return bad(format!("recorder: stop rule names no region `{name}`")),
            },
            None => None,
        };
        if let Some((_, g)) = rec.probes.iter().find(|(_, g)| *g >= n) {
            return bad(format!(
                "recorder: probe grain {g} is not inside the chain of {n} grains"
            ));
        }
        if let Some((_, grains, _)) = &rec.snapshots {
            if grains.end > n {
                return bad(format!(
                    "recorder: snapshot grains {grains:?} are not inside the chain of {n} grains"
                ));
            }
        }
        // The causal horizon (if the run has one) keeps what is recorded exact: every region
        // and probe to the end, a snapshot range to its last snapshot, the whole chain while
        // pulses are detected (they look at every grain ever touched).
        let end = sim.outputs();
        for (name, a, b) in &regions {
            if !rec.unprotected.contains(name) {
                sim.protect(*a, *b, end);
            }
        }
        for &(_, g) in &rec.probes {
            sim.protect(g, g, end);
        }
        if let Some((_, grains, schedule)) = &rec.snapshots {
            if let Some(last) = schedule.last(end) {
                if !grains.is_empty() {
                    sim.protect(grains.start, grains.end - 1, last);
                }
            }
        }
        if let Some((_, schedule)) = &rec.pulses {
            if let Some(last) = schedule.last(end) {
                sim.protect(0, n - 1, last);
            }
        }
        if rec.tracks.is_some() {
            sim.protect(0, n - 1, end);
        }
        let tracker = match &rec.tracks {
            Some((_, rule, _)) => {
                sim.watch_peak_speeds()?;
                Some(Tracker::new(*rule))
            }
            None => None,
        };
        let r = regions.len();
        Ok(Pass {
            rec,
            stop,
            energy: vec![0.0; r],
            momentum: vec![0.0; r],
            dissipated: Vec::new(),
            probes: vec![0.0; rec.probes.len()],
            values: Vec::new(),
            e_buf: Vec::new(),
            v_buf: Vec::new(),
            peaks: vec![0.0; if tracker.is_some() { n } else { 0 }],
            tracker,
            ended: Vec::new(),
            peak: 0.0,
            regions,
            sampled,
        })
    }

    fn names(&self) -> Vec<String> {
        self.regions.iter().map(|r| r.0.clone()).collect()
    }

    /// Everything asked for at one output, then the stop rule.
    fn output<S: Sink>(&mut self, fr: &Frame, sink: &mut S) -> Result<ControlFlow<()>, S::Error> {
        self.series(fr, sink)?;
        self.snapshot(fr, sink)?;
        self.pulses(fr, sink)?;
        self.tracks(fr, sink)?;
        sink.output_done(fr)?;
        if let Some((k, fraction)) = self.stop {
            let e = self.energy[k];
            self.peak = self.peak.max(e);
            if self.peak > 0.0 && e < fraction * self.peak {
                return Ok(ControlFlow::Break(()));
            }
        }
        Ok(ControlFlow::Continue(()))
    }

    /// The time-series row (region energies are computed for the stop rule even without it).
    fn series<S: Sink>(&mut self, fr: &Frame, sink: &mut S) -> Result<(), S::Error> {
        let chain = fr.chain;
        if self.rec.series || self.stop.is_some() {
            for (k, (_, a, b)) in self.regions.iter().enumerate() {
                if self.sampled[k].is_some_and(|s| !s.wants(fr.index)) {
                    (self.energy[k], self.momentum[k]) = (f64::NAN, f64::NAN);
                    continue;
                }
                self.energy[k] =
                    region_energy_with(chain, fr.state, fr.window, (*a, *b), &mut self.e_buf);
                self.momentum[k] = region_momentum(chain, fr.state, fr.window, *a, *b);
            }
        }
        if self.rec.series {
            for (x, (field, g)) in self.probes.iter_mut().zip(&self.rec.probes) {
                *x = field.value(chain, fr.state, *g);
            }
            // Contact damping: what each region's grains and the whole chain lost so far.
            // (Grains never touched lost nothing: only the envelope is summed.)
            let lost = &fr.state.dissipated;
            let ever = fr.window.ever();
            let dissipated = (!lost.is_empty()).then(|| lost[ever.clone()].iter().sum::<f64>());
            self.dissipated.clear();
            if !lost.is_empty() {
                self.dissipated.extend(self.regions.iter().map(|(_, a, b)| {
                    let (lo, hi) = ((*a).max(ever.start), (*b + 1).min(ever.end));
                    if lo < hi {
                        lost[lo..hi].iter().sum::<f64>()
                    } else {
                        0.0
                    }
                }));
            }
            sink.row(&Row {
                index: fr.index,
                time: fr.state.t,
                totals: fr.totals,
                dissipated,
                region_dissipated: &self.dissipated,
                region_energy: &self.energy,
                region_momentum: &self.momentum,
                probes: &self.probes,
                load: fr.load,
            })?;
        }
        Ok(())
    }

    fn snapshot<S: Sink>(&mut self, fr: &Frame, sink: &mut S) -> Result<(), S::Error> {
        let Some((fields, grains, schedule)) = &self.rec.snapshots else {
            return Ok(());
        };
        if !schedule.wants(fr.index) {
            return Ok(());
        }
        self.values.resize_with(fields.len(), Vec::new);
        for (f, out) in fields.iter().zip(self.values.iter_mut()) {
            out.clear();
            out.extend(grains.clone().map(|i| f.value(fr.chain, fr.state, i)));
        }
        sink.snapshot(&Snapshot {
            index: fr.index,
            time: fr.state.t,
            chain: fr.chain,
            grains: grains.clone(),
            fields,
            values: &self.values,
        })
    }

    /// Pulses of the grains ever touched, indexed from the first of them (returned).
    fn detect(&mut self, fr: &Frame, rule: &PulseRule) -> (usize, Vec<Pulse>) {
        let r = fr.window.ever();
        grain_energies(fr.chain, fr.state, r.clone(), &mut self.e_buf);
        self.v_buf.clear();
        self.v_buf.extend_from_slice(&fr.state.v[r.clone()]);
        (r.start, detect_pulses(&self.e_buf, &self.v_buf, rule))
    }

    fn pulses<S: Sink>(&mut self, fr: &Frame, sink: &mut S) -> Result<(), S::Error> {
        let Some((rule, schedule)) = &self.rec.pulses else {
            return Ok(());
        };
        if !schedule.wants(fr.index) {
            return Ok(());
        }
        let (origin, pulses) = self.detect(fr, rule);
        sink.pulses(&Pulses {
            index: fr.index,
            time: fr.state.t,
            chain: fr.chain,
            origin,
            pulses: &pulses,
        })
    }

    fn tracks<S: Sink>(&mut self, fr: &Frame, sink: &mut S) -> Result<(), S::Error> {
        let (Some(_), Some((rule, _, every))) = (&self.tracker, &self.rec.tracks) else {
            return Ok(());
        };
        let r = fr.window.ever();
        if let Some(p) = fr.peak_speed {
            for i in r.clone() {
                self.peaks[i] = self.peaks[i].max(p[i]);
            }
        }
        if !fr.index.is_multiple_of(*every) {
            return Ok(());
        }
        let (origin, mut pulses) = self.detect(fr, rule);
        for p in &mut pulses {
            p.first += origin;
            p.last += origin;
            p.position += origin as f64;
        }
        if let Some(tracker) = self.tracker.as_mut() {
            tracker.push(fr.index, fr.state.t, &pulses, &self.peaks, &mut self.ended);
        }
        for tr in self.ended.drain(..) {
            sink.track(&tr, fr.chain)?;
        }
        // A grain keeps its peak while a pulse covers it (a slow pulse takes several detections
        // to pass a grain); outside every pulse it starts again.
        let mut covered = pulses.iter().map(|p| p.first..p.last + 1).peekable();
        for i in r {
            while covered.peek().is_some_and(|c| c.end <= i) {
                covered.next();
            }
            if !covered.peek().is_some_and(|c| c.contains(&i)) {
                self.peaks[i] = 0.0;
            }
        }
        Ok(())
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

    /// A sampled region holds the full region's numbers at its outputs and NaN at the others;
    /// it cannot be the stop rule's region.
    #[test]
    fn sampled_region() {
        let rec = Recorder::new()
            .region("all", 0, 2)
            .region_sampled("some", 0, 2, Schedule::At(vec![0, 3]))
            .record(&mut sim())
            .unwrap();
        let (all, some) = (rec.region("all").unwrap(), rec.region("some").unwrap());
        assert_eq!(some.energy.len(), all.energy.len());
        for k in 0..all.energy.len() {
            if k == 0 || k == 3 {
                assert_eq!(some.energy[k], all.energy[k]);
                assert_eq!(some.momentum[k], all.momentum[k]);
            } else {
                assert!(some.energy[k].is_nan() && some.momentum[k].is_nan());
            }
        }
        let err = Recorder::new()
            .region_sampled("some", 0, 2, Schedule::Every(2))
            .stop_below("some", 0.5)
            .record(&mut sim())
            .unwrap_err();
        assert!(err.to_string().contains("`some` is sampled"), "{err}");
    }

    #[test]
    fn regions_by_section_name() {
        let law = ContactLaw::hertz(5657.0);
        let chain = ChainBuilder::new()
            .section(crate::Section::new("left", 10, 1.0, law))
            .section(crate::Section::new("middle", 5, 0.5, law))
            .section(crate::Section::new("right", 10, 1.0, law))
            .build()
            .unwrap();
        let mut sim = SimulationBuilder::new(chain)
            .schedule(0.5, 0.25)
            .velocity(0, 1.0)
            .build()
            .unwrap();
        let rec = Recorder::new()
            .section("middle")
            .sections("all", "left", "right")
            .region("by-index", 10, 14)
            .record(&mut sim)
            .unwrap();
        let (m, all) = (rec.region("middle").unwrap(), rec.region("all").unwrap());
        assert_eq!((m.first, m.last), (10, 14));
        assert_eq!((all.first, all.last), (0, 24));
        assert_eq!(m.energy, rec.region("by-index").unwrap().energy);
        let e = Recorder::new()
            .sections("c", "left", "walls")
            .record(&mut sim)
            .unwrap_err();
        assert!(
            matches!(&e, RunError::Settings(m) if m.contains("region `c`: no section named `walls` (sections: left, middle, right)")),
            "{e}"
        );
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
