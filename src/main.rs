//! The `grainchain` command-line tool: the arguments parsed (clap, `args.rs`) into the options of
//! the harness's commands (`grainchain::commands`, where each command is one function), and the
//! error mapped to an exit code.

mod args;

use args::{Cli, Command, ExportCommand};
use clap::{CommandFactory, FromArgMatches};
use grainchain::commands::{self, design, export, run, study, units, work_precision, Caller};
use grainchain::error::Error;
use grainchain::report::limits::LimitWords;
use grainchain::reproduce::Request;
use std::process::ExitCode;

/// The CLI as the commands' caller: it speaks, and its words are its flags.
const CLI: Caller = Caller {
    speaks: true,
    words: LimitWords {
        check: "`grainchain check`",
        allow: "--allow-large-output",
    },
};

fn real_main() -> Result<(), Error> {
    // `--version` says which revision built the binary (the program that files record).
    let program = grainchain::program();
    let version = program.strip_prefix("grainchain ").unwrap_or(program);
    let matches = Cli::command().version(version).get_matches();
    let cli = Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.exit());
    match cli.command {
        Command::Run(a) => {
            let o = run::RunOptions {
                scene: a.scene,
                out: a.out,
                allow_large_output: a.allow_large_output,
                force: a.force,
            };
            run::run(&o, &CLI).map(drop)
        }
        Command::Check(a) => {
            let o = run::CheckOptions {
                scene: a.scene,
                allow_large_output: a.allow_large_output,
            };
            run::check(&o, &CLI)
        }
        Command::WorkPrecision(a) => {
            let o = work_precision::Options {
                out: a.out,
                quick: a.quick,
                only: a.only,
                repeats: a.repeats,
                force: a.force,
            };
            work_precision::work_precision(&o, &CLI).map(drop)
        }
        Command::Reproduce(a) => {
            let r = Request {
                out: a.out,
                scenes: a.scenes,
                only: a.only,
                snapshots: a.snapshots,
                check_step: a.check_step,
                threads: a.threads,
                members: a.members,
                force: a.force,
            };
            commands::reproduce::reproduce(r, &CLI).map(drop)
        }
        Command::Study(a) => {
            let o = study::Options {
                sweep: a.sweep,
                out: a.out,
                shard: a.shard,
                merge: a.merge,
                from: a.from,
                resume: a.resume,
                partial: a.partial,
                check: a.check,
                threads: a.threads,
                force: a.force,
                allow_large_output: a.allow_large_output,
            };
            study::study(&o, &CLI).map(drop)
        }
        Command::Design(a) => {
            let o = design::Options {
                file: a.file,
                out: a.out,
                shard: a.shard,
                merge: a.merge,
                resume: a.resume,
                threads: a.threads,
                force: a.force,
            };
            design::design(&o, &CLI).map(drop)
        }
        Command::Export(ExportCommand::Lammps(a)) => {
            let o = export::LammpsOptions {
                scene: a.scene,
                out: a.out,
                force: a.force,
            };
            export::lammps(&o, &CLI)
        }
        Command::Units(a) => units::units(a.diameter, &CLI).map(drop),
    }
}

fn main() -> ExitCode {
    // Member files, manifests and digests record the revision that built this binary.
    grainchain::set_revision(grainchain_revision::GIT);
    // SIGINT / SIGTERM: delete the temporary output files of this run (an interrupted run never
    // leaves `.partial` files behind), then exit with the conventional 130.
    // Only a command that had output files open says it removed them (`check` writes none).
    // SIGXFSZ (a write past the file-size limit, `ulimit -f`) would kill the process with no
    // word and leave a `.partial` file (issue 50): ignored, the write fails instead with EFBIG,
    // which the output's error names, and the partial file is removed like any failed write's.
    #[cfg(unix)]
    // SAFETY: setting a signal's disposition to SIG_IGN before any other thread exists.
    unsafe {
        libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
    }
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
