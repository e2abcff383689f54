//! The reverse (adjoint) run of a protector's derivatives: every reported number's derivatives
//! with respect to all of the run's inputs from one sweep back through the run, at a cost that
//! does not grow with the inputs.
//!
//! The forward pass is the run with its values alone (`gradient::core` without tangents), which
//! keeps a [`Tape`]: the positions and velocities at the start of every piece of every step,
//! the piece's length and its event (past [`FULL_BYTES`], a [`Checkpoint`] every [`SEGMENT`]
//! steps instead, from which the sweep back runs each segment again, the same bits). The reverse pass takes the pieces
//! last to first. It replays each from its state on the tape (the same operations as the
//! forward pass, so the same numbers) and carries back the adjoints of the state, one lane per
//! reported number ([`Lane`]): through each stage's kick, accelerations, contact forces and
//! drift; into the run's inputs (each grain's mass, each contact's Hertz constant, the striker's
//! speed, the step: the slots of `gradient`'s forward mode); through a piece cut at an event,
//! whose length moves with the state at its start by the implicit function theorem on the
//! overlap polynomial whose root it is; and through what is left of a cut step, `h` less the
//! pieces before. Each number enters its lane where the run computed it ([`Outputs`]): the
//! peak's force at its step (or the three forces its located parabola goes through, with that
//! parabola's weights), the impulse's force at every step, the target's energy at its step, the
//! striker's final velocity.
//!
//! Forward mode carries `2 n + 4` tangents through every stage; this carries five adjoints
//! through every stage twice (replay and sweep), so its cost stays a few evaluations whatever the
//! column's length. Forward mode stays as its oracle (`gradient::gradients_forward`). The tape's
//! size is bounded before the run starts (`gradient::MAX_GRADIENT_BYTES`).

use crate::chain::law::Kernel;
use crate::chain::{compression, Chain};
use crate::integrators::{whole, Flows, Splitting};

/// The run's inputs, as slots of a derivative vector: the speed, the step, then per grain `i`
/// its mass and the Hertz constant of its left contact `i`, then the right end's contact `n`.
pub(super) const SPEED: usize = 0;
pub(super) const STEP: usize = 1;
pub(super) fn mass_slot(i: usize) -> usize {
    2 + 2 * i
}
pub(super) fn eta_slot(k: usize) -> usize {
    3 + 2 * k
}

/// The reported numbers the reverse pass differentiates, one lane each (the duration's
/// derivative is the step's alone and takes no lane).
#[derive(Clone, Copy, Debug)]
pub(super) enum Lane {
    Peak = 0,
    Impulse = 1,
    Target = 2,
    Rebound = 3,
    /// The other candidate of a tied peak (`gradient::Tie`).
    Tie = 4,
}

/// Lanes carried: every [`Lane`].
pub(super) const LANES: usize = 5;

/// Where a candidate peak comes from: the watched force at the end of step `s`, or the top of
/// the parabola through the forces at the ends of steps `s - 1`, `s` and `s + 1`, whose
/// derivative is theirs times these weights.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Src {
    Force(u64),
    Top(u64, [f64; 3]),
}

impl Src {
    /// The weight of the force at the end of step `s` in this candidate.
    fn weight(self, s: u64) -> f64 {
        match self {
            Src::Force(t) => f64::from(u8::from(t == s)),
            Src::Top(m, w) => {
                if s + 1 == m {
                    w[0]
                } else if s == m {
                    w[1]
                } else if s == m + 1 {
                    w[2]
                } else {
                    0.0
                }
            }
        }
    }

    /// The parabola's weights: its top `y1 - (y0 - y2)^2 / (8 c)`, `c = y0 - 2 y1 + y2`,
    /// differentiated in `y0`, `y1`, `y2`.
    pub(super) fn top(step: u64, y0: f64, y1: f64, y2: f64) -> Src {
        let (s, c) = (y0 - y2, y0 - 2.0 * y1 + y2);
        let q = s * s / (8.0 * c * c);
        Src::Top(step, [-s / (4.0 * c) + q, 1.0 - 2.0 * q, s / (4.0 * c) + q])
    }
}

/// The forward pass's record: per piece its starting state, length, event and wave front, and
/// where each step of the grid starts.
#[derive(Debug, Default)]
pub(super) struct Tape {
    n: usize,
    /// Per piece: `u` and `v` at its start of the grains up to the front, `front + 1` each
    /// (those beyond are at rest: both are `0`), from `starts[piece]`. The accelerations are
    /// the forces' at `u`, which the replay computes again (the same bits).
    states: Vec<f64>,
    starts: Vec<usize>,
    taus: Vec<f64>,
    /// The contact whose event ends the piece (`u32::MAX`: the grid's step, or what is left
    /// of it).
    events: Vec<u32>,
    /// The last grain the wave had reached at the piece's start.
    fronts: Vec<u32>,
    /// Each step's first piece.
    steps: Vec<usize>,
    /// Once the record passes [`FULL_BYTES`]: the steps recorded piece by piece (`1..=s`);
    /// from there the tape keeps a [`Checkpoint`] every [`SEGMENT`] steps, and the sweep back
    /// runs each segment again from its checkpoint to record it.
    full_steps: Option<u64>,
    /// Per checkpoint: `u` and `v` up to the front (from `cp_starts`), the front, and the
    /// events' scale.
    cp_states: Vec<f64>,
    cp_starts: Vec<usize>,
    cp_fronts: Vec<u32>,
    cp_scales: Vec<f64>,
    /// [`FULL_BYTES`] (a test sets it lower).
    full_limit: f64,
}

/// The record of a run is kept piece by piece up to this size; past it, a [`Checkpoint`] every
/// [`SEGMENT`] steps (the sweep back then runs each segment again, about a third more work).
pub(super) const FULL_BYTES: f64 = 128e6;

/// Steps between two checkpoints.
pub(super) const SEGMENT: u64 = 256;

/// The state at the start of a step, from which the run can be taken on again exactly: the
/// positions and velocities up to the front (the grains beyond are at rest), the front, and
/// the events' scale (`integrators::Events`: it decides which events are cut).
pub(super) struct Checkpoint<'a> {
    pub u: &'a [f64],
    pub v: &'a [f64],
    pub front: usize,
    pub scale: f64,
}

/// A tape up to this size is kept for the thread's next run ([`Tape::take`]).
const KEEP_BYTES: usize = 64 << 20;

thread_local! {
    /// The thread's last tape, kept for its memory: runs with derivatives come one after
    /// another (a search, a tolerance analysis), and the pages of a fresh tape cost the kernel
    /// more time (zeroing them, a fault each) than the run takes to write them.
    static SPARE: std::cell::RefCell<Tape> = std::cell::RefCell::new(Tape::default());
}

impl Tape {
    /// An empty tape for `n` grains, with the memory of this thread's last one.
    pub(super) fn take(n: usize) -> Self {
        Self::take_from(SPARE.with(|s| std::mem::take(&mut *s.borrow_mut())), n)
    }

    /// `t` emptied, for `n` grains.
    fn take_from(mut t: Tape, n: usize) -> Self {
        t.n = n;
        t.full_limit = FULL_BYTES;
        t.states.clear();
        t.starts.clear();
        t.taus.clear();
        t.events.clear();
        t.fronts.clear();
        t.steps.clear();
        t.full_steps = None;
        t.cp_states.clear();
        t.cp_starts.clear();
        t.cp_fronts.clear();
        t.cp_scales.clear();
        t
    }

    /// A step of the grid starts after `done` steps, from `u`, `v` (front `front`, the events'
    /// scale `scale`): whether to record its pieces. Past [`FULL_BYTES`] the tape keeps a
    /// checkpoint every [`SEGMENT`] steps instead.
    #[inline(always)]
    pub(super) fn begin_step(
        &mut self,
        done: u64,
        u: &[f64],
        v: &[f64],
        front: usize,
        scale: f64,
    ) -> bool {
        if self.full_steps.is_none() && self.bytes() > self.full_limit {
            self.full_steps = Some(done);
        }
        match self.full_steps {
            None => {
                self.step();
                true
            }
            Some(s) => {
                if (done - s).is_multiple_of(SEGMENT) {
                    let m = (front + 1).min(self.n);
                    self.cp_starts.push(self.cp_states.len());
                    self.cp_states.extend_from_slice(&u[..m]);
                    self.cp_states.extend_from_slice(&v[..m]);
                    self.cp_fronts.push(front as u32);
                    self.cp_scales.push(scale);
                }
                false
            }
        }
    }

    /// Keep checkpoints from the first step on (a test of the checkpoints).
    #[cfg(test)]
    pub(super) fn checkpoints_only(&mut self) {
        self.full_limit = -1.0;
    }

    /// The most bytes a tape of a run of at most `steps` steps of `n` grains holds: the record
    /// up to [`FULL_BYTES`], a checkpoint every [`SEGMENT`] steps, and a segment's record at
    /// `pieces` pieces per step.
    pub(super) fn bound(steps: f64, n: usize, pieces: f64) -> f64 {
        let piece = Self::bytes_per_piece(n);
        let full = (steps * pieces * piece).min(FULL_BYTES + piece);
        let checkpoints = (steps / SEGMENT as f64).ceil() * (2.0 * n as f64 * 8.0 + 32.0);
        let segment = if steps * pieces * piece > FULL_BYTES {
            SEGMENT as f64 * pieces * piece
        } else {
            0.0
        };
        full + checkpoints + segment
    }

    /// Checkpoint `c`.
    fn checkpoint(&self, c: usize) -> Checkpoint<'_> {
        let front = self.cp_fronts[c] as usize;
        let m = (front + 1).min(self.n);
        let st = &self.cp_states[self.cp_starts[c]..self.cp_starts[c] + 2 * m];
        Checkpoint {
            u: &st[..m],
            v: &st[m..],
            front,
            scale: self.cp_scales[c],
        }
    }

    /// Keep this tape's memory for the thread's next run, unless it is large.
    pub(super) fn keep(self) {
        if self.states.capacity() * 8 <= KEEP_BYTES {
            SPARE.with(|s| *s.borrow_mut() = self);
        }
    }

    /// A step of the grid starts (and its pieces are recorded).
    #[inline(always)]
    pub(super) fn step(&mut self) {
        self.steps.push(self.taus.len());
    }

    /// A piece of `tau` starts from `u`, `v` (the wave's front at grain `front`), ended by
    /// `event`'s contact or by the step's end.
    #[inline(always)]
    pub(super) fn piece(
        &mut self,
        u: &[f64],
        v: &[f64],
        front: usize,
        tau: f64,
        event: Option<usize>,
    ) {
        let m = (front + 1).min(self.n);
        self.starts.push(self.states.len());
        self.states.extend_from_slice(&u[..m]);
        self.states.extend_from_slice(&v[..m]);
        self.taus.push(tau);
        self.events.push(event.map_or(u32::MAX, |k| k as u32));
        self.fronts.push(front as u32);
    }

    /// The bytes the tape holds.
    pub(super) fn bytes(&self) -> f64 {
        ((self.states.len() + self.cp_states.len()) * 8
            + self.taus.len() * 24
            + self.cp_fronts.len() * 32) as f64
    }

    /// The most bytes the tape holds per piece for `n` grains.
    pub(super) fn bytes_per_piece(n: usize) -> f64 {
        (2 * n * 8 + 24) as f64
    }

    /// Piece `piece`'s starting positions and velocities, up to its front.
    #[inline(always)]
    fn state(&self, piece: usize) -> (&[f64], &[f64]) {
        let m = (self.fronts[piece] as usize + 1).min(self.n);
        let st = &self.states[self.starts[piece]..self.starts[piece] + 2 * m];
        (&st[..m], &st[m..])
    }
}

/// Where each reported number entered the forward pass.
pub(super) struct Outputs {
    /// Steps taken.
    pub steps: u64,
    /// The watched contact.
    pub contact: usize,
    pub dt: f64,
    pub peak: Src,
    pub tie: Option<Src>,
    /// The impulse over the step (`sum (F_(s-1) + F_s) / 2`): the impulse's derivative in the
    /// step where it multiplies the forces.
    pub impulse_per_step: f64,
    /// The target's largest energy: its step, grain, `m v` and the spring's `k u` there.
    pub target: Option<(u64, usize, f64, f64)>,
    /// How often to ask whether to go on (the stop rule's checks).
    pub check_every: u64,
}

/// The stop requested by the caller's `keep_going`.
pub(super) struct Stopped;

/// Every contact's law, looked up once for the runs that step contact by contact (the forward
/// pass, forward mode and the replay): its force and slope at given positions.
pub(super) struct Contacts {
    kernels: Vec<Option<Kernel>>,
}

impl Contacts {
    pub(super) fn new(chain: &Chain) -> Self {
        Contacts {
            kernels: (0..=chain.len())
                .map(|k| chain.contact_kernel(k).cloned())
                .collect(),
        }
    }

    /// Contact `c`'s Hertz constant (`0`: no contact).
    #[inline(always)]
    pub(super) fn eta(&self, c: usize) -> f64 {
        self.kernels[c].as_ref().map_or(0.0, |k| k.eta)
    }

    /// Contact `c`'s force and its slope `dF / d delta` at the positions `u` (the slope `0`
    /// where the force is), by `Chain::overlap`'s and the kernel's arithmetic (the force's bits
    /// are `Kernel::force_at`'s); `None` where there is no contact.
    #[inline(always)]
    pub(super) fn force(&self, u: &[f64], c: usize) -> Option<(f64, f64)> {
        let kernel = self.kernels[c].as_ref()?;
        let (f, slope) = kernel.force_slope_at(kernel.delta0 + compression(u, c));
        // A force below the floor of a closed contact is zero, and so is its slope.
        Some(if f == 0.0 { (0.0, 0.0) } else { (f, slope) })
    }
}

/// The replay of a piece ([`Reverse::replay`]) as a carrier of the splitting methods' step:
/// the grains `0..hi` move, and each stage keeps what the sweep back reads.
impl<const L: usize> Flows for Reverse<'_, L> {
    /// The opening kick, with the accelerations the piece starts from.
    #[inline(always)]
    fn kick(&mut self, c: f64, h: f64) {
        let hi = self.hi;
        for (v, a) in self.v[..hi].iter_mut().zip(&self.a_in[..hi]) {
            *v += c * h * a;
        }
    }

    /// One sweep, as the forward pass takes a stage (`gradient::Tangent`): grain `j` drifts,
    /// contact `j` takes its force, grain `j - 1` its acceleration and kick. Contacts `0..=hi`:
    /// contact `hi` joins the last grain that may move to one at rest (or the wall); those
    /// beyond join grains at rest and push nothing.
    #[inline(always)]
    fn stage(&mut self, stage: usize, d: f64, k: f64, h: f64, _closing: bool) {
        let (n, hi) = (self.n, self.hi);
        let (vs, fs) = (stage * n, stage * (n + 1));
        for j in 0..=hi {
            if j < hi {
                let v = self.v[j];
                self.vs[vs + j] = v;
                self.u[j] += d * h * v;
            }
            let (f, slope) = self.contacts.force(&self.u, j).unwrap_or((0.0, 0.0));
            self.fs[fs + j] = f;
            self.slopes[fs + j] = slope;
            if j > 0 {
                let i = j - 1;
                let acc = (self.fs[fs + i] - f) * self.inv_m[i];
                self.accs[vs + i] = acc;
                self.v[i] += k * h * acc;
            }
        }
    }
}

/// The reverse pass: the derivatives of every [`Lane`]'s number with respect to every slot
/// (rows per slot, [`mass_slot`], [`eta_slot`], [`SPEED`], [`STEP`]; a lane per column; the
/// tie's lane is carried only when there is a tie). Compiled for AVX2 where the CPU has it (the
/// same bits: `integrators::simd`).
pub(super) fn reverse(
    chain: &Chain,
    splitting: &Splitting,
    tape: &Tape,
    out: &Outputs,
    keep_going: &mut dyn FnMut() -> bool,
    regenerate: Regenerate<'_>,
) -> Result<Vec<[f64; LANES]>, Stopped> {
    fn pad<const L: usize>(g: Vec<[f64; L]>) -> Vec<[f64; LANES]> {
        g.into_iter()
            .map(|x| std::array::from_fn(|l| x.get(l).copied().unwrap_or(0.0)))
            .collect()
    }
    #[cfg(target_arch = "x86_64")]
    {
        #[target_feature(enable = "avx2")]
        fn avx2<const L: usize>(
            chain: &Chain,
            splitting: &Splitting,
            tape: &Tape,
            out: &Outputs,
            keep_going: &mut dyn FnMut() -> bool,
            regenerate: Regenerate<'_>,
        ) -> Result<Vec<[f64; L]>, Stopped> {
            sweep::<L>(chain, splitting, tape, out, keep_going, regenerate)
        }
        if crate::integrators::simd::has_avx2() {
            // SAFETY: the CPU supports AVX2 (checked just above).
            return unsafe {
                match out.tie {
                    None => avx2::<4>(chain, splitting, tape, out, keep_going, regenerate).map(pad),
                    Some(_) => {
                        avx2::<LANES>(chain, splitting, tape, out, keep_going, regenerate).map(pad)
                    }
                }
            };
        }
    }
    match out.tie {
        None => sweep::<4>(chain, splitting, tape, out, keep_going, regenerate).map(pad),
        Some(_) => sweep::<LANES>(chain, splitting, tape, out, keep_going, regenerate).map(pad),
    }
}

/// Runs `len` steps again from a checkpoint, recording their pieces into the tape given
/// (`gradient`'s forward pass: the same steps, so the same pieces).
pub(super) type Regenerate<'a> = &'a mut dyn FnMut(&Checkpoint, u64, &mut Tape);

/// [`reverse`]'s body with `L` lanes, inlined into each instruction set's build: the
/// checkpointed segments last to first, each run again and swept back, then the steps recorded
/// piece by piece.
#[inline(always)]
fn sweep<const L: usize>(
    chain: &Chain,
    splitting: &Splitting,
    tape: &Tape,
    out: &Outputs,
    keep_going: &mut dyn FnMut() -> bool,
    regenerate: Regenerate<'_>,
) -> Result<Vec<[f64; L]>, Stopped> {
    let mut r = Reverse::<L>::new(chain, splitting);
    let full = tape.full_steps.unwrap_or(out.steps);
    if full < out.steps {
        let mut segment = Tape::take(tape.n);
        for c in (0..tape.cp_fronts.len()).rev() {
            let first = full + c as u64 * SEGMENT;
            let len = SEGMENT.min(out.steps - first);
            segment = Tape::take_from(segment, tape.n);
            regenerate(&tape.checkpoint(c), len, &mut segment);
            r.steps(&segment, first, first + len, out, keep_going)?;
        }
        segment.keep();
    }
    r.steps(tape, 0, full, out, keep_going)?;
    r.g_speed = r.vb[0];
    r.g_step[Lane::Impulse as usize] += out.impulse_per_step;
    let n = chain.len();
    let mut g = vec![[0.0; L]; 2 * n + 4];
    g[SPEED] = r.g_speed;
    g[STEP] = r.g_step;
    for (i, m) in r.gm.iter().enumerate() {
        g[mass_slot(i)] = *m;
    }
    for (c, e) in r.ge.iter().enumerate() {
        g[eta_slot(c)] = *e;
    }
    Ok(g)
}

/// The reverse pass's state: the adjoints of positions, velocities and the current
/// accelerations in `L` lanes, the slots' derivatives, and one piece's replay.
struct Reverse<'a, const L: usize> {
    splitting: &'a Splitting,
    n: usize,
    inv_m: Vec<f64>,
    contacts: Contacts,
    eta: Vec<f64>,
    ub: Vec<[f64; L]>,
    vb: Vec<[f64; L]>,
    ab: Vec<[f64; L]>,
    /// The derivatives with respect to each grain's mass, each contact's Hertz constant, the
    /// speed and the step.
    gm: Vec<[f64; L]>,
    ge: Vec<[f64; L]>,
    g_speed: [f64; L],
    g_step: [f64; L],
    /// The replayed piece: grains `0..hi` move in it; per stage the velocities before its
    /// drift, the forces and their slopes `dF/d delta` after it, the accelerations.
    hi: usize,
    u: Vec<f64>,
    v: Vec<f64>,
    a_in: Vec<f64>,
    vs: Vec<f64>,
    fs: Vec<f64>,
    slopes: Vec<f64>,
    accs: Vec<f64>,
}

impl<'a, const L: usize> Reverse<'a, L> {
    fn new(chain: &Chain, splitting: &'a Splitting) -> Self {
        let n = chain.len();
        let stages = splitting.drifts.len();
        let zero = [0.0; L];
        Reverse {
            splitting,
            n,
            inv_m: chain.mass().iter().map(|m| 1.0 / m).collect(),
            contacts: Contacts::new(chain),
            eta: (0..=n)
                .map(|k| chain.contact_law(k).map_or(0.0, |l| l.eta))
                .collect(),
            ub: vec![zero; n],
            vb: vec![zero; n],
            ab: vec![zero; n],
            gm: vec![zero; n],
            ge: vec![zero; n + 1],
            g_speed: zero,
            g_step: zero,
            hi: n,
            u: vec![0.0; n],
            v: vec![0.0; n],
            a_in: vec![0.0; n],
            vs: vec![0.0; stages * n],
            fs: vec![0.0; stages * (n + 1)],
            slopes: vec![0.0; stages * (n + 1)],
            accs: vec![0.0; stages * n],
        }
    }

    /// The sweep back through steps `s1` down to `s0 + 1` (of the whole run), recorded piece
    /// by piece in `tape` from step `s0 + 1` on.
    #[inline(always)]
    fn steps(
        &mut self,
        tape: &Tape,
        s0: u64,
        s1: u64,
        out: &Outputs,
        keep_going: &mut dyn FnMut() -> bool,
    ) -> Result<(), Stopped> {
        let pieces = tape.taus.len();
        for s in (s0 + 1..=s1).rev() {
            let local = (s - s0 - 1) as usize;
            let first = tape.steps[local];
            let end = tape.steps.get(local + 1).copied().unwrap_or(pieces);
            let mut carry = [0.0; L];
            for piece in (first..end).rev() {
                self.replay(tape, piece);
                if piece + 1 == end {
                    self.seed(out, s, out.dt);
                }
                let tau_bar = self.back(tape.taus[piece]);
                match tape.events[piece] {
                    u32::MAX => {
                        for (g, t) in self.g_step.iter_mut().zip(tau_bar) {
                            *g += t;
                        }
                        carry = tau_bar;
                    }
                    k => {
                        let mut t = tau_bar;
                        for (t, c) in t.iter_mut().zip(carry) {
                            *t -= c;
                        }
                        self.event(tape, piece, k as usize, t);
                    }
                }
            }
            if s % out.check_every == 0 && !keep_going() {
                return Err(Stopped);
            }
        }
        Ok(())
    }

    /// Replay piece `piece` from its state on the tape: the opening kick, then each stage's
    /// drift, forces, accelerations and kick, keeping what the sweep back reads. Only grains
    /// the wave can reach in the piece move (the front moves at most a grain per stage).
    #[inline(always)]
    fn replay(&mut self, tape: &Tape, piece: usize) {
        let n = self.n;
        let (u, v) = tape.state(piece);
        let m = u.len();
        let stages = self.splitting.drifts.len();
        let hi = (m + stages + 1).min(n);
        self.hi = hi;
        // Grains `m..=hi` are at rest: the positions the forces read past the last moving
        // grain are `0` too.
        let rest = (hi + 1).min(n);
        self.u[..m].copy_from_slice(u);
        self.u[m..rest].iter_mut().for_each(|x| *x = 0.0);
        self.v[..m].copy_from_slice(v);
        self.v[m..hi].iter_mut().for_each(|x| *x = 0.0);
        // The accelerations the piece starts from: the forces at its start, as the forward
        // pass's last stage computed them (the same operations, so the same bits).
        let mut left = 0.0;
        for j in 0..=hi {
            let (f, _) = self.contacts.force(&self.u, j).unwrap_or((0.0, 0.0));
            if j > 0 {
                self.a_in[j - 1] = (left - f) * self.inv_m[j - 1];
            }
            left = f;
        }
        // The piece is a whole step of the method over this carrier (`integrators::whole`:
        // the one sequence of stages of every carrier).
        let sp = self.splitting;
        whole(sp, self, tape.taus[piece]);
    }

    /// The numbers that enter at the end of step `s` (the replayed piece is its last): the
    /// watched force's weight in each lane, the target's energy, the rebound.
    #[inline(always)]
    fn seed(&mut self, out: &Outputs, s: u64, dt: f64) {
        let n = self.n;
        let mut w = [0.0; L];
        w[Lane::Peak as usize] = out.peak.weight(s);
        if let (Some(t), Some(w)) = (out.tie, w.get_mut(Lane::Tie as usize)) {
            *w = t.weight(s);
        }
        w[Lane::Impulse as usize] = if s == out.steps { 0.5 * dt } else { dt };
        let c = out.contact;
        let last = (self.splitting.drifts.len() - 1) * (n + 1);
        // A contact the wave has not reached in this piece has no force.
        let (f, slope) = if c <= self.hi {
            (self.fs[last + c], self.slopes[last + c])
        } else {
            (0.0, 0.0)
        };
        if f != 0.0 {
            for (l, w) in w.iter().enumerate() {
                self.ge[c][l] += w * f / self.eta[c];
                let db = w * slope;
                if c > 0 {
                    self.ub[c - 1][l] += db;
                }
                if c < n {
                    self.ub[c][l] -= db;
                }
            }
        }
        if let Some((ts, i, mv, ku)) = out.target {
            if ts == s {
                self.vb[i][Lane::Target as usize] += mv;
                self.ub[i][Lane::Target as usize] += ku;
            }
        }
        if s == out.steps {
            self.vb[0][Lane::Rebound as usize] += 1.0;
        }
    }

    /// The sweep back through the replayed piece of length `tau`: the adjoints of its end
    /// state (`ab` that of its last accelerations) become those of its start state (`ab` that of
    /// the accelerations it started from); returns the adjoint of `tau`.
    #[inline(always)]
    fn back(&mut self, tau: f64) -> [f64; L] {
        let n = self.n;
        let hi = self.hi;
        let sp = self.splitting;
        let stages = sp.drifts.len();
        let mut tb = [0.0; L];
        for s in (0..stages).rev() {
            let (d, k) = (sp.drifts[s], sp.kicks[s + 1]);
            let (vs, fs) = (s * n, s * (n + 1));
            // Kick `v += k tau a`, and the accelerations `a_i = (F_i - F_(i+1)) / m_i`: `ab`
            // becomes the adjoint of `F_i - F_(i+1)`.
            let kt = k * tau;
            let mut dot = [0.0; L];
            for ((((ab, vb), &acc), &im), gm) in self.ab[..hi]
                .iter_mut()
                .zip(&self.vb[..hi])
                .zip(&self.accs[vs..vs + hi])
                .zip(&self.inv_m[..hi])
                .zip(&mut self.gm[..hi])
            {
                for l in 0..L {
                    dot[l] += acc * vb[l];
                    let a = ab[l] + kt * vb[l];
                    gm[l] -= a * acc * im;
                    ab[l] = a * im;
                }
            }
            for l in 0..L {
                tb[l] += k * dot[l];
            }
            // Forces: `dF_c = F_c / eta_c d eta_c + slope d delta_c`, `delta_c = u_(c-1) - u_c`.
            let (fs, slopes) = (&self.fs[fs..fs + hi + 1], &self.slopes[fs..fs + hi + 1]);
            let (ab, ub, ge) = (&self.ab[..hi], &mut self.ub[..hi], &mut self.ge[..hi + 1]);
            let eta = &self.eta[..hi + 1];
            // An open contact has `F = 0` and `slope = 0`: it adds zeros, without a branch.
            for c in 0..=hi {
                let f = fs[c];
                let mut fb = if c < hi { ab[c] } else { [0.0; L] };
                if c > 0 {
                    for (x, a) in fb.iter_mut().zip(ab[c - 1]) {
                        *x -= a;
                    }
                }
                let (fe, slope) = (f / eta[c], slopes[c]);
                for l in 0..L {
                    ge[c][l] += fb[l] * fe;
                }
                let db = fb.map(|x| x * slope);
                if c > 0 {
                    for (u, x) in ub[c - 1].iter_mut().zip(db) {
                        *u += x;
                    }
                }
                if c < hi {
                    for (u, x) in ub[c].iter_mut().zip(db) {
                        *u -= x;
                    }
                }
            }
            // The accelerations' adjoints are spent; the drift `u += d tau v`.
            let dt = d * tau;
            let mut dot = [0.0; L];
            for (((ab, ub), vb), &v) in self.ab[..hi]
                .iter_mut()
                .zip(&self.ub[..hi])
                .zip(&mut self.vb[..hi])
                .zip(&self.vs[vs..vs + hi])
            {
                *ab = [0.0; L];
                for l in 0..L {
                    dot[l] += v * ub[l];
                    vb[l] += dt * ub[l];
                }
            }
            for l in 0..L {
                tb[l] += d * dot[l];
            }
        }
        // The opening kick `v += k0 tau a_in`.
        let k0 = sp.kicks[0];
        let mut dot = [0.0; L];
        for ((ab, vb), &a) in self.ab[..hi]
            .iter_mut()
            .zip(&self.vb[..hi])
            .zip(&self.a_in[..hi])
        {
            for l in 0..L {
                dot[l] += a * vb[l];
                ab[l] = k0 * tau * vb[l];
            }
        }
        for l in 0..L {
            tb[l] += k0 * dot[l];
        }
        tb
    }

    /// A piece ended by contact `k`'s event (the replayed piece): its length `tau` is the root
    /// of the overlap
    /// polynomial `delta + delta' t + delta'' t^2 / 2` at the piece's start, so `d tau = -(d
    /// delta + tau d delta' + tau^2 / 2 d delta'') / P'(tau)`: `tb`, the adjoint of `tau`, goes to
    /// the start's positions, velocities and accelerations of the contact's two grains.
    #[inline(always)]
    fn event(&mut self, tape: &Tape, piece: usize, k: usize, tb: [f64; L]) {
        let n = self.n;
        let (_, v) = tape.state(piece);
        let a = &self.a_in;
        let tau = tape.taus[piece];
        let side = |i: Option<usize>| match i {
            Some(i) if i < v.len() => (v[i], a[i]),
            _ => (0.0, 0.0),
        };
        let (l, r) = (k.checked_sub(1), (k < n).then_some(k));
        let ((vl, al), (vr, ar)) = (side(l), side(r));
        let slope = (vl - vr) + (al - ar) * tau;
        for (i, sign) in [(l, 1.0), (r, -1.0)] {
            let Some(i) = i else { continue };
            let c = -sign / slope;
            let (ub, vb, ab) = (&mut self.ub[i], &mut self.vb[i], &mut self.ab[i]);
            for (((t, u), v), a) in tb.iter().zip(ub).zip(vb).zip(ab) {
                let t = t * c;
                *u += t;
                *v += t * tau;
                *a += t * 0.5 * tau * tau;
            }
        }
    }
}
