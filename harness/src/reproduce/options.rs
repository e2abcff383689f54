//! What a `reproduce` run is asked for ([`Options`]), the figures it can make ([`Figure`], each
//! named by its unit in `figures/`) and the constants every unit plans with.

use crate::error::Error;
use std::path::PathBuf;

/// A figure `reproduce` can make, as `--only` names it. Each unit names its own figures
/// (`Figure::FIG1` in `figures/fig1.rs`, ...); the registry lists them all ([`Figure::ALL`], in
/// the paper's order).
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Figure {
    /// Its lower-case name (`fig1` .. `fig5`), as `--only` spells it.
    name: &'static str,
    /// What it shows (the help of `--only`).
    about: &'static str,
}

impl Figure {
    /// A figure named `name` (`--only`'s spelling) that shows `about`.
    pub(crate) const fn new(name: &'static str, about: &'static str) -> Self {
        Figure { name, about }
    }

    /// Its lower-case name (`fig1` .. `fig5`), as `--only` spells it.
    pub fn name(self) -> &'static str {
        self.name
    }

    /// What it shows.
    pub fn about(self) -> &'static str {
        self.about
    }
}

/// `Fig1` .. `Fig5`, as when `Figure` was an enum: the output folder's claim digests `--only`
/// in this form, so a folder made before still belongs to the same options.
impl std::fmt::Debug for Figure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let mut c = self.name.chars();
        if let Some(first) = c.next() {
            write!(f, "{}", first.to_ascii_uppercase())?;
        }
        f.write_str(c.as_str())
    }
}

/// What to run and where to write it.
#[derive(Clone, Debug)]
pub struct Options {
    /// Output directory.
    pub out: PathBuf,
    /// The scene directory (`scenes/`, holding `fig1-heavy-to-light.toml`,
    /// `fig3-standard-container.toml` and `containers/*.toml`).
    pub scenes: PathBuf,
    /// Figures to make; empty: all.
    pub only: Vec<Figure>,
    /// Length of the Fig. 4/5 runs in snapshots (default: the scene files', 4000). Shorter runs
    /// are for quick looks and the golden tests; the report says when it is not the default.
    pub snapshots: Option<u64>,
    /// Also run every figure at an eighth of the step (and a chaos twin of every container) and
    /// report the differences (requirement 6 of the issue). Several minutes.
    pub check_step: bool,
    /// Worker threads for the simulations (default 2; at least 1, at most one per job). The
    /// results do not depend on it.
    pub threads: usize,
    /// Show a progress bar on stderr (hidden anyway when stderr is not a terminal).
    pub progress: bool,
    /// Sections appended to REPORT.md, rendered by others: the CLI's `reproduce --members N`
    /// runs the containers as an ensemble study first and hands its section in here.
    pub appendix: Vec<String>,
    /// The scene files already read and parsed ([`crate::reproduce::claim`] reads the whole
    /// scene folder for its digest); the figures load theirs from here. Empty: read when loaded.
    pub files: crate::batch::scenes::SceneFiles,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            out: PathBuf::from("out/reproduce"),
            scenes: PathBuf::from("scenes"),
            only: Vec::new(),
            snapshots: None,
            check_step: false,
            threads: 2,
            progress: true,
            appendix: Vec::new(),
            files: Default::default(),
        }
    }
}

impl Options {
    /// Whether figure `f` is to be made: it is listed in [`Options::only`], or that list is
    /// empty.
    pub fn wants(&self, f: Figure) -> bool {
        self.only.is_empty() || self.only.contains(&f)
    }
}

/// The fewest and most snapshots a Fig. 4/5 run may be asked for (`--snapshots`, Python's
/// `snapshots`): 40, and a scene's most output times ([`grainchain_engine::MAX_OUTPUTS`]).
pub const SNAPSHOTS: (u64, u64) = (40, grainchain_engine::MAX_OUTPUTS);

/// The fewest threads (`--threads`, Python's `threads`).
pub const MIN_THREADS: u64 = 1;

/// A `reproduce` command as asked, before its checks ([`Request::check`]): the CLI's flags and
/// Python's arguments both come in as one, so both are held to one set of rules and messages.
#[derive(Clone, Debug)]
pub struct Request {
    /// Output directory.
    pub out: PathBuf,
    /// The scene directory.
    pub scenes: PathBuf,
    /// Figures to make; empty: all.
    pub only: Vec<Figure>,
    /// Length of the Fig. 4/5 runs in snapshots, within [`SNAPSHOTS`] (default: the scene
    /// files').
    pub snapshots: Option<u64>,
    /// Also run everything at an eighth of the step.
    pub check_step: bool,
    /// Threads, at least [`MIN_THREADS`].
    pub threads: u64,
    /// Members of the containers' ensemble: 0 (none) or at least 2 ([`check_members`]).
    pub members: u64,
    /// Delete the files grainchain wrote in a folder of another command or other inputs.
    pub force: bool,
}

/// A [`Request`] that passed its checks: the run's [`Options`], the ensemble's size and
/// whether to take over a folder of other inputs.
#[derive(Clone, Debug)]
pub struct Checked {
    /// What to run and where.
    pub options: Options,
    /// Members of the containers' ensemble (0: none).
    pub members: u64,
    /// `--force`.
    pub force: bool,
}

impl Request {
    /// Check every option against its rule ([`SNAPSHOTS`], [`MIN_THREADS`], [`check_members`]);
    /// a value out of range is [`Error::Usage`] naming the option (exit code 2). `progress`:
    /// show progress bars on stderr.
    pub fn check(self, progress: bool) -> Result<Checked, Error> {
        if let Some(n) = self.snapshots {
            within("snapshots", n, SNAPSHOTS.0, SNAPSHOTS.1)?;
        }
        within("threads", self.threads, MIN_THREADS, u64::MAX)?;
        check_members(self.members).map_err(|problem| Error::Usage {
            name: "members",
            problem,
        })?;
        let threads = usize::try_from(self.threads).map_err(|_| Error::Usage {
            name: "threads",
            problem: format!("{} threads do not fit this machine's word", self.threads),
        })?;
        Ok(Checked {
            options: Options {
                out: self.out,
                scenes: self.scenes,
                only: self.only,
                snapshots: self.snapshots,
                check_step: self.check_step,
                threads,
                progress,
                appendix: Vec::new(),
                files: Default::default(),
            },
            members: self.members,
            force: self.force,
        })
    }
}

/// `n` if it lies in `lo..=hi`, else [`Error::Usage`] saying the range.
fn within(name: &'static str, n: u64, lo: u64, hi: u64) -> Result<u64, Error> {
    if (lo..=hi).contains(&n) {
        Ok(n)
    } else {
        Err(Error::Usage {
            name,
            problem: format!("must be an integer from {lo} to {hi}, got {n}"),
        })
    }
}

/// The rule of the ensemble's size (`--members N`): 0 (no ensemble) or at least 2 (the
/// delete-one jackknife over members gives the intervals; over one member it is undefined and
/// was printed [NaN, NaN]).
pub fn check_members(n: u64) -> Result<u64, String> {
    if n == 1 {
        return Err(
            "an ensemble needs at least 2 members (its intervals are a jackknife over members); 0 runs none"
                .into(),
        );
    }
    Ok(n)
}

/// Longest run of the variant studies of container (a), in snapshots: they compare fits over
/// the same window with the default run's first snapshots, and the cost of a run grows with the
/// square of its length (the active window grows with time), so they stop at half the paper's
/// 4000 snapshots.
pub const VARIANT_SNAPSHOTS: u64 = 2000;

/// The step-size check compares with a run at `dt / STEP_FACTOR`.
pub const STEP_FACTOR: f64 = 8.0;

#[cfg(test)]
mod tests {
    use super::*;

    fn request() -> Request {
        Request {
            out: PathBuf::from("out/x"),
            scenes: PathBuf::from("scenes"),
            only: Vec::new(),
            snapshots: None,
            check_step: false,
            threads: 2,
            members: 0,
            force: false,
        }
    }

    /// The message of a request that fails its checks.
    fn refusal(r: Request) -> String {
        match r.check(false) {
            Err(e @ Error::Usage { .. }) => e.to_string(),
            Err(e) => panic!("not a usage error: {e}"),
            Ok(_) => panic!("accepted"),
        }
    }

    /// Every option's rule, at its bounds, with the option's name in the message; a request
    /// inside them becomes the run's options unchanged.
    #[test]
    fn a_request_is_held_to_one_set_of_rules() {
        let (lo, hi) = SNAPSHOTS;
        for n in [lo, hi] {
            let r = Request {
                snapshots: Some(n),
                ..request()
            };
            assert_eq!(r.check(false).unwrap().options.snapshots, Some(n));
        }
        for n in [lo - 1, hi + 1] {
            let m = refusal(Request {
                snapshots: Some(n),
                ..request()
            });
            assert_eq!(
                m,
                format!("snapshots: must be an integer from {lo} to {hi}, got {n}")
            );
        }
        let m = refusal(Request {
            threads: 0,
            ..request()
        });
        assert!(
            m.starts_with("threads: must be an integer from 1 to "),
            "{m}"
        );
        let m = refusal(Request {
            members: 1,
            ..request()
        });
        assert!(
            m.starts_with("members: an ensemble needs at least 2 members"),
            "{m}"
        );
        for members in [0, 2] {
            let c = Request {
                members,
                threads: 3,
                ..request()
            }
            .check(true)
            .unwrap();
            assert_eq!((c.members, c.options.threads), (members, 3));
            assert!(c.options.progress);
        }
    }

    /// Figures by name, in any case; an unknown name lists the figures.
    #[test]
    fn figures_are_found_by_name() {
        assert!(Figure::named("FIG4") == Ok(Figure::FIG4));
        let e = Figure::named("fig9").err().unwrap();
        assert_eq!(e, "no figure `fig9` (the figures: fig1, fig3, fig4, fig5)");
    }
}
