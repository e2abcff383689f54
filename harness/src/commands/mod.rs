//! The commands of the `grainchain` tool, each one function that does all of it: read the input
//! once, check it, claim the output folder, run, write and say what it did ([`run::run`],
//! [`run::check`], [`export::lammps`], [`work_precision::work_precision`],
//! [`reproduce::reproduce`], [`study::study`], [`design::design`], [`units::units`]). Each takes a
//! plain options struct defined here (no parser's types) and a [`Caller`]: the command-line tool
//! (`src/main.rs`) parses its arguments into the options and maps the error to an exit code; the
//! Python package calls the same functions with a silent caller and its own words.
//!
//! This is the harness's top layer: `reproduce --members N` runs an ensemble study before the
//! figures, and only a module above both `study` and `reproduce` may join them.

pub mod design;
pub mod export;
pub mod reproduce;
pub mod run;
pub mod study;
pub mod units;
pub mod work_precision;

use crate::error::Error;
use crate::report::limits::LimitWords;
use crate::report::outdir::{value_digest, Claim, OutDir};
use grainchain_engine::file::{parse_toml, read_text, FileKind, Parsed, SceneFile};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::collections::BTreeMap;
use std::fmt::Arguments;
use std::io::Write as _;
use std::path::Path;

/// Who runs a command: whether it speaks (lines on stdout and stderr, progress bars on stderr:
/// the command-line tool) or is silent (Python, which gets back what was done), and its words
/// for the refusals of inputs over the size limits (a flag, an argument).
#[derive(Clone, Copy, Debug)]
pub struct Caller {
    /// Print the commands' lines and progress bars.
    pub speaks: bool,
    /// The caller's words in the refusals of a scene or study over the size limits.
    pub words: LimitWords,
}

impl Caller {
    /// A line on stdout, if the caller speaks. A closed stdout (`grainchain ... | head`) does not
    /// stop the command: a line nobody reads is dropped, and the files are written.
    pub fn out(&self, line: Arguments<'_>) {
        if self.speaks {
            let _ = writeln!(std::io::stdout(), "{line}");
        }
    }

    /// A line on stderr (a warning, a note, what a search did), if the caller speaks.
    pub fn note(&self, line: Arguments<'_>) {
        if self.speaks {
            let _ = writeln!(std::io::stderr(), "{line}");
        }
    }

    /// A progress bar of `len` outputs labelled `label` on stderr (hidden unless the caller
    /// speaks, and by indicatif when stderr is not a terminal).
    pub fn outputs_bar(&self, len: u64, label: &str) -> ProgressBar {
        if !self.speaks {
            return ProgressBar::hidden();
        }
        let pb = ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::stderr());
        pb.set_style(
            ProgressStyle::with_template(
                "{prefix} [{bar:40}] {pos}/{len} outputs, {elapsed} elapsed, eta {eta}",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
        );
        pb.set_prefix(label.to_string());
        pb
    }

    /// A spinner with the elapsed time and a message on stderr (hidden unless the caller speaks).
    pub fn spinner(&self) -> ProgressBar {
        if !self.speaks {
            return ProgressBar::hidden();
        }
        let pb = ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr());
        pb.set_style(
            ProgressStyle::with_template("{spinner} {elapsed} {msg}")
                .unwrap_or_else(|_| ProgressStyle::default_spinner()),
        );
        pb
    }
}

/// Read the scene file at `path` once and parse it once (a pipe or a FIFO can be read only
/// once): its typed form, for the memory estimate and the check, and its values, for the output
/// folder's digest.
pub fn read_scene(path: &Path) -> Result<Parsed<SceneFile>, Error> {
    Ok(parse_toml(&read_text(path)?, path, FileKind::Scene)?)
}

/// Claim `out` for `command` run on the scene file `path` whose values are `value` (`run`,
/// `export-lammps`): the folder belongs to the scene as parsed (comments and spelling do not
/// count), and the scene file is never deleted, even inside `out`.
pub fn claim_for_scene(
    out: &Path,
    command: &'static str,
    value: &toml::Value,
    path: &Path,
    force: bool,
) -> Result<OutDir, Error> {
    let inputs = BTreeMap::from([("scene".to_string(), value_digest(value)?)]);
    OutDir::claim_with(
        out,
        Claim {
            command,
            inputs,
            force,
            protect: vec![path.to_path_buf()],
            ..Claim::default()
        },
    )
}
