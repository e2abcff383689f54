//! The work-precision study: run time against error for every integrator on four problems, the
//! way DifferentialEquations.jl's work-precision diagrams show them.
//!
//! Problems:
//! 1. `collision`: two Hertz grains (m = 1 and 3, v = 1 and 0); error = largest deviation of the
//!    outgoing velocities from the exact elastic result (-0.5, 0.5) after the contact ended.
//! 2. `solitary-wave`: an equal-mass striker launches a solitary wave into 1,100 Hertz grains;
//!    error = largest of the relative errors of the arrival times (peak-velocity times) at
//!    grains 200, 400, 600, 800, 1000 and of the peak velocity at grain 1000, against a
//!    reference run of blanes-moan4 at dt = 2.5e-5, over 40 time units (the wave passes grain
//!    1000 at t = 37.6). Quick mode: 300 grains, 10 time units, the probe at grain 200.
//! 3. `container-a`: the standard container of Fig. 4(a) (scenes/containers/a-standard.toml) run
//!    for its first 500 snapshots; error = largest relative deviation of E_R(t) from a reference
//!    run (blanes-moan4 at dt = 2.5e-5) over the snapshots up to [`CONTAINER_HORIZON`] where the
//!    reference E_R exceeds 1e-3 of the incident energy (later snapshots are chaotic, see the
//!    constant). It also runs the paper's own scheme (velocity Verlet at dt = 1.25e-5, nothing
//!    skipped) as a baseline point, and multiple time stepping (`multirate-8`, `multirate-16`:
//!    the scene's dt on the container and the incident path, 8 or 16 times it on the outer
//!    chains). Quick mode runs only up to [`CONTAINER_HORIZON`] (the wave enters the container
//!    at about snapshot 140) and leaves out the paper's scheme (about a minute).
//! 4. `container-a-statistics`: container (a) past its predictable horizon, where E_R(t) is
//!    chaotic and a step's accuracy shows only in ensemble statistics: ensembles of 8 members
//!    (striker speeds 1 + k 1e-12) over 4000 snapshots per candidate setting, window means of
//!    E_R and gamma per decade compared with a reference ensemble (blanes-moan4 at dt/4), and the
//!    cheapest setting inside the reference's 95 % interval (module `statistics`, [`Statistics`]).
//!
//! A point whose error is undefined (the reference has no wave at a probe, or no snapshot to
//! compare) says so in [`Point::failure`] (`not evaluated: ...`) and has a NaN error.
//!
//! Fixed-step methods sweep dt (shortened by the run loop so a whole number of steps fits each
//! output interval: the effective dt is reported), dopri5 sweeps rtol with atol = 1e-3 rtol. Time
//! is the wall time of the whole run, the median of `repeats` runs.

use crate::error::Error;
use crate::report::plot::{LineChart, Scale, Series};
use crate::report::AtomicFile;
use grainchain_engine::problems::{Container, SolitaryWave, TwoGrainCollision};
use grainchain_engine::Field;
use grainchain_engine::Recorder;
use grainchain_engine::Scene;
use grainchain_engine::Simulation;
use grainchain_engine::{IntegrationParams, Method};
use serde::Serialize;
use std::path::Path;
use std::time::Instant;

mod config;
mod measure;
mod statistics;

pub use config::Config;
pub use measure::CONTAINER_HORIZON;
pub use statistics::Statistics;

use measure::{error_of, median, Outcome, WAVE_PROBES};

/// One point of the diagram.
#[derive(Clone, Debug, Serialize)]
pub struct Point {
    /// The problem's name ([`Benchmark::name`]).
    pub problem: &'static str,
    /// Method name, or `paper-scheme` for the paper's baseline.
    pub method: String,
    /// `dt` (fixed step, effective) or `rtol` (adaptive).
    pub setting: f64,
    /// The problem's error (module docs): the largest absolute deviation of the outgoing
    /// velocities for `collision`, the largest relative error for the others (infinite when a
    /// compared value is NaN); NaN when the run failed.
    pub error: f64,
    /// Wall time of one run in seconds, building the simulation not counted: the median of
    /// [`Config::repeats`] runs (one for `paper-scheme`); NaN when the run failed.
    pub seconds: f64,
    /// Accepted steps (0 when the run failed).
    pub steps: u64,
    /// Rejected steps (adaptive methods).
    pub rejected: u64,
    /// Force evaluations.
    pub force_evals: u64,
    /// Grains evaluated, summed over the force evaluations: the work done.
    pub grain_evals: u64,
    /// Empty, or why the point has no error: `failed: ...` when the run failed (e.g. a blow-up
    /// at a step past stability), `not evaluated: ...` when the error is undefined (the
    /// reference has nothing to compare with, see `error_of`).
    pub failure: String,
}

/// A problem of the study, built from the catalogue ([`grainchain_engine::problems`]); its name is the one
/// `grainchain work-precision --only` takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Benchmark {
    /// `collision`: the catalogue's [`TwoGrainCollision`] (masses 1 and 3).
    Collision,
    /// `solitary-wave`: the catalogue's [`SolitaryWave::hertz`], 1,100 grains (300 quick).
    SolitaryWave,
    /// `container-a`: the catalogue's [`Container::A`].
    ContainerA,
    /// `container-a-statistics`: ensembles of [`Container::A`] compared by their statistics
    /// ([`Statistics`]).
    ContainerAStatistics,
}

impl Benchmark {
    /// Every problem, in the study's order.
    pub const ALL: [Benchmark; 4] = [
        Benchmark::Collision,
        Benchmark::SolitaryWave,
        Benchmark::ContainerA,
        Benchmark::ContainerAStatistics,
    ];

    /// The names of [`Benchmark::ALL`], in order (the CLI's choices).
    pub const NAMES: [&'static str; 4] = [
        "collision",
        "solitary-wave",
        "container-a",
        "container-a-statistics",
    ];

    /// The name on the command line and in the CSV.
    pub fn name(self) -> &'static str {
        match self {
            Benchmark::Collision => "collision",
            Benchmark::SolitaryWave => "solitary-wave",
            Benchmark::ContainerA => "container-a",
            Benchmark::ContainerAStatistics => statistics::NAME,
        }
    }
}

/// The sweep for a method: (params, setting).
fn sweep(method: Method, quick: bool) -> Vec<IntegrationParams> {
    let base = IntegrationParams {
        method,
        ..Default::default()
    };
    let settings = config::samples(method);
    let mut v: Vec<IntegrationParams> = if method.is_adaptive() {
        settings
            .iter()
            .map(|&r| IntegrationParams {
                rtol: r,
                atol: 1e-3 * r,
                dt: 1e-4,
                ..base
            })
            .collect()
    } else {
        settings
            .iter()
            .map(|&dt| IntegrationParams { dt, ..base })
            .collect()
    };
    if quick {
        let keep = [0, v.len() / 2];
        v = keep.iter().map(|&i| v[i]).collect();
    }
    v
}

struct Runner {
    cfg: Config,
    container: Option<Scene>,
}

impl Runner {
    fn simulation(&self, problem: Benchmark, p: IntegrationParams) -> Result<Simulation, Error> {
        let quick = self.cfg.quick;
        Ok(match problem {
            // The catalogue's collision: masses 1 and 3, Hertz, eta = 5657. The contact lasts
            // 0.0904 (physics.md 4); 0.2 is well past it.
            Benchmark::Collision => TwoGrainCollision::default()
                .builder()?
                .params(p)
                .schedule(0.2, 0.2)
                .build()?,
            Benchmark::SolitaryWave => {
                // The wave travels 26.6 grains per time unit (measured: peaks at grains 200 and
                // 400 at t = 7.53 and 15.04), so it passes the last probe (grain 1000; grain 200
                // in quick mode) at t = 37.6 (7.5) and reaches the chain's end at 41.4 (11.3).
                let n = if quick { 300 } else { 1100 };
                let t = if quick { 10.0 } else { 40.0 };
                SolitaryWave::hertz(n)
                    .builder()?
                    .params(p)
                    .schedule(t, 0.01)
                    .build()?
            }
            Benchmark::ContainerA => {
                let mut sc = self.container.clone().ok_or_else(|| {
                    Error::Input(grainchain_engine::InputError::Read {
                        file: Container::A.file_name().into(),
                        source: std::io::Error::new(
                            std::io::ErrorKind::NotFound,
                            "the container scene was not loaded",
                        ),
                    })
                })?;
                // The first 500 snapshots of Fig. 4(a); in quick mode the first
                // CONTAINER_HORIZON + 1, the last compared: the wave enters the container only
                // at about snapshot 140, so a shorter run has nothing to compare.
                let duration = if quick {
                    (CONTAINER_HORIZON + 1) as f64 * sc.output_interval()
                } else {
                    62.5
                };
                sc.set_schedule(duration, sc.output_interval())?;
                // The scene's causal horizon is exact, so it stays for the methods that take it
                // (gear5 and dopri5 do not: their runs integrate the long chains). Dropped
                // before the method changes: the scene checks every edit.
                sc.set_horizon(
                    sc.horizon()
                        .copied()
                        .filter(|_| p.method.information().horizon),
                )?;
                sc.set_params(IntegrationParams {
                    max_energy_error: sc.params().max_energy_error,
                    ..p
                })?;
                sc.simulation()?
            }
            Benchmark::ContainerAStatistics => {
                unreachable!("container-a-statistics runs ensembles (statistics::run), not points")
            }
        })
    }

    fn run(
        &self,
        problem: Benchmark,
        p: IntegrationParams,
    ) -> Result<(Outcome, Simulation, f64), Error> {
        let mut sim = self.simulation(problem, p)?;
        let t0 = Instant::now();
        let outcome = match problem {
            Benchmark::Collision => {
                Recorder::new().record(&mut sim)?;
                let v = &sim.state().v;
                Outcome::Velocities(v[0], v[1])
            }
            Benchmark::SolitaryWave => {
                let probes: Vec<usize> = WAVE_PROBES
                    .iter()
                    .copied()
                    .filter(|&g| g < sim.chain().len())
                    .collect();
                let rec = Recorder::new()
                    .probes(Field::Velocity, probes.iter().copied())
                    .record(&mut sim)?;
                let dt = sim.output_interval();
                // Slide a window of three samples over each probe; a peak is found when the
                // middle one is the largest, and refined by the parabola through the three.
                let mut arrival = vec![f64::NAN; probes.len()];
                let mut peak = vec![0.0f64; probes.len()];
                for (k, series) in rec.probes.iter().enumerate() {
                    let mut h = [0.0f64; 3];
                    for (index, (&v, &t)) in series.values.iter().zip(&rec.time).enumerate() {
                        h = [h[1], h[2], v];
                        if index >= 2 && h[1] > h[0] && h[1] >= h[2] && h[1] > 1e-3 {
                            let denom = h[0] - 2.0 * h[1] + h[2];
                            let off = if denom != 0.0 {
                                0.5 * (h[0] - h[2]) / denom
                            } else {
                                0.0
                            };
                            arrival[k] = t - dt + off * dt;
                            peak[k] = h[1] - 0.25 * (h[0] - h[2]) * off;
                            break;
                        }
                    }
                }
                let last = *peak.last().unwrap_or(&f64::NAN);
                Outcome::Arrivals(arrival, last)
            }
            Benchmark::ContainerA => {
                let scene = self.container.as_ref().unwrap();
                let (a, b) = Container::grains(scene)?;
                let rec = Recorder::new().region("container", a, b).record(&mut sim)?;
                let e = rec.region("container").map(|r| r.energy.clone());
                Outcome::Energy(e.unwrap_or_default())
            }
            Benchmark::ContainerAStatistics => {
                unreachable!("container-a-statistics runs ensembles (statistics::run), not points")
            }
        };
        let secs = t0.elapsed().as_secs_f64();
        Ok((outcome, sim, secs))
    }
}

/// Internal indices of the multirate fast region of a container scene: from 20 grains before the
/// region `container` to 20 grains after the last grain that moves at t = 0 (the striker).
fn container_fast_region(sc: &Scene) -> Result<(usize, usize), Error> {
    let sim = sc.simulation()?;
    let (c0, _) = Container::grains(sc)?;
    let striker = (0..sim.chain().len())
        .rev()
        .find(|&i| sim.state().v[i] != 0.0)
        .unwrap_or(c0);
    let n = sim.chain().len();
    Ok((c0.saturating_sub(20), (striker + 20).min(n - 1)))
}

/// The result of a study.
#[derive(Debug, Serialize)]
pub struct Study {
    /// Every point, problem by problem in the order asked for; per problem the methods in
    /// [`Method::ALL`] order, then `container-a`'s extra settings (`scene-default`,
    /// `paper-scheme`, `multirate-8`, `multirate-16`). `container-a-statistics` has no points.
    pub points: Vec<Point>,
    /// The ensembles of `container-a-statistics`, when it was asked for.
    pub statistics: Option<Statistics>,
}

/// Run the study. `progress(label)` is called before each point.
pub fn run(
    cfg: &Config,
    problems: &[Benchmark],
    mut progress: impl FnMut(&str),
) -> Result<Study, Error> {
    let container = if problems.contains(&Benchmark::ContainerA) {
        Some(Container::A.scene(&cfg.scenes)?)
    } else {
        None
    };
    let runner = Runner {
        cfg: cfg.clone(),
        container,
    };
    let mut points = Vec::new();
    for &problem in problems
        .iter()
        .filter(|&&p| p != Benchmark::ContainerAStatistics)
    {
        progress(&format!("{}: reference", problem.name()));
        let reference = match problem {
            // Exact elastic collision of point masses 1 and 3 at velocities 1 and 0.
            Benchmark::Collision => {
                let (a, b) = TwoGrainCollision::default().outgoing_velocities();
                Outcome::Velocities(a, b)
            }
            _ => {
                let p = IntegrationParams {
                    method: Method::BlanesMoan4,
                    dt: 2.5e-5,
                    ..Default::default()
                };
                runner.run(problem, p)?.0
            }
        };
        let mut settings: Vec<(String, IntegrationParams)> = Vec::new();
        for m in Method::SINGLE_RATE {
            for p in sweep(m, cfg.quick) {
                settings.push((m.name().to_string(), p));
            }
        }
        if problem == Benchmark::ContainerA {
            // The settings of the scene file: what `grainchain reproduce` uses.
            if let Some(sc) = &runner.container {
                settings.push(("scene-default".to_string(), *sc.params()));
            }
            // The paper's scheme: velocity Verlet at dt = 1.25e-5, every grain integrated. Not in
            // quick mode: its 1.5e6 steps over all 8,361 grains take about a minute.
            if !cfg.quick {
                let p = IntegrationParams {
                    method: Method::Verlet,
                    dt: 1.25e-5,
                    skip_untouched: false,
                    ..Default::default()
                };
                settings.push(("paper-scheme".to_string(), p));
            }
            // Multiple time stepping as `grainchain study` sets it up: the container and the
            // incident path (container to striker) plus 20 grains on each side at the scene's
            // dt, the outer chains at 8 and 16 times it.
            if let Some(sc) = &runner.container {
                let (first, last) = container_fast_region(sc)?;
                for ratio in [8, 16] {
                    let p = IntegrationParams {
                        method: Method::Multirate,
                        multirate: Some(grainchain_engine::MultirateParams { ratio, first, last }),
                        ..*sc.params()
                    };
                    settings.push((format!("multirate-{ratio}"), p));
                }
            }
        }
        for (name, p) in settings {
            let setting = if p.method.is_adaptive() { p.rtol } else { p.dt };
            progress(&format!("{}: {name} {setting:e}", problem.name()));
            let mut times = Vec::new();
            let mut result = None;
            // The paper's scheme is slow and deterministic: time it once.
            let repeats = if name == "paper-scheme" {
                1
            } else {
                cfg.repeats.max(1)
            };
            for _ in 0..repeats {
                match runner.run(problem, p) {
                    Ok((o, sim, secs)) => {
                        times.push(secs);
                        result = Some(Ok((o, sim)));
                    }
                    Err(e) => {
                        result = Some(Err(e));
                        break;
                    }
                }
            }
            let point = match result.expect("at least one run") {
                Ok((o, sim)) => {
                    let st = *sim.stats();
                    let e0 = sim.initial_energy();
                    let (error, failure) = match error_of(&o, &reference, e0) {
                        Ok(e) => (e, String::new()),
                        Err(why) => (f64::NAN, why),
                    };
                    Point {
                        problem: problem.name(),
                        method: name,
                        setting: if p.method.is_adaptive() {
                            p.rtol
                        } else {
                            sim.params().dt
                        },
                        error,
                        seconds: median(times),
                        steps: st.steps,
                        rejected: st.rejected,
                        force_evals: st.force_evals,
                        grain_evals: st.grain_evals,
                        failure,
                    }
                }
                Err(e) => Point {
                    problem: problem.name(),
                    method: name,
                    setting,
                    error: f64::NAN,
                    seconds: f64::NAN,
                    steps: 0,
                    rejected: 0,
                    force_evals: 0,
                    grain_evals: 0,
                    failure: format!("failed: {e}"),
                },
            };
            points.push(point);
        }
    }
    let statistics = if problems.contains(&Benchmark::ContainerAStatistics) {
        Some(statistics::run(cfg, &mut progress)?)
    } else {
        None
    };
    Ok(Study { points, statistics })
}

impl Study {
    /// The fastest method reaching `target` error on `problem`: (method, seconds, error).
    pub fn fastest_at(&self, problem: &str, target: f64) -> Option<(&str, f64, f64)> {
        self.points
            .iter()
            .filter(|p| {
                p.problem == problem
                    && p.failure.is_empty()
                    && p.error <= target
                    && p.method != "paper-scheme"
                    && p.method != "scene-default"
            })
            .min_by(|a, b| a.seconds.total_cmp(&b.seconds))
            .map(|p| (p.method.as_str(), p.seconds, p.error))
    }

    /// The text of `work_precision.csv`: one row per point, numbers in the one CSV form
    /// ([`crate::report::csv_number`]: a point without an error or time has empty fields).
    pub fn csv(&self) -> Result<Vec<u8>, Error> {
        use crate::report::csv_number as num;
        let err = |source| Error::Csv {
            what: "work_precision.csv".into(),
            source,
        };
        let mut w = csv::Writer::from_writer(Vec::new());
        w.write_record([
            "problem",
            "method",
            "setting",
            "error",
            "seconds",
            "steps",
            "rejected",
            "force_evals",
            "grain_evals",
            "failure",
        ])
        .map_err(err)?;
        for p in &self.points {
            w.write_record([
                p.problem.to_string(),
                p.method.clone(),
                num(p.setting),
                num(p.error),
                num(p.seconds),
                p.steps.to_string(),
                p.rejected.to_string(),
                p.force_evals.to_string(),
                p.grain_evals.to_string(),
                p.failure.clone(),
            ])
            .map_err(err)?;
        }
        w.into_inner().map_err(|e| Error::Io {
            path: "work_precision.csv".into(),
            source: e.into_error(),
        })
    }

    /// Write `work_precision.csv` and one SVG per problem into `out` (the CSV only when there
    /// are points), and `container-a-statistics`'s files ([`Statistics::write`]).
    pub fn write(&self, out: &Path) -> Result<(), Error> {
        if let Some(s) = &self.statistics {
            s.write(out)?;
        }
        if self.points.is_empty() {
            return Ok(());
        }
        AtomicFile::write_all(out.join("work_precision.csv"), &self.csv()?)?;
        let problems: Vec<&str> = {
            let mut v: Vec<&str> = self.points.iter().map(|p| p.problem).collect();
            v.dedup();
            v
        };
        for prob in problems {
            let mut names: Vec<&str> = self
                .points
                .iter()
                .filter(|p| p.problem == prob)
                .map(|p| p.method.as_str())
                .collect();
            names.dedup();
            let curves: Vec<(&str, Vec<(f64, f64)>)> = names
                .iter()
                .map(|&m| {
                    let pts = self
                        .points
                        .iter()
                        .filter(|p| p.problem == prob && p.method == m && p.failure.is_empty())
                        .map(|p| (p.error, p.seconds))
                        .collect();
                    (m, pts)
                })
                .collect();
            AtomicFile::write_all(
                out.join(format!("work_precision_{prob}.svg")),
                chart_svg(prob, &curves)?.as_bytes(),
            )?;
        }
        Ok(())
    }
}

/// The work-precision chart of one problem as SVG: wall time against error, log-log, one curve
/// with markers per method (`(error, seconds)` points; zero, infinite and NaN errors are not
/// drawn, and a chart without any drawable point says so).
pub fn chart_svg(problem: &str, curves: &[(&str, Vec<(f64, f64)>)]) -> Result<String, Error> {
    let title = format!("work-precision: {problem}");
    LineChart {
        title: &title,
        x_label: "error",
        y_label: "wall time (s)",
        x_scale: Scale::Log,
        y_scale: Scale::Log,
        series: curves
            .iter()
            .map(|(m, pts)| Series {
                name: m.to_string(),
                points: pts.clone(),
                markers: true,
                ..Default::default()
            })
            .collect(),
        ..Default::default()
    }
    .to_svg()
}
