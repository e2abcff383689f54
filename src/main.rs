//! The `grainchain` command-line tool.

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
use grainchain::error::Error;
use grainchain::report::outdir::{files_with, value_digest, Claim};
use grainchain::report::run_output::{default_out_dir, output_files, run_scene};
use grainchain::report::{fnv1a, outdir::OutDir};
use grainchain_engine::file::{parse_toml, read_text, FileKind, SceneFile};
use grainchain_engine::format::{human_bytes, seconds, Num};
use grainchain_engine::{LimitWords, MemoryEstimate, Scene, OUTPUT_LIMIT_BYTES};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// `println!` that does not panic when stdout is closed (`grainchain ... | head`): a line nobody
/// reads is dropped, the run goes on and its files are written.
macro_rules! out {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout(), $($t)*);
    }};
}

#[derive(Parser)]
#[command(
    name = "grainchain",
    version,
    about = "Granular chain simulator and validation harness (Hong, PRL 94, 108001, 2005)"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a scene and write CSV files and summary.json.
    Run {
        /// The scene file (TOML).
        scene: PathBuf,
        /// Output directory (default: out/<scene name>).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Run even if the outputs are estimated at more than 1 GB (see `check`).
        #[arg(long)]
        allow_large_output: bool,
        /// Delete the files grainchain wrote in an --out folder of another command or other
        /// inputs (only those, unchanged; a folder holding anything else is refused even so).
        #[arg(long)]
        force: bool,
    },
    /// Check a scene file without running it.
    Check {
        /// The scene file (TOML).
        scene: PathBuf,
        /// Check even if the simulation is estimated to need more than 1 GB of memory.
        #[arg(long)]
        allow_large_output: bool,
    },
    /// Work-precision study: run time against error for every integrator (CSV + SVG).
    WorkPrecision {
        /// Output directory.
        #[arg(long, default_value = "out/work-precision")]
        out: PathBuf,
        /// Fewer points and shorter problems (a smoke run).
        #[arg(long)]
        quick: bool,
        /// Only these problems (comma-separated).
        #[arg(long, value_delimiter = ',', value_parser = grainchain::work_precision::Problem::NAMES)]
        only: Vec<String>,
        /// Timing repeats per point (the median is reported).
        #[arg(long, default_value_t = 3)]
        repeats: usize,
        /// Delete the files grainchain wrote in an --out folder of another command or other
        /// inputs (only those, unchanged; a folder holding anything else is refused even so).
        #[arg(long)]
        force: bool,
    },
    /// Reproduce the paper (Hong 2005): every figure as CSV and SVG, and REPORT.md comparing every
    /// number the paper states with ours.
    Reproduce {
        /// Output directory.
        #[arg(long, default_value = "out/reproduce")]
        out: PathBuf,
        /// Only these figures, comma-separated.
        #[arg(long, value_enum, value_delimiter = ',')]
        only: Vec<grainchain::reproduce::Figure>,
        /// Directory of the scene files.
        #[arg(long, default_value = "scenes")]
        scenes: PathBuf,
        /// Length of the Fig. 4/5 runs in snapshots (default: the scene files', 4000; at most
        /// 1e9, a scene's most output times).
        #[arg(long, value_parser = clap::value_parser!(u64).range(40..=grainchain_engine::MAX_OUTPUTS))]
        snapshots: Option<u64>,
        /// Also run everything at an eighth of the step and report the differences (minutes).
        #[arg(long)]
        check_step: bool,
        /// Threads for independent simulations (at least 1).
        #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u64).range(1..))]
        threads: u64,
        /// Also run every container as an ensemble of N members (multiple time stepping) and
        /// give gamma and alpha with intervals over members (minutes; see docs/studies.md). At least 2:
        /// the intervals are a jackknife over members, undefined for one.
        #[arg(long, default_value_t = 0, value_parser = members_arg)]
        members: u64,
        /// Delete the files grainchain wrote in an --out folder of another command or other
        /// inputs (only those, unchanged; a folder holding anything else is refused even so).
        #[arg(long)]
        force: bool,
    },
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
    Units {
        /// Grain diameter in metres (1e-6 to 1; the material is stainless steel, its eta the
        /// paper's 5657, both printed).
        #[arg(long, default_value_t = 1e-3, value_parser = grain_diameter, allow_negative_numbers = true)]
        diameter: f64,
    },
}

#[derive(Subcommand)]
enum ExportCommand {
    /// The scene as a LAMMPS input deck (in.lammps) and data file (data.lammps) for
    /// `pair_style granular`: Hertz and linear contacts, the interface rule's laws per type
    /// pair, masses per atom, walls as fixed atoms, the striker, velocity Verlet at the scene's
    /// step, dumps of the regions and snapshots (docs/lammps.md).
    Lammps {
        /// The scene file (TOML).
        scene: PathBuf,
        /// Output directory (default: out/lammps-<scene name>).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Delete the files grainchain wrote in an --out folder of another command or other
        /// inputs (only those, unchanged; a folder holding anything else is refused even so).
        #[arg(long)]
        force: bool,
    },
}

#[derive(clap::Args)]
struct DesignArgs {
    /// The design file (TOML; see designs/).
    file: PathBuf,
    /// Output directory (default: out/design-<file name>).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Run only island K of N (1-based; seed + K - 1) and keep its journal in
    /// evaluations/; write the outputs afterwards with --merge.
    #[arg(long)]
    shard: Option<grainchain::study::Shard>,
    /// Do not search: write the outputs from every island's journal in evaluations/.
    #[arg(long, conflicts_with = "shard")]
    merge: bool,
    /// Go on from the journal of an interrupted search (the same seed replays the same
    /// generations; designs in the journal are not run again).
    #[arg(long, conflicts_with = "merge")]
    resume: bool,
    /// Threads (default: all cores).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    threads: Option<u64>,
    /// Delete the files grainchain wrote in an --out folder of another command or another
    /// design file (only those, unchanged).
    #[arg(long)]
    force: bool,
}

#[derive(clap::Args)]
struct StudyArgs {
    /// The sweep file (TOML; see studies/).
    sweep: PathBuf,
    /// Output directory (default: out/study-<sweep name>).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Run only part K of N (1-based) and write its member files; merge afterwards with
    /// --merge.
    #[arg(long)]
    shard: Option<grainchain::study::Shard>,
    /// Do not run anything: merge the member files of every shard (from --out and --from)
    /// into the study's outputs.
    #[arg(long, conflicts_with = "shard")]
    merge: bool,
    /// More directories holding member files (`members/`) of shards, comma-separated.
    #[arg(long, value_delimiter = ',')]
    from: Vec<PathBuf>,
    /// Keep member files already written for this sweep file and run only the missing jobs.
    #[arg(long, conflicts_with = "merge")]
    resume: bool,
    /// With --merge: use the members present even if some are missing (a look at a study
    /// whose shards are still running; STUDY.md says what is missing).
    #[arg(long, requires = "merge")]
    partial: bool,
    /// Only check the sweep file and build every job's scene (nothing runs, nothing is written).
    #[arg(long, conflicts_with_all = ["merge", "shard", "resume"])]
    check: bool,
    /// Threads (default: all cores).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    threads: Option<u64>,
    /// Delete the files grainchain wrote in an --out folder of another command or another
    /// sweep (only those, unchanged; a folder holding anything else is refused even so).
    #[arg(long, conflicts_with = "check")]
    force: bool,
    /// Plan or run even if the member files (or the job list) are estimated at more than 1 GB.
    #[arg(long)]
    allow_large_output: bool,
}

fn progress_bar(len: u64, label: &str) -> ProgressBar {
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

fn work_precision(
    out: PathBuf,
    quick: bool,
    only: Vec<String>,
    repeats: usize,
    force: bool,
) -> Result<(), Error> {
    use grainchain::work_precision::{self as wp, Problem};
    // clap has checked the names (a wrong one exits with code 2).
    let problems: Vec<Problem> = Problem::ALL
        .into_iter()
        .filter(|p| only.is_empty() || only.iter().any(|n| n == p.name()))
        .collect();
    let cfg = wp::Config {
        quick,
        repeats,
        ..Default::default()
    };
    let options = format!("quick={quick} only={only:?} repeats={repeats}");
    let inputs = BTreeMap::from([("options".to_string(), fnv1a(options.as_bytes()))]);
    let dir = OutDir::claim(&out, "work-precision", inputs, None, force)?;
    let pb = ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr());
    pb.set_style(
        ProgressStyle::with_template("{spinner} {elapsed} {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_spinner()),
    );
    let study = wp::run(&cfg, &problems, |label| pb.set_message(label.to_string()));
    pb.finish_and_clear();
    let study = study?;
    study.write(&out)?;
    if !study.points.is_empty() {
        out!(
            "{:<14} {:<13} {:>11} {:>11} {:>10} {:>9}",
            "problem",
            "method",
            "setting",
            "error",
            "seconds",
            "evals"
        );
    }
    for p in &study.points {
        if p.failure.is_empty() {
            out!(
                "{:<14} {:<13} {:>11.3e} {:>11.3e} {:>10.4} {:>9}",
                p.problem,
                p.method,
                p.setting,
                p.error,
                p.seconds,
                p.force_evals
            );
        } else {
            // `failed: ...` or `not evaluated: ...` (no number is printed then).
            out!(
                "{:<14} {:<13} {:>11.3e} {}",
                p.problem,
                p.method,
                p.setting,
                p.failure
            );
        }
    }
    if let Some(s) = &study.statistics {
        out!("{}", s.table().trim_end());
    }
    dir.finish(&files_with(&out, &[".csv", ".svg"])?)?;
    out!("wrote {}", out.display());
    Ok(())
}

fn reproduce(
    mut opts: grainchain::reproduce::Options,
    members: u64,
    force: bool,
) -> Result<(), Error> {
    let dir = grainchain::reproduce::claim(&opts, members, force)?;
    // `--members N`: the containers as an ensemble study (the study layer), whose section REPORT.md
    // ends with; it runs first, so a failed ensemble writes no report.
    let wants_containers = opts.wants(grainchain::reproduce::Figure::FIG4)
        || opts.wants(grainchain::reproduce::Figure::FIG5);
    if members > 0 && wants_containers {
        let containers =
            grainchain::batch::scenes::container_sources(&opts.scenes.join("containers"))?;
        let (st, wall) = grainchain::study::reproduce_ensemble(
            &opts.scenes,
            &containers,
            members,
            opts.snapshots,
            &opts.out.join("ensemble"),
            opts.threads,
            opts.progress,
        )?;
        let section = grainchain::study::reproduce_section(&st, wall, opts.threads);
        opts.appendix.push(section);
    }
    let o = grainchain::reproduce::run(&opts)?;
    dir.finish(&files_with(&opts.out, &[".csv", ".svg", ".md"])?)?;
    out!(
        "reproduce: {} simulations in {:.1} s; wrote {} (REPORT.md)",
        o.runs.len(),
        o.wall,
        opts.out.display()
    );
    Ok(())
}

fn design(args: DesignArgs) -> Result<(), Error> {
    let out = args.out.clone().unwrap_or_else(|| {
        let stem = args.file.file_stem().unwrap_or_default().to_string_lossy();
        PathBuf::from(format!("out/design-{stem}"))
    });
    let opts = grainchain::design::Options {
        file: args.file.clone(),
        out: out.clone(),
        threads: args.threads.map_or_else(
            || std::thread::available_parallelism().map_or(1, |n| n.get()),
            |t| t as usize,
        ),
        shard: args.shard,
        merge: args.merge,
        resume: args.resume,
        force: args.force,
        progress: true,
    };
    let t = std::time::Instant::now();
    let s = grainchain::design::run(&opts)?;
    let best = s
        .best
        .map_or_else(|| "none".to_string(), |b| format!("{b:.4}"));
    if s.wrote_outputs {
        eprintln!(
            "design {}: {} designs evaluated ({} known), best objective {best}, in {:.1} s on {} \
             threads; wrote {}/DESIGN.md",
            args.file.display(),
            s.evaluated,
            s.known,
            t.elapsed().as_secs_f64(),
            s.threads,
            out.display()
        );
    } else {
        eprintln!(
            "design {}: island evaluated {} designs ({} known), best objective {best}, in {:.1} \
             s on {} threads; when every island has run: grainchain design {} --merge --out {}",
            args.file.display(),
            s.evaluated,
            s.known,
            t.elapsed().as_secs_f64(),
            s.threads,
            args.file.display(),
            out.display()
        );
    }
    Ok(())
}

fn study(args: StudyArgs) -> Result<(), Error> {
    let StudyArgs {
        sweep,
        out,
        shard,
        merge,
        from,
        resume,
        partial,
        threads,
        check,
        force,
        allow_large_output,
    } = args;
    use grainchain::study;
    for d in &from {
        if !d.join("members").is_dir() {
            return Err(Error::Io {
                path: d.join("members"),
                source: std::io::Error::new(
                    std::io::ErrorKind::NotFound,
                    "--from: no member folder here (give the --out folder of a shard)",
                ),
            });
        }
    }
    let sf = study::SweepFile::load(&sweep)?;
    if let Some(e) = sf
        .size_refusal(&sweep, WORDS)
        .filter(|_| !allow_large_output)
    {
        return Err(e.into());
    }
    let out = out.unwrap_or_else(|| PathBuf::from(format!("out/study-{}", sf.sweep.name)));
    let jobs = study::plan(&sf).len();
    if check {
        // The study's own checks before it claims its folder (`check_scenes`), and every job's
        // scene as the study builds it: `--check` passes what the study does not refuse before
        // running.
        study::check_scenes(&sf)?;
        for j in study::plan(&sf) {
            study::job_scene(&sf, &j)?;
        }
        let s = &sf.sweep;
        out!(
            "{}: ok ({} jobs: {} containers x {} members{}, {} snapshots each; run digest {})",
            sweep.display(),
            jobs,
            s.containers.len(),
            s.members,
            s.random.as_ref().map_or(String::new(), |r| format!(
                ", {} random x {}",
                r.count, r.members
            )) + &s.search.as_ref().map_or(String::new(), |x| format!(
                ", {} readings x {} containers x {}",
                x.count,
                x.scenes.len(),
                x.members
            )),
            s.snapshots,
            sf.digest
        );
        return Ok(());
    }
    // The folder belongs to this sweep (its inputs, not the build: members of another build are
    // refused one by one, and --resume runs them again). Shards of one study share it (the
    // folder's lock shared, each its own exclusively); a full run or a merge holds the folder's
    // exclusively, so it never runs beside a shard.
    if !merge {
        // A bad setting of the sweep file is reported before the folder is made.
        study::check_scenes(&sf)?;
    }
    let dir = study::claim(&sf, &sweep, &out, shard, force)?;
    if !merge {
        let threads = threads.map_or_else(
            || std::thread::available_parallelism().map_or(2, |n| n.get()),
            |t| t as usize,
        );
        let opts = study::Options {
            out: out.clone(),
            shard: shard.unwrap_or(study::Shard::ALL),
            threads,
            resume,
            progress: true,
        };
        let r = study::run_jobs(&sf, &opts)?;
        for why in &r.rerun {
            out!("ran again: {why}");
        }
        out!(
            "study {}: shard {}: ran {} of {} members ({} kept from an earlier run) in {:.1} s \
             on {} threads ({} s of member time)",
            sf.sweep.name,
            opts.shard,
            r.ran,
            jobs,
            r.kept,
            r.wall,
            // The pool's threads (`worker_threads`: at most one per job run and what the
            // machine runs at once): say how many ran.
            grainchain_engine::worker_threads(threads, r.ran),
            seconds(r.job_seconds)
        );
        if shard.is_some() {
            out!(
                "wrote {}/members; when every shard has run: grainchain study {} --merge --out {}",
                out.display(),
                sweep.display(),
                out.display()
            );
            return Ok(());
        }
    }
    let mut dirs = vec![out.clone()];
    dirs.extend(from);
    let st = study::merge_with(&sf, &dirs, &out, partial)?;
    dir.finish(&files_with(&out, &[".csv", ".svg", ".md"])?)?;
    if !st.missing.is_empty() {
        out!(
            "partial merge: {} members missing ({})",
            st.missing.len(),
            st.missing.join(", ")
        );
    }
    for k in &st.containers {
        if let Some(e) = k.fit.est {
            out!(
                "({}) gamma of the mean over [{}, {}]: {:.3} [{:.3}, {:.3}] ({} members)",
                k.key,
                k.fit.t_lo,
                k.fit.t_hi,
                e.value,
                e.ci_lo,
                e.ci_hi,
                e.n
            );
        } else {
            out!("({}) no gamma of the mean: {}", k.key, k.fit.why_missing());
        }
    }
    out!("wrote {} (STUDY.md)", out.display());
    Ok(())
}

fn real_main() -> Result<(), Error> {
    // `--version` says which revision built the binary (the program that files record).
    let program = grainchain::program();
    let version = program.strip_prefix("grainchain ").unwrap_or(program);
    let matches = Cli::command().version(version).get_matches();
    let cli = Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.exit());
    match cli.command {
        Command::Run {
            scene,
            out,
            allow_large_output,
            force,
        } => run_command(scene, out, allow_large_output, force),
        Command::Check {
            scene,
            allow_large_output,
        } => check_command(scene, allow_large_output),
        Command::WorkPrecision {
            out,
            quick,
            only,
            repeats,
            force,
        } => work_precision(out, quick, only, repeats, force),
        Command::Reproduce {
            out,
            only,
            scenes,
            snapshots,
            check_step,
            threads,
            members,
            force,
        } => {
            let opts = grainchain::reproduce::Options {
                appendix: Vec::new(),
                only,
                out,
                scenes,
                snapshots,
                check_step,
                threads: threads as usize,
                progress: true,
            };
            reproduce(opts, members, force)
        }
        Command::Study(args) => study(args),
        Command::Design(args) => design(args),
        Command::Export(ExportCommand::Lammps { scene, out, force }) => {
            export_lammps(scene, out, force)
        }
        Command::Units { diameter } => {
            let s = grainchain_engine::units::SiScale::hertz(
                diameter,
                grainchain_engine::units::STAINLESS_STEEL,
                grainchain_engine::paper::ETA,
            );
            out!("{}", serde_json::to_string_pretty(&s)?);
            Ok(())
        }
    }
}

/// `grainchain export lammps`: the deck and data file into a claimed output folder.
fn export_lammps(path: PathBuf, out: Option<PathBuf>, force: bool) -> Result<(), Error> {
    use grainchain::export::lammps;
    let parsed = parse_toml::<SceneFile>(&read_text(&path)?, &path, FileKind::Scene)?;
    let inputs = BTreeMap::from([("scene".to_string(), value_digest(&parsed.value)?)]);
    let scene = Scene::from_file(parsed.typed, &path)?;
    let deck = lammps::deck(&scene)?;
    let out = out.unwrap_or_else(|| lammps::default_out_dir(&scene));
    let dir = OutDir::claim_with(
        &out,
        Claim {
            command: "export-lammps",
            inputs,
            force,
            // The scene file is never deleted, even inside --out.
            protect: vec![path.clone()],
            ..Claim::default()
        },
    )?;
    let written = lammps::write(&deck, &out)?;
    dir.finish(&written)?;
    out!(
        "{}: {} atoms, {} steps of {} in LAMMPS (diameter {}); wrote {} (run it there: lmp -in {})",
        scene.name(),
        deck.rest.len(),
        deck.outputs * deck.steps_per_output,
        Num(deck.dt),
        Num(deck.diameter),
        out.display(),
        lammps::INPUT
    );
    Ok(())
}

/// `grainchain run`: refuse outputs over the limit, say a shortened step, run with a progress
/// bar, print the summary line.
fn run_command(
    path: PathBuf,
    out: Option<PathBuf>,
    allow_large_output: bool,
    force: bool,
) -> Result<(), Error> {
    // The file is read once (a pipe or a FIFO can be read only once) and parsed once.
    let parsed = parse_toml::<SceneFile>(&read_text(&path)?, &path, FileKind::Scene)?;
    memory_limit(&parsed.typed, &path, allow_large_output)?;
    let inputs = BTreeMap::from([("scene".to_string(), value_digest(&parsed.value)?)]);
    let scene = Scene::from_file(parsed.typed, &path)?;
    for w in scene.warnings() {
        eprintln!("warning: {}: {w}", path.display());
    }
    let est = scene.estimate();
    if let Some(e) = est.refusal(&path, WORDS).filter(|_| !allow_large_output) {
        return Err(e.into());
    }
    let out = out.unwrap_or_else(|| default_out_dir(&scene));
    if !scene.params().method.is_adaptive() {
        let taken = scene.params().fitted_step(scene.output_interval());
        if taken != scene.params().dt {
            eprintln!(
                "note: {}: dt shortened from {} to {} so that a whole number of steps fits each output interval ({})",
                scene.name(),
                Num(scene.params().dt),
                Num(taken),
                Num(scene.output_interval())
            );
        }
    }
    let dir = OutDir::claim_with(
        &out,
        Claim {
            command: "run",
            inputs,
            force,
            // The scene file is never deleted, even inside --out.
            protect: vec![path.clone()],
            ..Claim::default()
        },
    )?;
    let pb = progress_bar(scene.outputs(), scene.name());
    let summary = run_scene(&scene, &out, |done, _| pb.set_position(done));
    pb.finish_and_clear();
    let summary = summary?;
    dir.finish(&output_files(&scene))?;
    out!(
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
    );
    Ok(())
}

/// Refuse a scene whose simulation would need more than [`OUTPUT_LIMIT_BYTES`] of memory
/// (estimated from the grain counts of the file, before anything is built), unless `allow`. A
/// file that does not parse, or over the hard limit of grains, is left to the scene check.
fn memory_limit(f: &SceneFile, path: &Path, allow: bool) -> Result<(), Error> {
    let m = MemoryEstimate::of_run(f);
    match m.refusal(path, WORDS).filter(|_| !allow) {
        Some(e) => Err(e.into()),
        None => Ok(()),
    }
}

/// `grainchain check`: the scene's checks, then the estimate of steps, output sizes and memory.
fn check_command(scene: PathBuf, allow_large_output: bool) -> Result<(), Error> {
    let parsed = parse_toml::<SceneFile>(&read_text(&scene)?, &scene, FileKind::Scene)?;
    memory_limit(&parsed.typed, &scene, allow_large_output)?;
    let m = MemoryEstimate::of_run(&parsed.typed);
    let s = Scene::from_file(parsed.typed, &scene)?;
    for w in s.warnings() {
        eprintln!("warning: {}: {w}", scene.display());
    }
    let est = s.estimate();
    // The step the run takes (fitted to the output interval), and the one asked for if it differs.
    let taken = s.params().fitted_step(s.output_interval());
    let step = if taken == s.params().dt {
        format!("dt {}", Num(taken))
    } else {
        format!(
            "dt {} ({} shortened so that a whole number of steps fits each output interval)",
            Num(taken),
            Num(s.params().dt)
        )
    };
    out!(
        "{}: ok ({} grains, {} with {step}, {} output times after t = 0 ({} rows with the initial state))",
        scene.display(),
        s.grains(),
        s.params().method.name(),
        s.outputs(),
        s.outputs() + 1
    );
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
    out!(
        "  estimate: {steps}, {} grains; outputs at most about: {}",
        est.grains,
        if files.is_empty() {
            "summary.json only".to_string()
        } else {
            files.join(", ")
        }
    );
    if est.total_bytes() > OUTPUT_LIMIT_BYTES {
        out!(
            "  over the {} limit of `run`: it needs --allow-large-output",
            human_bytes(OUTPUT_LIMIT_BYTES)
        );
    }
    out!(
        "  memory: at most about {} (estimated upper bound: {} bytes per grain with {} and the \
         outputs asked for, and {} for the program)",
        human_bytes(m.bytes),
        m.per_grain,
        m.method.name(),
        human_bytes(grainchain_engine::MEMORY_BASE_BYTES)
    );
    Ok(())
}

/// The CLI's words in the refusals of a scene or study over the size limits.
const WORDS: LimitWords = LimitWords {
    check: "`grainchain check`",
    allow: "--allow-large-output",
};

/// `reproduce --members N`: 0 (no ensemble) or at least 2 (the delete-one jackknife over
/// members gives the intervals; over one member it is undefined and printed [NaN, NaN]).
fn members_arg(s: &str) -> Result<u64, String> {
    let n: u64 = s.parse().map_err(|e| format!("{e}"))?;
    if n == 1 {
        return Err(
            "an ensemble needs at least 2 members (its intervals are a jackknife over members); 0 runs none"
                .into(),
        );
    }
    Ok(n)
}

/// A command-line number that must be finite and > 0 (clap reports a failure as a usage error,
/// exit code 2, naming the flag).
/// `units --diameter`: a finite number within [`grainchain_engine::units::DIAMETER_RANGE_M`].
fn grain_diameter(s: &str) -> Result<f64, String> {
    let x: f64 = s.parse().map_err(|e| format!("{e}"))?;
    let (lo, hi) = grainchain_engine::units::DIAMETER_RANGE_M;
    if (lo..=hi).contains(&x) {
        Ok(x)
    } else {
        Err(format!(
            "a grain diameter must be between {} m and {} m (a steel sphere from a micrometre to \
             a metre), got {}",
            Num(lo),
            Num(hi),
            Num(x)
        ))
    }
}

fn main() -> ExitCode {
    // Member files, manifests and digests record the revision that built this binary.
    grainchain::set_revision(grainchain_revision::GIT);
    // SIGINT / SIGTERM: delete the temporary output files of this run (an interrupted run never
    // leaves `.partial` files behind), then exit with the conventional 130.
    // Only a command that had output files open says it removed them (`check` writes none).
    let _ = ctrlc::set_handler(|| {
        match grainchain::report::atomic::remove_partials() {
            0 => eprintln!("interrupted"),
            n => eprintln!("interrupted: {n} partial output file(s) removed"),
        }
        std::process::exit(130);
    });
    match real_main() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(e.exit_code() as u8)
        }
    }
}
