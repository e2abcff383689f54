//! What `grainchain run` writes: `energies.csv`, `snapshots.csv` (long format), `pulses.csv` and
//! `summary.json`, each only if the scene asks for it, all committed together at the end.
//!
//! Time-series rows are written as they come (to temporary files), so memory stays flat however
//! long the run.

use super::AtomicFile;
use crate::error::Error;
use crate::observables::{self, detect_pulses};
use crate::run::{Frame, Simulation};
use crate::scene::Scene;
use serde::Serialize;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The summary of a finished run.
#[derive(Debug, Serialize)]
pub struct Summary {
    pub scene: String,
    pub method: &'static str,
    /// The step taken (fixed-step methods: shortened so a whole number fits each output interval).
    pub dt: f64,
    /// The step the scene asked for.
    pub requested_dt: f64,
    pub grains: usize,
    pub duration: f64,
    pub outputs: u64,
    pub steps: u64,
    pub rejected_steps: u64,
    pub force_evaluations: u64,
    pub grain_evaluations: u64,
    /// Fraction of grain-evaluations skipped compared with integrating every grain (grain-steps
    /// saved, by skipping untouched grains and grains at rest between islands).
    pub skipped_fraction: f64,
    /// Grains never reached by any disturbance.
    pub grains_untouched: usize,
    /// Largest number of grains integrated at once (summed over islands).
    pub max_window: usize,
    /// Mean number of grains evaluated per force evaluation (islands and their margins).
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
    pub wall_time_s: f64,
    pub timings: crate::run::Timings,
    pub initial_energy: f64,
    pub max_relative_energy_error: f64,
    pub final_relative_energy_error: f64,
    /// Relative to the initial momentum (walls exchange momentum: meaningful for free ends).
    pub max_relative_momentum_error: f64,
    pub ns_per_grain_evaluation: f64,
}

impl Summary {
    /// The file form of [`Simulation::summary`], with the scene's name and the wall time.
    pub fn of(sim: &Simulation, scene_name: &str, wall: f64) -> Summary {
        let r = sim.summary();
        let st = &r.stats;
        let n = r.grains;
        // What is in the chain plus what damping and the sleep rule took out of it.
        let fin = observables::totals(sim.chain(), sim.state(), sim.window()).total
            + st.absorbed_energy
            + st.slept_energy;
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
        }
    }
}

fn io(path: &Path) -> impl Fn(std::io::Error) -> Error + '_ {
    move |source| Error::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Run a scene and write its outputs into `out`. `progress` is called with (done, total) output
/// counts.
pub fn run_scene(
    scene: &Scene,
    out: &Path,
    mut progress: impl FnMut(u64, u64),
) -> Result<Summary, Error> {
    let mut sim = scene.simulation()?;
    let chain_len = sim.chain().len();
    let total = sim.outputs();
    let start = Instant::now();

    let mut energies = if scene.output.energies {
        let mut f = AtomicFile::create(out.join("energies.csv"))?;
        let mut header = String::from("index,time,kinetic,potential,total,momentum");
        for r in &scene.regions {
            header.push_str(&format!(",E_{}", r.name));
        }
        for r in &scene.regions {
            header.push_str(&format!(",P_{}", r.name));
        }
        writeln!(f, "{header}").map_err(io(f.path()))?;
        Some(f)
    } else {
        None
    };
    let mut snaps = match &scene.output.snapshots {
        Some(s) => {
            let mut f = AtomicFile::create(out.join("snapshots.csv"))?;
            let names: Vec<&str> = s.fields.iter().map(|x| x.name()).collect();
            writeln!(f, "index,time,grain,{}", names.join(",")).map_err(io(f.path()))?;
            Some(f)
        }
        None => None,
    };
    let mut pulses = match &scene.output.pulses {
        Some(_) => {
            let mut f = AtomicFile::create(out.join("pulses.csv"))?;
            writeln!(
                f,
                "index,time,pulse,first,last,position,peak_velocity,energy"
            )
            .map_err(io(f.path()))?;
            Some(f)
        }
        None => None,
    };
    let mut e_buf = Vec::new();
    let mut v_buf = Vec::new();

    sim.run(|fr: &Frame| -> Result<(), Error> {
        let t = fr.state.t;
        let chain = fr.chain;
        if let Some(f) = energies.as_mut() {
            let tt = fr.totals;
            let mut line = format!(
                "{},{:e},{:e},{:e},{:e},{:e}",
                fr.index, t, tt.kinetic, tt.potential, tt.total, tt.momentum
            );
            let ranges = scene.regions.iter().map(|r| {
                (
                    chain.index_of(r.first).unwrap(),
                    chain.index_of(r.last).unwrap(),
                )
            });
            for (a, b) in ranges.clone() {
                line.push_str(&format!(
                    ",{:e}",
                    observables::region_energy(chain, fr.state, fr.window, a, b)
                ));
            }
            for (a, b) in ranges {
                line.push_str(&format!(
                    ",{:e}",
                    observables::region_momentum(chain, fr.state, fr.window, a, b)
                ));
            }
            writeln!(f, "{line}").map_err(io(f.path()))?;
        }
        if let (Some(f), Some(spec)) = (snaps.as_mut(), &scene.output.snapshots) {
            if spec.wants(fr.index) {
                let (a, b) = (
                    chain.index_of(spec.first).unwrap(),
                    chain.index_of(spec.last).unwrap(),
                );
                for i in a..=b {
                    write!(f, "{},{:e},{}", fr.index, t, chain.grain_number(i))
                        .map_err(io(f.path()))?;
                    for field in &spec.fields {
                        write!(f, ",{:e}", field.value(chain, fr.state, i))
                            .map_err(io(f.path()))?;
                    }
                    writeln!(f).map_err(io(f.path()))?;
                }
            }
        }
        if let (Some(f), Some(spec)) = (pulses.as_mut(), &scene.output.pulses) {
            if spec.wants(fr.index) {
                let r = fr.window.ever();
                observables::grain_energies(chain, fr.state, r.clone(), &mut e_buf);
                v_buf.clear();
                v_buf.extend_from_slice(&fr.state.v[r.clone()]);
                for (k, p) in detect_pulses(&e_buf, &v_buf, &spec.rule).iter().enumerate() {
                    let off = chain.grain_number(r.start) as f64;
                    writeln!(
                        f,
                        "{},{:e},{},{},{},{:e},{:e},{:e}",
                        fr.index,
                        t,
                        k + 1,
                        chain.grain_number(r.start + p.first),
                        chain.grain_number(r.start + p.last),
                        p.position + off,
                        p.peak_velocity,
                        p.energy
                    )
                    .map_err(io(f.path()))?;
                }
            }
        }
        progress(fr.index, total);
        Ok(())
    })?;
    let wall = start.elapsed().as_secs_f64();
    let summary = Summary::of(&sim, &scene.name, wall);
    let _ = chain_len;
    for f in [energies, snaps, pulses].into_iter().flatten() {
        f.commit()?;
    }
    let json = serde_json::to_string_pretty(&summary)?;
    AtomicFile::write_all(out.join("summary.json"), json.as_bytes())?;
    Ok(summary)
}

/// Default output directory for a scene: `out/<scene name>`.
pub fn default_out_dir(scene: &Scene) -> PathBuf {
    PathBuf::from("out").join(&scene.name)
}
