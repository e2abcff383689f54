//! Contact events located inside the step (`integrator.events`, verlet and blanes-moan4).
//!
//! A contact force `eta delta^p` is not smooth where the overlap `delta` crosses zero (C^0 for
//! p = 1, C^1 for Hertz), and a step that straddles that instant is computed as if it were:
//! the error of that one step is of low order whatever the method. With events on, each step
//! of the fixed grid is cut at the instants where a contact closes or opens, and each piece is
//! a whole (unfused) step of the method over a stretch where every contact keeps its state.
//!
//! The instant is predicted from the state at the piece's start: the overlap's Taylor
//! polynomial `delta + delta' tau + delta'' tau^2 / 2` (velocities and accelerations of the two
//! grains), whose root is off the true one by O(h^3). A piece that ends that close to the true
//! instant carries a kink of size `eta |delta|^p` over a time O(h^3), an error O(h^(3 (p + 1)))
//! per event: far below the method's own. The loop that cuts the steps is the splitting
//! methods' (`splitting::cut_at_events`); the watchers (load, peak speeds, reflections) see the
//! states on the grid only, so every output keeps its times.
//!
//! What this does not bring back: a Hertz force grows as `(t - t*)^(3/2)` from the closing
//! instant, not smooth on the closed side either, so the steps just after it keep an error
//! O(h^(5/2)) per contact (`validation/orders.rs` measures it).
//!
//! A damped contact (`chain::damping`) has a second kind of event: the clamp, where its total
//! force `eta delta^p + c delta^q delta'` reaches zero while it is closed (the grains separate
//! with no force from there) or comes back. The total force is continuous there with a kink;
//! the instant is the root of `eta delta^(p - q) + c delta'` on the same overlap polynomial,
//! whose accelerations then include the dashpots'. With both located, the restitution of a
//! damped collision converges at order 2 per halving; unlocated, the kinks fall anywhere in a
//! step and the error's constant with them (`validation/orders.rs`).

use crate::chain::{Chain, Window};
use crate::state::State;

/// A predicted event closer than this fraction of the step to a piece's end is not split off
/// (the kink it leaves is of order `eta (v h 1e-9)^p` over `1e-9 h`).
const NEGLIGIBLE: f64 = 1e-9;

/// An event is not split off when the whole force its contact can reach over the rest of the
/// step would change a velocity by less than this fraction of the largest relative speed of
/// the contacts (at the last prediction): such a kink is below what any accuracy can ask of
/// doubles. This is what keeps a wave's front cheap: each force evaluation closes a contact
/// there with an overlap far below anything physical (a Hertz precursor decays faster than
/// exponentially), and locating those would cut almost every step into many pieces.
const INSIGNIFICANT: f64 = 1e-14;

/// The contacts that can change state: per contact `k` (`0..=n`) its overlap at rest
/// `delta0` (infinite where there is no contact or its force is smooth through zero, a
/// tension law: such a contact never crosses zero), its exponent, and `eta / m` of its lighter
/// grain.
#[derive(Clone, Debug, Default)]
pub(crate) struct Events {
    delta0: Vec<f64>,
    power: Vec<f64>,
    stiffness: Vec<f64>,
    /// Per contact: `eta`, the dashpot's `c` (zero: undamped, or two-sided) and `p - q`, the
    /// exponent of `delta` in `eta delta^(p - q) + c delta'`, whose sign is the total force's
    /// (the clamp, `chain::damping`).
    damping: Vec<(f64, f64, f64)>,
    /// Whether any contact has a dashpot (else no contact can clamp, and the scan skips it).
    damped: bool,
    gravity: f64,
    /// The largest relative speed of a contact at the last prediction.
    scale: f64,
}

impl Events {
    /// The largest relative speed of a contact at the last prediction: with the state, what
    /// decides the next cuts (a run taken on again from a checkpoint sets it back,
    /// `protector::gradient`).
    pub fn scale(&self) -> f64 {
        self.scale
    }

    /// Set [`Events::scale`].
    pub fn set_scale(&mut self, scale: f64) {
        self.scale = scale;
    }

    /// For `chain`.
    pub fn new(chain: &Chain) -> Self {
        let n = chain.len();
        let m = chain.mass();
        let mut e = Events {
            gravity: chain.gravity(),
            ..Events::default()
        };
        for k in 0..=n {
            let lightest = match (k.checked_sub(1).map(|i| m[i]), m.get(k)) {
                (Some(a), Some(&b)) => a.min(b),
                (Some(a), None) => a,
                (None, Some(&b)) => b,
                (None, None) => f64::INFINITY,
            };
            let (d0, p, s) = match chain.contact_law(k) {
                Some(law) if !law.tension => (law.delta0, law.p, law.eta / lightest),
                _ => (f64::INFINITY, 1.0, 0.0),
            };
            let damping = match chain.contact_law(k) {
                Some(law) if !law.tension => law
                    .damping
                    .filter(|d| d.c > 0.0)
                    .map_or((0.0, 0.0, 0.0), |d| {
                        (law.eta, d.c, law.p - d.model.exponent(law.p))
                    }),
                _ => (0.0, 0.0, 0.0),
            };
            e.damped |= damping.1 > 0.0;
            e.damping.push(damping);
            e.delta0.push(d0);
            e.power.push(p);
            e.stiffness.push(s);
        }
        e
    }

    /// The earliest instant within `(0, left)` after `state` (synchronized velocities,
    /// accelerations `a` of the contact forces, dashpots included) where a contact of the
    /// window is predicted to close or open, or a damped contact to clamp or unclamp (its total
    /// force to reach zero while closed, `chain::damping`), and matters ([`INSIGNIFICANT`]), as
    /// the time from `state.t`, with that contact (a carrier of derivatives needs its overlap
    /// polynomial: `protector::gradient`); `None` if there is none (or it lies within
    /// [`NEGLIGIBLE`] of either end).
    pub fn first(
        &mut self,
        state: &State,
        a: &[f64],
        win: &Window,
        left: f64,
    ) -> Option<(f64, usize)> {
        let (u, v) = (&state.u, &state.v);
        let n = u.len();
        let g = self.gravity;
        let mut scan = Scan {
            floor: INSIGNIFICANT * self.scale,
            lo_cut: NEGLIGIBLE * left,
            left,
            best: left - NEGLIGIBLE * left,
            found: false,
            which: 0,
            scale: 0.0,
        };
        for isl in win.islands() {
            let (lo, hi) = (isl.lo, isl.hi);
            if lo >= hi {
                continue;
            }
            // The island's edge contacts: the grain beyond each edge is at rest (v = 0, no
            // acceleration), a wall's side fixed.
            let left_grain = if lo == 0 {
                (0.0, 0.0, 0.0)
            } else {
                (u[lo - 1], 0.0, 0.0)
            };
            scan.contact(self, lo, left_grain, (u[lo], v[lo], a[lo] + g));
            let right_grain = if hi == n {
                (0.0, 0.0, 0.0)
            } else {
                (u[hi], 0.0, 0.0)
            };
            scan.contact(self, hi, (u[hi - 1], v[hi - 1], a[hi - 1] + g), right_grain);
            // Interior contacts lo + 1..hi (gravity acts on both grains alike); their largest
            // relative speed in a pass of its own (`largest_speed`).
            scan.scale = largest_speed(&v[lo..hi], scan.scale);
            if self.damped {
                for k in lo + 1..hi {
                    let x0 = self.delta0[k] + u[k - 1] - u[k];
                    let x1 = v[k - 1] - v[k];
                    let x2 = 0.5 * (a[k - 1] - a[k]);
                    scan.predict(self, k, x0, x1, x2);
                    scan.clamp(self, k, x0, x1, x2);
                }
            } else {
                // No dashpot: the same scan without the clamp's test (which returns at once).
                for k in lo + 1..hi {
                    let x0 = self.delta0[k] + u[k - 1] - u[k];
                    let x1 = v[k - 1] - v[k];
                    let x2 = 0.5 * (a[k - 1] - a[k]);
                    scan.predict(self, k, x0, x1, x2);
                }
            }
        }
        self.scale = scan.scale;
        scan.found.then_some((scan.best, scan.which))
    }
}

/// One prediction sweep's state.
struct Scan {
    floor: f64,
    lo_cut: f64,
    left: f64,
    best: f64,
    found: bool,
    /// The contact of `best`.
    which: usize,
    scale: f64,
}

impl Scan {
    /// A contact between grains `(u, v, a)` on its left and right.
    #[inline(always)]
    fn contact(&mut self, e: &Events, k: usize, l: (f64, f64, f64), r: (f64, f64, f64)) {
        let x0 = e.delta0[k] + l.0 - r.0;
        let (x1, x2) = (l.1 - r.1, 0.5 * (l.2 - r.2));
        self.overlap(e, k, x0, x1, x2);
        self.clamp(e, k, x0, x1, x2);
    }

    /// Contact `k` whose overlap is `x0 + x1 t + x2 t^2`, its relative speed `x1` counted in
    /// the scale.
    #[inline(always)]
    fn overlap(&mut self, e: &Events, k: usize, x0: f64, x1: f64, x2: f64) {
        self.scale = self.scale.max(x1.abs());
        self.predict(e, k, x0, x1, x2);
    }

    /// Contact `k` whose overlap is `x0 + x1 t + x2 t^2`: the earliest event so far if its
    /// overlap crosses zero first and matters.
    #[inline(always)]
    fn predict(&mut self, e: &Events, k: usize, x0: f64, x1: f64, x2: f64) {
        // Most contacts cannot reach zero within the step: the polynomial moves by at most
        // `reach` (an infinite `delta0`, no event possible, never does).
        let b = self.best;
        let reach = (x1.abs() + x2.abs() * b) * b;
        if x0.abs() >= reach {
            return;
        }
        let Some(hi) = crossing(x0, x1, x2, b) else {
            return;
        };
        // The most this contact's force can change a velocity over the step: its force at
        // the largest overlap speed reached, times the step.
        let speed = x1.abs() + 2.0 * x2.abs() * self.left;
        let kick = e.stiffness[k] * (speed * self.left).powf(e.power[k]) * self.left;
        if kick < self.floor {
            return;
        }
        let t = bisect(x0, x1, x2, hi);
        if t > self.lo_cut {
            self.best = t;
            self.found = true;
            self.which = k;
        }
    }

    /// A damped contact `k` whose overlap is `x0 + x1 t + x2 t^2`: where its total force's sign,
    /// that of `eta x^(p - q) + c x'`, changes while it is closed (the clamp).
    #[inline(always)]
    fn clamp(&mut self, e: &Events, k: usize, x0: f64, x1: f64, x2: f64) {
        let (eta, c, pq) = e.damping[k];
        if c == 0.0 || x0 <= 0.0 {
            return;
        }
        let b = self.best;
        let h = |t: f64| {
            let x = (x0 + t * (x1 + t * x2)).max(0.0);
            eta * x.powf(pq) + c * (x1 + 2.0 * t * x2)
        };
        let (h0, hb) = (h(0.0), h(b));
        if (h0 > 0.0) == (hb > 0.0) {
            return;
        }
        // The kink is a change of slope of a force of at most `eta x0^p`, felt by the lighter
        // grain over the step.
        if e.stiffness[k] * x0.powf(e.power[k]) * self.left < self.floor {
            return;
        }
        let (mut lo, mut hi) = (0.0, b);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            if (h(mid) > 0.0) == (h0 > 0.0) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        if hi > self.lo_cut {
            self.best = hi;
            self.found = true;
            self.which = k;
        }
    }
}

/// The larger of `scale` and the largest `|v[i] - v[i + 1]|`: the relative speeds of the
/// contacts between the grains `v` holds. Four running maxima rather than one: a single one
/// chains each contact's step of the scan to the last one's, and the maximum of a set is exact
/// in any order (the bits are a single running maximum's; the speeds are never NaN where it
/// matters, and `f64::max` skips a NaN either way).
#[inline(always)]
fn largest_speed(v: &[f64], scale: f64) -> f64 {
    let mut m = [scale; 4];
    let (pairs, rest) = (v.len().saturating_sub(1) / 4, v.len().saturating_sub(1) % 4);
    for c in 0..pairs {
        for (j, m) in m.iter_mut().enumerate() {
            let i = 4 * c + j;
            *m = m.max((v[i] - v[i + 1]).abs());
        }
    }
    for i in 4 * pairs..4 * pairs + rest {
        m[0] = m[0].max((v[i] - v[i + 1]).abs());
    }
    m[0].max(m[1]).max(m[2].max(m[3]))
}

/// Where `x0 + x1 t + x2 t^2` changes the sign of `x0 > 0` (closed against open) in `(0, b)`:
/// the end of a bracket of its first such root (`b`, or the extremum inside), if any.
#[inline(always)]
fn crossing(x0: f64, x1: f64, x2: f64, b: f64) -> Option<f64> {
    let p = |t: f64| x0 + t * (x1 + t * x2);
    let closed = x0 > 0.0;
    if (p(b) > 0.0) != closed {
        return Some(b);
    }
    // An extremum inside that crosses and comes back within the step.
    let tm = -x1 / (2.0 * x2);
    (tm > 0.0 && tm < b && (p(tm) > 0.0) != closed).then_some(tm)
}

/// The root of `x0 + x1 t + x2 t^2` in the bracket `(0, hi)` of [`crossing`], by bisection.
fn bisect(x0: f64, x1: f64, x2: f64, mut hi: f64) -> f64 {
    let p = |t: f64| x0 + t * (x1 + t * x2);
    let closed = x0 > 0.0;
    let mut lo = 0.0;
    // 60 halvings reach the rounding of `hi`.
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if (p(mid) > 0.0) != closed {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    hi
}

/// The first root of [`crossing`] and [`bisect`] (for the tests).
#[cfg(test)]
fn first_root(x0: f64, x1: f64, x2: f64, b: f64) -> Option<f64> {
    crossing(x0, x1, x2, b).map(|hi| bisect(x0, x1, x2, hi))
}

#[cfg(test)]
mod tests {
    use super::first_root;

    #[test]
    fn roots_of_the_overlap_polynomial() {
        // Closing at t = 0.25 (linear), inside a step of 1.
        let t = first_root(-0.25, 1.0, 0.0, 1.0).unwrap();
        assert!((t - 0.25).abs() < 1e-15, "{t}");
        // Opening: 1 - t^2 = 0 at t = 1, beyond a step of 0.5.
        assert_eq!(first_root(1.0, 0.0, -1.0, 0.5), None);
        // A brief contact inside the step: -0.01 + t - t^2 closes at t = 0.0101...
        let t = first_root(-0.01, 1.0, -1.0, 2.0).unwrap();
        let exact = (1.0 - (1.0f64 - 0.04).sqrt()) / 2.0;
        assert!((t - exact).abs() < 1e-15, "{t} against {exact}");
        // No sign change and an extremum that does not cross.
        assert_eq!(first_root(1.0, -1.0, 1.0, 2.0), None);
    }
}
