//! The sweep file: one TOML file holding every setting of a study (schema below, example in
//! `studies/`). Paths inside it are relative to the file. Unknown keys are errors.
//!
//! ```toml
//! name = "containers"
//! snapshots = 4000          # run length of every member, in output intervals of the scenes
//! members = 8               # ensemble size per container
//! perturbation = { kind = "striker-speed", epsilon = 1e-12 }
//! # or { kind = "displacement", amplitude = 1e-12, seed = 1 }
//! outer_chains = 4000       # grains of `outer-left` and `beyond-striker` (default: the scene's)
//! reference = "a"           # alpha is measured against this container
//! levels = [0.1, 0.03, 0.01, 0.003]   # E_R levels (fractions of the incident energy) for alpha
//!
//! [[containers]]
//! key = "a"
//! scene = "../scenes/containers/a-standard.toml"
//! # optional, each left out of the run digest when absent:
//! # free_ends = true                                    # the paper's Fig. 3 geometry
//! # outer = { medium = "ground-damped", distance = 300, layer = 200, rate = 0.1 }
//! #   (or "long", "free-ends" with distance, "dashpot" with distance, layer, c)
//! # dissipation = { model = "scale-respecting", restitution = 0.95 }
//! # speed = 1e-3                                        # in the Hertz time scale of the impact
//! # multirate = { ratio = 8, margin = 20 }
//!
//! [search]                  # optional: readings of the lost Fig. 2 (see `study::search`)
//! count = 24
//! seed = 2005
//! members = 2
//! scenes = ["../scenes/containers/a-standard.toml", "..."]   # a, c, d, e required
//! # wall_masses, masses, exponents, interfaces, media: lists of choices (defaults in
//! # `study::search::SearchSpec`)
//!
//! [random]                  # optional: random containers (see `study::random`)
//! count = 24
//! members = 3
//! seed = 7
//! template = "../scenes/containers/a-standard.toml"
//! sections = [3, 8]         # interior sections per container (inclusive range)
//! grains = [10, 30]         # grains per section (inclusive range)
//! masses = [0.1, 0.5, 1.0]
//! exponents = [1.0, 1.5, 2.0]
//! walls = ["none", "ends", "ends-and-middle"]
//! ```

use crate::error::Error;
use crate::report::limits::{LimitWords, OUTPUT_LIMIT_BYTES};
use grainchain_engine::format::human_bytes;
use grainchain_engine::InputError;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// How the members of an ensemble differ. Member `k` counts from 0.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum Perturbation {
    /// The striker's speed times `1 + k epsilon`: member 0 is the scene itself.
    StrikerSpeed {
        /// Relative speed step between consecutive members (in (0, 1e-3)).
        epsilon: f64,
    },
    /// Every container grain displaced by a uniform random amount in `[-amplitude, amplitude]`
    /// (the scene's length units), drawn from a ChaCha8 stream seeded by `seed` and the member
    /// number: the same field for a given seed and member on every machine.
    Displacement {
        /// Largest displacement, in the scene's length units (in (0, 1e-3)).
        amplitude: f64,
        /// Seed of the ChaCha8 stream; member `k` draws from stream `2^32 + k`.
        seed: u64,
    },
}

/// `multirate = { ratio = 8, margin = 20 }`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MultirateSpec {
    /// `ratio`: the outer chains step at `ratio` times the scene's dt (at least 1); required.
    pub ratio: u64,
    /// `margin`: grains added on each side of the fast region (the container and the path from
    /// it to the striker); required.
    pub margin: u64,
}

/// One container of the study.
#[derive(Clone, Debug, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ContainerEntry {
    /// Short name used in outputs (`a`).
    pub key: String,
    /// Scene file, relative to the sweep file. It must follow the container contract of
    /// `scenes/containers/` (sections `outer-left`, `outer-right`, `beyond-striker`, a region
    /// `container`, the striker as an `[[initial]]` velocity).
    pub scene: PathBuf,
    /// Multiple time stepping for this container only (overrides the sweep's `multirate`).
    #[serde(default)]
    pub multirate: Option<MultirateSpec>,
    /// The paper's Fig. 3 geometry instead of long outer chains: `outer-left` of 120 grains and
    /// no `beyond-striker` (the striker is the last grain), both ends free, so disturbances
    /// reach the ends and come back (the run does not require untouched ends).
    /// (Left out of the run digest when false, so digests of sweeps written before this key
    /// existed do not change.)
    #[serde(default, skip_serializing_if = "is_false")]
    pub free_ends: bool,
    /// Contact damping at every contact of the scene, steel-like: `{ model, restitution }`
    /// (`batch::ContainerScene::dissipation`; integrated by blanes-moan4 at the scene's dt, not
    /// multirate). Left out of the run digest when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dissipation: Option<DissipationSpec>,
    /// The striker's speed (program units; default the scene's), in the Hertz time scale of the
    /// impact: snapshots and run length scaled by `(v0 / speed)^(1/5)`
    /// (`batch::ContainerScene::striker_speed`). Left out of the run digest when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub speed: Option<f64>,
    /// What lies beyond the outer chains (`outer = { medium = "free-ends", distance = 300 }`;
    /// [`crate::batch::scenes::OuterMedium`]): `long` (the default), `free-ends`,
    /// `ground-damped` or `dashpot`. Left out of the run digest when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub outer: Option<crate::batch::scenes::OuterMedium>,
}

impl ContainerEntry {
    /// Container `key` on `scene` as the file stands: every dimension at its default (a new
    /// dimension gives its default here, not at every place that makes an entry).
    pub fn new(key: impl Into<String>, scene: impl Into<PathBuf>) -> Self {
        ContainerEntry {
            key: key.into(),
            scene: scene.into(),
            multirate: None,
            free_ends: false,
            dissipation: None,
            speed: None,
            outer: None,
        }
    }
}

/// `dissipation = { model = "scale-respecting", restitution = 0.95 }`: every section's contacts
/// damped so that two of its grains part with this restitution.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DissipationSpec {
    /// `viscous`, `kuwabara-kono` or `scale-respecting` (the restitution at every speed).
    pub model: grainchain_engine::DampingModel,
    /// The coefficient of restitution of two equal grains at speed 1, in [0.05, 1).
    pub restitution: f64,
}

/// Wall layout of a random container.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum Walls {
    /// `none`: no walls; the interior sections touch the outer chains.
    None,
    /// `ends`: a linear wall section at each end of the container.
    Ends,
    /// `ends-and-middle`: walls at both ends and one after the middle interior section (section
    /// `ceil(n/2)` of `n`, when `n >= 2`), like container (a).
    EndsAndMiddle,
}

impl Walls {
    /// The layout's name as written in the sweep file (`none`, `ends`, `ends-and-middle`).
    pub fn name(self) -> &'static str {
        match self {
            Walls::None => "none",
            Walls::Ends => "ends",
            Walls::EndsAndMiddle => "ends-and-middle",
        }
    }
}

/// The distribution of random containers.
#[derive(Clone, Debug, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RandomSpec {
    /// `count`: number of random containers (at least 1), keyed `r-001`, `r-002`, ...
    pub count: u64,
    /// `members`: ensemble members per random container (at least 1).
    pub members: u64,
    /// `seed`: seed of the ChaCha8 streams; container `i` (1-based) draws from stream `i`.
    pub seed: u64,
    /// A container scene whose outer chains, striker, integrator and run settings are kept; its
    /// container is replaced.
    pub template: PathBuf,
    /// `sections`: `[min, max]`, the number of interior sections is drawn uniformly from
    /// `min..=max` (1 <= min <= max <= 50).
    pub sections: [u64; 2],
    /// `grains`: `[min, max]`, each interior section's grain count is drawn uniformly from
    /// `min..=max` (1 <= min <= max <= 1000).
    pub grains: [u64; 2],
    /// `masses`: each interior section's grain mass is drawn uniformly from this list (positive,
    /// at least one).
    pub masses: Vec<f64>,
    /// `exponents`: each interior section's contact exponent p is drawn uniformly from this list
    /// (>= 1, at least one).
    pub exponents: Vec<f64>,
    /// `walls`: the wall layout is drawn uniformly from this list (at least one).
    pub walls: Vec<Walls>,
    /// Wall sections: grains, mass (default 20 grains of mass 2, linear, as in the paper's
    /// containers).
    #[serde(default = "default_wall_grains")]
    pub wall_grains: u64,
    /// `wall_mass`: mass of each wall grain (> 0); default 2.
    #[serde(default = "default_wall_mass")]
    pub wall_mass: f64,
}

fn is_false(b: &bool) -> bool {
    !*b
}

fn default_wall_grains() -> u64 {
    20
}
fn default_wall_mass() -> f64 {
    2.0
}

/// A study: everything `grainchain study` needs.
#[derive(Clone, Debug, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Sweep {
    /// `name`: the study's name, the title of `STUDY.md` (not in the run digest).
    pub name: String,
    /// `description`: free text for `STUDY.md`; default none (not in the run digest).
    #[serde(default)]
    pub description: Option<String>,
    /// `snapshots`: run length of every member, in output intervals of its scene (at least 20: a
    /// fit needs a decade of snapshots from `snapshots/10`).
    pub snapshots: u64,
    /// `members`: ensemble size of each `[[containers]]` entry (at least 1 when there are any);
    /// default 0.
    #[serde(default)]
    pub members: u64,
    /// `perturbation`: how the members of an ensemble differ; required.
    pub perturbation: Perturbation,
    /// `outer_chains`: grains of the `outer-left` and `beyond-striker` sections of every scene
    /// (at least 10); default: the scene's own.
    #[serde(default)]
    pub outer_chains: Option<u64>,
    /// Integrate with multiple time stepping (`integrators::multirate`): the container plus
    /// `margin` grains on each side at the scene's dt, the rest at `ratio` times it.
    #[serde(default)]
    pub multirate: Option<MultirateSpec>,
    /// `reference`: key of the container that alpha and the collapse are measured against;
    /// default none (no alpha). Not in the run digest.
    #[serde(default)]
    pub reference: Option<String>,
    /// `levels`: E_R levels, as fractions of the incident energy in (0, 1), at which alpha (the
    /// ratio of crossing times) and the local slope are compared; default
    /// `[0.1, 0.03, 0.01, 0.003]`. Not in the run digest.
    #[serde(default = "default_levels")]
    pub levels: Vec<f64>,
    /// `[[containers]]`: the containers given by scene files, in study order; default none.
    #[serde(default)]
    pub containers: Vec<ContainerEntry>,
    /// `[random]`: random containers drawn from a seeded distribution; default none. A study
    /// needs `[[containers]]` or `[random]`.
    #[serde(default)]
    pub random: Option<RandomSpec>,
    /// `[search]`: readings of the lost Fig. 2, each run on containers (a)-(e)
    /// ([`crate::study::search`]); default none. Left out of the run digest when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub search: Option<super::search::SearchSpec>,
    /// `mechanism`: count the reflections at the edges of every container and follow the pulses
    /// inside (the paper's mechanism: STUDY.md's section "The paper's mechanism",
    /// `mechanism.csv`, `leak.csv` and their plots); default false. Left out of the run digest
    /// when false.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub mechanism: bool,
}

fn default_levels() -> Vec<f64> {
    vec![0.1, 0.03, 0.01, 0.003]
}

/// A sweep file, read and checked.
#[derive(Clone, Debug)]
pub struct SweepFile {
    /// The sweep file, as given; relative paths inside it are resolved against its directory.
    pub path: PathBuf,
    /// The parsed and checked settings.
    pub sweep: Sweep,
    /// FNV-1a 64 of [`SweepFile::settings`]: everything that decides what a member computes.
    /// Member files of another digest are never merged or kept.
    pub digest: String,
    /// What decides what a member computes, normalised: the run settings of the sweep (not its
    /// analysis settings: name, description, reference, levels), every scene file it uses as
    /// parsed (so comments, spacing, key order and number spelling do not count) and the program
    /// ([`crate::program()`]). Member files record it, so a refused member names the difference.
    pub settings: serde_json::Value,
    /// Every scene file the sweep names, read and parsed once (the digest is taken from these
    /// parses, and every job edits a copy), by resolved path.
    sources: Vec<crate::batch::SceneSource>,
}

/// Bytes of one number of a member file (shortest round-trip text of an energy, about 20
/// characters, and a comma), for [`SweepFile::size_estimate`].
pub const MEMBER_NUMBER_BYTES: u64 = 20;
/// Bytes of a member's JSON bookkeeping (its measured size: BENCHMARKS.md, "Ensemble studies").
pub const MEMBER_META_BYTES: u64 = 7000;

fn invalid(path: &Path, key: &str, message: impl Into<String>) -> Error {
    Error::Input(InputError::Invalid {
        file: path.to_path_buf(),
        key: key.into(),
        message: message.into(),
    })
}

use crate::report::fnv1a;

impl SweepFile {
    /// Read, parse and check a sweep file: errors name the file and key.
    pub fn load(path: impl AsRef<Path>) -> Result<Self, Error> {
        let path = path.as_ref().to_path_buf();
        let text = grainchain_engine::file::read_text(&path)?;
        // One parse; TOML integers are 64-bit signed, a larger number refused as in a scene.
        let sweep: Sweep = grainchain_engine::file::parse_toml(
            &text,
            &path,
            grainchain_engine::file::FileKind::Sweep,
        )?
        .typed;
        let mut f = SweepFile {
            digest: String::new(),
            settings: serde_json::Value::Null,
            path,
            sweep,

            sources: Vec::new(),
        };
        f.check()?;
        f.settings = f.run_settings()?;
        f.digest = fnv1a(&serde_json::to_vec(&f.settings)?);
        Ok(f)
    }

    /// The key of the sweep that sets most of its jobs (for the message refusing too many):
    /// `members` of the containers, or the `count` or `members` of `[random]` or `[search]`.
    pub fn jobs_key(&self) -> &'static str {
        let s = &self.sweep;
        let mut parts = vec![(
            (s.containers.len() as u64).saturating_mul(s.members),
            "members",
        )];
        if let Some(r) = &s.random {
            let jobs = r.count.saturating_mul(r.members);
            parts.push((
                jobs,
                if r.count >= r.members {
                    "random.count"
                } else {
                    "random.members"
                },
            ));
        }
        if let Some(x) = &s.search {
            let jobs = x
                .count
                .saturating_mul(x.members)
                .saturating_mul(x.scenes.len() as u64);
            parts.push((
                jobs,
                if x.count >= x.members {
                    "search.count"
                } else {
                    "search.members"
                },
            ));
        }
        // The first of the largest, in file order.
        parts
            .iter()
            .rev()
            .max_by_key(|p| p.0)
            .map_or("members", |p| p.1)
    }

    /// The refusal of this study when its member files are estimated above
    /// [`OUTPUT_LIMIT_BYTES`] (the sweep file at `sweep`, its jobs key), `words.allow` the
    /// caller's way to run anyway; `None` under the limit. Bounded before the job list is made
    /// (a list of 1e8 jobs alone takes gigabytes).
    pub fn size_refusal(&self, sweep: &Path, words: LimitWords) -> Option<InputError> {
        let (n_jobs, bytes) = self.size_estimate();
        (bytes > OUTPUT_LIMIT_BYTES).then(|| InputError::Invalid {
            file: sweep.to_path_buf(),
            key: self.jobs_key().to_string(),
            message: format!(
                "{n_jobs} jobs whose member files would take at least {} (estimated), over the \
                 limit of {}; run fewer members or snapshots, or pass {}",
                human_bytes(bytes),
                human_bytes(OUTPUT_LIMIT_BYTES),
                words.allow
            ),
        })
    }

    /// Jobs and a lower estimate of the bytes of their member files, from the file's numbers
    /// alone (no job list is made, no scene built): every member file has `snapshots + 1` rows
    /// of at least a snapshot number and two energies (the container and one section outside
    /// it), `MEMBER_NUMBER_BYTES` each, and a JSON file of about `MEMBER_META_BYTES`.
    pub fn size_estimate(&self) -> (u64, u64) {
        let s = &self.sweep;
        let jobs = (s.containers.len() as u64)
            .saturating_mul(s.members)
            .saturating_add(
                s.random
                    .as_ref()
                    .map_or(0, |r| r.count.saturating_mul(r.members)),
            )
            .saturating_add(s.search.as_ref().map_or(0, |x| {
                (x.count.saturating_mul(x.members)).saturating_mul(x.scenes.len() as u64)
            }));
        let per_member = s
            .snapshots
            .saturating_add(1)
            .saturating_mul(3 * MEMBER_NUMBER_BYTES)
            .saturating_add(MEMBER_META_BYTES);
        (jobs, jobs.saturating_mul(per_member))
    }

    /// The parsed scene file at `path` (resolved), one of those the sweep names.
    pub fn source(&self, path: &Path) -> Option<&crate::batch::SceneSource> {
        self.sources.iter().find(|s| s.path == path)
    }

    /// Read and parse every scene file the sweep names, once each ([`SweepFile::sources`]),
    /// and return the run settings, the scenes as parsed among them.
    fn run_settings(&mut self) -> Result<serde_json::Value, Error> {
        let s = &self.sweep;
        let mut scenes = serde_json::Map::new();
        let files = s
            .containers
            .iter()
            .map(|c| &c.scene)
            .chain(s.random.as_ref().map(|r| &r.template))
            .chain(s.search.iter().flat_map(|x| &x.scenes));
        let mut sources: Vec<crate::batch::SceneSource> = Vec::new();
        for p in files {
            let f = self.resolve(p);
            if !sources.iter().any(|s| s.path == f) {
                sources.push(crate::batch::SceneSource::read(&f)?);
            }
            let value = sources.iter().find(|s| s.path == f).expect("just read");
            scenes.insert(
                p.display().to_string(),
                serde_json::to_value(value.value())?,
            );
        }
        self.sources = sources;
        let mut v = serde_json::json!({
            "program": crate::program(),
            "snapshots": s.snapshots,
            "members": s.members,
            "perturbation": s.perturbation,
            "outer_chains": s.outer_chains,
            "multirate": s.multirate,
            "containers": s.containers,
            "random": s.random,
            "scenes": scenes,
        });
        if let Some(x) = &s.search {
            v["search"] = serde_json::to_value(x)?;
        }
        Ok(v)
    }

    /// A sweep built in code: `path` is where its relative paths are resolved from (its
    /// directory) and what errors name.
    pub fn from_sweep(path: impl Into<PathBuf>, sweep: Sweep) -> Result<Self, Error> {
        let mut f = SweepFile {
            path: path.into(),
            sweep,
            digest: String::new(),
            settings: serde_json::Value::Null,

            sources: Vec::new(),
        };
        f.check()?;
        f.settings = f.run_settings()?;
        f.digest = fnv1a(&serde_json::to_vec(&f.settings)?);
        Ok(f)
    }

    /// The batch members of this sweep belong to: its digest and settings.
    pub fn id(&self) -> crate::batch::BatchId<'_> {
        crate::batch::BatchId {
            digest: &self.digest,
            settings: &self.settings,
        }
    }

    /// Digest of what the sweep's members compute, leaving out the program (an output folder
    /// belongs to a sweep across builds; its members are checked against the build one by one).
    pub fn inputs_digest(&self) -> String {
        let mut s = self.settings.clone();
        if let Some(m) = s.as_object_mut() {
            m.remove("program");
        }
        fnv1a(&serde_json::to_vec(&s).unwrap_or_default())
    }

    /// Rows of every member file: snapshots 0 to [`Sweep::snapshots`].
    pub fn rows(&self) -> usize {
        self.sweep.snapshots as usize + 1
    }

    /// What every member file holds: [`SweepFile::rows`] rows, the container's energy in every
    /// row, the energy budget's sections at [`crate::study::budget_outputs`] only.
    pub fn shape(&self) -> crate::batch::Shape {
        crate::batch::Shape {
            rows: self.rows(),
            every_row: std::iter::once("container")
                .chain(crate::batch::GAUGES)
                .map(String::from)
                .collect(),
            sampled_at: Some(budget_outputs(self.rows() - 1)),
        }
    }

    /// A path of the sweep file, resolved against its directory.
    pub fn resolve(&self, p: &Path) -> PathBuf {
        match self.path.parent() {
            Some(d) if p.is_relative() => d.join(p),
            _ => p.to_path_buf(),
        }
    }

    fn check(&self) -> Result<(), Error> {
        let s = &self.sweep;
        let p = &self.path;
        if s.snapshots < 20 {
            return Err(invalid(p, "snapshots", format!("must be at least 20 (got {}): a fit needs a decade of snapshots from snapshots/10", s.snapshots)));
        }
        // The scenes' own limit (scene::check, `run`): checked here so that it is reported
        // against this file, not the container scene whose duration it sets.
        if s.snapshots > grainchain_engine::MAX_OUTPUTS {
            return Err(invalid(
                p,
                "snapshots",
                format!("must be at most 1e9 output times (got {})", s.snapshots),
            ));
        }
        if s.containers.is_empty() && s.random.is_none() && s.search.is_none() {
            return Err(invalid(
                p,
                "containers",
                "the study has nothing to run: give [[containers]], [random] or [search]",
            ));
        }
        if !s.containers.is_empty() && s.members == 0 {
            return Err(invalid(p, "members", "must be at least 1"));
        }
        match s.perturbation {
            Perturbation::StrikerSpeed { epsilon } => {
                if !(epsilon.is_finite() && epsilon > 0.0 && epsilon < 1e-3) {
                    return Err(invalid(
                        p,
                        "perturbation.epsilon",
                        format!("must be in (0, 1e-3): a tiny perturbation (got {epsilon})"),
                    ));
                }
            }
            Perturbation::Displacement { amplitude, .. } => {
                if !(amplitude.is_finite() && amplitude > 0.0 && amplitude < 1e-3) {
                    return Err(invalid(
                        p,
                        "perturbation.amplitude",
                        format!("must be in (0, 1e-3) length units of the scene: a tiny perturbation (got {amplitude})"),
                    ));
                }
            }
        }
        if let Some(m) = s.multirate {
            if m.ratio == 0 {
                return Err(invalid(p, "multirate.ratio", "must be at least 1"));
            }
        }
        for (i, c) in s.containers.iter().enumerate() {
            if let Some(v) = c.speed.filter(|v| !(v.is_finite() && *v > 0.0)) {
                return Err(invalid(
                    p,
                    &format!("containers[{i}].speed"),
                    format!("must be a finite number > 0, got {v}"),
                ));
            }
            if let Some(d) = c.dissipation {
                if !(0.05..1.0).contains(&d.restitution) {
                    return Err(invalid(
                        p,
                        &format!("containers[{i}].dissipation.restitution"),
                        format!("must be in [0.05, 1), got {}", d.restitution),
                    ));
                }
            }
            if let Some(problem) = c.outer.and_then(|o| o.problem()) {
                return Err(invalid(p, &format!("containers[{i}].outer"), problem));
            }
            if c.free_ends && c.outer.is_some() {
                return Err(invalid(
                    p,
                    &format!("containers[{i}].outer"),
                    "give either `free_ends` (the paper's Fig. 3 geometry) or `outer`, not both",
                ));
            }
            // Contact damping and a damped outer medium need a single-rate splitting method
            // (multirate applies no damping): a container that asks for multirate itself
            // beside them is refused naming both keys, rather than running single rate
            // silently. (The sweep's own `multirate` gives way to the container's setting.)
            let damped = if c.dissipation.is_some() {
                Some("dissipation")
            } else if c.outer.is_some_and(|o| o.damps()) {
                Some("outer")
            } else {
                None
            };
            if let (Some(_), Some(what)) = (c.multirate, damped) {
                return Err(invalid(
                    p,
                    &format!("containers[{i}].multirate"),
                    format!(
                        "cannot apply with `containers[{i}].{what}`: damping needs a single-rate \
                         splitting method (multirate applies none); remove one of the two"
                    ),
                ));
            }
            if c.multirate.is_some_and(|m| m.ratio == 0) {
                return Err(invalid(
                    p,
                    &format!("containers[{i}].multirate.ratio"),
                    "must be at least 1",
                ));
            }
        }
        if let Some(n) = s.outer_chains {
            // The outer medium's `distance` has the same bound; two such chains stay far
            // inside a scene's 1e8 grains, and no count can wrap.
            if !(10..=1_000_000).contains(&n) {
                return Err(invalid(
                    p,
                    "outer_chains",
                    format!("must be between 10 and 1e6 grains (got {n})"),
                ));
            }
        }
        for (i, l) in s.levels.iter().enumerate() {
            if !(*l > 0.0 && *l < 1.0) {
                return Err(invalid(
                    p,
                    &format!("levels[{i}]"),
                    format!("must be a fraction of the incident energy in (0, 1) (got {l})"),
                ));
            }
        }
        self.check_containers()?;
        if let Some(r) = &s.random {
            self.check_random(r)?;
        }
        if let Some(x) = &s.search {
            self.check_search(x)?;
        }
        Ok(())
    }

    /// Container keys (unique, not `r-`), their scene files, and the reference key.
    fn check_containers(&self) -> Result<(), Error> {
        let (s, p) = (&self.sweep, &self.path);
        let mut keys = std::collections::BTreeSet::new();
        for (i, c) in s.containers.iter().enumerate() {
            let ok = !c.key.is_empty()
                && c.key
                    .chars()
                    .all(|ch| ch.is_ascii_alphanumeric() || ch == '-' || ch == '_');
            use super::KeyKind;
            let [random, search] =
                [KeyKind::Random, KeyKind::Search].map(|k| k.prefix().unwrap_or_default());
            if !ok || c.key.starts_with(random) || c.key.starts_with(search) {
                return Err(invalid(
                    p,
                    &format!("containers[{i}].key"),
                    format!("`{}`: use letters, digits, `-` and `_` (not starting with `{random}` or `{search}`, which name random containers and the search's)", c.key),
                ));
            }
            // It names the container's member files (`<key>-m<k>.csv`): the scene name's limit.
            if c.key.len() > grainchain_engine::NAME_MAX_BYTES {
                return Err(invalid(
                    p,
                    &format!("containers[{i}].key"),
                    format!(
                        "is {} bytes long; at most {} (it names the member files, and a file \
                         name has at most 255 bytes)",
                        c.key.len(),
                        grainchain_engine::NAME_MAX_BYTES
                    ),
                ));
            }
            if !keys.insert(c.key.clone()) {
                return Err(invalid(
                    p,
                    &format!("containers[{i}].key"),
                    format!("`{}` is used twice", c.key),
                ));
            }
            let f = self.resolve(&c.scene);
            if !f.is_file() {
                return Err(invalid(
                    p,
                    &format!("containers[{i}].scene"),
                    format!("no such file: {}", f.display()),
                ));
            }
        }
        if let Some(r) = &s.reference {
            if !keys.contains(r) {
                return Err(invalid(
                    p,
                    "reference",
                    format!("`{r}` is not the key of a container of this study"),
                ));
            }
        }
        Ok(())
    }

    /// The `[search]` table: counts, the lists of choices and the container scenes.
    fn check_search(&self, x: &super::search::SearchSpec) -> Result<(), Error> {
        let p = &self.path;
        let k = |y: &str| format!("search.{y}");
        if x.count == 0 {
            return Err(invalid(p, &k("count"), "must be at least 1"));
        }
        if x.members == 0 {
            return Err(invalid(p, &k("members"), "must be at least 1"));
        }
        let positive = |v: f64| v.is_finite() && v > 0.0;
        if x.wall_masses.is_empty() || !x.wall_masses.iter().all(|m| positive(*m)) {
            return Err(invalid(
                p,
                &k("wall_masses"),
                "must be positive masses, at least one",
            ));
        }
        if x.masses.is_empty() || !x.masses.iter().flatten().all(|m| positive(*m)) {
            return Err(invalid(
                p,
                &k("masses"),
                "must be triples of positive masses, at least one",
            ));
        }
        if x.exponents.is_empty()
            || !x
                .exponents
                .iter()
                .flatten()
                .all(|e| e.is_finite() && *e >= 1.0)
        {
            return Err(invalid(
                p,
                &k("exponents"),
                "must be triples of exponents >= 1, at least one",
            ));
        }
        if x.interfaces.is_empty() {
            return Err(invalid(
                p,
                &k("interfaces"),
                "give at least one interface rule",
            ));
        }
        if x.media.is_empty() {
            return Err(invalid(p, &k("media"), "give at least one outer medium"));
        }
        for (i, m) in x.media.iter().enumerate() {
            if let Some(problem) = m.problem() {
                return Err(invalid(p, &k(&format!("media[{i}]")), problem));
            }
        }
        let mut keys = Vec::new();
        for (i, f) in x.scenes.iter().enumerate() {
            if !self.resolve(f).is_file() {
                return Err(invalid(
                    p,
                    &k(&format!("scenes[{i}]")),
                    format!("no such file: {}", self.resolve(f).display()),
                ));
            }
            let key = super::search::scene_key(f);
            if keys.contains(&key) {
                return Err(invalid(
                    p,
                    &k(&format!("scenes[{i}]")),
                    format!("a second container `{key}` (scenes are keyed by their file name up to the first `-`)"),
                ));
            }
            keys.push(key);
        }
        for need in ["a", "c", "d", "e"] {
            if !keys.iter().any(|k| k == need) {
                return Err(invalid(
                    p,
                    &k("scenes"),
                    format!("needs container `{need}` (a scene file named `{need}-*.toml`): gamma is (a)'s, alpha is scored for (c), (d), (e)"),
                ));
            }
        }
        Ok(())
    }

    /// The `[random]` table: counts, ranges and the template scene.
    fn check_random(&self, r: &RandomSpec) -> Result<(), Error> {
        let p = &self.path;
        let k = |x: &str| format!("random.{x}");
        if r.count == 0 {
            return Err(invalid(p, &k("count"), "must be at least 1"));
        }
        if r.members == 0 {
            return Err(invalid(p, &k("members"), "must be at least 1"));
        }
        if r.sections[0] < 1 || r.sections[0] > r.sections[1] || r.sections[1] > 50 {
            return Err(invalid(
                p,
                &k("sections"),
                "must be [min, max] with 1 <= min <= max <= 50",
            ));
        }
        if r.grains[0] < 1 || r.grains[0] > r.grains[1] || r.grains[1] > 1000 {
            return Err(invalid(
                p,
                &k("grains"),
                "must be [min, max] with 1 <= min <= max <= 1000",
            ));
        }
        if r.masses.is_empty() || r.masses.iter().any(|m| !(m.is_finite() && *m > 0.0)) {
            return Err(invalid(
                p,
                &k("masses"),
                "must be positive masses, at least one",
            ));
        }
        if r.exponents.is_empty() || r.exponents.iter().any(|e| !(e.is_finite() && *e >= 1.0)) {
            return Err(invalid(
                p,
                &k("exponents"),
                "must be contact exponents >= 1, at least one",
            ));
        }
        if r.walls.is_empty() {
            return Err(invalid(p, &k("walls"), "give at least one wall layout"));
        }
        if !(1..=1000).contains(&r.wall_grains) {
            return Err(invalid(
                p,
                &k("wall_grains"),
                format!(
                    "must be between 1 and 1000 grains, as a section's `grains` (got {})",
                    r.wall_grains
                ),
            ));
        }
        if !(r.wall_mass.is_finite() && r.wall_mass > 0.0) {
            return Err(invalid(
                p,
                &k("wall_mass"),
                format!("must be a positive mass (got {})", r.wall_mass),
            ));
        }
        let t = self.resolve(&r.template);
        if !t.is_file() {
            return Err(invalid(
                p,
                &k("template"),
                format!("no such file: {}", t.display()),
            ));
        }
        Ok(())
    }
}

/// `K/N`: run the K-th of N parts of a study (1-based).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// Which part this is, 1-based (`1..=n`).
    pub k: usize,
    /// Number of parts the study is split into (at least 1).
    pub n: usize,
}

impl Shard {
    /// The whole study as one shard: `1/1`.
    pub const ALL: Shard = Shard { k: 1, n: 1 };

    /// Job `j` (0-based, in study order) belongs to this shard: round robin, so every shard gets
    /// a mix of cheap and costly jobs.
    pub fn owns(self, j: usize) -> bool {
        j % self.n == self.k - 1
    }
}

impl std::str::FromStr for Shard {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let (a, b) = s
            .split_once('/')
            .ok_or_else(|| format!("`{s}`: expected K/N, e.g. 2/3"))?;
        let k: usize = a
            .trim()
            .parse()
            .map_err(|_| format!("`{s}`: K must be a whole number"))?;
        let n: usize = b
            .trim()
            .parse()
            .map_err(|_| format!("`{s}`: N must be a whole number"))?;
        if n == 0 || k == 0 || k > n {
            return Err(format!("`{s}`: need 1 <= K <= N (part K of N parts)"));
        }
        Ok(Shard { k, n })
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.k, self.n)
    }
}

/// Snapshots 1 to `n`, every one up to 100, then 200 per decade (the points of a log-time plot).
pub(super) fn log_thinned(n: usize) -> Vec<usize> {
    let mut v: Vec<usize> = (1..=n.min(100)).collect();
    let mut x = 100.0f64;
    while (x as usize) < n {
        x *= 10f64.powf(1.0 / 200.0);
        let t = (x as usize).min(n);
        if v.last() != Some(&t) {
            v.push(t);
        }
    }
    v
}

/// The snapshots at which a study records the energy budget's sections outside the container:
/// 0 and the points of its plot (every snapshot to 100, then 200 per decade), so the last
/// snapshot `n` too. About 700 of 100,000.
pub fn budget_outputs(n: usize) -> Vec<usize> {
    let mut v = vec![0];
    v.extend(log_thinned(n));
    v
}

/// What a container key of a study names; the job list ([`super::plan`]) says which kind each key is,
/// and the keys of random containers and search readings are made here only
/// ([`KeyKind::random`], [`KeyKind::search`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KeyKind {
    /// A `[[containers]]` entry: its key as the sweep file writes it.
    Container,
    /// A random container: `r-001`, `r-002`, ...
    Random,
    /// A reading of the search on one of its scenes: `s-001-a`, ...
    Search,
}

impl KeyKind {
    /// The prefix every key of this kind starts with (none for a container, whose key is the
    /// user's and may not start with either).
    pub const fn prefix(self) -> Option<&'static str> {
        match self {
            KeyKind::Container => None,
            KeyKind::Random => Some("r-"),
            KeyKind::Search => Some("s-"),
        }
    }

    /// The key of random container `i` (1-based).
    pub fn random(i: u64) -> String {
        format!("r-{i:03}")
    }

    /// The key of reading `i` (1-based) of the search on the container keyed `scene`
    /// ([`super::search::scene_key`]).
    pub fn search(i: u64, scene: &str) -> String {
        format!("s-{i:03}-{scene}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_parse_and_partition() {
        assert_eq!("2/3".parse::<Shard>(), Ok(Shard { k: 2, n: 3 }));
        for bad in ["4/3", "0/3", "1/0", "x/2", "3"] {
            assert!(bad.parse::<Shard>().is_err(), "{bad}");
        }
        // Every job in exactly one shard.
        for j in 0..20 {
            let owners = (1..=3).filter(|&k| Shard { k, n: 3 }.owns(j)).count();
            assert_eq!(owners, 1);
        }
    }

    #[test]
    fn fnv_matches_reference_vectors() {
        // Published FNV-1a 64 test vectors.
        assert_eq!(fnv1a(b""), "cbf29ce484222325");
        assert_eq!(fnv1a(b"a"), "af63dc4c8601ec8c");
        assert_eq!(fnv1a(b"foobar"), "85944171f73967e8");
    }
}
