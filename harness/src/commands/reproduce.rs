//! `grainchain reproduce`: the request checked, the folder claimed, the containers' ensemble
//! (`--members N`, a study) run first, then the figures and REPORT.md.

use super::Caller;
use crate::error::Error;
use crate::report::outdir::files_with;
use crate::reproduce::{self as rp, Figure, Outcome, Request};

/// `grainchain reproduce` (and Python's `reproduce`): check `request` ([`Request::check`]),
/// claim its folder, run the ensemble study of the containers if asked (its section ends
/// REPORT.md; it runs first, so a failed ensemble writes no report), reproduce the figures,
/// commit the folder and say what was done.
pub fn reproduce(request: Request, caller: &Caller) -> Result<Outcome, Error> {
    let rp::Checked {
        mut options,
        members,
        force,
    } = request.check(caller.speaks)?;
    let (dir, files) = rp::claim(&options, members, force)?;
    options.files = files;
    let wants_containers = options.wants(Figure::FIG4) || options.wants(Figure::FIG5);
    if members > 0 && wants_containers {
        let containers = crate::batch::scenes::container_sources(
            &options.scenes.join("containers"),
            &options.files,
        )?;
        let (st, wall) = crate::study::reproduce_ensemble(
            &options.scenes,
            &containers,
            members,
            options.snapshots,
            &options.out.join("ensemble"),
            options.threads,
            options.progress,
        )?;
        let section = crate::study::reproduce_section(&st, wall, options.threads);
        options.appendix.push(section);
    }
    let o = rp::run(&options)?;
    dir.finish(&files_with(&options.out, &[".csv", ".svg", ".md"])?)?;
    caller.out(format_args!(
        "reproduce: {} simulations in {:.1} s; wrote {} (REPORT.md)",
        o.runs.len(),
        o.wall,
        options.out.display()
    ));
    Ok(o)
}
