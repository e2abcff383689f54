//! The work-precision study: run time against error for every integrator on eight problems, the
//! way DifferentialEquations.jl's work-precision diagrams show them, and the order each method
//! reaches on the contact problems.
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
//! The order problems (issue 40: what the non-smooth contact force costs each method's order;
//! [`Benchmark::measures_order`]) sweep the fixed steps in exact halvings (`config::halvings`)
//! and report the observed order of each halving ([`Study::orders`]):
//! 5. `collision-hertz`: `collision` again, its steps halved exactly.
//! 6. `collision-linear`: the same collision with a linear contact (p = 1, eta = 5657; contact
//!    time pi sqrt(mu/eta) = 0.0362); the same exact result.
//! 7. `restitution`: two unit grains, Hertz (eta = 1), contact damping c = 0.1 in each model the
//!    engine has ([`DampingModel`]), impact speed 1; error = |e - e_ref| of the coefficient of
//!    restitution against an independent integration of the contact's own equation
//!    (`reference.rs`, to about 1e-13). Points are labelled `restitution-<model>`; only the
//!    methods that take damping (the splitting methods) run it.
//! 8. `protector-40`: one protector evaluation of the 40-bead reference column of
//!    `benches/protector.rs`, its peak force (the search's default stop), per method (verlet,
//!    blanes-moan4) and steps per contact time in exact halvings, against blanes-moan4 at a
//!    step 4 times finer, whose own error a `reference-check` point states (module
//!    `protector`; why not the impulse and duration: [`protector::QUANTITIES`]). Points are
//!    labelled `protector-40-peak`; the setting is the step in seconds, the time that of one
//!    whole `evaluate` call.
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
use grainchain_engine::{ChainBuilder, ContactLaw, DampingModel, SimulationBuilder};
use grainchain_engine::{IntegrationParams, Method};
use serde::Serialize;
use std::path::Path;
use std::time::Instant;

mod config;
mod measure;
pub mod protector;
pub mod reference;
mod statistics;

pub use config::Config;
pub use measure::{Point, CONTAINER_HORIZON};
pub use statistics::Statistics;

use measure::{error_of, median, Outcome, WAVE_PROBES};

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
    /// `collision-hertz`: [`Benchmark::Collision`] with its steps halved exactly (an order
    /// problem).
    CollisionHertz,
    /// `collision-linear`: the same collision with a linear contact (p = 1; an order problem).
    CollisionLinear,
    /// `restitution`: a damped collision of two unit Hertz grains, once per [`DampingModel`]
    /// (an order problem).
    Restitution,
    /// `protector-40`: a protector evaluation of [`grainchain_engine::protector::Case::steel_then_ptfe`]`(40)`,
    /// its peak force (an order problem; module [`protector`]).
    Protector40,
}

/// Damping coefficient of `restitution` (e = 0.78 to 0.86 in the three models).
pub const RESTITUTION_DAMPING: f64 = 0.1;

/// Length of a run of `restitution`: 3.3 elastic contact times (tc = 2.44 for unit grains,
/// eta = 1, speed 1), so every model's contact has ended.
const RESTITUTION_RUN: f64 = 8.0;

/// Length of a run of the collisions (`collision` and the order problems).
const COLLISION_RUN: f64 = 0.2;

/// The damping models of `restitution`, in the order of its labels.
const MODELS: [DampingModel; 3] = [
    DampingModel::Viscous,
    DampingModel::KuwabaraKono,
    DampingModel::ScaleRespecting,
];

impl Benchmark {
    /// Every problem, in the study's order.
    pub const ALL: [Benchmark; 8] = [
        Benchmark::Collision,
        Benchmark::SolitaryWave,
        Benchmark::ContainerA,
        Benchmark::ContainerAStatistics,
        Benchmark::CollisionHertz,
        Benchmark::CollisionLinear,
        Benchmark::Restitution,
        Benchmark::Protector40,
    ];

    /// The names of [`Benchmark::ALL`], in order (the CLI's choices).
    pub const NAMES: [&'static str; 8] = [
        "collision",
        "solitary-wave",
        "container-a",
        "container-a-statistics",
        "collision-hertz",
        "collision-linear",
        "restitution",
        protector::NAME,
    ];

    /// The name on the command line and in the CSV.
    pub fn name(self) -> &'static str {
        match self {
            Benchmark::Collision => "collision",
            Benchmark::SolitaryWave => "solitary-wave",
            Benchmark::ContainerA => "container-a",
            Benchmark::ContainerAStatistics => statistics::NAME,
            Benchmark::CollisionHertz => "collision-hertz",
            Benchmark::CollisionLinear => "collision-linear",
            Benchmark::Restitution => "restitution",
            Benchmark::Protector40 => protector::NAME,
        }
    }

    /// Whether the problem measures the observed order: its fixed steps are exact halvings
    /// (`config::halvings`) and [`Study::orders`] reports it.
    pub fn measures_order(self) -> bool {
        matches!(
            self,
            Benchmark::CollisionHertz
                | Benchmark::CollisionLinear
                | Benchmark::Restitution
                | Benchmark::Protector40
        )
    }

    /// The labels of the problem's points with their damping model: one per [`DampingModel`]
    /// for `restitution` (`restitution-viscous`, ...), one per number for `protector-40`
    /// ([`protector::QUANTITIES`]), the name for the others.
    pub fn labels(self) -> Vec<(&'static str, Option<DampingModel>)> {
        match self {
            Benchmark::Restitution => MODELS
                .iter()
                .map(|&m| {
                    let label = match m {
                        DampingModel::Viscous => "restitution-viscous",
                        DampingModel::KuwabaraKono => "restitution-kuwabara-kono",
                        DampingModel::ScaleRespecting => "restitution-scale-respecting",
                    };
                    (label, Some(m))
                })
                .collect(),
            Benchmark::Protector40 => protector::QUANTITIES
                .iter()
                .map(|&(label, _)| (label, None))
                .collect(),
            _ => vec![(self.name(), None)],
        }
    }

    /// The length of one run (a whole number of every step of [`config::halvings`]).
    fn run_length(self) -> f64 {
        match self {
            Benchmark::Restitution => RESTITUTION_RUN,
            _ => COLLISION_RUN,
        }
    }
}

/// The exact restitution of `restitution` for `model`: `reference.rs` at 4000 steps per piece
/// (about 1e-14; `validation/orders.rs`).
pub fn restitution_reference(model: DampingModel) -> Result<f64, String> {
    let contact = reference::Contact {
        p: 1.5,
        eta: 1.0,
        mu: 0.5,
        q: model.exponent(1.5),
        c: RESTITUTION_DAMPING,
    };
    Ok(-contact.outgoing_rate(1.0, 4000)?)
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

/// The sweep of an order problem: dt = `length` / n for n in [`config::halvings`] (exact
/// halvings), dopri5 as in [`sweep`].
fn halving_sweep(method: Method, quick: bool, length: f64) -> Vec<IntegrationParams> {
    if method.is_adaptive() {
        return sweep(method, quick);
    }
    let mut v: Vec<IntegrationParams> = config::halvings(method)
        .into_iter()
        .map(|n| IntegrationParams {
            method,
            dt: length / n as f64,
            ..Default::default()
        })
        .collect();
    if quick && !v.is_empty() {
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
    fn simulation(
        &self,
        problem: Benchmark,
        model: Option<DampingModel>,
        p: IntegrationParams,
    ) -> Result<Simulation, Error> {
        let quick = self.cfg.quick;
        Ok(match problem {
            // The catalogue's collision: masses 1 and 3, Hertz, eta = 5657. The contact lasts
            // 0.0904 (physics.md 4); 0.2 is well past it.
            Benchmark::Collision | Benchmark::CollisionHertz => TwoGrainCollision::default()
                .builder()?
                .params(p)
                .schedule(COLLISION_RUN, COLLISION_RUN)
                .build()?,
            // The contact lasts pi sqrt(0.75 / 5657) = 0.0362.
            Benchmark::CollisionLinear => TwoGrainCollision {
                p: 1.0,
                ..Default::default()
            }
            .builder()?
            .params(p)
            .schedule(COLLISION_RUN, COLLISION_RUN)
            .build()?,
            Benchmark::Restitution => {
                let model = model.unwrap_or(DampingModel::Viscous);
                let law = ContactLaw::hertz(1.0).with_damping(model, RESTITUTION_DAMPING);
                let chain = ChainBuilder::new().grains(2, 1.0, law).build()?;
                SimulationBuilder::new(chain)
                    .params(p)
                    .schedule(RESTITUTION_RUN, RESTITUTION_RUN)
                    .velocity(0, 1.0)
                    .build()?
            }
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
            Benchmark::Protector40 => {
                unreachable!("protector-40 runs protector evaluations (protector::run)")
            }
        })
    }

    fn run(
        &self,
        problem: Benchmark,
        model: Option<DampingModel>,
        p: IntegrationParams,
    ) -> Result<(Outcome, Simulation, f64), Error> {
        let mut sim = self.simulation(problem, model, p)?;
        let t0 = Instant::now();
        let outcome = match problem {
            Benchmark::Collision | Benchmark::CollisionHertz | Benchmark::CollisionLinear => {
                Recorder::new().record(&mut sim)?;
                let v = &sim.state().v;
                Outcome::Velocities(v[0], v[1])
            }
            Benchmark::Restitution => {
                Recorder::new().record(&mut sim)?;
                let st = sim.state();
                // Still in contact at the end: no restitution (NaN, an infinite error).
                let e = if st.u[0] < st.u[1] {
                    st.v[1] - st.v[0]
                } else {
                    f64::NAN
                };
                Outcome::Restitution(e)
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
            Benchmark::Protector40 => {
                unreachable!("protector-40 runs protector evaluations (protector::run)")
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
    /// `paper-scheme`, `multirate-8`, `multirate-16`); `protector-40`'s label by label, each
    /// its `reference-check` point first. `container-a-statistics` has no points.
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
        if problem == Benchmark::Protector40 {
            points.extend(protector::run(cfg.quick, cfg.repeats, &mut progress)?);
            continue;
        }
        for (label, model) in problem.labels() {
            progress(&format!("{}: reference", label));
            let reference = match problem {
                // Exact elastic collision of point masses 1 and 3 at velocities 1 and 0.
                // (The linear collision has the same: the result does not depend on the law.)
                Benchmark::Collision | Benchmark::CollisionHertz | Benchmark::CollisionLinear => {
                    let (a, b) = TwoGrainCollision::default().outgoing_velocities();
                    Outcome::Velocities(a, b)
                }
                // Unit grains at speed 1: e = the reference's outgoing rate over the speed.
                Benchmark::Restitution => Outcome::Restitution(
                    restitution_reference(model.unwrap_or(DampingModel::Viscous))
                        .map_err(|e| Error::Run(grainchain_engine::RunError::Settings(e)))?,
                ),
                _ => {
                    let p = IntegrationParams {
                        method: Method::BlanesMoan4,
                        dt: 2.5e-5,
                        ..Default::default()
                    };
                    runner.run(problem, model, p)?.0
                }
            };
            let mut settings: Vec<(String, IntegrationParams)> = Vec::new();
            for m in Method::SINGLE_RATE {
                // Damping is applied only by the methods that take it.
                if model.is_some() && !m.information().damping {
                    continue;
                }
                let sweep = if problem.measures_order() {
                    halving_sweep(m, cfg.quick, problem.run_length())
                } else {
                    sweep(m, cfg.quick)
                };
                for p in &sweep {
                    settings.push((m.name().to_string(), *p));
                }
                // The same halvings with the steps cut at contact events.
                if problem.measures_order() && m.information().events {
                    for p in sweep {
                        let p = IntegrationParams { events: true, ..p };
                        settings.push((format!("{}+events", m.name()), p));
                    }
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
                            multirate: Some(grainchain_engine::MultirateParams {
                                ratio,
                                first,
                                last,
                            }),
                            ..*sc.params()
                        };
                        settings.push((format!("multirate-{ratio}"), p));
                    }
                }
            }
            for (name, p) in settings {
                let setting = if p.method.is_adaptive() { p.rtol } else { p.dt };
                progress(&format!("{}: {name} {setting:e}", label));
                let mut times = Vec::new();
                let mut result = None;
                // The paper's scheme is slow and deterministic: time it once.
                let repeats = if name == "paper-scheme" {
                    1
                } else {
                    cfg.repeats.max(1)
                };
                for _ in 0..repeats {
                    match runner.run(problem, model, p) {
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
                            problem: label,
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
                    Err(e) => Point::failed(label, name, setting, e),
                };
                points.push(point);
            }
        }
    }
    let statistics = if problems.contains(&Benchmark::ContainerAStatistics) {
        Some(statistics::run(cfg, &mut progress)?)
    } else {
        None
    };
    Ok(Study { points, statistics })
}

/// The observed order between two consecutive points of a method on an order problem.
#[derive(Clone, Debug, Serialize)]
pub struct Order {
    /// The point's label ([`Benchmark::labels`]).
    pub problem: &'static str,
    /// The method's name.
    pub method: String,
    /// `dt` (fixed step) or `rtol` (dopri5) of the finer point.
    pub setting: f64,
    /// The finer point's error.
    pub error: f64,
    /// Accepted steps of the finer point.
    pub steps: u64,
    /// `ln(e_coarse / e_fine) / ln(work_fine / work_coarse)`, the work being `1/dt` (so
    /// log2 of the error ratio for a halving) or, for dopri5, the accepted steps; NaN at a
    /// method's first point or where an error is not a positive finite number.
    pub order: f64,
}

/// Whether a point's label is an order problem's.
fn is_order_label(label: &str) -> bool {
    Benchmark::ALL
        .iter()
        .filter(|b| b.measures_order())
        .any(|b| b.labels().iter().any(|(l, _)| *l == label))
}

impl Study {
    /// The observed orders on the order problems ([`Benchmark::measures_order`]): per label and
    /// method, one row per point in sweep order, its order against the point before.
    pub fn orders(&self) -> Vec<Order> {
        let mut out = Vec::new();
        let mut prev: Option<&Point> = None;
        for p in self.points.iter().filter(|p| is_order_label(p.problem)) {
            let before = prev
                .filter(|q| q.problem == p.problem && q.method == p.method && q.failure.is_empty());
            let order = match before {
                Some(q) if p.failure.is_empty() && q.error > 0.0 && p.error > 0.0 => {
                    let work = if p.method == Method::Dopri5.name() {
                        p.steps as f64 / q.steps as f64
                    } else {
                        q.setting / p.setting
                    };
                    let o = (q.error / p.error).ln() / work.ln();
                    if o.is_finite() {
                        o
                    } else {
                        f64::NAN
                    }
                }
                _ => f64::NAN,
            };
            out.push(Order {
                problem: p.problem,
                method: p.method.clone(),
                setting: p.setting,
                error: p.error,
                steps: p.steps,
                order,
            });
            prev = Some(p);
        }
        out
    }

    /// The text of `work_precision_orders.csv` ([`Study::orders`]; an order without a value is
    /// an empty field).
    pub fn orders_csv(&self) -> Result<Vec<u8>, Error> {
        use crate::report::csv_number as num;
        let err = |source| Error::Csv {
            what: "work_precision_orders.csv".into(),
            source,
        };
        let mut w = csv::Writer::from_writer(Vec::new());
        w.write_record(["problem", "method", "setting", "error", "steps", "order"])
            .map_err(err)?;
        for o in self.orders() {
            w.write_record([
                o.problem.to_string(),
                o.method,
                num(o.setting),
                num(o.error),
                o.steps.to_string(),
                num(o.order),
            ])
            .map_err(err)?;
        }
        w.into_inner().map_err(|e| Error::Io {
            path: "work_precision_orders.csv".into(),
            source: e.into_error(),
        })
    }

    /// The observed orders as a text table (empty when no order problem ran).
    pub fn orders_table(&self) -> String {
        use std::fmt::Write as _;
        let orders = self.orders();
        let mut s = String::new();
        if orders.is_empty() {
            return s;
        }
        let _ = writeln!(
            s,
            "observed order (per halving of dt; dopri5: per ratio of accepted steps)"
        );
        let _ = writeln!(
            s,
            "{:<28} {:<13} {:>11} {:>11} {:>7}",
            "problem", "method", "setting", "error", "order"
        );
        for o in &orders {
            let order = if o.order.is_nan() {
                String::new()
            } else {
                format!("{:.2}", o.order)
            };
            let _ = writeln!(
                s,
                "{:<28} {:<13} {:>11.4e} {:>11.3e} {:>7}",
                o.problem, o.method, o.setting, o.error, order
            );
        }
        s
    }
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
                    && p.method != protector::REFERENCE_CHECK
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
    /// are points), `work_precision_orders.csv` when an order problem ran, and `container-a-statistics`'s files ([`Statistics::write`]).
    pub fn write(&self, out: &Path) -> Result<(), Error> {
        if let Some(s) = &self.statistics {
            s.write(out)?;
        }
        if self.points.is_empty() {
            return Ok(());
        }
        AtomicFile::write_all(out.join("work_precision.csv"), &self.csv()?)?;
        if !self.orders().is_empty() {
            AtomicFile::write_all(out.join("work_precision_orders.csv"), &self.orders_csv()?)?;
        }
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
