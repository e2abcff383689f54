//! Fig. 1: a solitary wave through a heavy-to-light interface, as one unit: the run and its
//! control run (each also at `dt / 8` with `--check-step`), their analysis ([`Fig1`]) and its
//! outputs (`fig1_snapshots.csv`, `fig1_pulses.csv`, `fig1.svg`, its rows of the paper
//! comparison and its section of REPORT.md).
//!
//! Definitions (also stated in REPORT.md): the *incident wave* is the largest pulse of the heavy
//! section in the first listed snapshot; the *transmitted waves* are the pulses of the light
//! section in the last one, leading (rightmost) first; the *reflected energy* is the energy left in
//! the heavy section minus the energy left in the same grains of a control run whose light section
//! is heavy too (so the striker's own slow rebound, present in both, cancels).

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
use crate::reproduce::unit::{FigureUnit, Part};
use grainchain_engine::paper;
use grainchain_engine::PulseRule;
use std::fmt::Write;

/// Fig. 1: heavy-to-light interface.
#[derive(Clone, Debug)]
pub struct Fig1 {
    /// The first listed snapshot: the incident wave still in the heavy section.
    pub before: Snap,
    /// The last listed snapshot, the figure's: the transmitted waves in the light section.
    pub after: Snap,
    /// Printed grain number of internal grain 0 (0 when, as in the scene file, the striker hits
    /// the left end).
    pub first_grain: i64,
    /// First grain of the light section (printed number).
    pub interface: i64,
    /// Grains of the heavy section.
    pub heavy: usize,
    /// Grains of the light section.
    pub light: usize,
    /// The scene's pulse rule, used for every pulse here.
    pub rule: PulseRule,
    /// E0: the energy at t = 0, all the striker's.
    pub striker_energy: f64,
    /// The incident wave: the largest pulse of the heavy section in `before` (`fraction` 1).
    pub incident: PulseOut,
    /// Pulses of the light section, leading first; `fraction` is of the incident wave's energy.
    pub transmitted: Vec<PulseOut>,
    /// Energy left in the heavy section in `after`.
    pub heavy_after: f64,
    /// Energy in the same grains at the same snapshot of the control run (light section made
    /// heavy): the striker's own rebound, without any reflection at the interface.
    pub heavy_control: f64,
    /// `heavy_after - heavy_control`.
    pub reflected: f64,
    /// Energy in the light section in `after`.
    pub light_after: f64,
    /// Grains between the furthest disturbance and the far end.
    pub margin: usize,
    /// Transmitted waves carrying at least 1 % of the incident energy.
    pub above_1_percent: usize,
    /// Transmitted waves carrying at least 0.1 % of the incident energy.
    pub above_0_1_percent: usize,
    /// Mean ratio of a transmitted wave's energy to the previous one's, over the first (at
    /// most 5) pairs of leading waves (0 when fewer than two were found).
    pub train_ratio: f64,
    /// `reflected / incident.energy`.
    pub reflected_fraction: f64,
    /// `100 * reflected_fraction`: reflected energy in % of the incident wave's.
    pub reflected_percent: f64,
    /// `light_after` in % of the incident wave's energy.
    pub light_percent: f64,
    /// `heavy_after` in % of the incident wave's energy.
    pub heavy_percent: f64,
    /// `heavy_control` in % of the incident wave's energy.
    pub control_percent: f64,
}

impl Fig1 {
    /// Transmitted waves carrying at least `fraction` of the incident energy.
    pub fn count_above(&self, fraction: f64) -> usize {
        count_above(&self.transmitted, fraction)
    }
}

fn count_above(transmitted: &[PulseOut], fraction: f64) -> usize {
    transmitted
        .iter()
        .filter(|p| p.fraction >= fraction)
        .count()
}

/// Fig. 1 from the run `main` and its control run `control` (light section made heavy), both
/// recording the regions `heavy` and `light` and two snapshots; pulses found with `rule`.
fn analyse(main: &RunData, control: &RunData, rule: PulseRule) -> Result<Fig1, Error> {
    let (before, after) = snap_pair(main, "fig1")?;
    let (heavy, light) = (main.region("heavy")?, main.region("light")?);
    let (h, l) = (heavy.range, light.range);
    let fg = main.first_grain;
    let incident = pulses_in(&before, h.0, h.1, &rule, fg)
        .into_iter()
        .max_by(|a, b| a.energy.total_cmp(&b.energy))
        .ok_or(crate::error::ReproduceError::NoIncidentWave {
            figure: "fig1",
            place: "in the heavy section",
        })?;
    let e_inc = incident.energy;
    let mut transmitted: Vec<PulseOut> = pulses_in(&after, l.0, l.1, &rule, fg)
        .into_iter()
        .map(|p| with_fraction(p, e_inc))
        .collect();
    transmitted.sort_by(|a, b| b.position.total_cmp(&a.position));
    let k = after.index as usize;
    let heavy_after = heavy.energy[k];
    let heavy_control = control.region("heavy")?.energy[k];
    let pairs = transmitted.len().saturating_sub(1).min(5);
    let train_ratio = (0..pairs)
        .map(|k| transmitted[k + 1].energy / transmitted[k].energy)
        .sum::<f64>()
        / pairs.max(1) as f64;
    let reflected = heavy_after - heavy_control;
    let reflected_fraction = reflected / e_inc;
    let light_after = light.energy[k];
    Ok(Fig1 {
        above_1_percent: count_above(&transmitted, 0.01),
        above_0_1_percent: count_above(&transmitted, 0.001),
        train_ratio,
        reflected_fraction,
        reflected_percent: 100.0 * reflected_fraction,
        light_percent: 100.0 * light_after / e_inc,
        heavy_percent: 100.0 * heavy_after / e_inc,
        control_percent: 100.0 * heavy_control / e_inc,
        interface: l.0 as i64 + fg,
        heavy: h.1 - h.0 + 1,
        light: l.1 - l.0 + 1,
        first_grain: fg,
        rule,
        striker_energy: main.run.initial_energy,
        incident: with_fraction(incident, e_inc),
        transmitted,
        heavy_after,
        heavy_control,
        reflected,
        light_after,
        margin: main.run.grains - main.run.ever.1,
        before,
        after,
    })
}

/// A quantity of Fig. 1 compared between the runs at `dt` and at `dt / STEP_FACTOR`.
#[derive(Clone, Debug, PartialEq)]
pub enum Fig1Quantity {
    /// Both velocity snapshots, max |dv| / max |v|.
    VelocitySnapshots,
    /// Energies of the `waves` leading transmitted waves; pulses found at each step.
    TransmittedEnergies {
        /// Leading waves compared (at most 10, and no more than either run found).
        waves: usize,
        /// Transmitted pulses found at `dt`.
        found: usize,
        /// Transmitted pulses found at `dt / STEP_FACTOR`.
        found_fine: usize,
    },
    /// Reflected energy over incident.
    Reflected,
}

impl Describe for Fig1Quantity {
    fn describe(&self) -> (String, String) {
        match self {
            Fig1Quantity::VelocitySnapshots => (
                "velocity snapshots, max |dv| / max |v|".into(),
                String::new(),
            ),
            Fig1Quantity::TransmittedEnergies {
                waves,
                found,
                found_fine,
            } => (
                format!("energies of the {waves} leading transmitted waves, max relative"),
                format!("{found} vs {found_fine} pulses found"),
            ),
            Fig1Quantity::Reflected => (
                "reflected energy / incident, absolute difference".into(),
                String::new(),
            ),
        }
    }
}

impl Figure {
    /// Fig. 1 (`--only fig1`; its help line is the second argument).
    pub const FIG1: Figure = Figure::new(
        "fig1",
        "Fig. 1: a solitary wave from heavy into light grains breaks into a train of solitary waves (`fig1-heavy-to-light.toml` and its control run)",
    );
}

/// The Fig. 1 unit; it keeps its scene and the scene's pulse rule for the analysis, and what
/// it measured.
#[derive(Default)]
pub(crate) struct Fig1Unit {
    /// Its analysis (set by `analyse`).
    out: Option<Fig1>,
    /// Its step-size check (`--check-step`, set by `analyse`).
    step: Option<StepCheck<Fig1Quantity>>,
    /// `fig1-heavy-to-light.toml` (read by `load`).
    src: Option<SceneSource>,
    /// Its pulse rule (set by `plan`).
    rule: PulseRule,
}

impl Fig1Unit {
    /// Its numbers: the analysis and the step-size check.
    pub(crate) fn into_results(self) -> (Option<Fig1>, Option<StepCheck<Fig1Quantity>>) {
        (self.out, self.step)
    }
}

impl FigureUnit for Fig1Unit {
    fn wanted(&self, opts: &Options) -> bool {
        opts.wants(Figure::FIG1)
    }

    /// The run and its control run (the light section heavy too), each also at `dt / 8` with
    /// `--check-step`.
    fn load(&mut self, opts: &Options) -> Result<(), Error> {
        self.src = Some(load(opts, "fig1-heavy-to-light.toml")?);
        Ok(())
    }

    fn plan(&mut self, opts: &Options, plan: &mut Plan) -> Result<(), Error> {
        let src = self.src.as_ref().expect("loaded");
        let (snaps, rule) = listed_snapshots(src, "fig1")?;
        self.rule = rule;
        let fines: &[bool] = if opts.check_step {
            &[false, true]
        } else {
            &[false]
        };
        for &fine in fines {
            for control in [false, true] {
                let sc = src.scene(|f| {
                    if control {
                        scenes::copy_mass(src, f, "light", "heavy")?;
                    }
                    if fine {
                        scenes::refine_step(f, STEP_FACTOR);
                    }
                    Ok(())
                })?;
                plan.add(JobKey::Fig1 { control, fine }, sc, snaps.clone());
            }
        }
        Ok(())
    }

    fn analyse(&mut self, runs: &Runs) -> Result<(), Error> {
        let key = |control, fine| JobKey::Fig1 { control, fine };
        let m = runs.need(&key(false, false))?;
        let f = analyse(m, runs.need(&key(true, false))?, self.rule)?;
        if let (Some(mf), Some(cf)) = (runs.get(&key(false, true)), runs.get(&key(true, true))) {
            let ff = analyse(mf, cf, self.rule)?;
            self.step = Some(step_check(&f, &ff, m, mf));
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

/// The step-size check (`f` from the runs `m`, `ff` from the fine runs `mf`).
fn step_check(f: &Fig1, ff: &Fig1, m: &RunData, mf: &RunData) -> StepCheck<Fig1Quantity> {
    let vmax = ff
        .after
        .velocity
        .iter()
        .chain(&ff.before.velocity)
        .fold(0.0f64, |a, v| a.max(v.abs()));
    let dv = f
        .after
        .velocity
        .iter()
        .zip(&ff.after.velocity)
        .chain(f.before.velocity.iter().zip(&ff.before.velocity))
        .fold(0.0f64, |a, (x, y)| a.max((x - y).abs()))
        / vmax;
    let k = f.transmitted.len().min(ff.transmitted.len()).min(10);
    let de = (0..k)
        .map(|i| rel(f.transmitted[i].energy, ff.transmitted[i].energy))
        .fold(0.0, f64::max);
    let transmitted = Fig1Quantity::TransmittedEnergies {
        waves: k,
        found: f.transmitted.len(),
        found_fine: ff.transmitted.len(),
    };
    let reflected = (f.reflected - ff.reflected).abs() / ff.incident.energy;
    StepCheck {
        run: "fig1".into(),
        method: m.run.method,
        dt: m.run.dt,
        dt_fine: mf.run.dt,
        rows: vec![
            (Fig1Quantity::VelocitySnapshots, dv),
            (transmitted, de),
            (Fig1Quantity::Reflected, reflected),
        ],
    }
}

/// Its rows of the paper comparison: transmitted waves, reflected energy.
fn compare_rows(f: &Fig1) -> String {
    let mut s = String::new();
    let w = &mut s;
    let n1 = f.above_1_percent;
    let _ = writeln!(
        w,
        "| 1 | transmitted solitary waves (mass ratio 10) | \"about the mass ratio\" (10) | {} with >= 1 % of the incident energy; {} with >= 0.1 %; {} pulses at the pulse rule | {} | the train does not end (each of the first waves carries {:.2} of the previous one's energy on average), so a count needs an energy threshold the paper does not state |",
        n1,
        f.above_0_1_percent,
        f.transmitted.len(),
        rel_diff(n1 as f64, paper::MASS_RATIO),
        f.train_ratio
    );
    let _ = writeln!(
        w,
        "| 1 | reflected energy | 0 (\"total transmission\") | {} % of the incident wave | - | {} |",
        sig(f.reflected_percent),
        if f.reflected_fraction.abs() < 1e-3 { "agrees (below 0.1 %)" } else { "differs: energy stays behind in the heavy section" }
    );
    s
}

/// `## Fig. 1`: the interface, the energy balance and the transmitted waves.
fn section(f: &Fig1) -> String {
    let mut s = String::new();
    let w = &mut s;
    let _ = writeln!(w, "## Fig. 1: heavy-to-light interface\n");
    let _ = writeln!(
        w,
        "Scene `fig1-heavy-to-light.toml`: {} heavy grains (m = 10) then {} light ones (m = 1), Hertz, \
         a striker of the heavy mass. Snapshots {} (t = {}) and {} (t = {}); `fig1_snapshots.csv`, `fig1.svg`. \
         Pulse rule: threshold {:e} of the largest grain energy in the light section, valley {}.\n",
        f.heavy,
        f.light,
        f.before.index,
        f.before.time,
        f.after.index,
        f.after.time,
        f.rule.threshold,
        f.rule.valley
    );
    let _ = writeln!(
        w,
        "- Striker energy {}; incident solitary wave {} (grains {}-{}).",
        sig(f.striker_energy),
        sig(f.incident.energy),
        f.incident.first,
        f.incident.last
    );
    let _ = writeln!(
        w,
        "- Light section at the end: {} % of the incident energy; heavy section {} % (control run without the interface: {} %, the striker's own rebound); reflected: {} %.",
        sig(f.light_percent),
        sig(f.heavy_percent),
        sig(f.control_percent),
        sig(f.reflected_percent)
    );
    let _ = writeln!(
        w,
        "- The furthest disturbance stayed {} grains from the light section's end.\n",
        f.margin
    );
    let _ = writeln!(
        w,
        "| wave | grains | energy, % of incident | peak velocity |"
    );
    let _ = writeln!(w, "|---|---|---|---|");
    for (k, p) in f.transmitted.iter().enumerate().take(12) {
        let _ = writeln!(
            w,
            "| {} | {}-{} | {} | {} |",
            k + 1,
            p.first,
            p.last,
            sig(p.percent),
            sig(p.peak_velocity)
        );
    }
    if f.transmitted.len() > 12 {
        let _ = writeln!(
            w,
            "| ... | {} more in `fig1_pulses.csv` | | |",
            f.transmitted.len() - 12
        );
    }
    let _ = writeln!(w);
    s
}

/// `fig1_snapshots.csv`, `fig1_pulses.csv`.
fn tables(f: &Fig1) -> Vec<Table> {
    let mut ts = Vec::new();
    let mut t = Table::new(
        "fig1_snapshots.csv",
        &["grain", "velocity_before", "velocity_after"],
    );
    for (i, (a, b)) in f.before.velocity.iter().zip(&f.after.velocity).enumerate() {
        t.push(vec![(i as i64 + f.first_grain).into(), num(*a), num(*b)]);
    }
    ts.push(t);
    let mut t = Table::new(
        "fig1_pulses.csv",
        &[
            "rank",
            "first",
            "last",
            "position",
            "peak_velocity",
            "energy",
            "fraction_of_incident",
        ],
    );
    for (k, p) in f.transmitted.iter().enumerate() {
        t.push(pulse_row((k + 1).into(), p, p.fraction));
    }
    ts.push(t);
    ts
}

/// `fig1.svg`: velocity against grain number, before and after the interface.
fn svg(f: &Fig1) -> Result<crate::reproduce::unit::Svg, Error> {
    let text = velocity_plot(
        "Fig. 1: solitary wave through a heavy-to-light interface (mass ratio 10)",
        f.first_grain,
        &[
            (
                format!("t = {} (snapshot {})", f.before.time, f.before.index),
                &f.before.velocity,
            ),
            (
                format!("t = {} (snapshot {})", f.after.time, f.after.index),
                &f.after.velocity,
            ),
        ],
        &[(f.interface as f64 - 0.5, "interface")],
    )?;
    Ok(crate::reproduce::unit::Svg {
        name: "fig1.svg",
        text,
    })
}
