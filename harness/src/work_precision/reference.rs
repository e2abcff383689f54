//! The reference of `restitution`: the two-grain contact `mu x'' = -F(x, x')` integrated on its
//! own, without the engine, to about 1e-13 (`validation/orders.rs` checks it against a second,
//! independently written integrator and against the elastic closed forms).
//!
//! `x` is the overlap, `w = x'` the rate of compression; while the contact is closed the force
//! is `F = max(eta x^p + c x^q w, 0)` (the engine's clipped damping, `chain/damping.rs`). The
//! contact starts at `x = 0`, `w = v` and ends at the first zero of `g = eta x^p + c x^q w`
//! (the clip; `x = 0` when `c = 0`), after which the grains fly apart at `w` (the force stays
//! zero: both terms of `g` only fall). The restitution is `-w_end / v`.
//!
//! The powers `x^p`, `x^q` are not smooth at `x = 0`, where the contact starts (and ends when
//! elastic), so a step in time there converges slowly (the first step's error is of order
//! `h^(q+1)`). Near `x = 0` the independent variable is `y = x^(1/4)` instead: `x = y^4`,
//! `dw/dy = 4 y^3 a / w` with `a = -g / mu`, smooth in `y` for every exponent that is a multiple
//! of 1/4 (p = 1, 3/2; q = 0, 1/4, 1/2). In the middle, where `w` passes zero, the variable is
//! time. Each piece is classical RK4; the event `g = 0` is found by bisection on the length of
//! the last step.

/// The contact: `F = eta x^p + c x^q x'` (clipped at zero), reduced mass `mu`.
#[derive(Clone, Copy, Debug)]
pub struct Contact {
    /// Exponent of the elastic force.
    pub p: f64,
    /// Stiffness.
    pub eta: f64,
    /// Reduced mass `m1 m2 / (m1 + m2)`.
    pub mu: f64,
    /// Exponent of `x` in the damping force.
    pub q: f64,
    /// Damping coefficient (0: elastic).
    pub c: f64,
}

impl Contact {
    fn g(&self, x: f64, w: f64) -> f64 {
        if self.c == 0.0 {
            // Elastic: the contact ends at x = 0 (the force is never clipped).
            return x;
        }
        self.eta * x.powf(self.p) + self.c * x.powf(self.q) * w
    }

    fn accel(&self, x: f64, w: f64) -> f64 {
        -(self.eta * x.max(0.0).powf(self.p) + self.c * x.max(0.0).powf(self.q) * w) / self.mu
    }

    /// `dw/dy` in the variable `y = x^(1/4)`.
    fn dw_dy(&self, y: f64, w: f64) -> f64 {
        4.0 * y * y * y * self.accel(y.powi(4), w) / w
    }

    /// One RK4 step in `y` of length `dy`.
    fn step_y(&self, y: f64, w: f64, dy: f64) -> f64 {
        let k1 = self.dw_dy(y, w);
        let k2 = self.dw_dy(y + 0.5 * dy, w + 0.5 * dy * k1);
        let k3 = self.dw_dy(y + 0.5 * dy, w + 0.5 * dy * k2);
        let k4 = self.dw_dy(y + dy, w + dy * k3);
        w + dy / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    }

    /// One RK4 step in time of length `h`.
    fn step_t(&self, x: f64, w: f64, h: f64) -> (f64, f64) {
        let (a1, b1) = (w, self.accel(x, w));
        let (a2, b2) = (
            w + 0.5 * h * b1,
            self.accel(x + 0.5 * h * a1, w + 0.5 * h * b1),
        );
        let (a3, b3) = (
            w + 0.5 * h * b2,
            self.accel(x + 0.5 * h * a2, w + 0.5 * h * b2),
        );
        let (a4, b4) = (w + h * b3, self.accel(x + h * a3, w + h * b3));
        (
            x + h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4),
            w + h / 6.0 * (b1 + 2.0 * b2 + 2.0 * b3 + b4),
        )
    }

    /// The outgoing rate `w_end` (negative) of a contact entered at rate `v > 0`, with `n` steps
    /// per piece (`n` = 4000 gives about 1e-14 on the problems of the study). Err: the contact
    /// never opens (damping so strong that the compression stops below a quarter of the elastic
    /// largest overlap; the pieces assume more).
    pub fn outgoing_rate(&self, v: f64, n: usize) -> Result<f64, String> {
        // Elastic largest overlap: mu v^2 / 2 = eta x^(p+1) / (p + 1).
        let x_max =
            ((self.p + 1.0) * self.mu * v * v / (2.0 * self.eta)).powf(1.0 / (self.p + 1.0));
        let x_switch = 0.25 * x_max;
        // Piece 1: y from 0 to x_switch^(1/4), compressing (w > 0 throughout).
        let y1 = x_switch.powf(0.25);
        let dy = y1 / n as f64;
        let mut w = v;
        for k in 0..n {
            w = self.step_y(k as f64 * dy, w, dy);
            if w <= 0.0 {
                return Err("the compression stops before a quarter of the elastic overlap".into());
            }
        }
        // Piece 2: time, from x_switch through the turning point down to x_switch again (or to
        // the clip). Step: the elastic contact's time scale x_max / v over 4 n... (4 n steps).
        let h = x_max / v / (4 * n) as f64;
        let mut x = x_switch;
        let mut steps = 0usize;
        while !(w < 0.0 && x < x_switch) {
            let (xn, wn) = self.step_t(x, w, h);
            if self.g(xn, wn) <= 0.0 {
                // The clip inside this step: bisect on the step's length.
                let (mut lo, mut hi) = (0.0, h);
                for _ in 0..200 {
                    let mid = 0.5 * (lo + hi);
                    if mid <= lo || mid >= hi {
                        break;
                    }
                    let (xm, wm) = self.step_t(x, w, mid);
                    if self.g(xm, wm) > 0.0 {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                return Ok(self.step_t(x, w, 0.5 * (lo + hi)).1);
            }
            (x, w) = (xn, wn);
            steps += 1;
            if steps > 1000 * n {
                return Err("the contact does not open".into());
            }
        }
        // Piece 3: y from x^(1/4) down to 0 (elastic), or to the clip.
        let y0 = x.powf(0.25);
        let dy = -y0 / n as f64;
        for k in 0..n {
            let y = y0 + k as f64 * dy;
            let wn = self.step_y(y, w, dy);
            if self.g((y + dy).max(0.0).powi(4), wn) <= 0.0 && self.c != 0.0 {
                let (mut lo, mut hi) = (0.0, dy);
                for _ in 0..200 {
                    let mid = 0.5 * (lo + hi);
                    if mid == lo || mid == hi {
                        break;
                    }
                    if self.g((y + mid).powi(4), self.step_y(y, w, mid)) > 0.0 {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                return Ok(self.step_y(y, w, 0.5 * (lo + hi)));
            }
            w = wn;
        }
        Ok(w)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Elastic contacts give back the approach rate (energy is conserved; closed form
    /// `w_end = -v`): Hertz and linear, to 1e-13 (RK4 at n = 4000 errs by about 1e-15 here;
    /// the bound leaves room for the rounding of ~3e4 steps).
    #[test]
    fn elastic_contacts_return_the_approach_rate() {
        for p in [1.0, 1.5] {
            let c = Contact {
                p,
                eta: 5657.0,
                mu: 0.75,
                q: 0.0,
                c: 0.0,
            };
            let w = c.outgoing_rate(1.0, 4000).unwrap();
            assert!((w + 1.0).abs() < 1e-13, "p = {p}: {w}");
        }
    }
}
