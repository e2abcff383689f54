//! `grainchain reproduce`: every figure of Hong (2005) from the scene files in `scenes/`, as CSV,
//! SVG and a `REPORT.md` that puts each number the paper states beside ours.
//!
//! Figures: `fig1` (heavy-to-light interface), `fig3` (the standard container's leaks at the
//! 280th snapshot), `fig4` (energy remaining in containers (a)-(e), plus the outer-chain checks),
//! `fig5` (power-law fits, the time rescaling alpha per container, and how gamma moves with the
//! fit window and the open choices of the reconstruction). The container layouts are a
//! reconstruction (`../shared/reference/containers.md`); every output says so.
//!
//! Independent simulations run as [`jobs::Job`]s on `threads` threads; results are indexed by
//! job, so they do not depend on scheduling.

/// The analysis is a library module of its own ([`crate::analysis`]); re-exported here for the
/// figures that use it.
pub use crate::analysis;
pub mod figures;
pub mod jobs;
mod plots;
mod report;
pub mod scenes;
pub mod table;

use crate::chain::InterfaceRule;
use crate::error::Error;
use crate::observables::PulseRule;
use figures::{ContainerFit, CurveDiff, Fig1, Fig3};
use jobs::{Job, RunData};
use scenes::SceneSource;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;
use table::{Cell, Table};

/// The figures `reproduce` can make.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, clap::ValueEnum)]
pub enum Figure {
    Fig1,
    Fig3,
    Fig4,
    Fig5,
}

impl Figure {
    pub const ALL: [Figure; 4] = [Figure::Fig1, Figure::Fig3, Figure::Fig4, Figure::Fig5];

    pub fn name(self) -> &'static str {
        match self {
            Figure::Fig1 => "fig1",
            Figure::Fig3 => "fig3",
            Figure::Fig4 => "fig4",
            Figure::Fig5 => "fig5",
        }
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
    pub threads: usize,
    /// Show a progress bar on stderr (hidden anyway when stderr is not a terminal).
    pub progress: bool,
    /// Also run every container as an ensemble of this many members (striker speed x (1 + k
    /// 1e-12), multirate 16 with margin 20, as `grainchain study`) and give gamma and alpha with
    /// intervals from the spread over members (0: no ensemble). Member files and the study's
    /// tables go to `<out>/ensemble/`.
    pub members: u64,
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
            members: 0,
        }
    }
}

impl Options {
    pub fn wants(&self, f: Figure) -> bool {
        self.only.is_empty() || self.only.contains(&f)
    }
}

/// Longest run of the variant studies of container (a), in snapshots: they compare fits over
/// the same window with the default run's first snapshots, and the cost of a run grows with the
/// square of its length (the active window grows with time), so they stop at half the paper's
/// 4000 snapshots.
pub const VARIANT_SNAPSHOTS: u64 = 2000;

/// Relative change of the striker's speed in the chaos twin: far below any integrator error, so
/// whatever it changes no step size can pin down.
pub const TWIN_EPS: f64 = 1e-12;

/// The step-size check compares with a run at `dt / STEP_FACTOR`.
pub const STEP_FACTOR: f64 = 8.0;

/// Paper values (Hong 2005).
pub mod paper {
    /// Fig. 5: the universal exponent.
    pub const GAMMA: f64 = 0.7055;
    /// Fig. 5: time rescaling per container ((b) is not rescaled; (d) is 2/9 in the caption).
    pub const ALPHA: [(&str, f64); 5] =
        [("a", 1.0), ("b", 1.0), ("c", 2.0), ("d", 0.22), ("e", 9.0)];
    /// Fig. 3: leading waves leaving at the right and left, % of the incident energy.
    pub const RIGHT_PERCENT: f64 = 3.3;
    pub const LEFT_PERCENT: f64 = 7.7;
    /// Fig. 1: the number of transmitted waves is "about the mass ratio".
    pub const MASS_RATIO: f64 = 10.0;
    /// Fig. 3 text: a solitary wave is about 5 grains wide.
    pub const WAVE_GRAINS: f64 = 5.0;
    /// Fig. 5: A = 65.31 alpha^gamma (normalisation unstated).
    pub const A: f64 = 65.31;

    pub fn alpha(key: &str) -> Option<f64> {
        ALPHA.iter().find(|(k, _)| *k == key).map(|(_, a)| *a)
    }
}

/// A container scene file and its key (`a` for `a-standard.toml`).
#[derive(Clone, Debug)]
pub struct ContainerSource {
    pub key: String,
    pub label: String,
    pub source: SceneSource,
}

/// Every `*.toml` in `dir`, sorted by file name; the key is the file name up to the first `-`.
pub fn container_sources(dir: &Path) -> Result<Vec<ContainerSource>, Error> {
    let bad = |source: std::io::Error| {
        Error::Scene(crate::error::SceneError::Read {
            file: dir.to_path_buf(),
            source,
        })
    };
    let rd = std::fs::read_dir(dir).map_err(bad)?;
    let mut paths: Vec<PathBuf> = rd
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    paths.sort();
    let mut out = Vec::new();
    for p in paths {
        let stem = p
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let (key, label) = match stem.split_once('-') {
            Some((k, l)) => (k.to_string(), l.replace('-', " ")),
            None => (stem.clone(), stem.clone()),
        };
        out.push(ContainerSource {
            key,
            label,
            source: SceneSource::load(&p)?,
        });
    }
    if out.is_empty() {
        return Err(bad(std::io::Error::new(
            std::io::ErrorKind::NotFound,
            "no container scenes (*.toml)",
        )));
    }
    if !out.iter().any(|c| c.key == "a") {
        return Err(bad(std::io::Error::new(
            std::io::ErrorKind::NotFound,
            "the reference container `a-*.toml` is missing (Fig. 5 rescales time relative to it)",
        )));
    }
    Ok(out)
}

/// Which ends of a chain must stay untouched.
fn ends(job: Job, left: bool, right: bool) -> Job {
    Job {
        require_untouched_ends: (left, right),
        ..job
    }
}

fn job(label: String, scene: crate::scene::Scene, regions: &[&str], snapshots: Vec<u64>) -> Job {
    Job {
        label,
        scene,
        regions: regions.iter().map(|s| s.to_string()).collect(),
        snapshots,
        require_untouched_ends: (false, false),
    }
}

/// The snapshot indices a figure scene lists in `output.snapshots.at`.
fn listed_snapshots(src: &SceneSource, fig: &str) -> Result<(Vec<u64>, PulseRule), Error> {
    let sc = src.scene(|_| Ok(()))?;
    let at = sc
        .output
        .snapshots
        .as_ref()
        .map(|s| s.at.clone())
        .unwrap_or_default();
    if at.len() < 2 {
        return Err(src.missing(&format!(
            "`output.snapshots.at` with at least two snapshots ({fig}: before/incident and the figure's)"
        )));
    }
    let rule = sc
        .output
        .pulses
        .as_ref()
        .map(|p| p.rule)
        .unwrap_or_default();
    Ok((at, rule))
}

/// A variant of container (a) for the comparisons of Fig. 4 and 5.
#[derive(Clone, Debug)]
pub struct Variant {
    pub key: &'static str,
    pub change: &'static str,
    /// Ends that must stay untouched (false for the free-end variant, whose point is that they
    /// are reached).
    pub check_ends: bool,
    /// Run only with `--check-step` (its result is known by construction: see the report).
    pub check_only: bool,
}

pub const VARIANTS: [Variant; 5] = [
    Variant {
        key: "outer chains shortened",
        change: "outer-left and beyond-striker cut to half their grains (still never reached)",
        check_ends: true,
        check_only: true,
    },
    Variant {
        key: "free ends (Fig. 3 geometry)",
        change: "outer-left 120 grains, beyond-striker removed: free ends 120 grains from the container, the striker at the chain's end",
        check_ends: false,
        check_only: false,
    },
    Variant {
        key: "interface max-exponent",
        change: "chain.interface = \"max-exponent\"",
        check_ends: true,
        check_only: false,
    },
    Variant {
        key: "two-sided linear walls",
        change: "tension = true on every p = 1 section",
        check_ends: true,
        check_only: false,
    },
    Variant {
        key: "chaos twin",
        change: "striker speed x (1 + 1e-12)",
        check_ends: true,
        check_only: false,
    },
];

impl Variant {
    /// A variant of the outer chains (rather than of the container).
    pub fn is_outer_chain(&self) -> bool {
        self.key.contains("outer") || self.key.contains("free ends")
    }
}

fn apply_variant(
    v: &Variant,
    src: &SceneSource,
    f: &mut crate::scene::file::SceneFile,
) -> Result<(), Error> {
    match v.key {
        "outer chains shortened" => {
            let l = scenes::section_count(src, f, "outer-left")?;
            let r = scenes::section_count(src, f, "beyond-striker")?;
            scenes::set_outer_left(src, f, l / 2)?;
            scenes::set_beyond_striker(src, f, r / 2)
        }
        "free ends (Fig. 3 geometry)" => {
            scenes::set_outer_left(src, f, 120)?;
            scenes::set_beyond_striker(src, f, 0)
        }
        "interface max-exponent" => {
            scenes::set_interface(f, InterfaceRule::MaxExponent);
            Ok(())
        }
        "two-sided linear walls" => {
            if scenes::two_sided_walls(f) == 0 {
                return Err(src.missing("a linear (p = 1) section for the two-sided-wall variant"));
            }
            Ok(())
        }
        "chaos twin" => {
            scenes::perturb_striker(f, TWIN_EPS);
            Ok(())
        }
        _ => Err(Error::Other(format!("unknown variant {}", v.key))),
    }
}

/// Results of one variant run of (a).
#[derive(Clone, Debug)]
pub struct VariantResult {
    pub variant: Variant,
    pub snapshots: usize,
    pub fit: Option<analysis::PowerFit>,
    /// Default (a) fitted over the same window.
    pub default_fit: Option<analysis::PowerFit>,
    pub window: (usize, usize),
    pub diff: CurveDiff,
    pub margin: Option<usize>,
}

/// Step-size check of one run.
#[derive(Clone, Debug)]
pub struct StepCheck {
    pub label: String,
    pub method: &'static str,
    pub dt: f64,
    pub dt_fine: f64,
    /// What was compared and its largest relative difference.
    pub rows: Vec<(String, f64, String)>,
}

/// Headline numbers (the insta snapshot of the golden tests).
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct Headline {
    pub fig1: Option<Fig1Headline>,
    pub fig3: Option<Fig3Headline>,
    pub fig5: Vec<Fig5Headline>,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct Fig1Headline {
    pub incident_energy: f64,
    pub transmitted_pulses: usize,
    pub transmitted_above_1_percent: usize,
    pub transmitted_above_0_1_percent: usize,
    pub leading_fraction: f64,
    pub reflected_fraction: f64,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct Fig3Headline {
    pub incident_energy: f64,
    pub left_lead_percent: Option<f64>,
    pub right_lead_percent: Option<f64>,
    pub container_percent: f64,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct Fig5Headline {
    pub container: String,
    pub gamma: Option<f64>,
    pub gamma_ci: Option<(f64, f64)>,
    pub alpha: Option<f64>,
}

/// Everything a `reproduce` run produced.
#[derive(Clone, Debug, Default)]
pub struct Outcome {
    pub tables: Vec<Table>,
    pub headline: Headline,
    pub report: String,
    pub wall: f64,
    pub fig1: Option<Fig1>,
    pub fig3: Option<Fig3>,
    pub fits: Option<Vec<ContainerFit>>,
    pub variants: Vec<VariantResult>,
    pub step_checks: Vec<StepCheck>,
    pub runs: Vec<RunEntry>,
    /// The ensemble study of the containers (with `Options::members > 0`) and its wall time.
    pub ensemble: Option<(crate::study::outputs::Study, f64)>,
}

/// One simulation of a `reproduce` run, for its runs table.
#[derive(Clone, Debug)]
pub struct RunEntry {
    pub label: String,
    /// The run's bookkeeping ([`crate::run::RunSummary`]).
    pub run: crate::run::RunSummary,
    /// Output times recorded (t = 0 included).
    pub recorded: usize,
    /// Wall time of the job, set-up included.
    pub wall: f64,
}

impl RunEntry {
    fn of(d: &RunData) -> Self {
        RunEntry {
            label: d.label.clone(),
            run: d.run.clone(),
            recorded: d.energies.first().map_or(0, |e| e.len()),
            wall: d.wall,
        }
    }
}

/// The plan: jobs and the index of each by name.
#[derive(Default)]
struct Plan {
    jobs: Vec<Job>,
    index: BTreeMap<String, usize>,
}

impl Plan {
    fn add(&mut self, key: impl Into<String>, j: Job) {
        self.index.insert(key.into(), self.jobs.len());
        self.jobs.push(j);
    }
}

/// Run `reproduce`: simulate, analyse, write CSV, SVG and REPORT.md into `opts.out`.
pub fn run(opts: &Options) -> Result<Outcome, Error> {
    let t0 = Instant::now();
    let want4 = opts.wants(Figure::Fig4) || opts.wants(Figure::Fig5);
    let fig1_src = if opts.wants(Figure::Fig1) {
        Some(SceneSource::load(
            opts.scenes.join("fig1-heavy-to-light.toml"),
        )?)
    } else {
        None
    };
    let fig3_src = if opts.wants(Figure::Fig3) {
        Some(SceneSource::load(
            opts.scenes.join("fig3-standard-container.toml"),
        )?)
    } else {
        None
    };
    let containers = if want4 {
        container_sources(&opts.scenes.join("containers"))?
    } else {
        Vec::new()
    };
    if let Some(n) = opts.snapshots {
        if n < 40 {
            return Err(Error::Other(format!(
                "--snapshots {n}: the containers need at least 40 snapshots (the incident wave alone takes ~140 to arrive)"
            )));
        }
    }
    let set_len = |f: &mut crate::scene::file::SceneFile, n: Option<u64>| {
        if let Some(n) = n {
            scenes::set_snapshots(f, n);
        }
        Ok(())
    };

    // Fig. 4 needs the outer-chain variants; Fig. 5 all of them (the outer-chain treatment is one
    // of its open choices); the shortened chains only with --check-step.
    let wanted = |v: &Variant| {
        (opts.check_step || !v.check_only) && (opts.wants(Figure::Fig5) || v.is_outer_chain())
    };
    let mut plan = Plan::default();
    // Biggest jobs first so the two threads finish together.
    if want4 {
        if opts.check_step {
            for c in &containers {
                let sc = c.source.scene(|f| {
                    set_len(f, opts.snapshots)?;
                    scenes::refine_step(f, STEP_FACTOR);
                    Ok(())
                })?;
                plan.add(
                    format!("fine:{}", c.key),
                    ends(
                        job(format!("({}) dt/8", c.key), sc, &["container"], vec![]),
                        true,
                        true,
                    ),
                );
            }
        }
        for c in &containers {
            let sc = c.source.scene(|f| set_len(f, opts.snapshots))?;
            plan.add(
                format!("container:{}", c.key),
                ends(
                    job(format!("fig4 ({})", c.key), sc, &["container"], vec![]),
                    true,
                    true,
                ),
            );
        }
        if opts.check_step {
            for c in &containers {
                let sc = c.source.scene(|f| {
                    set_len(f, opts.snapshots)?;
                    scenes::perturb_striker(f, TWIN_EPS);
                    Ok(())
                })?;
                plan.add(
                    format!("twin:{}", c.key),
                    ends(
                        job(format!("({}) twin", c.key), sc, &["container"], vec![]),
                        true,
                        true,
                    ),
                );
            }
        }
        let a = containers.iter().find(|c| c.key == "a").expect("checked");
        let n_main = {
            let sc = a.source.scene(|f| set_len(f, opts.snapshots))?;
            sc.outputs()
        };
        let n_var = n_main.min(VARIANT_SNAPSHOTS);
        for v in VARIANTS.iter().filter(|v| wanted(v)) {
            let sc = a.source.scene(|f| {
                scenes::set_snapshots(f, n_var);
                apply_variant(v, &a.source, f)
            })?;
            plan.add(
                format!("variant:{}", v.key),
                ends(
                    job(format!("(a) {}", v.key), sc, &["container"], vec![]),
                    v.check_ends,
                    v.check_ends,
                ),
            );
        }
    }
    let mut fig1_rule = PulseRule::default();
    if let Some(src) = &fig1_src {
        let (at, rule) = listed_snapshots(src, "fig1")?;
        fig1_rule = rule;
        let snaps = vec![at[0], *at.last().expect("two")];
        let main = src.scene(|_| Ok(()))?;
        let control = src.scene(|f| scenes::copy_mass(src, f, "light", "heavy"))?;
        plan.add(
            "fig1",
            ends(
                job("fig1".into(), main, &["heavy", "light"], snaps.clone()),
                false,
                true,
            ),
        );
        plan.add(
            "fig1:control",
            ends(
                job(
                    "fig1 control".into(),
                    control,
                    &["heavy", "light"],
                    snaps.clone(),
                ),
                false,
                true,
            ),
        );
        if opts.check_step {
            for (k, ctl) in [("fig1:fine", false), ("fig1:control:fine", true)] {
                let sc = src.scene(|f| {
                    if ctl {
                        scenes::copy_mass(src, f, "light", "heavy")?;
                    }
                    scenes::refine_step(f, STEP_FACTOR);
                    Ok(())
                })?;
                plan.add(
                    k,
                    ends(
                        job(k.to_string(), sc, &["heavy", "light"], snaps.clone()),
                        false,
                        true,
                    ),
                );
            }
        }
    }
    let mut fig3_rule = PulseRule::default();
    if let Some(src) = &fig3_src {
        let (at, rule) = listed_snapshots(src, "fig3")?;
        fig3_rule = rule;
        let snaps = vec![at[0], *at.last().expect("two")];
        let main = src.scene(|_| Ok(()))?;
        plan.add(
            "fig3",
            ends(
                job("fig3".into(), main, &["container"], snaps.clone()),
                true,
                false,
            ),
        );
        if opts.check_step {
            let sc = src.scene(|f| {
                scenes::refine_step(f, STEP_FACTOR);
                Ok(())
            })?;
            plan.add(
                "fig3:fine",
                ends(
                    job("fig3 dt/8".into(), sc, &["container"], snaps.clone()),
                    true,
                    false,
                ),
            );
        }
    }

    let data = jobs::run_all(&plan.jobs, opts.threads, opts.progress)?;
    let get = |k: &str| plan.index.get(k).map(|&i| &data[i]);

    let mut out = Outcome {
        runs: data.iter().map(RunEntry::of).collect(),
        ..Default::default()
    };

    if let (Some(m), Some(c)) = (get("fig1"), get("fig1:control")) {
        let f = figures::fig1(m, c, fig1_rule)?;
        if let (Some(mf), Some(cf)) = (get("fig1:fine"), get("fig1:control:fine")) {
            let ff = figures::fig1(mf, cf, fig1_rule)?;
            out.step_checks.push(step_check_fig1(&f, &ff, m, mf));
        }
        out.headline.fig1 = Some(Fig1Headline {
            incident_energy: f.incident.energy,
            transmitted_pulses: f.transmitted.len(),
            transmitted_above_1_percent: f.count_above(0.01),
            transmitted_above_0_1_percent: f.count_above(0.001),
            leading_fraction: f.transmitted.first().map_or(0.0, |p| p.fraction),
            reflected_fraction: f.reflected / f.incident.energy,
        });
        out.fig1 = Some(f);
    }
    if let Some(d) = get("fig3") {
        let f = figures::fig3(d, fig3_rule)?;
        if let Some(df) = get("fig3:fine") {
            let ff = figures::fig3(df, fig3_rule)?;
            out.step_checks.push(step_check_fig3(&f, &ff, d, df));
        }
        out.headline.fig3 = Some(Fig3Headline {
            incident_energy: f.incident.energy,
            left_lead_percent: f.left_lead.as_ref().map(|p| 100.0 * p.fraction),
            right_lead_percent: f.right_lead.as_ref().map(|p| 100.0 * p.fraction),
            container_percent: 100.0 * f.container_energy / f.incident.energy,
        });
        out.fig3 = Some(f);
    }
    if want4 {
        let curves = containers
            .iter()
            .map(|c| {
                let d = get(&format!("container:{}", c.key)).expect("planned");
                (
                    c.key.clone(),
                    c.label.clone(),
                    d.energies[0].clone(),
                    d.run.initial_energy,
                )
            })
            .collect();
        let fits = figures::fig45(curves)?;
        let a = fits.iter().find(|c| c.key == "a").expect("checked");
        for v in VARIANTS.iter().filter(|v| wanted(v)) {
            let d = get(&format!("variant:{}", v.key)).expect("planned");
            let e = &d.energies[0];
            let n = e.len() - 1;
            // The headline window's start (a tenth of the full run, not of the variant's shorter
            // one), after both curves' leak onsets; the variant's end.
            let onset = |x: &[f64]| analysis::leak_onset(x, figures::ONSET_FRACTION).unwrap_or(0);
            let w = (a.window.0.max(onset(e)).max(onset(&a.er)), n);
            out.variants.push(VariantResult {
                variant: v.clone(),
                snapshots: n,
                fit: figures::fit_percent(e, d.run.initial_energy, w.0, w.1),
                default_fit: figures::fit_percent(&a.er[..=n.min(a.er.len() - 1)], a.e0, w.0, w.1),
                window: w,
                diff: figures::curve_diff(e, &a.er, a.e0),
                margin: v.check_ends.then(|| d.run.end_margin()),
            });
        }
        if opts.check_step {
            for c in &containers {
                let main = get(&format!("container:{}", c.key)).expect("planned");
                let fine = get(&format!("fine:{}", c.key)).expect("planned");
                let twin = get(&format!("twin:{}", c.key)).expect("planned");
                out.step_checks
                    .push(step_check_container(&c.key, main, fine, twin, &fits));
            }
        }
        out.headline.fig5 = fits
            .iter()
            .map(|c| Fig5Headline {
                container: c.key.clone(),
                gamma: c.fit.map(|f| f.gamma),
                gamma_ci: c.fit.map(|f| (f.ci_lo, f.ci_hi)),
                alpha: c.collapse.map(|x| x.alpha),
            })
            .collect();
        out.fits = Some(fits);
    }

    if want4 && opts.members > 0 {
        out.ensemble = Some(ensemble(opts, &containers)?);
    }
    out.tables = report::tables(opts, &out);
    out.wall = t0.elapsed().as_secs_f64();
    out.report = report::markdown(opts, &out);
    if let Some((st, wall)) = &out.ensemble {
        out.report
            .push_str(&ensemble_section(st, *wall, opts.threads));
    }
    write_outputs(opts, &out)?;
    Ok(out)
}

/// The containers as an ensemble study (`grainchain study` in-process).
fn ensemble(
    opts: &Options,
    containers: &[ContainerSource],
) -> Result<(crate::study::outputs::Study, f64), Error> {
    use crate::study::sweep::{ContainerEntry, MultirateSpec, Perturbation, Sweep};
    let t0 = Instant::now();
    let sweep = Sweep {
        name: "reproduce-ensemble".into(),
        description: Some(format!(
            "The containers of `reproduce`, {} members each (reproduce --members).",
            opts.members
        )),
        snapshots: opts.snapshots.unwrap_or(4000),
        members: opts.members,
        perturbation: Perturbation::StrikerSpeed { epsilon: TWIN_EPS },
        outer_chains: None,
        multirate: Some(MultirateSpec {
            ratio: 16,
            margin: 20,
        }),
        reference: containers.iter().any(|c| c.key == "a").then(|| "a".into()),
        levels: vec![0.3, 0.2, 0.1, 0.05],
        containers: containers
            .iter()
            .map(|c| -> Result<ContainerEntry, Error> {
                Ok(ContainerEntry {
                    key: c.key.clone(),
                    // Absolute, so that it does not depend on where the sweep's path points.
                    scene: std::fs::canonicalize(&c.source.path).map_err(|source| Error::Io {
                        path: c.source.path.clone(),
                        source,
                    })?,
                    multirate: None,
                    free_ends: false,
                })
            })
            .collect::<Result<_, _>>()?,
        random: None,
    };
    let sf =
        crate::study::SweepFile::from_sweep(opts.scenes.join("reproduce-ensemble.toml"), sweep)?;
    let dir = opts.out.join("ensemble");
    let so = crate::study::Options {
        out: dir.clone(),
        shard: crate::study::Shard::ALL,
        threads: opts.threads,
        resume: false,
        progress: opts.progress,
    };
    crate::study::run_jobs(&sf, &so)?;
    let st = crate::study::merge(&sf, std::slice::from_ref(&dir), &dir)?;
    Ok((st, t0.elapsed().as_secs_f64()))
}

fn ensemble_section(st: &crate::study::outputs::Study, wall: f64, threads: usize) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    let n = st.containers.first().map_or(0, |k| k.members);
    let _ = writeln!(
        s,
        "\n## Ensemble: gamma and alpha with intervals over members\n\n`reproduce --members {n}`: \
         every container as {n} members whose striker speeds differ by k x {TWIN_EPS:e} \
         (k = 0..{}), integrated with multiple time stepping (outer chains at 16 dt; checked \
         against single-rate ensembles in studies/multirate-check.toml). Intervals: 95 %, \
         delete-one jackknife over members. {wall:.1} s on {threads} threads. All tables and \
         figures of the ensemble: `ensemble/STUDY.md`.\n",
        n.saturating_sub(1)
    );
    let _ = writeln!(
        s,
        "| container | gamma of the ensemble mean [95 %] | window | alpha by collapse | alpha at E_R = 10 % [95 %] | paper alpha |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|");
    for k in &st.containers {
        let g = k.fit.est.map_or("n/a".into(), |e| {
            format!("{:.3} [{:.3}, {:.3}]", e.value, e.ci_lo, e.ci_hi)
        });
        let col = st
            .collapse
            .iter()
            .find(|c| c.0 == k.key)
            .and_then(|c| c.1)
            .map_or(
                if k.key == "a" {
                    "1 (reference)".into()
                } else {
                    "n/a".into()
                },
                |c| format!("{:.3}", c.alpha),
            );
        let lv = st
            .alpha
            .iter()
            .find(|a| a.key == k.key && a.level == 0.1)
            .map_or("n/a".into(), |a| match a.alpha {
                Some(x) if a.ci_lo.is_finite() => {
                    format!("{x:.3} [{:.3}, {:.3}]", a.ci_lo, a.ci_hi)
                }
                Some(x) => format!("{x:.3}"),
                None => "not reached".into(),
            });
        let _ = writeln!(
            s,
            "| ({}) | {g} | [{}, {}] | {col} | {lv} | {} |",
            k.key,
            k.fit.t_lo,
            k.fit.t_hi,
            paper::alpha(&k.key).map_or("n/a".into(), |a| format!("{a}"))
        );
    }
    let _ = writeln!(
        s,
        "\nPaper: gamma = {} for every container. The local slope of each ensemble mean \
         (`ensemble/slope.svg`) is not constant over the window: see `ensemble/STUDY.md`.",
        paper::GAMMA
    );
    s
}

fn write_outputs(opts: &Options, out: &Outcome) -> Result<(), Error> {
    let dir = &opts.out;
    std::fs::create_dir_all(dir).map_err(|source| Error::Io {
        path: dir.clone(),
        source,
    })?;
    for t in &out.tables {
        t.write(dir)?;
    }
    if let Some(f) = &out.fig1 {
        plots::fig1(dir, f)?;
    }
    if let Some(f) = &out.fig3 {
        plots::fig3(dir, f)?;
    }
    if let Some(fits) = &out.fits {
        if opts.wants(Figure::Fig4) {
            plots::fig4(dir, fits)?;
        }
        if opts.wants(Figure::Fig5) {
            plots::fig5(dir, fits)?;
        }
    }
    crate::report::AtomicFile::write_all(dir.join("REPORT.md"), out.report.as_bytes())
}

fn rel(a: f64, b: f64) -> f64 {
    if b == 0.0 {
        a.abs()
    } else {
        ((a - b) / b).abs()
    }
}

fn step_check_fig1(f: &Fig1, ff: &Fig1, m: &RunData, mf: &RunData) -> StepCheck {
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
    let mut rows = vec![(
        "velocity snapshots, max |dv| / max |v|".to_string(),
        dv,
        String::new(),
    )];
    let k = f.transmitted.len().min(ff.transmitted.len()).min(10);
    let de = (0..k)
        .map(|i| rel(f.transmitted[i].energy, ff.transmitted[i].energy))
        .fold(0.0, f64::max);
    rows.push((
        format!("energies of the {k} leading transmitted waves, max relative"),
        de,
        format!(
            "{} vs {} pulses found",
            f.transmitted.len(),
            ff.transmitted.len()
        ),
    ));
    rows.push((
        "reflected energy / incident, absolute difference".into(),
        (f.reflected - ff.reflected).abs() / ff.incident.energy,
        String::new(),
    ));
    StepCheck {
        label: "fig1".into(),
        method: m.run.method,
        dt: m.run.dt,
        dt_fine: mf.run.dt,
        rows,
    }
}

fn step_check_fig3(f: &Fig3, ff: &Fig3, d: &RunData, df: &RunData) -> StepCheck {
    let lead = |a: &Option<figures::PulseOut>, b: &Option<figures::PulseOut>| match (a, b) {
        (Some(a), Some(b)) => rel(a.fraction, b.fraction),
        _ => f64::NAN,
    };
    let e0 = d.run.initial_energy;
    let curve = figures::curve_diff(&d.energies[0], &df.energies[0], e0);
    StepCheck {
        label: "fig3".into(),
        method: d.run.method,
        dt: d.run.dt,
        dt_fine: df.run.dt,
        rows: vec![
            (
                "left leading wave energy, relative".into(),
                lead(&f.left_lead, &ff.left_lead),
                String::new(),
            ),
            (
                "right leading wave energy, relative".into(),
                lead(&f.right_lead, &ff.right_lead),
                String::new(),
            ),
            (
                "container energy over the run, max relative".into(),
                curve.max_rel,
                format!(
                    "at snapshot {}; first above 1e-4 at {}",
                    curve.at,
                    curve
                        .first_above_level
                        .map_or("-".into(), |k| k.to_string())
                ),
            ),
        ],
    }
}

fn step_check_container(
    key: &str,
    main: &RunData,
    fine: &RunData,
    twin: &RunData,
    fits: &[ContainerFit],
) -> StepCheck {
    let e0 = main.run.initial_energy;
    let (e, ef, et) = (&main.energies[0], &fine.energies[0], &twin.energies[0]);
    let step = figures::curve_diff(e, ef, e0);
    let chaos = figures::curve_diff(et, e, e0);
    let n = e.len() - 1;
    let w = figures::fit_window(n, analysis::leak_onset(e, figures::ONSET_FRACTION));
    let g = |x: &[f64]| figures::fit_percent(x, e0, w.0, w.1).map_or(f64::NAN, |f| f.gamma);
    let (g0, gf, gt) = (g(e), g(ef), g(et));
    let peak = e
        .iter()
        .enumerate()
        .fold(
            (0, f64::NEG_INFINITY),
            |b, (k, &x)| if x > b.1 { (k, x) } else { b },
        )
        .0;
    let first = |d: &CurveDiff| d.first_above_level.map_or(f64::NAN, |k| k as f64);
    let mut rows = vec![
        (
            "first snapshot at which E_R(dt) and E_R(dt/8) differ by more than 1e-4".to_string(),
            first(&step),
            format!("before it they agree within 1e-4 (requirement 6); E_R peaks at snapshot {peak}"),
        ),
        (
            "first snapshot at which the twin (striker speed x (1 + 1e-12), same dt) differs by more than 1e-4".into(),
            first(&chaos),
            "beyond it no step size can hold E_R to 1e-4".into(),
        ),
        (
            "E_R over the whole run, max relative difference, dt vs dt/8".into(),
            step.max_rel,
            format!("at snapshot {}", step.at),
        ),
        (
            "E_R over the whole run, max relative difference, twin vs dt".into(),
            chaos.max_rel,
            format!("at snapshot {}", chaos.at),
        ),
        (
            format!("gamma over [{}, {}], absolute difference dt vs dt/8", w.0, w.1),
            (g0 - gf).abs(),
            format!("gamma {g0:.4} vs {gf:.4}; twin {gt:.4} (difference {:.4})", (g0 - gt).abs()),
        ),
    ];
    if key != "a" {
        // alpha of the fine run against the fine reference would need the fine (a); compare the
        // fine curve's alpha against the default (a) instead, which isolates this curve's change.
        let a = fits.iter().find(|c| c.key == "a").expect("checked");
        let (_, ra) = figures::onset_bins(&a.er);
        let (_, bf) = figures::onset_bins(ef);
        let alpha_f =
            analysis::collapse(&ra, &bf, &analysis::CollapseRule::default()).map(|c| c.alpha);
        let alpha0 = fits
            .iter()
            .find(|c| c.key == key)
            .and_then(|c| c.collapse)
            .map(|c| c.alpha);
        if let (Some(x), Some(y)) = (alpha0, alpha_f) {
            rows.push((
                "alpha, relative (this curve at dt vs dt/8, reference (a) at dt)".into(),
                rel(x, y),
                format!("{x:.4} vs {y:.4}"),
            ));
        }
    }
    StepCheck {
        label: format!("fig4 ({key})"),
        method: main.run.method,
        dt: main.run.dt,
        dt_fine: fine.run.dt,
        rows,
    }
}

/// The cell helpers for report tables.
pub(crate) fn num(x: f64) -> Cell {
    Cell::Num(x)
}
