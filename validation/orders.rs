//! The order each method reaches on a contact (issue 40, its groundwork): the work-precision
//! order problems (`grainchain work-precision --only collision-hertz,collision-linear,restitution`)
//! run here in full, their observed order per halving of dt recorded in the report.
//!
//! The contact force is not smooth where the contact closes and opens (`eta delta^p`, p = 3/2 or
//! 1), and a damped contact's force is clipped to stay compressive, so no method reaches its
//! nominal order on these problems today; that is what is measured, not asserted. What is
//! asserted is true today with its reason: the references are right (the elastic closed forms;
//! the restitution against this file's own integration of the contact's equation, which uses no
//! grainchain code), every method converges, and the finest errors are below stated bounds.

use crate::common;

use common::{g, record_one, Row};
use grainchain::work_precision::{self as wp, Benchmark};
use grainchain_engine::problems::TwoGrainCollision;
use grainchain_engine::DampingModel;

/// The contact `mu x'' = -max(eta x^p + c x^q x', 0)` from `x = 0`, `x' = v`: the outgoing rate
/// `x'` when the contact ends (the force reaches zero: `x = 0` when elastic, the clip when
/// damped; after it both terms only fall, so the grains fly apart).
///
/// Independent of grainchain: classical RK4 in the variable `y = x^(1/4)` near `x = 0` (where
/// `x^(3/2)`, `x^(1/2)`, `x^(1/4)` are not smooth in time but are polynomials in `y`:
/// `dx'/dy = 4 y^3 x'' / x'`), in time in the middle (through the turning point `x' = 0`). The
/// contact's end is found on the cubic Hermite interpolant of the last step by bisection. `n`
/// steps per piece. Also the reference of
/// `protector_reference::the_restitution_of_each_damping_model`.
pub(crate) struct Contact {
    pub(crate) p: f64,
    pub(crate) eta: f64,
    pub(crate) mu: f64,
    pub(crate) q: f64,
    pub(crate) c: f64,
}

impl Contact {
    /// The force before the clip (its zero ends a damped contact).
    fn force(&self, x: f64, w: f64) -> f64 {
        let x = x.max(0.0);
        self.eta * x.powf(self.p) + self.c * x.powf(self.q) * w
    }

    fn ends(&self, x: f64, w: f64) -> bool {
        if self.c == 0.0 {
            x <= 0.0
        } else {
            self.force(x, w) <= 0.0
        }
    }

    /// d/ds of (x, w) for s = t (`in_time`) or s = y.
    fn rate(&self, s: f64, z: [f64; 2], in_time: bool) -> [f64; 2] {
        if in_time {
            [z[1], -self.force(z[0], z[1]) / self.mu]
        } else {
            let dx = 4.0 * s.powi(3);
            let x = s.powi(4);
            [dx, dx * (-self.force(x, z[1]) / self.mu) / z[1]]
        }
    }

    fn rk4(&self, s: f64, z: [f64; 2], h: f64, in_time: bool) -> [f64; 2] {
        let add = |a: [f64; 2], b: [f64; 2], k: f64| [a[0] + k * b[0], a[1] + k * b[1]];
        let k1 = self.rate(s, z, in_time);
        let k2 = self.rate(s + h / 2.0, add(z, k1, h / 2.0), in_time);
        let k3 = self.rate(s + h / 2.0, add(z, k2, h / 2.0), in_time);
        let k4 = self.rate(s + h, add(z, k3, h), in_time);
        [
            z[0] + h / 6.0 * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0]),
            z[1] + h / 6.0 * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1]),
        ]
    }

    /// The end of the contact inside the step (s0, z0) -> (s0 + h, z1): bisection on the cubic
    /// Hermite interpolant of (x, w) (its error is of order h^4, below 1e-15 at the steps used).
    fn end_in_step(&self, s0: f64, z0: [f64; 2], z1: [f64; 2], h: f64, in_time: bool) -> f64 {
        let (d0, d1) = (self.rate(s0, z0, in_time), self.rate(s0 + h, z1, in_time));
        let at = |th: f64| -> [f64; 2] {
            let h00 = (1.0 + 2.0 * th) * (1.0 - th) * (1.0 - th);
            let h10 = th * (1.0 - th) * (1.0 - th);
            let h01 = th * th * (3.0 - 2.0 * th);
            let h11 = th * th * (th - 1.0);
            let f = |i: usize| h00 * z0[i] + h10 * h * d0[i] + h01 * z1[i] + h11 * h * d1[i];
            [f(0), f(1)]
        };
        let (mut lo, mut hi) = (0.0f64, 1.0f64);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            let z = at(mid);
            if self.ends(z[0], z[1]) {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        at(hi)[1]
    }

    pub(crate) fn outgoing_rate(&self, v: f64, n: usize) -> f64 {
        let x_max =
            ((self.p + 1.0) * self.mu * v * v / (2.0 * self.eta)).powf(1.0 / (self.p + 1.0));
        // Leave the y-pieces at a fifth of the elastic largest overlap (w is far from 0 there).
        let x_edge = 0.2 * x_max;
        let y_edge = x_edge.powf(0.25);
        let mut z = [0.0, v];
        let dy = y_edge / n as f64;
        for k in 0..n {
            z = self.rk4(k as f64 * dy, z, dy, false);
        }
        z[0] = x_edge;
        let h = x_max / v / n as f64;
        let mut t = 0.0;
        loop {
            let z1 = self.rk4(t, z, h, true);
            if self.ends(z1[0], z1[1]) {
                return self.end_in_step(t, z, z1, h, true);
            }
            z = z1;
            t += h;
            if z[1] < 0.0 && z[0] < x_edge {
                break;
            }
            assert!(t < 100.0 * x_max / v, "the contact does not open");
        }
        let y0 = z[0].powf(0.25);
        let dy = -y0 / n as f64;
        for k in 0..n {
            let y = y0 + k as f64 * dy;
            let mut z1 = self.rk4(y, z, dy, false);
            z1[0] = (y + dy).max(0.0).powi(4);
            if self.c != 0.0 && self.ends(z1[0], z1[1]) {
                return self.end_in_step(y, z, z1, dy, false);
            }
            z = z1;
        }
        z[1]
    }
}

/// The restitution problem of work-precision: unit Hertz grains (eta = 1, mu = 1/2), speed 1.
fn restitution_contact(model: DampingModel) -> Contact {
    // q of each model, written out here (law.rs `DampingModel::exponent` is the code under test).
    let q = match model {
        DampingModel::Viscous => 0.0,
        DampingModel::KuwabaraKono => 0.5,
        DampingModel::ScaleRespecting => 0.25,
    };
    Contact {
        p: 1.5,
        eta: 1.0,
        mu: 0.5,
        q,
        c: wp::RESTITUTION_DAMPING,
    }
}

const MODELS: [DampingModel; 3] = [
    DampingModel::Viscous,
    DampingModel::KuwabaraKono,
    DampingModel::ScaleRespecting,
];

/// This file's reference integrator gives the elastic closed forms (the outgoing rate equals
/// the incoming one: energy is conserved) for the collision of work-precision (masses 1 and 3,
/// eta = 5657), Hertz and linear, and converges: 2000 and 4000 steps per piece agree. And the
/// references the order problems measure against are right: the collisions' (-0.5, 0.5) is the
/// elastic formula, and work-precision's restitution (its own integrator, `reference.rs`)
/// agrees with this one for every damping model.
#[test]
fn the_references_are_right() {
    let mut rows = Vec::new();
    let mut ok = true;
    for p in [1.5, 1.0] {
        let c = Contact {
            p,
            eta: 5657.0,
            mu: 0.75,
            q: 0.0,
            c: 0.0,
        };
        let w = c.outgoing_rate(1.0, 4000);
        // 1e-12: the target; RK4 at 4000 steps per piece errs by ~1e-15 here and the
        // ~1e4 steps' rounding by ~1e-14.
        let pass = (w + 1.0).abs() < 1e-12;
        ok &= pass;
        rows.push(format!("p = {p}: |w_out + 1| = {:.1e}", (w + 1.0).abs()));
    }
    // Masses 1 and 3 at speeds 1 and 0: ((m1 - m2) v / (m1 + m2), 2 m1 v / (m1 + m2)).
    let (a, b) = TwoGrainCollision::default().outgoing_velocities();
    let exact = (a == -0.5 && b == 0.5)
        && TwoGrainCollision {
            p: 1.0,
            ..Default::default()
        }
        .outgoing_velocities()
            == (-0.5, 0.5);
    ok &= exact;
    rows.push(format!("collision reference ({a}, {b})"));
    for model in MODELS {
        let c = restitution_contact(model);
        let (fine, finer) = (-c.outgoing_rate(1.0, 2000), -c.outgoing_rate(1.0, 4000));
        let theirs = wp::restitution_reference(model).unwrap();
        // 1e-12: the target for the reference. The two step counts agree to ~1e-15
        // (RK4's error falls 16 times from 2000 to 4000 steps), so their difference bounds this
        // integrator's error; work-precision's reference is another integrator of the same
        // equation (RK4 with bisection on re-taken steps, other piece boundaries).
        let pass = (fine - finer).abs() < 1e-12 && (theirs - finer).abs() < 1e-12 && finer < 1.0;
        ok &= pass;
        rows.push(format!(
            "{}: e = {finer:.15} (n/2: {:.1e} off; work-precision's: {:.1e} off)",
            model.name(),
            (fine - finer).abs(),
            (theirs - finer).abs()
        ));
    }
    record_one(
        Row::new(
            "order problems: references",
            "elastic collision masses 1, 3 (eta 5657, p = 3/2 and 1); restitution c = 0.1, unit Hertz grains",
            "elastic closed form; an RK4 integration of mu x'' = -F in this test",
        )
        .expected("agree")
        .measured(rows.join("; "))
        .tolerance("1e-12")
        .pass(ok),
    );
    assert!(ok, "{rows:?}");
}

/// The least-squares slope of log(error) against log(dt) (`-log` of the setting: the
/// order) over one method's points.
fn fitted_order(rows: &[&wp::Order]) -> f64 {
    let pts: Vec<(f64, f64)> = rows
        .iter()
        .map(|o| (o.setting.ln(), o.error.ln()))
        .collect();
    let n = pts.len() as f64;
    let (mx, my) = (
        pts.iter().map(|p| p.0).sum::<f64>() / n,
        pts.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
    sxy / sxx
}

/// The order problems of work-precision in full: observed order per halving recorded per
/// problem and method. Asserted: every point ran and has an error; each method converges (its
/// finest error is at least 4 times below its coarsest); the finest errors stay below bounds
/// met today with room.
#[test]
fn observed_orders_on_contacts() {
    let cfg = wp::Config {
        repeats: 1,
        ..Default::default()
    };
    let study = wp::run(
        &cfg,
        &[
            Benchmark::CollisionHertz,
            Benchmark::CollisionLinear,
            Benchmark::Restitution,
        ],
        |_| {},
    )
    .unwrap();
    let orders = study.orders();
    let mut failures = Vec::new();
    for p in &study.points {
        if !p.failure.is_empty() || !p.error.is_finite() {
            failures.push(format!(
                "{} {} {}: {}",
                p.problem, p.method, p.setting, p.failure
            ));
        }
    }
    let mut labels: Vec<(&str, &str)> = orders
        .iter()
        .map(|o| (o.problem, o.method.as_str()))
        .collect();
    labels.dedup();
    for (problem, method) in labels {
        let rows: Vec<&wp::Order> = orders
            .iter()
            .filter(|o| o.problem == problem && o.method == method)
            .collect();
        let (first, last) = (rows[0], rows[rows.len() - 1]);
        // Bounds of the finest error, about 3 times what is measured today (collisions: 3.8e-7
        // is the largest, linear verlet at dt = 2.4e-5; restitution: 4.4e-7, kuwabara-kono
        // blanes-moan4 without events at dt = 3.9e-3, where the Strang-split flow of before
        // the damped drift left 8.1e-6, and viscous 3.2e-4): a method that stops resolving
        // the contact fails them.
        let bound = if problem.starts_with("restitution") {
            1.5e-6
        } else {
            1e-6
        };
        // Convergence, whatever the order: over five halvings (six tolerances for dopri5) the
        // error falls at least 4 times (today it falls 25 times or more).
        let converges = last.error <= first.error / 4.0 && last.error < bound;
        if !converges {
            failures.push(format!(
                "{problem} {method}: error {:.2e} -> {:.2e} (bound {bound:.0e})",
                first.error, last.error
            ));
        }
        // With contact events (the steps cut where a contact closes or opens) each collision
        // converges at every halving. Hertz: at least order 1.5 per halving (measured 1.9 to 3.2
        // for verlet, 1.6 to 2.8 for blanes-moan4; the force grows as (t - t*)^(3/2) from the
        // closing instant, which caps any method near 2.5, `integrators/events.rs`); without
        // events the same halvings measure -3.9 to 10 (verlet) and -0.6 to 3.2. Linear: the
        // pieces are smooth, so blanes-moan4 is fourth order again: its first two halvings
        // measure 10.1 and 4.1 (then round-off, 3e-16); at least 3.5 is asked.
        let restitution = problem.starts_with("restitution");
        let fitted = fitted_order(&rows);
        let events_ok = if restitution {
            // Damped contacts at order 2 (issue 49, item 5; `chain/damping.rs`): the damped
            // drift moves each dashpot's exact momentum `G(delta_end) - G(delta_start)`, and
            // events locate the closing and the clamp. With events the least-squares order over
            // the six steps is asked to be at least 1.8, the goal set for it (measured 1.81 to
            // 1.90; per halving 1.65 to 2.01). Without events the kinks at the closing (q = 0)
            // and at the clamp fall anywhere in a step, so the error is of order 2 with a
            // constant that depends on where: per halving -2.5 to 4.8, fitted 1.77 to 2.01; at
            // least 1.6 is asked of the fit. (Before, the Strang-split flow: order q + 1,
            // 1.0, 1.24, 1.47.)
            let least = if method.ends_with("+events") {
                1.8
            } else {
                1.6
            };
            fitted >= least
        } else if !method.ends_with("+events") {
            true
        } else if problem == "collision-linear" && method.starts_with("blanes-moan4") {
            rows[1..3].iter().all(|o| o.order >= 3.5)
        } else {
            // Linear verlet: second order, measured 2.2 to 6.5 per halving.
            rows[1..].iter().all(|o| o.order >= 1.5)
        };
        if !events_ok {
            failures.push(format!(
                "{problem} {method}: with events an order per halving is below what is asked"
            ));
        }
        let table = rows
            .iter()
            .map(|o| {
                let order = if o.order.is_nan() {
                    String::new()
                } else {
                    format!(" ({:.2})", o.order)
                };
                format!("{}: {:.2e}{order}", g(o.setting), o.error)
            })
            .collect::<Vec<_>>()
            .join("; ");
        let setting = if method == "dopri5" { "rtol" } else { "dt" };
        record_one(
            Row::new(
                "observed order on a contact",
                format!("{problem}, {method}"),
                "reported: the contact force is not smooth where the contact closes and opens",
            )
            .expected(format!("finest error < {bound:.0e}, 4x below the coarsest"))
            .measured(if restitution {
                format!("{setting}: error (order per halving): {table}; fitted order {fitted:.2}")
            } else {
                format!("{setting}: error (order per halving): {table}")
            })
            .tolerance("n/a (order reported; with events: a least order per halving)")
            .pass(converges && events_ok),
        );
    }
    assert!(failures.is_empty(), "{failures:#?}");
}
