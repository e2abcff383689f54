//! The catalogue of sample problems: named set-ups with their reference values, shared by the
//! validation suite, the benchmarks, `grainchain work-precision` and the examples, so that each
//! problem is built in one place.
//!
//! Each problem is a small struct of public fields (its physical parameters) that builds its
//! [`Chain`] and a [`SimulationBuilder`] holding the chain, the initial conditions and recommended
//! integration settings (a caller's own `.params(..)` and `.schedule(..)` replace them), and
//! that computes its reference values (`docs/physics.md`, section numbers below):
//!
//! | name | struct | reference values |
//! |---|---|---|
//! | `solitary-wave` | [`SolitaryWave`] | width L(p), speed exponent, kinetic-energy fraction (2) |
//! | `two-grain-collision` | [`TwoGrainCollision`] | contact time, largest overlap, outgoing velocities (4) |
//! | `linear-spring-chain` | [`LinearSpringChain`] | `v_n(t) = v0 J_2n(2 omega0 t)` (5) |
//! | `heavy-to-light` | [`MassInterface`] | total transmission, about `ratio` waves; light to heavy: point-mass transmission (6) |
//! | `grains-in-a-box` | [`GrainsInABox`] | the conserved energy |
//! | `container-a` .. `container-e` | [`Container`] | the scene files `scenes/containers/*.toml`; gamma, alpha (7) |
//!
//! [`by_name`] looks a named instance up; [`Problem`] is that instance, with its name,
//! description, recommended simulation and reference values.
//!
//! ```
//! use grainchain_engine::problems::{self, SolitaryWave, TwoGrainCollision};
//!
//! // An equal-mass striker launches a solitary wave into 200 Hertz grains (eta = m = 1).
//! let wave = SolitaryWave::unit(1.5, 200, 1.0);
//! let mut sim = wave.builder()?.schedule(10.0, 0.5).build()?;
//! sim.run(|_| Ok::<(), grainchain_engine::RunError>(()))?;
//! assert!((wave.width() - 4.967).abs() < 1e-3); // about five grains
//!
//! // Equal masses exchange their velocities.
//! let c = TwoGrainCollision { striker_mass: 1.0, grain_mass: 1.0, ..TwoGrainCollision::default() };
//! assert_eq!(c.outgoing_velocities(), (0.0, 1.0));
//!
//! // Named problems; an unknown name lists the known ones.
//! assert_eq!(problems::by_name("solitary-wave")?.name(), "solitary-wave");
//! assert!(problems::by_name("tsunami").unwrap_err().to_string().contains("container-a"));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use crate::chain::{
    Chain, ChainBuilder, ChainError, ContactLaw, DampingModel, End, Section, Striker, StrikerEnd,
};
use crate::error::{Error, InputError};
use crate::integrators::{IntegrationParams, Method};
use crate::run::{Simulation, SimulationBuilder};
use crate::scene::Scene;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

/// Blanes-Moan 4 at step `dt` (the method the reference runs use).
fn bm4(dt: f64) -> IntegrationParams {
    IntegrationParams {
        method: Method::BlanesMoan4,
        dt,
        ..Default::default()
    }
}

/// The contact time of two grains of reduced mass `mu` approaching at `v` under `F = eta x^p`
/// (physics.md 4): `2 (delta_max / v) I_p`, `I_p = B(1/(p+1), 1/2) / (p+1)`.
pub fn contact_time(p: f64, eta: f64, mu: f64, v: f64) -> f64 {
    2.0 * max_overlap(p, eta, mu, v) / v * contact_integral(p)
}

/// The largest overlap of two grains of reduced mass `mu` approaching at `v` (physics.md 4):
/// `((p+1) mu v^2 / (2 eta))^(1/(p+1))`.
pub fn max_overlap(p: f64, eta: f64, mu: f64, v: f64) -> f64 {
    ((p + 1.0) * mu * v * v / (2.0 * eta)).powf(1.0 / (p + 1.0))
}

/// `I_p = integral_0^1 dx / sqrt(1 - x^(p+1)) = B(1/(p+1), 1/2) / (p+1)` (physics.md 4;
/// Hertz: 1.4716).
pub fn contact_integral(p: f64) -> f64 {
    let a = 1.0 / (p + 1.0);
    use crate::analysis::ln_gamma;
    (ln_gamma(a) + ln_gamma(0.5) - ln_gamma(a + 0.5)).exp() / (p + 1.0)
}

/// `chain` with a striker of `mass` hitting its left end at `speed` (the striker's contact takes
/// the law of the first section).
fn struck_from_left(chain: ChainBuilder, mass: f64, speed: f64) -> Result<Chain, ChainError> {
    chain
        .striker(Striker {
            end: StrikerEnd::Left,
            mass,
            speed,
            law: None,
        })
        .build()
}

/// Bessel function of the first kind `J_n(x)`, integer `n`, by the trapezoidal rule on
/// `J_n(x) = (1/2pi) int_0^2pi cos(n tau - x sin tau) dtau` with enough points that the aliased
/// terms are below 1e-30 (accurate to round-off, about 1e-15).
pub fn bessel_j(n: i64, x: f64) -> f64 {
    let m = (2 * (n.unsigned_abs() as usize + x.abs() as usize) + 128).next_power_of_two();
    let h = 2.0 * PI / m as f64;
    let s: f64 = (0..m)
        .map(|k| {
            let tau = k as f64 * h;
            (n as f64 * tau - x * tau.sin()).cos()
        })
        .sum();
    s / m as f64
}

/// A single solitary wave: a striker of the grain mass hits, on the left, a uniform chain at
/// rest (physics.md 2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolitaryWave {
    /// Contact exponent.
    pub p: f64,
    /// Contact stiffness.
    pub eta: f64,
    /// Mass of every grain and of the striker.
    pub mass: f64,
    /// Grains of the chain (the striker not counted).
    pub grains: usize,
    /// Speed of the striker.
    pub speed: f64,
}

impl Default for SolitaryWave {
    /// The named instance: [`SolitaryWave::hertz`] with 1,100 grains.
    fn default() -> Self {
        SolitaryWave::hertz(1100)
    }
}

impl SolitaryWave {
    /// Hertz grains in the paper's program units (eta = 5657, m = 1), striker speed 1.
    pub fn hertz(grains: usize) -> Self {
        SolitaryWave {
            p: 1.5,
            eta: 5657.0,
            mass: 1.0,
            grains,
            speed: 1.0,
        }
    }

    /// The dimensionless chain of the validation suite: exponent `p`, eta = m = 1.
    pub fn unit(p: f64, grains: usize, speed: f64) -> Self {
        SolitaryWave {
            p,
            eta: 1.0,
            mass: 1.0,
            grains,
            speed,
        }
    }

    /// The chain: internal index 0 is the striker, 1..=grains the chain.
    pub fn chain(&self) -> Result<Chain, ChainError> {
        struck_from_left(
            ChainBuilder::new().grains(self.grains, self.mass, ContactLaw::new(self.p, self.eta)),
            self.mass,
            self.speed,
        )
    }

    /// The chain with Blanes-Moan 4 at 1/400 of the striker's contact time and outputs every
    /// 1/40 of it (set the duration with `.schedule`).
    pub fn builder(&self) -> Result<SimulationBuilder, ChainError> {
        let tc = self.contact_time();
        Ok(SimulationBuilder::new(self.chain()?)
            .params(bm4(tc / 400.0))
            .schedule(100.0 * tc, tc / 40.0))
    }

    /// Duration of the striker's contact with the first grain, as for two free grains
    /// (physics.md 4): the time scale of the wave.
    pub fn contact_time(&self) -> f64 {
        contact_time(self.p, self.eta, 0.5 * self.mass, self.speed)
    }

    /// Continuum width `L(p) = (pi/(p-1)) sqrt(p(p+1)/6)` in grain diameters (physics.md 2):
    /// 4.967 for Hertz.
    pub fn width(&self) -> f64 {
        PI / (self.p - 1.0) * (self.p * (self.p + 1.0) / 6.0).sqrt()
    }

    /// Exponent of the wave speed against the peak grain velocity, `(p-1)/(p+1)`: exact for the
    /// discrete chain by the amplitude symmetry (physics.md 2-3).
    pub fn speed_exponent(&self) -> f64 {
        (self.p - 1.0) / (self.p + 1.0)
    }

    /// Time-averaged kinetic energy over total energy of a travelling wave, `(p+1)/(p+3)`
    /// (virial identity, physics.md 2).
    pub fn kinetic_fraction(&self) -> f64 {
        (self.p + 1.0) / (self.p + 3.0)
    }
}

/// Two grains: a striker hits a single grain at rest (physics.md 4).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TwoGrainCollision {
    /// Contact exponent.
    pub p: f64,
    /// Contact stiffness.
    pub eta: f64,
    /// Mass of the striker (internal index 0).
    pub striker_mass: f64,
    /// Mass of the grain at rest (internal index 1).
    pub grain_mass: f64,
    /// Speed of the striker.
    pub speed: f64,
}

impl Default for TwoGrainCollision {
    /// The named instance: Hertz, eta = 5657, a striker of mass 1 at speed 1 hits a grain of
    /// mass 3 (outgoing velocities -0.5 and 0.5; the `collision` of `work-precision`).
    fn default() -> Self {
        TwoGrainCollision {
            p: 1.5,
            eta: 5657.0,
            striker_mass: 1.0,
            grain_mass: 3.0,
            speed: 1.0,
        }
    }
}

impl TwoGrainCollision {
    /// The chain: the striker and the grain.
    pub fn chain(&self) -> Result<Chain, ChainError> {
        struck_from_left(
            ChainBuilder::new().grains(1, self.grain_mass, ContactLaw::new(self.p, self.eta)),
            self.striker_mass,
            self.speed,
        )
    }

    /// The chain with Blanes-Moan 4 at 1/2000 of the contact time, run to 1.5 contact times
    /// with outputs every 1/500 of it.
    pub fn builder(&self) -> Result<SimulationBuilder, ChainError> {
        let tc = self.contact_time();
        Ok(SimulationBuilder::new(self.chain()?)
            .params(bm4(tc / 2000.0))
            .schedule(1.5 * tc, tc / 500.0))
    }

    /// Reduced mass `m1 m2 / (m1 + m2)`.
    pub fn reduced_mass(&self) -> f64 {
        self.striker_mass * self.grain_mass / (self.striker_mass + self.grain_mass)
    }

    /// Duration of the contact (physics.md 4).
    pub fn contact_time(&self) -> f64 {
        contact_time(self.p, self.eta, self.reduced_mass(), self.speed)
    }

    /// Largest overlap (physics.md 4).
    pub fn max_overlap(&self) -> f64 {
        max_overlap(self.p, self.eta, self.reduced_mass(), self.speed)
    }

    /// Velocities (striker, grain) after the contact: the elastic collision of point masses,
    /// `((m1 - m2) / (m1 + m2) v, 2 m1 / (m1 + m2) v)`; equal masses exchange velocities.
    pub fn outgoing_velocities(&self) -> (f64, f64) {
        let (m1, m2, v) = (self.striker_mass, self.grain_mass, self.speed);
        ((m1 - m2) / (m1 + m2) * v, 2.0 * m1 / (m1 + m2) * v)
    }

    /// Coefficient of restitution `(v_grain - v_striker) / speed` after the contact when it is
    /// damped by `model` with coefficient `c` ([`ContactLaw::with_damping`]): Blanes-Moan 4 at
    /// 1/4096 of the elastic contact time, run for 8 elastic contact times. The damped contact
    /// converges at first order in the step (the damping force is not smooth where the contact
    /// closes), so against an independent solution the restitution is off by about 5e-7 with
    /// `kuwabara-kono`, 5e-6 to 1.2e-5 with `scale-respecting` and 5e-5 to 1e-4 with `viscous`
    /// (c = 0.1 and the c of e = 0.5: `validation/protector_reference.rs`). Error: a run error, or grains still in contact then (a
    /// damping so strong that the contact lasts longer; restitution near 0).
    pub fn restitution(&self, model: DampingModel, c: f64) -> Result<f64, crate::run::RunError> {
        self.collision().restitution(model, c)
    }

    /// The coefficient `c` of `model` for which this collision's restitution is `e`
    /// (0.05 <= e < 1): bisection on `c` (the restitution falls as `c` grows) to 1e-12 of it.
    /// For the scale-respecting model the answer holds at every impact speed; it depends on the
    /// masses only through `c / sqrt(eta m_eff)`. (The implementation is the scene's, which
    /// turns a scene's `restitution` into contact damping with it.)
    pub fn damping_for_restitution(
        &self,
        model: DampingModel,
        e: f64,
    ) -> Result<f64, crate::run::RunError> {
        self.collision().damping_for_restitution(model, e)
    }

    /// This collision with its elastic contact time, as the scene's restitution code takes it.
    fn collision(&self) -> crate::scene::restitution::Collision {
        crate::scene::restitution::Collision {
            p: self.p,
            eta: self.eta,
            striker_mass: self.striker_mass,
            grain_mass: self.grain_mass,
            speed: self.speed,
            contact_time: self.contact_time(),
        }
    }
}

/// A chain of two-sided linear springs with one grain kicked (physics.md 5).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinearSpringChain {
    /// Grains of the chain (free ends).
    pub grains: usize,
    /// Internal index of the kicked grain.
    pub kicked: usize,
    /// Spring constant.
    pub k: f64,
    /// Mass of every grain.
    pub mass: f64,
    /// Initial velocity of the kicked grain.
    pub v0: f64,
}

impl Default for LinearSpringChain {
    /// The named instance: 301 grains (k = m = 1), the middle one kicked to 1. Up to t = 60 the
    /// front (at most omega0 = 1 grain per unit time) stays 90 grains from the ends, where
    /// `J_2n(120)`, n >= 150, is below 1e-30: the finite chain is the infinite one.
    fn default() -> Self {
        LinearSpringChain {
            grains: 301,
            kicked: 150,
            k: 1.0,
            mass: 1.0,
            v0: 1.0,
        }
    }
}

impl LinearSpringChain {
    /// The chain (no initial conditions: see [`LinearSpringChain::builder`]).
    pub fn chain(&self) -> Result<Chain, ChainError> {
        ChainBuilder::new()
            .grains(self.grains, self.mass, ContactLaw::linear_spring(self.k))
            .build()
    }

    /// The chain with the kick, Blanes-Moan 4 at dt = 0.02 / omega0, outputs every 5 / omega0
    /// up to 60 / omega0.
    pub fn builder(&self) -> Result<SimulationBuilder, ChainError> {
        let w = self.omega0();
        Ok(SimulationBuilder::new(self.chain()?)
            .params(bm4(0.02 / w))
            .schedule(60.0 / w, 5.0 / w)
            .velocity(self.kicked, self.v0))
    }

    /// `omega0 = sqrt(k / m)`.
    pub fn omega0(&self) -> f64 {
        (self.k / self.mass).sqrt()
    }

    /// Velocity of grain `i` (internal index) at time `t` on the infinite chain:
    /// `v0 J_2n(2 omega0 t)`, `n = i - kicked` (physics.md 5).
    pub fn velocity(&self, i: usize, t: f64) -> f64 {
        let n = i as i64 - self.kicked as i64;
        self.v0 * bessel_j(2 * n, 2.0 * self.omega0() * t)
    }

    /// Dispersion relation `omega(q) = 2 omega0 |sin(q/2)|` (physics.md 5).
    pub fn frequency(&self, q: f64) -> f64 {
        2.0 * self.omega0() * (0.5 * q).sin().abs()
    }
}

/// Two sections of equal law and different masses; optionally a striker of the first section's
/// mass on the left (physics.md 6; Hong 2005 Fig. 1 when the first section is the heavier).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MassInterface {
    /// Contact exponent.
    pub p: f64,
    /// Contact stiffness.
    pub eta: f64,
    /// Grains of the first section (section `first`).
    pub first_grains: usize,
    /// Mass of the first section's grains.
    pub first_mass: f64,
    /// Grains of the second section (section `second`).
    pub second_grains: usize,
    /// Mass of the second section's grains.
    pub second_mass: f64,
    /// Speed of a striker of the first section's mass on the left, or none (the caller sets the
    /// initial conditions).
    pub striker_speed: Option<f64>,
}

impl Default for MassInterface {
    /// The named instance `heavy-to-light`: 60 grains of mass 10, then 400 of mass 1, Hertz,
    /// eta = 5657, the striker at speed 1.
    fn default() -> Self {
        MassInterface {
            p: 1.5,
            eta: 5657.0,
            first_grains: 60,
            first_mass: 10.0,
            second_grains: 400,
            second_mass: 1.0,
            striker_speed: Some(1.0),
        }
    }
}

impl MassInterface {
    /// The chain: sections `first` and `second`, and the striker if any (internal index 0).
    pub fn chain(&self) -> Result<Chain, ChainError> {
        let law = ContactLaw::new(self.p, self.eta);
        let b = ChainBuilder::new()
            .section(Section::new(
                "first",
                self.first_grains,
                self.first_mass,
                law,
            ))
            .section(Section::new(
                "second",
                self.second_grains,
                self.second_mass,
                law,
            ));
        match self.striker_speed {
            Some(speed) => b.striker(Striker {
                end: StrikerEnd::Left,
                mass: self.first_mass,
                speed,
                law: None,
            }),
            None => b,
        }
        .build()
    }

    /// The chain with Blanes-Moan 4 at dt = 2e-4 and outputs every 0.125 up to 12 (what the
    /// named instance needs for its transmitted train to form: the `builder` example).
    pub fn builder(&self) -> Result<SimulationBuilder, ChainError> {
        Ok(SimulationBuilder::new(self.chain()?)
            .params(bm4(2e-4))
            .schedule(12.0, 0.125))
    }

    /// `first_mass / second_mass`.
    pub fn mass_ratio(&self) -> f64 {
        self.first_mass / self.second_mass
    }

    /// Heavy to light with one law: total transmission, no reflected wave (physics.md 6).
    pub fn transmits_totally(&self) -> bool {
        self.first_mass > self.second_mass
    }

    /// Heavy to light: the number of solitary waves the transmitted impulse breaks into, about
    /// the mass ratio (physics.md 6; the train is infinite, so a count needs a threshold).
    pub fn wave_count(&self) -> f64 {
        self.mass_ratio()
    }

    /// The transmitted energy fraction of an elastic collision of two point masses of the two
    /// sections' masses, `4q / (1+q)^2`: a comparison for light to heavy, not a prediction for
    /// a chain (physics.md 6).
    pub fn point_mass_transmission(&self) -> f64 {
        let q = self.second_mass / self.first_mass;
        4.0 * q / (1.0 + q).powi(2)
    }
}

/// A few grains between two walls (the walls have the grains' law), some of them moving: a
/// closed system whose energy must stay constant.
#[derive(Clone, Debug, PartialEq)]
pub struct GrainsInABox {
    /// Contact exponent.
    pub p: f64,
    /// Contact stiffness.
    pub eta: f64,
    /// Mass of every grain.
    pub mass: f64,
    /// Grains.
    pub grains: usize,
    /// Initial velocities: (internal index, velocity).
    pub velocities: Vec<(usize, f64)>,
}

impl Default for GrainsInABox {
    /// The named instance: four Hertz grains (eta = m = 1), grain 1 at speed 1 and grain 3 at
    /// -0.5 (1-based), the validation suite's long-run energy check.
    fn default() -> Self {
        GrainsInABox {
            p: 1.5,
            eta: 1.0,
            mass: 1.0,
            grains: 4,
            velocities: vec![(0, 1.0), (2, -0.5)],
        }
    }
}

impl GrainsInABox {
    /// The chain between two walls.
    pub fn chain(&self) -> Result<Chain, ChainError> {
        let law = ContactLaw::new(self.p, self.eta);
        ChainBuilder::new()
            .grains(self.grains, self.mass, law)
            .left(End::Wall(law))
            .right(End::Wall(law))
            .build()
    }

    /// The chain with the initial velocities, Blanes-Moan 4 at dt = 0.01, outputs every 1 up to
    /// 100.
    pub fn builder(&self) -> Result<SimulationBuilder, ChainError> {
        let mut b = SimulationBuilder::new(self.chain()?)
            .params(bm4(0.01))
            .schedule(100.0, 1.0);
        for &(i, v) in &self.velocities {
            b = b.velocity(i, v);
        }
        Ok(b)
    }

    /// The energy, all kinetic at t = 0 (no contact is compressed).
    pub fn energy(&self) -> f64 {
        self.velocities
            .iter()
            .map(|&(_, v)| 0.5 * self.mass * v * v)
            .sum()
    }
}

/// The five granular containers of Hong 2005 Fig. 4, read from `scenes/containers/*.toml`
/// (the layouts are a reconstruction: `docs/containers.md`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Container {
    /// (a) the standard container (Fig. 3).
    A,
    /// (b) (a) with the right half's sections reversed.
    B,
    /// (c) uniform sides.
    C,
    /// (d) long sections.
    D,
    /// (e) no walls.
    E,
}

impl Container {
    /// All five, in the paper's order.
    pub const ALL: [Container; 5] = [
        Container::A,
        Container::B,
        Container::C,
        Container::D,
        Container::E,
    ];

    /// `container-a` .. `container-e`.
    pub fn name(self) -> &'static str {
        match self {
            Container::A => "container-a",
            Container::B => "container-b",
            Container::C => "container-c",
            Container::D => "container-d",
            Container::E => "container-e",
        }
    }

    /// The scene file's name under `scenes/containers/`.
    pub fn file_name(self) -> &'static str {
        match self {
            Container::A => "a-standard.toml",
            Container::B => "b-right-half-reversed.toml",
            Container::C => "c-uniform-sides.toml",
            Container::D => "d-long-sections.toml",
            Container::E => "e-no-walls.toml",
        }
    }

    /// The scene file in the scene directory `scenes` (e.g. `scenes/`).
    pub fn path(self, scenes: &Path) -> PathBuf {
        scenes.join("containers").join(self.file_name())
    }

    /// The scene, loaded from the scene directory `scenes`.
    pub fn scene(self, scenes: &Path) -> Result<Scene, InputError> {
        Scene::load(self.path(scenes))
    }

    /// The internal grain indices (first, last) of the scene's region `container`
    /// ([`Scene::region_grains`]).
    pub fn grains(scene: &Scene) -> Result<(usize, usize), Error> {
        let r = scene.region_grains("container")?;
        Ok((*r.start(), *r.end()))
    }

    /// The time rescaling factor alpha that collapses this container's E_R(t) onto (a)'s
    /// ([`crate::paper::alpha`]).
    pub fn alpha(self) -> Option<f64> {
        crate::paper::alpha(&self.name()["container-".len()..])
    }
}

/// One reference value of a problem.
#[derive(Clone, Debug, PartialEq)]
pub struct Reference {
    /// What the value is.
    pub name: &'static str,
    /// The value.
    pub value: f64,
    /// Where it comes from.
    pub source: &'static str,
}

/// A named problem of the catalogue (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub enum Problem {
    /// `solitary-wave`.
    SolitaryWave(SolitaryWave),
    /// `two-grain-collision`.
    TwoGrainCollision(TwoGrainCollision),
    /// `linear-spring-chain`.
    LinearSpringChain(LinearSpringChain),
    /// `heavy-to-light`.
    HeavyToLight(MassInterface),
    /// `grains-in-a-box`.
    GrainsInABox(GrainsInABox),
    /// `container-a` .. `container-e`.
    Container(Container),
}

/// The names [`by_name`] knows, in catalogue order.
pub const NAMES: [&str; 10] = [
    "solitary-wave",
    "two-grain-collision",
    "linear-spring-chain",
    "heavy-to-light",
    "grains-in-a-box",
    "container-a",
    "container-b",
    "container-c",
    "container-d",
    "container-e",
];

/// A name [`by_name`] does not know; its message lists the known names.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown problem `{name}`; known problems: {}", NAMES.join(", "))]
pub struct UnknownProblem {
    /// The name asked for.
    pub name: String,
}

/// The named problem `name` (one of [`NAMES`]).
pub fn by_name(name: &str) -> Result<Problem, UnknownProblem> {
    Ok(match name {
        "solitary-wave" => Problem::SolitaryWave(SolitaryWave::default()),
        "two-grain-collision" => Problem::TwoGrainCollision(TwoGrainCollision::default()),
        "linear-spring-chain" => Problem::LinearSpringChain(LinearSpringChain::default()),
        "heavy-to-light" => Problem::HeavyToLight(MassInterface::default()),
        "grains-in-a-box" => Problem::GrainsInABox(GrainsInABox::default()),
        _ => match Container::ALL.into_iter().find(|c| c.name() == name) {
            Some(c) => Problem::Container(c),
            None => {
                return Err(UnknownProblem {
                    name: name.to_string(),
                })
            }
        },
    })
}

/// Every named problem, in the order of [`NAMES`].
pub fn all() -> Vec<Problem> {
    NAMES
        .iter()
        .map(|n| by_name(n).expect("every listed name is known"))
        .collect()
}

impl Problem {
    /// The catalogue name.
    pub fn name(&self) -> &'static str {
        match self {
            Problem::SolitaryWave(_) => "solitary-wave",
            Problem::TwoGrainCollision(_) => "two-grain-collision",
            Problem::LinearSpringChain(_) => "linear-spring-chain",
            Problem::HeavyToLight(_) => "heavy-to-light",
            Problem::GrainsInABox(_) => "grains-in-a-box",
            Problem::Container(c) => c.name(),
        }
    }

    /// One line on what the problem is.
    pub fn description(&self) -> &'static str {
        match self {
            Problem::SolitaryWave(_) => {
                "an equal-mass striker launches one Nesterenko solitary wave into a Hertz chain"
            }
            Problem::TwoGrainCollision(_) => {
                "a striker hits one grain: exact contact time and elastic outgoing velocities"
            }
            Problem::LinearSpringChain(_) => {
                "two-sided linear springs, one grain kicked: v_n(t) = v0 J_2n(2 omega0 t)"
            }
            Problem::HeavyToLight(_) => {
                "a solitary wave crosses from heavy to light grains: total transmission, a train of waves"
            }
            Problem::GrainsInABox(_) => "a few Hertz grains bouncing between two walls: energy conserved",
            Problem::Container(_) => {
                "a granular container of Hong 2005 Fig. 4, struck from the right (scene file)"
            }
        }
    }

    /// The problem's recommended simulation; `scenes` is the scene directory (used by the
    /// containers only).
    pub fn simulation(&self, scenes: &Path) -> Result<Simulation, Error> {
        let b = match self {
            Problem::SolitaryWave(w) => w.builder()?,
            Problem::TwoGrainCollision(c) => c.builder()?,
            Problem::LinearSpringChain(l) => l.builder()?,
            Problem::HeavyToLight(h) => h.builder()?,
            Problem::GrainsInABox(g) => g.builder()?,
            Problem::Container(c) => return Ok(c.scene(scenes)?.simulation()?),
        };
        Ok(b.build()?)
    }

    /// The problem's reference values.
    pub fn references(&self) -> Vec<Reference> {
        let r = |name, value, source| Reference {
            name,
            value,
            source,
        };
        match self {
            Problem::SolitaryWave(w) => vec![
                r("width (grains)", w.width(), "docs/physics.md 2"),
                r("speed exponent", w.speed_exponent(), "docs/physics.md 2-3"),
                r(
                    "kinetic-energy fraction",
                    w.kinetic_fraction(),
                    "docs/physics.md 2",
                ),
            ],
            Problem::TwoGrainCollision(c) => {
                let (v1, v2) = c.outgoing_velocities();
                vec![
                    r("contact time", c.contact_time(), "docs/physics.md 4"),
                    r("largest overlap", c.max_overlap(), "docs/physics.md 4"),
                    r("striker velocity after", v1, "docs/physics.md 4"),
                    r("grain velocity after", v2, "docs/physics.md 4"),
                ]
            }
            Problem::LinearSpringChain(l) => vec![
                r("omega0", l.omega0(), "docs/physics.md 5"),
                r(
                    "kicked grain's velocity at t = 1 / omega0",
                    l.velocity(l.kicked, 1.0 / l.omega0()),
                    "docs/physics.md 5",
                ),
            ],
            Problem::HeavyToLight(h) => vec![
                r("reflected energy fraction", 0.0, "docs/physics.md 6"),
                r(
                    "transmitted waves (about)",
                    h.wave_count(),
                    "docs/physics.md 6",
                ),
            ],
            Problem::GrainsInABox(g) => vec![r("energy", g.energy(), "exact: closed system")],
            Problem::Container(c) => {
                let mut v = vec![r("gamma", crate::paper::GAMMA, "Hong 2005; docs/paper.md")];
                if let Some(a) = c.alpha() {
                    v.push(r("alpha", a, "Hong 2005; docs/paper.md"));
                }
                if *c == Container::A {
                    v.push(r(
                        "leading wave right, 280th snapshot (fraction)",
                        0.033,
                        "Hong 2005 Fig. 3; docs/paper.md",
                    ));
                    v.push(r(
                        "leading wave left, 280th snapshot (fraction)",
                        0.077,
                        "Hong 2005 Fig. 3; docs/paper.md",
                    ));
                }
                v
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reference_values_match_known_numbers() {
        // physics.md 2 and 4: L(1.5) = 4.967, I_1.5 = 1.4716; I_1 = pi/2 (half a period).
        assert!((SolitaryWave::hertz(10).width() - 4.967).abs() < 1e-3);
        assert!((contact_integral(1.5) - 1.4716).abs() < 1e-4);
        assert!((contact_integral(1.0) - PI / 2.0).abs() < 1e-13);
        // The scene's constant for restitution damping (it sits below `analysis`): the same
        // number to round-off (ln_gamma is accurate to about 1e-15).
        assert!(
            (contact_integral(1.5) - crate::scene::restitution::HERTZ_CONTACT_INTEGRAL).abs()
                < 1e-13
        );
        // Tabulated J_0(1), J_1(1) (A&S table 9.1).
        assert!((bessel_j(0, 1.0) - 0.765_197_686_557_966_6).abs() < 1e-15);
        assert!((bessel_j(1, 1.0) - 0.440_050_585_744_933_5).abs() < 1e-15);
        assert_eq!(
            TwoGrainCollision::default().outgoing_velocities(),
            (-0.5, 0.5)
        );
        assert_eq!(GrainsInABox::default().energy(), 0.625);
        assert!((MassInterface::default().point_mass_transmission() - 40.0 / 121.0).abs() < 1e-15);
    }

    #[test]
    fn every_name_is_found_and_builds() {
        let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
        for (p, name) in all().iter().zip(NAMES) {
            assert_eq!(p.name(), name);
            assert!(!p.description().is_empty() && !p.references().is_empty());
            if !matches!(p, Problem::Container(_)) {
                p.simulation(&scenes).unwrap();
            } else if let Problem::Container(c) = p {
                assert!(c.path(&scenes).is_file(), "{name}");
            }
        }
        let e = by_name("nope").unwrap_err().to_string();
        assert!(
            e.contains("`nope`") && e.contains("linear-spring-chain"),
            "{e}"
        );
    }
}
