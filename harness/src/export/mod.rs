//! `grainchain export`: a scene written out for another simulator, built from the checked scene
//! (the engine's built chain, its laws and initial state), never re-derived from the file.
//! One file per target: [`lammps`] (an input deck and a data file for LAMMPS).

pub mod lammps;
