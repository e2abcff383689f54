//! Scene files (TOML): everything a run needs, checked strictly before anything runs.
//!
//! Parsing is two-stage: serde reads the file into [`file::SceneFile`] (unknown keys are errors),
//! then [`Scene::from_file`] checks every value and builds the chain, naming the file and the key
//! of the first problem. Grain numbers in scene files and outputs are 1-based as in the paper
//! (a left striker is grain 0, a right striker N + 1).

mod check;
pub mod file;
pub mod outer;
mod parts;
pub(crate) mod restitution;
mod si;
pub(crate) use si::{contact, run as bead_run, Contact, Other};

pub use check::{MAX_GRAINS, MAX_OUTPUTS, NAME_MAX_BYTES};
use parts::Ctx;
pub use parts::{OutputSpec, PulseSpec, Region, SnapshotSpec, TrackSpec};

use crate::chain::Chain;
use crate::error::InputError;
use crate::integrators::{IntegrationParams, MultirateParams};
use crate::run::{Horizon, RunError, Simulation, SimulationBuilder};
use file::{EndFile, SceneFile};
use std::path::{Path, PathBuf};

/// What a scene will cost and write, estimated before it runs (`grainchain check`).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct OutputEstimate {
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

/// Bytes of one number as the outputs print it (`report::csv_number` of an f64, at most 24
/// characters, and a comma); integers (index, grain) are counted at 12.
const NUMBER_BYTES: u64 = 25;
const INTEGER_BYTES: u64 = 12;

// The memory model of a simulation: an upper bound of the peak resident memory of `grainchain
// run` (and `check`, which builds the chain only), from the scene file's sizes alone. Where the
// memory goes, per grain (measured with `/usr/bin/time -v`, maximum resident set, over the grid
// of BENCHMARKS.md, "Memory": every method, every output, an `[[initial]]` range over all
// grains, 1e3 to 1e6 grains):
//
// - building the chain, for every method: each grain's `(law, section)` (56 bytes), the interior
//   contacts' laws (48), masses (8), static forces (8), segment index (4) and the fused sweeps'
//   per-contact constants and run index (`chain::Forms`: 28), 152 bytes, all alive at once while
//   `chain::builder` lays the chain out; afterwards the chain keeps 56 (the forms' 28 added to
//   each method's measured run, 2026-11-28, and not yet measured over the grid);
// - the run: the state (`u`, `v`: 16) and the method's workspace: verlet and blanes-moan4 `a`,
//   `f` (16), multirate also its fast-region copies (16), gear5 five Nordsieck vectors, `a`, `f`
//   and its four start-up accelerations (88), dopri5 seven stages of `u` and `v`, the stage state
//   and forces (136). The splitting methods' run stays under their build, so their peak is the
//   build's;
// - `[[initial]]`: the scene's table of grains (40 bytes per grain given) and the simulation
//   builder's copy (40 per value given: a velocity and a displacement are two entries), alive
//   together;
// - outputs, during the run: a snapshot holds 8 bytes per field and grain of its range, pulses
//   16 per grain (the energy profile and its pulses), tracks 32 (that and the peak speeds),
//   regions 8;
// - contact damping and damped sections: the dissipated energy per grain and the damped step's
//   buffers ([`DAMPING_BYTES_PER_GRAIN`]);
// - gravity (`chain.gravity`): every contact has its own static overlap, so its own segment of
//   the force loop, laid out by a growing `Vec` (up to twice its length):
//   [`gravity_bytes_per_grain`]. Measured at 2e5 grains (verlet, no output): 68.4 MB peak
//   against 31.4 MB without gravity, 185 bytes per grain more.
//
// Each term bounds what was measured over 1e5 and 1e6 grains (BENCHMARKS.md, "Memory"), the
// terms are added although the build's and the run's peaks do not coincide, and the sum is
// multiplied by [`MEMORY_MARGIN`].
// (The build's 160 bytes per grain and each method's run are `MethodInfo::bytes_per_grain`.)

/// `[[initial]]`: bytes per grain listed in the scene, and per value (velocity, displacement)
/// given to it (the memory model above).
pub const INITIAL_BYTES_PER_GRAIN: u64 = 40;
/// Contact damping or a damped section, per grain.
pub const DAMPING_BYTES_PER_GRAIN: u64 = 40;
/// Gravity's segment per contact, per grain: twice the size of a segment (a growing `Vec`'s
/// capacity is at most twice its length).
fn gravity_bytes_per_grain() -> u64 {
    2 * std::mem::size_of::<crate::chain::Segment>() as u64
}
/// The process before any grain: the binary, the C library, the parsed scene, the threads'
/// stacks. Counted at 8 MB, above the peak measured at 1e3 grains (BENCHMARKS.md, "Memory"), for
/// a larger scene text and a test build.
pub const MEMORY_BASE_BYTES: u64 = 8_000_000;
/// The margin on the per-grain sum, 5/4 (as numerator, denominator): the spread of the
/// allocator's heap reuse between grid points (BENCHMARKS.md, "Memory"), and combinations of
/// outputs not measured one by one.
pub const MEMORY_MARGIN: (u64, u64) = (5, 4);

/// The memory a scene file asks for, from its sizes alone (nothing is built): an upper bound of
/// the peak resident memory of `run` (the memory model above it says where it goes).
#[derive(Clone, Debug, PartialEq)]
pub struct MemoryEstimate {
    /// Grains, a striker included.
    pub grains: u64,
    /// Bytes: [`MEMORY_BASE_BYTES`] plus `grains * per_grain`.
    pub bytes: u64,
    /// Bytes per grain of the chain (the method, `[[initial]]`, the outputs, damping, the
    /// margin), rounded up.
    pub per_grain: u64,
    /// The method counted (the scene's, else the default verlet).
    pub method: crate::integrators::Method,
    /// The key that sets it: the count of the largest section.
    pub key: String,
}

impl MemoryEstimate {
    /// The estimate of a parsed scene file as it runs: with its outer medium (`chain.outer`)
    /// applied to the counts of its first and last section (`outer-left` and `beyond-striker`,
    /// each with its damped layer), so that a memory guard judges the chain that runs (a
    /// 1e7-grain `outer-left` cut to 300 grains by the medium is small) and still names the
    /// file's own section keys; the counts as written when there is no medium or it does not
    /// apply. `grainchain check` and the Python `check()` both print this.
    pub fn of_run(f: &SceneFile) -> MemoryEstimate {
        match after_outer(f) {
            Some(cut) => MemoryEstimate::of_file(&cut),
            None => MemoryEstimate::of_file(f),
        }
    }

    /// The estimate of a parsed scene file (the counts as written, before any check).
    pub fn of_file(f: &SceneFile) -> MemoryEstimate {
        let grains = f
            .chain
            .sections
            .iter()
            .fold(0u64, |t, s| t.saturating_add(s.count))
            .saturating_add(u64::from(f.striker.is_some()))
            .saturating_add(u64::from(f.target.is_some()));
        let largest = f
            .chain
            .sections
            .iter()
            .enumerate()
            .max_by_key(|(_, s)| s.count)
            .map_or(0, |(i, _)| i);
        let method = f
            .integrator
            .as_ref()
            .and_then(|i| i.method)
            .unwrap_or(crate::integrators::Method::Verlet);
        // Grains of a printed range, clipped to the chain (the check refuses a range outside it).
        let span = |first: Option<i64>, last: Option<i64>| -> u64 {
            let first = first.unwrap_or(i64::MIN);
            let last = last.unwrap_or(i64::MAX);
            let n = (i128::from(last) - i128::from(first) + 1).max(0);
            u64::try_from(n).unwrap_or(u64::MAX).min(grains)
        };
        // Summed in grain-bytes over the chain (u128: no sum can wrap).
        let mut total = u128::from(method.information().bytes_per_grain) * u128::from(grains);
        for g in &f.initial {
            let listed = match g.grain {
                Some(_) => 1,
                None => span(g.first, g.last),
            };
            let values = u64::from(g.velocity.is_some()) + u64::from(g.displacement.is_some());
            total += u128::from(listed) * u128::from(INITIAL_BYTES_PER_GRAIN * (1 + values));
        }
        if let Some(o) = &f.output {
            if let Some(s) = &o.snapshots {
                total += u128::from(span(s.first, s.last)) * 8 * s.fields.len() as u128;
            }
            if o.pulses.is_some() {
                total += u128::from(grains) * 16;
            }
            if o.tracks.is_some() {
                total += u128::from(grains) * 32;
            }
        }
        if !f.regions.is_empty() {
            total += u128::from(grains) * 8;
        }
        let damped = f.chain.sections.iter().any(|s| {
            s.damping.is_some_and(|c| c != 0.0) || s.law.contact_damping.is_some()
        }) || [&f.chain.left, &f.chain.right]
            .into_iter()
            .flatten()
            .any(|e| matches!(e, EndFile::Wall(l) if l.contact_damping.is_some()))
            // An outer medium may bring damped sections.
            || f.chain.outer.is_some()
            // A restitution below 1 damps contacts (SI scenes).
            || f.chain.restitution.is_some()
            || f.chain.sections.iter().any(|s| s.law.restitution.is_some())
            || f.striker.as_ref().is_some_and(|s| s.restitution.is_some())
            || f.target.as_ref().is_some_and(|t| t.restitution.is_some());
        if damped {
            total += u128::from(grains) * u128::from(DAMPING_BYTES_PER_GRAIN);
        }
        if f.chain.gravity.is_some_and(|g| g != 0.0) {
            total += u128::from(grains) * u128::from(gravity_bytes_per_grain());
        }
        let (num, den) = MEMORY_MARGIN;
        let total = (total * u128::from(num)).div_ceil(u128::from(den));
        let per_grain = if grains == 0 {
            0
        } else {
            u64::try_from(total.div_ceil(u128::from(grains))).unwrap_or(u64::MAX)
        };
        MemoryEstimate {
            grains,
            bytes: u64::try_from(total)
                .unwrap_or(u64::MAX)
                .saturating_add(MEMORY_BASE_BYTES),
            per_grain,
            method,
            key: format!("chain.sections[{largest}].count"),
        }
    }
}

impl OutputEstimate {
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

/// The builder of a scene's simulation on `chain`: its settings (the multirate fast region
/// filled in), schedule (duration, output interval) and initial conditions (internal indices).
fn simulation_builder(
    chain: Chain,
    mut params: IntegrationParams,
    multirate: Option<MultirateParams>,
    (duration, interval): (f64, f64),
    initial: &[(usize, Option<f64>, Option<f64>)],
    horizon: Option<Horizon>,
) -> SimulationBuilder {
    // The scene's fast region, unless the caller's settings bring their own (a study of
    // multirate ratios, work-precision's multirate points).
    if params.multirate.is_none() {
        params.multirate = multirate;
    }
    // A scene's settings were checked with its chain and kept valid by its edits.
    let mut b = SimulationBuilder::new(chain)
        .params(params)
        .schedule(duration, interval)
        .horizon(horizon)
        .checked();
    for &(i, u, v) in initial {
        if let Some(u) = u {
            b = b.displacement(i, u);
        }
        if let Some(v) = v {
            b = b.velocity(i, v);
        }
    }
    b
}

/// A TOML input file parsed once: its typed form and the same document as TOML values, from
/// which an output folder's digest is taken. Nothing reads or parses the text again (issue 39:
/// `run` used to parse its scene five to eight times, and a scene given through a pipe was
/// refused because a second read found it empty).
#[derive(Clone, Debug)]
pub struct Parsed<T> {
    /// The typed file (serde; unknown keys refused in every table).
    pub typed: T,
    /// The document as TOML values (integers checked to fit 64 bits).
    pub value: toml::Value,
}

/// Parse a TOML input file's text once into its typed form and its values (nothing checked but
/// the form): errors name the key and line, and a file of the other `kind` is said to be one.
///
/// TOML integers are 64-bit signed (the TOML specification): a number above
/// 9223372036854775807 is refused here, in every input file alike.
pub fn parse_toml<T: serde::de::DeserializeOwned>(
    text: &str,
    path: &Path,
    kind: file::FileKind,
) -> Result<Parsed<T>, InputError> {
    use serde::Deserialize;
    use toml::de::{DeTable, Deserializer};
    let error = |message: String| InputError::Parse {
        file: path.to_path_buf(),
        message,
    };
    // The one parse of the text; the typed form and the values are both read from its tree.
    let root = DeTable::parse(text).map_err(|e| error(file::describe_toml_error(&e, text)))?;
    let typed = T::deserialize(Deserializer::from(root.clone())).map_err(|e| {
        let keys: Vec<&str> = root
            .get_ref()
            .keys()
            .map(|k| k.get_ref().as_ref())
            .collect();
        error(file::wrong_kind(&keys, kind).unwrap_or_else(|| file::describe_toml_error(&e, text)))
    })?;
    let value = toml::Value::deserialize(Deserializer::from(root)).map_err(|e| {
        error(format!(
            "{} (TOML integers go up to 9223372036854775807)",
            file::describe_toml_error(&e, text)
        ))
    })?;
    Ok(Parsed { typed, value })
}

/// Parse a scene file's text ([`parse_toml`]; nothing checked but its form): errors name the
/// key and line.
pub fn parse_file(text: &str, path: &Path) -> Result<SceneFile, InputError> {
    parse_toml(text, path, file::FileKind::Scene).map(|p| p.typed)
}

/// A checked scene: built only by the check ([`Scene::from_file`]) and kept valid by it, since
/// every edit ([`Scene::set_params`], [`Scene::set_schedule`], [`Scene::set_horizon`]) checks the
/// run's settings again (`run::check_settings`, the rules [`SimulationBuilder::build`] applies)
/// and recomputes what depends on them. Its simulation is therefore built without a second
/// check.
#[derive(Clone, Debug)]
pub struct Scene {
    path: PathBuf,
    name: String,
    description: String,
    params: IntegrationParams,
    duration: f64,
    output_interval: f64,
    horizon: Option<Horizon>,
    horizon_bound: Option<f64>,
    warnings: Vec<String>,
    regions: Vec<Region>,
    output: OutputSpec,
    /// The chain, built once by the check.
    chain: Chain,
    /// `[[initial]]` by internal index.
    initial: Vec<(usize, Option<f64>, Option<f64>)>,
    /// Multirate: ratio and the fast region (internal indices).
    multirate: Option<MultirateParams>,
    grains: usize,
    si: bool,
    /// Printed number of internal grain 0 (0 with a left striker, else 1).
    first_number: i64,
}

impl Scene {
    /// The scene file (as given), named in error messages.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The scene's name: key `name`, or the file name without its extension.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Key `description`, or empty.
    pub fn description(&self) -> &str {
        &self.description
    }

    /// The integration settings (`[integrator]`, or the last [`Scene::set_params`]); `dt` is the
    /// step asked for ([`Scene::step`] is the one taken). The multirate grains are filled in by
    /// [`Scene::simulation`] / [`Scene::into_simulation`].
    pub fn params(&self) -> &IntegrationParams {
        &self.params
    }

    /// The step a fixed-step method takes: `dt` shortened so that a whole number of steps fits
    /// each output interval ([`IntegrationParams::fitted_step`]); the first step of the adaptive
    /// method.
    pub fn step(&self) -> f64 {
        if self.params.method.is_adaptive() {
            self.params.dt
        } else {
            self.params.fitted_step(self.output_interval)
        }
    }

    /// Simulated time, in the scene's time units (`run.duration`).
    pub fn duration(&self) -> f64 {
        self.duration
    }

    /// Time between output times (`run.output_interval`).
    pub fn output_interval(&self) -> f64 {
        self.output_interval
    }

    /// The causal horizon (`run.horizon`), if any.
    pub fn horizon(&self) -> Option<&Horizon> {
        self.horizon.as_ref()
    }

    /// The horizon's bound ([`Horizon::speed_bound`]) for the ranges `grainchain run` records,
    /// computed by the check as the run computes it; `None` without a horizon or with nothing
    /// recorded that it protects. A `run.horizon.speed` below it is an error unless
    /// `run.horizon.unsafe`.
    pub fn horizon_bound(&self) -> Option<f64> {
        self.horizon_bound
    }

    /// What the check allowed only because the scene says so explicitly and that may make the
    /// recorded numbers wrong (a horizon speed below its bound with `unsafe = true`), one
    /// sentence each; `grainchain check` and `run` print them, the run records them in
    /// `summary.json`.
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// The named grain ranges (`[[regions]]`), in file order.
    pub fn regions(&self) -> &[Region] {
        &self.regions
    }

    /// What to record (`[output]`).
    pub fn output(&self) -> &OutputSpec {
        &self.output
    }

    /// Number of grains including a striker.
    pub fn grains(&self) -> usize {
        self.grains
    }

    /// Whether the scene is in SI units (its sections are given by `material` and `diameter`):
    /// then every time is in seconds, length in metres, mass in kilograms, force in newtons and
    /// energy in joules; else the program's units.
    pub fn is_si(&self) -> bool {
        self.si
    }

    /// Integrate with `params` instead (a study's or a benchmark's method and step), checked
    /// against the scene as the file's `[integrator]` is; on an error the scene is unchanged.
    pub fn set_params(&mut self, params: IntegrationParams) -> Result<(), InputError> {
        let mut next = self.clone_settings();
        next.0 = params;
        self.settle(next)
    }

    /// Run for `duration`, with outputs every `interval`, checked as `[run]` is; on an error
    /// the scene is unchanged.
    pub fn set_schedule(&mut self, duration: f64, interval: f64) -> Result<(), InputError> {
        let mut next = self.clone_settings();
        (next.1, next.2) = (duration, interval);
        self.settle(next)
    }

    /// Run under `horizon` (or none), checked as `run.horizon` is (its speed against the
    /// bound, unless `unsafe_speed`); on an error the scene is unchanged.
    pub fn set_horizon(&mut self, horizon: Option<Horizon>) -> Result<(), InputError> {
        let mut next = self.clone_settings();
        next.3 = horizon;
        self.settle(next)
    }

    /// The settings an edit changes: parameters, duration, interval, horizon.
    fn clone_settings(&self) -> (IntegrationParams, f64, f64, Option<Horizon>) {
        (
            self.params,
            self.duration,
            self.output_interval,
            self.horizon,
        )
    }

    /// Check edited settings against the chain (`run::check_settings`, under their scene keys)
    /// and recompute the horizon's bound and warning; the scene takes them only if they pass.
    fn settle(
        &mut self,
        (params, duration, interval, horizon): (IntegrationParams, f64, f64, Option<Horizon>),
    ) -> Result<(), InputError> {
        let c = Ctx { file: &self.path };
        crate::run::check_settings(&self.chain, &params, duration, interval, horizon.as_ref())
            .map_err(|e| c.params(e))?;
        let first = self.first_number;
        let outputs = crate::run::output_count(duration, interval);
        let envelope = check::protected_envelope(
            self.chain.len(),
            &self.regions,
            &self.output,
            outputs,
            |g| (g - first) as usize,
        );
        let run_params = IntegrationParams {
            multirate: params.multirate.or(self.multirate),
            ..params
        };
        let (bound, warning) = check::horizon_bound(
            &c,
            horizon,
            &self.chain,
            &run_params,
            &self.initial,
            envelope,
        )?;
        self.params = params;
        (self.duration, self.output_interval) = (duration, interval);
        self.horizon = horizon;
        self.horizon_bound = bound;
        self.warnings = warning.into_iter().collect();
        Ok(())
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
    pub fn region_grains(&self, name: &str) -> Result<std::ops::RangeInclusive<usize>, InputError> {
        let r = self.region(name).ok_or_else(|| InputError::Invalid {
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
    pub fn load(path: impl AsRef<Path>) -> Result<Scene, InputError> {
        let path = path.as_ref();
        Scene::parse(&file::read_text(path)?, path)
    }

    /// Check a scene given as text (`path` names it in error messages).
    pub fn parse(text: &str, path: &Path) -> Result<Scene, InputError> {
        Scene::from_file(parse_file(text, path)?, path)
    }

    /// Check the values of a parsed scene, table by table (`check`), in the order errors are
    /// reported.
    pub fn from_file(mut f: SceneFile, path: &Path) -> Result<Scene, InputError> {
        let c = Ctx { file: path };
        si::units(&c, &f)?;
        let si = si::is_si(&f);
        let mut moved = 0;
        if f.chain.outer.is_some() && f.chain.gravity.is_some_and(|g| g != 0.0) {
            return Err(c.err(
                "chain.gravity",
                "not with `chain.outer`: the outer media are edits of a chain at rest without \
                 gravity (their walls and dashpots hold no weight)",
            ));
        }
        if let Some(medium) = f.chain.outer.take() {
            moved = outer::apply(&mut f, medium).map_err(|m| c.err("chain.outer", m))?;
            check::outer_method(&c, &f, medium)?;
        }
        check::name(&c, f.name.as_deref())?;
        let built = check::chain(&c, &f)?;
        let spheres = built.spheres.as_deref();
        let (builder, striker_end, striker_damped) =
            check::striker(&c, &f, built.builder, spheres)?;
        let (builder, target_damped) = check::target(&c, &f, builder, spheres)?;
        let total = built.total + usize::from(f.target.is_some());
        let damped_key = built.damped_key.or(striker_damped).or(target_damped);
        let grains = total + usize::from(striker_end.is_some());
        // The limit holds for the whole chain, target and striker included: the sections alone
        // at the limit plus a striker passed this check and the memory estimate's, which
        // trusts it, and the run then allocated 16 GB (issue 38).
        if grains > check::MAX_GRAINS {
            let key = if striker_end.is_some() {
                "striker"
            } else {
                "target"
            };
            return Err(c.err(
                key,
                format!(
                    "the chain may have at most {} grains, sections, target and striker \
                     together; this one has {grains}",
                    check::MAX_GRAINS
                ),
            ));
        }
        let num = check::Numbers::new(total, striker_end, moved);
        let initial = check::initial(&c, &f, num)?;
        let (duration, interval) = check::run_times(&c, &f.run)?;
        let params = check::integrator(&c, &f, damped_key, interval)?;
        let horizon = check::horizon(&c, &f.run, &params)?;
        check::gravity(&c, &f, &params, horizon.as_ref())?;
        let regions = check::regions(&c, &f, num)?;
        let outputs = crate::run::output_count(duration, interval);
        let output = check::output(&c, &f, num, &params, outputs)?;
        let chain = check::whole_chain(&c, &f, builder)?;
        let multirate = check::multirate(&c, &f, &params, interval, &regions, num, &chain)?;
        // Checked inside the chain above.
        let initial: Vec<_> = initial
            .into_iter()
            .map(|(n, u, v)| ((n - num.lo) as usize, u, v))
            .collect();
        let envelope = check::protected_envelope(chain.len(), &regions, &output, outputs, |g| {
            (g - num.lo) as usize
        });
        let run_params = IntegrationParams {
            multirate,
            ..params
        };
        let (horizon_bound, warning) =
            check::horizon_bound(&c, horizon, &chain, &run_params, &initial, envelope)?;
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
            horizon,
            regions,
            output,
            horizon_bound,
            warnings: warning.into_iter().collect(),
            initial,
            chain,
            grains,
            si,
            first_number: num.lo,
        })
    }

    /// The contact whose force is the force on what the chain protects (index `k` joins grains
    /// `k - 1` and `k`; `0` is a left wall's, `n` a right wall's, as
    /// [`Chain::contact_law`]): the contact into the section named `target` (the `[target]`
    /// body) if there is one, else the right wall's contact, else `None` (a free right end).
    pub fn protected_contact(&self) -> Option<usize> {
        protected_contact(&self.chain)
    }

    /// The multirate fast region (internal indices, inclusive, the margin included and clamped
    /// to the chain's ends), if the scene runs multirate.
    pub fn multirate_grains(&self) -> Option<std::ops::RangeInclusive<usize>> {
        self.multirate.map(|m| m.first..=m.last)
    }

    /// The chain this scene describes (built once, when the scene was checked).
    pub fn chain(&self) -> &Chain {
        &self.chain
    }

    /// The simulation this scene describes, on a copy of its chain; [`Scene::into_simulation`]
    /// hands over the chain itself.
    pub fn simulation(&self) -> Result<Simulation, RunError> {
        let s = self;
        simulation_builder(
            s.chain.clone(),
            s.params,
            s.multirate,
            s.schedule(),
            &s.initial,
            s.horizon,
        )
        .build()
    }

    /// The simulation this scene describes, consuming the scene (its chain is not copied).
    pub fn into_simulation(self) -> Result<Simulation, RunError> {
        let schedule = self.schedule();
        let Scene {
            chain,
            params,
            multirate,
            initial,
            horizon,
            ..
        } = self;
        simulation_builder(chain, params, multirate, schedule, &initial, horizon).build()
    }

    /// Duration and output interval.
    fn schedule(&self) -> (f64, f64) {
        (self.duration, self.output_interval)
    }

    /// Steps, grains and the size of the output files this scene will write.
    pub fn estimate(&self) -> OutputEstimate {
        let outputs = self.outputs();
        let steps = (!self.params.method.is_adaptive())
            .then(|| self.params.steps_per_output(self.output_interval) * outputs);
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
        OutputEstimate {
            grains: self.grains,
            outputs,
            steps,
            energies_bytes,
            snapshots_bytes,
            pulses: self.output.pulses.is_some(),
            tracks: self.output.tracks.is_some(),
        }
    }

    /// Number of output times after t = 0 (`output_count`).
    pub fn outputs(&self) -> u64 {
        crate::run::output_count(self.duration, self.output_interval)
    }
}

/// [`Scene::protected_contact`] of a chain.
fn protected_contact(chain: &Chain) -> Option<usize> {
    match chain.section(check::TARGET) {
        // The target's first grain (its only one in a scene) is not grain 0: a section is
        // joined to the grain on its left by contact `first`.
        Some(t) if t.first > 0 => Some(t.first),
        _ => chain.contact_law(chain.len()).map(|_| chain.len()),
    }
}

#[cfg(test)]
mod tests;

/// A scene file with its outer medium applied to the counts of its first and last section and
/// the medium taken out ([`MemoryEstimate::of_run`]); `None` when there is no medium or it does
/// not apply.
fn after_outer(f: &SceneFile) -> Option<SceneFile> {
    let medium = f.chain.outer?;
    let mut applied = f.clone();
    applied.chain.outer = None;
    outer::apply(&mut applied, medium).ok()?;
    let count = |names: &[&str]| -> Option<u64> {
        let n: u64 = applied
            .chain
            .sections
            .iter()
            .filter(|s| s.name.as_deref().is_some_and(|x| names.contains(&x)))
            .map(|s| s.count)
            .sum();
        // As a TOML integer (the text this replaced wrote it back into the file).
        i64::try_from(n).ok().map(|_| n)
    };
    let (left, right) = (
        count(&["outer-left", "layer-left"])?,
        count(&["beyond-striker", "layer-right"])?,
    );
    let mut cut = f.clone();
    cut.chain.outer = None;
    let last = cut.chain.sections.len().checked_sub(1)?;
    cut.chain.sections[0].count = left;
    cut.chain.sections[last].count = right;
    Some(cut)
}
