//! Reflections counted: the pulses that meet the two edges of a stretch of grains (a container),
//! after every step, with the energy each brings and the energy it sends out (Hong 2005's
//! mechanism: energy leaks when a solitary wave is partly transmitted at a container wall).
//!
//! The rule, applied to each edge contact of the stretch `first..=last` (contact `first`, between
//! grain `first - 1` outside and `first` inside; contact `last + 1` on the right; an edge at the
//! chain's end is its wall's contact) after every step:
//!
//! 1. A *hit* starts when the edge contact closes (its force turns positive) and ends when it
//!    opens again. Inside a hit, a dip of the force to `m` between two maxima `P` (the hit's
//!    largest force so far) and `Q` splits it in two when `m < valley * min(P, Q)`: two waves
//!    arriving one after the other are two hits even if the contact never opens between them.
//! 2. The *transmitted* energy of a hit is the work the edge contact did on the grain outside
//!    over the hit, `sum of (F_before + F_after) / 2 * (outward displacement of that grain)` over
//!    its steps (positions only, so exact to the step's second order; 0 against a wall).
//! 3. The *incident* energy is the largest, over the steps at which the edge force rises to a
//!    new maximum of the hit (its start included), of the energy moving outwards in the `zone`
//!    grains inside the edge plus what the hit has transmitted so far. The energy moving
//!    outwards: the kinetic energy of each grain moving outwards, the potential of each of their
//!    contacts whose two grains move outwards on average (the edge contact's whole, the inner
//!    boundary's half). As the arriving pulse presses into the edge it is all in the zone and
//!    still moving out (a wave's energy lies within about five grains,
//!    `problems::SolitaryWave`; the default zone is 10), while a pulse an earlier hit sent
//!    back, still in the zone, moves inwards and is left out. Whatever else moves outwards in
//!    the zone counts too, which makes the incident energy an upper bound when pulses crowd; a
//!    pulse spread over more than the zone (a linear section's dispersing pulse) is only partly
//!    counted.
//!
//! The velocities a splitting method holds after a step include the next step's opening kick
//! (a fraction of the step for blanes-moan4, half of it for verlet): the incident energy's
//! kinetic part carries that shift, which is O(dt) against a pulse's duration.
//!
//! One wave between two walls `L` grains apart, moving at `c` grains per unit time, hits each
//! wall `c / (2 L)` times per unit time, with nothing transmitted; `validation/mechanism.rs`
//! checks that and the transmitted share of a light-to-heavy interface.

use super::load::contact_force;
use crate::chain::Chain;
use crate::state::State;
use serde::{Deserialize, Serialize};

/// Which edge of the watched stretch.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Edge {
    /// The left edge (contact `first`).
    Left,
    /// The right edge (contact `last + 1`).
    Right,
}

/// The settings of the counting rule (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ReflectionRule {
    /// A dip of the edge force below this fraction of the smaller neighbouring maximum splits a
    /// hit in two.
    pub valley: f64,
    /// Grains inside each edge whose outward-moving energy is a hit's incident energy.
    pub zone: usize,
}

impl Default for ReflectionRule {
    fn default() -> Self {
        ReflectionRule {
            valley: 0.5,
            zone: 10,
        }
    }
}

impl ReflectionRule {
    /// Whether the rule's numbers make sense: `valley` in `(0, 1)`, `zone` at least 1.
    pub fn check(&self) -> Result<(), String> {
        if !(self.valley > 0.0 && self.valley < 1.0) {
            return Err(format!(
                "a hit's valley fraction must lie in (0, 1), got {}",
                self.valley
            ));
        }
        if self.zone == 0 {
            return Err("the incident energy's zone must hold at least 1 grain".into());
        }
        Ok(())
    }
}

/// One hit of a pulse on an edge (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Reflection {
    /// The edge it met.
    pub edge: Edge,
    /// Time of the edge force's largest value in the hit.
    pub time: f64,
    /// That force.
    pub peak_force: f64,
    /// The largest energy moving outwards in the zone inside the edge while the force rose,
    /// plus what had been transmitted by then (module docs, rule 3).
    pub incident: f64,
    /// Work done on the grain outside over the hit.
    pub transmitted: f64,
}

/// The work done on the grains beyond the edges since the watch started ([`Edge::Left`]
/// first), and the part of it done in hits that have not ended (so not yet in any
/// [`Reflection`]): energy sent out, negative where energy came in.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct EdgeWork {
    /// Work through each edge since the start.
    pub sent: [f64; 2],
    /// Work through each edge in the hit still going on.
    pub open: [f64; 2],
}

/// One edge's state between steps.
#[derive(Clone, Debug)]
struct EdgeState {
    edge: Edge,
    /// The edge contact.
    contact: usize,
    /// The grain outside (`None`: a wall).
    outside: Option<usize>,
    /// The zone's grains `[lo, hi]` inside the edge.
    lo: usize,
    hi: usize,
    /// +1 when the outside lies to the right (outward displacement positive), -1 on the left.
    sign: f64,
    force: f64,
    x: f64,
    /// Work done on the outside since the watch started.
    work: f64,
    hit: Option<Hit>,
}

#[derive(Clone, Copy, Debug)]
struct Hit {
    /// `work` when the hit started.
    start: f64,
    peak: f64,
    peak_time: f64,
    incident: f64,
    /// The lowest force since the peak and `work` then.
    dip: f64,
    dip_work: f64,
}

impl Hit {
    /// The hit as ended, at `edge`, having sent out `transmitted`.
    fn reflection(&self, edge: Edge, transmitted: f64) -> Reflection {
        Reflection {
            edge,
            time: self.peak_time,
            peak_force: self.peak,
            incident: self.incident,
            transmitted,
        }
    }
}

/// Counts reflections at the two edges of a stretch after every step (switched on by
/// [`crate::Simulation::watch_reflections`]); off by default, when a step pays one branch.
#[derive(Clone, Debug, Default)]
pub struct ReflectionWatch {
    on: bool,
    valley: f64,
    t0: f64,
    steps: u64,
    dt: f64,
    edges: Vec<EdgeState>,
    found: Vec<Reflection>,
}

impl ReflectionWatch {
    /// Start watching the edges of grains `first..=last` of `chain` from `state`, with steps of
    /// `dt`. The caller has checked that the stretch lies inside the chain and has room for the
    /// zone.
    pub(crate) fn start(
        &mut self,
        chain: &Chain,
        state: &State,
        dt: f64,
        first: usize,
        last: usize,
        rule: ReflectionRule,
    ) {
        let n = chain.len();
        let zone = rule.zone.min(last + 1 - first);
        let mut edges = Vec::with_capacity(2);
        for edge in [Edge::Left, Edge::Right] {
            let (contact, outside, lo, hi, sign) = match edge {
                Edge::Left => (first, first.checked_sub(1), first, first + zone - 1, -1.0),
                Edge::Right => (
                    last + 1,
                    (last + 1 < n).then_some(last + 1),
                    last + 1 - zone,
                    last,
                    1.0,
                ),
            };
            let mut e = EdgeState {
                edge,
                contact,
                outside,
                lo,
                hi,
                sign,
                force: 0.0,
                x: 0.0,
                work: 0.0,
                hit: None,
            };
            e.force = contact_force(chain, state, contact);
            e.x = outside.map_or(0.0, |g| state.u[g]);
            edges.push(e);
        }
        *self = ReflectionWatch {
            on: true,
            valley: rule.valley,
            t0: state.t,
            steps: 0,
            dt,
            edges,
            found: Vec::new(),
        };
    }

    /// Whether the watch is on.
    pub fn is_on(&self) -> bool {
        self.on
    }

    /// The work sent through each edge so far ([`EdgeWork`]).
    pub fn work(&self) -> EdgeWork {
        let mut w = EdgeWork::default();
        for (i, e) in self.edges.iter().enumerate().take(2) {
            w.sent[i] = e.work;
            w.open[i] = e.hit.map_or(0.0, |h| e.work - h.start);
        }
        w
    }

    /// End the hits still going on, as if their contacts opened now (at the end of a run, so
    /// that the hits hold all the work through the edges), and take every hit.
    pub fn end(&mut self) -> Vec<Reflection> {
        for e in &mut self.edges {
            if let Some(h) = e.hit.take() {
                self.found.push(h.reflection(e.edge, e.work - h.start));
            }
        }
        self.take()
    }

    /// Take the hits that have ended so far (the watch goes on).
    pub fn take(&mut self) -> Vec<Reflection> {
        std::mem::take(&mut self.found)
    }

    /// Fold in the state after a step of `dt`.
    #[inline(always)]
    pub(crate) fn update(&mut self, chain: &Chain, state: &State) {
        if self.on {
            self.record(chain, state);
        }
    }

    #[inline(never)]
    fn record(&mut self, chain: &Chain, state: &State) {
        self.steps += 1;
        let (t, valley) = (self.t0 + self.steps as f64 * self.dt, self.valley);
        for e in &mut self.edges {
            let f = contact_force(chain, state, e.contact);
            let x = e.outside.map_or(0.0, |g| state.u[g]);
            let before = e.work;
            e.work += 0.5 * (e.force + f) * e.sign * (x - e.x);
            e.force = f;
            e.x = x;
            match &mut e.hit {
                None => {
                    if f > 0.0 {
                        let incident = zone_energy(chain, state, e.lo, e.hi, e.edge, e.outside);
                        e.hit = Some(Hit {
                            start: before,
                            peak: f,
                            peak_time: t,
                            incident,
                            dip: f,
                            dip_work: e.work,
                        });
                    }
                }
                Some(h) => {
                    if f <= 0.0 {
                        self.found.push(h.reflection(e.edge, e.work - h.start));
                        e.hit = None;
                    } else if f > h.peak {
                        h.peak = f;
                        h.peak_time = t;
                        let now = zone_energy(chain, state, e.lo, e.hi, e.edge, e.outside)
                            + (e.work - h.start);
                        h.incident = h.incident.max(now);
                        h.dip = f;
                        h.dip_work = e.work;
                    } else if f < h.dip {
                        h.dip = f;
                        h.dip_work = e.work;
                    } else if h.dip < valley * f.min(h.peak) {
                        // A deep dip between two maxima: the hit ended at the dip, a new one
                        // started there.
                        self.found.push(h.reflection(e.edge, h.dip_work - h.start));
                        let start = h.dip_work;
                        let incident = zone_energy(chain, state, e.lo, e.hi, e.edge, e.outside);
                        *h = Hit {
                            start,
                            peak: f,
                            peak_time: t,
                            incident,
                            dip: f,
                            dip_work: e.work,
                        };
                    }
                }
            }
        }
    }
}

/// The energy moving outwards in grains `lo..=hi` (module docs, rule 3): the kinetic energy of
/// the grains moving outwards, the potential of the contacts between them, of the edge contact
/// (whole) and of the inner boundary contact (half) whose two grains move outwards on average.
fn zone_energy(
    chain: &Chain,
    state: &State,
    lo: usize,
    hi: usize,
    edge: Edge,
    outside: Option<usize>,
) -> f64 {
    let (m, v) = (chain.mass(), &state.v);
    let sign = match edge {
        Edge::Left => -1.0,
        Edge::Right => 1.0,
    };
    let n = v.len();
    let speed = |i: Option<usize>| i.filter(|&i| i < n).map_or(0.0, |i| v[i]);
    let out = |k: usize| {
        // Contact k joins grains k - 1 and k.
        sign * (speed(k.checked_sub(1)) + speed(Some(k))) > 0.0
    };
    let mut e = 0.0;
    for i in lo..=hi {
        if sign * v[i] > 0.0 {
            e += 0.5 * m[i] * v[i] * v[i];
        }
    }
    for k in lo + 1..=hi {
        if out(k) {
            e += chain.contact_energy(&state.u, k);
        }
    }
    let (edge_contact, boundary) = match edge {
        Edge::Left => (lo, hi + 1),
        Edge::Right => (hi + 1, lo),
    };
    // The edge contact against a wall: the grain inside decides.
    let edge_out = match outside {
        Some(_) => out(edge_contact),
        None => sign * v[if edge == Edge::Left { lo } else { hi }] > 0.0,
    };
    if edge_out {
        e += chain.contact_energy(&state.u, edge_contact);
    }
    if out(boundary) {
        e += 0.5 * chain.contact_energy(&state.u, boundary);
    }
    e
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_rule_checks_itself() {
        assert!(ReflectionRule::default().check().is_ok());
        assert!(ReflectionRule {
            valley: 1.0,
            zone: 10
        }
        .check()
        .is_err());
        assert!(ReflectionRule {
            valley: 0.5,
            zone: 0
        }
        .check()
        .is_err());
    }
}
