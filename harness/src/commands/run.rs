//! `grainchain run` and `grainchain check`: one scene file, read once (a pipe or a FIFO can be
//! read only once), refused over the size limits unless allowed, then run into a claimed folder
//! or only estimated.

use super::{claim_for_scene, read_scene, Caller};
use crate::error::Error;
use crate::report::limits::{Refusal, OUTPUT_LIMIT_BYTES};
use crate::report::run_output::{
    default_out_dir, output_files, output_size_check, run_scene, Summary,
};
use grainchain_engine::file::SceneFile;
use grainchain_engine::format::{human_bytes, Num};
use grainchain_engine::{MemoryEstimate, Scene};
use std::path::{Path, PathBuf};

/// What `grainchain run` is asked for.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// The scene file (TOML).
    pub scene: PathBuf,
    /// Output directory (default: `out/<scene name>`).
    pub out: Option<PathBuf>,
    /// Run even if the outputs or the memory are estimated over the limits.
    pub allow_large_output: bool,
    /// Delete the files grainchain wrote in a folder of another command or other inputs.
    pub force: bool,
}

/// `grainchain run`: refuse a run over the memory or output limits, say the scene's warnings and
/// a shortened step, claim the output folder, run with a progress bar, commit the files and say
/// what the run did. Returns the run's summary.
pub fn run(opts: &RunOptions, caller: &Caller) -> Result<Summary, Error> {
    let path = &opts.scene;
    let parsed = read_scene(path)?;
    memory_limit(&parsed.typed, path, caller, opts.allow_large_output)?;
    let scene = Scene::from_file(parsed.typed, path)?;
    for w in scene.warnings() {
        caller.note(format_args!("warning: {}: {w}", path.display()));
    }
    output_size_check(&scene, path, caller.words, opts.allow_large_output)?;
    let out = opts.out.clone().unwrap_or_else(|| default_out_dir(&scene));
    if !scene.params().method.is_adaptive() {
        let taken = scene.step();
        if taken != scene.params().dt {
            caller.note(format_args!(
                "note: {}: dt shortened from {} to {} so that a whole number of steps fits each output interval ({})",
                scene.name(),
                Num(scene.params().dt),
                Num(taken),
                Num(scene.output_interval())
            ));
        }
    }
    let dir = claim_for_scene(&out, "run", &parsed.value, path, opts.force)?;
    let pb = caller.outputs_bar(scene.outputs(), scene.name());
    let summary = run_scene(&scene, &out, |done, _| pb.set_position(done));
    pb.finish_and_clear();
    let summary = summary?;
    dir.finish(&output_files(&scene))?;
    caller.out(format_args!(
        "{}: {} steps ({} rejected), {} force evaluations, {:.3} s, max |dE/E0| = {:.2e}, {} of {} grains never touched, {:.0} grains integrated on average (max {}), {:.1} % of grain-steps saved; wrote {}",
        summary.scene,
        summary.steps,
        summary.rejected_steps,
        summary.force_evaluations,
        summary.wall_time_s,
        summary.max_relative_energy_error,
        summary.grains_untouched,
        summary.grains,
        summary.mean_window,
        summary.max_window,
        100.0 * summary.skipped_fraction,
        out.display()
    ));
    Ok(summary)
}

/// Refuse a scene whose simulation would need more than [`OUTPUT_LIMIT_BYTES`] of memory
/// (estimated from the grain counts of the file, before anything is built), unless `allow`. A
/// file that does not parse, or over the hard limit of grains, is left to the scene check.
fn memory_limit(f: &SceneFile, path: &Path, caller: &Caller, allow: bool) -> Result<(), Error> {
    let m = MemoryEstimate::of_run(f);
    match m.refusal(path, caller.words).filter(|_| !allow) {
        Some(e) => Err(e.into()),
        None => Ok(()),
    }
}

/// What `grainchain check` is asked for.
#[derive(Clone, Debug, Default)]
pub struct CheckOptions {
    /// The scene file (TOML).
    pub scene: PathBuf,
    /// Check even if the simulation is estimated to need more memory than the limit.
    pub allow_large_output: bool,
}

/// `grainchain check`: the scene's checks, then the estimate of steps, output sizes and memory.
pub fn check(opts: &CheckOptions, caller: &Caller) -> Result<(), Error> {
    let scene = &opts.scene;
    let parsed = read_scene(scene)?;
    memory_limit(&parsed.typed, scene, caller, opts.allow_large_output)?;
    let m = MemoryEstimate::of_run(&parsed.typed);
    let s = Scene::from_file(parsed.typed, scene)?;
    for w in s.warnings() {
        caller.note(format_args!("warning: {}: {w}", scene.display()));
    }
    let est = s.estimate();
    // The step the run takes (fitted to the output interval), and the one asked for if it differs.
    let taken = s.step();
    let step = if taken == s.params().dt {
        format!("dt {}", Num(taken))
    } else {
        format!(
            "dt {} ({} shortened so that a whole number of steps fits each output interval)",
            Num(taken),
            Num(s.params().dt)
        )
    };
    caller.out(format_args!(
        "{}: ok ({} grains, {} with {step}, {} output times after t = 0 ({} rows with the initial state))",
        scene.display(),
        s.grains(),
        s.params().method.name(),
        s.outputs(),
        s.outputs() + 1
    ));
    let steps = est
        .steps
        .map_or("adaptive".to_string(), |n| format!("{n} steps"));
    let mut files = vec![];
    if est.energies_bytes > 0 {
        files.push(format!("energies.csv {}", human_bytes(est.energies_bytes)));
    }
    if est.snapshots_bytes > 0 {
        files.push(format!(
            "snapshots.csv {}",
            human_bytes(est.snapshots_bytes)
        ));
    }
    if est.pulses {
        files.push("pulses.csv (size depends on the pulses found)".to_string());
    }
    if est.tracks {
        files.push("tracks.csv (size depends on the pulses found)".to_string());
    }
    caller.out(format_args!(
        "  estimate: {steps}, {} grains; outputs at most about: {}",
        est.grains,
        if files.is_empty() {
            "summary.json only".to_string()
        } else {
            files.join(", ")
        }
    ));
    if est.total_bytes() > OUTPUT_LIMIT_BYTES {
        caller.out(format_args!(
            "  over the {} limit of `run`: it needs {}",
            human_bytes(OUTPUT_LIMIT_BYTES),
            caller.words.allow
        ));
    }
    caller.out(format_args!(
        "  memory: at most about {} (estimated upper bound: {} bytes per grain with {} and the \
         outputs asked for, and {} for the program)",
        human_bytes(m.bytes),
        m.per_grain,
        m.method.name(),
        human_bytes(grainchain_engine::MEMORY_BASE_BYTES)
    ));
    Ok(())
}
