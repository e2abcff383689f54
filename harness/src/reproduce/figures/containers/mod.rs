//! Fig. 4 and Fig. 5 as one unit, since both are drawn from the same runs: every container of
//! `containers/*.toml` (with `--check-step` also at `dt / 8` and its chaos twin) and the
//! variants of container (a) ([`Variant`]); their analysis (`fit.rs`: the fits, the rescaling
//! onto (a) and the curves drawn; `variants.rs`: each variant against the default (a); here:
//! the step-size check); their outputs (`fig4.rs`: tables, SVG and section; `fig5.rs`: Fig. 5's
//! rows of the paper comparison and section; `fig5_data.rs`: its tables and SVG).

mod fig4;
mod fig5;
mod fig5_data;
mod fit;
mod variant;
mod variants;

pub use fit::{CollapsePoint, ContainerFit};
pub use variant::Variant;
pub use variants::VariantResult;

use super::curves::{curve_diff, CurveDiff};
use crate::batch::scenes::{self, container_sources, ContainerSource, TWIN_EPS};
use crate::batch::RunData;
use crate::error::Error;
use crate::reproduce::jobs::{RunEntry, Runs};
use crate::reproduce::options::{Figure, Options, STEP_FACTOR, VARIANT_SNAPSHOTS};
use crate::reproduce::plan::{set_len, ContainerRun, JobKey, Plan};
use crate::reproduce::render::step_check::{self as check, Describe};
use crate::reproduce::step_check::{rel, StepCheck};
use crate::reproduce::unit::{FigureUnit, Part};
use fit::Curve;
use grainchain_engine::analysis::{self, decay};

/// A quantity of a container compared between the runs at `dt` and at `dt / STEP_FACTOR`
/// (and the chaos twin).
#[derive(Clone, Debug, PartialEq)]
pub enum ContainerQuantity {
    /// First snapshot at which dt and dt/8 differ by more than 1e-4 (the row's value
    /// is that output index, NaN when never).
    FirstStepDifference {
        /// Output index at which `E_R` (at dt) peaks.
        peak: usize,
    },
    /// First snapshot at which the twin differs by more than 1e-4 (the row's value
    /// is that output index, NaN when never).
    FirstTwinDifference,
    /// `E_R` over the run, dt vs dt/8 (the row's value: largest relative difference).
    StepDifference {
        /// Output index of the largest relative difference.
        at: usize,
    },
    /// `E_R` over the run, twin vs dt (the row's value: largest relative difference).
    TwinDifference {
        /// Output index of the largest relative difference.
        at: usize,
    },
    /// gamma over `window` at dt, dt/8 and of the twin (the row's value:
    /// `|gamma(dt) - gamma(dt/8)|`).
    Gamma {
        /// The fit window, first and last output index
        /// ([`grainchain_engine::analysis::decay::fit_window`] of the run at dt).
        window: (usize, usize),
        /// gamma of the run at dt (NaN: no fit).
        dt: f64,
        /// gamma of the run at dt/8 (NaN: no fit).
        fine: f64,
        /// gamma of the chaos twin (NaN: no fit).
        twin: f64,
        /// `|gamma(dt) - gamma(twin)|`.
        twin_difference: f64,
    },
    /// Other than (a): alpha at dt and dt/8 (the row's value: their relative
    /// difference).
    Alpha {
        /// alpha of the run at dt onto (a) at dt.
        dt: f64,
        /// alpha of the run at dt/8 onto (a) at dt.
        fine: f64,
    },
}

impl Describe for ContainerQuantity {
    fn describe(&self) -> (String, String) {
        use ContainerQuantity as Q;
        match self {
            Q::FirstStepDifference { peak } => (
                "first snapshot at which E_R(dt) and E_R(dt/8) differ by more than 1e-4".into(),
                format!("before it they agree within 1e-4 (requirement 6); E_R peaks at snapshot {peak}"),
            ),
            Q::FirstTwinDifference => (
                "first snapshot at which the twin (striker speed x (1 + 1e-12), same dt) differs by more than 1e-4".into(),
                "beyond it no step size can hold E_R to 1e-4".into(),
            ),
            Q::StepDifference { at } => (
                "E_R over the whole run, max relative difference, dt vs dt/8".into(),
                format!("at snapshot {at}"),
            ),
            Q::TwinDifference { at } => (
                "E_R over the whole run, max relative difference, twin vs dt".into(),
                format!("at snapshot {at}"),
            ),
            Q::Gamma {
                window,
                dt,
                fine,
                twin,
                twin_difference,
            } => (
                format!(
                    "gamma over [{}, {}], absolute difference dt vs dt/8",
                    window.0, window.1
                ),
                format!("gamma {dt:.4} vs {fine:.4}; twin {twin:.4} (difference {twin_difference:.4})"),
            ),
            Q::Alpha { dt, fine } => (
                "alpha, relative (this curve at dt vs dt/8, reference (a) at dt)".into(),
                format!("{dt:.4} vs {fine:.4}"),
            ),
        }
    }
}

impl Figure {
    /// Fig. 4 (`--only fig4`; its help line is the second argument).
    pub const FIG4: Figure = Figure::new(
        "fig4",
        "Fig. 4: the energy `E_R` remaining in containers (a)-(e) over time (`containers/*.toml`), with the outer-chain variants of (a)",
    );
    /// Fig. 5 (`--only fig5`; its help line is the second argument).
    pub const FIG5: Figure = Figure::new(
        "fig5",
        "Fig. 5: power-law fits `E_R ~ t^-gamma` of the same container runs, the time rescaling alpha of each onto (a), and every variant of (a)",
    );
}

/// The unit of Fig. 4 and 5; it keeps the containers found, the variants run and what it
/// measured of them.
#[derive(Default)]
pub(crate) struct Containers {
    /// The containers, in file-name order (empty: none found, nothing planned).
    containers: Vec<ContainerSource>,
    /// The variants of (a) that run.
    variants: Vec<Variant>,
    /// One fit per container, in file-name order (set by `analyse`; `None` before, or when
    /// no container was found).
    fits: Option<Vec<ContainerFit>>,
    /// The variants' results, in [`Variant::ALL`] order.
    variant_results: Vec<VariantResult>,
    /// The containers' step-size checks, in file-name order (`--check-step`).
    steps: Vec<StepCheck<ContainerQuantity>>,
}

impl Containers {
    /// Its numbers: the fits, the variants' results and the step checks.
    pub(crate) fn into_results(
        self,
    ) -> (
        Option<Vec<ContainerFit>>,
        Vec<VariantResult>,
        Vec<StepCheck<ContainerQuantity>>,
    ) {
        (self.fits, self.variant_results, self.steps)
    }
}

impl FigureUnit for Containers {
    fn wanted(&self, opts: &Options) -> bool {
        opts.wants(Figure::FIG4) || opts.wants(Figure::FIG5)
    }

    /// The container runs are the longest: they go first.
    fn runs_first(&self) -> bool {
        true
    }

    /// Every container at `dt / 8` (with `--check-step`), then as Fig. 4/5 runs, then their
    /// twins; then the variants of (a), at most [`VARIANT_SNAPSHOTS`] long.
    fn load(&mut self, opts: &Options) -> Result<(), Error> {
        self.containers = container_sources(&opts.scenes.join("containers"), &opts.files)?;
        Ok(())
    }

    fn plan(&mut self, opts: &Options, plan: &mut Plan) -> Result<(), Error> {
        if self.containers.is_empty() {
            return Ok(());
        }
        let mut runs = vec![ContainerRun::Main];
        if opts.check_step {
            runs = vec![ContainerRun::Fine, ContainerRun::Main, ContainerRun::Twin];
        }
        for run in runs {
            for c in &self.containers {
                // The scene as its file stands was built when it was checked: run that one.
                if run == ContainerRun::Main && opts.snapshots.is_none() {
                    let sc = c.source.checked()?;
                    plan.add(JobKey::container(&c.key, run), sc, vec![]);
                    continue;
                }
                let sc = c.source.scene(|f| {
                    set_len(opts, f)?;
                    match run {
                        ContainerRun::Main => {}
                        ContainerRun::Fine => scenes::refine_step(f, STEP_FACTOR),
                        ContainerRun::Twin => scenes::perturb_striker(f, TWIN_EPS),
                    }
                    Ok(())
                })?;
                plan.add(JobKey::container(&c.key, run), sc, vec![]);
            }
        }
        let a = self
            .containers
            .iter()
            .find(|c| c.key == "a")
            .expect("checked");
        let src = a.source.clone();
        let n_main = match opts.snapshots {
            None => src.checked()?.outputs(),
            Some(_) => src.scene(|f| set_len(opts, f))?.outputs(),
        };
        let n_var = n_main.min(VARIANT_SNAPSHOTS);
        let fig5 = opts.wants(Figure::FIG5);
        for v in Variant::ALL
            .into_iter()
            .filter(|v| v.wanted(opts.check_step, fig5))
        {
            let mut c = src.container();
            scenes::set_snapshots(c.file_mut(), n_var);
            v.apply(&mut c)?;
            let sc = c.build()?;
            plan.add(JobKey::Variant(v), sc, vec![]);
            self.variants.push(v);
        }
        Ok(())
    }

    /// The fits of every container, the variants of (a) and, with `--check-step`, the step
    /// checks of the containers.
    fn analyse(&mut self, runs: &Runs) -> Result<(), Error> {
        if self.containers.is_empty() {
            return Ok(());
        }
        let main = |key: &str| runs.need(&JobKey::container(key, ContainerRun::Main));
        let mut curves = Vec::new();
        for c in &self.containers {
            let d = main(&c.key)?;
            curves.push(Curve {
                key: c.key.clone(),
                label: c.label.clone(),
                er: d.region("container")?.energy.to_vec(),
                e0: d.run.initial_energy,
            });
        }
        let fits = fit::fits(curves)?;
        let a = fits.iter().find(|c| c.key == "a").expect("checked");
        for &v in &self.variants {
            let d = runs.need(&JobKey::Variant(v))?;
            self.variant_results.push(variants::variant(v, d, a)?);
        }
        for c in &self.containers {
            let fine = JobKey::container(&c.key, ContainerRun::Fine);
            let twin = JobKey::container(&c.key, ContainerRun::Twin);
            if let (Some(fine), Some(twin)) = (runs.get(&fine), runs.get(&twin)) {
                let check = step_check(&c.key, main(&c.key)?, fine, twin, &fits)?;
                self.steps.push(check);
            }
        }
        self.fits = Some(fits);
        Ok(())
    }

    /// Fig. 4's section always (its margins and outer-chain checks are what Fig. 5's fits
    /// stand on), its table and SVG when Fig. 4 is wanted; Fig. 5's rows of the comparison,
    /// section, tables and SVG when Fig. 5 is.
    fn render(&self, opts: &Options, runs: &[RunEntry]) -> Result<Part, Error> {
        let Some(fits) = &self.fits else {
            return Ok(Part::default());
        };
        let variants = &self.variant_results;
        let mut part = Part {
            section: fig4::section(runs, variants),
            checks: self.steps.iter().flat_map(check::rows).collect(),
            ..Part::default()
        };
        if opts.wants(Figure::FIG4) {
            part.tables.extend(fig4::tables(variants, fits));
            part.svgs.push(fig4::svg(fits)?);
        }
        if opts.wants(Figure::FIG5) {
            part.compare = fig5::compare_rows(fits);
            part.section.push_str(&fig5::section(variants, fits));
            part.tables.extend(fig5_data::tables(variants, fits));
            part.svgs.push(fig5_data::svg(fits)?);
        }
        Ok(part)
    }
}

/// The step-size check of a container: its runs at dt (`main`), dt/8 (`fine`) and the chaos
/// twin (`twin`); `fits` of every container at dt.
fn step_check(
    key: &str,
    main: &RunData,
    fine: &RunData,
    twin: &RunData,
    fits: &[ContainerFit],
) -> Result<StepCheck<ContainerQuantity>, Error> {
    let e0 = main.run.initial_energy;
    let e = main.region("container")?.energy;
    let ef = fine.region("container")?.energy;
    let et = twin.region("container")?.energy;
    let step = curve_diff(e, ef, e0);
    let chaos = curve_diff(et, e, e0);
    let n = e.len() - 1;
    let w = decay::fit_window(n, analysis::leak_onset(e, decay::ONSET_FRACTION));
    let g = |x: &[f64]| decay::fit_percent(x, e0, w.0, w.1).map_or(f64::NAN, |f| f.gamma);
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
    let gamma = ContainerQuantity::Gamma {
        window: w,
        dt: g0,
        fine: gf,
        twin: gt,
        twin_difference: (g0 - gt).abs(),
    };
    let mut rows = vec![
        (
            ContainerQuantity::FirstStepDifference { peak },
            first(&step),
        ),
        (ContainerQuantity::FirstTwinDifference, first(&chaos)),
        (
            ContainerQuantity::StepDifference { at: step.at },
            step.max_rel,
        ),
        (
            ContainerQuantity::TwinDifference { at: chaos.at },
            chaos.max_rel,
        ),
        (gamma, (g0 - gf).abs()),
    ];
    if key != "a" {
        if let Some((x, y)) = alpha_pair(key, ef, fits) {
            rows.push((ContainerQuantity::Alpha { dt: x, fine: y }, rel(x, y)));
        }
    }
    Ok(StepCheck {
        run: format!("fig4 ({key})"),
        method: main.run.method,
        dt: main.run.dt,
        dt_fine: fine.run.dt,
        rows,
    })
}

/// alpha of container `key` at dt and of its fine curve `ef`. alpha of the fine run against the
/// fine reference would need the fine (a); the fine curve is compared against the default (a)
/// instead, which isolates this curve's change.
fn alpha_pair(key: &str, ef: &[f64], fits: &[ContainerFit]) -> Option<(f64, f64)> {
    let a = fits.iter().find(|c| c.key == "a").expect("checked");
    let (_, ra) = decay::onset_bins(&a.er);
    let (_, bf) = decay::onset_bins(ef);
    let alpha_f = analysis::collapse(&ra, &bf, &analysis::CollapseRule::default()).map(|c| c.alpha);
    let alpha0 = fits
        .iter()
        .find(|c| c.key == key)
        .and_then(|c| c.collapse)
        .map(|c| c.alpha);
    alpha0.zip(alpha_f)
}
