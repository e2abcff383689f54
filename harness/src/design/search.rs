//! The search: a genetic algorithm over one choice per section (the `genetic_algorithm`
//! crate: list genotype, tournament selection, uniform crossover, single-gene mutation, seeded,
//! fitness in parallel), every evaluation kept in a journal (`island-K-of-N.csv`, appended as
//! they finish) so an interrupted search resumes: the same seed replays the same generations
//! and finds each design it already ran in the journal.
//!
//! What `--resume` and `--merge` read is checked (issue 38): every journal line carries its
//! checksum, a finished island leaves a convergence file recording its journal's lines (and its
//! own checksum), and a merge needs every island 1..N of N. Only a last line cut by an
//! interruption is dropped (by `--resume`); anything else damaged, foreign or missing is an
//! error naming the file, the line and what to run ([`JournalError`]).

use super::file::{DesignSpec, Minimize, Robust};
use super::tolerance::{first_order, sampled_here, Sampled, P95_Z};
use crate::error::{DesignFailure, Error, JournalError};
use genetic_algorithm::strategy::evolve::prelude::*;
use grainchain_engine::protector::{
    evaluate, gradients, steps_for_accuracy, Bead, Evaluation, Need, Settings,
};
use std::collections::{HashMap, HashSet};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Condvar, Mutex};

/// One design's result over the file's speeds.
#[derive(Clone, Debug, PartialEq)]
pub struct Scored {
    /// One choice per section.
    pub genes: Vec<usize>,
    /// The objective (relative to the reference column; lower is better); infinite when a
    /// constraint is broken.
    pub objective: f64,
    /// The worst-case (largest over speeds) peak force, N.
    pub peak: f64,
    /// The impulse at the worst-case speed, N s.
    pub impulse: f64,
    /// The duration at the worst-case speed, s.
    pub duration: f64,
    /// The column's mass, kg.
    pub mass: f64,
    /// The column's length, m.
    pub length: f64,
    /// Whether every run of it ended by the stop rule (its numbers are exact), not the cap.
    pub complete: bool,
    /// Whether a run of it gave up (`Settings::give_up_above`): its peak and objective are then
    /// lower bounds, at or above the objective of a design no heavier (see [`Front`]).
    pub given_up: bool,
}

/// What the settings of a run need for the objective, at the step of the file's accuracy
/// (`[search] accuracy`, [`steps_for_accuracy`]).
pub fn settings(problem: &DesignSpec) -> Settings {
    let o = &problem.file.objective;
    let w = o.weights.unwrap_or_default();
    let need = match o.minimize {
        Minimize::Peak
        | Minimize::P95
        | Minimize::Mean
        | Minimize::Quantile
        | Minimize::P95FirstOrder => Need::Peak,
        Minimize::Duration => Need::Duration,
        Minimize::Impulse => Need::Everything,
        Minimize::Mix if w.impulse > 0.0 => Need::Everything,
        Minimize::Mix if w.duration > 0.0 => Need::Duration,
        Minimize::Mix => Need::Peak,
    };
    Settings {
        need,
        fraction: o.fraction,
        time_cap: SEARCH_CAP,
        steps_per_contact: steps_for_accuracy(problem.file.search.accuracy),
        ..Settings::default()
    }
}

/// The search's time cap, in contact-time sums (about one transit of the column each): a tenth
/// of the engine's default, so a column that traps its energy costs a search tens of
/// milliseconds, not hundreds; its peak is then the largest seen so far (`complete` false). The
/// outputs evaluate the best designs and the baselines again at the engine's default.
pub const SEARCH_CAP: f64 = 10.0;

/// The reference column's evaluation at each speed (the objective's unit).
pub fn reference(problem: &DesignSpec) -> Result<Vec<Evaluation>, Error> {
    let beads = vec![problem.reference; problem.file.space.beads];
    Ok(evaluate_all(problem, &beads, None, false)?.0)
}

/// The objective's weight on the peak when the peak is all it needs (then a run may give up
/// on a design that cannot be wanted), else `None`.
fn peak_only_weight(problem: &DesignSpec) -> Option<f64> {
    let o = &problem.file.objective;
    match (settings(problem).need, o.minimize) {
        // The first-order 95th percentile is at least the peak: a bound on the peak bounds it
        // too. (A Monte Carlo statistic gives up on its columns' peaks: `robust_all`.)
        (Need::Peak, Minimize::Peak | Minimize::P95FirstOrder) => Some(1.0),
        (Need::Peak, Minimize::Mix) => {
            Some(o.weights.unwrap_or_default().peak).filter(|&w| w > 0.0)
        }
        _ => None,
    }
}

/// Evaluate a column at every speed; with `give_up` (an objective and the reference's runs),
/// each run gives up once its peak alone puts the objective at or above it. With `spread` (the
/// p95 objective), each run is one with the peak's derivatives ([`gradients`], whose evaluation
/// is [`evaluate`]'s to rounding), and the second list holds each peak's first-order standard
/// deviation under the file's tolerances; otherwise it is empty.
fn evaluate_all(
    problem: &DesignSpec,
    beads: &[Bead],
    give_up: Option<(f64, &[Evaluation])>,
    spread: bool,
) -> Result<(Vec<Evaluation>, Vec<f64>), Error> {
    let s = settings(problem);
    let weight = peak_only_weight(problem);
    let failed = |source| {
        Error::Design(DesignFailure::Evaluation {
            file: problem.path.clone(),
            source,
        })
    };
    let mut evals = Vec::with_capacity(problem.impacts.len());
    let mut sd = Vec::new();
    for (i, imp) in problem.impacts.iter().enumerate() {
        // The objective is at least `weight * peak / reference peak` at each speed.
        let give_up_above = match (give_up, weight) {
            (Some((t, r)), Some(w)) if t.is_finite() => t * r[i].peak_force / w,
            _ => f64::INFINITY,
        };
        let s = Settings { give_up_above, ..s };
        match problem.tolerances.as_ref().filter(|_| spread) {
            Some(tol) => {
                let g = gradients(beads, imp, &problem.protected, &s).map_err(failed)?;
                let e = g.evaluation;
                sd.push(first_order(beads, imp.speed, e.peak_force, &g.peak, tol).sd);
                evals.push(e);
            }
            None => evals.push(evaluate(beads, imp, &problem.protected, &s).map_err(failed)?),
        }
    }
    Ok((evals, sd))
}

/// The objective's weights on the peak (the p95's too), the impulse and the duration.
pub fn weights(problem: &DesignSpec) -> (f64, f64, f64) {
    let o = &problem.file.objective;
    match o.minimize {
        Minimize::Peak
        | Minimize::P95
        | Minimize::Mean
        | Minimize::Quantile
        | Minimize::P95FirstOrder => (1.0, 0.0, 0.0),
        Minimize::Impulse => (0.0, 1.0, 0.0),
        Minimize::Duration => (0.0, 0.0, 1.0),
        Minimize::Mix => {
            let w = o.weights.unwrap_or_default();
            (w.peak, w.impulse, w.duration)
        }
    }
}

/// The objective of evaluations at each speed against the reference's: the worst case over
/// speeds of the weighted ratios. For the p95 objective `sd` holds each peak's first-order
/// standard deviation, and the peak counts as `peak + 1.645 sd` (but for a run that gave up,
/// whose peak alone is the lower bound a given-up design's objective must be); without them
/// (an empty `sd`: the outputs' finer runs before their spreads are known) it is NaN. Other
/// objectives do not read it.
pub fn objective(
    problem: &DesignSpec,
    evals: &[Evaluation],
    sd: &[f64],
    reference: &[Evaluation],
) -> f64 {
    let p95 = problem.file.objective.minimize == Minimize::P95FirstOrder;
    let w = weights(problem);
    evals
        .iter()
        .zip(reference)
        .enumerate()
        .map(|(i, (e, r))| {
            let ratio = |a: f64, b: f64| if w_zero(a, b) { 0.0 } else { a / b };
            let peak = if p95 && !e.given_up {
                e.peak_force + P95_Z * sd.get(i).copied().unwrap_or(f64::NAN)
            } else {
                e.peak_force
            };
            w.0 * ratio(peak, r.peak_force)
                + w.1 * ratio(e.impulse, r.impulse)
                + w.2 * ratio(e.duration, r.duration)
        })
        .fold(f64::NEG_INFINITY, f64::max)
}

fn w_zero(a: f64, b: f64) -> bool {
    a == 0.0 && b == 0.0
}

/// Score one design (no journal).
pub fn score(
    problem: &DesignSpec,
    genes: &[usize],
    reference: &[Evaluation],
) -> Result<Scored, Error> {
    score_unless(problem, genes, reference, f64::INFINITY)
}

/// Score one design, giving up once its objective is known to be at least `worse_than`
/// (`Scored::given_up`; infinite: never, and only a peak-only objective can).
pub fn score_unless(
    problem: &DesignSpec,
    genes: &[usize],
    reference: &[Evaluation],
    worse_than: f64,
) -> Result<Scored, Error> {
    let beads = problem.beads(genes);
    let mass = beads.iter().map(Bead::mass).sum();
    let length = beads.iter().map(|b| b.diameter).sum();
    if problem.violation(&beads).is_some() {
        return Ok(Scored {
            genes: genes.to_vec(),
            objective: f64::INFINITY,
            peak: f64::NAN,
            impulse: f64::NAN,
            duration: f64::NAN,
            mass,
            length,
            complete: true,
            given_up: false,
        });
    }
    if let Some(r) = &problem.robust {
        let (evals, stats) = robust_all(problem, &beads, reference, worse_than, (r, r.screen))?;
        let mut s = scored(problem, genes, &beads, &evals, &[], reference);
        s.objective = robust_objective(&stats, reference);
        s.given_up = stats.iter().any(|x| x.given_up);
        s.complete &= stats.iter().all(|x| x.bounds == 0);
        return Ok(s);
    }
    let p95 = problem.file.objective.minimize == Minimize::P95FirstOrder;
    let (evals, sd) = evaluate_all(problem, &beads, Some((worse_than, reference)), p95)?;
    Ok(scored(problem, genes, &beads, &evals, &sd, reference))
}

/// A robust objective's runs of a column at every speed: the nominal run, and the statistic of
/// its first `n` common draws ([`sampled_here`], on this thread). With a finite `worse_than`
/// (the objective a design no heavier has), each speed's draws give up once their statistic is
/// settled at or above `worse_than` times the reference's peak there.
pub fn robust_all(
    problem: &DesignSpec,
    beads: &[Bead],
    reference: &[Evaluation],
    worse_than: f64,
    (r, n): (&Robust, usize),
) -> Result<(Vec<Evaluation>, Vec<Sampled>), Error> {
    let s = settings(problem);
    let failed = |source| {
        Error::Design(DesignFailure::Evaluation {
            file: problem.path.clone(),
            source,
        })
    };
    let mut evals = Vec::with_capacity(problem.impacts.len());
    let mut stats = Vec::with_capacity(problem.impacts.len());
    for (imp, reference) in problem.impacts.iter().zip(reference) {
        evals.push(evaluate(beads, imp, &problem.protected, &s).map_err(failed)?);
        let give_up_above = if worse_than.is_finite() {
            worse_than * reference.peak_force
        } else {
            f64::INFINITY
        };
        let s = Settings { give_up_above, ..s };
        stats.push(
            sampled_here(
                beads,
                imp,
                &problem.protected,
                &s,
                (&r.draws, n),
                r.statistic,
            )
            .map_err(failed)?,
        );
    }
    Ok((evals, stats))
}

/// A robust objective from each speed's statistic: the worst case over speeds of the statistic
/// relative to the reference's nominal peak.
pub fn robust_objective(stats: &[Sampled], reference: &[Evaluation]) -> f64 {
    stats
        .iter()
        .zip(reference)
        .map(|(x, r)| x.value / r.peak_force)
        .fold(f64::NEG_INFINITY, f64::max)
}

/// A column's score from its evaluations at the file's speeds (and, for the p95 objective, their
/// peaks' first-order standard deviations, [`objective`]): the objective, and the peak, impulse
/// and duration at the speed of the largest peak.
pub fn scored(
    problem: &DesignSpec,
    genes: &[usize],
    beads: &[Bead],
    evals: &[Evaluation],
    sd: &[f64],
    reference: &[Evaluation],
) -> Scored {
    let worst = evals
        .iter()
        .max_by(|a, b| a.peak_force.total_cmp(&b.peak_force))
        .expect("at least one speed");
    Scored {
        genes: genes.to_vec(),
        objective: objective(problem, evals, sd, reference),
        peak: worst.peak_force,
        impulse: worst.impulse,
        duration: worst.duration,
        mass: beads.iter().map(Bead::mass).sum(),
        length: beads.iter().map(|b| b.diameter).sum(),
        complete: evals.iter().all(|e| e.complete),
        given_up: evals.iter().any(|e| e.given_up),
    }
}

/// A column in words: runs of equal beads (`20 x steel 6 mm + 20 x ptfe 6 mm`).
pub fn describe(beads: &[Bead]) -> String {
    let mut parts: Vec<(usize, String)> = Vec::new();
    for b in beads {
        let name = format!("{} {:.2} mm", b.material.name, b.diameter * 1e3);
        match parts.last_mut() {
            Some((n, last)) if *last == name => *n += 1,
            _ => parts.push((1, name)),
        }
    }
    if parts.len() > 8 {
        let first = &parts[0].1;
        let last = &parts[parts.len() - 1].1;
        return format!(
            "{} beads in {} runs, {first} ... {last}",
            beads.len(),
            parts.len()
        );
    }
    parts
        .iter()
        .map(|(n, s)| format!("{n} x {s}"))
        .collect::<Vec<_>>()
        .join(" + ")
}

/// The genes as text (`0.1.1.0`), the journal's key.
pub fn genes_key(genes: &[usize]) -> String {
    genes
        .iter()
        .map(usize::to_string)
        .collect::<Vec<_>>()
        .join(".")
}

/// The journal's header: a design's result in nine columns, and `fnv`, the line's checksum.
pub const JOURNAL_HEADER: &str =
    "genes,objective,peak_n,impulse_ns,duration_s,mass_kg,length_m,complete,given_up,fnv";

/// The header of a journal written before its lines carried checksums (grainchain before issue
/// 38): its lines cannot be checked, so it is refused with the advice to run the search again.
const OLDER_JOURNAL_HEADER: &str =
    "genes,objective,peak_n,impulse_ns,duration_s,mass_kg,length_m,complete,given_up";

/// A journal's (and a convergence file's) first line: the digest of the design file it belongs
/// to.
fn digest_line(digest: &str) -> String {
    format!("# design {digest}")
}

/// The checksum of a journal line's text (`body`, without the checksum) in the journal of the
/// design file with `digest`: FNV-1a 64 of `<digest>,<body>` ([`crate::report::fnv1a`], as a
/// study member's `json_fnv`), so a line changed or cut after it was written, or copied from
/// the journal of another design file, does not match it.
fn line_fnv(digest: &str, body: &str) -> String {
    crate::report::fnv1a(format!("{digest},{body}").as_bytes())
}

/// A journal line of the design file with `digest`: the design's result, then its checksum.
fn journal_line(s: &Scored, digest: &str) -> String {
    use crate::report::csv_number as n;
    let body = format!(
        "{},{},{},{},{},{},{},{},{}",
        genes_key(&s.genes),
        n(s.objective),
        n(s.peak),
        n(s.impulse),
        n(s.duration),
        n(s.mass),
        n(s.length),
        s.complete,
        s.given_up
    );
    let fnv = line_fnv(digest, &body);
    format!("{body},{fnv}\n")
}

/// Who reads a journal. Only an interruption cuts a line, and only the last one (each line is
/// written whole, with its line end, by one unbuffered write): `--resume`, whose island it is,
/// drops a cut last line and runs that design again; a merge refuses it (the island has not
/// finished). Anything else that is wrong is refused by both, naming the file and the line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Reader {
    /// `--resume` of the journal's island.
    Resume,
    /// `--merge`, or a search writing its outputs.
    Merge,
}

/// A journal read back and checked.
#[derive(Clone, Debug, Default)]
struct Journal {
    /// Every design in it.
    designs: HashMap<Vec<usize>, Scored>,
    /// Its evaluation lines, whole (without their line ends), in the file's order.
    lines: Vec<String>,
}

/// What a file of the journals is.
enum Reading<T> {
    /// A file of another design file (its digest).
    Foreign(String),
    /// A file of this design file, read and checked.
    Ours(T),
}

/// What is wrong with a journal or a convergence file: at which line (counting the digest line
/// as 1; `None`: the whole file), and what.
#[derive(Debug)]
struct Damage {
    line: Option<usize>,
    problem: String,
    /// Whether it is a last line cut by an interruption (which `--resume` finishes).
    interrupted: bool,
}

fn at_line(line: usize, problem: impl Into<String>) -> Damage {
    Damage {
        line: Some(line),
        problem: problem.into(),
        interrupted: false,
    }
}

/// A damage of the whole file.
fn whole_file(problem: impl Into<String>) -> Damage {
    Damage {
        line: None,
        problem: problem.into(),
        interrupted: false,
    }
}

/// Split a file into its lines (without their line ends) and a last line without one (cut), the
/// first `whole` lines (digest, header) required whole and every line that is read UTF-8.
fn split_lines(bytes: &[u8], whole: usize) -> Result<(Vec<&str>, Option<&[u8]>), Damage> {
    let mut pieces: Vec<&[u8]> = bytes.split(|&b| b == b'\n').collect();
    // After a final line end `split` gives an empty piece; else the last piece is a cut line.
    let cut = pieces.pop().filter(|p| !p.is_empty());
    if pieces.len() < whole {
        return Err(at_line(
            pieces.len() + 1,
            "cut short: the file ends before its header",
        ));
    }
    let lines = pieces
        .iter()
        .enumerate()
        .map(|(i, p)| {
            std::str::from_utf8(p).map_err(|e| {
                at_line(
                    i + 1,
                    format!(
                        "not UTF-8 text (byte {} of the line): damaged after it was written",
                        e.valid_up_to() + 1
                    ),
                )
            })
        })
        .collect::<Result<Vec<&str>, Damage>>()?;
    Ok((lines, cut))
}

/// A file of the search split into its lines ([`split_lines`], the first two whole), or the
/// digest of the design file it belongs to when that is not ours.
enum Opened<'a> {
    /// Ours: its lines and a last line without its line end.
    Ours(Vec<&'a str>, Option<&'a [u8]>),
    /// Another design file's (the digest on its first line).
    Foreign(String),
}

/// Split a journal or convergence file (`what`, for the message) into lines and check its first
/// line, `# design <digest>`, against the design file's `digest`: the prologue both readers share.
fn open_lines<'a>(bytes: &'a [u8], digest: &str, what: &str) -> Result<Opened<'a>, Damage> {
    let (lines, cut) = split_lines(bytes, 2)?;
    let Some(there) = lines[0].strip_prefix("# design ") else {
        return Err(at_line(
            1,
            format!("not {what} grainchain wrote (its first line is not `# design <digest>`)"),
        ));
    };
    if there != digest {
        return Ok(Opened::Foreign(there.to_string()));
    }
    Ok(Opened::Ours(lines, cut))
}

/// Check a journal's bytes (see [`Reader`]) against the design file with `digest`, its designs
/// of `sections` genes, each one of `choices`.
fn check_journal(
    bytes: &[u8],
    (sections, choices): (usize, usize),
    digest: &str,
    reader: Reader,
) -> Result<Reading<Journal>, Damage> {
    let (lines, cut) = match open_lines(bytes, digest, "a design journal")? {
        Opened::Ours(lines, cut) => (lines, cut),
        Opened::Foreign(there) => return Ok(Reading::Foreign(there)),
    };
    if lines[1] == OLDER_JOURNAL_HEADER {
        return Err(whole_file(
            "written by an older grainchain, whose journal lines carry no checksum (column \
             `fnv`): its evaluations cannot be checked",
        ));
    }
    if lines[1] != JOURNAL_HEADER {
        return Err(at_line(
            2,
            format!("not the journal's header `{JOURNAL_HEADER}`"),
        ));
    }
    let mut journal = Journal::default();
    for (i, line) in lines.iter().enumerate().skip(2) {
        let s =
            parse_checked(line, (sections, choices), digest).map_err(|why| at_line(i + 1, why))?;
        journal.designs.insert(s.genes.clone(), s);
        journal.lines.push(line.to_string());
    }
    if cut.is_some() && reader == Reader::Merge {
        return Err(Damage {
            interrupted: true,
            ..at_line(
                lines.len() + 1,
                "cut short (no line end): the island was interrupted while writing it and has \
                 not finished",
            )
        });
    }
    Ok(Reading::Ours(journal))
}

/// A journal line checked against its checksum and read.
fn parse_checked(
    line: &str,
    (sections, choices): (usize, usize),
    digest: &str,
) -> Result<Scored, String> {
    let Some((body, fnv)) = line.rsplit_once(',') else {
        return Err("not a journal line (no checksum)".into());
    };
    if line_fnv(digest, body) != fnv {
        return Err(
            "does not match its checksum (column `fnv`): cut or changed after it was written"
                .into(),
        );
    }
    parse_line(body, sections, choices).ok_or_else(|| {
        "matches its checksum but is not a result of this design file's designs".into()
    })
}

fn parse_line(line: &str, sections: usize, choices: usize) -> Option<Scored> {
    let f: Vec<&str> = line.split(',').collect();
    if f.len() != 9 {
        return None;
    }
    let genes: Vec<usize> = f[0]
        .split('.')
        .map(str::parse)
        .collect::<Result<_, _>>()
        .ok()?;
    if genes.len() != sections || genes.iter().any(|&g| g >= choices) {
        return None;
    }
    // An empty field is a number a design breaking a constraint does not have (`csv_number`
    // writes non-finite numbers so): an infinite objective, no peak.
    let num = |s: &str| s.parse::<f64>().ok();
    let or = |s: &str, none: f64| if s.is_empty() { Some(none) } else { num(s) };
    Some(Scored {
        genes,
        objective: or(f[1], f64::INFINITY)?,
        peak: or(f[2], f64::NAN)?,
        impulse: or(f[3], f64::NAN)?,
        duration: or(f[4], f64::NAN)?,
        mass: num(f[5])?,
        length: num(f[6])?,
        complete: f[7].parse().ok()?,
        given_up: f[8].parse().ok()?,
    })
}

/// The designs a search knows exactly, as (mass, objective): what a new design must beat to
/// be wanted. A design whose objective is at least [`Front::worse_than`] its mass is matched
/// or beaten by one no heavier, so it is on no Pareto front of objective against mass and is
/// not the best: the search may give up on it as soon as its peak says so
/// (`Settings::give_up_above`). Its journal line then holds lower bounds (`given_up`), and
/// the best design and the front of the designs evaluated are the ones the search would have
/// found with every run to its cap (`validation/design.rs` checks both).
///
/// The front is frozen for a generation (updated between generations, from the designs the
/// generation asked for), so what a run gives up on does not depend on which thread finished
/// first: the same seed gives the same search at every thread count, and on resume.
#[derive(Clone, Debug, Default)]
pub struct Front {
    /// Exact designs' (mass, objective), by mass, objective the running minimum.
    points: Vec<(f64, f64)>,
}

impl Front {
    /// The front of the exactly known designs among `designs`.
    pub fn of<'a>(designs: impl IntoIterator<Item = &'a Scored>) -> Front {
        let mut f = Front::default();
        f.add(designs);
        f
    }

    fn add<'a>(&mut self, designs: impl IntoIterator<Item = &'a Scored>) {
        self.points.extend(
            designs
                .into_iter()
                .filter(|s| !s.given_up && s.objective.is_finite())
                .map(|s| (s.mass, s.objective)),
        );
        self.points
            .sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
        let mut best = f64::INFINITY;
        for p in &mut self.points {
            best = best.min(p.1);
            p.1 = best;
        }
    }

    /// The least objective of a known design no heavier than `mass` (infinite if none).
    pub fn worse_than(&self, mass: f64) -> f64 {
        let k = self.points.partition_point(|p| p.0 <= mass);
        if k == 0 {
            f64::INFINITY
        } else {
            self.points[k - 1].1
        }
    }
}

/// The non-dominated designs in (mass, objective), lightest first.
pub fn pareto(all: &[Scored]) -> Vec<&Scored> {
    let mut v: Vec<&Scored> = all.iter().filter(|s| s.objective.is_finite()).collect();
    v.sort_by(|a, b| {
        a.mass
            .total_cmp(&b.mass)
            .then(a.objective.total_cmp(&b.objective))
    });
    let mut front: Vec<&Scored> = Vec::new();
    for s in v {
        if front.last().is_none_or(|f| s.objective < f.objective) {
            front.push(s);
        }
    }
    front
}

/// The shared state of the fitness threads: what was evaluated, and the journal.
#[derive(Debug)]
struct Memory {
    seen: HashMap<Vec<usize>, Scored>,
    /// What this generation's runs must beat (frozen while it runs).
    front: Front,
    /// The designs this generation asked for (added to `front` when it ends).
    asked: Vec<Vec<usize>>,
    /// Unbuffered: each line reaches the file as it is written, so an interrupted search
    /// loses at most the line being written.
    journal: std::fs::File,
    /// Its path, named if a line cannot be written.
    journal_path: PathBuf,
    /// The digest of the design file (each journal line's checksum includes it).
    digest: String,
    evaluated: u64,
    failed: Option<Error>,
    /// Designs a thread is evaluating now: a second thread asking for one waits for its result
    /// (`DesignFitness::done`) instead of running it again, so every design is run and journaled
    /// once and the journal and its count are the same at every run (they held duplicates that
    /// depended on which thread got there first).
    running: HashSet<Vec<usize>>,
}

impl Memory {
    /// Between generations: the designs the last one asked for join the front.
    fn next_generation(&mut self) {
        let asked = std::mem::take(&mut self.asked);
        let seen = &self.seen;
        self.front.add(asked.iter().filter_map(|g| seen.get(g)));
    }
}

#[derive(Clone, Debug)]
struct DesignFitness {
    problem: Arc<DesignSpec>,
    reference: Arc<Vec<Evaluation>>,
    memory: Arc<Mutex<Memory>>,
    /// Signalled when a design of `Memory::running` is done.
    done: Arc<Condvar>,
    tick: Tick,
}

/// Called after each new evaluation (the progress bar).
#[derive(Clone)]
pub struct Tick(pub Arc<dyn Fn() + Send + Sync>);

impl std::fmt::Debug for Tick {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Tick")
    }
}

/// Objectives are ratios near 1: scored in millionths.
const PRECISION: f64 = 1e-6;

impl Fitness for DesignFitness {
    type Genotype = ListGenotype<usize>;
    fn calculate_for_chromosome(
        &mut self,
        chromosome: &FitnessChromosome<Self>,
        _genotype: &FitnessGenotype<Self>,
    ) -> Option<FitnessValue> {
        let genes = chromosome.genes.clone();
        let (known, worse_than) = {
            let mut m = self.memory.lock().expect("not poisoned");
            m.asked.push(genes.clone());
            let mass = self.problem.beads(&genes).iter().map(Bead::mass).sum();
            let worse_than = if self.problem.file.search.give_up {
                m.front.worse_than(mass)
            } else {
                f64::INFINITY
            };
            // Known, or being run by another thread (wait for it), or ours to run.
            loop {
                if let Some(s) = m.seen.get(&genes) {
                    break (Some(s.clone()), worse_than);
                }
                if m.running.insert(genes.clone()) {
                    break (None, worse_than);
                }
                m = self.done.wait(m).expect("not poisoned");
            }
        };
        let scored = match known {
            Some(s) => s,
            None => match score_unless(&self.problem, &genes, &self.reference, worse_than) {
                Ok(s) => {
                    let mut m = self.memory.lock().expect("not poisoned");
                    let line = journal_line(&s, &m.digest);
                    if let Err(source) = m.journal.write_all(line.as_bytes()) {
                        let path = m.journal_path.clone();
                        m.failed.get_or_insert(Error::Io { path, source });
                    }
                    m.evaluated += 1;
                    m.running.remove(&genes);
                    m.seen.insert(genes, s.clone());
                    self.done.notify_all();
                    (self.tick.0)();
                    s
                }
                Err(e) => {
                    let mut m = self.memory.lock().expect("not poisoned");
                    m.failed.get_or_insert(e);
                    m.running.remove(&genes);
                    self.done.notify_all();
                    return None;
                }
            },
        };
        if scored.objective.is_finite() {
            fitness_score(scored.objective, PRECISION)
        } else {
            None
        }
    }
}

/// Records the best objective after every generation, and moves the front on.
#[derive(Clone)]
struct Convergence {
    best: Arc<Mutex<Vec<(usize, f64)>>>,
    memory: Arc<Mutex<Memory>>,
}

impl StrategyReporter for Convergence {
    type Genotype = ListGenotype<usize>;
    /// After the first population's fitness.
    fn on_start<S: StrategyState<Self::Genotype>, C: StrategyConfig>(
        &mut self,
        _genotype: &Self::Genotype,
        _state: &S,
        _config: &C,
    ) {
        self.memory.lock().expect("not poisoned").next_generation();
    }
    fn on_generation_complete<S: StrategyState<Self::Genotype>, C: StrategyConfig>(
        &mut self,
        _genotype: &Self::Genotype,
        state: &S,
        _config: &C,
    ) {
        self.memory.lock().expect("not poisoned").next_generation();
        if let Some(b) = state.best_fitness_score() {
            self.best
                .lock()
                .expect("not poisoned")
                .push((state.current_generation(), b as f64 * PRECISION));
        }
    }
}

/// What a search found.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// Every design evaluated (this run's and the journal's), sorted by objective then genes.
    pub all: Vec<Scored>,
    /// The best objective after each generation.
    pub convergence: Vec<(usize, f64)>,
    /// Designs evaluated by this run (the rest came from the journal).
    pub evaluated: u64,
    /// The reference column at each speed.
    pub reference: Vec<Evaluation>,
}

/// Run the search of `problem` with seed `seed` on `threads` threads, its journal at
/// `journal` (read first when `resume`, if it belongs to the design file with `digest`), `tick`
/// after each new evaluation. An interrupted search (Ctrl-C ends the process) keeps every
/// evaluation that finished in the journal.
pub fn run(
    problem: &DesignSpec,
    seed: u64,
    threads: usize,
    journal: &Path,
    resume: bool,
    digest: &str,
    tick: Tick,
) -> Result<Outcome, Error> {
    let sections = problem.sections();
    // What a journal line's design may be: its genes, each one of the choices.
    let space = (sections, problem.choices.len());
    let convergence_file = convergence_path(journal);
    let io = |source| Error::Io {
        path: PathBuf::from(journal),
        source,
    };
    // The journal is appended to as evaluations finish, so it is not an atomic file with a
    // record in the folder's journal: a file in its place (or in its convergence file's) is
    // replaced only if it is grainchain's (its first line `# design <digest>`), never a file of
    // the user's (issue 38).
    for path in [journal, &convergence_file] {
        if let Ok(bytes) = std::fs::read(path) {
            if !bytes.starts_with(b"# design ") {
                let name = path
                    .file_name()
                    .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
                return Err(crate::error::OutDirError::NotOurs {
                    dir: path.parent().map(Path::to_path_buf).unwrap_or_default(),
                    why: format!(
                        "{name} is in the way: it is not a file of a design search grainchain \
                         wrote (its first line is not `# design <digest>`), and grainchain \
                         replaces only what it wrote"
                    ),
                    advice: "move or remove it, then run the command again".into(),
                }
                .into());
            }
        }
    }
    let seen = if resume {
        match std::fs::read(journal) {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => HashMap::new(),
            Err(source) => return Err(io(source)),
            Ok(bytes) => match check_journal(&bytes, space, digest, Reader::Resume) {
                Ok(Reading::Ours(j)) => j.designs,
                // Nothing of another design file's journal is this search's: it starts afresh
                // (as a resumed study runs a member of other settings again).
                Ok(Reading::Foreign(_)) => HashMap::new(),
                Err(d) => {
                    return Err(damaged(
                        journal,
                        d,
                        "run the search again without --resume, which starts this journal \
                         afresh"
                            .into(),
                    ))
                }
            },
        }
    } else {
        HashMap::new()
    };
    // A run in progress has no convergence file: an island interrupted from here on is one a
    // merge finds unfinished (the file is grainchain's, checked above, and written again when
    // the search has finished).
    if let Err(e) = std::fs::remove_file(&convergence_file) {
        if e.kind() != std::io::ErrorKind::NotFound {
            return Err(Error::Io {
                path: convergence_file.clone(),
                source: e,
            });
        }
    }
    // Rewrite the journal with what it held (drops a line cut by an interruption), at once so
    // an interruption leaves the old one whole, then append.
    let mut text = format!("{}\n{JOURNAL_HEADER}\n", digest_line(digest));
    let mut old: Vec<&Scored> = seen.values().collect();
    old.sort_by(|a, b| a.genes.cmp(&b.genes));
    for s in old {
        text.push_str(&journal_line(s, digest));
    }
    crate::report::AtomicFile::write_unrecorded(journal, text.as_bytes())?;
    let file = std::fs::OpenOptions::new()
        .append(true)
        .open(journal)
        .map_err(io)?;
    let reference = reference(problem)?;
    let memory = Arc::new(Mutex::new(Memory {
        seen,
        front: Front::default(),
        asked: Vec::new(),
        journal: file,
        journal_path: journal.to_path_buf(),
        digest: digest.to_string(),
        evaluated: 0,
        failed: None,
        running: HashSet::new(),
    }));
    let fitness = DesignFitness {
        problem: Arc::new(problem.clone()),
        reference: Arc::new(reference.clone()),
        memory: memory.clone(),
        done: Arc::new(Condvar::new()),
        tick,
    };
    let genotype = ListGenotype::builder()
        .with_genes_size(sections)
        .with_allele_list((0..problem.choices.len()).collect())
        .build()
        .map_err(|e| DesignFailure::Genetic(format!("{e:?}")))?;
    let best = Arc::new(Mutex::new(Vec::new()));
    let s = &problem.file.search;
    // One generation's designs are evaluated at once: at most one thread each.
    let pool =
        grainchain_engine::thread_pool(threads, s.population).map_err(DesignFailure::Threads)?;
    pool.install(|| {
        Evolve::builder()
            .with_genotype(genotype)
            .with_target_population_size(s.population)
            .with_max_stale_generations(s.stale)
            .with_max_generations(s.generations)
            .with_fitness(fitness)
            .with_fitness_ordering(FitnessOrdering::Minimize)
            .with_par_fitness(threads > 1)
            .with_mutate(MutateSingleGene::new(0.2))
            .with_crossover(CrossoverUniform::new(0.7, 0.8))
            .with_select(SelectTournament::new(0.5, 0.02, 4))
            .with_rng_seed_from_u64(seed)
            .with_reporter(Convergence {
                best: best.clone(),
                memory: memory.clone(),
            })
            .call()
            .map(|_| ())
            .map_err(|e| Error::Design(DesignFailure::Genetic(format!("{e:?}"))))
    })?;
    let mut m = memory.lock().expect("not poisoned");
    if let Some(f) = m.failed.take() {
        return Err(f);
    }
    let mut all: Vec<Scored> = m.seen.values().cloned().collect();
    all.sort_by(|a, b| {
        a.objective
            .total_cmp(&b.objective)
            .then(a.genes.cmp(&b.genes))
    });
    let convergence = best.lock().expect("not poisoned").clone();
    // The island has finished: its convergence file records the journal as it is now.
    let bytes = std::fs::read(journal).map_err(io)?;
    let written = match check_journal(&bytes, space, digest, Reader::Merge) {
        Ok(Reading::Ours(j)) => j,
        Ok(Reading::Foreign(there)) => {
            return Err(damaged(
                journal,
                at_line(1, format!("digest {there}, changed while the search ran")),
                "run the search again".into(),
            ))
        }
        Err(d) => {
            return Err(damaged(
                journal,
                d,
                "changed by something else while the search ran: run the search again".into(),
            ))
        }
    };
    write_convergence(&convergence_file, &written, digest, &convergence)?;
    Ok(Outcome {
        all,
        convergence,
        evaluated: m.evaluated,
        reference,
    })
}

/// A [`Damage`] of `file` as the error of a merge or resume, with what to do.
fn damaged(file: &Path, d: Damage, advice: String) -> Error {
    JournalError::Damaged {
        file: file.to_path_buf(),
        line: d.line,
        problem: d.problem,
        advice,
    }
    .into()
}

/// The convergence file beside a journal (`island-K-of-N.convergence.csv`).
fn convergence_path(journal: &Path) -> PathBuf {
    journal.with_extension("convergence.csv")
}

/// How a convergence file's second line, its record of the journal, starts.
const RECORD: &str = "# journal: ";
/// What comes before the convergence file's own checksum in its record.
const OWN_FNV: &str = "; this file: fnv1a ";
/// A convergence file's header.
const CONVERGENCE_HEADER: &str = "generation,best_objective";

/// The checksum of a journal's evaluation lines as a set: FNV-1a of the lines sorted, each with
/// its line end. A line removed, added or changed changes it; the order the threads finished in
/// does not (`studies/cluster/test-slurm.sh` compares an island's journals sorted).
fn lines_fnv(lines: &[String]) -> String {
    let mut sorted: Vec<&String> = lines.iter().collect();
    sorted.sort();
    let mut text = String::new();
    for l in sorted {
        text.push_str(l);
        text.push('\n');
    }
    crate::report::fnv1a(text.as_bytes())
}

/// Write an island's convergence file when its search has finished: the digest line, the record
/// of its `journal` (`# journal: <lines> evaluations, fnv1a <lines_fnv>; this file: fnv1a
/// <hex>`, the last the FNV-1a of the file's text with that value empty, as a member's
/// `json_fnv`), then the best objective after each generation. A merge needs it of every
/// island, and the journal as it records it.
fn write_convergence(
    path: &Path,
    journal: &Journal,
    digest: &str,
    convergence: &[(usize, f64)],
) -> Result<(), Error> {
    use std::fmt::Write as _;
    let mut text = format!(
        "{}\n{RECORD}{} evaluations, fnv1a {}{OWN_FNV}",
        digest_line(digest),
        journal.lines.len(),
        lines_fnv(&journal.lines)
    );
    let at = text.len();
    let _ = write!(text, "\n{CONVERGENCE_HEADER}\n");
    for (g, b) in convergence {
        let _ = writeln!(text, "{g},{}", crate::report::csv_number(*b));
    }
    let fnv = crate::report::fnv1a(text.as_bytes());
    text.insert_str(at, &fnv);
    crate::report::AtomicFile::write_unrecorded(path, text.as_bytes())
}

/// A convergence file read back and checked.
#[derive(Debug)]
struct Record {
    /// The journal's evaluation lines when its island finished.
    evaluations: usize,
    /// Their [`lines_fnv`].
    journal_fnv: String,
    /// The best objective after each generation.
    rows: Vec<(usize, f64)>,
}

/// Check a convergence file's bytes against the design file with `digest`.
fn check_convergence(bytes: &[u8], digest: &str) -> Result<Reading<Record>, Damage> {
    let lines = match open_lines(bytes, digest, "a convergence file")? {
        Opened::Ours(lines, _) => lines,
        Opened::Foreign(there) => return Ok(Reading::Foreign(there)),
    };
    if lines[1] == CONVERGENCE_HEADER {
        return Err(whole_file(
            "written by an older grainchain, whose convergence files record no checksum of \
             their journal",
        ));
    }
    let record = lines[1].strip_prefix(RECORD).and_then(|r| {
        let (journal, own) = r.split_once(OWN_FNV)?;
        let (n, fnv) = journal.split_once(" evaluations, fnv1a ")?;
        Some((n.parse::<usize>().ok()?, fnv, own))
    });
    let Some((evaluations, journal_fnv, own)) = record else {
        return Err(at_line(
            2,
            format!(
                "not the record of its journal (`{RECORD}<lines> evaluations, fnv1a \
                 <hex>{OWN_FNV}<hex>`)"
            ),
        ));
    };
    // The file's text with its own checksum's value empty (the value ends line 2).
    let end = lines[0].len() + 1 + lines[1].len();
    let start = end - own.len();
    let blank = [&bytes[..start], &bytes[end..]].concat();
    if crate::report::fnv1a(&blank) != own {
        return Err(whole_file(
            "its bytes do not match the checksum it records (`this file: fnv1a`): cut or \
             changed after it was written",
        ));
    }
    if lines.get(2) != Some(&CONVERGENCE_HEADER) {
        return Err(at_line(3, format!("not the header `{CONVERGENCE_HEADER}`")));
    }
    let rows = lines
        .iter()
        .enumerate()
        .skip(3)
        .map(|(i, l)| {
            l.split_once(',')
                .and_then(|(g, b)| Some((g.parse().ok()?, b.parse().ok()?)))
                .ok_or_else(|| at_line(i + 1, "not a generation and its best objective"))
        })
        .collect::<Result<Vec<(usize, f64)>, Damage>>()?;
    Ok(Reading::Ours(Record {
        evaluations,
        journal_fnv: journal_fnv.to_string(),
        rows,
    }))
}

/// An island's file in the journals' folder, as (N, K, whether its convergence file):
/// `island-K-of-N.csv` (its journal) or `island-K-of-N.convergence.csv`, 1 <= K <= N, the
/// numbers as grainchain writes them. `None` for any other name (not an island's file).
fn island_file(name: &str) -> Option<(usize, usize, bool)> {
    let rest = name.strip_prefix("island-")?;
    let (rest, convergence) = match rest.strip_suffix(".convergence.csv") {
        Some(r) => (r, true),
        None => (rest.strip_suffix(".csv")?, false),
    };
    let (k, n) = rest.split_once("-of-")?;
    let number = |s: &str| s.parse::<usize>().ok().filter(|x| x.to_string() == s);
    let (k, n) = (number(k)?, number(n)?);
    (1..=n).contains(&k).then_some((n, k, convergence))
}

/// The command that runs island `k` of `n` of `problem`'s search whose journals are in `dir`
/// (with `--resume`: keeping what its journal holds).
fn island_command(problem: &DesignSpec, dir: &Path, k: usize, n: usize, resume: bool) -> String {
    let out = dir.parent().unwrap_or(dir);
    let shard = if n == 1 {
        String::new()
    } else {
        format!(" --shard {k}/{n}")
    };
    format!(
        "`grainchain design {}{shard}{} --out {}`",
        problem.path.display(),
        if resume { " --resume" } else { "" },
        out.display()
    )
}

/// Every island's journal in `dir` and its convergence file, checked and merged: the outcome
/// the outputs are written from. The islands found must be whole sets: for every N in a name
/// `island-K-of-N`, islands 1 to N, each with its journal (every line whole and matching its
/// checksum) and its convergence file (written when the island finished, matching its own
/// checksum and recording the journal as it is), all of this design file. Anything missing or
/// damaged is refused, naming the files and what to run (`JournalError`).
pub fn merge_journals(problem: &DesignSpec, dir: &Path) -> Result<Outcome, Error> {
    // (N, K) -> (journal there, convergence file there).
    let mut islands: std::collections::BTreeMap<(usize, usize), (bool, bool)> =
        std::collections::BTreeMap::new();
    if let Ok(rd) = std::fs::read_dir(dir) {
        for e in rd.flatten() {
            if let Some((n, k, convergence)) = e.file_name().to_str().and_then(island_file) {
                let there = islands.entry((n, k)).or_default();
                if convergence {
                    there.1 = true;
                } else {
                    there.0 = true;
                }
            }
        }
    }
    if islands.is_empty() {
        return Err(Error::Design(DesignFailure::NoEvaluations {
            file: problem.path.clone(),
            dir: dir.to_path_buf(),
            parts: "islands",
        }));
    }
    let sets: std::collections::BTreeSet<usize> = islands.keys().map(|&(n, _)| n).collect();
    let mut missing = Vec::new();
    let mut first = None;
    for &n in &sets {
        for k in 1..=n {
            let name = format!("island-{k}-of-{n}");
            match islands.get(&(n, k)) {
                Some((true, true)) => continue,
                Some((true, false)) => missing.push(format!(
                    "island {k} of {n} has not finished (no {name}.convergence.csv)"
                )),
                _ => missing.push(format!("island {k} of {n} is missing (no {name}.csv)")),
            }
            first.get_or_insert((k, n));
        }
    }
    if let Some((k, n)) = first {
        // A list of a few islands says what is wrong; the rest are counted.
        const LISTED: usize = 8;
        let more = missing.len().saturating_sub(LISTED);
        missing.truncate(LISTED);
        if more > 0 {
            missing.push(format!("and {more} more"));
        }
        let advice = format!(
            "run {} first, e.g. {} (--resume keeps what an interrupted island journalled), then \
             merge",
            if missing.len() == 1 { "it" } else { "them" },
            island_command(problem, dir, k, n, true)
        );
        return Err(JournalError::MissingIslands {
            dir: dir.to_path_buf(),
            missing,
            advice,
        }
        .into());
    }
    let space = (problem.sections(), problem.choices.len());
    let mut seen: HashMap<Vec<usize>, Scored> = HashMap::new();
    let mut by_gen: std::collections::BTreeMap<usize, f64> = std::collections::BTreeMap::new();
    for &(n, k) in islands.keys() {
        let path = dir.join(format!("island-{k}-of-{n}.csv"));
        let convergence = convergence_path(&path);
        let again = if n == 1 {
            format!(
                "run the search again with {}, which starts its journal afresh",
                island_command(problem, dir, k, n, false)
            )
        } else {
            format!(
                "run island {k} of {n} again with {}, which starts its journal afresh",
                island_command(problem, dir, k, n, false)
            )
        };
        let finish = format!(
            "finish {} with {}, which keeps the evaluations in its journal and writes its \
             convergence file anew",
            if n == 1 { "the search" } else { "the island" },
            island_command(problem, dir, k, n, true)
        );
        let foreign = |there: String| {
            at_line(
                1,
                format!(
                    "written for another design file (digest {there}; this one's is {})",
                    problem.digest
                ),
            )
        };
        let read = |p: &Path| {
            std::fs::read(p).map_err(|source| Error::Io {
                path: p.to_path_buf(),
                source,
            })
        };
        let bytes = read(&path)?;
        let journal = match check_journal(&bytes, space, &problem.digest, Reader::Merge) {
            Ok(Reading::Ours(j)) => j,
            Ok(Reading::Foreign(there)) => return Err(damaged(&path, foreign(there), again)),
            // A cut last line: the island was interrupted; --resume finishes it.
            Err(d) if d.interrupted => return Err(damaged(&path, d, finish)),
            Err(d) => return Err(damaged(&path, d, again)),
        };
        let record = match check_convergence(&read(&convergence)?, &problem.digest) {
            Ok(Reading::Ours(c)) => c,
            Ok(Reading::Foreign(there)) => {
                return Err(damaged(&convergence, foreign(there), finish))
            }
            Err(d) => return Err(damaged(&convergence, d, finish)),
        };
        let fnv = lines_fnv(&journal.lines);
        if (journal.lines.len(), &fnv) != (record.evaluations, &record.journal_fnv) {
            return Err(damaged(
                &path,
                whole_file(format!(
                    "{} evaluations (fnv1a {fnv} of their lines), but its island finished with \
                     {} (fnv1a {}, recorded in {}): changed after the island finished",
                    journal.lines.len(),
                    record.evaluations,
                    record.journal_fnv,
                    convergence
                        .file_name()
                        .map_or_else(String::new, |n| n.to_string_lossy().into_owned())
                )),
                finish,
            ));
        }
        // A design two islands ran: an exact result over a lower bound (one island may have
        // given up on it against its own front).
        for (genes, s) in journal.designs {
            match seen.get(&genes) {
                Some(old) if !old.given_up || s.given_up => {}
                _ => {
                    seen.insert(genes, s);
                }
            }
        }
        // Several islands: the best over islands after each generation.
        for (g, b) in record.rows {
            let e = by_gen.entry(g).or_insert(f64::INFINITY);
            *e = e.min(b);
        }
    }
    let mut all: Vec<Scored> = seen.into_values().collect();
    all.sort_by(|a, b| {
        a.objective
            .total_cmp(&b.objective)
            .then(a.genes.cmp(&b.genes))
    });
    Ok(Outcome {
        all,
        convergence: by_gen.into_iter().collect(),
        evaluated: 0,
        reference: reference(problem)?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A design that breaks a constraint (no peak, infinite objective: empty fields) and one
    /// with numbers.
    fn designs() -> [Scored; 2] {
        let broken = Scored {
            genes: vec![1, 0, 2],
            objective: f64::INFINITY,
            peak: f64::NAN,
            impulse: f64::NAN,
            duration: f64::NAN,
            mass: 0.25,
            length: 0.018,
            complete: true,
            given_up: false,
        };
        let found = Scored {
            genes: vec![0, 2, 2],
            objective: 0.1 + 0.2,
            peak: 6e-46,
            impulse: 1.5e15,
            duration: 4.5e-5,
            complete: false,
            given_up: true,
            ..broken.clone()
        };
        [broken, found]
    }

    fn journal_text(digest: &str) -> String {
        let mut text = format!("{}\n{JOURNAL_HEADER}\n", digest_line(digest));
        for s in designs() {
            text.push_str(&journal_line(&s, digest));
        }
        text
    }

    /// A journal of the design file with digest `d1`: 3 sections, 3 choices each.
    fn read(text: &[u8], reader: Reader) -> Result<Journal, Damage> {
        match check_journal(text, (3, 3), "d1", reader)? {
            Reading::Ours(j) => Ok(j),
            Reading::Foreign(d) => panic!("foreign {d}"),
        }
    }

    /// Every field reads back bit for bit, the empty ones as infinite and NaN.
    #[test]
    fn journal_lines_read_back_exactly() {
        let j = read(journal_text("d1").as_bytes(), Reader::Merge).unwrap();
        for s in designs() {
            let r = &j.designs[&s.genes];
            let numbers =
                |s: &Scored| [s.objective, s.peak, s.impulse, s.duration, s.mass, s.length];
            for (a, b) in numbers(r).into_iter().zip(numbers(&s)) {
                // NaN has more than one bit pattern: a missing number reads back as some NaN.
                assert!(
                    a.to_bits() == b.to_bits() || a.is_nan() && b.is_nan(),
                    "{a} {b}"
                );
            }
            assert_eq!((r.complete, r.given_up), (s.complete, s.given_up));
        }
        assert_eq!(j.lines.len(), 2);
    }

    /// A last line cut by an interruption: `--resume` drops it, a merge refuses it as such; the
    /// same line whole but edited is refused by both, at its line.
    #[test]
    fn only_a_cut_last_line_is_dropped_and_only_by_resume() {
        let text = journal_text("d1");
        // The last 10 bytes off: the line end and 9 of the 16 digits of the last checksum.
        let cut = &text.as_bytes()[..text.len() - 10];
        assert_eq!(read(cut, Reader::Resume).unwrap().designs.len(), 1);
        let d = read(cut, Reader::Merge).unwrap_err();
        assert!(d.interrupted && d.line == Some(4), "{d:?}");
        let edited = text.replacen("0.30000000000000004", "0.3", 1);
        assert_ne!(edited, text);
        for reader in [Reader::Resume, Reader::Merge] {
            let d = read(edited.as_bytes(), reader).unwrap_err();
            assert!(!d.interrupted && d.line == Some(4), "{d:?}");
            assert!(d.problem.contains("checksum"), "{d:?}");
        }
        // A line of another design file's journal (its checksum covers that file's digest).
        let other = journal_text("d2");
        let pasted = format!("{text}{}\n", other.lines().nth(2).unwrap());
        assert_eq!(
            read(pasted.as_bytes(), Reader::Resume).unwrap_err().line,
            Some(5)
        );
        // A gene beyond the choices, its checksum recomputed: not a design of this file.
        let body = "0.3.0,1,1,1,1,1,1,true,false";
        let forged = format!("{text}{body},{}\n", line_fnv("d1", body));
        let d = read(forged.as_bytes(), Reader::Resume).unwrap_err();
        assert!(
            d.line == Some(5) && d.problem.contains("not a result"),
            "{d:?}"
        );
    }

    /// The record of a journal does not depend on the order of its lines.
    #[test]
    fn a_journals_record_is_of_its_lines_as_a_set() {
        let lines: Vec<String> = ["b", "a", "c"].map(String::from).to_vec();
        let mut other = lines.clone();
        other.reverse();
        assert_eq!(lines_fnv(&lines), lines_fnv(&other));
        assert_ne!(lines_fnv(&lines), lines_fnv(&lines[..2]));
    }

    /// A convergence file as written reads back; one byte changed anywhere is refused.
    #[test]
    fn a_convergence_file_checks_itself() {
        let dir = std::env::temp_dir().join(format!("grainchain-search-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("island-1-of-1.convergence.csv");
        let journal = read(journal_text("d1").as_bytes(), Reader::Merge).unwrap();
        write_convergence(&path, &journal, "d1", &[(1, 0.5), (2, 0.25)]).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let _ = std::fs::remove_dir_all(&dir);
        let Ok(Reading::Ours(r)) = check_convergence(&bytes, "d1") else {
            panic!("{}", String::from_utf8_lossy(&bytes));
        };
        assert_eq!(r.evaluations, 2);
        assert_eq!(r.journal_fnv, lines_fnv(&journal.lines));
        assert_eq!(r.rows, [(1, 0.5), (2, 0.25)]);
        for i in (0..bytes.len()).filter(|&i| bytes[i] != b'\n') {
            let mut b = bytes.clone();
            b[i] = if b[i] == b'1' { b'2' } else { b'1' };
            assert!(
                !matches!(check_convergence(&b, "d1"), Ok(Reading::Ours(_))),
                "byte {i} changed: {}",
                String::from_utf8_lossy(&b)
            );
        }
    }

    /// Only the names grainchain writes are islands' files.
    #[test]
    fn island_files_by_name() {
        assert_eq!(island_file("island-2-of-3.csv"), Some((3, 2, false)));
        assert_eq!(
            island_file("island-2-of-3.convergence.csv"),
            Some((3, 2, true))
        );
        for name in [
            "island-02-of-3.csv",
            "island-4-of-3.csv",
            "island-0-of-3.csv",
            "island-1-of-0.csv",
            "island-1-of-3.csv.partial",
            "notes.csv",
        ] {
            assert_eq!(island_file(name), None, "{name}");
        }
    }
}
