//! Fig. 3: the standard container's leaks at the paper's 280th snapshot, as one unit: the run
//! (also at `dt / 8` with `--check-step`), its analysis ([`Fig3`]) and its outputs
//! (`fig3_snapshot.csv`, `fig3_pulses.csv`, `fig3.svg`, its rows of the paper comparison and its
//! section of REPORT.md).
//!
//! Definitions (also stated in REPORT.md): the *incident energy* is the energy of the largest pulse
//! right of the container in the first listed snapshot (the solitary wave launched by the striker,
//! before it reaches the container); the *leading waves* are the outermost pulses left and right of
//! the container in the figure's snapshot, among pulses found over the whole chain, excluding
//! pulses that touch an end of the chain (on the right that is the striker's slow rebound, which
//! never was in the container).

use super::curves::curve_diff;
use super::pulses::{pulse_row, pulses_in, snap_pair, with_fraction, PulseOut};
use crate::batch::scenes::{self, SceneSource};
use crate::batch::{RunData, Snap};
use crate::error::Error;
use crate::reproduce::jobs::{RunEntry, Runs};
use crate::reproduce::options::{Figure, Options, STEP_FACTOR};
use crate::reproduce::plan::{listed_snapshots, load, JobKey, Plan};
use crate::reproduce::render::plots::velocity_plot;
use crate::reproduce::render::step_check::{self as check, Describe};
use crate::reproduce::render::text::{num, rel_diff, sig};
use crate::reproduce::step_check::{rel, StepCheck};
use crate::reproduce::table::Table;
use crate::reproduce::unit::Svg;
use crate::reproduce::unit::{FigureUnit, Part};
use grainchain_engine::paper;
use grainchain_engine::PulseRule;
use std::fmt::Write;

/// Fig. 3: the standard container's leaks at the paper's 280th snapshot.
#[derive(Clone, Debug)]
pub struct Fig3 {
    /// The figure's snapshot (the last listed, the paper's 280th).
    pub snap: Snap,
    /// Printed grain number of internal grain 0.
    pub first_grain: i64,
    /// First and last grain of the container region (printed numbers, inclusive).
    pub container: (i64, i64),
    /// The scene's pulse rule, used for every pulse here.
    pub rule: PulseRule,
    /// E0: the energy at t = 0, all the striker's.
    pub striker_energy: f64,
    /// The incident solitary wave (first listed snapshot).
    pub incident: PulseOut,
    /// Output index of the first listed snapshot, where `incident` was found.
    pub incident_index: u64,
    /// Pulses outside the container, `fraction` of the incident energy; side "left"/"right".
    pub outside: Vec<(&'static str, PulseOut)>,
    /// The leading wave on the left: the leftmost pulse of `outside` left of the container
    /// (`None`: none there).
    pub left_lead: Option<PulseOut>,
    /// The leading wave on the right: the rightmost pulse of `outside` right of the container
    /// (`None`: none there).
    pub right_lead: Option<PulseOut>,
    /// Energy of the container region in the figure's snapshot.
    pub container_energy: f64,
    /// Grains between the left end of the chain and the leftmost grain ever disturbed.
    pub margin: usize,
    /// Grains of the incident wave (`incident.last - incident.first + 1`).
    pub incident_width: f64,
    /// The incident wave's energy in % of the striker's.
    pub incident_percent_of_striker: f64,
    /// `container_energy` in % of the incident wave's energy.
    pub container_percent: f64,
    /// The largest pulse of `outside` in % of the incident energy (0 when there is none).
    pub largest_outside_percent: f64,
    /// The most energetic pulse of `outside` (the last of equals) and the local maxima of the
    /// grain energies over its grains in the figure's snapshot: more than one means it may be
    /// several waves the valley rule did not split.
    pub largest_outside: Option<LargestPulse>,
}

/// The most energetic pulse outside the container in the figure's snapshot.
#[derive(Clone, Debug)]
pub struct LargestPulse {
    /// "left" or "right" of the container.
    pub side: &'static str,
    /// The pulse.
    pub pulse: PulseOut,
    /// Local maxima of the grain energies over its grains.
    pub peaks: usize,
}

/// The most energetic pulse of `outside` (the last of equals) with its peaks in `snap`.
fn largest(
    outside: &[(&'static str, PulseOut)],
    snap: &Snap,
    first_grain: i64,
) -> Option<LargestPulse> {
    outside
        .iter()
        .max_by(|a, b| a.1.energy.total_cmp(&b.1.energy))
        .map(|(side, p)| LargestPulse {
            side,
            pulse: p.clone(),
            peaks: local_maxima(
                &snap.energy,
                (p.first - first_grain) as usize,
                (p.last - first_grain) as usize,
            ),
        })
}

/// Local maxima of `e` over `a..=b`.
fn local_maxima(e: &[f64], a: usize, b: usize) -> usize {
    (a..=b)
        .filter(|&i| {
            let l = if i > a { e[i - 1] } else { f64::NEG_INFINITY };
            let r = if i < b { e[i + 1] } else { f64::NEG_INFINITY };
            e[i] > l && e[i] >= r
        })
        .count()
}

/// Fig. 3 from the run `d`, which records the region `container` and two snapshots (the
/// incident wave's and the figure's); pulses found with `rule`.
fn analyse(d: &RunData, rule: PulseRule) -> Result<Fig3, Error> {
    let (first, snap) = snap_pair(d, "fig3")?;
    let container = d.region("container")?;
    let (a, b) = container.range;
    let fg = d.first_grain;
    let n = d.run.grains;
    let incident = pulses_in(&first, b + 1, n - 1, &rule, fg)
        .into_iter()
        .max_by(|x, y| x.energy.total_cmp(&y.energy))
        .ok_or(crate::error::ReproduceError::NoIncidentWave {
            figure: "fig3",
            place: "right of the container in the first snapshot",
        })?;
    let e_inc = incident.energy;
    let all = pulses_in(&snap, 0, n - 1, &rule, fg);
    let (ca, cb) = (a as i64 + fg, b as i64 + fg);
    let (g0, g1) = (fg, n as i64 - 1 + fg);
    let mut outside = Vec::new();
    for p in all {
        if p.first == g0 || p.last == g1 {
            continue; // touches an end of the chain (the striker's rebound on the right)
        }
        let p = with_fraction(p, e_inc);
        if p.last < ca {
            outside.push(("left", p));
        } else if p.first > cb {
            outside.push(("right", p));
        }
    }
    let left_lead = outside
        .iter()
        .filter(|(s, _)| *s == "left")
        .min_by_key(|(_, p)| p.first)
        .map(|(_, p)| p.clone());
    let right_lead = outside
        .iter()
        .filter(|(s, _)| *s == "right")
        .max_by_key(|(_, p)| p.last)
        .map(|(_, p)| p.clone());
    let container_energy = container.energy[snap.index as usize];
    let largest_outside_percent = outside.iter().map(|(_, p)| p.percent).fold(0.0, f64::max);
    let largest_outside = largest(&outside, &snap, fg);
    Ok(Fig3 {
        incident_width: (incident.last - incident.first + 1) as f64,
        incident_percent_of_striker: 100.0 * incident.energy / d.run.initial_energy,
        container_percent: 100.0 * container_energy / e_inc,
        largest_outside_percent,
        largest_outside,
        container_energy,
        first_grain: fg,
        container: (ca, cb),
        rule,
        striker_energy: d.run.initial_energy,
        incident: with_fraction(incident, e_inc),
        incident_index: first.index,
        outside,
        left_lead,
        right_lead,
        margin: d.run.ever.0,
        snap,
    })
}

/// A side of the container (Fig. 3's leading waves).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    /// Left of the container (away from the striker).
    Left,
    /// Right of the container (the striker's side).
    Right,
}

/// A quantity of Fig. 3 compared between the runs at `dt` and at `dt / STEP_FACTOR`.
#[derive(Clone, Debug, PartialEq)]
pub enum Fig3Quantity {
    /// Energy of the leading wave on one side.
    LeadingWave(Side),
    /// Container energy over the run.
    ContainerEnergy {
        /// Output index of the largest relative difference.
        at: usize,
        /// First output index at which the relative difference exceeds
        /// the curve comparison's level, 1e-4 (`None`: never).
        first_above: Option<usize>,
    },
}

impl Describe for Fig3Quantity {
    fn describe(&self) -> (String, String) {
        match self {
            Fig3Quantity::LeadingWave(Side::Left) => {
                ("left leading wave energy, relative".into(), String::new())
            }
            Fig3Quantity::LeadingWave(Side::Right) => {
                ("right leading wave energy, relative".into(), String::new())
            }
            Fig3Quantity::ContainerEnergy { at, first_above } => (
                "container energy over the run, max relative".into(),
                format!(
                    "at snapshot {at}; first above 1e-4 at {}",
                    first_above.map_or("-".into(), |k| k.to_string())
                ),
            ),
        }
    }
}

impl Figure {
    /// Fig. 3 (`--only fig3`; its help line is the second argument).
    pub const FIG3: Figure = Figure::new(
        "fig3",
        "Fig. 3: the standard container's leading waves at the figure's snapshot (`fig3-standard-container.toml`)",
    );
}

/// The Fig. 3 unit; it keeps its scene and the scene's pulse rule for the analysis, and what
/// it measured.
#[derive(Default)]
pub(crate) struct Fig3Unit {
    /// Its analysis (set by `analyse`).
    out: Option<Fig3>,
    /// Its step-size check (`--check-step`, set by `analyse`).
    step: Option<StepCheck<Fig3Quantity>>,
    /// `fig3-standard-container.toml` (read by `load`).
    src: Option<SceneSource>,
    /// Its pulse rule (set by `plan`).
    rule: PulseRule,
}

impl Fig3Unit {
    /// Its numbers: the analysis and the step-size check.
    pub(crate) fn into_results(self) -> (Option<Fig3>, Option<StepCheck<Fig3Quantity>>) {
        (self.out, self.step)
    }
}

impl FigureUnit for Fig3Unit {
    fn wanted(&self, opts: &Options) -> bool {
        opts.wants(Figure::FIG3)
    }

    /// The run, also at `dt / 8` with `--check-step`.
    fn load(&mut self, opts: &Options) -> Result<(), Error> {
        self.src = Some(load(opts, "fig3-standard-container.toml")?);
        Ok(())
    }

    fn plan(&mut self, opts: &Options, plan: &mut Plan) -> Result<(), Error> {
        let src = self.src.as_ref().expect("loaded");
        let (snaps, rule) = listed_snapshots(src, "fig3")?;
        self.rule = rule;
        let main = src.checked()?;
        plan.add(JobKey::Fig3 { fine: false }, main, snaps.clone());
        if opts.check_step {
            let sc = src.scene(|f| {
                scenes::refine_step(f, STEP_FACTOR);
                Ok(())
            })?;
            plan.add(JobKey::Fig3 { fine: true }, sc, snaps);
        }
        Ok(())
    }

    fn analyse(&mut self, runs: &Runs) -> Result<(), Error> {
        let d = runs.need(&JobKey::Fig3 { fine: false })?;
        let f = analyse(d, self.rule)?;
        if let Some(df) = runs.get(&JobKey::Fig3 { fine: true }) {
            let ff = analyse(df, self.rule)?;
            self.step = Some(step_check(&f, &ff, d, df)?);
        }
        self.out = Some(f);
        Ok(())
    }

    fn render(&self, _: &Options, _: &[RunEntry]) -> Result<Part, Error> {
        let Some(f) = &self.out else {
            return Ok(Part::default());
        };
        Ok(Part {
            compare: compare_rows(f),
            section: section(f),
            tables: tables(f),
            svgs: vec![svg(f)?],
            checks: self.step.as_ref().map_or_else(Vec::new, check::rows),
        })
    }
}

/// The step-size check (`f` from the run `d`, `ff` from the fine run `df`).
fn step_check(
    f: &Fig3,
    ff: &Fig3,
    d: &RunData,
    df: &RunData,
) -> Result<StepCheck<Fig3Quantity>, Error> {
    let lead = |a: &Option<PulseOut>, b: &Option<PulseOut>| match (a, b) {
        (Some(a), Some(b)) => rel(a.fraction, b.fraction),
        _ => f64::NAN,
    };
    let e0 = d.run.initial_energy;
    let (e, ef) = (d.region("container")?, df.region("container")?);
    let curve = curve_diff(e.energy, ef.energy, e0);
    let container = Fig3Quantity::ContainerEnergy {
        at: curve.at,
        first_above: curve.first_above_level,
    };
    Ok(StepCheck {
        run: "fig3".into(),
        method: d.run.method,
        dt: d.run.dt,
        dt_fine: df.run.dt,
        rows: vec![
            (
                Fig3Quantity::LeadingWave(Side::Left),
                lead(&f.left_lead, &ff.left_lead),
            ),
            (
                Fig3Quantity::LeadingWave(Side::Right),
                lead(&f.right_lead, &ff.right_lead),
            ),
            (container, curve.max_rel),
        ],
    })
}

/// Its rows of the paper comparison: wave width, leading waves, the largest pulse outside.
fn compare_rows(f: &Fig3) -> String {
    let mut s = String::new();
    let w = &mut s;
    let width = f.incident_width;
    let _ = writeln!(
        w,
        "| 3 | grains in a solitary wave | about 5 | {} (the incident wave, grains {}-{}, at the pulse threshold {:e}) | {} | - |",
        width,
        f.incident.first,
        f.incident.last,
        f.rule.threshold,
        rel_diff(width, paper::WAVE_GRAINS)
    );
    let lead = |p: &Option<PulseOut>| p.as_ref().map_or(f64::NAN, |p| p.percent);
    let (r, l) = (lead(&f.right_lead), lead(&f.left_lead));
    let _ = writeln!(
        w,
        "| 3 | leading wave leaving at the right, % of incident | {} | {} | {} | reconstructed layout (section masses and exponents are guesses); the leak through a linear wall depends on them |",
        paper::RIGHT_PERCENT,
        sig(r),
        rel_diff(r, paper::RIGHT_PERCENT)
    );
    let _ = writeln!(
        w,
        "| 3 | leading wave leaving at the left, % of incident | {} | {} | {} | reconstructed layout |",
        paper::LEFT_PERCENT,
        sig(l),
        rel_diff(l, paper::LEFT_PERCENT)
    );
    let biggest = f.largest_outside_percent;
    let why = match &f.largest_outside {
        Some(LargestPulse { side, pulse: p, peaks }) if biggest >= 10.0 => format!(
            "the largest pulse ({side}, grains {}-{}) has {peaks} energy peaks that the valley rule ({}) does not split, so it may be several waves; otherwise reconstructed layout",
            p.first, p.last, f.rule.valley
        ),
        _ => "agrees".to_string(),
    };
    let _ = writeln!(
        w,
        "| 3 | largest pulse outside the container, % of incident | < 10 (\"less than 10 % of the original\") | {} | - | {why} |",
        sig(biggest),
    );
    s
}

/// `## Fig. 3`: definitions, the container energy and the pulses outside.
fn section(f: &Fig3) -> String {
    let mut s = String::new();
    let w = &mut s;
    let _ = writeln!(
        w,
        "## Fig. 3: leaks of the standard container (a), walls m = 10\n"
    );
    let _ = writeln!(
        w,
        "Scene `fig3-standard-container.toml` (container at grains {}-{}, free ends {} grains away on the left, \
         the striker at the right end). Snapshot {} (`fig3_snapshot.csv`, `fig3.svg`).\n",
        f.container.0,
        f.container.1,
        f.container.0 - f.first_grain,
        f.snap.index
    );
    let _ = writeln!(
        w,
        "- **Incident energy** = the energy of the solitary wave launched by the striker, measured as the \
         largest pulse right of the container at snapshot {}: {} ({} % of the striker's {}; the rest is the \
         striker's slow rebound).",
        f.incident_index,
        sig(f.incident.energy),
        sig(f.incident_percent_of_striker),
        sig(f.striker_energy)
    );
    let _ = writeln!(
        w,
        "- **Leading waves** = the outermost pulses left and right of the container at snapshot {}, pulses found \
         over the whole chain with threshold {:e} and valley {}, excluding pulses touching an end of the chain \
         (the striker's rebound).",
        f.snap.index, f.rule.threshold, f.rule.valley
    );
    let _ = writeln!(
        w,
        "- Energy still in the container: {} % of the incident energy. The furthest disturbance stayed {} grains from the left end.\n",
        sig(f.container_percent),
        f.margin
    );
    let _ = writeln!(
        w,
        "| side | grains | energy, % of incident | peak velocity |"
    );
    let _ = writeln!(w, "|---|---|---|---|");
    for (side, p) in &f.outside {
        let _ = writeln!(
            w,
            "| {side} | {}-{} | {} | {} |",
            p.first,
            p.last,
            sig(p.percent),
            sig(p.peak_velocity)
        );
    }
    let _ = writeln!(w);
    s
}

/// `fig3_snapshot.csv`, `fig3_pulses.csv`.
fn tables(f: &Fig3) -> Vec<Table> {
    let mut ts = Vec::new();
    let mut t = Table::new("fig3_snapshot.csv", &["grain", "velocity", "energy"]);
    for (i, (v, e)) in f.snap.velocity.iter().zip(&f.snap.energy).enumerate() {
        t.push(vec![(i as i64 + f.first_grain).into(), num(*v), num(*e)]);
    }
    ts.push(t);
    let mut t = Table::new(
        "fig3_pulses.csv",
        &[
            "side",
            "first",
            "last",
            "position",
            "peak_velocity",
            "energy",
            "percent_of_incident",
        ],
    );
    t.push(pulse_row(
        "incident".into(),
        &f.incident,
        f.incident.percent,
    ));
    for (side, p) in &f.outside {
        t.push(pulse_row((*side).into(), p, p.percent));
    }
    ts.push(t);
    ts
}

/// `fig3.svg`: velocity against grain number in the figure's snapshot.
fn svg(f: &Fig3) -> Result<Svg, Error> {
    let text = velocity_plot(
        &format!(
            "Fig. 3: snapshot {} of the standard container (reconstructed layout)",
            f.snap.index
        ),
        f.first_grain,
        &[(format!("snapshot {}", f.snap.index), &f.snap.velocity)],
        &[
            (f.container.0 as f64 - 0.5, "container edges"),
            (f.container.1 as f64 + 0.5, "container edges"),
        ],
    )?;
    Ok(Svg {
        name: "fig3.svg",
        text,
    })
}
