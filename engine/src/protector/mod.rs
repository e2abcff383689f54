//! Granular protectors in real materials: a column of spheres (each with its material and
//! diameter) between a striker and what it protects (a rigid wall, or a target body on a spring
//! to ground), evaluated by what a designer optimises: the force on the protected face (its
//! true peak over every step, when, how long above a fraction of it), the impulse it passes on,
//! the energy the target takes, the striker's rebound. SI units throughout (m, kg, s, N, J).
//!
//! [`evaluate`] runs one design; [`evaluate_many`] a batch, threads inside, results in input
//! order and the same at every thread count. A run may stop early, exactly: see [`stop`] for
//! the rule and its proof.

mod adjoint;
mod gradient;
pub mod stop;

pub use gradient::{
    gradients, gradients_forward, gradients_many, gradients_until, Derivatives, Gradients, Tie,
    MAX_GRADIENT_BYTES, MAX_GRADIENT_GRAIN_STEPS, MAX_GRADIENT_WORK, TIE,
};

use crate::chain::{ChainBuilder, ContactLaw, End, Section, Striker, StrikerEnd};
use crate::integrators::{IntegrationParams, Method};
use crate::problems::contact_time;
use crate::run::{RunError, SimulationBuilder};
use crate::scene::{bead_run, contact, Other};
use crate::units::{hertz_eta, hertz_eta_flat, Material};
use crate::Chain;
use std::ops::ControlFlow;

pub use crate::chain::material::Bead;

/// What the column protects, at its right end.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub enum Protected {
    /// A rigid flat wall of a material (the last bead touches it as a sphere on a flat).
    Wall(Material),
    /// A body of `mass` (kg) whose face is a flat of `material`, held by a linear spring of
    /// stiffness `spring` (N/m) to ground (0: a free body).
    Target {
        /// Mass, kg.
        mass: f64,
        /// The material of its face.
        material: Material,
        /// Stiffness of its spring to ground, N/m (0: none).
        spring: f64,
    },
}

/// The load: a striker sphere at a speed, and the contacts' dissipation.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Impact {
    /// The striker.
    pub striker: Bead,
    /// Its speed towards the column, m/s.
    pub speed: f64,
    /// The coefficient of restitution of every contact that `restitution_pairs` does not name
    /// (`None`: elastic), through the scale-respecting dashpot
    /// (`DampingModel::ScaleRespecting`), whose restitution is the same at every impact speed.
    pub restitution: Option<f64>,
    /// Pairs of materials with a restitution of their own (the first that names a contact's
    /// two materials sets it).
    pub restitution_pairs: Vec<PairRestitution>,
}

/// A pair of materials with a coefficient of restitution of its own (a contact of a bead, the
/// striker, the wall or the target's face of one with one of the other, in either order).
/// Materials are matched by name, so a bead whose constants the tolerances perturb keeps its
/// pair's restitution.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct PairRestitution {
    /// The two materials' names ([`Material::name`]; the same name twice: the material with
    /// itself).
    pub between: [&'static str; 2],
    /// Its coefficient of restitution, from 0.05 to 1 (1: elastic).
    pub restitution: f64,
}

impl Impact {
    /// The coefficient of restitution of a contact between materials `a` and `b` (`None`:
    /// elastic): the first pair naming both, else [`Impact::restitution`].
    pub fn restitution_between(&self, a: &Material, b: &Material) -> Option<f64> {
        match self.restitution_pairs.iter().find(|p| p.joins(a, b)) {
            Some(p) => (p.restitution < 1.0).then_some(p.restitution),
            None => self.restitution,
        }
    }

    /// Whether every contact is elastic (no dissipation anywhere).
    pub fn is_elastic(&self) -> bool {
        self.restitution.is_none() && self.restitution_pairs.iter().all(|p| p.restitution == 1.0)
    }
}

impl PairRestitution {
    /// Whether the pair names the materials of a contact between `a` and `b`.
    pub fn joins(&self, a: &Material, b: &Material) -> bool {
        self.names(a.name, b.name)
    }

    /// Whether it names the same two materials as `other`, in either order.
    pub fn same_pair(&self, other: &PairRestitution) -> bool {
        self.names(other.between[0], other.between[1])
    }

    fn names(&self, a: &str, b: &str) -> bool {
        let [x, y] = self.between;
        (x == a && y == b) || (x == b && y == a)
    }
}

/// Which quantity the run must get exactly; the run stops as soon as no later step can change
/// it ([`stop`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Need {
    /// The peak force on the protected face.
    Peak,
    /// The time at or above the fraction of the peak (and the peak).
    Duration,
    /// The impulse (and everything else): run until nothing can touch the face again.
    Everything,
}

/// How designs are evaluated.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Settings {
    /// What must be exact.
    pub need: Need,
    /// The fraction of the peak the duration counts above.
    pub fraction: f64,
    /// Velocity Verlet steps per contact time of the stiffest pair at the whole impact energy
    /// (the step is that contact time over this number).
    pub steps_per_contact: f64,
    /// Steps between two checks of the stop rule.
    pub check_every: u32,
    /// The integrator: a splitting method (verlet or blanes-moan4), which the load watch needs.
    pub method: Method,
    /// Cut the steps at contact events and locate the peak between steps
    /// ([`IntegrationParams::events`]).
    pub events: bool,
    /// The run ends at this many times the sum of every contact's time at the impact energy
    /// (about the time a wave takes to cross the column) if it has not stopped before
    /// ([`Evaluation::complete`] says whether it did).
    pub time_cap: f64,
    /// [`Need::Peak`] only: give up on a design whose peak reaches this force (N), as soon as
    /// the force on the face has fallen back below half its peak (the pulse that crossed it has
    /// passed): its peak is then at least [`Evaluation::peak_force`], which is all a search
    /// needs to know of a design worse than one it has (`f64::INFINITY`, the default: never).
    /// [`Evaluation::given_up`] says whether it happened.
    pub give_up_above: f64,
}

impl Default for Settings {
    /// The peak, duration above half of it, blanes-moan4 with contact events at 20 steps per
    /// contact time ([`steps_for_accuracy`] of [`DEFAULT_ACCURACY`]: the peak force to 5.7e-7 on
    /// the reference column, to 4.0e-5 on a column whose peak comes after many reflections; the
    /// table there), checks every 32 steps, a cap of 100 contact-time
    /// sums (enough to prove the peak of a column that traps its energy: 20 PTFE beads struck
    /// by steel, then 20 steel ones by the wall, `examples/protector.rs`).
    fn default() -> Self {
        Settings {
            need: Need::Peak,
            fraction: 0.5,
            steps_per_contact: steps_for_accuracy(DEFAULT_ACCURACY),
            check_every: 32,
            method: Method::BlanesMoan4,
            events: true,
            time_cap: 100.0,
            give_up_above: f64::INFINITY,
        }
    }
}

impl Settings {
    /// Whether a run may end where the stop rule's bound is `bound` ([`stop`]) and the peak
    /// so far is `peak`: what [`Settings::need`] asks for is final.
    pub(crate) fn ends(&self, bound: &stop::Bound, peak: f64) -> bool {
        match self.need {
            Need::Peak => bound.force < peak,
            Need::Duration => bound.force < self.fraction * peak,
            Need::Everything => bound.force == 0.0,
        }
    }

    /// Whether a run may give up at all ([`Settings::give_up_above`]: only one that needs the
    /// peak).
    pub(crate) fn may_give_up(&self) -> bool {
        self.need == Need::Peak && self.give_up_above.is_finite()
    }

    /// Whether a run that may give up does, with the peak `peak` so far and the protected
    /// contact's force `force` now (checked after [`Settings::ends`], which makes the peak
    /// exact when it can): the peak is past the bound and the force has fallen below half of
    /// it.
    pub(crate) fn gives_up(&self, peak: f64, force: f64) -> bool {
        peak >= self.give_up_above && force < 0.5 * peak
    }
}

/// What one run of a design found (SI units).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Evaluation {
    /// The largest force on the protected face over every step, N.
    pub peak_force: f64,
    /// When it happened, s.
    pub peak_time: f64,
    /// The force's integral up to the end of the run, N s (final when `need` is
    /// [`Need::Everything`] and the run is complete).
    pub impulse: f64,
    /// The time at or above `fraction` of the peak, s (final for [`Need::Duration`] and
    /// [`Need::Everything`]).
    pub duration: f64,
    /// The largest energy of the target body, J (0 for a wall; final for [`Need::Everything`]).
    pub target_energy: f64,
    /// The striker's velocity at the end, m/s (negative: it bounced back); final when
    /// `rebound_final`.
    pub rebound: f64,
    /// Whether the striker can no longer be touched (it left the column for good).
    pub rebound_final: bool,
    /// The column's mass, kg, and length (sum of diameters), m.
    pub mass: f64,
    /// The column's length, m.
    pub length: f64,
    /// The time reached, s, and the steps taken.
    pub time: f64,
    /// Steps taken.
    pub steps: u64,
    /// The step, s.
    pub dt: f64,
    /// Whether the stop rule ended the run (else the time cap did, or the run gave up).
    pub complete: bool,
    /// Whether the run gave up at [`Settings::give_up_above`]: the design's peak is then at
    /// least `peak_force` (the largest up to the time reached), not that peak itself.
    pub given_up: bool,
}

/// A design with its load and what it protects: the cases the benchmarks, the work-precision
/// study and the validation suite share, each built in one place.
#[derive(Clone, Debug, PartialEq)]
pub struct Case {
    /// The column, from the struck end to the protected one.
    pub beads: Vec<Bead>,
    /// The load.
    pub impact: Impact,
    /// What the column protects.
    pub protected: Protected,
}

impl Case {
    /// The issue-27 target case at `n` beads: `n / 2` steel beads then `n - n / 2` PTFE beads
    /// of 6 mm (the struck end first) against a steel wall, struck by a 6 mm steel sphere at
    /// 1 m/s, elastic contacts. At 40 beads it is the reference of `benches/protector.rs` and of
    /// `grainchain work-precision --only protector-40`.
    pub fn steel_then_ptfe(n: usize) -> Case {
        use crate::units::{PTFE, STEEL};
        const D: f64 = 6e-3;
        let steel = Bead {
            material: STEEL,
            diameter: D,
        };
        let ptfe = Bead {
            material: PTFE,
            diameter: D,
        };
        Case {
            beads: [vec![steel; n / 2], vec![ptfe; n - n / 2]].concat(),
            impact: Impact {
                striker: steel,
                speed: 1.0,
                restitution: None,
                restitution_pairs: Vec::new(),
            },
            protected: Protected::Wall(STEEL),
        }
    }

    /// [`evaluate`] the case with `settings`.
    pub fn evaluate(&self, settings: &Settings) -> Result<Evaluation, DesignError> {
        evaluate(&self.beads, &self.impact, &self.protected, settings)
    }
}

/// Why a design cannot be evaluated.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum DesignError {
    /// No beads.
    #[error("a design needs at least one bead")]
    Empty,
    /// A bead, the striker or the protected body with bad numbers.
    #[error("{what}: {problem}")]
    Bad {
        /// Which part (`bead 3`, `striker`, `wall`, `target`, `speed`, ...).
        what: String,
        /// What is wrong.
        problem: String,
    },
    /// The run failed (a blow-up, bad settings).
    #[error(transparent)]
    Run(#[from] RunError),
    /// The caller stopped the run ([`gradients_until`]).
    #[error("stopped by its caller before the end")]
    Stopped,
}

fn bad(what: impl Into<String>, problem: impl Into<String>) -> DesignError {
    DesignError::Bad {
        what: what.into(),
        problem: problem.into(),
    }
}

fn check_bead(what: String, b: &Bead) -> Result<(), DesignError> {
    match b.problem() {
        Some(p) => Err(bad(what, p)),
        None => Ok(()),
    }
}

/// A design laid out as a chain, with its step and time cap.
#[derive(Clone, Debug)]
pub struct Layout {
    /// The chain: a left striker (grain 0), the beads in runs of equal spheres, and the
    /// protected wall or target at the right.
    pub chain: Chain,
    /// The contact whose force is the load on the protected face.
    pub contact: usize,
    /// Whether the chain's last grain is a target body.
    pub target: bool,
    /// The step, s.
    pub dt: f64,
    /// The time cap, s.
    pub time_cap: f64,
    /// Mass and length of the column.
    pub mass: f64,
    /// Length of the column, m.
    pub length: f64,
}

/// Lay a design out as a chain ([`Layout`]).
fn layout(
    beads: &[Bead],
    impact: &Impact,
    protected: &Protected,
    settings: &Settings,
) -> Result<Layout, DesignError> {
    if beads.is_empty() {
        return Err(DesignError::Empty);
    }
    for (i, b) in beads.iter().enumerate() {
        check_bead(format!("bead {}", i + 1), b)?;
    }
    check_bead("striker".into(), &impact.striker)?;
    if !(impact.speed.is_finite() && impact.speed > 0.0) {
        return Err(bad(
            "speed",
            format!("must be a finite number > 0 m/s, got {}", impact.speed),
        ));
    }
    let energy = impact.energy();
    if !(energy > 0.0 && energy.is_finite()) {
        return Err(bad(
            "speed",
            format!(
                "{:e} m/s gives the striker an impact energy of {energy:e} J in double precision, \
                 so the contact times of the run are no finite numbers: give a physical speed",
                impact.speed
            ),
        ));
    }
    let e = |a: &Bead, b: &Material| impact.restitution_between(&a.material, b);
    // Every contact from the one function of the scenes' too (`scene::bead_run`,
    // `scene::contact`); the shortest contact time at the whole energy sets the step, the sum
    // of them the cap. `contacts`: how many contacts have this law (a run's inner ones: its
    // beads less one), each counted in the cap's sum.
    let (mut t_min, mut t_sum) = (f64::INFINITY, 0.0);
    let mut time = |c: &crate::scene::Contact, contacts: usize| {
        let tc = pair_time(c.eta, c.masses.0, c.masses.1, energy);
        if contacts > 0 {
            t_min = t_min.min(tc);
        }
        t_sum += contacts as f64 * tc;
        c.law
    };
    let mut builder = ChainBuilder::new();
    let mut prev: Option<Bead> = None;
    let mut i = 0;
    while i < beads.len() {
        let b = beads[i];
        let mut j = i + 1;
        while j < beads.len() && beads[j] == b {
            j += 1;
        }
        let joint = prev.and_then(|p| e(&p, &b.material));
        let run = bead_run(&b, prev.as_ref(), e(&b, &b.material), joint)?;
        let own = time(&run.inner, j - i - 1);
        let mut section = Section::new(format!("beads {}-{}", i + 1, j), j - i, run.mass, own);
        if let Some(joint) = &run.joint {
            section = section.with_joint(time(joint, 1));
        }
        builder = builder.section(section);
        prev = Some(b);
        i = j;
    }
    let first = beads[0];
    let s = impact.striker;
    let striker_law = time(
        &contact(&s, &Other::Bead(first), e(&s, &first.material))?,
        1,
    );
    builder = builder.striker(Striker {
        end: StrikerEnd::Left,
        mass: s.mass(),
        speed: impact.speed,
        law: Some(striker_law),
    });
    let last = *beads.last().expect("not empty");
    let (contact_of, target) = match *protected {
        Protected::Wall(m) => {
            if let Some(p) = m.problem() {
                return Err(bad("wall", p));
            }
            let wall = Other::Flat {
                material: m,
                mass: f64::INFINITY,
            };
            builder = builder.right(End::Wall(time(&contact(&last, &wall, e(&last, &m))?, 1)));
            (0, false)
        }
        Protected::Target {
            mass,
            material,
            spring,
        } => {
            if let Some(p) = material.problem() {
                return Err(bad("target", p));
            }
            if !(mass.is_finite() && mass > 0.0) {
                return Err(bad(
                    "target",
                    format!("mass must be a finite number > 0 kg, got {mass}"),
                ));
            }
            if !(spring.is_finite() && spring >= 0.0) {
                return Err(bad(
                    "target",
                    format!("spring must be a finite number >= 0 N/m, got {spring}"),
                ));
            }
            let face = time(
                &contact(&last, &Other::Flat { material, mass }, e(&last, &material))?,
                1,
            );
            builder = builder.section(Section::new("target", 1, mass, face).with_joint(face));
            if spring > 0.0 {
                builder = builder.right(End::Wall(ContactLaw::linear_spring(spring)));
            }
            (1, true)
        }
    };
    let chain = builder.build().map_err(|e| bad("design", e.to_string()))?;
    let n = chain.len();
    let (dt, time_cap) = (
        t_min / settings.steps_per_contact,
        settings.time_cap * t_sum,
    );
    // The refusal of `step_bound`, for the one design (a caller that skipped the bound of its
    // candidates, or picked its beads freely: Python's `evaluate`).
    if !(time_cap / dt <= MAX_EVALUATION_STEPS) {
        return Err(bad(
            "design",
            format!(
                "its run could take up to {:.3e} steps (contact times from {t_min:.3e} s to \
                 {:.3e} s in all), over the limit of {MAX_EVALUATION_STEPS:.0e}: beads of such \
                 different sizes or materials need a step far shorter than the run",
                time_cap / dt,
                t_sum
            ),
        ));
    }
    Ok(Layout {
        contact: n - contact_of,
        target,
        dt,
        time_cap,
        mass: beads.iter().map(Bead::mass).sum(),
        length: beads.iter().map(|b| b.diameter).sum(),
        chain,
    })
}

/// The most steps one evaluation may take: 1e8 (about 5 s of velocity Verlet on a 40-bead
/// column on the 2-core machine; the shipped designs' bounds are below 1e7). Beyond it a design
/// is refused before it runs (issue 38: a space of 1 um and 1 m diameters ran for minutes on
/// four designs with no word).
pub const MAX_EVALUATION_STEPS: f64 = 1e8;

/// The most force evaluations of the chain the finer run of a bound's run-on
/// ([`estimate_to_end`]) may take: 1e8, the step limit's cost in velocity Verlet (one
/// evaluation per step). Counted in evaluations, not steps, so that the run-on costs the same
/// for every method: a blanes-moan4 step is six evaluations
/// ([`crate::MethodInfo::evaluations_per_step`]), and counted in steps its run-on took six times
/// Verlet's (issue 48: 123 s of a 2-second search in `grainchain design`).
pub const MAX_RUN_ON_EVALUATIONS: f64 = 1e8;

/// The contact time of two grains of masses `m1`, `m2` (`m2` infinite: a wall) under Hertz's
/// constant `eta`, closing with the whole impact `energy` (the longest and the shortest the
/// evaluation allows for, [`layout`]).
fn pair_time(eta: f64, m1: f64, m2: f64, energy: f64) -> f64 {
    let mu = if m2.is_finite() {
        m1 * m2 / (m1 + m2)
    } else {
        m1
    };
    let v = (2.0 * energy / mu).sqrt();
    contact_time(1.5, eta, mu, v)
}

impl Impact {
    /// The striker's kinetic energy, J.
    pub fn energy(&self) -> f64 {
        0.5 * self.striker.mass() * self.speed * self.speed
    }
}

/// The most steps an evaluation with `settings` of any column of `beads` beads chosen from
/// `candidates` can take, struck as `impact` says in front of `protected` (without checking
/// them: [`evaluate`] does): the layout's step is the shortest contact time over
/// `steps_per_contact` and its run at most `time_cap` times the sum of the column's `beads + 1`
/// contact times, so the bound is `time_cap (beads + 1) t_max / t_min steps_per_contact`, with
/// `t_min` and `t_max` over every pair the column can hold (two candidates, the striker and a
/// candidate, a candidate and the protected face). Compare with [`MAX_EVALUATION_STEPS`]. NaN
/// where a contact time is no positive finite number (an impact energy that rounds to 0).
pub fn step_bound(
    candidates: &[Bead],
    beads: usize,
    impact: &Impact,
    protected: &Protected,
    settings: &Settings,
) -> f64 {
    let energy = impact.energy();
    let (mut t_min, mut t_max) = (f64::INFINITY, 0.0_f64);
    // A contact time that is no positive finite number (an impact energy that rounds to 0, a
    // target too light) makes the bound NaN: `min` and `max` would skip it.
    let mut finite = true;
    let mut pair = |eta: f64, m1: f64, m2: f64| {
        let t = pair_time(eta, m1, m2, energy);
        finite &= t > 0.0 && t.is_finite();
        t_min = t_min.min(t);
        t_max = t_max.max(t);
    };
    let s = impact.striker;
    for a in candidates {
        pair(
            hertz_eta(&s.material, s.diameter, &a.material, a.diameter),
            s.mass(),
            a.mass(),
        );
        if beads > 1 {
            for b in candidates {
                let eta = hertz_eta(&a.material, a.diameter, &b.material, b.diameter);
                pair(eta, a.mass(), b.mass());
            }
        }
        match *protected {
            Protected::Wall(m) => pair(
                hertz_eta_flat(&a.material, a.diameter, &m),
                a.mass(),
                f64::INFINITY,
            ),
            Protected::Target { mass, material, .. } => pair(
                hertz_eta_flat(&a.material, a.diameter, &material),
                a.mass(),
                mass,
            ),
        }
    }
    if !finite {
        return f64::NAN;
    }
    settings.time_cap * (beads as f64 + 1.0) * t_max / t_min * settings.steps_per_contact
}

/// Check the settings once.
fn check_settings(s: &Settings) -> Result<(), DesignError> {
    if !(s.fraction > 0.0 && s.fraction <= 1.0) {
        return Err(bad(
            "fraction",
            format!("must lie in (0, 1], got {}", s.fraction),
        ));
    }
    if !(s.steps_per_contact.is_finite() && s.steps_per_contact >= MIN_STEPS_PER_CONTACT) {
        return Err(bad(
            "steps_per_contact",
            format!("must be a finite number >= 4, got {}", s.steps_per_contact),
        ));
    }
    if s.check_every == 0 {
        return Err(bad("check_every", "must be at least 1"));
    }
    if s.give_up_above.is_nan() || s.give_up_above <= 0.0 {
        return Err(bad(
            "give_up_above",
            format!(
                "must be a force > 0 N (infinite: never give up), got {}",
                s.give_up_above
            ),
        ));
    }
    if !(s.time_cap.is_finite() && s.time_cap > 0.0) {
        return Err(bad(
            "time_cap",
            format!("must be a finite number > 0, got {}", s.time_cap),
        ));
    }
    Ok(())
}

/// The settings and the impact's restitution, checked once per call.
fn check(settings: &Settings, impact: &Impact) -> Result<(), DesignError> {
    check_settings(settings)?;
    if let Some(e) = impact.restitution.filter(|e| !(0.05..1.0).contains(e)) {
        return Err(bad(
            "restitution",
            format!("must lie in [0.05, 1) (leave it out for elastic contacts), got {e}"),
        ));
    }
    for (i, p) in impact.restitution_pairs.iter().enumerate() {
        let e = p.restitution;
        if !(0.05..=1.0).contains(&e) {
            return Err(bad(
                "restitution_pairs",
                format!(
                    "pair {} ({} and {}): must be a coefficient of restitution from 0.05 to 1 \
                     (elastic), got {e}",
                    i + 1,
                    p.between[0],
                    p.between[1]
                ),
            ));
        }
        if let Some(j) = impact.restitution_pairs[..i]
            .iter()
            .position(|q| q.same_pair(p))
        {
            return Err(bad(
                "restitution_pairs",
                format!(
                    "pairs {} and {} both name {} and {}: give each pair once",
                    j + 1,
                    i + 1,
                    p.between[0],
                    p.between[1]
                ),
            ));
        }
    }
    Ok(())
}

/// Evaluate one design (beads from the struck end to the protected one).
pub fn evaluate(
    beads: &[Bead],
    impact: &Impact,
    protected: &Protected,
    settings: &Settings,
) -> Result<Evaluation, DesignError> {
    check(settings, impact)?;
    run(beads, impact, protected, settings)
}

/// Evaluate many designs on `threads` threads ([`crate::worker_threads`]: at least 1, at most
/// one per design and what the machine runs at once): the results in input order, each the
/// same bits as [`evaluate`] of that design alone, at every thread count.
pub fn evaluate_many(
    designs: &[Vec<Bead>],
    impact: &Impact,
    protected: &Protected,
    settings: &Settings,
    threads: usize,
) -> Result<Vec<Result<Evaluation, DesignError>>, DesignError> {
    check(settings, impact)?;
    each_design(designs, threads, |d| run(d, impact, protected, settings))
}

/// `f` of every design on `threads` threads ([`crate::worker_threads`]), the results in input
/// order: what [`evaluate_many`], [`estimate_many`] and [`gradients_many`] share.
fn each_design<T: Send>(
    designs: &[Vec<Bead>],
    threads: usize,
    f: impl Fn(&[Bead]) -> Result<T, DesignError> + Sync,
) -> Result<Vec<Result<T, DesignError>>, DesignError> {
    use rayon::prelude::*;
    let pool =
        crate::thread_pool(threads, designs.len()).map_err(|e| bad("threads", e.to_string()))?;
    Ok(pool.install(|| designs.par_iter().map(|d| f(d)).collect()))
}

/// Lay out and run one design.
fn run(
    beads: &[Bead],
    impact: &Impact,
    protected: &Protected,
    settings: &Settings,
) -> Result<Evaluation, DesignError> {
    let lay = layout(beads, impact, protected, settings)?;
    let interval = lay.dt * f64::from(settings.check_every);
    let params = IntegrationParams {
        method: settings.method,
        dt: lay.dt,
        events: settings.events,
        ..Default::default()
    };
    let outputs = (lay.time_cap / interval).ceil().max(1.0);
    let mut sim = SimulationBuilder::new(lay.chain.clone())
        .params(params)
        .schedule(outputs * interval, interval)
        .build()?;
    sim.watch_load(lay.contact, settings.fraction, lay.target)?;
    let mut complete = false;
    let mut given_up = false;
    let mut striker_free = false;
    let give_up = settings.may_give_up();
    loop {
        let mut bound = None;
        let mut force = 0.0;
        let finished = sim.run_until(|fr| {
            bound = Some(stop::bound(fr.chain, fr.state, lay.contact));
            if give_up {
                force = crate::integrators::contact_force(fr.chain, fr.state, lay.contact);
            }
            ControlFlow::Break(())
        })?;
        let load = sim.load().expect("watched");
        if let Some(b) = bound {
            striker_free = b.striker_free;
            if settings.ends(&b, load.peak) {
                complete = true;
                break;
            }
        }
        if give_up && settings.gives_up(load.peak, force) {
            given_up = true;
            break;
        }
        if finished {
            break;
        }
    }
    let load = sim.load().expect("watched");
    let state = sim.state();
    Ok(Evaluation {
        peak_force: load.peak,
        peak_time: load.peak_time,
        impulse: load.impulse,
        duration: load.duration,
        target_energy: load.target_energy,
        rebound: state.v[0],
        rebound_final: striker_free,
        mass: lay.mass,
        length: lay.length,
        time: state.t,
        steps: sim.stats().steps,
        dt: sim.params().dt,
        complete,
        given_up,
    })
}

/// The chain a design makes (for a scene file or a plot of its run): [`Layout`].
pub fn lay_out(
    beads: &[Bead],
    impact: &Impact,
    protected: &Protected,
    settings: &Settings,
) -> Result<Layout, DesignError> {
    check(settings, impact)?;
    layout(beads, impact, protected, settings)
}

/// The force on the protected face at `samples + 1` evenly spaced times from 0 to `until`
/// seconds (for plots; the peak over every step is [`evaluate`]'s), as `(t, F)` pairs: the same
/// run as [`evaluate`]'s, its step fitted to the sampling interval.
pub fn force_history(
    beads: &[Bead],
    impact: &Impact,
    protected: &Protected,
    settings: &Settings,
    until: f64,
    samples: usize,
) -> Result<Vec<(f64, f64)>, DesignError> {
    check(settings, impact)?;
    if !(until.is_finite() && until > 0.0) || samples == 0 {
        return Err(bad(
            "force history",
            format!("needs a duration > 0 and samples >= 1, got {until} s and {samples}"),
        ));
    }
    let lay = layout(beads, impact, protected, settings)?;
    let params = IntegrationParams {
        method: settings.method,
        dt: lay.dt,
        events: settings.events,
        ..Default::default()
    };
    let mut sim = SimulationBuilder::new(lay.chain.clone())
        .params(params)
        .schedule(until, until / samples as f64)
        .build()?;
    let mut out = Vec::with_capacity(samples + 1);
    sim.run(|fr| {
        out.push((
            fr.state.t,
            crate::integrators::contact_force(fr.chain, fr.state, lay.contact),
        ));
        Ok::<(), RunError>(())
    })?;
    Ok(out)
}

/// The default relative accuracy of a protector's peak force (the design file's `[search]
/// accuracy`): [`steps_for_accuracy`] gives it 20 steps per contact time of the default method.
pub const DEFAULT_ACCURACY: f64 = 1e-5;

/// The accuracies [`steps_for_accuracy`] accepts: from 1e-9 (796 steps per contact time, its
/// estimate at 1592; finer is near the round-off of the peak, about 1e-12 after the thousands
/// of steps of a run) to 1e-2 (the rule's floor of 8 steps).
pub const ACCURACY_RANGE: [f64; 2] = [1e-9, 1e-2];

/// Why `accuracy` is no relative accuracy [`steps_for_accuracy`] takes, if it is not.
pub fn accuracy_problem(accuracy: f64) -> Option<String> {
    let [lo, hi] = ACCURACY_RANGE;
    (!(accuracy.is_finite() && (lo..=hi).contains(&accuracy))).then(|| {
        format!(
            "must be a relative error of the peak force in [{lo:e}, {hi:e}] (default \
             {DEFAULT_ACCURACY:e}), got {accuracy}"
        )
    })
}

/// The fewest steps per contact time a run may take (`Settings::steps_per_contact`).
pub(crate) const MIN_STEPS_PER_CONTACT: f64 = 4.0;

/// The steps per contact time of the default method (blanes-moan4 with contact events, the peak
/// located between steps) for a relative `accuracy` of the peak force: `20 (1e-5 /
/// accuracy)^(2/5)`, at least 8 (order 2.5, the Hertz force's `(t - t*)^(3/2)` from each closing
/// instant, `integrators/events.rs`). Its constant meets 1e-5 on the reference column
/// ([`Case::steel_then_ptfe`]`(40)`) with room (5.7e-7 at 20; 8.6e-6 at 10) at 0.78 times the
/// cost of velocity Verlet at 160 steps, the default before events (1.63 ms against 2.09 ms, one
/// process, medians of 15 rounds of 20); on other columns the same step gives more (below), so
/// the rule is a target, not a guarantee, and every number a design search reports comes with
/// its own error ([`estimate`]), which tells.
///
/// Measured relative error of the peak force against blanes-moan4 with events at 2560 steps
/// per contact time (its own error, from 1280, column by column: 3e-11, 2e-11, 2e-9, 3e-7), `[x]`: a run that
/// reached its time cap (a lower bound on the peak, compared as such), 2026-11-27, `cargo run
/// --release --example protector_accuracy` (and `-- verlet` for the second table):
///
/// | steps per contact | protector-40 | 40 steel 6 mm | steel-ptfe.toml's best | multi-material.toml's best |
/// |---|---|---|---|---|
/// | 10 | 8.6e-6 | 6.6e-5 | [1.1e-4] | [4.1e-2] |
/// | 14 | 5.7e-6 | 7.4e-5 | [1.0e-4] | [1.2e-3] |
/// | **20** | **5.7e-7** | 1.5e-5 | 4.0e-5 | [1.1e-2] |
/// | 28 | 4.7e-7 | 2.7e-6 | [1.3e-5] | [7.5e-4] |
/// | 40 | 1.9e-7 | 3.1e-6 | [4.8e-6] | [8.3e-4] |
/// | 56 | 1.1e-7 | 5.9e-7 | [7.2e-7] | [2.6e-4] |
/// | 80 | 4.5e-8 | 4.5e-8 | 8.7e-7 | 1.0e-4 |
/// | 160 | 7.5e-9 | 7.8e-9 | 8.8e-8 | [2.5e-6] |
/// | 320 | 1.6e-9 | 1.3e-9 | [3.2e-8] | 4.5e-6 |
///
/// Velocity Verlet without events, against blanes-moan4 at 2560 without events (the table of
/// the default before events):
///
/// | steps per contact | protector-40 | 40 steel 6 mm | steel-ptfe.toml's best | multi-material.toml's best |
/// |---|---|---|---|---|
/// | 40 | 1.8e-4 | 1.2e-4 | 5.9e-2 | 4.8e-2 |
/// | 80 | 3.9e-5 | 1.1e-4 | [1.4e-2] | 3.5e-2 |
/// | **160** | **6.3e-6** | 2.8e-5 | 3.5e-3 | [4.7e-2] |
/// | 320 | 2.2e-6 | 6.9e-6 | 8.7e-4 | [3.5e-2] |
/// | 1280 | 1.4e-7 | 4.2e-7 | [5.4e-5] | [6.7e-3] |
///
/// Error times steps^2.5 stays within 1e-3 to 4e-3 on the reference column; the steel column
/// needs about 25 steps for 1e-5, steel-ptfe's best (whose peak comes after many reflections)
/// about 40, where velocity Verlet needed 270 and 3000. Multi-material's best traps its energy
/// and its largest force up to the cap moved by percents with Verlet's step, with no convergence
/// by 1280; with events it converges (1e-4 at 80, a few 1e-6 from 160: about 150 for 1e-5). Impulse and duration are
/// final on none of the references (their runs reach the cap), so no row of them is stated.
pub fn steps_for_accuracy(accuracy: f64) -> f64 {
    (20.0 * (DEFAULT_ACCURACY / accuracy).powf(0.4)).max(8.0)
}

/// One design evaluated three times, at twice the settings' step, at it and at half of it: the
/// finest run's numbers, with the larger of the two differences between neighbouring runs as
/// their error. In the asymptotic range of a method of order `p >= 2` the middle run's error is
/// about `2^p` times the finest's, so `|fine - coarse|` alone (about `2^p - 1` times the
/// finest's error) would do; but a Hertz contact's peak converges erratically at these steps
/// (the force grows as `(t - t*)^(3/2)` where a contact closes, wherever that falls in a step),
/// and one difference can be small by chance while the finest run is further off than it (3.6
/// times on issue 50's stainless-steel and PTFE space). The larger of two differences bounds the
/// error on both brute-forced four-bead spaces, the worst at 0.31 of it (`validation/
/// protector_reference.rs`, against an integration written without engine code). The duration,
/// counted in whole steps, adds the middle run's step ([`Estimate::duration_error`]). A peak after
/// hundreds of reflections moves by percents with the step, and the differences are then a
/// sample of that scatter, not a bound: the calibration of [`steps_for_accuracy`] shows where.
/// At the settings' least steps (4 per contact time) the coarsest run is the middle one, and
/// the error is one difference.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Estimate {
    /// The run at twice the settings' steps per contact time: the numbers to report.
    pub value: Evaluation,
    /// The run at the settings' steps per contact time.
    pub coarse: Evaluation,
    /// The run at half the settings' steps per contact time (at least 4).
    pub coarsest: Evaluation,
    /// The larger of `|value - coarse|` and `|coarse - coarsest|` of the peak force, N.
    pub peak_error: f64,
    /// Of the impulse likewise, N s, when the impulse is final (`need` is [`Need::Everything`]
    /// and every run is complete); `None`: the impulse is the integral up to the end of the run
    /// only, no final number.
    pub impulse_error: Option<f64>,
    /// The duration's error, s, when it is final (`need` [`Need::Duration`] or
    /// [`Need::Everything`], every run complete; else `None`): the differences' larger plus the
    /// middle run's step. The duration counts whole steps ([`crate::Load::duration`]), so it is
    /// off by up to one step per interval the force spends above the level, an error of order
    /// 1 that the differences of the runs can miss (all may count the same time); the middle
    /// step is two of the finest run's, which covers two such intervals.
    pub duration_error: Option<f64>,
    /// Whether the peak is only a lower bound: a run reached its time cap (or gave up) before
    /// the stop rule proved it, so the true peak is at least the value's peak less its error
    /// ([`Estimate::reported`]).
    pub bound: bool,
    /// The time cap the runs had, in sums of the contact times ([`Settings::time_cap`]; more
    /// than the settings' after [`estimate_to_end`] extended it).
    pub time_cap: f64,
}

impl Estimate {
    /// The numbers to report: the finest run's, and for a lower bound its peak less its error,
    /// so that the true peak is at least it (the largest force up to the cap is computed to
    /// within the error, either way).
    pub fn reported(&self) -> Evaluation {
        let mut e = self.value;
        if self.bound {
            e.peak_force -= self.peak_error;
        }
        e
    }
}

/// [`evaluate`] a design at `settings` and at twice its steps per contact time: [`Estimate`].
pub fn estimate(
    beads: &[Bead],
    impact: &Impact,
    protected: &Protected,
    settings: &Settings,
) -> Result<Estimate, DesignError> {
    check(settings, impact)?;
    run_estimate(beads, impact, protected, settings)
}

fn run_estimate(
    beads: &[Bead],
    impact: &Impact,
    protected: &Protected,
    settings: &Settings,
) -> Result<Estimate, DesignError> {
    let at = |factor: f64| Settings {
        steps_per_contact: (factor * settings.steps_per_contact).max(MIN_STEPS_PER_CONTACT),
        ..*settings
    };
    // The runs side by side when threads are free (a long run to the step limit is the tail of
    // a batch): each is the same bits on any thread.
    let ((coarsest, coarse), value) = rayon::join(
        || {
            rayon::join(
                || run(beads, impact, protected, &at(0.5)),
                || run(beads, impact, protected, settings),
            )
        },
        || run(beads, impact, protected, &at(2.0)),
    );
    let (coarsest, coarse, value) = (coarsest?, coarse?, value?);
    let complete = coarsest.complete && coarse.complete && value.complete;
    let error = |f: fn(&Evaluation) -> f64| {
        (f(&value) - f(&coarse))
            .abs()
            .max((f(&coarse) - f(&coarsest)).abs())
    };
    let need = settings.need;
    Ok(Estimate {
        value,
        coarse,
        coarsest,
        peak_error: error(|e| e.peak_force),
        impulse_error: (complete && need == Need::Everything).then(|| error(|e| e.impulse)),
        duration_error: (complete && need != Need::Peak).then(|| error(|e| e.duration) + coarse.dt),
        bound: !complete,
        time_cap: settings.time_cap,
    })
}

/// [`estimate`], and while its peak is a bound (a run reached the time cap), again at ten times
/// the cap, up to the cap at which the finer run may take [`MAX_RUN_ON_EVALUATIONS`] force
/// evaluations (or [`MAX_EVALUATION_STEPS`] steps, whichever is fewer): the
/// estimate that ended by the stop rule, or the one at the longest cap, still a bound. A run
/// that gave up ([`Settings::give_up_above`]) is not extended.
pub fn estimate_to_end(
    beads: &[Bead],
    impact: &Impact,
    protected: &Protected,
    settings: &Settings,
) -> Result<Estimate, DesignError> {
    check(settings, impact)?;
    run_estimate_to_end(beads, impact, protected, settings)
}

fn run_estimate_to_end(
    beads: &[Bead],
    impact: &Impact,
    protected: &Protected,
    settings: &Settings,
) -> Result<Estimate, DesignError> {
    let mut est = run_estimate(beads, impact, protected, settings)?;
    let fine = Settings {
        steps_per_contact: 2.0 * settings.steps_per_contact,
        ..*settings
    };
    let lay = layout(beads, impact, protected, &fine)?;
    // The cap whose fine run takes the step limit or the run-on's force evaluations, whichever
    // comes first, a hair under it so rounding cannot pass it.
    let evaluations = f64::from(settings.method.information().evaluations_per_step);
    let steps = MAX_EVALUATION_STEPS.min(MAX_RUN_ON_EVALUATIONS / evaluations);
    let longest = settings.time_cap * steps / (lay.time_cap / lay.dt) * (1.0 - 1e-9);
    let mut cap = settings.time_cap;
    while est.bound && !est.value.given_up && !est.coarse.given_up && cap < longest {
        cap = (cap * 10.0).min(longest);
        let longer = Settings {
            time_cap: cap,
            ..*settings
        };
        est = run_estimate(beads, impact, protected, &longer)?;
    }
    Ok(est)
}

/// [`estimate`] (or, with `to_end`, [`estimate_to_end`]) many designs on `threads` threads, as
/// [`evaluate_many`] does: the results in input order, each the same bits as the design's
/// estimate alone.
pub fn estimate_many(
    designs: &[Vec<Bead>],
    impact: &Impact,
    protected: &Protected,
    settings: &Settings,
    threads: usize,
    to_end: bool,
) -> Result<Vec<Result<Estimate, DesignError>>, DesignError> {
    estimate_many_ticking(
        designs,
        impact,
        protected,
        settings,
        (threads, to_end),
        &|| {},
    )
}

/// [`estimate_many`], calling `tick` as each design's estimate finishes (a progress bar's step;
/// from the worker threads, in the order they finish).
pub fn estimate_many_ticking(
    designs: &[Vec<Bead>],
    impact: &Impact,
    protected: &Protected,
    settings: &Settings,
    (threads, to_end): (usize, bool),
    tick: &(dyn Fn() + Sync),
) -> Result<Vec<Result<Estimate, DesignError>>, DesignError> {
    check(settings, impact)?;
    each_design(designs, threads, |d| {
        let r = if to_end {
            run_estimate_to_end(d, impact, protected, settings)
        } else {
            run_estimate(d, impact, protected, settings)
        };
        tick();
        r
    })
}
