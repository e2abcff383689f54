//! The exact derivatives of a protector's evaluation: of the peak force on the protected face,
//! the impulse, the time above the fraction, the target's energy and the rebound, with respect
//! to every bead's diameter, density, Young's modulus and Poisson ratio and to the striker's
//! speed and mass, for the discrete run as [`super::evaluate`] takes it (the same layout, step,
//! method, contact events, located peak and stop rule).
//!
//! **Two routes through one run.** [`gradients`] records the run (values only, the same
//! stages and event cuts) and sweeps back through it once, carrying the adjoints of the numbers
//! it reports (`super::adjoint`): its cost is a few evaluations whatever the column's length.
//! [`gradients_forward`] repeats the run with, beside each position and velocity, its
//! derivatives with respect to the run's own inputs: each grain's mass, each contact's Hertz
//! constant, the striker's speed and the step (`2 n + 4` slots for `n` grains). Both take the
//! splitting methods' one step (`integrators::stages`, the same function a scene's run takes,
//! here over [`Tangent`], a carrier of the values and, in forward mode, their tangents) and
//! their one cut at events (`integrators::cut_at_events`), and end by the evaluation's stop rule
//! ([`Settings::ends`]); a piece of a step cut at a contact event carries its length's
//! derivative, from the implicit function theorem on the overlap polynomial whose root the
//! event is (`dtau = -dP(tau) / P'(tau)`); the located peak (the parabola through three steps'
//! forces) carries its own. At the end the run's inputs are mapped onto the beads' properties in
//! closed form (a sphere's mass, Hertz's constant, the contact time that sets the step). Forward
//! mode keeps no trajectory and its cost grows with the inputs (about `2 n` passes); it is the
//! reverse run's oracle (the two agree to rounding: the tests below, `validation/`).
//!
//! **What is not differentiable.** The duration counts whole steps: its derivative is that of
//! the step alone (the count is piecewise constant). The step is the shortest contact time over
//! the steps per contact: where several contacts share it (a column of equal beads), its
//! derivative is that of the first. A peak that two instants share within rounding ([`TIE`])
//! has no derivative: [`Gradients::tie`] gives the other instant's slope beside the first's.
//! Damped contacts (a restitution) are refused.

use super::adjoint::{
    eta_slot, mass_slot, Checkpoint, Contacts, Lane, Outputs, Src, Tape, SPEED, STEP,
};
use super::{bad, check, layout, pair_time, stop, Bead, DesignError, Evaluation, Impact};
use super::{Protected, Settings};
use crate::chain::{Chain, Window};
use crate::integrators::{cut_at_events, whole, Above, Cuts, Events, Flows, Parabola, Splitting};
use crate::state::State;
use crate::units::Material;

/// The most memory a run with derivatives may take: 1 GB, the guard of `grainchain run`. The
/// reverse run ([`gradients`]) keeps the positions and velocities of its grains at the start of
/// every piece of every step up to 128 MB, then a checkpoint every 256 steps from which the sweep
/// back runs each segment again (`super::adjoint::Tape`): its bound counts the checkpoints up to
/// the time cap and a segment's record, and the run stops if events cut more pieces than
/// counted. Forward mode
/// ([`gradients_forward`]) carries `2 n + 4` derivatives beside each grain's position, velocity
/// and acceleration and each contact's force (`4 n (2 n + 4)` doubles): about 3,900 grains.
pub const MAX_GRADIENT_BYTES: f64 = 1e9;

/// The most work the reverse run ([`gradients`]) may take, counted as steps times grains at
/// the time cap (an upper bound: the stop rule may end the run sooner): 1e9, some 4 minutes at
/// the 240 ns per grain-step measured (300 random steel and PTFE beads at a cap of 3
/// contact-time sums: 65,760 steps in 4.8 s, 2026-11-29, the 2-core machine), a third more
/// where the run is long enough to keep checkpoints (`super::adjoint::FULL_BYTES`).
pub const MAX_GRADIENT_GRAIN_STEPS: f64 = 1e9;

/// The pieces per step the reverse run's bound on its record counts: contact events cut a step
/// of a long column into 1.5 to 2 pieces on average (random steel and PTFE columns of 100, 200
/// and 300 beads at a cap of 3 contact-time sums: 1.48, 1.78 and 2.03; the reference column
/// 1.10), and the bound leaves room above that.
const PIECES_PER_STEP: f64 = 2.5;

/// The most work forward mode ([`gradients_forward`]) may take, counted as steps times grains
/// times derivative slots at the time cap (`time_cap / dt * n * (2 n + 4)`, an upper bound: the stop rule may
/// end the run sooner): 3e10, some 2.5 to 4 minutes on one core at the 4.8 to 7.2 ns per unit
/// measured on random steel and PTFE columns of 100 and 200 beads (2026-11-29, the 2-core
/// machine: 200 beads at a cap of 3 contact-time sums took 48,288 steps, 3.9e9 units, in 28 s;
/// 8.7 to 12.8 ns per unit before the changes of that day). The cost grows as `n^3`, so
/// a gradient past it is refused before it starts (issue 49: 40,000 beads aborted Python on a
/// 25 GB allocation).
pub const MAX_GRADIENT_WORK: f64 = 3e10;

/// Two candidate peaks closer than this relative difference are one peak reached twice
/// ([`Gradients::tie`]): far above the rounding a run of thousands of steps accumulates in a
/// force (about 1e-13 of it), far below any physical difference of two pulses.
pub const TIE: f64 = 1e-12;

/// The derivatives of one number with respect to each bead's properties (struck end first)
/// and the striker's speed and mass, in SI units (the number's unit per m, per kg/m^3, per Pa,
/// per unit of Poisson ratio, per m/s, per kg).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct Derivatives {
    /// With respect to each bead's diameter.
    pub diameter: Vec<f64>,
    /// With respect to each bead's density.
    pub density: Vec<f64>,
    /// With respect to each bead's Young's modulus.
    pub young: Vec<f64>,
    /// With respect to each bead's Poisson ratio.
    pub poisson: Vec<f64>,
    /// With respect to the striker's speed.
    pub speed: f64,
    /// With respect to the striker's mass (its density, at its diameter).
    pub striker_mass: f64,
}

/// Another instant whose force equals the peak within [`TIE`]: the peak is the larger of two
/// branches there, with a slope for each.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Tie {
    /// The other instant, s.
    pub time: f64,
    /// Its force, N.
    pub force: f64,
    /// The derivatives of its force.
    pub peak: Derivatives,
}

/// A design's evaluation with the derivatives of its numbers ([`gradients`]).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Gradients {
    /// The evaluation (the same numbers as [`super::evaluate`]'s, to rounding: the run is
    /// repeated with its derivatives).
    pub evaluation: Evaluation,
    /// Of the peak force, N.
    pub peak: Derivatives,
    /// Of the impulse up to the end of the run, N s.
    pub impulse: Derivatives,
    /// Of the time above the fraction, s (whole steps: the step's derivative times their
    /// count).
    pub duration: Derivatives,
    /// Of the target's largest energy, J (zero for a wall).
    pub target_energy: Derivatives,
    /// Of the striker's final velocity, m/s.
    pub rebound: Derivatives,
    /// A second instant that reaches the peak within [`TIE`], if any: `peak` is then one
    /// branch's slope, this the other's.
    pub tie: Option<Tie>,
    /// Whether several contacts share the shortest contact time that sets the step (a column
    /// of equal beads): the step is then the minimum of equal branches, and its part of every
    /// derivative (of the size of the method's error's derivative) is the first contact's.
    pub step_shared: bool,
}

/// [`super::evaluate`] one design with the derivatives of its numbers ([`Gradients`]).
pub fn gradients(
    beads: &[Bead],
    impact: &Impact,
    protected: &Protected,
    settings: &Settings,
) -> Result<Gradients, DesignError> {
    gradients_until(beads, impact, protected, settings, &mut || true)
}

/// [`gradients`], asking `keep_going` at every check of the stop rule (every
/// `settings.check_every` steps) whether to go on: when it says no, the run ends with
/// [`DesignError::Stopped`]. For a caller that must answer an interrupt within a second (Python's
/// Ctrl-C): a run with derivatives of a long column takes minutes.
pub fn gradients_until(
    beads: &[Bead],
    impact: &Impact,
    protected: &Protected,
    settings: &Settings,
    keep_going: &mut dyn FnMut() -> bool,
) -> Result<Gradients, DesignError> {
    check(settings, impact)?;
    run_gradients(
        beads,
        impact,
        protected,
        settings,
        keep_going,
        Mode::Reverse,
    )
}

/// [`gradients`] by forward mode: every input's tangent carried through the run beside its
/// values (`2 n + 4` of them for `n` grains), so its cost grows with the column's length. It
/// differentiates the same run by another route, and is the reverse run's oracle: the two
/// agree to rounding (`protector::gradient`'s tests, `validation/protector.rs`).
pub fn gradients_forward(
    beads: &[Bead],
    impact: &Impact,
    protected: &Protected,
    settings: &Settings,
) -> Result<Gradients, DesignError> {
    check(settings, impact)?;
    run_gradients(
        beads,
        impact,
        protected,
        settings,
        &mut || true,
        Mode::Forward,
    )
}

/// [`gradients`] of many designs on `threads` threads (as [`super::evaluate_many`]): results in
/// input order, each the same bits as the design's alone.
pub fn gradients_many(
    designs: &[Vec<Bead>],
    impact: &Impact,
    protected: &Protected,
    settings: &Settings,
    threads: usize,
) -> Result<Vec<Result<Gradients, DesignError>>, DesignError> {
    check(settings, impact)?;
    super::each_design(designs, threads, |d| {
        run_gradients(d, impact, protected, settings, &mut || true, Mode::Reverse)
    })
}

/// `y[..] += a x[..]` over the first `len` slots.
#[inline(always)]
fn axpy(y: &mut [f64], a: f64, x: &[f64]) {
    for (y, x) in y.iter_mut().zip(x) {
        *y += a * x;
    }
}

/// The forward-mode run: the state with its tangents (row `i` of `du`, `dv`, `da`: grain `i`'s
/// derivatives; row `k` of `df`: contact `k`'s).
struct Tangent {
    n: usize,
    /// Slots per row.
    p: usize,
    /// Slots possibly nonzero so far (the rest stay 0 until the wave reaches their grains).
    live: usize,
    /// The last grain the wave has reached (grains beyond are at rest with zero tangents).
    front: usize,
    inv_m: Vec<f64>,
    contacts: Contacts,
    state: State,
    du: Vec<f64>,
    dv: Vec<f64>,
    a: Vec<f64>,
    da: Vec<f64>,
    f: Vec<f64>,
    df: Vec<f64>,
    /// Whether the current piece is a step cut at an event (its length's tangent is `dh`) or
    /// the grid's step (slot [`STEP`]).
    cut: bool,
    dh: Vec<f64>,
    /// Rows known to hold only zeros: contact `k`'s (`df`: it has had no force since) and
    /// grain `i`'s (`da`: neither of its contacts pushes it). A grain between two open contacts
    /// (half of the grain-stages of the reference column) then takes no pass over its
    /// tangents in its acceleration and kick: adding `x * 0` to them changes no number, since
    /// no tangent is ever `-0` (every row starts at `+0` and is only added to, or set to a
    /// positive slope or inverse mass times a difference, so a `-0` would need one already).
    df_zero: Vec<bool>,
    da_zero: Vec<bool>,
}

impl Tangent {
    /// With `tangents` the run carries every slot; without, it carries the values alone
    /// (`p = 0`: the reverse run's forward pass, `super::adjoint`).
    fn new(chain: &Chain, tangents: bool) -> Self {
        let n = chain.len();
        let p = if tangents { 2 * n + 4 } else { 0 };
        let mut state = State::at_rest(n);
        let (striker, speed) = chain.striker().expect("a protector has a striker");
        state.v[striker] = speed;
        debug_assert_eq!(striker, 0);
        let mut t = Tangent {
            n,
            p,
            live: p.min(eta_slot(2) + 1),
            front: 0,
            inv_m: chain.mass().iter().map(|m| 1.0 / m).collect(),
            contacts: Contacts::new(chain),
            state,
            du: vec![0.0; n * p],
            dv: vec![0.0; n * p],
            a: vec![0.0; n],
            da: vec![0.0; n * p],
            f: vec![0.0; n + 1],
            df: vec![0.0; (n + 1) * p],
            cut: false,
            dh: vec![0.0; p],
            df_zero: vec![true; n + 1],
            da_zero: vec![true; n],
        };
        if p > 0 {
            t.dv[SPEED] = 1.0;
        }
        t.forces();
        t
    }

    /// The values-only run (`p = 0`) set back to a checkpoint: positions and velocities up to
    /// the front (the rest at rest), and the forces and accelerations there.
    fn restore(&mut self, u: &[f64], v: &[f64], front: usize) {
        debug_assert_eq!(self.p, 0);
        let m = u.len();
        self.state.u.iter_mut().for_each(|x| *x = 0.0);
        self.state.v.iter_mut().for_each(|x| *x = 0.0);
        self.state.u[..m].copy_from_slice(u);
        self.state.v[..m].copy_from_slice(v);
        self.front = front;
        self.forces();
    }

    /// Forces and accelerations (with their tangents) at the current positions, up to the
    /// contact beyond the front (the start of the run; a stage takes them in its own sweep).
    fn forces(&mut self) {
        let n = self.n;
        loop {
            for k in 0..=(self.front + 1).min(n) {
                self.force(k);
            }
            // The wave reached the grain beyond the front: widen, and evaluate again (its
            // contact beyond may close only in a later stage, but its forces must be current).
            if !self.widen() {
                break;
            }
        }
        for i in 0..=self.front.min(n - 1) {
            self.accelerate(i);
        }
    }

    /// Contact `k`'s force and its tangent (row `k` of `df`) at the current positions.
    #[inline(always)]
    fn force(&mut self, k: usize) {
        let (n, p, live) = (self.n, self.p, self.live);
        let Some((force, slope)) = self.contacts.force(&self.state.u, k) else {
            return;
        };
        self.f[k] = force;
        if p == 0 {
            return;
        }
        let dk = &mut self.df[k * p..k * p + live];
        if force == 0.0 {
            if !self.df_zero[k] {
                dk.iter_mut().for_each(|x| *x = 0.0);
                self.df_zero[k] = true;
            }
            return;
        }
        self.df_zero[k] = false;
        // dF = F'(delta) d(delta) + (F / eta) d(eta), one pass over the slots.
        let row = |i: usize| &self.du[i * p..i * p + live];
        match (k > 0, k < n) {
            (true, true) => {
                for ((d, l), r) in dk.iter_mut().zip(row(k - 1)).zip(row(k)) {
                    *d = slope * (l - r);
                }
            }
            (true, false) => {
                for (d, l) in dk.iter_mut().zip(row(k - 1)) {
                    *d = slope * l;
                }
            }
            (false, true) => {
                for (d, r) in dk.iter_mut().zip(row(k)) {
                    *d = -slope * r;
                }
            }
            (false, false) => dk.iter_mut().for_each(|x| *x = 0.0),
        }
        dk[eta_slot(k)] += force / self.contacts.eta(k);
    }

    /// After contact `front + 1`'s force: whether it pushes the grain beyond the front, which
    /// then joins the moving grains (the slots widen to its contacts). The slots that widen are
    /// 0 in every row (nothing has depended on them yet), and stay so in the rows a stage took
    /// before.
    #[inline(always)]
    fn widen(&mut self) -> bool {
        if self.front + 1 < self.n && self.f[self.front + 1] != 0.0 {
            self.front += 1;
            self.live = self.p.min(eta_slot(self.front + 2) + 1);
            true
        } else {
            false
        }
    }

    /// Grain `i`'s acceleration and its tangent (row `i` of `da`) from its contacts' forces.
    #[inline(always)]
    fn accelerate(&mut self, i: usize) {
        let (p, live) = (self.p, self.live);
        let im = self.inv_m[i];
        let acc = (self.f[i] - self.f[i + 1]) * im;
        self.a[i] = acc;
        if p == 0 {
            return;
        }
        // Both contacts without force: their rows are zero, and so is this one.
        if self.df_zero[i] && self.df_zero[i + 1] {
            if !self.da_zero[i] {
                self.da[i * p..i * p + live]
                    .iter_mut()
                    .for_each(|x| *x = 0.0);
                self.da_zero[i] = true;
            }
            return;
        }
        self.da_zero[i] = false;
        let (l, r) = (
            &self.df[i * p..i * p + live],
            &self.df[(i + 1) * p..(i + 1) * p + live],
        );
        let da = &mut self.da[i * p..i * p + live];
        for ((d, l), r) in da.iter_mut().zip(l).zip(r) {
            *d = (l - r) * im;
        }
        // d(1/m) = -dm / m^2.
        da[mass_slot(i)] -= acc * im;
    }

    /// The grains that move (up to the front).
    fn moving(&self) -> usize {
        (self.front + 1).min(self.n)
    }

    /// The next piece: the grid's step (`None`) or a piece cut at an event whose length has
    /// the tangent `dh`.
    fn set_piece(&mut self, dh: Option<&[f64]>) {
        self.cut = dh.is_some();
        if let Some(dh) = dh {
            self.dh.copy_from_slice(dh);
        }
    }

    /// Grain `i` drifts by `c h` (`h` the piece's length, its tangent
    /// [`Tangent::set_piece`]'s).
    #[inline(always)]
    fn drift(&mut self, i: usize, c: f64, h: f64) {
        let (p, live) = (self.p, self.live);
        let v = self.state.v[i];
        self.state.u[i] += c * h * v;
        if p == 0 {
            return;
        }
        let (du, dv) = (
            &mut self.du[i * p..i * p + live],
            &self.dv[i * p..i * p + live],
        );
        axpy(du, c * h, dv);
        match self.cut {
            false => du[STEP] += c * v,
            true => axpy(du, c * v, &self.dh[..live]),
        }
    }

    /// Grain `i` is kicked by `c h` with its current acceleration.
    #[inline(always)]
    fn kick_grain(&mut self, i: usize, c: f64, h: f64) {
        let (p, live) = (self.p, self.live);
        let a = self.a[i];
        self.state.v[i] += c * h * a;
        if p == 0 || self.da_zero[i] {
            // `a` is 0 too: every tangent would take `+-0`.
            return;
        }
        let (dv, da) = (
            &mut self.dv[i * p..i * p + live],
            &self.da[i * p..i * p + live],
        );
        axpy(dv, c * h, da);
        match self.cut {
            false => dv[STEP] += c * a,
            true => axpy(dv, c * a, &self.dh[..live]),
        }
    }

    /// The tangent of an event's instant `tau` at contact `k`: the root of the overlap
    /// polynomial `x0 + x1 t + x2 t^2` ([`Events`]), moved by its coefficients' tangents.
    fn event_tangent(&self, k: usize, tau: f64, out: &mut [f64]) {
        let (n, p, live) = (self.n, self.p, self.live);
        let (u, v) = (&self.state.u, &self.state.v);
        let side = |i: Option<usize>| match i {
            Some(i) => (u[i], v[i], self.a[i]),
            None => (0.0, 0.0, 0.0),
        };
        let (l, r) = (k.checked_sub(1), (k < n).then_some(k));
        let ((_, vl, al), (_, vr, ar)) = (side(l), side(r));
        let slope = (vl - vr) + 2.0 * 0.5 * (al - ar) * tau;
        out.iter_mut().for_each(|x| *x = 0.0);
        let mut add = |i: Option<usize>, sign: f64| {
            if let Some(i) = i {
                let row = i * p..i * p + live;
                let c = -sign / slope;
                axpy(&mut out[..live], c, &self.du[row.clone()]);
                axpy(&mut out[..live], c * tau, &self.dv[row.clone()]);
                axpy(&mut out[..live], c * 0.5 * tau * tau, &self.da[row]);
            }
        };
        add(l, 1.0);
        add(r, -1.0);
    }
}

/// The splitting methods' step ([`crate::integrators::stages`]) carried with tangents: every
/// stage's drift, forces and kick by the chain rule. Each piece closes (no fused kicks).
impl Flows for Tangent {
    #[inline(always)]
    fn kick(&mut self, c: f64, h: f64) {
        if self.p == 0 {
            let m = self.moving();
            for (v, a) in self.state.v[..m].iter_mut().zip(&self.a[..m]) {
                *v += c * h * a;
            }
            return;
        }
        for i in 0..self.moving() {
            self.kick_grain(i, c, h);
        }
    }

    /// One sweep grain by grain, as the f64 sweeps take a stage: grain `j` drifts, contact `j`
    /// (between grains `j - 1` and `j`) takes its force, grain `j - 1` its acceleration and
    /// kick; so each row of the tangents is read and written while it is in the cache. Each
    /// number is computed by the same operations as in separate passes.
    #[inline(always)]
    fn stage(&mut self, _stage: usize, d: f64, k: f64, h: f64, _closing: bool) {
        if self.p == 0 {
            self.stage_values(d, k, h);
            return;
        }
        let n = self.n;
        let mut j = 0;
        while j <= (self.front + 1).min(n) {
            if j <= self.front && j < n {
                self.drift(j, d, h);
            }
            self.force(j);
            if j == self.front + 1 {
                self.widen();
            }
            if j > 0 {
                self.accelerate(j - 1);
                self.kick_grain(j - 1, k, h);
            }
            j += 1;
        }
    }
}

impl Tangent {
    /// [`Flows::stage`] without tangents (the reverse run's forward pass): the same operations
    /// in the same order on the values alone, over slices bound once.
    #[inline(always)]
    fn stage_values(&mut self, d: f64, k: f64, h: f64) {
        let n = self.n;
        let Tangent {
            contacts,
            inv_m,
            state,
            a,
            f,
            front,
            ..
        } = self;
        let (u, v) = (&mut state.u[..], &mut state.v[..]);
        let mut j = 0;
        while j <= (*front + 1).min(n) {
            if j <= *front && j < n {
                u[j] += d * h * v[j];
            }
            if let Some((force, _)) = contacts.force(u, j) {
                f[j] = force;
            }
            // `widen`: the wave reached the grain beyond the front.
            if j == *front + 1 && j < n && f[j] != 0.0 {
                *front += 1;
            }
            if j > 0 {
                let i = j - 1;
                let acc = (f[i] - f[i + 1]) * inv_m[i];
                a[i] = acc;
                v[i] += k * h * acc;
            }
            j += 1;
        }
    }
}

/// A step of the grid cut at contact events ([`cut_at_events`]): each piece's length carries
/// its tangent, an event's from the implicit function theorem ([`Tangent::event_tangent`]),
/// the rest's that of the grid's step less the pieces before.
struct Cut<'t> {
    t: &'t mut Tangent,
    events: &'t mut Events,
    win: &'t Window,
    splitting: &'static Splitting,
    /// The tangent of what is left of the grid's step, and of the last event's instant.
    left: Vec<f64>,
    tau: Vec<f64>,
    /// Whether no event has cut this step yet: what is left is then the grid's step, whose
    /// tangent is slot [`STEP`] alone (`left`'s unit vector, taken without a pass over it).
    uncut: bool,
    /// The reverse run's record, kept by its forward pass.
    tape: Option<&'t mut Tape>,
}

impl Cuts for Cut<'_> {
    fn next_cut(&mut self, left: f64) -> Option<(f64, usize)> {
        self.events.first(&self.t.state, &self.t.a, self.win, left)
    }

    #[inline(always)]
    fn piece(&mut self, tau: f64, event: Option<usize>) {
        if let Some(tape) = self.tape.as_deref_mut() {
            let t = &self.t;
            tape.piece(&t.state.u, &t.state.v, t.front, tau, event);
        }
        match event {
            None if self.uncut => self.t.set_piece(None),
            None => self.t.set_piece(Some(&self.left)),
            Some(k) => {
                self.t.event_tangent(k, tau, &mut self.tau);
                self.t.set_piece(Some(&self.tau));
            }
        }
        whole(self.splitting, self.t, tau);
        if event.is_some() {
            axpy(&mut self.left, -1.0, &self.tau);
            self.uncut = false;
        }
    }
}

/// The load watch of [`crate::LoadWatch`] with tangents, step by step: its rules (the located
/// peak, [`Parabola`]; the duration, [`Above`]) with each number's tangent, and a second
/// candidate for the peak (the tie).
struct Watch {
    p: usize,
    dt: f64,
    steps: u64,
    fraction: f64,
    located: bool,
    peak: f64,
    peak_time: f64,
    peak_step: u64,
    dpeak: Vec<f64>,
    /// Where the peak came from (for the reverse run).
    peak_src: Src,
    runner: Option<(f64, f64, u64, Vec<f64>, Src)>,
    impulse: f64,
    dimpulse: Vec<f64>,
    last: f64,
    dlast: Vec<f64>,
    before: f64,
    dbefore: Vec<f64>,
    above: Above,
    target_energy: f64,
    dtarget: Vec<f64>,
    /// The target's largest energy's step, grain, `m v` and spring `k u` (the reverse run's
    /// seed).
    target_at: Option<(u64, usize, f64, f64)>,
}

impl Watch {
    fn new(p: usize, dt: f64, fraction: f64, located: bool, f: f64, df: &[f64]) -> Self {
        Watch {
            p,
            dt,
            steps: 0,
            fraction,
            located,
            peak: f,
            peak_time: 0.0,
            peak_step: 0,
            dpeak: df.to_vec(),
            peak_src: Src::Force(0),
            runner: None,
            impulse: 0.0,
            dimpulse: vec![0.0; p],
            last: f,
            dlast: df.to_vec(),
            before: f,
            dbefore: df.to_vec(),
            above: Above::default(),
            target_energy: 0.0,
            dtarget: vec![0.0; p],
            target_at: None,
        }
    }

    /// A candidate peak `x` at `step` (time `time`), tangent `dx`, from `src`.
    fn candidate(&mut self, x: f64, time: f64, step: u64, dx: &[f64], src: Src) {
        let apart = step.abs_diff(self.peak_step) >= 2;
        if x > self.peak {
            // The same maximum better located (`!apart`) is no other instant.
            if apart && self.peak >= x * (1.0 - TIE) {
                self.runner = Some((
                    self.peak,
                    self.peak_time,
                    self.peak_step,
                    self.dpeak.clone(),
                    self.peak_src,
                ));
            }
            self.peak = x;
            self.peak_time = time;
            self.peak_step = step;
            self.dpeak.copy_from_slice(dx);
            self.peak_src = src;
        } else if apart
            && x >= self.peak * (1.0 - TIE)
            && self.runner.as_ref().is_none_or(|r| x > r.0)
        {
            self.runner = Some((x, time, step, dx.to_vec(), src));
        }
    }

    fn record(&mut self, f: f64, df: &[f64]) {
        let (p, dt) = (self.p, self.dt);
        self.steps += 1;
        self.impulse += 0.5 * (self.last + f) * dt;
        for ((d, l), f) in self.dimpulse.iter_mut().zip(&self.dlast).zip(df) {
            *d += 0.5 * (l + f) * dt;
        }
        if p > 0 {
            self.dimpulse[STEP] += 0.5 * (self.last + f);
        }
        let steps = self.steps;
        if f > self.peak || (f >= self.peak * (1.0 - TIE) && f > 0.0) {
            self.candidate(f, steps as f64 * dt, steps, df, Src::Force(steps));
        }
        if self.located && self.last > self.before && self.last >= f && steps >= 2 {
            let (y0, y1, y2) = (self.before, self.last, f);
            if let Some(Parabola {
                top,
                curvature,
                offset,
            }) = Parabola::through(y0, y1, y2)
            {
                if top >= self.peak * (1.0 - TIE) {
                    // d top = dy1 - [2 (y0 - y2) (dy0 - dy2) c - (y0 - y2)^2 dc] / (8 c^2).
                    let s = y0 - y2;
                    let c8 = 8.0 * curvature;
                    let dtop: Vec<f64> = (0..p)
                        .map(|j| {
                            let (d0, d1, d2) = (self.dbefore[j], self.dlast[j], df[j]);
                            let dc = d0 - 2.0 * d1 + d2;
                            d1 - (2.0 * s * (d0 - d2) * c8 - s * s * 8.0 * dc) / (c8 * c8)
                        })
                        .collect();
                    self.candidate(
                        top,
                        ((steps - 1) as f64 + offset) * dt,
                        steps - 1,
                        &dtop,
                        Src::top(steps - 1, y0, y1, y2),
                    );
                }
            }
        }
        std::mem::swap(&mut self.before, &mut self.last);
        std::mem::swap(&mut self.dbefore, &mut self.dlast);
        self.last = f;
        self.dlast.copy_from_slice(df);
        self.above.record(f, self.fraction * self.peak);
    }

    /// The count of steps at or above the fraction of the final peak.
    fn above(&self) -> usize {
        self.above.count(self.fraction * self.peak)
    }
}

/// How a run's derivatives are computed: one sweep back through the recorded run
/// (`super::adjoint`), or forward mode, every input's tangent carried through the run (its
/// oracle).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Mode {
    Reverse,
    Forward,
    /// The reverse run keeping checkpoints from the first step (its test).
    #[cfg_attr(not(test), allow(dead_code))]
    Checkpointed,
}

fn run_gradients(
    beads: &[Bead],
    impact: &Impact,
    protected: &Protected,
    settings: &Settings,
    keep_going: &mut dyn FnMut() -> bool,
    mode: Mode,
) -> Result<Gradients, DesignError> {
    if !impact.is_elastic() {
        return Err(bad(
            "gradients",
            "are built for elastic contacts only (leave out the restitution and its pairs)",
        ));
    }
    let Some(splitting) = settings.method.splitting() else {
        return Err(bad(
            "gradients",
            format!(
                "need a splitting method (verlet or blanes-moan4), got {}",
                settings.method.name()
            ),
        ));
    };
    let lay = layout(beads, impact, protected, settings)?;
    let grains = lay.chain.len();
    let n = grains as f64;
    let interval = f64::from(settings.check_every);
    let steps = (lay.time_cap / (lay.dt * interval)).ceil().max(1.0) * interval;
    let cost = |mode: Mode| match mode {
        // Tangents: `2 n + 4` beside each grain's position, velocity and acceleration and each
        // contact's force, through every grain of every step.
        Mode::Forward => {
            let slots = 2.0 * n + 4.0;
            (4.0 * n * slots * 8.0, steps * n * slots)
        }
        // The tape: [`PIECES_PER_STEP`] pieces per step (the run stops if events cut more and
        // it passes the bound); the work a few passes over every grain of every step.
        Mode::Reverse | Mode::Checkpointed => {
            (Tape::bound(steps, grains, PIECES_PER_STEP), steps * n)
        }
    };
    let (bytes, work) = cost(mode);
    let most = match mode {
        Mode::Forward => MAX_GRADIENT_WORK,
        Mode::Reverse | Mode::Checkpointed => MAX_GRADIENT_GRAIN_STEPS,
    };
    if !(bytes <= MAX_GRADIENT_BYTES && work <= most) {
        return Err(bad(
            "beads",
            format!(
                "the gradients of {} beads to a time cap of {} contact-time sums would take up \
                 to {} of memory and {work:.2e} units of work (steps x grains{}), over the \
                 limits of {} and {most:.0e}: give fewer beads or a shorter time cap, or \
                 evaluate without gradients",
                beads.len(),
                settings.time_cap,
                crate::number::human_bytes(bytes as u64),
                if mode == Mode::Forward {
                    " x derivatives"
                } else {
                    ""
                },
                crate::number::human_bytes(MAX_GRADIENT_BYTES as u64),
            ),
        ));
    }
    let map = Inputs::new(
        &lay.chain,
        beads,
        impact,
        protected,
        settings.steps_per_contact,
    );
    let p = 2 * grains + 4;
    let (core, slots) = match mode {
        Mode::Forward => {
            let c = core(&lay, settings, splitting, keep_going, true, None)?;
            let w = &c.watch;
            let mut lanes = [
                vec![0.0; p],
                vec![0.0; p],
                vec![0.0; p],
                vec![0.0; p],
                vec![],
            ];
            lanes[Lane::Peak as usize].copy_from_slice(&w.dpeak);
            lanes[Lane::Impulse as usize].copy_from_slice(&w.dimpulse);
            lanes[Lane::Target as usize].copy_from_slice(&w.dtarget);
            lanes[Lane::Rebound as usize].copy_from_slice(&c.rebound);
            lanes[Lane::Tie as usize] = w.runner.as_ref().map_or(vec![], |r| r.3.clone());
            (c, lanes)
        }
        Mode::Reverse | Mode::Checkpointed => {
            let mut tape = Tape::take(grains);
            #[cfg(test)]
            if mode == Mode::Checkpointed {
                tape.checkpoints_only();
            }
            let c = core(
                &lay,
                settings,
                splitting,
                keep_going,
                false,
                Some(&mut tape),
            )?;
            let w = &c.watch;
            let out = Outputs {
                steps: c.evaluation.steps,
                contact: lay.contact,
                dt: lay.dt,
                peak: w.peak_src,
                tie: w.runner.as_ref().map(|r| r.4),
                impulse_per_step: w.impulse / lay.dt,
                target: w.target_at,
                check_every: u64::from(settings.check_every),
            };
            let win = Window::full(grains);
            let mut regenerate = |c: &Checkpoint, len: u64, segment: &mut Tape| {
                let mut t = Tangent::new(&lay.chain, false);
                t.restore(c.u, c.v, c.front);
                let mut events = settings.events.then(|| {
                    let mut e = Events::new(&lay.chain);
                    e.set_scale(c.scale);
                    e
                });
                let mut scratch = (Vec::new(), Vec::new());
                for _ in 0..len {
                    segment.step();
                    grid_step(
                        &mut t,
                        events.as_mut(),
                        &win,
                        splitting,
                        lay.dt,
                        Some(segment),
                        (&mut scratch.0, &mut scratch.1),
                    );
                }
            };
            let g = super::adjoint::reverse(
                &lay.chain,
                splitting,
                &tape,
                &out,
                keep_going,
                &mut regenerate,
            )
            .map_err(|_| DesignError::Stopped)?;
            tape.keep();
            let lane = |l: Lane| g.iter().map(|x| x[l as usize]).collect::<Vec<f64>>();
            let lanes = [
                lane(Lane::Peak),
                lane(Lane::Impulse),
                lane(Lane::Target),
                lane(Lane::Rebound),
                lane(Lane::Tie),
            ];
            (c, lanes)
        }
    };
    let Core {
        evaluation,
        above,
        watch,
        ..
    } = core;
    let mut duration = vec![0.0; p];
    duration[STEP] = above as f64;
    let tie = watch
        .runner
        .as_ref()
        .filter(|r| r.0 >= watch.peak * (1.0 - TIE))
        .map(|r| Tie {
            time: r.1,
            force: r.0,
            peak: map.map(&slots[Lane::Tie as usize]),
        });
    Ok(Gradients {
        evaluation,
        peak: map.map(&slots[Lane::Peak as usize]),
        impulse: map.map(&slots[Lane::Impulse as usize]),
        duration: map.map(&duration),
        target_energy: map.map(&slots[Lane::Target as usize]),
        rebound: map.map(&slots[Lane::Rebound as usize]),
        tie,
        step_shared: map.shared,
    })
}

/// One step of the grid `dt` of the run, cut at events where `events` are on, each piece
/// recorded in `tape` if given. `scratch`: the tangents of what is left of the step and of the
/// last event's instant (reused from step to step).
#[inline(always)]
fn grid_step(
    t: &mut Tangent,
    events: Option<&mut Events>,
    win: &Window,
    splitting: &'static Splitting,
    dt: f64,
    mut tape: Option<&mut Tape>,
    scratch: (&mut Vec<f64>, &mut Vec<f64>),
) {
    match events {
        None => {
            if let Some(tape) = tape.as_deref_mut() {
                tape.piece(&t.state.u, &t.state.v, t.front, dt, None);
            }
            t.set_piece(None);
            whole(splitting, t, dt);
        }
        Some(events) => {
            let p = t.p;
            let (left, tau) = scratch;
            let mut cut = Cut {
                t,
                events,
                win,
                splitting,
                left: std::mem::take(left),
                tau: std::mem::take(tau),
                uncut: true,
                tape,
            };
            cut.left.iter_mut().for_each(|x| *x = 0.0);
            if p > 0 {
                cut.left[STEP] = 1.0;
            }
            cut_at_events(&mut cut, dt);
            (*left, *tau) = (cut.left, cut.tau);
        }
    }
}

/// The run's numbers with their derivatives with respect to the run's inputs (the slots).
struct Core {
    evaluation: Evaluation,
    /// Steps at or above the fraction of the peak.
    above: usize,
    watch: Watch,
    /// The striker's velocity's tangent at the end.
    rebound: Vec<f64>,
}

/// The forward-mode run of a laid-out design (any chain with a striker at grain 0), compiled
/// for AVX2 where the CPU has it (the same bits: `integrators::simd`): its passes over the
/// tangents' slots are most of its work.
///
/// Without `tangents` it carries the values alone and keeps the reverse run's `tape`.
fn core(
    lay: &super::Layout,
    settings: &Settings,
    splitting: &'static Splitting,
    keep_going: &mut dyn FnMut() -> bool,
    tangents: bool,
    tape: Option<&mut Tape>,
) -> Result<Core, DesignError> {
    #[cfg(target_arch = "x86_64")]
    {
        #[target_feature(enable = "avx2")]
        fn avx2(
            lay: &super::Layout,
            settings: &Settings,
            splitting: &'static Splitting,
            keep_going: &mut dyn FnMut() -> bool,
            tangents: bool,
            tape: Option<&mut Tape>,
        ) -> Result<Core, DesignError> {
            core_impl(lay, settings, splitting, keep_going, tangents, tape)
        }
        if crate::integrators::simd::has_avx2() {
            // SAFETY: the CPU supports AVX2 (checked just above).
            return unsafe { avx2(lay, settings, splitting, keep_going, tangents, tape) };
        }
    }
    core_impl(lay, settings, splitting, keep_going, tangents, tape)
}

/// [`core`]'s body, inlined into each instruction set's build.
#[inline(always)]
fn core_impl(
    lay: &super::Layout,
    settings: &Settings,
    splitting: &'static Splitting,
    keep_going: &mut dyn FnMut() -> bool,
    tangents: bool,
    mut tape: Option<&mut Tape>,
) -> Result<Core, DesignError> {
    let chain = &lay.chain;
    let dt = lay.dt;
    let mut t = Tangent::new(chain, tangents);
    let (n, p) = (t.n, t.p);
    let c = lay.contact;
    let mut watch = Watch::new(
        p,
        dt,
        settings.fraction,
        settings.events,
        0.0,
        &vec![0.0; p],
    );
    let mut events = settings.events.then(|| Events::new(chain));
    let win = Window::full(n);
    let interval = f64::from(settings.check_every);
    let outputs = (lay.time_cap / (dt * interval)).ceil().max(1.0) as u64;
    let total = outputs * u64::from(settings.check_every);
    let (mut left_tangent, mut tau_tangent) = (vec![0.0; p], vec![0.0; p]);
    let mut complete = false;
    let mut given_up = false;
    let mut striker_free = false;
    let give_up = settings.may_give_up();
    let mut steps = 0u64;
    while steps < total {
        // One step of the grid, cut at events, its pieces recorded (or a checkpoint kept).
        let record = match tape.as_deref_mut() {
            Some(tape) => {
                let scale = events.as_ref().map_or(0.0, Events::scale);
                tape.begin_step(steps, &t.state.u, &t.state.v, t.front, scale)
            }
            None => false,
        };
        let tape_now = if record { tape.as_deref_mut() } else { None };
        grid_step(
            &mut t,
            events.as_mut(),
            &win,
            splitting,
            dt,
            tape_now,
            (&mut left_tangent, &mut tau_tangent),
        );
        steps += 1;
        watch.record(t.f[c], &t.df[c * p..(c + 1) * p]);
        if lay.target {
            let i = n - 1;
            let (m, v) = (chain.mass()[i], t.state.v[i]);
            let e = 0.5 * m * v * v + chain.contact_energy(&t.state.u, n);
            if e > watch.target_energy {
                watch.target_energy = e;
                let spring = chain.contact_law(n).map_or(0.0, |l| l.eta);
                let u = t.state.u[i];
                watch.target_at = Some((steps, i, m * v, spring * u));
                for j in 0..p {
                    watch.dtarget[j] = m * v * t.dv[i * p + j] + spring * u * t.du[i * p + j];
                }
            }
        }
        if steps.is_multiple_of(u64::from(settings.check_every)) {
            if !t.state.u.iter().chain(&t.state.v).all(|x| x.is_finite()) {
                return Err(bad(
                    "gradients",
                    format!(
                        "the run blew up (a position or velocity is not finite) by step {steps}"
                    ),
                ));
            }
            if !keep_going() {
                return Err(DesignError::Stopped);
            }
            if let Some(tape) = tape.as_deref() {
                // Events cut the steps into more pieces than the bound allowed for.
                if tape.bytes() > MAX_GRADIENT_BYTES {
                    return Err(bad(
                        "beads",
                        format!(
                            "the gradients' record of the run passed {} by step {steps} \
                             (contact events cut its steps into many pieces): give fewer \
                             beads or a shorter time cap, or evaluate without gradients",
                            crate::number::human_bytes(MAX_GRADIENT_BYTES as u64)
                        ),
                    ));
                }
            }
            t.state.t = steps as f64 * dt;
            let b = stop::bound(chain, &t.state, c);
            striker_free = b.striker_free;
            if settings.ends(&b, watch.peak) {
                complete = true;
                break;
            }
            if give_up && settings.gives_up(watch.peak, t.f[c]) {
                given_up = true;
                break;
            }
        }
    }
    let above = watch.above();
    let evaluation = Evaluation {
        peak_force: watch.peak,
        peak_time: watch.peak_time,
        impulse: watch.impulse,
        duration: above as f64 * dt,
        target_energy: watch.target_energy,
        rebound: t.state.v[0],
        rebound_final: striker_free,
        mass: lay.mass,
        length: lay.length,
        time: steps as f64 * dt,
        steps,
        dt,
        complete,
        given_up,
    };
    let rebound = t.dv[..p].to_vec();
    Ok(Core {
        evaluation,
        above,
        watch,
        rebound,
    })
}

/// A Hertz contact a bead takes part in: its left grain, its right grain (`None`: a flat, the
/// wall or the target's face), its constant, the left sphere's material and diameter, the right
/// side's material.
#[derive(Clone, Copy)]
struct Pair {
    l: usize,
    r: Option<usize>,
    eta: f64,
    ml: Material,
    dl: f64,
    mr: Material,
}

/// How the run's inputs (masses, Hertz constants, speed, step) move with the beads'
/// properties: the chain rule's last link, in closed form.
struct Inputs {
    p: usize,
    /// Whether several contacts share the shortest contact time ([`Gradients::step_shared`]).
    shared: bool,
    beads: Vec<Bead>,
    /// Per contact `k`: its two sides (grain indices; `None` a flat: wall or target face) and
    /// its Hertz constant, for the Hertz contacts a bead takes part in.
    contacts: Vec<Pair>,
    /// The contact that sets the step, and the step's logarithmic derivatives with respect to
    /// the log of its reduced mass's parts and of its Hertz constant.
    masses: Vec<f64>,
    /// The step's contact `k` and its other mass (infinite: a wall).
    step_contact: usize,
    step_other: f64,
    step: f64,
    energy_log: [f64; 2],
}

impl Inputs {
    fn new(
        chain: &Chain,
        beads: &[Bead],
        impact: &Impact,
        protected: &Protected,
        steps_per_contact: f64,
    ) -> Self {
        let n = chain.len();
        let m = chain.mass().to_vec();
        let s = impact.striker;
        let nb = beads.len();
        // Grain i (1..=nb) is bead i - 1; grain 0 the striker; grain nb + 1 the target, if any.
        let flat = match *protected {
            Protected::Wall(w) => w,
            Protected::Target { material, .. } => material,
        };
        let mut contacts = Vec::new();
        for k in 1..=nb + 1 {
            let Some(law) = chain.contact_law(k) else {
                continue;
            };
            let (ml, dl) = if k == 1 {
                (s.material, s.diameter)
            } else {
                (beads[k - 2].material, beads[k - 2].diameter)
            };
            if k <= nb {
                let b = beads[k - 1];
                contacts.push(Pair {
                    l: k - 1,
                    r: Some(k),
                    eta: law.eta,
                    ml,
                    dl,
                    mr: b.material,
                });
            } else {
                contacts.push(Pair {
                    l: k - 1,
                    r: None,
                    eta: law.eta,
                    ml,
                    dl,
                    mr: flat,
                });
            }
        }
        // The step: the shortest contact time at the impact's energy, as the layout finds it.
        let energy = impact.energy();
        let (mut best, mut which, mut other) = (f64::INFINITY, 0, f64::INFINITY);
        let mut times = Vec::with_capacity(contacts.len());
        for (k, &Pair { l, r, eta, .. }) in contacts.iter().enumerate() {
            let m2 = match r {
                Some(r) => m[r],
                None if k + 1 == contacts.len() && n > nb + 1 => m[nb + 1],
                None => f64::INFINITY,
            };
            let tc = pair_time(eta, m[l], m2, energy);
            times.push(tc);
            if tc < best {
                (best, which, other) = (tc, k, m2);
            }
        }
        let shared = times.iter().filter(|&&t| t <= best * (1.0 + TIE)).count() > 1;
        Inputs {
            p: 2 * n + 4,
            shared,
            beads: beads.to_vec(),
            contacts,
            masses: m,
            step_contact: which,
            step_other: other,
            step: best / steps_per_contact,
            energy_log: [1.0 / s.mass(), 2.0 / impact.speed],
        }
    }

    /// The derivatives with respect to the beads' properties, from those with respect to the
    /// run's inputs `g` (slots as [`mass_slot`], [`eta_slot`], [`SPEED`], [`STEP`]).
    fn map(&self, g: &[f64]) -> Derivatives {
        debug_assert_eq!(g.len(), self.p);
        let nb = self.beads.len();
        let mut out = Derivatives {
            diameter: vec![0.0; nb],
            density: vec![0.0; nb],
            young: vec![0.0; nb],
            poisson: vec![0.0; nb],
            speed: g[SPEED],
            striker_mass: g[mass_slot(0)],
        };
        // Masses: m = rho pi d^3 / 6.
        for (b, bead) in self.beads.iter().enumerate() {
            let i = b + 1;
            let m = self.masses[i];
            out.diameter[b] += g[mass_slot(i)] * 3.0 * m / bead.diameter;
            out.density[b] += g[mass_slot(i)] * m / bead.material.density;
        }
        // Hertz constants: eta = 4/3 E* sqrt(R*), 1 / E* = C_l + C_r, C = (1 - nu^2) / E.
        let gs = g[STEP];
        let step_log = |k: usize| {
            if k == self.step_contact {
                -0.4 * gs * self.step
            } else {
                0.0
            }
        };
        for (
            k,
            &Pair {
                l,
                r,
                eta,
                ml,
                dl,
                mr,
            },
        ) in self.contacts.iter().enumerate()
        {
            let ge = g[eta_slot(k + 1)] * eta + step_log(k);
            let cl = (1.0 - ml.poisson * ml.poisson) / ml.young;
            let cr = (1.0 - mr.poisson * mr.poisson) / mr.young;
            let sum = cl + cr;
            let mut side = |b: usize, mat: Material, dlog_d: f64| {
                out.diameter[b] += ge * dlog_d;
                out.young[b] +=
                    ge * (1.0 - mat.poisson * mat.poisson) / (mat.young * mat.young) / sum;
                out.poisson[b] += ge * 2.0 * mat.poisson / mat.young / sum;
            };
            match r {
                Some(r) => {
                    let dr = self.beads[r - 1].diameter;
                    // R* = d_l d_r / (2 (d_l + d_r)): d ln R* / d d_l = 1/d_l - 1/(d_l + d_r).
                    if l >= 1 {
                        side(l - 1, ml, 0.5 * (1.0 / dl - 1.0 / (dl + dr)));
                    }
                    side(r - 1, mr, 0.5 * (1.0 / dr - 1.0 / (dl + dr)));
                }
                None => side(l - 1, ml, 0.5 / dl),
            }
        }
        // The step: t = const mu^(1/2) eta^(-2/5) E^(-1/10), E the impact energy.
        let Pair { l, r, .. } = self.contacts[self.step_contact];
        let ml = self.masses[l];
        let mo = self.step_other;
        let (wl, wr) = if mo.is_finite() {
            (mo / (ml + mo), ml / (ml + mo))
        } else {
            (1.0, 0.0)
        };
        let dstep_dlogm = |w: f64| 0.5 * w * gs * self.step;
        let mut mass_log = |i: usize, w: f64| {
            let d = dstep_dlogm(w) / self.masses[i];
            if i == 0 {
                out.striker_mass += d;
            } else if i <= nb {
                let b = i - 1;
                out.diameter[b] += d * 3.0 * self.masses[i] / self.beads[b].diameter;
                out.density[b] += d * self.masses[i] / self.beads[b].material.density;
            }
        };
        mass_log(l, wl);
        if let Some(r) = r {
            mass_log(r, wr);
        }
        let e = -0.1 * gs * self.step;
        out.striker_mass += e * self.energy_log[0];
        out.speed += e * self.energy_log[1];
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrators::Method;
    use crate::protector::{evaluate, Case, Need};
    use crate::units::BRASS;

    /// The forward-mode run is the evaluation's run: the same numbers to rounding (the two add
    /// the same terms in a different order where the engine fuses kicks), the same steps.
    #[test]
    fn the_run_with_derivatives_is_the_evaluation() {
        let mut case = Case::steel_then_ptfe(8);
        for (i, b) in case.beads.iter_mut().enumerate() {
            b.diameter *= 1.0 + 0.037 * i as f64;
        }
        case.beads[5].material = BRASS;
        for method in [Method::Verlet, Method::BlanesMoan4] {
            for events in [false, true] {
                let s = Settings {
                    method,
                    events,
                    steps_per_contact: if method == Method::Verlet { 80.0 } else { 20.0 },
                    need: Need::Everything,
                    ..Settings::default()
                };
                let g = gradients(&case.beads, &case.impact, &case.protected, &s).unwrap();
                let e = evaluate(&case.beads, &case.impact, &case.protected, &s).unwrap();
                let (a, b) = (g.evaluation, e);
                assert_eq!(
                    (a.steps, a.complete),
                    (b.steps, b.complete),
                    "{method:?} {events}"
                );
                // 1e-12: the rounding of a few thousand steps' sums, summed in another order.
                for (x, y) in [
                    (a.peak_force, b.peak_force),
                    (a.impulse, b.impulse),
                    (a.rebound, b.rebound),
                    (a.duration, b.duration),
                ] {
                    assert!(
                        (x - y).abs() <= 1e-12 * y.abs(),
                        "{method:?} {events}: {x} {y}"
                    );
                }
                assert!(!g.step_shared && g.tie.is_none());
            }
        }
    }

    /// The reverse run against forward mode, its oracle: every derivative of every reported
    /// number, for both splitting methods with and without events, on a wall and on a target,
    /// on a mixed column whose beads part and meet again.
    #[test]
    fn the_reverse_run_agrees_with_forward_mode() {
        use crate::units::PTFE;
        let mut case = Case::steel_then_ptfe(8);
        for (i, b) in case.beads.iter_mut().enumerate() {
            b.diameter *= 1.0 + 0.037 * i as f64;
        }
        case.beads[5].material = BRASS;
        case.beads[1].material = PTFE;
        let target = Protected::Target {
            material: crate::units::STEEL,
            mass: 0.02,
            spring: 3e5,
        };
        let mut worst = 0.0f64;
        for protected in [case.protected, target] {
            for method in [Method::Verlet, Method::BlanesMoan4] {
                for events in [false, true] {
                    let s = Settings {
                        method,
                        events,
                        steps_per_contact: if method == Method::Verlet { 80.0 } else { 20.0 },
                        need: Need::Everything,
                        ..Settings::default()
                    };
                    let r = gradients(&case.beads, &case.impact, &protected, &s).unwrap();
                    let f = gradients_forward(&case.beads, &case.impact, &protected, &s).unwrap();
                    assert_eq!(format!("{:?}", r.evaluation), format!("{:?}", f.evaluation));
                    let pairs = [
                        ("peak", &r.peak, &f.peak),
                        ("impulse", &r.impulse, &f.impulse),
                        ("duration", &r.duration, &f.duration),
                        ("target energy", &r.target_energy, &f.target_energy),
                        ("rebound", &r.rebound, &f.rebound),
                    ];
                    for (what, a, b) in pairs {
                        let flat = |d: &Derivatives| {
                            let mut v = d.diameter.clone();
                            v.extend(&d.density);
                            v.extend(&d.young);
                            v.extend(&d.poisson);
                            v.push(d.speed);
                            v.push(d.striker_mass);
                            v
                        };
                        let (x, y) = (flat(a), flat(b));
                        // Each derivative against the largest of its kind (diameters, ...):
                        // the two sum the same terms in another order.
                        let scale = y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                        for (j, (x, y)) in x.iter().zip(&y).enumerate() {
                            let e = (x - y).abs() / scale.max(f64::MIN_POSITIVE);
                            worst = worst.max(e);
                            assert!(
                                e < 1e-9,
                                "{protected:?} {method:?} events {events}: {what}[{j}] {x} against {y}"
                            );
                        }
                    }
                }
            }
        }
        println!("largest difference: {worst:.1e} of the largest derivative");
    }

    /// The tie's lane (carried only when a peak is tied, which no column of the tests above
    /// reaches) is the peak's machinery on another candidate: given the peak's own source it
    /// gives the peak's derivatives bit for bit, and carrying it changes no bit of the others.
    #[test]
    fn the_tie_lane_is_the_peak_lane_on_its_own_candidate() {
        let case = Case::steel_then_ptfe(8);
        let s = Settings {
            need: Need::Everything,
            ..Settings::default()
        };
        let lay = super::super::layout(&case.beads, &case.impact, &case.protected, &s).unwrap();
        let splitting = s.method.splitting().unwrap();
        let mut tape = Tape::take(lay.chain.len());
        let c = core(&lay, &s, splitting, &mut || true, false, Some(&mut tape)).unwrap();
        let mut out = Outputs {
            steps: c.evaluation.steps,
            contact: lay.contact,
            dt: lay.dt,
            peak: c.watch.peak_src,
            tie: None,
            impulse_per_step: c.watch.impulse / lay.dt,
            target: c.watch.target_at,
            check_every: u64::from(s.check_every),
        };
        assert!(matches!(out.peak, Src::Top(..)), "{:?}", out.peak);
        let sweep = |out: &Outputs| {
            let never = &mut |_: &Checkpoint, _: u64, _: &mut Tape| unreachable!("no checkpoints");
            super::super::adjoint::reverse(&lay.chain, splitting, &tape, out, &mut || true, never)
                .ok()
                .unwrap()
        };
        let without = sweep(&out);
        out.tie = Some(out.peak);
        let with = sweep(&out);
        for (a, b) in without.iter().zip(&with) {
            for l in [Lane::Peak, Lane::Impulse, Lane::Target, Lane::Rebound] {
                assert_eq!(a[l as usize].to_bits(), b[l as usize].to_bits());
            }
            assert_eq!(a[Lane::Tie as usize], 0.0);
            assert_eq!(
                b[Lane::Tie as usize].to_bits(),
                b[Lane::Peak as usize].to_bits()
            );
        }
    }

    /// A run kept as checkpoints (a tape past 128 MB, here from the first step) and swept back
    /// segment by segment, each run again from its checkpoint, gives the same bits as the run
    /// recorded piece by piece: the segments run again are the same steps.
    #[test]
    fn checkpoints_give_the_same_bits() {
        let mut case = Case::steel_then_ptfe(12);
        for (i, b) in case.beads.iter_mut().enumerate() {
            b.diameter *= 1.0 + 0.021 * i as f64;
        }
        for events in [false, true] {
            let s = Settings {
                events,
                need: Need::Everything,
                ..Settings::default()
            };
            let run = |mode| {
                run_gradients(
                    &case.beads,
                    &case.impact,
                    &case.protected,
                    &s,
                    &mut || true,
                    mode,
                )
                .unwrap()
            };
            let (whole, kept) = (run(Mode::Reverse), run(Mode::Checkpointed));
            // More than one segment of 256 steps.
            assert!(whole.evaluation.steps > 600, "{}", whole.evaluation.steps);
            assert_eq!(format!("{whole:?}"), format!("{kept:?}"), "events {events}");
        }
    }

    /// `gradients_until` is asked at every check of the stop rule: always yes gives
    /// `gradients`' bits, and a no ends the run with `Stopped` at once.
    #[test]
    fn a_caller_can_stop_a_run_with_derivatives() {
        let case = Case::steel_then_ptfe(8);
        let s = Settings::default();
        let whole = gradients(&case.beads, &case.impact, &case.protected, &s).unwrap();
        let mut asked = 0u64;
        let again = gradients_until(&case.beads, &case.impact, &case.protected, &s, &mut || {
            asked += 1;
            true
        })
        .unwrap();
        // Debug text: the same bits print the same (NaN included, which == would not call equal).
        assert_eq!(format!("{whole:?}"), format!("{again:?}"));
        // Once per check of the run (the steps over `check_every`), and once per as many steps
        // of the sweep back.
        let checks = whole.evaluation.steps / u64::from(s.check_every);
        assert_eq!(asked, 2 * checks);
        // A no in the run, and one in the sweep back.
        for at in [3, checks + 2] {
            let mut left = at;
            let r = gradients_until(&case.beads, &case.impact, &case.protected, &s, &mut || {
                left -= 1;
                left > 0
            });
            assert!(matches!(r, Err(DesignError::Stopped)), "{r:?}");
            assert_eq!(left, 0);
        }
    }

    /// A sphere of mass `m` at speed `v` on a wall (Hertz constant `eta`): `F_max = eta
    /// delta_max^(3/2)`, `delta_max = (5 m v^2 / (4 eta))^(2/5)`, so `F_max = eta^(2/5) (5 m v^2
    /// / 4)^(3/5)`: `d F / d m = 3 F / (5 m)`, `d F / d v = 6 F / (5 v)`, `d F / d eta = 2 F / (5
    /// eta)`, and the step's derivative only that of the scheme's error. Through them by hand, a
    /// steel sphere of diameter `d` on a steel wall (`eta = 4/3 E* sqrt(d / 2)`, `m = rho pi d^3 /
    /// 6`): `d ln F / d ln d = 2/5 * 1/2 + 3/5 * 3 = 2`, `d ln F / d ln rho = 3/5`, `d ln F / d ln
    /// E = 2/5 C / (2 C)` (the sphere's compliance `C` is half the pair's), `d ln F / d nu = 2/5
    /// (2 nu / E) / (2 C)`. The chain is the sphere (the striker) and the wall as a grain of
    /// 1e30 kg (the reduced mass is the sphere's to 1e-33), the watched contact between them.
    #[test]
    fn a_sphere_on_a_wall_against_the_closed_form() {
        use crate::chain::{ChainBuilder, ContactLaw, Section, Striker, StrikerEnd};
        use crate::problems::contact_time;
        use crate::units::{hertz_eta_flat, STEEL};
        let (d, v) = (6e-3, 1.0);
        let m = STEEL.sphere_mass(d);
        let eta = hertz_eta_flat(&STEEL, d, &STEEL);
        let chain = ChainBuilder::new()
            .section(Section::new("wall", 1, 1e30, ContactLaw::hertz(eta)))
            .striker(Striker {
                end: StrikerEnd::Left,
                mass: m,
                speed: v,
                law: Some(ContactLaw::hertz(eta)),
            })
            .build()
            .unwrap();
        let tc = contact_time(1.5, eta, m, v);
        let settings = Settings {
            need: Need::Peak,
            ..Settings::default()
        };
        let lay = super::super::Layout {
            chain,
            contact: 1,
            target: false,
            dt: tc / 400.0,
            time_cap: 2.0 * tc,
            mass: m,
            length: d,
        };
        let run = core(
            &lay,
            &settings,
            settings.method.splitting().unwrap(),
            &mut || true,
            true,
            None,
        )
        .unwrap();
        let f = run.evaluation.peak_force;
        let exact = eta.powf(0.4) * (1.25 * m * v * v).powf(0.6);
        let g = &run.watch.dpeak;
        let hand = [
            ("m", g[mass_slot(0)], 0.6 * exact / m),
            ("v", g[SPEED], 1.2 * exact / v),
            ("eta", g[eta_slot(1)], 0.4 * exact / eta),
        ];
        // The peak at 400 steps per contact time with events and the located peak: its error
        // is below 1e-9 (`steps_for_accuracy`'s table: 7.5e-9 at 160 on a column, here one
        // contact); the derivatives' errors are of the same order, so 1e-7 leaves room and a
        // wrong factor (the smallest is 2/5 against 3/5) fails by far.
        assert!((f - exact).abs() < 1e-8 * exact, "{f} against {exact}");
        // The table (`cargo test -p grainchain-engine --lib closed_form -- --nocapture`).
        println!("peak: {f:.12e} N against {exact:.12e} N");
        for (what, got, want) in hand {
            println!(
                "dF/d{what}: {got:.12e} against {want:.12e} (relative {:.1e})",
                (got - want).abs() / want.abs()
            );
            assert!(
                (got - want).abs() < 1e-7 * want.abs(),
                "{what}: {got} against {want}"
            );
        }
        // The step moves the peak only by the scheme's error: dt dF/ddt is far below 1e-8 F.
        assert!((g[STEP] * lay.dt).abs() < 1e-8 * f, "{}", g[STEP]);
        // By hand through a steel sphere on a steel wall.
        let c = (1.0 - STEEL.poisson * STEEL.poisson) / STEEL.young;
        let by_hand = [
            ("diameter", 2.0 * exact / d),
            ("rho", 0.6 * exact / STEEL.density),
            ("E", 0.4 * 0.5 * exact / STEEL.young),
            (
                "nu",
                0.4 * (2.0 * STEEL.poisson / STEEL.young) / (2.0 * c) * exact,
            ),
        ];
        // The same derivatives from the run's: m = rho pi d^3/6 and eta = 4/3 E* sqrt(d/2),
        // E* = 1 / (2 C) for two equal solids (the sphere's part is half of every derivative
        // of E* in the sphere's constants).
        let (gm, ge) = (g[mass_slot(0)], g[eta_slot(1)]);
        let from_run = [
            3.0 * m / d * gm + 0.5 * eta / d * ge,
            m / STEEL.density * gm,
            eta * (c / STEEL.young) / (2.0 * c) * ge,
            eta * (2.0 * STEEL.poisson / STEEL.young) / (2.0 * c) * ge,
        ];
        for ((what, want), got) in by_hand.iter().zip(from_run) {
            println!(
                "dF/d{what}: {got:.12e} against {want:.12e} (relative {:.1e})",
                (got - want).abs() / want.abs()
            );
            assert!(
                (got - want).abs() < 1e-7 * want.abs(),
                "{what}: {got} against {want}"
            );
        }
    }
}
