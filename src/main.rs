//! The `grainchain` command-line tool.

use clap::{Parser, Subcommand};
use grainchain::error::Error;
use grainchain::report::run_output::{default_out_dir, run_scene};
use grainchain::scene::Scene;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::path::PathBuf;
use std::process::ExitCode;

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
    },
    /// Check a scene file without running it.
    Check {
        /// The scene file (TOML).
        scene: PathBuf,
    },
    /// Print the SI value of the program units for steel grains of a given diameter.
    Units {
        /// Grain diameter in metres.
        #[arg(long, default_value_t = 1e-3)]
        diameter: f64,
    },
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

fn real_main() -> Result<(), Error> {
    let cli = Cli::parse();
    match cli.command {
        Command::Run { scene, out } => {
            let scene = Scene::load(&scene)?;
            let out = out.unwrap_or_else(|| default_out_dir(&scene));
            let steps = (scene.duration / scene.output_interval).floor() as u64;
            let pb = progress_bar(steps, &scene.name);
            let summary = run_scene(&scene, &out, |done, _| pb.set_position(done));
            pb.finish_and_clear();
            let summary = summary?;
            println!(
                "{}: {} steps ({} rejected), {} force evaluations, {:.3} s, max |dE/E0| = {:.2e}, {} of {} grains never touched; wrote {}",
                summary.scene,
                summary.steps,
                summary.rejected_steps,
                summary.force_evaluations,
                summary.wall_time_s,
                summary.max_relative_energy_error,
                summary.grains_untouched,
                summary.grains,
                out.display()
            );
            Ok(())
        }
        Command::Check { scene } => {
            let s = Scene::load(&scene)?;
            println!(
                "{}: ok ({} grains, {} with dt {}, {} output times)",
                scene.display(),
                s.grains,
                s.params.method.name(),
                s.params.dt,
                (s.duration / s.output_interval).floor()
            );
            Ok(())
        }
        Command::Units { diameter } => {
            if !(diameter.is_finite() && diameter > 0.0) {
                return Err(Error::Other(format!(
                    "--diameter must be a finite number > 0, got {diameter}"
                )));
            }
            let s = grainchain::units::SiScale::hertz(
                diameter,
                grainchain::units::STAINLESS_STEEL,
                grainchain::units::paper::ETA,
            );
            println!(
                "{}",
                serde_json::to_string_pretty(&s).map_err(|e| Error::Other(e.to_string()))?
            );
            Ok(())
        }
    }
}

fn main() -> ExitCode {
    match real_main() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(e.exit_code() as u8)
        }
    }
}
