//! The on-disk form of a scene: serde structs that reject unknown keys.
//!
//! ```toml
//! name = "standard-container"
//! description = "Hong 2005, Fig. 3"
//!
//! [chain]
//! interface = "min-exponent"       # min-exponent | max-exponent | left | right
//! left = { kind = "free" }         # or { kind = "wall", p = 1.5, eta = 5657.0 }
//!
//! [[chain.sections]]
//! name = "outer"                   # optional
//! count = 120
//! mass = 100.0
//! p = 1.5
//! eta = 5657.0
//! delta0 = 0.0                     # optional precompression overlap (needs walls)
//! tension = false                  # optional two-sided linear spring (p = 1 only)
//! damping = 0.0                    # optional viscous damping rate (absorbing layer; verlet
//!                                  # and blanes-moan4 only)
//!
//! [striker]
//! end = "right"
//! mass = 100.0
//! speed = 10.0                     # towards the chain
//!
//! [[initial]]                      # optional per-grain initial conditions
//! grain = 5                        # or first = 5, last = 9
//! velocity = 1.0
//! displacement = 0.0
//!
//! [integrator]
//! method = "verlet"                # verlet | blanes-moan4 | gear5 | dopri5
//! dt = 1e-4                        # fixed step (initial step of dopri5)
//! rtol = 1e-8                      # dopri5 only
//! atol = 1e-10                     # dopri5 only
//! skip_untouched = true
//! max_energy_error = 1e-2
//! sleep = { velocity = 1e-9, force = 1e-9 }   # optional, off by default: grains slower than
//!                                  # `velocity` with a net force below `force` are put to rest
//!                                  # (approximate; verlet and blanes-moan4 only)
//!
//! [run]
//! duration = 35.0
//! output_interval = 0.125
//!
//! [[regions]]
//! name = "container"
//! first = 121
//! last = 300
//!
//! [output]
//! energies = true
//! snapshots = { fields = ["velocity"], every = 1, at = [280], first = 1, last = 420 }
//!                                  # fields: velocity, displacement, force, overlap, energy, mass
//! pulses = { every = 1, threshold = 1e-4, valley = 0.25 }
//! tracks = { every = 1, threshold = 1e-4, valley = 0.25, max_jump = 50.0 }
//!                                  # pulses followed from one detection (every `every`-th
//!                                  # output) to the next, with speed and true peak velocity
//!                                  # (tracks.csv); max_jump: largest move in grains between
//!                                  # detections (default: no limit); verlet, blanes-moan4 and
//!                                  # dopri5 only
//! ```
//!
//! An **SI scene** gives its sections by `material` and `diameter` instead of `mass`, `p` and
//! `eta` (a wall by `material`, the striker by `material`, `diameter` and its `speed` in m/s; an
//! optional `[target]` at the right end, an optional `restitution`): it takes and gives seconds,
//! metres, kilograms, newtons and joules (`integrator.dt`, required there, `run.duration` and
//! `run.output_interval` in seconds). A scene is all program units or all SI (`scene::si`).
//!
//! ```toml
//! [chain]
//! right = { kind = "wall", material = "steel" }
//! restitution = 0.95               # optional, every contact; default elastic
//!
//! [[chain.sections]]
//! count = 20
//! material = "steel"               # or { E = 200e9, nu = 0.29, rho = 7800 }
//! diameter = 6e-3                  # metres
//!
//! [striker]
//! end = "left"
//! material = "steel"
//! diameter = 6e-3
//! speed = 1.0                      # m/s
//!
//! # [target]                       # instead of the right wall: the protected body
//! # mass = 0.5                     # kg (or material + diameter, a sphere)
//! # material = "steel"             # with mass: a flat face of steel
//! # spring = 1e6                   # N/m to the ground; default free
//!
//! [integrator]
//! dt = 1e-8                        # seconds; required in an SI scene
//! ```

use crate::chain::{InterfaceRule, StrikerEnd};
use crate::error::InputError;
use crate::integrators::Method;
use crate::observables::Field;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The rest of an internally tagged table whose variant takes no keys: serde would skip
/// whatever else the table holds; this refuses it as an unknown field, naming it (the scene
/// error then names its table and key). `what` says which table it is.
fn only_the_tag<'de, D: serde::Deserializer<'de>>(
    d: D,
    what: &'static str,
) -> Result<(), D::Error> {
    struct NoKeys(&'static str);
    impl<'de> serde::de::Visitor<'de> for NoKeys {
        type Value = ();
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            write!(f, "{} with no other key", self.0)
        }
        fn visit_unit<E: serde::de::Error>(self) -> Result<(), E> {
            Ok(())
        }
        fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<(), A::Error> {
            match map.next_key::<String>()? {
                None => Ok(()),
                Some(key) => Err(serde::de::Error::custom(format_args!(
                    "unknown field `{key}`: {} has no other key",
                    self.0
                ))),
            }
        }
    }
    d.deserialize_any(NoKeys(what))
}

/// `{ kind = "free" }` and nothing else ([`EndFile::Free`]).
fn free_end<'de, D: serde::Deserializer<'de>>(d: D) -> Result<(), D::Error> {
    only_the_tag(d, "a free end (`kind = \"free\"`)")
}

/// `{ medium = "long" }` and nothing else ([`super::outer::OuterMedium::Long`]).
pub(crate) fn long_medium<'de, D: serde::Deserializer<'de>>(d: D) -> Result<(), D::Error> {
    only_the_tag(d, "the medium `long`")
}

/// What surrounds a container beyond its outer chains: the medium the leaked waves run into,
/// and which presses back on the container (`[chain] outer = { medium = .. }` of a scene,
/// `outer` of a sweep file's container; [`super::outer::apply`]). `distance` counts the grains of
/// Hertz outer chain between the container and the medium on each side (on the right:
/// `outer-right`, the striker and `beyond-striker`). Its edit of the scene is `scene::outer`'s;
/// the type is here with the rest of the schema, so the schema depends on no edit.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(tag = "medium", rename_all = "kebab-case", deny_unknown_fields)]
pub enum OuterMedium {
    /// `long`: the scene's long outer chains, from which nothing comes back (the default). No
    /// other key (serde would skip one in a unit variant of a tagged enum).
    #[serde(deserialize_with = "long_medium")]
    Long,
    /// `free-ends`: the outer chains end after `distance` grains, both ends free: the leaked
    /// waves come back as rarefactions.
    FreeEnds {
        /// Outer grains on each side.
        distance: u64,
    },
    /// `ground-damped`: after `distance` grains, `layer` grains each damped against the ground,
    /// `dv/dt = .. - rate v` (a section's `damping`), then a free end.
    GroundDamped {
        /// Outer grains on each side before the layer.
        distance: u64,
        /// Grains of the layer on each side.
        layer: u64,
        /// Damping rate of each layer grain, per time unit.
        rate: f64,
    },
    /// `dashpot`: after `distance` grains, `layer` grains whose contacts have a viscous dashpot
    /// `c d(delta)/dt` in parallel (contact damping, `viscous`), then a free end.
    Dashpot {
        /// Outer grains on each side before the layer.
        distance: u64,
        /// Grains of the layer on each side.
        layer: u64,
        /// The dashpot's coefficient (force per unit of closing speed).
        c: f64,
    },
}

/// A whole scene file, as read (checked into a [`crate::scene::Scene`] by
/// [`crate::scene::Scene::from_file`]).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// `name`: the scene's name (in `summary.json`; `grainchain run` writes to `out/<name>` by
    /// default, so a plain folder name of at most 200 bytes); default: the file name without its
    /// extension.
    pub name: Option<String>,
    /// `description`: one line of free text; default empty.
    pub description: Option<String>,
    /// `[chain]`: sections, ends and the interface rule (required).
    pub chain: ChainFile,
    /// `[striker]`: an extra grain hitting a free end; default none.
    pub striker: Option<StrikerFile>,
    /// `[target]`: the protected body at the right end; default none.
    pub target: Option<TargetFile>,
    /// `[[initial]]`: initial displacements and velocities of chosen grains; default: every grain
    /// at rest.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub initial: Vec<InitialFile>,
    /// `[integrator]`: method and step; default: verlet with the defaults of
    /// [`crate::integrators::IntegrationParams`].
    pub integrator: Option<IntegratorFile>,
    /// `[run]`: duration and output interval (required).
    pub run: RunFile,
    /// `[[regions]]`: named grain ranges whose energy and momentum are recorded; default none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub regions: Vec<RegionFile>,
    /// `[output]`: what to record; default: energies only.
    pub output: Option<OutputFile>,
    /// `[design]`: what `grainchain design` found for this column under this load (its
    /// `best.toml` writes it; `check` and `run` do not read it); default none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub design: Option<DesignRecordFile>,
}

/// The `[design]` table of a `best.toml`: the column's numbers as `grainchain design` reported
/// them (the run at twice the search's steps per contact time, its error the difference from
/// the run at the search's), for the reader; nothing reads them back.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(deny_unknown_fields)]
pub struct DesignRecordFile {
    /// `accuracy`: the design file's `[search] accuracy`, the relative error asked for.
    pub accuracy: f64,
    /// `steps_per_contact`: the reported run's steps per contact time (the scene's
    /// `integrator.dt` is its step).
    pub steps_per_contact: f64,
    /// `peak_force`: the peak force on the protected face, N (a lower bound when
    /// `peak_bound`).
    pub peak_force: f64,
    /// `peak_force_error`: its error estimate, N.
    pub peak_force_error: f64,
    /// `peak_bound`: whether the run reached its time cap before the peak was proven, so the
    /// peak is at least `peak_force` (the largest force up to the cap less its error).
    pub peak_bound: bool,
    /// `impulse`: the impulse on the face up to the end of the run, N s.
    pub impulse: f64,
    /// `impulse_error`: its error estimate, N s; left out when the impulse is not final (the
    /// run stopped at the peak or at its time cap).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub impulse_error: Option<f64>,
    /// `duration`: the time at or above the objective's fraction of the peak, s.
    pub duration: f64,
    /// `duration_error`: its error estimate, s; left out when the duration is not final.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub duration_error: Option<f64>,
}

/// The `[chain]` table.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(deny_unknown_fields)]
pub struct ChainFile {
    /// `interface`: which law a contact between sections of different laws uses
    /// (`min-exponent`, `max-exponent`, `left`, `right`); default `min-exponent`.
    pub interface: Option<InterfaceRule>,
    /// `left`: the left end; default `{ kind = "free" }`.
    pub left: Option<EndFile>,
    /// `right`: the right end; default `{ kind = "free" }`.
    pub right: Option<EndFile>,
    /// `[[chain.sections]]`: the sections, left to right (at least one).
    #[serde(default)]
    pub sections: Vec<SectionFile>,
    /// `outer = { medium = "free-ends", distance = 300 }`: what lies beyond a container scene's
    /// outer chains ([`OuterMedium`]: `long`, `free-ends`,
    /// `ground-damped`, `dashpot`); default: the sections as written.
    pub outer: Option<OuterMedium>,
    /// `restitution`: SI scenes: the coefficient of restitution (0.05 to 1) of every contact
    /// that does not give its own (sections, walls, striker, target); default elastic.
    pub restitution: Option<f64>,
    /// `gravity`: a constant acceleration on every grain, in the scene's units (length over
    /// time squared; m/s^2 in an SI scene), positive towards the right end; default 0 (none).
    /// With a wall at the end it points to (the floor) and the other end free, the chain starts
    /// at rest in its static equilibrium (each contact holding the weight of the grains above
    /// it); with that end free it falls. Needs verlet or blanes-moan4; refused with `delta0`,
    /// walls at both ends, `chain.outer`, `integrator.sleep` and `run.horizon`.
    pub gravity: Option<f64>,
}

/// One `[[chain.sections]]` entry: a run of identical grains.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(deny_unknown_fields)]
pub struct SectionFile {
    /// `name`: unique among the sections; default `section K` (K its 1-based position). Lookups
    /// by name ([`crate::Chain::section`], [`crate::Chain::grains_of`]) use it.
    pub name: Option<String>,
    /// `count`: number of grains (at least 1; at most 1e8 in the whole chain).
    pub count: u64,
    /// `mass`: mass of each grain (> 0), in mass units; required in a program-unit scene,
    /// refused in an SI scene (there the mass is `material`'s density times the sphere's
    /// volume).
    pub mass: Option<f64>,
    /// `diameter`: the grains' diameter in metres (1e-6 to 1), with `material` (an SI scene);
    /// required there, refused without it.
    pub diameter: Option<f64>,
    /// Viscous damping rate of every grain of the section (`dv/dt = ... - damping * v`, per
    /// time unit; default 0): an absorbing layer. Needs a splitting method.
    pub damping: Option<f64>,
    /// `p`, `eta`, `delta0`, `tension`: the law of the contacts inside the section (flattened
    /// into the section's table).
    #[serde(flatten)]
    pub law: LawFile,
}

/// The keys of a contact law, shared by sections and walls. Unknown keys are refused in a
/// wall's table by `deny_unknown_fields` here, and in a section's table by [`SectionFile`]'s
/// (flattened, this struct sees only its own keys there).
#[derive(Debug, Clone, Deserialize, Serialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(deny_unknown_fields)]
pub struct LawFile {
    /// `p`: exponent of F = eta delta^p (>= 1; 1 linear, 1.5 Hertz); required in a
    /// program-unit scene, refused with `material`.
    pub p: Option<f64>,
    /// `eta`: stiffness (> 0); required in a program-unit scene, refused with `material`.
    pub eta: Option<f64>,
    /// `delta0`: static precompression overlap (>= 0, needs walls at both ends); default 0.
    pub delta0: Option<f64>,
    /// `tension`: a two-sided linear spring that also pulls (p = 1 only); default false.
    pub tension: Option<bool>,
    /// `contact_damping = { model, c }`: a dashpot in parallel with the contact, force
    /// `c delta^q d(delta)/dt` with `model` `viscous` (q = 0), `kuwabara-kono` (q = 1/2) or
    /// `scale-respecting` (q = (p - 1)/2); default none. An interface contact takes the damping
    /// of the law the interface rule picks. Needs verlet or blanes-moan4. With `tension = true`
    /// only the forms with q = 0 (`viscous`, `scale-respecting`): `kuwabara-kono`'s delta^(1/2)
    /// has no value at a two-sided contact's negative overlaps.
    pub contact_damping: Option<ContactDampingFile>,
    /// `material`: makes the scene an SI scene. A section's grains are spheres of this
    /// material (with `diameter`): mass `rho pi d^3 / 6`, contacts Hertz's law with the pair's
    /// constant (`units::hertz_eta`), the contact with the section on the left too; a wall is a
    /// flat of this material (`units::hertz_eta_flat`). A key of the material table (`steel`,
    /// `stainless-steel`, `brass`, `aluminium`, `ptfe`, `glass`, `tungsten-carbide`) or
    /// `{ E = .., nu = .., rho = .., name = .. }` (E from 1e3 to 1e13 Pa, nu in (-1, 0.5], rho
    /// from 1 to 1e5 kg/m^3; `name` optional, what outputs call it, default its constants). Not
    /// with `p`, `eta`, `delta0`, `tension` or `contact_damping`.
    pub material: Option<MaterialFile>,
    /// `restitution`: the coefficient of restitution (0.05 to 1, 1 elastic) of this section's
    /// contacts (its contact with the section on its left included) or of this wall's; SI
    /// scenes only; default `chain.restitution`, else elastic. A damped contact needs verlet or
    /// blanes-moan4.
    pub restitution: Option<f64>,
}

/// `material = "steel"` or `material = { E = 200e9, nu = 0.29, rho = 7800 }`: a key of
/// `units::MATERIALS`, or a material's own constants.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[cfg_attr(feature = "schema", schemars(untagged))]
pub enum MaterialFile {
    /// A key of the material table (`units::MATERIALS`).
    Named(String),
    /// A material's own constants.
    Custom(CustomMaterialFile),
}

/// `{ E = .., nu = .., rho = .., name = .. }`: Young's modulus (Pa), Poisson's ratio, density
/// (kg/m^3) and an optional name.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(deny_unknown_fields)]
pub struct CustomMaterialFile {
    /// `E`: Young's modulus, Pa.
    #[serde(rename = "E")]
    pub young: f64,
    /// `nu`: Poisson's ratio.
    pub nu: f64,
    /// `rho`: density, kg/m^3.
    pub rho: f64,
    /// `name`: what every output calls it (1 to 40 characters without quotes or `|`, not a key
    /// of the table); default its constants, `E=2e11,nu=0.3,rho=7900`.
    pub name: Option<String>,
}

impl Serialize for MaterialFile {
    /// As written: the name as a string, the constants as a table.
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            MaterialFile::Named(name) => s.serialize_str(name),
            MaterialFile::Custom(x) => x.serialize(s),
        }
    }
}

impl<'de> Deserialize<'de> for MaterialFile {
    /// A string or a table; anything else is refused naming both forms (serde's untagged enum
    /// would say only that no variant matched).
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<MaterialFile, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = MaterialFile;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                write!(
                    f,
                    "a material's name (a string) or its constants `{{ E = .., nu = .., rho = .. }}`"
                )
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<MaterialFile, E> {
                Ok(MaterialFile::Named(v.to_string()))
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                map: A,
            ) -> Result<MaterialFile, A::Error> {
                CustomMaterialFile::deserialize(serde::de::value::MapAccessDeserializer::new(map))
                    .map(MaterialFile::Custom)
            }
        }
        d.deserialize_any(V)
    }
}

impl LawFile {
    /// The law `p`, `eta` with every optional key absent (the form a scene edit builds, so a new
    /// optional key of the law touches no edit).
    pub fn new(p: f64, eta: f64) -> LawFile {
        LawFile {
            p: Some(p),
            eta: Some(eta),
            delta0: None,
            tension: None,
            contact_damping: None,
            material: None,
            restitution: None,
        }
    }
}

/// `contact_damping = { model = "kuwabara-kono", c = 0.5 }`.
#[derive(Debug, Clone, Copy, Deserialize, Serialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(deny_unknown_fields)]
pub struct ContactDampingFile {
    /// `model`: `viscous`, `kuwabara-kono` or `scale-respecting`.
    pub model: crate::chain::law::DampingModel,
    /// `c`: the coefficient (>= 0).
    pub c: f64,
}

/// An end: `{ kind = "free" }` or `{ kind = "wall", p = .., eta = .., delta0 = .. }`; any
/// other key is an error (serde's internally tagged enums skip unknown keys in a unit variant
/// and leave a newtype variant's to its type: `free_end` and [`LawFile`]'s
/// `deny_unknown_fields` refuse them).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum EndFile {
    /// `{ kind = "free" }`: nothing beyond the last grain (no other key).
    #[serde(deserialize_with = "free_end")]
    Free,
    /// `{ kind = "wall", p, eta, delta0, tension }`: a rigid wall with its own contact law.
    Wall(LawFile),
}

/// The `[striker]` table: an extra grain outside the sections that hits a free end (printed
/// grain 0 at the left end, N + 1 at the right).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(deny_unknown_fields)]
pub struct StrikerFile {
    /// `end`: `left` or `right`, which end it hits (must be free); required.
    pub end: StrikerEnd,
    /// `mass`: its mass (> 0); required in a program-unit scene, refused in an SI scene.
    pub mass: Option<f64>,
    /// `speed`: its speed towards the chain (> 0), m/s in an SI scene; required.
    pub speed: f64,
    /// `p`: exponent of its contact with the end grain; give with `eta`, or neither (default: the
    /// end section's law). Program-unit scenes only.
    pub p: Option<f64>,
    /// `eta`: stiffness of its contact with the end grain; give with `p`, or neither.
    pub eta: Option<f64>,
    /// `material`: in an SI scene, the striker is a sphere of this material (as a section's
    /// `material`) and `diameter`; its contact with the end grain follows Hertz with the pair's
    /// constant. Required there.
    pub material: Option<MaterialFile>,
    /// `diameter`: the striker's diameter in metres (1e-6 to 1), with `material`.
    pub diameter: Option<f64>,
    /// `restitution`: of its contact with the end grain (0.05 to 1); SI scenes only; default
    /// `chain.restitution`, else elastic.
    pub restitution: Option<f64>,
}

/// The `[target]` table: the body the chain protects, one grain joined to the right end of the
/// last section (a section named `target`), free or held to the ground by a linear spring.
/// Not with a right wall or a right striker.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(deny_unknown_fields)]
pub struct TargetFile {
    /// `mass`: its mass (> 0; kg in an SI scene). Give `mass`, or `material` and `diameter` (a
    /// sphere, SI scenes).
    pub mass: Option<f64>,
    /// `material`: SI scenes: with `diameter` a sphere of this material (its mass from its
    /// density), touching the last bead through the pair's Hertz constant; with `mass` instead a
    /// body with a flat face of this material (sphere on a flat, `units::hertz_eta_flat`).
    pub material: Option<MaterialFile>,
    /// `diameter`: with `material`, the target sphere's diameter in metres.
    pub diameter: Option<f64>,
    /// `p`: exponent of its contact with the last bead, with `eta` (and `mass`), instead of a
    /// material; in a program-unit scene default the last section's law.
    pub p: Option<f64>,
    /// `eta`: stiffness of its contact with the last bead (N/m^p in an SI scene), with `p`.
    pub eta: Option<f64>,
    /// `spring`: stiffness of a linear spring holding it to the ground (> 0; N/m in an SI
    /// scene); default none (a free body).
    pub spring: Option<f64>,
    /// `restitution`: of its contact with the last bead (0.05 to 1); SI scenes only; default
    /// `chain.restitution`, else elastic.
    pub restitution: Option<f64>,
}

/// One `[[initial]]` entry: a displacement and/or velocity given to one grain or a range of
/// grains at t = 0 (printed grain numbers: chain grains 1..=N, a left striker 0, a right
/// striker N + 1).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(deny_unknown_fields)]
pub struct InitialFile {
    /// `grain`: a single grain; or give `first` and `last` instead.
    pub grain: Option<i64>,
    /// `first`: first grain of the range (inclusive).
    pub first: Option<i64>,
    /// `last`: last grain of the range (inclusive).
    pub last: Option<i64>,
    /// `velocity`: initial velocity (finite), in velocity units; default: not set.
    pub velocity: Option<f64>,
    /// `displacement`: initial displacement from the rest position (finite); default 0. At least
    /// one of `velocity` and `displacement` must be given.
    pub displacement: Option<f64>,
}

/// The `[integrator]` table; absent keys take the defaults of
/// [`crate::integrators::IntegrationParams`].
#[derive(Clone, Debug, Default, Deserialize, Serialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(deny_unknown_fields)]
pub struct IntegratorFile {
    /// `method`: `verlet`, `blanes-moan4`, `gear5`, `dopri5` or `multirate`; default `verlet`.
    pub method: Option<Method>,
    /// `dt`: the fixed step (the initial step of dopri5), in time units, shortened so a whole
    /// number of steps fits an output interval; default 1e-4.
    pub dt: Option<f64>,
    /// `rtol`: relative tolerance of dopri5 (adaptive methods only); default 1e-8.
    pub rtol: Option<f64>,
    /// `atol`: absolute tolerance of dopri5 (adaptive methods only); default 1e-10.
    pub atol: Option<f64>,
    /// `skip_untouched`: integrate only the grains a disturbance has reached (exact, bit for bit);
    /// default true.
    pub skip_untouched: Option<bool>,
    /// `max_energy_error`: relative energy error at an output time above which the run stops as a
    /// blow-up; default 1e-2.
    pub max_energy_error: Option<f64>,
    /// `sleep`: the approximate sleep rule, `{ velocity, force }`; default off. Splitting methods
    /// only.
    pub sleep: Option<SleepFile>,
    /// `multirate`: settings of the multirate method, `{ ratio, fast, margin }`; required with
    /// `method = "multirate"` and only allowed with it.
    pub multirate: Option<MultirateFile>,
    /// `events`: cut each step where a contact closes or opens, or a damped contact's total
    /// force clamps to zero or comes back, so that no step straddles the kink of a contact
    /// force (verlet and blanes-moan4); default false.
    pub events: Option<bool>,
}

/// `multirate = { ratio = 8, fast = "container", margin = 20 }`: the fast region is the named
/// region widened by `margin` grains on each side (see `integrators::multirate`).
#[derive(Debug, Clone, Deserialize, Serialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(deny_unknown_fields)]
pub struct MultirateFile {
    /// `ratio`: outer step H = ratio dt; must divide the number of steps per output interval.
    pub ratio: u64,
    /// `fast`: name of the region (`[[regions]]`) integrated at the small step.
    pub fast: String,
    /// `margin`: grains added on each side of the fast region (clipped to the chain); default 0.
    pub margin: Option<u64>,
}

/// `sleep = { velocity, force }`: grains with speed at most `velocity` and net force at most
/// `force` are put to rest at output times (approximate; see
/// [`crate::integrators::Sleep`]).
#[derive(Debug, Clone, Copy, Deserialize, Serialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(deny_unknown_fields)]
pub struct SleepFile {
    /// `velocity`: speed threshold (>= 0), in velocity units.
    pub velocity: f64,
    /// `force`: net force threshold (>= 0), in force units.
    pub force: f64,
}

/// The `[run]` table (required).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(deny_unknown_fields)]
pub struct RunFile {
    /// `duration`: simulated time (> 0), in time units.
    pub duration: f64,
    /// `output_interval`: time between output times (> 0, at most `duration`); output `k` is at
    /// exactly `k * output_interval`.
    pub output_interval: f64,
    /// `horizon`: integrate only the grains from which a disturbance can still reach a recorded
    /// region, probe or snapshot range before the run ends (`crate::run::Horizon`);
    /// `horizon = {}` takes the defaults. Default: no horizon.
    pub horizon: Option<HorizonFile>,
}

/// `horizon = { speed = 1.6, pad = 8 }`: the causal horizon of `[run]` (`unsafe = true` to run
/// with a speed below the bound).
#[derive(Clone, Debug, Default, Deserialize, Serialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(deny_unknown_fields)]
pub struct HorizonFile {
    /// `speed`: the fastest a disturbance may travel back towards a recorded range, in grains
    /// per time unit (> 0, and at least `Horizon::speed_bound` unless `unsafe`); default
    /// `Horizon::speed_bound`, the fastest sound speed the run's energy allows outside the
    /// recorded ranges.
    pub speed: Option<f64>,
    /// `pad`: grains kept beyond the reach on each side; default `Horizon::DEFAULT_PAD`.
    pub pad: Option<usize>,
    /// `unsafe`: run with a `speed` below the bound anyway (refused otherwise, by the check
    /// and the run: the recorded ranges would not be exact); the run prints a warning and
    /// records it in `summary.json`. Default false; only with `speed`.
    #[serde(rename = "unsafe")]
    pub unsafe_speed: Option<bool>,
}

/// One `[[regions]]` entry: a named range of grains whose energy and momentum are recorded.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(deny_unknown_fields)]
pub struct RegionFile {
    /// `name`: non-empty, no commas, unique among the regions.
    pub name: String,
    /// `first`: first grain, as a printed grain number (chain grains 1..=N, a left striker 0, a
    /// right striker N + 1).
    pub first: i64,
    /// `last`: last grain (inclusive, printed grain number, not before `first`).
    pub last: i64,
}

/// The `[output]` table.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(deny_unknown_fields)]
pub struct OutputFile {
    /// `energies`: write `energies.csv` (totals, momentum, region energies every output time);
    /// default true.
    pub energies: Option<bool>,
    /// `snapshots`: per-grain fields at chosen output times (`snapshots.csv`); default none.
    pub snapshots: Option<SnapshotFile>,
    /// `pulses`: pulse detection in the energy profile at chosen output times (`pulses.csv`);
    /// default none.
    pub pulses: Option<PulsesFile>,
    /// `tracks`: pulses followed from one detection to the next, with their speed and true peak
    /// velocity (`tracks.csv`); default none. Needs verlet, blanes-moan4 or dopri5.
    pub tracks: Option<TracksFile>,
}

/// `output.snapshots = { fields, every, at, first, last }`.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(deny_unknown_fields)]
pub struct SnapshotFile {
    /// `fields`: what to record per grain (`velocity`, `displacement`, `force`, `overlap`,
    /// `energy`, `mass`); at least one.
    pub fields: Vec<Field>,
    /// `every`: record output indices that are multiples of this (>= 1); default 1.
    pub every: Option<u64>,
    /// `at`: record exactly these output indices instead (output 0 is t = 0; increasing, each
    /// once, none after the run's last); default empty (use `every`).
    #[serde(default)]
    pub at: Vec<u64>,
    /// `first`: first grain recorded (printed grain number); default the first grain of the chain
    /// (a left striker included).
    pub first: Option<i64>,
    /// `last`: last grain recorded (printed grain number); default the last grain of the chain (a
    /// right striker included).
    pub last: Option<i64>,
}

/// `output.pulses = { every, at, threshold, valley }`: split the per-grain energy profile into
/// pulses.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(deny_unknown_fields)]
pub struct PulsesFile {
    /// `every`: detect at output indices that are multiples of this (>= 1); default 1.
    pub every: Option<u64>,
    /// `at`: detect at exactly these output indices instead (increasing, each once, none after
    /// the run's last); default empty (use `every`).
    #[serde(default)]
    pub at: Vec<u64>,
    /// `threshold`: a grain belongs to a pulse when its energy exceeds this fraction of the
    /// largest grain energy (in (0, 1)); default 1e-4.
    pub threshold: Option<f64>,
    /// `valley`: a dip below this fraction of the smaller neighbouring peak splits a pulse in two
    /// (in (0, 1]); default 0.25.
    pub valley: Option<f64>,
}

/// `output.tracks = { every, threshold, valley, max_jump }`: detect pulses as `output.pulses`
/// does and link them from one detection to the next (`observables::tracking`).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(deny_unknown_fields)]
pub struct TracksFile {
    /// `every`: detect at output indices that are multiples of this (>= 1); default 1.
    pub every: Option<u64>,
    /// `threshold`: as `output.pulses.threshold`; default 1e-4.
    pub threshold: Option<f64>,
    /// `valley`: as `output.pulses.valley`; default 0.25.
    pub valley: Option<f64>,
    /// `max_jump`: largest move of a pulse between two detections, in grains (> 0); default
    /// unbounded.
    pub max_jump: Option<f64>,
}

/// Top-level keys only a scene file has.
const SCENE_KEYS: [&str; 8] = [
    "chain",
    "striker",
    "target",
    "initial",
    "integrator",
    "run",
    "regions",
    "output",
];

/// Top-level keys only a sweep file (`grainchain study`) has.
const SWEEP_KEYS: [&str; 9] = [
    "snapshots",
    "members",
    "perturbation",
    "outer_chains",
    "multirate",
    "reference",
    "levels",
    "containers",
    "random",
];

/// What a file that failed to parse as `expected` is instead, judged by its top-level keys:
/// a message saying so when it has keys of the other kind and none of `expected`'s, so that a
/// sweep file given to `run` is not reported as an unknown key `containers`. `None` when the
/// keys do not tell. `top` are the file's top-level keys.
pub fn wrong_kind(top: &[&str], expected: FileKind) -> Option<String> {
    let has = |keys: &[&str]| keys.iter().any(|k| top.contains(k));
    match expected {
        FileKind::Scene if has(&SWEEP_KEYS) && !has(&SCENE_KEYS) => Some(
            "this is a sweep file, not a scene (run it with `grainchain study`)".into(),
        ),
        FileKind::Sweep if has(&SCENE_KEYS) && !has(&SWEEP_KEYS) => Some(
            "this is a scene file, not a sweep file (run it with `grainchain run`; `grainchain study` takes a sweep file)".into(),
        ),
        _ => None,
    }
}

/// The two kinds of input file (for [`wrong_kind`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FileKind {
    /// A scene (`grainchain run`, `check`).
    Scene,
    /// A sweep file (`grainchain study`).
    Sweep,
}

/// A one-line description of a TOML error: where, which key, what.
pub fn describe_toml_error(e: &toml::de::Error, text: &str) -> String {
    let msg = e.message().trim().replace('\n', " ");
    let Some(span) = e.span() else {
        return deepest_line(text)
            .filter(|_| msg.contains("recursion"))
            .map_or(msg.clone(), |(n, line)| {
                format!("line {n} (`{line}`): nested too deeply for the TOML reader ({msg})")
            });
    };
    let start = span.start.min(text.len());
    let line_no = text[..start].matches('\n').count() + 1;
    let line_start = text[..start].rfind('\n').map_or(0, |i| i + 1);
    let column = text[line_start..start].chars().count() + 1;
    let line_text = text[line_start..].lines().next().unwrap_or("").trim();
    let at = key_at(text, line_start);
    let mut key = at.as_ref().map(KeyAt::path);
    let quoted = |prefix: &str| Some(msg.strip_prefix(prefix)?.split('`').next()?.to_string());
    // A missing top-level key is reported at the start of the file, which may be another key's
    // line (issue 38: a missing `[run]` blamed `name`); a table's, at the table's header.
    if let Some(field) = quoted("missing field `") {
        if key.is_none() || (start == 0 && at.as_ref().is_some_and(|a| a.key.is_some())) {
            key = Some(field);
        }
    }
    // serde points an unknown field at the line that sets it; name the field itself, which is
    // one part of a dotted key (issue 38: `foo.bar.baz = 1` in `[output]` was reported as
    // `output.foo.bar.baz.foo`).
    if let (Some(at), Some(field)) = (&at, quoted("unknown field `")) {
        key = Some(at.path_to(&field));
    }
    // `[[name]]` where the file takes one table `[name]`: serde reads the array as a sequence
    // of the table's fields and says "invalid type: map, expected f64" (issue 50).
    if let Some(name) = line_text
        .strip_prefix("[[")
        .and_then(|t| t.split("]]").next())
        .filter(|_| msg.starts_with("invalid type: map, expected"))
    {
        let name = name.trim();
        return format!(
            "key `{name}` (line {line_no}, column {column}): `[[{name}]]` makes an array of \
             tables, and `{name}` is one table: write `[{name}]`"
        );
    }
    match key {
        Some(key) => format!("key `{key}` (line {line_no}, column {column}): {msg}"),
        None => format!("line {line_no}, column {column} (`{line_text}`): {msg}"),
    }
}

/// The line of `text` nested deepest (a table header's dotted parts; an assignment's dotted key
/// and the brackets of its value), with its number (1-based), cut to 60 characters: where a
/// TOML reader's recursion limit, which has no position, was hit.
fn deepest_line(text: &str) -> Option<(usize, String)> {
    let depth = |l: &str| {
        let l = l.trim();
        if l.starts_with('[') && !l.contains('=') {
            return l.matches('.').count() + 1;
        }
        let Some((key, value)) = l.split_once('=') else {
            return 0;
        };
        let (mut d, mut most) = (0usize, 0usize);
        for c in value.chars() {
            match c {
                '[' | '{' => {
                    d += 1;
                    most = most.max(d);
                }
                ']' | '}' => d = d.saturating_sub(1),
                _ => {}
            }
        }
        key.matches('.').count() + 1 + most
    };
    let (n, line) = text
        .lines()
        .enumerate()
        .max_by_key(|(i, l)| (depth(l), std::cmp::Reverse(*i)))?;
    Some((n + 1, line.trim().chars().take(60).collect()))
}

/// Where a line of a TOML text sits: its table (a header's own path, `sections[2]` for an array
/// of tables), and the dotted key it assigns (`None` on a header line).
struct KeyAt {
    table: Option<String>,
    key: Option<String>,
}

impl KeyAt {
    /// The dotted path of what the line sets.
    fn path(&self) -> String {
        match (&self.table, &self.key) {
            (Some(t), Some(k)) => format!("{t}.{k}"),
            (Some(t), None) => t.clone(),
            (None, Some(k)) => k.clone(),
            (None, None) => String::new(),
        }
    }

    /// The path of the unknown `field` the line sets: the line's dotted key (or the header's
    /// path) up to the first part named `field`; the field after the line's path when no part
    /// is (an inline table's key).
    fn path_to(&self, field: &str) -> String {
        let cut = |path: &str| {
            let parts: Vec<&str> = path.split('.').map(str::trim).collect();
            let i = parts.iter().position(|p| *p == field)?;
            Some(parts[..=i].join("."))
        };
        let within = match (&self.table, &self.key) {
            (t, Some(k)) => cut(k).map(|k| match t {
                Some(t) => format!("{t}.{k}"),
                None => k,
            }),
            (Some(t), None) => cut(t),
            (None, None) => None,
        };
        within.unwrap_or_else(|| match self.path() {
            p if p.is_empty() => field.to_string(),
            p => format!("{p}.{field}"),
        })
    }
}

/// Where the line starting at `line_start` sits: [`KeyAt`] of an assignment or a table header.
fn key_at(text: &str, line_start: usize) -> Option<KeyAt> {
    let line = text[line_start..].lines().next()?.trim();
    let header = |l: &str| -> Option<(String, bool)> {
        let l = l.trim();
        if let Some(h) = l.strip_prefix("[[") {
            return Some((h.split("]]").next()?.trim().to_string(), true));
        }
        if let Some(h) = l.strip_prefix('[') {
            return Some((h.split(']').next()?.trim().to_string(), false));
        }
        None
    };
    if let Some((h, array)) = header(line) {
        let idx = text[..line_start]
            .lines()
            .filter(|l| header(l) == Some((h.clone(), true)))
            .count();
        return Some(KeyAt {
            table: Some(if array { format!("{h}[{idx}]") } else { h }),
            key: None,
        });
    }
    let key = line.split('=').next()?.trim();
    if key.is_empty() || line.starts_with('#') || !line.contains('=') {
        return None;
    }
    // Find the enclosing table header, and its array index if it is an array of tables.
    let before = &text[..line_start];
    let mut table = None;
    for (i, l) in before
        .lines()
        .enumerate()
        .collect::<Vec<_>>()
        .into_iter()
        .rev()
    {
        if let Some((h, array)) = header(l) {
            let offset: usize = before.lines().take(i).map(|x| x.len() + 1).sum();
            let idx = before[..offset]
                .lines()
                .filter(|x| header(x) == Some((h.clone(), true)))
                .count();
            table = Some(if array { format!("{h}[{idx}]") } else { h });
            break;
        }
    }
    Some(KeyAt {
        table,
        key: Some(key.to_string()),
    })
}

/// The most bytes grainchain reads from an input file (a scene, a sweep, a design file): 100 MB,
/// thirteen times a scene of 100,000 one-grain sections (7.7 MB), whose check takes seconds. An
/// input file is text a person or a script wrote; a path to a device or a huge file of something
/// else is refused after this many bytes instead of filling the memory (issue 38: a scene path
/// to `/dev/zero` was read until the memory ran out).
pub const INPUT_LIMIT_BYTES: u64 = 100_000_000;

/// Read the input file at `path` as text: at most [`INPUT_LIMIT_BYTES`], UTF-8 (the error names
/// the line of the first byte that is not). Every input file of the tool and the Python module
/// is read here.
pub fn read_text(path: &Path) -> Result<String, InputError> {
    use std::io::Read;
    let read = |source| InputError::Read {
        file: path.to_path_buf(),
        source,
    };
    let mut bytes = Vec::new();
    std::fs::File::open(path)
        .and_then(|f| f.take(INPUT_LIMIT_BYTES + 1).read_to_end(&mut bytes))
        .map_err(read)?;
    if bytes.len() as u64 > INPUT_LIMIT_BYTES {
        return Err(read(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!(
                "longer than {} (an input file is text: a scene, a sweep or a design file)",
                crate::number::human_bytes(INPUT_LIMIT_BYTES)
            ),
        )));
    }
    String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let line = 1 + e.as_bytes()[..at].iter().filter(|&&b| b == b'\n').count();
        read(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("line {line}: not UTF-8 text (byte {at} of the file)"),
        ))
    })
}
