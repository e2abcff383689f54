//! The command line's vocabulary: the commands, their flags and help texts (clap), and clap's
//! first checks, which apply the library's rules (`reproduce`'s bounds and `--members`, `units
//! --diameter`). `main.rs` turns what they parse into the harness's options.

use clap::{Parser, Subcommand};
use grainchain::reproduce;
use std::path::PathBuf;

#[derive(Parser)]
#[command(
    name = "grainchain",
    version,
    about = "Granular chain simulator and validation harness (Hong, PRL 94, 108001, 2005)"
)]
pub(crate) struct Cli {
    #[command(subcommand)]
    pub(crate) command: Command,
}

#[derive(Subcommand)]
pub(crate) enum Command {
    /// Run a scene and write CSV files and summary.json.
    Run(RunArgs),
    /// Check a scene file without running it.
    Check(CheckArgs),
    /// Work-precision study: run time against error for every integrator (CSV + SVG).
    WorkPrecision(WorkPrecisionArgs),
    /// Reproduce the paper (Hong 2005): every figure as CSV and SVG, and REPORT.md comparing every
    /// number the paper states with ours.
    Reproduce(ReproduceArgs),
    /// Ensemble study of containers: E_R as a statistic over members, the local slope, gamma per
    /// decade, alpha by level, the energy budget and random containers (CSV, SVG, STUDY.md).
    Study(StudyArgs),
    /// Search a design space of granular protectors in real materials (a design file, TOML;
    /// see designs/): the force on the protected wall or target against the known designs
    /// (DESIGN.md, CSV, SVG, the best design as a scene file).
    Design(DesignArgs),
    /// Write a scene for another simulator (`lammps`: an input deck and a data file; see
    /// docs/lammps.md). A scene the target cannot represent is refused with the reason.
    #[command(subcommand)]
    Export(ExportCommand),
    /// Print the SI value of the program units for steel grains of a given diameter.
    Units(UnitsArgs),
}

#[derive(Subcommand)]
pub(crate) enum ExportCommand {
    /// The scene as a LAMMPS input deck (in.lammps) and data file (data.lammps) for
    /// `pair_style granular`: Hertz and linear contacts, the interface rule's laws per type
    /// pair, masses per atom, walls as fixed atoms, the striker, velocity Verlet at the scene's
    /// step, dumps of the regions and snapshots (docs/lammps.md).
    Lammps(LammpsArgs),
}

#[derive(clap::Args)]
pub(crate) struct DesignArgs {
    /// The design file (TOML; see designs/).
    pub(crate) file: PathBuf,
    /// Output directory (default: out/design-<file name>).
    #[arg(long)]
    pub(crate) out: Option<PathBuf>,
    /// Run only island K of N (1-based; seed + K - 1) and keep its journal in
    /// evaluations/; write the outputs afterwards with --merge.
    #[arg(long)]
    pub(crate) shard: Option<grainchain::study::Shard>,
    /// Do not search: write the outputs from every island's journal in evaluations/.
    #[arg(long, conflicts_with = "shard")]
    pub(crate) merge: bool,
    /// Go on from the journal of an interrupted search (the same seed replays the same
    /// generations; designs in the journal are not run again).
    #[arg(long, conflicts_with = "merge")]
    pub(crate) resume: bool,
    /// Threads (default: all cores).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    pub(crate) threads: Option<u64>,
    /// Delete the files grainchain wrote in an --out folder of another command or another
    /// design file (only those, unchanged).
    #[arg(long)]
    pub(crate) force: bool,
}

#[derive(clap::Args)]
pub(crate) struct StudyArgs {
    /// The sweep file (TOML; see studies/).
    pub(crate) sweep: PathBuf,
    /// Output directory (default: out/study-<sweep name>).
    #[arg(long)]
    pub(crate) out: Option<PathBuf>,
    /// Run only part K of N (1-based) and write its member files; merge afterwards with
    /// --merge.
    #[arg(long)]
    pub(crate) shard: Option<grainchain::study::Shard>,
    /// Do not run anything: merge the member files of every shard (from --out and --from)
    /// into the study's outputs.
    #[arg(long, conflicts_with = "shard")]
    pub(crate) merge: bool,
    /// More directories holding member files (`members/`) of shards, comma-separated.
    #[arg(long, value_delimiter = ',')]
    pub(crate) from: Vec<PathBuf>,
    /// Keep member files already written for this sweep file and run only the missing jobs.
    #[arg(long, conflicts_with = "merge")]
    pub(crate) resume: bool,
    /// With --merge: use the members present even if some are missing (a look at a study
    /// whose shards are still running; STUDY.md says what is missing).
    #[arg(long, requires = "merge")]
    pub(crate) partial: bool,
    /// Only check the sweep file and build every job's scene (nothing runs, nothing is written).
    #[arg(long, conflicts_with_all = ["merge", "shard", "resume"])]
    pub(crate) check: bool,
    /// Threads (default: all cores).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    pub(crate) threads: Option<u64>,
    /// Delete the files grainchain wrote in an --out folder of another command or another
    /// sweep (only those, unchanged; a folder holding anything else is refused even so).
    #[arg(long, conflicts_with = "check")]
    pub(crate) force: bool,
    /// Plan or run even if the member files (or the job list) are estimated at more than 1 GB.
    #[arg(long)]
    pub(crate) allow_large_output: bool,
}

#[derive(clap::Args)]
pub(crate) struct RunArgs {
    /// The scene file (TOML).
    pub(crate) scene: PathBuf,
    /// Output directory (default: out/<scene name>).
    #[arg(long)]
    pub(crate) out: Option<PathBuf>,
    /// Run even if the outputs are estimated at more than 1 GB (see `check`).
    #[arg(long)]
    pub(crate) allow_large_output: bool,
    #[arg(long, help = FORCE)]
    pub(crate) force: bool,
}

#[derive(clap::Args)]
pub(crate) struct CheckArgs {
    /// The scene file (TOML).
    pub(crate) scene: PathBuf,
    /// Check even if the simulation is estimated to need more than 1 GB of memory.
    #[arg(long)]
    pub(crate) allow_large_output: bool,
}

#[derive(clap::Args)]
pub(crate) struct WorkPrecisionArgs {
    /// Output directory.
    #[arg(long, default_value = "out/work-precision")]
    pub(crate) out: PathBuf,
    /// Fewer points and shorter problems (a smoke run).
    #[arg(long)]
    pub(crate) quick: bool,
    /// Only these problems (comma-separated).
    #[arg(long, value_delimiter = ',', value_parser = grainchain::work_precision::Benchmark::NAMES)]
    pub(crate) only: Vec<String>,
    /// Timing repeats per point (the median is reported).
    #[arg(long, default_value_t = 3)]
    pub(crate) repeats: usize,
    #[arg(long, help = FORCE)]
    pub(crate) force: bool,
}

#[derive(clap::Args)]
pub(crate) struct ReproduceArgs {
    /// Output directory.
    #[arg(long, default_value = "out/reproduce")]
    pub(crate) out: PathBuf,
    /// Only these figures, comma-separated.
    #[arg(long, value_enum, value_delimiter = ',')]
    pub(crate) only: Vec<reproduce::Figure>,
    /// Directory of the scene files.
    #[arg(long, default_value = "scenes")]
    pub(crate) scenes: PathBuf,
    /// Length of the Fig. 4/5 runs in snapshots (default: the scene files', 4000; at most
    /// 1e9, a scene's most output times).
    #[arg(long, value_parser = clap::value_parser!(u64).range(reproduce::SNAPSHOTS.0..=reproduce::SNAPSHOTS.1))]
    pub(crate) snapshots: Option<u64>,
    /// Also run everything at an eighth of the step and report the differences (minutes).
    #[arg(long)]
    pub(crate) check_step: bool,
    /// Threads for independent simulations (at least 1).
    #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u64).range(reproduce::MIN_THREADS..))]
    pub(crate) threads: u64,
    /// Also run every container as an ensemble of N members (multiple time stepping) and
    /// give gamma and alpha with intervals over members (minutes; see docs/studies.md). At least 2:
    /// the intervals are a jackknife over members, undefined for one.
    #[arg(long, default_value_t = 0, value_parser = members_arg)]
    pub(crate) members: u64,
    #[arg(long, help = FORCE)]
    pub(crate) force: bool,
}

#[derive(clap::Args)]
pub(crate) struct UnitsArgs {
    /// Grain diameter in metres (1e-6 to 1; the material is stainless steel, its eta the
    /// paper's 5657, both printed).
    #[arg(long, default_value_t = 1e-3, value_parser = grain_diameter, allow_negative_numbers = true)]
    pub(crate) diameter: f64,
}

#[derive(clap::Args)]
pub(crate) struct LammpsArgs {
    /// The scene file (TOML).
    pub(crate) scene: PathBuf,
    /// Output directory (default: out/lammps-<scene name>).
    #[arg(long)]
    pub(crate) out: Option<PathBuf>,
    #[arg(long, help = FORCE)]
    pub(crate) force: bool,
}

/// The help of `--force` of `run`, `work-precision`, `reproduce` and `export lammps` (no final
/// period: clap drops a doc comment's, and the text stays as it was).
pub(crate) const FORCE: &str = "Delete the files grainchain wrote in an --out folder of another \
                                command or other inputs (only those, unchanged; a folder holding \
                                anything else is refused even so)";

/// The library's rule for `--members` ([`reproduce::check_members`]), as clap's parser.
pub(crate) fn members_arg(s: &str) -> Result<u64, String> {
    reproduce::check_members(s.parse().map_err(|e| format!("{e}"))?)
}

/// The library's rule for `units --diameter` ([`grainchain::commands::units::diameter`]), as clap's parser.
pub(crate) fn grain_diameter(s: &str) -> Result<f64, String> {
    grainchain::commands::units::diameter(s.parse().map_err(|e| format!("{e}"))?)
}
