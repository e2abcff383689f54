//! The design file of `grainchain design`: the design space, the constraints, the load, the
//! objective and the search, in SI units. Unknown keys are errors; a bad value names its file
//! and key. Example in `designs/steel-ptfe.toml`:
//!
//! ```toml
//! [space]
//! beads = 40                       # beads in the column
//! sections = 8                     # optional: 8 sections of 5 equal beads (one choice each)
//! materials = ["steel", "ptfe"]    # candidates: names, or { E = .., nu = .., rho = .., name = .. }
//! diameters = [0.006]              # candidates, m
//! order = "free"                   # or "graded": bead masses never increase towards the wall
//!
//! [constraints]                    # optional
//! max_mass = 0.1                   # kg
//! max_length = 0.3                 # m
//!
//! [load]
//! striker = { material = "steel", diameter = 0.006 }
//! speeds = [1.0]                   # m/s; several: the worst case over them is optimised
//! wall = "steel"                   # or target = { mass = 0.1, material = "steel", spring = 1e5 }
//! # restitution = 0.95             # every contact's coefficient of restitution, but for
//! # restitution_pairs = [{ between = ["steel", "ptfe"], restitution = 0.9 }]  # pairs' own
//!
//! [objective]                      # optional
//! minimize = "peak"                # "peak", "impulse", "duration", or "mix" with weights; with
//!                                  # [tolerances] "p95", "mean", "quantile" or "p95-first-order"
//! # weights = { peak = 1.0, impulse = 0.0, duration = 0.0 }
//! fraction = 0.5                   # the duration counts the time above this share of the peak
//!
//! [search]                         # optional
//! seed = 1
//! population = 64
//! generations = 100                # at most
//! stale = 25                       # stop after this many generations without a better design
//! accuracy = 1e-5                  # relative error of the peak, impulse and duration
//!
//! [tolerances]                     # optional: the peak's spread (`tolerance.rs`)
//! diameter = 0.001                 # relative standard deviations: 0.001 is 0.1 %
//! E = 0.02
//! rho = 0.005
//! speed = 0.05
//! samples = 1000                   # Monte Carlo columns
//! screen = 64                      # a robust objective's draws per candidate in the search
//! confirm = 256                    # ... per finalist
//! finalists = 8                    # ... finalists from each search at most
//! ```

use super::tolerance::{
    corners, Draws, Statistic, Tolerances, MAX_SIGMA, MIN_SAMPLES, SEARCH_STREAM, Z_MAX,
};
use grainchain_engine::protector::{
    accuracy_problem, step_bound, steps_for_accuracy, Bead, Impact, PairRestitution, Protected,
    Settings, DEFAULT_ACCURACY, MAX_EVALUATION_STEPS,
};
use grainchain_engine::units::{diameter_problem, Material};
use grainchain_engine::InputError;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// A material: a name from the table, or its constants.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(untagged, deny_unknown_fields)]
pub enum MaterialKey {
    /// A name of `units::MATERIALS` (steel, stainless-steel, brass, aluminium, ptfe, glass,
    /// tungsten-carbide).
    Name(String),
    /// Its constants.
    Constants {
        /// Young's modulus, Pa (1e3 to 1e13).
        #[serde(rename = "E")]
        young: f64,
        /// Poisson's ratio.
        nu: f64,
        /// Density, kg/m^3 (1 to 1e5).
        rho: f64,
        /// What every output calls it (1 to 40 characters without quotes or `|`, not a key of
        /// the table); default its constants, `E=2e11,nu=0.3,rho=7900`.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        name: Option<String>,
    },
}

/// A sphere: material and diameter.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SphereKey {
    /// Its material.
    pub material: MaterialKey,
    /// Its diameter, m.
    pub diameter: f64,
}

/// Whether bead order is free.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize, schemars::JsonSchema,
)]
#[serde(rename_all = "kebab-case")]
pub enum Order {
    /// Any bead at any position.
    #[default]
    Free,
    /// Bead masses never increase from the struck end to the wall (a graded column).
    Graded,
}

/// `[space]`: what may be chosen.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Space {
    /// Beads in the column (1-400).
    pub beads: usize,
    /// Sections of equal beads (each one choice; divides `beads`); default: one per bead.
    pub sections: Option<usize>,
    /// Candidate materials (at least one).
    pub materials: Vec<MaterialKey>,
    /// Candidate diameters, m (at least one).
    pub diameters: Vec<f64>,
    /// Whether order is free.
    #[serde(default)]
    pub order: Order,
}

/// `[constraints]`.
#[derive(Clone, Debug, Default, PartialEq, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Constraints {
    /// The column's largest mass, kg.
    pub max_mass: Option<f64>,
    /// The column's largest length (sum of diameters), m.
    pub max_length: Option<f64>,
}

/// A target body on a spring.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TargetKey {
    /// Mass, kg.
    pub mass: f64,
    /// The material of its face.
    pub material: MaterialKey,
    /// Its spring to ground, N/m (0: a free body).
    #[serde(default)]
    pub spring: f64,
}

/// `[load]`.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LoadKey {
    /// The striker sphere.
    pub striker: SphereKey,
    /// Impact speeds, m/s (the worst case over them is optimised).
    pub speeds: Vec<f64>,
    /// The wall's material (default steel) when there is no target.
    pub wall: Option<MaterialKey>,
    /// A target body instead of a wall.
    pub target: Option<TargetKey>,
    /// Every contact's coefficient of restitution (default: elastic), but for the pairs of
    /// `restitution_pairs`.
    pub restitution: Option<f64>,
    /// Pairs of materials with a coefficient of restitution of their own (default: none).
    // Left out of the serialised file when empty, so that the digest of a file without it is
    // what it was before the key existed.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub restitution_pairs: Vec<PairKey>,
}

/// A pair of materials with a coefficient of restitution of its own: every contact of a bead,
/// the striker, the wall or the target's face of one material with one of the other.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PairKey {
    /// The two materials (as in `space.materials`: names or constants; one material twice:
    /// its contacts with itself). Each must be a material of the file's beads, striker, wall
    /// or target.
    pub between: [MaterialKey; 2],
    /// The pair's coefficient of restitution, 0.05 to 1 (1: elastic).
    pub restitution: f64,
}

/// What is minimised.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize, schemars::JsonSchema,
)]
#[serde(rename_all = "kebab-case")]
pub enum Minimize {
    /// The peak force on the protected face.
    #[default]
    Peak,
    /// The impulse it passes on.
    Impulse,
    /// The time above `fraction` of the peak (a long low pulse is the aim of some designs:
    /// minimising it rewards short pulses, so mix it with the peak).
    Duration,
    /// `weights`: a weighted sum of the three, each relative to the reference column's.
    Mix,
    /// The 95th percentile of the peak under `[tolerances]` (needed), by a seeded Monte Carlo
    /// with common random numbers (every candidate perturbed by the same draws: `tolerances.screen`
    /// of them in the search, `tolerances.confirm` for the finalists), relative to the reference
    /// column's nominal peak. The search runs twice: the nominal one (the peak) and the robust
    /// one, and the outputs set both winners side by side on fresh draws (docs/design.md).
    P95,
    /// The mean of the peak under `[tolerances]`, as `p95` is its 95th percentile.
    Mean,
    /// The `objective.quantile` of the peak under `[tolerances]`, as `p95` is its 95th
    /// percentile.
    Quantile,
    /// The first-order 95th percentile of the peak under `[tolerances]` (needed): `P + 1.645
    /// sigma_1`, `sigma_1` from the peak's exact derivatives, relative to the reference column's
    /// nominal peak (so it is the peak objective plus the tolerance's margin). An approximation,
    /// right while the tolerances are small against the scale on which the peak bends
    /// (docs/design.md says where it held). Each design costs a run with derivatives: about 8
    /// evaluations on a 40-bead column (the run recorded, then one sweep back through it).
    P95FirstOrder,
}

impl Minimize {
    /// Whether it is a statistic of the peak by the Monte Carlo (`mean`, `p95`, `quantile`).
    pub fn is_robust(self) -> bool {
        matches!(self, Minimize::P95 | Minimize::Mean | Minimize::Quantile)
    }
}

/// Weights of the mix, each on a quantity relative to the reference column's.
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Weights {
    /// On the peak force.
    #[serde(default)]
    pub peak: f64,
    /// On the impulse.
    #[serde(default)]
    pub impulse: f64,
    /// On the duration.
    #[serde(default)]
    pub duration: f64,
}

/// `[objective]`.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ObjectiveKey {
    /// What is minimised.
    #[serde(default)]
    pub minimize: Minimize,
    /// The mix's weights.
    pub weights: Option<Weights>,
    /// The duration's share of the peak (default 0.5).
    #[serde(default = "half")]
    pub fraction: f64,
    /// The quantile `minimize = "quantile"` minimises, in (0, 1) (0.99 is the 99th
    /// percentile); for that objective only.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub quantile: Option<f64>,
}

fn half() -> f64 {
    0.5
}

impl Default for ObjectiveKey {
    fn default() -> Self {
        ObjectiveKey {
            minimize: Minimize::Peak,
            weights: None,
            fraction: 0.5,
            quantile: None,
        }
    }
}

/// `[search]`.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SearchKey {
    /// The seed of the search.
    #[serde(default = "one")]
    pub seed: u64,
    /// Designs per generation.
    #[serde(default = "population")]
    pub population: usize,
    /// Generations at most.
    #[serde(default = "generations")]
    pub generations: usize,
    /// Stop after this many generations without a better design.
    #[serde(default = "stale")]
    pub stale: usize,
    /// Give up on a design as soon as its peak shows that a design no heavier is at least as
    /// good (peak-only objectives; its journal line then holds lower bounds): the best design
    /// and the Pareto front are unchanged, the search about four times cheaper. `false` runs
    /// every design to the search's time cap.
    #[serde(default = "yes")]
    pub give_up: bool,
    /// The relative error wanted of the peak force (1e-9 to 1e-2; default 1e-5). It sets the
    /// evaluation's step: blanes-moan4 with contact events at `20 (1e-5 / accuracy)^(2/5)` steps
    /// per contact time of the stiffest pair, at least 8 (`protector::steps_for_accuracy`, order
    /// 2.5), so 1e-7 costs 6.3 times the default per evaluation. Calibrated on the 40-bead
    /// steel-PTFE column (20 steps: 5.7e-7); it is a target, not a promise: on a column whose
    /// peak comes after many reflections the same step is further off (4.0e-5 on the best design
    /// of `designs/steel-ptfe.toml`). So every
    /// reported number (the best designs, the baselines, `best.toml`) is evaluated again at twice
    /// the steps, at them and at half of them, and comes with its error, the larger of the two
    /// differences between neighbouring runs.
    #[serde(
        default = "default_accuracy",
        skip_serializing_if = "is_default_accuracy"
    )]
    pub accuracy: f64,
}

fn default_accuracy() -> f64 {
    DEFAULT_ACCURACY
}

/// Left out of the serialised file (and so of its digest) at its default, the step every search
/// ran at before the key existed: their journals and output folders stay this file's.
fn is_default_accuracy(a: &f64) -> bool {
    *a == DEFAULT_ACCURACY
}

fn yes() -> bool {
    true
}

fn one() -> u64 {
    1
}
fn population() -> usize {
    64
}
fn generations() -> usize {
    100
}
fn stale() -> usize {
    25
}

impl Default for SearchKey {
    fn default() -> Self {
        SearchKey {
            seed: 1,
            population: 64,
            generations: 100,
            stale: 25,
            give_up: true,
            accuracy: DEFAULT_ACCURACY,
        }
    }
}

/// `[tolerances]`: relative standard deviations of the beads' and the load's numbers, each
/// bead's drawn independently; the outputs give the peak's spread to first order and by a Monte
/// Carlo for the best designs and the baselines (`tolerances.csv`, `sensitivities.csv`,
/// DESIGN.md, `sensitivity.svg`). Each tolerance lies in [0, 0.2] (0.01 is 1 %): draws are cut
/// at 4 standard deviations, so at most 0.2 keeps every factor `1 + sigma z` at 0.2 or more and a
/// perturbed bead a valid bead (the check also proves each candidate's extremes valid and
/// within the step limit).
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TolerancesKey {
    /// Relative standard deviation of each bead's diameter (0.01 is 1 %; 0 to 0.2, default 0).
    #[serde(default)]
    pub diameter: f64,
    /// Relative standard deviation of each bead's Young's modulus (0 to 0.2, default 0).
    #[serde(default, rename = "E")]
    pub young: f64,
    /// Relative standard deviation of each bead's density (0 to 0.2, default 0).
    #[serde(default)]
    pub rho: f64,
    /// Relative standard deviation of the striker's speed, one draw per Monte Carlo column (0 to
    /// 0.2, default 0).
    #[serde(default)]
    pub speed: f64,
    /// Monte Carlo columns per design (100 to 100000; default 1000).
    #[serde(default = "thousand")]
    pub samples: usize,
    /// The Monte Carlo's seed (default: the search's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
    /// A robust objective's draws per candidate in the search, the same draws for every
    /// candidate (16 to `confirm`; default 64).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub screen: Option<usize>,
    /// A robust objective's draws per finalist (the screening draws and more of the same
    /// stream; `screen` to 100000, default 256).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub confirm: Option<usize>,
    /// A robust objective's finalists at most: the best designs of the search whose screening
    /// interval reaches the best one's, confirmed on `confirm` draws (1 to 32, default 8).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub finalists: Option<usize>,
}

fn thousand() -> usize {
    1000
}

/// The most Monte Carlo columns per design: 1e5 (each is an evaluation; twenty designs at 1e5
/// are hours).
const MAX_SAMPLES: usize = 100_000;

/// The design file as written.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DesignFile {
    /// What may be chosen.
    pub space: Space,
    /// Limits on the column.
    #[serde(default)]
    pub constraints: Constraints,
    /// The load.
    pub load: LoadKey,
    /// What is minimised.
    #[serde(default)]
    pub objective: ObjectiveKey,
    /// The search.
    #[serde(default)]
    pub search: SearchKey,
    /// Manufacturing tolerances (optional): the spread of the reported columns' peaks, to first
    /// order and by a Monte Carlo (`tolerances.csv`, `sensitivities.csv`); needed by `minimize =
    /// "p95"`. Left out of the serialised file (and so of its digest) when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tolerances: Option<TolerancesKey>,
    /// The gradient refinement of the best designs (none without it; left out of the digest
    /// when absent).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub refine: Option<RefineKey>,
}

/// `[refine]`: refine the best designs' diameters by their gradients (optional; without it no
/// refinement runs).
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RefineKey {
    /// The interval the diameters may take, m, `[lo, hi]`: exactly two numbers, lo < hi
    /// (default: the smallest and largest of `[space] diameters`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schemars(length(min = 2, max = 2))]
    pub diameters: Option<Vec<f64>>,
    /// How many of the best designs to refine, 1 to 10 (default 3).
    #[serde(default = "three")]
    pub designs: usize,
    /// L-BFGS iterations per design at most, 1 to 200 (default 20; each takes one or a few
    /// runs with gradients per speed, a run with gradients some ten evaluations).
    #[serde(default = "twenty")]
    pub iterations: u64,
}

fn three() -> usize {
    3
}

fn twenty() -> u64 {
    20
}

impl RefineKey {
    /// Why the table cannot be used with `spec`'s other tables, if it cannot (under the key to
    /// blame: one of `refine.<key>`, or `objective.minimize` for an objective it cannot
    /// refine), and the interval it refines in.
    pub fn check(
        &self,
        candidates: &[f64],
        minimize: Minimize,
    ) -> Result<[f64; 2], (String, String)> {
        let bad = |k: &str, m: String| Err((format!("refine.{k}"), m));
        if !(1..=10).contains(&self.designs) {
            return bad("designs", format!("must be 1 to 10, got {}", self.designs));
        }
        if !(1..=200).contains(&self.iterations) {
            return bad(
                "iterations",
                format!("must be 1 to 200, got {}", self.iterations),
            );
        }
        let objective = |m: &str| Err(("objective.minimize".to_string(), m.to_string()));
        if minimize == Minimize::P95FirstOrder {
            return objective(
                "[refine] needs the objective's gradient, and the p95 objective's gradient needs the derivatives of the spread, second \
                 derivatives of the run, which grainchain does not compute (refine the peak, or \
                 leave out [refine])",
            );
        }
        if minimize.is_robust() {
            return objective(
                "[refine] needs the objective's gradient, and a Monte Carlo statistic of the peak \
                 has none that grainchain computes (refine the peak, or leave out [refine])",
            );
        }
        if minimize == Minimize::Duration {
            return objective(
                "[refine] needs the objective's gradient, and a duration counts whole steps: its \
                 derivative is the step's alone, nothing to refine by (minimize the peak, the \
                 impulse or a mix, or leave out [refine])",
            );
        }
        let lo = candidates.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = candidates.iter().copied().fold(0.0, f64::max);
        let [lo, hi] = match self.diameters.as_deref() {
            None => [lo, hi],
            Some(&[lo, hi]) => [lo, hi],
            Some(other) => {
                return bad(
                    "diameters",
                    format!(
                        "needs exactly two numbers, the interval [lo, hi], got {} ({other:?})",
                        other.len()
                    ),
                )
            }
        };
        for d in [lo, hi] {
            if let Some(why) = grainchain_engine::units::diameter_problem(d) {
                return bad("diameters", why);
            }
        }
        if lo >= hi {
            return bad(
                "diameters",
                format!(
                    "needs an interval lo < hi, got [{lo}, {hi}] (the space's diameters are one \
                     size: give `diameters = [lo, hi]`)"
                ),
            );
        }
        Ok([lo, hi])
    }
}

/// The digest of what a search of `file` reads: the file without `[refine]`, and without what
/// of `[tolerances]` the objective does not read (all of it for the peak and the other nominal
/// objectives; `samples`, `confirm` and `finalists` for a robust one, whose search reads only
/// its `screen` draws, the first of every longer set; all but the standard deviations for the
/// first-order p95). A file with neither table keeps the digest of the whole file.
pub fn search_digest(file: &DesignFile) -> String {
    let mut f = file.clone();
    f.refine = None;
    let minimize = f.objective.minimize;
    f.tolerances = f.tolerances.take().and_then(|t| {
        let kept = TolerancesKey {
            samples: thousand(),
            confirm: None,
            finalists: None,
            ..t
        };
        if minimize.is_robust() {
            Some(kept)
        } else if minimize == Minimize::P95FirstOrder {
            Some(TolerancesKey {
                seed: None,
                screen: None,
                ..kept
            })
        } else {
            None
        }
    });
    crate::report::fnv1a(&serde_json::to_vec(&f).expect("serialisable"))
}

/// A design file checked: every value usable.
#[derive(Clone, Debug)]
pub struct DesignSpec {
    /// The file.
    pub path: PathBuf,
    /// As written (for the digest and the outputs).
    pub file: DesignFile,
    /// The candidates: every (material, diameter) pair, materials first.
    pub choices: Vec<Bead>,
    /// Names of the choices (`steel 6 mm`).
    pub names: Vec<String>,
    /// Beads per section.
    pub per_section: usize,
    /// The impacts, one per speed.
    pub impacts: Vec<Impact>,
    /// What is protected.
    pub protected: Protected,
    /// The reference column: `beads` of the first candidate.
    pub reference: Bead,
    /// `[tolerances]` checked, its seed resolved (`None`: no table).
    pub tolerances: Option<Tolerances>,
    /// The digest of what the search reads ([`search_digest`]): its journals and the output
    /// folder belong to it, so an edit of what only the later phases read (`[refine]`,
    /// `[tolerances] samples`, a robust objective's `confirm` and `finalists`) keeps both.
    pub digest: String,
    /// The interval `[refine]` refines the diameters in (checked; `None` without the table).
    pub refine_range: Option<[f64; 2]>,
    /// A robust objective's statistic and draws (`None` for the others).
    pub robust: Option<Robust>,
}

/// A robust objective checked: the statistic of the peak it minimises and the common draws.
#[derive(Clone, Debug)]
pub struct Robust {
    /// The statistic.
    pub statistic: Statistic,
    /// Draws per candidate in the search: the first `screen` of `draws`.
    pub screen: usize,
    /// The finalists at most.
    pub finalists: usize,
    /// The search's common draws, `tolerances.confirm` of them.
    pub draws: Draws,
}

fn invalid(path: &Path, key: impl Into<String>, message: impl Into<String>) -> InputError {
    InputError::Invalid {
        file: path.to_path_buf(),
        key: key.into(),
        message: message.into(),
    }
}

/// The material a key names or gives ([`Material::named`], [`Material::explicit`]), or why
/// not under `key`.
fn material(path: &Path, key: &str, m: &MaterialKey) -> Result<Material, InputError> {
    match m {
        MaterialKey::Name(name) => Material::named(name),
        MaterialKey::Constants {
            young,
            nu,
            rho,
            name,
        } => Material::explicit(name.as_deref(), *young, *nu, *rho),
    }
    .map_err(|why| invalid(path, key, why))
}

/// A diameter ([`diameter_problem`]), or why not under `key`.
fn diameter(path: &Path, key: &str, d: f64) -> Result<f64, InputError> {
    match diameter_problem(d) {
        Some(why) => Err(invalid(path, key, why)),
        None => Ok(d),
    }
}

fn positive(path: &Path, key: &str, x: f64, unit: &str) -> Result<f64, InputError> {
    if x.is_finite() && x > 0.0 {
        Ok(x)
    } else {
        Err(invalid(
            path,
            key,
            format!("must be a finite number > 0 {unit}, got {x}"),
        ))
    }
}

/// `[tolerances]` checked ([`TolerancesKey`]): each tolerance in [0, [`MAX_SIGMA`]], the
/// samples, elastic contacts (the first-order spread needs the peak's derivatives, built for
/// elastic contacts only), and every candidate at the extremes the draws can reach (each property
/// 4 standard deviations off, [`corners`]) a valid bead whose columns stay within the step limit.
fn check_tolerances(
    p: &Path,
    file: &DesignFile,
    t: &TolerancesKey,
    choices: &[Bead],
    impacts: &[Impact],
    protected: &Protected,
) -> Result<Tolerances, InputError> {
    let sigmas = [
        ("tolerances.diameter", t.diameter),
        ("tolerances.E", t.young),
        ("tolerances.rho", t.rho),
        ("tolerances.speed", t.speed),
    ];
    for (key, x) in sigmas {
        if !(x.is_finite() && (0.0..=MAX_SIGMA).contains(&x)) {
            return Err(invalid(
                p,
                key,
                format!(
                    "must be a relative standard deviation in [0, {MAX_SIGMA}] (0.01 is 1 %), \
                     got {x}"
                ),
            ));
        }
    }
    if !(MIN_SAMPLES..=MAX_SAMPLES).contains(&t.samples) {
        return Err(invalid(
            p,
            "tolerances.samples",
            format!(
                "must lie in {MIN_SAMPLES}..={MAX_SAMPLES} Monte Carlo columns, got {}",
                t.samples
            ),
        ));
    }
    // A robust objective is the Monte Carlo's alone (its winners' first-order p95 is left out
    // with damped contacts); the analysis of the ten best is first order too.
    if !impacts[0].is_elastic() && !file.objective.minimize.is_robust() {
        return Err(invalid(
            p,
            "tolerances",
            "the peak's first-order spread needs its derivatives, which are built for elastic \
             contacts only: leave out load.restitution and load.restitution_pairs, or this \
             table, or minimize a robust statistic (\"p95\", \"mean\", \"quantile\": a Monte \
             Carlo alone)",
        ));
    }
    let tol = Tolerances {
        diameter: t.diameter,
        young: t.young,
        density: t.rho,
        speed: t.speed,
        samples: t.samples,
        seed: t.seed.unwrap_or(file.search.seed),
    };
    let names: Vec<String> = choices
        .iter()
        .map(|c| format!("{} {} mm", c.material.name, c.diameter * 1e3))
        .collect();
    for (c, name) in choices.iter().zip(&names) {
        for (key, sigma, what) in [
            ("tolerances.diameter", tol.diameter, "diameter"),
            ("tolerances.E", tol.young, "Young's modulus"),
            ("tolerances.rho", tol.density, "density"),
        ] {
            for f in [1.0 - Z_MAX * sigma, 1.0 + Z_MAX * sigma] {
                let mut b = *c;
                match key {
                    "tolerances.diameter" => b.diameter *= f,
                    "tolerances.E" => b.material.young *= f,
                    _ => b.material.density *= f,
                }
                if let Some(why) = b.problem() {
                    return Err(invalid(
                        p,
                        key,
                        format!(
                            "the candidate {name} with its {what} times {f} (the draws reach \
                             {Z_MAX} standard deviations) is no bead: {why}"
                        ),
                    ));
                }
            }
        }
    }
    // The steps of the reported runs (twice the accuracy's) at the engine's time cap, as the
    // file's check bounds the nominal candidates.
    let extremes: Vec<Bead> = choices.iter().flat_map(|c| corners(c, &tol)).collect();
    let settings = Settings {
        steps_per_contact: 2.0 * steps_for_accuracy(file.search.accuracy),
        ..Settings::default()
    };
    for imp in impacts {
        let bound = step_bound(&extremes, file.space.beads, imp, protected, &settings);
        if !(bound <= MAX_EVALUATION_STEPS) {
            let (key, _) = sigmas[..3]
                .iter()
                .copied()
                .max_by(|a, b| a.1.total_cmp(&b.1))
                .expect("three");
            return Err(invalid(
                p,
                key,
                format!(
                    "a column of the candidates perturbed by up to {Z_MAX} standard deviations \
                     could need up to {bound:.3e} steps per run, over the limit of \
                     {MAX_EVALUATION_STEPS:.0e}: give smaller tolerances"
                ),
            ));
        }
    }
    Ok(tol)
}

/// The robust objective's statistic and draws checked (`None` for other objectives; a key of
/// a robust objective given without one is refused).
fn robust(
    p: &Path,
    file: &DesignFile,
    tol: Option<&Tolerances>,
) -> Result<Option<Robust>, InputError> {
    let o = &file.objective;
    match (o.minimize, o.quantile) {
        (Minimize::Quantile, None) => {
            return Err(invalid(
                p,
                "objective.quantile",
                "`minimize = \"quantile\"` needs the quantile, e.g. `quantile = 0.99`",
            ))
        }
        (Minimize::Quantile, Some(q)) if !(q > 0.0 && q < 1.0) => {
            return Err(invalid(
                p,
                "objective.quantile",
                format!("must lie in (0, 1) (0.99 is the 99th percentile), got {q}"),
            ))
        }
        (Minimize::Quantile, Some(_)) => {}
        (_, Some(_)) => {
            return Err(invalid(
                p,
                "objective.quantile",
                "is for `minimize = \"quantile\"` only",
            ))
        }
        _ => {}
    }
    let key = file.tolerances.as_ref();
    let (screen, confirm, finalists) = (
        key.and_then(|t| t.screen),
        key.and_then(|t| t.confirm),
        key.and_then(|t| t.finalists),
    );
    let (Some(tol), true) = (tol, o.minimize.is_robust()) else {
        for (k, given) in [
            ("screen", screen.is_some()),
            ("confirm", confirm.is_some()),
            ("finalists", finalists.is_some()),
        ] {
            if given {
                return Err(invalid(
                    p,
                    format!("tolerances.{k}"),
                    "is for a robust objective only (`minimize = \"p95\"`, \"mean\" or \
                     \"quantile\")",
                ));
            }
        }
        return Ok(None);
    };
    let confirm = confirm.unwrap_or(DEFAULT_CONFIRM);
    let screen = screen.unwrap_or(DEFAULT_SCREEN.min(confirm));
    if !(MIN_SCREEN..=confirm).contains(&screen) {
        return Err(invalid(
            p,
            "tolerances.screen",
            format!("must lie in {MIN_SCREEN}..=tolerances.confirm ({confirm}), got {screen}"),
        ));
    }
    if confirm > MAX_SAMPLES {
        return Err(invalid(
            p,
            "tolerances.confirm",
            format!("must be at most {MAX_SAMPLES}, got {confirm}"),
        ));
    }
    let finalists = finalists.unwrap_or(8);
    if !(1..=32).contains(&finalists) {
        return Err(invalid(
            p,
            "tolerances.finalists",
            format!("must lie in 1..=32, got {finalists}"),
        ));
    }
    let statistic = match o.minimize {
        Minimize::Mean => Statistic::Mean,
        Minimize::Quantile => Statistic::Quantile(o.quantile.expect("checked above")),
        _ => Statistic::Quantile(0.95),
    };
    Ok(Some(Robust {
        statistic,
        screen,
        finalists,
        draws: Draws::new(file.space.beads, tol, confirm, SEARCH_STREAM),
    }))
}

/// A robust objective's screening draws per candidate unless given: the 95th percentile of 64
/// draws has a distribution-free interval from the 58th value to the largest.
const DEFAULT_SCREEN: usize = 64;

/// The fewest screening draws: below 16 a 95th percentile is the largest draw or the one below.
const MIN_SCREEN: usize = 16;

/// The finalists' draws unless given.
const DEFAULT_CONFIRM: usize = 256;

impl DesignSpec {
    /// Read, parse and check a design file.
    pub fn load(path: impl AsRef<Path>) -> Result<DesignSpec, InputError> {
        let path = path.as_ref().to_path_buf();
        let text = grainchain_engine::file::read_text(&path)?;
        let file: DesignFile = toml::from_str(&text).map_err(|e| InputError::Parse {
            file: path.clone(),
            message: grainchain_engine::file::describe_toml_error(&e, &text),
        })?;
        DesignSpec::check(path, file)
    }

    /// Check a parsed design file.
    pub fn check(path: PathBuf, file: DesignFile) -> Result<DesignSpec, InputError> {
        let p = &path;
        let s = &file.space;
        if !(1..=400).contains(&s.beads) {
            return Err(invalid(
                p,
                "space.beads",
                format!("must lie in 1..=400, got {}", s.beads),
            ));
        }
        let sections = s.sections.unwrap_or(s.beads);
        if sections == 0 || !s.beads.is_multiple_of(sections) {
            return Err(invalid(
                p,
                "space.sections",
                format!(
                    "must divide space.beads = {} into equal sections, got {sections}",
                    s.beads
                ),
            ));
        }
        if s.materials.is_empty() {
            return Err(invalid(p, "space.materials", "give at least one material"));
        }
        if s.diameters.is_empty() {
            return Err(invalid(p, "space.diameters", "give at least one diameter"));
        }
        let mut choices = Vec::new();
        let mut names = Vec::new();
        // Every material the file names, with its key: outputs tell materials apart by name
        // alone, so one name with two sets of constants is refused wherever it appears.
        let mut named: Vec<(String, Material)> = Vec::new();
        let mut once = |key: String, mat: Material| -> Result<(), InputError> {
            if let Some((other, _)) = named.iter().find(|(_, x)| x.name == mat.name && *x != mat) {
                return Err(invalid(
                    p,
                    key,
                    format!(
                        "named `{}` like {other}, with other constants; give each material its \
                         own name",
                        mat.name
                    ),
                ));
            }
            named.push((key, mat));
            Ok(())
        };
        for (i, m) in s.materials.iter().enumerate() {
            let key = format!("space.materials[{i}]");
            let mat = material(p, &key, m)?;
            once(key, mat)?;
            for (j, &d) in s.diameters.iter().enumerate() {
                let d = diameter(p, &format!("space.diameters[{j}]"), d)?;
                choices.push(Bead {
                    material: mat,
                    diameter: d,
                });
                names.push(format!("{} {} mm", mat.name, d * 1e3));
            }
        }
        if choices.len() > 255 {
            // Blame the longer list (issue 38: 1000 diameters were blamed on the materials).
            let key = if s.diameters.len() > s.materials.len() {
                "space.diameters"
            } else {
                "space.materials"
            };
            return Err(invalid(
                p,
                key,
                format!(
                    "at most 255 (material, diameter) pairs, got {} x {}",
                    s.materials.len(),
                    s.diameters.len()
                ),
            ));
        }
        let c = &file.constraints;
        if let Some(m) = c.max_mass {
            positive(p, "constraints.max_mass", m, "kg")?;
        }
        if let Some(l) = c.max_length {
            positive(p, "constraints.max_length", l, "m")?;
        }
        let l = &file.load;
        let smat = material(p, "load.striker.material", &l.striker.material)?;
        once("load.striker.material".into(), smat)?;
        let striker = Bead {
            material: smat,
            diameter: diameter(p, "load.striker.diameter", l.striker.diameter)?,
        };
        if l.speeds.is_empty() {
            return Err(invalid(p, "load.speeds", "give at least one impact speed"));
        }
        if let Some(e) = l.restitution {
            if !(0.05..1.0).contains(&e) {
                return Err(invalid(
                    p,
                    "load.restitution",
                    format!("must lie in [0.05, 1) (leave it out for elastic contacts), got {e}"),
                ));
            }
        }
        let mut impacts = Vec::new();
        for (i, &v) in l.speeds.iter().enumerate() {
            impacts.push(Impact {
                striker,
                speed: positive(p, &format!("load.speeds[{i}]"), v, "m/s")?,
                restitution: l.restitution,
                restitution_pairs: Vec::new(),
            });
        }
        let protected = match (&l.wall, &l.target) {
            (Some(_), Some(_)) => {
                return Err(invalid(
                    p,
                    "load.target",
                    "give a wall or a target, not both",
                ))
            }
            (_, Some(t)) => {
                let mat = material(p, "load.target.material", &t.material)?;
                once("load.target.material".into(), mat)?;
                positive(p, "load.target.mass", t.mass, "kg")?;
                if !(t.spring.is_finite() && t.spring >= 0.0) {
                    return Err(invalid(
                        p,
                        "load.target.spring",
                        format!("must be a finite number >= 0 N/m, got {}", t.spring),
                    ));
                }
                Protected::Target {
                    mass: t.mass,
                    material: mat,
                    spring: t.spring,
                }
            }
            (w, None) => {
                let steel = MaterialKey::Name("steel".into());
                let mat = material(p, "load.wall", w.as_ref().unwrap_or(&steel))?;
                once("load.wall".into(), mat)?;
                Protected::Wall(mat)
            }
        };
        let mut pairs: Vec<PairRestitution> = Vec::new();
        for (i, pair) in l.restitution_pairs.iter().enumerate() {
            let key = format!("load.restitution_pairs[{i}]");
            let mut between = [""; 2];
            for (j, m) in pair.between.iter().enumerate() {
                let at = format!("{key}.between[{j}]");
                let mat = material(p, &at, m)?;
                match named.iter().find(|(_, x)| x.name == mat.name) {
                    None => {
                        let mut known: Vec<&str> = named.iter().map(|(_, x)| x.name).collect();
                        known.dedup();
                        return Err(invalid(
                            p,
                            at,
                            format!(
                                "`{}` is no material of this file's beads, striker, wall or \
                                 target (they are {}): a pair no contact is made of",
                                mat.name,
                                known.join(", ")
                            ),
                        ));
                    }
                    Some((other, x)) if *x != mat => {
                        return Err(invalid(
                            p,
                            at,
                            format!(
                                "named `{}` like {other}, with other constants; give each \
                                 material its own name",
                                mat.name
                            ),
                        ))
                    }
                    Some(_) => {}
                }
                between[j] = mat.name;
            }
            let e = pair.restitution;
            if !(0.05..=1.0).contains(&e) {
                return Err(invalid(
                    p,
                    format!("{key}.restitution"),
                    format!(
                        "must be a coefficient of restitution from 0.05 to 1 (elastic), got {e}"
                    ),
                ));
            }
            let new = PairRestitution {
                between,
                restitution: e,
            };
            if let Some(j) = pairs.iter().position(|q| q.same_pair(&new)) {
                return Err(invalid(
                    p,
                    key,
                    format!(
                        "names {} and {} like load.restitution_pairs[{j}]: give each pair once",
                        between[0], between[1]
                    ),
                ));
            }
            pairs.push(new);
        }
        for imp in &mut impacts {
            imp.restitution_pairs = pairs.clone();
        }
        let accuracy = file.search.accuracy;
        if let Some(why) = accuracy_problem(accuracy) {
            return Err(invalid(p, "search.accuracy", why));
        }
        // Every evaluation's steps bounded before anything runs or is written, at the engine's
        // default time cap and twice the accuracy's steps per contact time: the reported
        // designs' finer runs (their runs past that cap stop at the step limit themselves).
        let steps = |accuracy: f64| Settings {
            steps_per_contact: 2.0 * steps_for_accuracy(accuracy),
            ..Settings::default()
        };
        for (i, imp) in impacts.iter().enumerate() {
            let bound = step_bound(&choices, s.beads, imp, &protected, &steps(accuracy));
            // Contact times that are no finite numbers in doubles: a speed whose impact energy
            // rounds to 0 or overflows (the run's own check says the same, naming `speed`).
            let energy = imp.energy();
            if !(energy > 0.0 && energy.is_finite()) {
                return Err(invalid(
                    p,
                    format!("load.speeds[{i}]"),
                    format!(
                        "a speed of {:e} m/s gives the striker an impact energy of {energy:e} J \
                         in double precision, so the contact times of the run are no finite \
                         numbers: give a physical speed",
                        imp.speed
                    ),
                ));
            }
            if !(bound <= MAX_EVALUATION_STEPS) {
                let at_default =
                    step_bound(&choices, s.beads, imp, &protected, &steps(DEFAULT_ACCURACY));
                // A target so light that its contacts alone need the steps: the same column
                // in front of a wall of its material is within the limit.
                let light_target = match protected {
                    Protected::Target { material, .. } => {
                        step_bound(
                            &choices,
                            s.beads,
                            imp,
                            &Protected::Wall(material),
                            &steps(accuracy),
                        ) <= MAX_EVALUATION_STEPS
                    }
                    Protected::Wall(_) => false,
                };
                if light_target {
                    return Err(invalid(
                        p,
                        "load.target.mass",
                        format!(
                            "this target makes a run need up to {bound:.3e} steps, over the \
                             limit of {MAX_EVALUATION_STEPS:.0e} (its contacts are far shorter \
                             than the column's; in front of a wall the column is within it): \
                             give a heavier target"
                        ),
                    ));
                }
                let key = if accuracy < DEFAULT_ACCURACY && at_default <= MAX_EVALUATION_STEPS {
                    "search.accuracy"
                } else if s.diameters.len() > 1 {
                    "space.diameters"
                } else {
                    "space.materials"
                };
                return Err(invalid(
                    p,
                    key,
                    format!(
                        "a column of these candidates could need up to {bound:.3e} steps per run \
                         at accuracy {accuracy:e} (its shortest contact sets the step, the sum of \
                         its contacts the run), over the limit of {MAX_EVALUATION_STEPS:.0e}: {}",
                        if key == "search.accuracy" {
                            "ask for a coarser accuracy"
                        } else {
                            "choose candidates of closer sizes and stiffnesses"
                        }
                    ),
                ));
            }
        }
        let o = &file.objective;
        if !(o.fraction > 0.0 && o.fraction <= 1.0) {
            return Err(invalid(
                p,
                "objective.fraction",
                format!("must lie in (0, 1], got {}", o.fraction),
            ));
        }
        match (o.minimize, &o.weights) {
            (Minimize::Mix, None) => return Err(invalid(
                p,
                "objective.weights",
                "`minimize = \"mix\"` needs weights = { peak = .., impulse = .., duration = .. }",
            )),
            (Minimize::Mix, Some(w)) => {
                let all = [w.peak, w.impulse, w.duration];
                if all.iter().any(|x| !(x.is_finite() && *x >= 0.0))
                    || all.iter().sum::<f64>() <= 0.0
                {
                    return Err(invalid(
                        p,
                        "objective.weights",
                        "weights must be finite numbers >= 0, not all 0",
                    ));
                }
            }
            (_, Some(_)) => {
                return Err(invalid(
                    p,
                    "objective.weights",
                    "weights are for `minimize = \"mix\"` only",
                ))
            }
            _ => {}
        }
        let sr = &file.search;
        if !(4..=10_000).contains(&sr.population) {
            return Err(invalid(
                p,
                "search.population",
                format!("must lie in 4..=10000, got {}", sr.population),
            ));
        }
        if sr.generations == 0 {
            return Err(invalid(p, "search.generations", "must be at least 1"));
        }
        if sr.stale == 0 {
            return Err(invalid(p, "search.stale", "must be at least 1"));
        }
        let tolerances = match &file.tolerances {
            Some(t) => Some(check_tolerances(
                p, &file, t, &choices, &impacts, &protected,
            )?),
            None if o.minimize.is_robust() || o.minimize == Minimize::P95FirstOrder => {
                return Err(invalid(
                    p,
                    "objective.minimize",
                    "this objective is a statistic of the peak under the tolerances: it needs a \
                     [tolerances] table (e.g. `diameter = 0.01`)",
                ))
            }
            None => None,
        };
        let robust = robust(p, &file, tolerances.as_ref())?;
        let refine_range = match &file.refine {
            None => None,
            Some(_) if !impacts[0].is_elastic() => {
                return Err(invalid(
                    p,
                    "refine",
                    "[refine] follows the objective's gradient, and derivatives are built for \
                     elastic contacts only: leave out load.restitution and \
                     load.restitution_pairs, or [refine]",
                ))
            }
            Some(r) => {
                let ds: Vec<f64> = choices.iter().map(|b| b.diameter).collect();
                Some(
                    r.check(&ds, file.objective.minimize)
                        .map_err(|(key, why)| invalid(p, key, why))?,
                )
            }
        };
        let digest = search_digest(&file);
        Ok(DesignSpec {
            tolerances,
            robust,
            refine_range,
            per_section: s.beads / sections,
            reference: choices[0],
            path,
            file,
            choices,
            names,
            impacts,
            protected,
            digest,
        })
    }

    /// The nominal problem of a robust objective: its peak, without tolerances or the Monte
    /// Carlo (the first of a robust design's two searches; its outputs are the nominal ones).
    /// Its digest is that of what its search reads: the same file without the robust objective
    /// has the same nominal search journal.
    pub fn nominal(&self) -> DesignSpec {
        let mut n = self.clone();
        n.file.objective.minimize = Minimize::Peak;
        n.file.objective.quantile = None;
        n.robust = None;
        n.tolerances = None;
        n.digest = search_digest(&n.file);
        n
    }

    /// Sections (genes) of a design.
    pub fn sections(&self) -> usize {
        self.file.space.beads / self.per_section
    }

    /// The beads of a design given as one choice per section.
    pub fn beads(&self, genes: &[usize]) -> Vec<Bead> {
        genes
            .iter()
            .flat_map(|&g| std::iter::repeat_n(self.choices[g], self.per_section))
            .collect()
    }

    /// Why a design breaks a constraint, if it does.
    pub fn violation(&self, beads: &[Bead]) -> Option<String> {
        let mass: f64 = beads.iter().map(Bead::mass).sum();
        let length: f64 = beads.iter().map(|b| b.diameter).sum();
        let c = &self.file.constraints;
        if let Some(m) = c.max_mass.filter(|&m| mass > m) {
            return Some(format!("mass {mass:.4} kg > {m} kg"));
        }
        if let Some(l) = c.max_length.filter(|&l| length > l) {
            return Some(format!("length {length:.4} m > {l} m"));
        }
        if self.file.space.order == Order::Graded
            && beads.windows(2).any(|w| w[1].mass() > w[0].mass())
        {
            return Some("not graded: a bead heavier than the one before it".into());
        }
        None
    }
}
