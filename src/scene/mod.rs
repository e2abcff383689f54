//! Scene files (TOML): everything a run needs, checked strictly before anything runs.
//!
//! Parsing is two-stage: serde reads the file into [`file::SceneFile`] (unknown keys are errors),
//! then [`Scene::from_file`] checks every value and builds the chain, naming the file and the key
//! of the first problem. Grain numbers in scene files and outputs are 1-based as in the paper
//! (a left striker is grain 0, a right striker N + 1).

pub mod file;

use crate::chain::{
    ChainBuilder, ChainError, ContactLaw, End, InterfaceRule, Section, Striker, StrikerEnd,
};
use crate::error::SceneError;
use crate::integrators::{IntegrationParams, Method, Sleep};
use crate::observables::{Field, PulseRule, TrackRule};
use crate::run::{RunError, Simulation, SimulationBuilder};
use file::{EndFile, LawFile, SceneFile};
use std::path::{Path, PathBuf};

/// A named grain range (printed grain numbers, inclusive).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Region {
    /// The region's name (key `regions[i].name`): the column suffix in `energies.csv`
    /// (`E_<name>`, `P_<name>`) and the name `integrator.multirate.fast` refers to.
    pub name: String,
    /// First grain, as a printed grain number (chain grains 1..=N, a left striker 0, a right
    /// striker N + 1).
    pub first: i64,
    /// Last grain, as a printed grain number (inclusive).
    pub last: i64,
}

/// What to record.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct OutputSpec {
    /// Time series of total energies, momentum and region energies.
    pub energies: bool,
    /// Per-grain snapshots (`snapshots.csv`), if asked for.
    pub snapshots: Option<SnapshotSpec>,
    /// Pulse detection (`pulses.csv`), if asked for.
    pub pulses: Option<PulseSpec>,
    /// Pulses followed from one detection to the next (`tracks.csv`).
    pub tracks: Option<TrackSpec>,
}

/// Which snapshots to record.
#[derive(Clone, Debug, PartialEq)]
pub struct SnapshotSpec {
    /// The per-grain fields recorded, in the order of the columns.
    pub fields: Vec<Field>,
    /// Record output indices that are multiples of `every` ...
    pub every: u64,
    /// ... or exactly these output indices (when not empty).
    pub at: Vec<u64>,
    /// Printed grain numbers, inclusive.
    pub first: i64,
    /// Last grain recorded (printed grain number, inclusive).
    pub last: i64,
}

impl SnapshotSpec {
    /// Whether output index `index` (0 is t = 0) is recorded.
    pub fn wants(&self, index: u64) -> bool {
        if self.at.is_empty() {
            index.is_multiple_of(self.every)
        } else {
            self.at.contains(&index)
        }
    }
}

/// What a scene will cost and write, estimated before it runs (`grainchain check`).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Estimate {
    /// Grains, a striker included.
    pub grains: usize,
    /// Output times after t = 0.
    pub outputs: u64,
    /// Steps of a fixed-step method (None for the adaptive one).
    pub steps: Option<u64>,
    /// Upper estimate of `energies.csv` in bytes (0 when not asked for).
    pub energies_bytes: u64,
    /// Upper estimate of `snapshots.csv` in bytes (0 when not asked for).
    pub snapshots_bytes: u64,
    /// Whether `pulses.csv` is written (its size depends on the pulses found).
    pub pulses: bool,
    /// Whether `tracks.csv` is written (its size depends on the pulses found).
    pub tracks: bool,
}

/// Bytes of one number as the outputs print it (`{:e}` of an f64, at most 24 characters, and a
/// comma); integers (index, grain) are counted at 12.
const NUMBER_BYTES: u64 = 25;
const INTEGER_BYTES: u64 = 12;

impl Estimate {
    /// The larger of the two estimated files and its key, for the size limit of `run`.
    pub fn largest(&self) -> (&'static str, u64) {
        if self.snapshots_bytes >= self.energies_bytes {
            ("output.snapshots", self.snapshots_bytes)
        } else {
            ("output.energies", self.energies_bytes)
        }
    }

    /// Both estimated files together.
    pub fn total_bytes(&self) -> u64 {
        self.energies_bytes + self.snapshots_bytes
    }
}

/// Pulse detection settings.
#[derive(Clone, Debug, PartialEq)]
pub struct PulseSpec {
    /// Detect at output indices that are multiples of `every` ...
    pub every: u64,
    /// ... or exactly at these output indices (when not empty).
    pub at: Vec<u64>,
    /// The thresholds that split an energy profile into pulses.
    pub rule: PulseRule,
}

impl PulseSpec {
    /// Whether pulses are detected at output index `index` (0 is t = 0).
    pub fn wants(&self, index: u64) -> bool {
        if self.at.is_empty() {
            index.is_multiple_of(self.every)
        } else {
            self.at.contains(&index)
        }
    }
}

/// Pulse tracking settings (`output.tracks`): pulses detected with `rule` at every `every`-th
/// output and linked by `track` ([`crate::observables::tracking`]).
#[derive(Clone, Debug, PartialEq)]
pub struct TrackSpec {
    pub every: u64,
    pub rule: PulseRule,
    pub track: TrackRule,
}

/// A checked scene.
#[derive(Clone, Debug)]
pub struct Scene {
    /// The scene file (as given), named in error messages.
    pub path: PathBuf,
    /// The scene's name: key `name`, or the file name without its extension.
    pub name: String,
    /// Key `description`, or empty.
    pub description: String,
    /// The integration settings (`[integrator]`); the multirate grains are filled in by
    /// [`Scene::simulation`].
    pub params: IntegrationParams,
    /// Simulated time, in the scene's time units (`run.duration`).
    pub duration: f64,
    /// Time between output times (`run.output_interval`).
    pub output_interval: f64,
    /// The named grain ranges (`[[regions]]`), in file order.
    pub regions: Vec<Region>,
    /// What to record (`[output]`).
    pub output: OutputSpec,
    builder: ChainBuilder,
    initial: Vec<(i64, Option<f64>, Option<f64>)>,
    /// Multirate: ratio and the fast region's first and last grain numbers.
    multirate: Option<(u64, i64, i64)>,
    /// Number of grains including a striker.
    pub grains: usize,
    /// Printed number of internal grain 0 (0 with a left striker, else 1).
    first_number: i64,
}

struct Ctx<'a> {
    file: &'a Path,
}

impl Ctx<'_> {
    fn err(&self, key: impl Into<String>, message: impl Into<String>) -> SceneError {
        SceneError::Invalid {
            file: self.file.to_path_buf(),
            key: key.into(),
            message: message.into(),
        }
    }

    fn positive(&self, key: &str, x: f64) -> Result<f64, SceneError> {
        if x.is_finite() && x > 0.0 {
            Ok(x)
        } else {
            Err(self.err(key, format!("must be a finite number > 0, got {x}")))
        }
    }

    fn non_negative(&self, key: &str, x: f64) -> Result<f64, SceneError> {
        if x.is_finite() && x >= 0.0 {
            Ok(x)
        } else {
            Err(self.err(key, format!("must be a finite number >= 0, got {x}")))
        }
    }

    /// The law of a section, wall or striker, checked by [`ContactLaw::validate`] (the one place
    /// the rules live) and its error put under the scene key of the parameter at fault.
    fn law(&self, key: &str, l: &LawFile) -> Result<ContactLaw, SceneError> {
        let law = ContactLaw {
            p: l.p,
            eta: l.eta,
            delta0: l.delta0.unwrap_or(0.0),
            tension: l.tension.unwrap_or(false),
        };
        law.validate()
            .map_err(|e| self.err(format!("{key}.{}", e.key()), e.problem()))?;
        Ok(law)
    }
}

impl Scene {
    /// The region called `name`, if the scene defines one.
    pub fn region(&self, name: &str) -> Option<&Region> {
        self.regions.iter().find(|r| r.name == name)
    }

    /// The grains of region `name` as internal indices (inclusive), the numbering of the
    /// library ([`crate::Chain`], [`crate::recorder::Recorder`], [`SimulationBuilder`]); the
    /// scene file gives them as printed grain numbers. The error names the scene's regions.
    pub fn region_grains(&self, name: &str) -> Result<std::ops::RangeInclusive<usize>, SceneError> {
        let r = self.region(name).ok_or_else(|| SceneError::Invalid {
            file: self.path.clone(),
            key: "regions".into(),
            message: format!(
                "no region named `{name}` (regions: {})",
                self.regions
                    .iter()
                    .map(|r| r.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        })?;
        // Checked inside the chain when the scene was read.
        let index = |g: i64| (g - self.first_number) as usize;
        Ok(index(r.first)..=index(r.last))
    }

    /// Read and check a scene file.
    pub fn load(path: impl AsRef<Path>) -> Result<Scene, SceneError> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|source| SceneError::Read {
            file: path.to_path_buf(),
            source,
        })?;
        Scene::parse(&text, path)
    }

    /// Check a scene given as text (`path` names it in error messages).
    pub fn parse(text: &str, path: &Path) -> Result<Scene, SceneError> {
        let f: SceneFile = toml::from_str(text).map_err(|e| SceneError::Parse {
            file: path.to_path_buf(),
            message: file::describe_toml_error(&e, text),
        })?;
        Scene::from_file(f, path)
    }

    /// Check the values of a parsed scene.
    pub fn from_file(f: SceneFile, path: &Path) -> Result<Scene, SceneError> {
        let c = Ctx { file: path };
        let ch = &f.chain;
        if ch.sections.is_empty() {
            return Err(c.err("chain.sections", "the chain needs at least one section"));
        }
        let mut builder =
            ChainBuilder::new().interface(ch.interface.unwrap_or(InterfaceRule::MinExponent));
        let mut total: usize = 0;
        let mut damped_key: Option<String> = None;
        let mut names: Vec<String> = Vec::new();
        for (i, s) in ch.sections.iter().enumerate() {
            let key = format!("chain.sections[{i}]");
            if s.count == 0 {
                return Err(c.err(format!("{key}.count"), "must be at least 1"));
            }
            total = total
                .checked_add(s.count as usize)
                .filter(|&t| t <= 100_000_000)
                .ok_or_else(|| {
                    c.err(
                        format!("{key}.count"),
                        "the chain may have at most 100000000 grains",
                    )
                })?;
            c.positive(&format!("{key}.mass"), s.mass)?;
            let law = c.law(&key, &s.law)?;
            let name = s
                .name
                .clone()
                .unwrap_or_else(|| format!("section {}", i + 1));
            // Sections are looked up by name (regions, multirate, studies): a name given twice
            // would make the lookup ambiguous.
            if names.contains(&name) {
                return Err(c.err(
                    format!("{key}.name"),
                    format!("section `{name}` is named twice (names must be unique)"),
                ));
            }
            names.push(name.clone());
            let damping = c.non_negative(&format!("{key}.damping"), s.damping.unwrap_or(0.0))?;
            if damping > 0.0 && damped_key.is_none() {
                damped_key = Some(format!("{key}.damping"));
            }
            builder = builder
                .section(Section::new(name, s.count as usize, s.mass, law).with_damping(damping));
        }
        for (side, e) in [("left", &ch.left), ("right", &ch.right)] {
            let end = match e {
                None | Some(EndFile::Free) => End::Free,
                Some(EndFile::Wall(l)) => End::Wall(c.law(&format!("chain.{side}"), l)?),
            };
            builder = if side == "left" {
                builder.left(end)
            } else {
                builder.right(end)
            };
        }
        let mut striker_end = None;
        if let Some(s) = &f.striker {
            c.positive("striker.mass", s.mass)?;
            c.positive("striker.speed", s.speed)?;
            let law = match (s.p, s.eta) {
                (None, None) => None,
                (Some(p), Some(eta)) => Some(c.law(
                    "striker",
                    &LawFile {
                        p,
                        eta,
                        delta0: None,
                        tension: None,
                    },
                )?),
                _ => {
                    return Err(c.err(
                        "striker",
                        "give both `p` and `eta` for the striker's contact, or neither",
                    ))
                }
            };
            let end = s.end;
            let wall = match end {
                StrikerEnd::Left => matches!(ch.left, Some(EndFile::Wall(_))),
                StrikerEnd::Right => matches!(ch.right, Some(EndFile::Wall(_))),
            };
            if wall {
                return Err(c.err(
                    "striker.end",
                    "that end of the chain is a wall; a striker needs a free end",
                ));
            }
            striker_end = Some(end);
            builder = builder.striker(Striker {
                end,
                mass: s.mass,
                speed: s.speed,
                law,
            });
        }
        let grains = total + usize::from(striker_end.is_some());
        let (lo_num, hi_num) = match striker_end {
            Some(StrikerEnd::Left) => (0i64, total as i64),
            Some(StrikerEnd::Right) => (1, total as i64 + 1),
            None => (1, total as i64),
        };
        let grain_ok = |key: String, g: i64| -> Result<i64, SceneError> {
            if g < lo_num || g > hi_num {
                Err(c.err(
                    key,
                    format!("grain {g} is outside the chain (grains {lo_num} to {hi_num})"),
                ))
            } else {
                Ok(g)
            }
        };

        let mut initial = Vec::new();
        for (i, g) in f.initial.iter().enumerate() {
            let key = format!("initial[{i}]");
            let (first, last) = match (g.grain, g.first, g.last) {
                (Some(n), None, None) => (n, n),
                (None, Some(a), Some(b)) => (a, b),
                _ => return Err(c.err(key, "give either `grain`, or both `first` and `last`")),
            };
            grain_ok(format!("{key}.first"), first)?;
            grain_ok(format!("{key}.last"), last)?;
            if first > last {
                return Err(c.err(
                    format!("{key}.last"),
                    format!("last ({last}) is before first ({first})"),
                ));
            }
            if g.velocity.is_none() && g.displacement.is_none() {
                return Err(c.err(key, "give a `velocity` or a `displacement`"));
            }
            if let Some(v) = g.velocity {
                if !v.is_finite() {
                    return Err(c.err(
                        format!("{key}.velocity"),
                        format!("must be a finite number, got {v}"),
                    ));
                }
            }
            if let Some(u) = g.displacement {
                if !u.is_finite() {
                    return Err(c.err(
                        format!("{key}.displacement"),
                        format!("must be a finite number, got {u}"),
                    ));
                }
            }
            for n in first..=last {
                initial.push((n, g.displacement, g.velocity));
            }
        }

        let r = &f.run;
        let duration = c.positive("run.duration", r.duration)?;
        let interval = c.positive("run.output_interval", r.output_interval)?;
        if interval > duration {
            return Err(c.err(
                "run.output_interval",
                format!("must be at most run.duration ({duration}), got {interval}"),
            ));
        }
        if duration / interval > 1e9 {
            return Err(c.err(
                "run.output_interval",
                "more than 1e9 output times; use a longer interval",
            ));
        }

        let i = f.integrator.as_ref();
        let mut params = IntegrationParams::default();
        if let Some(i) = i {
            params.method = i.method.unwrap_or(Method::Verlet);
            if let Some(dt) = i.dt {
                params.dt = c.positive("integrator.dt", dt)?;
            }
            if let Some(x) = i.rtol {
                params.rtol = c.positive("integrator.rtol", x)?;
            }
            if let Some(x) = i.atol {
                params.atol = c.positive("integrator.atol", x)?;
            }
            if let Some(x) = i.skip_untouched {
                params.skip_untouched = x;
            }
            if let Some(x) = i.max_energy_error {
                params.max_energy_error = c.positive("integrator.max_energy_error", x)?;
            }
            if let Some(s) = i.sleep {
                c.non_negative("integrator.sleep.velocity", s.velocity)?;
                c.non_negative("integrator.sleep.force", s.force)?;
                if !params.method.uses_islands() {
                    return Err(c.err(
                        "integrator.sleep",
                        format!(
                            "the sleep rule needs a splitting method (verlet or blanes-moan4), not {}",
                            params.method.name()
                        ),
                    ));
                }
                params.sleep = Some(Sleep {
                    velocity: s.velocity,
                    force: s.force,
                });
            }
            if !params.method.is_adaptive() && (i.rtol.is_some() || i.atol.is_some()) {
                return Err(c.err(
                    "integrator.rtol",
                    format!(
                        "tolerances apply to adaptive methods only; {} takes a fixed dt",
                        params.method.name()
                    ),
                ));
            }
        }
        if let Some(key) = damped_key {
            if !params.method.uses_islands() {
                return Err(c.err(
                    key,
                    format!(
                        "damping needs a splitting method (verlet or blanes-moan4), not {}",
                        params.method.name()
                    ),
                ));
            }
        }
        if !params.method.is_adaptive() && interval / params.dt > 1e12 {
            return Err(c.err(
                "integrator.dt",
                format!(
                    "dt = {:e} needs more than 1e12 steps per output interval ({interval})",
                    params.dt
                ),
            ));
        }

        let mut regions = Vec::new();
        for (i, g) in f.regions.iter().enumerate() {
            let key = format!("regions[{i}]");
            if g.name.trim().is_empty() || g.name.contains(|ch: char| ch == ',' || ch.is_control())
            {
                return Err(c.err(
                    format!("{key}.name"),
                    "must be a non-empty name without commas",
                ));
            }
            if regions.iter().any(|r: &Region| r.name == g.name) {
                return Err(c.err(
                    format!("{key}.name"),
                    format!("region `{}` is defined twice", g.name),
                ));
            }
            grain_ok(format!("{key}.first"), g.first)?;
            grain_ok(format!("{key}.last"), g.last)?;
            if g.first > g.last {
                return Err(c.err(
                    format!("{key}.last"),
                    format!("last ({}) is before first ({})", g.last, g.first),
                ));
            }
            regions.push(Region {
                name: g.name.clone(),
                first: g.first,
                last: g.last,
            });
        }

        let mut output = OutputSpec {
            energies: true,
            ..Default::default()
        };
        if let Some(o) = &f.output {
            output.energies = o.energies.unwrap_or(true);
            if let Some(s) = &o.snapshots {
                if s.fields.is_empty() {
                    return Err(c.err("output.snapshots.fields", "name at least one field"));
                }
                let every = s.every.unwrap_or(1);
                if every == 0 {
                    return Err(c.err("output.snapshots.every", "must be at least 1"));
                }
                let first = grain_ok("output.snapshots.first".into(), s.first.unwrap_or(lo_num))?;
                let last = grain_ok("output.snapshots.last".into(), s.last.unwrap_or(hi_num))?;
                if first > last {
                    return Err(c.err(
                        "output.snapshots.last",
                        format!("last ({last}) is before first ({first})"),
                    ));
                }
                output.snapshots = Some(SnapshotSpec {
                    fields: s.fields.clone(),
                    every,
                    at: s.at.clone(),
                    first,
                    last,
                });
            }
            if let Some(p) = &o.pulses {
                let every = p.every.unwrap_or(1);
                if every == 0 {
                    return Err(c.err("output.pulses.every", "must be at least 1"));
                }
                let rule = PulseRule {
                    threshold: p.threshold.unwrap_or(PulseRule::default().threshold),
                    valley: p.valley.unwrap_or(PulseRule::default().valley),
                };
                if !(rule.threshold.is_finite() && rule.threshold > 0.0 && rule.threshold < 1.0) {
                    return Err(c.err(
                        "output.pulses.threshold",
                        format!("must be between 0 and 1, got {}", rule.threshold),
                    ));
                }
                if !(rule.valley.is_finite() && rule.valley > 0.0 && rule.valley <= 1.0) {
                    return Err(c.err(
                        "output.pulses.valley",
                        format!("must be in (0, 1], got {}", rule.valley),
                    ));
                }
                output.pulses = Some(PulseSpec {
                    every,
                    at: p.at.clone(),
                    rule,
                });
            }
            if let Some(p) = &o.tracks {
                let every = p.every.unwrap_or(1);
                if every == 0 {
                    return Err(c.err("output.tracks.every", "must be at least 1"));
                }
                let rule = PulseRule {
                    threshold: p.threshold.unwrap_or(PulseRule::default().threshold),
                    valley: p.valley.unwrap_or(PulseRule::default().valley),
                };
                if !(rule.threshold.is_finite() && rule.threshold > 0.0 && rule.threshold < 1.0) {
                    return Err(c.err(
                        "output.tracks.threshold",
                        format!("must be between 0 and 1, got {}", rule.threshold),
                    ));
                }
                if !(rule.valley.is_finite() && rule.valley > 0.0 && rule.valley <= 1.0) {
                    return Err(c.err(
                        "output.tracks.valley",
                        format!("must be in (0, 1], got {}", rule.valley),
                    ));
                }
                let max_jump = p.max_jump.unwrap_or(f64::INFINITY);
                if !(max_jump > 0.0) {
                    return Err(c.err(
                        "output.tracks.max_jump",
                        format!("must be positive, got {max_jump}"),
                    ));
                }
                if matches!(params.method, Method::Gear5 | Method::Multirate) {
                    return Err(c.err(
                        "output.tracks",
                        format!(
                            "the true peak velocity needs per-step velocities, which verlet, \
                             blanes-moan4 and dopri5 keep and {} does not",
                            params.method.name()
                        ),
                    ));
                }
                output.tracks = Some(TrackSpec {
                    every,
                    rule,
                    track: TrackRule { max_jump },
                });
            }
        }

        // The builder checks what only the whole chain can tell (precompression balance).
        builder.clone().build().map_err(|e| match e {
            ChainError::PrecompressionWithoutWalls => c.err(
                "chain.left",
                "precompression (delta0 > 0) needs walls at both ends to hold it",
            ),
            other => c.err("chain", other.to_string()),
        })?;

        // Multiple time stepping: the fast region by name, the ratio dividing the steps of an
        // output interval.
        let mut multirate = None;
        let mr = i.and_then(|i| i.multirate.as_ref());
        match (params.method, mr) {
            (Method::Multirate, None) => {
                return Err(c.err(
                    "integrator.multirate",
                    "method multirate needs `multirate = { ratio = .., fast = \"<region>\" }`",
                ))
            }
            (m, Some(_)) if m != Method::Multirate => {
                return Err(c.err(
                    "integrator.multirate",
                    format!("applies to method multirate only, not {}", m.name()),
                ))
            }
            (_, Some(m)) => {
                let steps = (interval / crate::run::fitted_dt(params.dt, interval)).round() as u64;
                if m.ratio == 0 || !steps.is_multiple_of(m.ratio) {
                    return Err(c.err(
                        "integrator.multirate.ratio",
                        format!(
                            "must divide the {steps} steps of dt per output interval, got {}",
                            m.ratio
                        ),
                    ));
                }
                let r = regions.iter().find(|r| r.name == m.fast).ok_or_else(|| {
                    c.err(
                        "integrator.multirate.fast",
                        format!("`{}` is not a region of this scene", m.fast),
                    )
                })?;
                let margin = m.margin.unwrap_or(0) as i64;
                multirate = Some((
                    m.ratio,
                    (r.first - margin).max(lo_num),
                    (r.last + margin).min(hi_num),
                ));
            }
            _ => {}
        }

        Ok(Scene {
            multirate,
            path: path.to_path_buf(),
            name: f.name.clone().unwrap_or_else(|| {
                path.file_stem()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_default()
            }),
            description: f.description.clone().unwrap_or_default(),
            params,
            duration,
            output_interval: interval,
            regions,
            output,
            builder,
            initial,
            grains,
            first_number: lo_num,
        })
    }

    /// Build the simulation this scene describes.
    pub fn simulation(&self) -> Result<Simulation, RunError> {
        let chain = self.builder.clone().build().map_err(RunError::Chain)?;
        let mut params = self.params;
        if let Some((ratio, first, last)) = self.multirate {
            let idx = |g: i64| {
                chain
                    .index_of(g)
                    .ok_or_else(|| RunError::Settings(format!("grain {g} is outside the chain")))
            };
            params.multirate = Some(crate::integrators::MultirateParams {
                ratio,
                first: idx(first)?,
                last: idx(last)?,
            });
        }
        let mut b = SimulationBuilder::new(chain.clone())
            .params(params)
            .schedule(self.duration, self.output_interval);
        for &(n, u, v) in &self.initial {
            let i = chain
                .index_of(n)
                .ok_or_else(|| RunError::Settings(format!("grain {n} is outside the chain")))?;
            if let Some(u) = u {
                b = b.displacement(i, u);
            }
            if let Some(v) = v {
                b = b.velocity(i, v);
            }
        }
        b.build()
    }

    /// Steps, grains and the size of the output files this scene will write.
    pub fn estimate(&self) -> Estimate {
        let outputs = self.outputs();
        let steps = (!self.params.method.is_adaptive()).then(|| {
            let dt = crate::run::fitted_dt(self.params.dt, self.output_interval);
            (self.output_interval / dt).round() as u64 * outputs
        });
        let rows = outputs + 1;
        let energies_bytes = if self.output.energies {
            // index, then time, kinetic, potential, total, momentum and two columns per region
            // (energy and momentum).
            rows * (INTEGER_BYTES + NUMBER_BYTES * (5 + 2 * self.regions.len() as u64))
        } else {
            0
        };
        let snapshots_bytes = self.output.snapshots.as_ref().map_or(0, |s| {
            let times = if s.at.is_empty() {
                outputs / s.every + 1
            } else {
                s.at.iter().filter(|&&k| k <= outputs).count() as u64
            };
            let grains = (s.last - s.first + 1).max(0) as u64;
            // index, time, grain, then the fields.
            let row = 2 * INTEGER_BYTES + NUMBER_BYTES * (1 + s.fields.len() as u64);
            times.saturating_mul(grains).saturating_mul(row)
        });
        Estimate {
            grains: self.grains,
            outputs,
            steps,
            energies_bytes,
            snapshots_bytes,
            pulses: self.output.pulses.is_some(),
            tracks: self.output.tracks.is_some(),
        }
    }

    /// Number of output times after t = 0 ([`crate::run::output_count`]).
    pub fn outputs(&self) -> u64 {
        crate::run::output_count(self.duration, self.output_interval)
    }
}

#[cfg(test)]
mod tests;
