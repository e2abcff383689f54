//! Writing results: atomic files, CSV tables and the run summary.

pub mod atomic;
pub mod plot;
pub mod run_output;

pub use atomic::AtomicFile;
