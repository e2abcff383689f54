//! `grainchain export lammps`: the deck and data file of a scene into a claimed output folder.

use super::{claim_for_scene, read_scene, Caller};
use crate::error::Error;
use crate::export::lammps as target;
use grainchain_engine::format::Num;
use grainchain_engine::Scene;
use std::path::PathBuf;

/// What `grainchain export lammps` is asked for.
#[derive(Clone, Debug, Default)]
pub struct LammpsOptions {
    /// The scene file (TOML).
    pub scene: PathBuf,
    /// Output directory (default: `out/lammps-<scene name>`).
    pub out: Option<PathBuf>,
    /// Delete the files grainchain wrote in a folder of another command or other inputs.
    pub force: bool,
}

/// `grainchain export lammps`: read and check the scene, build the deck (a scene LAMMPS cannot
/// represent is refused with the reason), claim the folder, write the deck and data file, say
/// what was written.
pub fn lammps(opts: &LammpsOptions, caller: &Caller) -> Result<(), Error> {
    let path = &opts.scene;
    let parsed = read_scene(path)?;
    let scene = Scene::from_file(parsed.typed, path)?;
    let deck = target::deck(&scene)?;
    let out = opts
        .out
        .clone()
        .unwrap_or_else(|| target::default_out_dir(&scene));
    let dir = claim_for_scene(&out, "export-lammps", &parsed.value, path, opts.force)?;
    let written = target::write(&deck, &out)?;
    dir.finish(&written)?;
    caller.out(format_args!(
        "{}: {} atoms, {} steps of {} in LAMMPS (diameter {}); wrote {} (run it there: lmp -in {})",
        scene.name(),
        deck.rest.len(),
        deck.outputs * deck.steps_per_output,
        Num(deck.dt),
        Num(deck.diameter),
        out.display(),
        target::INPUT
    ));
    Ok(())
}
