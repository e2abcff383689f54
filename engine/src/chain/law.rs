//! Contact laws `F = eta * [delta0 + u_n - u_{n+1}]_+^p` and their monomorphized force kernels.
//!
//! The exponent is resolved once per run of equal contacts (a [`Segment`](super::Segment)), never
//! per contact per step: [`Kernel`] names the compiled variant and [`Kernel::forces`] dispatches
//! once per segment to a loop generic over [`Power`] and over the precompression / tension
//! variants.
//!
//! The force is written once, `contact_force`: the scalar path ([`ContactLaw::force`],
//! [`Kernel::force_at`]), the kernels' loops, the fused sweep's scalar path
//! (`chain::fused`) and the energies all call it. The exponent kinds are declared here once:
//! [`PowerKind`] (chosen from p by [`PowerKind::of`]), one zero-sized [`Power`] type each, and
//! `with_power!`, the one `match` that turns a kernel's kind into its compiled type. The only
//! other place that knows a kind is the AVX2 sweep (`chain::fused`), which needs the four-lane
//! form of its power (`PowerX4`). Adding a kind (say p = 5/2 as `x * x * sqrt(x)`): a type and
//! its `Power` impl, a `PowerKind` variant, its line in `PowerKind::of` and in `with_power!`
//! (this file), and its `PowerX4` impl (`fused.rs`).

use serde::Serialize;

/// Contact forces smaller than this are treated as exactly zero.
///
/// The discrete solitary wave has super-exponentially decaying tails. Without a floor the tails
/// reach subnormal numbers within a few grains ahead of every wave, and arithmetic on subnormals
/// is up to 100 times slower on x86. A contact whose overlap would give a force below this floor
/// (far below anything physical: forces in a wave are of order 1e-20 or more in any sensible unit
/// system) is treated as open. The floor is applied identically with and without skipping, so it
/// does not break the bit-for-bit equality of the two.
pub const FORCE_FLOOR: f64 = 1e-200;

/// One contact law.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ContactLaw {
    /// Exponent p >= 1 (1 linear, 1.5 Hertz, 2 rough grains).
    pub p: f64,
    /// Stiffness eta > 0.
    pub eta: f64,
    /// Static precompression overlap delta0 >= 0 (held by walls).
    pub delta0: f64,
    /// Two-sided (a spring that also pulls). Only allowed for p = 1.
    pub tension: bool,
    /// Contact damping (a dashpot in parallel with the contact; `None`: elastic).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub damping: Option<ContactDamping>,
}

/// The form of a contact's damping force `c * delta^q * d(delta)/dt`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, serde::Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(rename_all = "kebab-case")]
pub enum DampingModel {
    /// `q = 0`: a plain dashpot, `c * d(delta)/dt`.
    Viscous,
    /// `q = 1/2`: the viscoelastic Hertz contact of Kuwabara & Kono (1987) and Brilliantov et
    /// al. (1996), `c * delta^(1/2) * d(delta)/dt` (for p = 3/2).
    KuwabaraKono,
    /// `q = (p - 1)/2`: the form that keeps the contact's equation free of a scale, so the
    /// coefficient of restitution is the same at every impact speed (for any p).
    ScaleRespecting,
}

impl DampingModel {
    /// The model's name as scene files write it (`viscous`, `kuwabara-kono`,
    /// `scale-respecting`).
    pub fn name(self) -> &'static str {
        match self {
            DampingModel::Viscous => "viscous",
            DampingModel::KuwabaraKono => "kuwabara-kono",
            DampingModel::ScaleRespecting => "scale-respecting",
        }
    }

    /// The exponent `q` of `delta` in the damping force for a contact of exponent `p`.
    pub fn exponent(self, p: f64) -> f64 {
        match self {
            DampingModel::Viscous => 0.0,
            DampingModel::KuwabaraKono => 0.5,
            DampingModel::ScaleRespecting => 0.5 * (p - 1.0),
        }
    }
}

/// Damping of a contact: the total force is `eta delta^p + c delta^q d(delta)/dt` while the
/// contact is closed, never tensile (a compression-only contact's total force is clipped at zero
/// while it opens fast; a two-sided spring's is not clipped).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ContactDamping {
    /// The form (the exponent `q`).
    pub model: DampingModel,
    /// The coefficient `c >= 0`.
    pub c: f64,
}

/// Why a contact law is not acceptable.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum LawError {
    /// The exponent p is below 1 or not finite.
    #[error("exponent p must be a finite number >= 1, got {0}")]
    Exponent(f64),
    /// The stiffness eta is not finite and positive.
    #[error("stiffness eta must be a finite number > 0, got {0}")]
    Stiffness(f64),
    /// The precompression overlap delta0 is negative or not finite.
    #[error("precompression delta0 must be a finite number >= 0, got {0}")]
    Precompression(f64),
    /// A two-sided (tension) law with p != 1.
    #[error("a two-sided (tension) contact must be linear (p = 1), got p = {0}")]
    TensionNonlinear(f64),
    /// A damping coefficient that is negative or not finite.
    #[error("damping coefficient c must be a finite number >= 0, got {0}")]
    Damping(f64),
    /// A damping form `c delta^q d(delta)/dt` with `q != 0` on a two-sided (tension) contact:
    /// such a contact reaches negative overlaps, where `delta^q` has no value (q = 1/2:
    /// `kuwabara-kono`). See [`ContactLaw::validate`].
    #[error("{} contact damping (c delta^{q} d(delta)/dt) is not defined on a two-sided (tension) contact, whose overlap delta goes negative; use viscous (or scale-respecting: q = (p - 1)/2 = 0 on its linear law)", .model.name())]
    DampingOnTension {
        /// The damping model asked for.
        model: DampingModel,
        /// Its exponent q on this contact.
        q: f64,
    },
}

impl LawError {
    /// The parameter at fault, as its scene key (`p`, `eta`, `delta0`, `tension`).
    pub fn key(&self) -> &'static str {
        match self {
            LawError::Exponent(_) => "p",
            LawError::Stiffness(_) => "eta",
            LawError::Precompression(_) => "delta0",
            LawError::TensionNonlinear(_) => "tension",
            LawError::Damping(_) => "contact_damping.c",
            LawError::DampingOnTension { .. } => "contact_damping.model",
        }
    }

    /// What is wrong, without naming the parameter (for messages that name it by key).
    pub fn problem(&self) -> String {
        match self {
            LawError::Exponent(p) => format!("exponent must be a finite number >= 1, got {p}"),
            LawError::Stiffness(x) => format!("must be a finite number > 0, got {x}"),
            LawError::Precompression(x) => format!("must be a finite number >= 0, got {x}"),
            LawError::TensionNonlinear(p) => {
                format!("a two-sided (tension) contact must be linear (p = 1), got p = {p}")
            }
            LawError::Damping(c) => format!("must be a finite number >= 0, got {c}"),
            LawError::DampingOnTension { model, q } => format!(
                "`{}` (c delta^{q} d(delta)/dt) is not defined with `tension = true`: a \
                 two-sided contact's overlap delta goes negative, where delta^{q} has no value; \
                 use `viscous` (or `scale-respecting`: q = (p - 1)/2 = 0 on the linear law of a \
                 two-sided contact), or leave out `tension`",
                model.name()
            ),
        }
    }
}

impl ContactLaw {
    /// A compression-only law without precompression.
    pub fn new(p: f64, eta: f64) -> Self {
        Self {
            p,
            eta,
            delta0: 0.0,
            tension: false,
            damping: None,
        }
    }

    /// Hertz contact (p = 3/2).
    pub fn hertz(eta: f64) -> Self {
        Self::new(1.5, eta)
    }

    /// With a static precompression overlap.
    pub fn with_precompression(mut self, delta0: f64) -> Self {
        self.delta0 = delta0;
        self
    }

    /// Two-sided linear spring.
    pub fn linear_spring(eta: f64) -> Self {
        Self {
            p: 1.0,
            eta,
            delta0: 0.0,
            tension: true,
            damping: None,
        }
    }

    /// With contact damping `c delta^q d(delta)/dt` of form `model` (a `c` of 0 is elastic).
    pub fn with_damping(mut self, model: DampingModel, c: f64) -> Self {
        self.damping = Some(ContactDamping { model, c });
        self
    }

    /// Check the parameters.
    pub fn validate(&self) -> Result<(), LawError> {
        if !(self.p.is_finite() && self.p >= 1.0) {
            return Err(LawError::Exponent(self.p));
        }
        if !(self.eta.is_finite() && self.eta > 0.0) {
            return Err(LawError::Stiffness(self.eta));
        }
        if !(self.delta0.is_finite() && self.delta0 >= 0.0) {
            return Err(LawError::Precompression(self.delta0));
        }
        if self.tension && self.p != 1.0 {
            return Err(LawError::TensionNonlinear(self.p));
        }
        if let Some(d) = self.damping {
            if !(d.c.is_finite() && d.c >= 0.0) {
                return Err(LawError::Damping(d.c));
            }
            // A two-sided contact's overlap goes negative (it pulls), and `delta^q` of a negative
            // overlap has no value for q = 1/2 (Kuwabara-Kono). The ways to give it one are each
            // a model nobody derived: `|delta|^q` would switch the dashpot off as the spring
            // passes its rest length and back on in tension; `[delta]_+^q` would leave the
            // spring undamped in tension. The form is refused instead (at any c, so a scene does
            // not become wrong when c is raised from 0). The forms with q = 0 are defined at
            // every overlap: viscous, and scale-respecting (q = (p - 1)/2 = 0 on the linear law
            // a two-sided contact must have), both `c d(delta)/dt` in tension as in compression
            // (`chain::damping`).
            let q = d.model.exponent(self.p);
            if self.tension && q != 0.0 {
                return Err(LawError::DampingOnTension { model: d.model, q });
            }
        }
        Ok(())
    }

    /// Overlap below which the contact counts as open (see [`FORCE_FLOOR`]).
    pub fn cutoff(&self) -> f64 {
        (FORCE_FLOOR / self.eta).powf(1.0 / self.p)
    }

    /// The compiled kernel variant for this law.
    pub(crate) fn kernel(&self) -> Kernel {
        Kernel {
            p: self.p,
            power: PowerKind::of(self.p),
            precompressed: self.delta0 != 0.0,
            tension: self.tension,
            eta: self.eta,
            delta0: self.delta0,
            cut: self.cutoff(),
        }
    }

    /// Force for a total overlap `x = delta0 + u_n - u_{n+1}` (scalar path, same arithmetic as the
    /// kernels).
    pub fn force(&self, x: f64) -> f64 {
        self.kernel().force_at(x)
    }

    /// Potential energy stored in the contact at total overlap `x`: eta x^(p+1)/(p+1), computed
    /// as `F(x) x / (p+1)` so the special exponents avoid `powf` (observables at every output
    /// time must stay cheap). Zero when open; below the force floor ([`FORCE_FLOOR`]) the energy
    /// is below 1e-200 and counts as zero too.
    pub fn potential(&self, x: f64) -> f64 {
        if self.tension {
            0.5 * self.eta * x * x
        } else {
            self.kernel().potential_at(x)
        }
    }

    /// Static force at the precompression overlap.
    pub fn static_force(&self) -> f64 {
        self.force(self.delta0)
    }
}

/// How `x^p` is evaluated; one zero-sized type per special exponent.
pub trait Power: Copy {
    /// `x^p` for `x >= 0` (and any `x` for the linear law).
    fn pow(self, x: f64) -> f64;

    /// `x^p` (the same bits as [`Power::pow`]) and its derivative `p x^(p-1)`, for `x > 0`:
    /// what a run with derivatives needs of a closed contact (`protector::gradient`).
    fn pow_slope(self, x: f64) -> (f64, f64);
}

/// p = 1.
#[derive(Clone, Copy)]
pub struct Linear;
/// p = 3/2: `x * sqrt(x)`.
#[derive(Clone, Copy)]
pub struct Hertz;
/// p = 2.
#[derive(Clone, Copy)]
pub struct Quadratic;
/// Any other p: `powf`.
#[derive(Clone, Copy)]
pub struct General(pub f64);

impl Power for Linear {
    #[inline(always)]
    fn pow(self, x: f64) -> f64 {
        x
    }
    #[inline(always)]
    fn pow_slope(self, x: f64) -> (f64, f64) {
        (x, 1.0)
    }
}
impl Power for Hertz {
    #[inline(always)]
    fn pow(self, x: f64) -> f64 {
        x * x.sqrt()
    }
    /// One square root for both.
    #[inline(always)]
    fn pow_slope(self, x: f64) -> (f64, f64) {
        let s = x.sqrt();
        (x * s, 1.5 * s)
    }
}
impl Power for Quadratic {
    #[inline(always)]
    fn pow(self, x: f64) -> f64 {
        x * x
    }
    #[inline(always)]
    fn pow_slope(self, x: f64) -> (f64, f64) {
        (x * x, 2.0 * x)
    }
}
impl Power for General {
    #[inline(always)]
    fn pow(self, x: f64) -> f64 {
        x.powf(self.0)
    }
    #[inline(always)]
    fn pow_slope(self, x: f64) -> (f64, f64) {
        let y = x.powf(self.0);
        (y, self.0 * y / x)
    }
}

/// Which [`Power`] a kernel uses.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PowerKind {
    /// p = 1: [`Linear`].
    Linear,
    /// p = 3/2: [`Hertz`].
    Hertz,
    /// p = 2: [`Quadratic`].
    Quadratic,
    /// Any other exponent (the value of p): [`General`], through `powf`.
    General(f64),
}

impl PowerKind {
    /// The kind that evaluates `x^p`: a special form where there is one, else `powf`.
    pub fn of(p: f64) -> PowerKind {
        if p == 1.0 {
            PowerKind::Linear
        } else if p == 1.5 {
            PowerKind::Hertz
        } else if p == 2.0 {
            PowerKind::Quadratic
        } else {
            PowerKind::General(p)
        }
    }
}

/// `$body` compiled once per exponent kind and tension variant of kernel `$k`, with `$pw` the
/// kind's [`Power`] value and `$tension` a `const bool`: the one `match` over [`PowerKind`]
/// (a branch per call, never per contact). A two-sided law is linear ([`ContactLaw::validate`]).
macro_rules! with_power {
    ($k:expr, |$pw:ident, $tension:ident| $body:expr) => {{
        use $crate::chain::law::{General, Hertz, Linear, PowerKind, Quadratic};
        match $k.power {
            PowerKind::Linear if $k.tension => {
                const $tension: bool = true;
                let $pw = Linear;
                $body
            }
            PowerKind::Linear => {
                const $tension: bool = false;
                let $pw = Linear;
                $body
            }
            PowerKind::Hertz => {
                const $tension: bool = false;
                let $pw = Hertz;
                $body
            }
            PowerKind::Quadratic => {
                const $tension: bool = false;
                let $pw = Quadratic;
                $body
            }
            PowerKind::General(p) => {
                const $tension: bool = false;
                let $pw = General(p);
                $body
            }
        }
    }};
}
pub(crate) use with_power;

/// A contact law resolved into the parameters its kernel needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Kernel {
    /// Exponent p of the law.
    pub p: f64,
    /// How `x^p` is evaluated, resolved from `p`.
    pub power: PowerKind,
    /// Whether delta0 != 0, so the loop adds delta0 to each overlap.
    pub precompressed: bool,
    /// Two-sided linear spring: negative overlaps pull instead of opening the contact.
    pub tension: bool,
    /// Stiffness eta.
    pub eta: f64,
    /// Static precompression overlap delta0.
    pub delta0: f64,
    /// Overlap below which the contact counts as open ([`ContactLaw::cutoff`], from
    /// [`FORCE_FLOOR`]).
    pub cut: f64,
}

/// The contact force `eta [delta0 + du]_+^p` (`PRE`: with delta0; `TENSION`: `[x]` for `|x|`
/// above the cut instead of `[x]_+`), zero below the cut `cut` ([`FORCE_FLOOR`]): the one
/// scalar form of the force, used by every path. The AVX2 sweep (`chain::fused`) is the same
/// expression in intrinsics.
#[inline(always)]
pub(crate) fn contact_force<P: Power, const PRE: bool, const TENSION: bool>(
    pw: P,
    eta: f64,
    delta0: f64,
    cut: f64,
    du: f64,
) -> f64 {
    let x = if PRE { delta0 + du } else { du };
    // `[x]_+` with the force floor folded in: a select, not a branch, once vectorized.
    let x = if TENSION {
        if x.abs() > cut {
            x
        } else {
            0.0
        }
    } else if x > cut {
        x
    } else {
        0.0
    };
    eta * pw.pow(x)
}

#[inline(always)]
fn forces_loop<P: Power, const PRE: bool, const TENSION: bool>(
    pw: P,
    k: &Kernel,
    u: &[f64],
    f: &mut [f64],
) {
    let (eta, delta0, cut) = (k.eta, k.delta0, k.cut);
    let n = f.len();
    for ((fj, a), b) in f.iter_mut().zip(&u[..n]).zip(&u[1..n + 1]) {
        *fj = contact_force::<P, PRE, TENSION>(pw, eta, delta0, cut, a - b);
    }
}

impl Kernel {
    /// Force at total overlap `x` (`x` already includes delta0); the same arithmetic as the
    /// loops of [`Kernel::forces`] once the overlap is formed.
    pub fn force_at(&self, x: f64) -> f64 {
        let (eta, cut) = (self.eta, self.cut);
        with_power!(self, |pw, TENSION| contact_force::<_, false, TENSION>(
            pw, eta, 0.0, cut, x
        ))
    }

    /// [`Kernel::force_at`] (the same bits) and its derivative in `x`, `0` where the force is.
    #[inline(always)]
    pub(crate) fn force_slope_at(&self, x: f64) -> (f64, f64) {
        let (eta, cut) = (self.eta, self.cut);
        // Selects, not branches: whether a contact is closed is no pattern a predictor learns.
        with_power!(self, |pw, TENSION| {
            let closed = if TENSION { x.abs() > cut } else { x > cut };
            let (y, dy) = pw.pow_slope(if closed { x } else { 0.0 });
            (eta * y, if closed { eta * dy } else { 0.0 })
        })
    }

    /// Potential energy at total overlap `x` (see [`ContactLaw::potential`]).
    #[inline]
    pub fn potential_at(&self, x: f64) -> f64 {
        if self.tension {
            0.5 * self.eta * x * x
        } else if x > 0.0 {
            self.force_at(x) * x / (self.p + 1.0)
        } else {
            0.0
        }
    }

    /// Calls `each` with the potential energy (relative to the static value) of each contact
    /// `u[j], u[j+1]` for `j in 0..u.len() - 1`, in order: the bits of
    /// [`crate::Chain::contact_energy`], with one dispatch per call instead of one per contact.
    #[inline(always)]
    pub(crate) fn for_each_potential(&self, u: &[f64], mut each: impl FnMut(f64)) {
        let (eta, cut, d0, p1) = (self.eta, self.cut, self.delta0, self.p + 1.0);
        let base = if self.precompressed {
            self.potential_at(d0)
        } else {
            0.0
        };
        let pre = self.precompressed;
        with_power!(self, |pw, TENSION| {
            for w in u.windows(2) {
                let x = d0 + (w[0] - w[1]);
                let e = if TENSION {
                    0.5 * eta * x * x
                } else if x > 0.0 {
                    contact_force::<_, false, TENSION>(pw, eta, 0.0, cut, x) * x / p1
                } else {
                    0.0
                };
                each(if pre { e - base } else { e });
            }
        })
    }

    /// `f[j] = F(delta0 + u[j] - u[j+1])` for `j in 0..f.len()`; `u.len()` must be at least
    /// `f.len() + 1`. One dispatch per call, a branch-free loop inside.
    #[inline(always)]
    pub fn forces(&self, u: &[f64], f: &mut [f64]) {
        with_power!(self, |pw, TENSION| if self.precompressed {
            forces_loop::<_, true, TENSION>(pw, self, u, f)
        } else {
            forces_loop::<_, false, TENSION>(pw, self, u, f)
        })
    }
}

/// A run of consecutive contacts `[k0, k1)` (contact indices `0..=n`) with one damping.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct DampedRun {
    pub k0: usize,
    pub k1: usize,
    /// The coefficient `c`.
    pub c: f64,
    /// How `delta^q` is evaluated (chosen once per run, never per contact).
    pub q: QPower,
    /// The elastic law's kernel (one law per run: runs split where the law does).
    pub kernel: Kernel,
}

/// `delta^q` for the exponents of the three damping models on the usual contact laws.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum QPower {
    /// q = 0 (viscous; scale-respecting on a linear contact).
    Zero,
    /// q = 1/2 (Kuwabara-Kono; scale-respecting on p = 2): `sqrt`.
    Half,
    /// q = 1/4 (scale-respecting on Hertz): `sqrt(sqrt)`, exact under scaling by powers of 16.
    Quarter,
    /// Any other q: `powf`.
    General(f64),
}

impl QPower {
    pub(crate) fn of(q: f64) -> QPower {
        if q == 0.0 {
            QPower::Zero
        } else if q == 0.5 {
            QPower::Half
        } else if q == 0.25 {
            QPower::Quarter
        } else {
            QPower::General(q)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn special_exponents_match_powf() {
        for p in [1.0, 1.5, 2.0, 2.5, 3.0] {
            let law = ContactLaw::new(p, 5657.0);
            for x in [1e-3, 0.1, 1.0, 7.5] {
                let want = 5657.0 * f64::powf(x, p);
                // The special forms (x*sqrt(x), x*x) differ from powf by at most a few ulp.
                approx::assert_relative_eq!(law.force(x), want, max_relative = 4.0 * f64::EPSILON);
            }
        }
    }

    #[test]
    fn compression_only_and_tension() {
        let law = ContactLaw::hertz(2.0);
        assert_eq!(law.force(-0.5), 0.0);
        assert_eq!(law.potential(-0.5), 0.0);
        let spring = ContactLaw::linear_spring(3.0);
        assert_eq!(spring.force(-0.5), -1.5);
        assert_eq!(spring.potential(-0.5), 0.375);
    }

    #[test]
    fn floor_makes_tiny_forces_exactly_zero() {
        for p in [1.0, 1.5, 2.0, 4.0] {
            let law = ContactLaw::new(p, 5657.0);
            let cut = law.cutoff();
            assert_eq!(law.force(cut * 0.999), 0.0);
            let f = law.force(cut * 1.001);
            assert!(f >= FORCE_FLOOR && f.is_normal(), "p = {p}: force {f}");
        }
    }

    #[test]
    fn kernel_loop_equals_scalar_path() {
        let u = [0.3, 0.1, 0.2, -0.4, 0.0];
        for law in [
            ContactLaw::hertz(5657.0),
            ContactLaw::new(2.5, 3.0),
            ContactLaw::new(1.0, 2.0),
            ContactLaw::linear_spring(2.0),
            ContactLaw::new(2.0, 1.0),
        ] {
            let mut f = [0.0; 4];
            law.kernel().forces(&u, &mut f);
            for j in 0..4 {
                assert_eq!(f[j].to_bits(), law.force(u[j] - u[j + 1]).to_bits());
            }
        }
    }

    #[test]
    fn precompressed_kernel() {
        let law = ContactLaw::hertz(2.0).with_precompression(0.5);
        let mut f = [0.0; 1];
        law.kernel().forces(&[0.0, 0.0], &mut f);
        assert_eq!(f[0], law.static_force());
        law.kernel().forces(&[0.0, 1.0], &mut f);
        assert_eq!(f[0], 0.0);
    }

    #[test]
    fn validation_rejects_bad_parameters() {
        assert!(ContactLaw::new(0.5, 1.0).validate().is_err());
        assert!(ContactLaw::new(f64::NAN, 1.0).validate().is_err());
        assert!(ContactLaw::new(1.5, 0.0).validate().is_err());
        assert!(ContactLaw::new(1.5, 1.0)
            .with_precompression(-1.0)
            .validate()
            .is_err());
        let mut t = ContactLaw::linear_spring(1.0);
        t.p = 1.5;
        assert!(t.validate().is_err());
        assert!(ContactLaw::hertz(1.0).validate().is_ok());
    }
}
