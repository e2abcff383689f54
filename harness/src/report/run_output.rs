//! What `grainchain run` writes: `energies.csv`, `snapshots.csv` (long format), `pulses.csv` and
//! `summary.json`, each only if the scene asks for it, all committed together at the end.
//!
//! Everything is recorded by the shared [`Recorder`] ([`scene_recorder`] turns the scene's
//! `[output]` into one) and streamed into the files by a [`Sink`] as it is produced (to temporary
//! files), so memory stays flat however long the run. `tracks.csv` gets a track's rows when the
//! track ends.

use super::AtomicFile;
// Every number in the one CSV form (CONTRIBUTING.md, "CSV conventions").
use super::CsvNumber as num;
use crate::error::Error;
use crate::report::limits::{LimitWords, Refusal};
use grainchain_engine::Chain;
use grainchain_engine::InputError;
use grainchain_engine::Scene;
use grainchain_engine::{self, Track};
use grainchain_engine::{Frame, Simulation};
use grainchain_engine::{Pulses, Recorder, Row, Sink, Snapshot};
use serde::Serialize;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The summary of a finished run.
#[derive(Debug, Serialize)]
pub struct Summary {
    /// The scene's name.
    pub scene: String,
    /// The integration method (`verlet`, `blanes-moan4`, `gear5`, `dopri5`, `multirate`).
    pub method: &'static str,
    /// The step taken (fixed-step methods: shortened so a whole number fits each output interval).
    pub dt: f64,
    /// The step the scene asked for.
    pub requested_dt: f64,
    /// Grains in the chain, a striker included.
    pub grains: usize,
    /// Simulated time reached: the time of the last output.
    pub duration: f64,
    /// Output times after t = 0.
    pub outputs: u64,
    /// Accepted steps.
    pub steps: u64,
    /// Rejected steps (adaptive methods; 0 otherwise).
    pub rejected_steps: u64,
    /// Force evaluations (each over the active window).
    pub force_evaluations: u64,
    /// Grains evaluated, summed over the force evaluations: the work done.
    pub grain_evaluations: u64,
    /// Fraction of grain-evaluations skipped compared with integrating every grain (grain-steps
    /// saved, by skipping untouched grains and grains at rest between islands).
    pub skipped_fraction: f64,
    /// Grains never reached by any disturbance.
    pub grains_untouched: usize,
    /// Largest number of grains integrated at once (summed over islands).
    pub max_window: usize,
    /// Mean number of grains integrated per force evaluation (summed over islands, margins not
    /// counted, as in `max_window`; the work with the margins is `grain_evaluations`).
    pub mean_window: f64,
    /// Islands at the end of the run.
    pub islands: usize,
    /// Grains taken out of the islands at output times (at rest, or put to rest by the sleep
    /// rule), counted each time.
    pub slept_grains: u64,
    /// Kinetic energy removed by the sleep rule, relative to the initial energy.
    pub slept_energy_relative: f64,
    /// Energy taken out by damped sections (absorbing layers), relative to the initial energy.
    pub absorbed_energy_relative: f64,
    /// The causal horizon's speed (grains per time unit; `run.horizon`), when the run has one.
    pub horizon_speed: Option<f64>,
    /// The horizon's bound ([`grainchain_engine::Horizon::speed_bound`], grains per time unit), when
    /// the run has a horizon and records something it protects.
    pub horizon_bound: Option<f64>,
    /// What the run did that may make its numbers wrong and that the scene allowed explicitly
    /// (a horizon speed below its bound with `run.horizon.unsafe = true`), one sentence each;
    /// empty for a run whose settings are all safe.
    pub warnings: Vec<String>,
    /// Grains dropped from the integration by the causal horizon.
    pub dropped_grains: u64,
    /// Kinetic energy the dropped grains had, relative to the initial energy.
    pub dropped_energy_relative: f64,
    /// Energy dissipated by contact damping, relative to the initial energy (absent without
    /// damped contacts).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dissipated_energy_relative: Option<f64>,
    /// Wall time of the run and of writing its CSV files, in seconds.
    pub wall_time_s: f64,
    /// Wall time per stage of the run loop (integrate, checks, output), in seconds.
    pub timings: grainchain_engine::Timings,
    /// Total energy (kinetic + potential) at t = 0, in the scene's units.
    pub initial_energy: f64,
    /// Largest relative energy error at an output time: energy in the chain plus what damping
    /// and the sleep rule took out, against the initial energy (absolute when that is zero).
    pub max_relative_energy_error: f64,
    /// The same error at the end of the run.
    pub final_relative_energy_error: f64,
    /// Relative to the initial momentum (walls exchange momentum: meaningful for free ends).
    pub max_relative_momentum_error: f64,
    /// Integration wall time per grain evaluation, in nanoseconds (0 when nothing was
    /// evaluated).
    pub ns_per_grain_evaluation: f64,
    /// The load on what the chain protects (its right wall, or the target body), over every
    /// step: true peak and its time, impulse, the time above half the peak, the target's
    /// largest energy ([`grainchain_engine::Load`]); present when the scene has a protected
    /// contact and steps with verlet or blanes-moan4 ([`watch_protected`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub load: Option<grainchain_engine::Load>,
    /// The striker's velocity at the end of the run, in the scene's units, positive to the
    /// right (a left striker that bounced back has a negative one); present when the scene has
    /// a striker.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub striker_rebound: Option<f64>,
    /// The process's peak resident memory when the summary was made, bytes (Linux: `VmHWM` of
    /// `/proc/self/status`, which starts afresh at `exec`, unlike a parent's `wait4` figure,
    /// which carries the parent's own peak when it spawned the run; absent elsewhere).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub peak_resident_bytes: Option<u64>,
}

/// `VmHWM` of `/proc/self/status` in bytes (Linux), else `None`.
fn peak_resident_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// The share of the peak the load's duration counts above, in `summary.json`.
pub const LOAD_FRACTION: f64 = 0.5;

/// Watch the load on the scene's protected contact (`Scene::protected_contact`) when it has
/// one and its method takes whole steps (verlet, blanes-moan4); other scenes are left alone.
pub fn watch_protected(
    scene: &Scene,
    sim: &mut Simulation,
) -> Result<(), grainchain_engine::RunError> {
    let Some(contact) = scene.protected_contact() else {
        return Ok(());
    };
    if !matches!(
        sim.params().method,
        grainchain_engine::Method::Verlet | grainchain_engine::Method::BlanesMoan4
    ) || sim.horizon().is_some()
    {
        return Ok(());
    }
    let target = sim.chain().section("target").is_some();
    sim.watch_load(contact, LOAD_FRACTION, target)
}

impl Summary {
    /// The summary of a finished scene run, as `summary.json` holds it (`grainchain run` and
    /// the Python `run` alike): [`Summary::of`], the load [`watch_protected`] watched, and the
    /// process's peak resident memory.
    pub fn finished(sim: &mut Simulation, scene_name: &str, wall: f64) -> Summary {
        let mut summary = Summary::of(sim, scene_name, wall);
        summary.load = sim.load();
        summary.striker_rebound = sim.chain().striker().map(|(i, _)| sim.state().v[i]);
        summary.peak_resident_bytes = peak_resident_bytes();
        summary
    }

    /// The file form of [`Simulation::summary`], with the scene's name and the wall time.
    pub fn of(sim: &Simulation, scene_name: &str, wall: f64) -> Summary {
        let r = sim.summary();
        let st = &r.stats;
        let n = r.grains;
        // What is in the chain plus what damping, the sleep rule and the horizon took out of it.
        let fin = grainchain_engine::totals(sim.chain(), sim.state(), sim.window()).total
            + st.absorbed_energy
            + st.slept_energy
            + st.dropped_energy
            + st.dissipated_energy;
        let e0 = r.initial_energy;
        let rel = |x: f64| if e0 != 0.0 { x / e0.abs() } else { x };
        Summary {
            scene: scene_name.to_string(),
            method: r.method,
            dt: r.dt,
            requested_dt: r.requested_dt,
            grains: n,
            duration: r.time,
            outputs: r.outputs,
            steps: st.steps,
            rejected_steps: st.rejected,
            force_evaluations: st.force_evals,
            grain_evaluations: st.grain_evals,
            skipped_fraction: st.saved_fraction(n).max(0.0),
            grains_untouched: r.untouched(),
            max_window: st.max_window,
            mean_window: st.mean_window(),
            islands: r.islands,
            slept_grains: st.slept_grains,
            slept_energy_relative: rel(st.slept_energy),
            absorbed_energy_relative: rel(st.absorbed_energy),
            horizon_speed: r.horizon_speed,
            horizon_bound: r.horizon_bound,
            warnings: r.warnings.clone(),
            dropped_grains: st.dropped_grains,
            dropped_energy_relative: rel(st.dropped_energy),
            dissipated_energy_relative: sim
                .chain()
                .has_contact_damping()
                .then(|| rel(st.dissipated_energy)),
            wall_time_s: wall,
            timings: r.timings,
            initial_energy: e0,
            max_relative_energy_error: r.max_energy_error,
            final_relative_energy_error: if e0 != 0.0 {
                ((fin - e0) / e0).abs()
            } else {
                fin.abs()
            },
            max_relative_momentum_error: r.max_momentum_error,
            ns_per_grain_evaluation: if st.grain_evals > 0 {
                r.timings.integrate.as_secs_f64() * 1e9 / st.grain_evals as f64
            } else {
                0.0
            },
            load: None,
            striker_rebound: None,
            peak_resident_bytes: None,
        }
    }
}

fn io(path: &Path) -> impl Fn(std::io::Error) -> Error + '_ {
    move |source| Error::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// The recorder of a scene: its regions (printed grain numbers turned into internal indices),
/// and the time series, snapshots, pulses and tracks its `[output]` asks for.
pub fn scene_recorder(scene: &Scene, chain: &Chain) -> Recorder {
    let idx = |g: i64| chain.index_of(g).expect("scene grain numbers are checked");
    let mut rec = Recorder::new().time_series(scene.output().energies);
    for r in scene.regions() {
        let g = scene.region_grains(&r.name).expect("a region of the scene");
        rec = rec.region(r.name.clone(), *g.start(), *g.end());
    }
    if let Some(s) = &scene.output().snapshots {
        rec = rec.snapshots_on(&s.fields, idx(s.first)..idx(s.last) + 1, s.schedule());
    }
    if let Some(p) = &scene.output().pulses {
        rec = rec.pulses(p.rule, p.schedule());
    }
    if let Some(t) = &scene.output().tracks {
        rec = rec.tracks(t.rule, t.track, t.every);
    }
    rec
}

/// One value of a row of `pulses.csv` or `tracks.csv`: a whole number (an output index, a
/// pulse, track or grain number), written as such, or a real, written as every CSV number is
/// ([`super::CsvNumber`]; NaN is the empty field). Python takes every cell as a float64
/// ([`Cell::value`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Cell {
    /// A whole number.
    Whole(i64),
    /// A real number.
    Real(f64),
}

impl Cell {
    /// The cell as a float64 (a whole number is exact below 2^53).
    pub fn value(self) -> f64 {
        match self {
            Cell::Whole(n) => n as f64,
            Cell::Real(x) => x,
        }
    }
}

impl std::fmt::Display for Cell {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Cell::Whole(n) => write!(f, "{n}"),
            Cell::Real(x) => write!(f, "{}", num(x)),
        }
    }
}

/// The columns of `pulses.csv` (and of Python's `pulses`), in the order of [`pulse_rows`].
pub const PULSE_COLUMNS: [&str; 8] = [
    "index",
    "time",
    "pulse",
    "first",
    "last",
    "position",
    "peak_velocity",
    "energy",
];

/// The rows of [`PULSE_COLUMNS`] for the pulses found at one output: the output's index and
/// time, the pulse's number (from 1), its first and last grain, its position (in printed grain
/// numbers), peak velocity and energy.
pub fn pulse_rows<'a>(p: &'a Pulses<'_>) -> impl Iterator<Item = [Cell; 8]> + 'a {
    let (chain, r0) = (p.chain, p.origin);
    let off = chain.grain_number(r0) as f64;
    p.pulses.iter().enumerate().map(move |(k, q)| {
        [
            Cell::Whole(p.index as i64),
            Cell::Real(p.time),
            Cell::Whole(k as i64 + 1),
            Cell::Whole(chain.grain_number(r0 + q.first)),
            Cell::Whole(chain.grain_number(r0 + q.last)),
            Cell::Real(q.position + off),
            Cell::Real(q.peak_velocity),
            Cell::Real(q.energy),
        ]
    })
}

/// The columns of `tracks.csv` (and of Python's `tracks`), in the order of [`track_rows`].
pub const TRACK_COLUMNS: [&str; 10] = [
    "track",
    "index",
    "time",
    "position",
    "first",
    "last",
    "energy",
    "peak_velocity",
    "instant_peak_velocity",
    "speed",
];

/// The rows of [`TRACK_COLUMNS`] for a finished track, one per point: the track's number, the
/// output's index and time, the position (in printed grain numbers), first and last grain,
/// energy, peak velocities and the track's speed (missing for a track of one point).
pub fn track_rows<'a>(track: &'a Track, chain: &'a Chain) -> impl Iterator<Item = [Cell; 10]> + 'a {
    let speed = track.speed().unwrap_or(f64::NAN);
    let off = chain.grain_number(0) as f64;
    track.points.iter().map(move |p| {
        [
            Cell::Whole(track.id as i64),
            Cell::Whole(p.index as i64),
            Cell::Real(p.time),
            Cell::Real(p.position + off),
            Cell::Whole(chain.grain_number(p.first)),
            Cell::Whole(chain.grain_number(p.last)),
            Cell::Real(p.energy),
            Cell::Real(p.peak_velocity),
            Cell::Real(p.instant_peak_velocity),
            Cell::Real(speed),
        ]
    })
}

/// A row as a CSV line (no line end).
fn csv_line(row: &[Cell]) -> String {
    use std::fmt::Write as _;
    let mut line = String::with_capacity(16 * row.len());
    for (i, c) in row.iter().enumerate() {
        let _ = write!(line, "{}{c}", if i == 0 { "" } else { "," });
    }
    line
}

/// Refuse a scene whose outputs are estimated at more than the engine's limit
/// (`OUTPUT_LIMIT_BYTES`) unless `allow`: the refusal of `grainchain run` and Python's `run`
/// alike, in the caller's `words`.
pub fn output_size_check(
    scene: &Scene,
    path: &Path,
    words: LimitWords,
    allow: bool,
) -> Result<(), InputError> {
    match scene.estimate().refusal(path, words).filter(|_| !allow) {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

/// The CSV files of `grainchain run`, written row by row as the recorder produces them.
struct CsvFiles<P> {
    energies: Option<AtomicFile>,
    snapshots: Option<AtomicFile>,
    pulses: Option<AtomicFile>,
    tracks: Option<AtomicFile>,
    progress: P,
    total: u64,
    /// The regions' names (from `start`) and whether energies.csv has its header yet.
    regions: Vec<String>,
    started: bool,
    /// One row's values (reused).
    values: Vec<f64>,
}

fn header(file: Option<AtomicFile>, text: &str) -> Result<Option<AtomicFile>, Error> {
    match file {
        Some(mut f) => {
            writeln!(f, "{text}").map_err(io(f.path()))?;
            Ok(Some(f))
        }
        None => Ok(None),
    }
}

impl<P: FnMut(u64, u64)> Sink for CsvFiles<P> {
    type Error = Error;

    fn start(&mut self, regions: &[String]) -> Result<(), Error> {
        self.regions = regions.to_vec();
        Ok(())
    }

    fn row(&mut self, row: &Row<'_>) -> Result<(), Error> {
        // The header at the first row, which says which columns there are (`Row::columns`).
        if !std::mem::replace(&mut self.started, true) {
            let h = row.columns(&self.regions).join(",");
            self.energies = header(self.energies.take(), &h)?;
        }
        let Some(f) = self.energies.as_mut() else {
            return Ok(());
        };
        self.values.clear();
        row.values(&mut self.values);
        let mut line = String::with_capacity(24 * self.values.len());
        for (i, x) in self.values.iter().enumerate() {
            use std::fmt::Write as _;
            let _ = write!(line, "{}{}", if i == 0 { "" } else { "," }, num(*x));
        }
        writeln!(f, "{line}").map_err(io(f.path()))
    }

    fn snapshot(&mut self, s: &Snapshot<'_>) -> Result<(), Error> {
        let Some(f) = self.snapshots.as_mut() else {
            return Ok(());
        };
        for (g, i) in s.grains.clone().enumerate() {
            write!(f, "{},{},{}", s.index, num(s.time), s.chain.grain_number(i))
                .map_err(io(f.path()))?;
            for field in s.values {
                write!(f, ",{}", num(field[g])).map_err(io(f.path()))?;
            }
            writeln!(f).map_err(io(f.path()))?;
        }
        Ok(())
    }

    fn pulses(&mut self, p: &Pulses<'_>) -> Result<(), Error> {
        let Some(f) = self.pulses.as_mut() else {
            return Ok(());
        };
        for row in pulse_rows(p) {
            writeln!(f, "{}", csv_line(&row)).map_err(io(f.path()))?;
        }
        Ok(())
    }

    fn track(&mut self, track: &Track, chain: &Chain) -> Result<(), Error> {
        let Some(f) = self.tracks.as_mut() else {
            return Ok(());
        };
        for row in track_rows(track, chain) {
            writeln!(f, "{}", csv_line(&row)).map_err(io(f.path()))?;
        }
        Ok(())
    }

    fn output_done(&mut self, frame: &Frame) -> Result<(), Error> {
        (self.progress)(frame.index, self.total);
        Ok(())
    }
}

/// The files [`run_scene`] writes for `scene`, in its output folder.
pub fn output_files(scene: &Scene) -> Vec<&'static str> {
    let o = &scene.output();
    let mut v = Vec::new();
    for (asked, name) in [
        (o.energies, "energies.csv"),
        (o.snapshots.is_some(), "snapshots.csv"),
        (o.pulses.is_some(), "pulses.csv"),
        (o.tracks.is_some(), "tracks.csv"),
    ] {
        if asked {
            v.push(name);
        }
    }
    v.push("summary.json");
    v
}

/// A scene's run streamed into `sink`, the one way every front end runs a scene (`grainchain run`
/// into CSV files, [`run_scene`]; Python into arrays): the simulation built, the load on its
/// protected contact watched ([`watch_protected`]), the scene's recorder ([`scene_recorder`])
/// streaming into `sink`, and the [`Summary`], made also of a run the sink stopped. The outer
/// error is the engine's (the run could not be built or failed); the inner one is the sink's, with
/// `Ok(finished)` as [`Recorder::stream`] gives it.
#[allow(clippy::type_complexity)]
pub fn stream<S: Sink>(
    scene: &Scene,
    sink: &mut S,
) -> Result<(Result<bool, S::Error>, Summary), grainchain_engine::RunError> {
    let mut sim = scene.simulation()?;
    watch_protected(scene, &mut sim)?;
    let recorder = scene_recorder(scene, sim.chain());
    let start = Instant::now();
    let streamed = recorder.stream(&mut sim, sink);
    let wall = start.elapsed().as_secs_f64();
    Ok((streamed, Summary::finished(&mut sim, scene.name(), wall)))
}

/// Run a scene and write its outputs into `out`. `progress` is called with (done, total) output
/// counts.
pub fn run_scene(
    scene: &Scene,
    out: &Path,
    progress: impl FnMut(u64, u64),
) -> Result<Summary, Error> {
    let file = |asked: bool, name: &str| -> Result<Option<AtomicFile>, Error> {
        Ok(if asked {
            Some(AtomicFile::create(out.join(name))?)
        } else {
            None
        })
    };
    let o = &scene.output();
    let snapshots = match &o.snapshots {
        Some(s) => {
            let names: Vec<&str> = s.fields.iter().map(|x| x.name()).collect();
            header(
                file(true, "snapshots.csv")?,
                &format!("index,time,grain,{}", names.join(",")),
            )?
        }
        None => None,
    };
    let mut files = CsvFiles {
        energies: file(o.energies, "energies.csv")?,
        snapshots,
        pulses: header(
            file(o.pulses.is_some(), "pulses.csv")?,
            &PULSE_COLUMNS.join(","),
        )?,
        tracks: header(
            file(o.tracks.is_some(), "tracks.csv")?,
            &TRACK_COLUMNS.join(","),
        )?,
        progress,
        total: scene.outputs(),
        regions: Vec::new(),
        started: false,
        values: Vec::new(),
    };
    let (streamed, summary) = stream(scene, &mut files)?;
    streamed?;
    for f in [files.energies, files.snapshots, files.pulses, files.tracks]
        .into_iter()
        .flatten()
    {
        f.commit()?;
    }
    let json = serde_json::to_string_pretty(&summary)?;
    AtomicFile::write_all(out.join("summary.json"), json.as_bytes())?;
    Ok(summary)
}

/// Default output directory for a scene: `out/<scene name>`.
pub fn default_out_dir(scene: &Scene) -> PathBuf {
    PathBuf::from("out").join(scene.name())
}

#[cfg(test)]
mod tests {
    use super::{csv_line, Cell, PULSE_COLUMNS, TRACK_COLUMNS};

    /// A whole number is written as one, a real as every CSV number (a NaN: the empty field),
    /// and both are the same float64 in Python's arrays.
    #[test]
    fn cells_are_written_as_the_csv_convention_says() {
        let row = [
            Cell::Whole(1_000_000_000),
            Cell::Real(0.25),
            Cell::Whole(-3),
            Cell::Real(1e-5),
            Cell::Real(f64::NAN),
        ];
        assert_eq!(csv_line(&row), "1000000000,0.25,-3,1e-5,");
        assert_eq!(row[0].value(), 1e9);
        assert_eq!(row[2].value(), -3.0);
        // The headers `grainchain run` writes (and Python's keys).
        assert_eq!(
            PULSE_COLUMNS.join(","),
            "index,time,pulse,first,last,position,peak_velocity,energy"
        );
        assert_eq!(
            TRACK_COLUMNS.join(","),
            "track,index,time,position,first,last,energy,peak_velocity,instant_peak_velocity,speed"
        );
    }
}
