//! SI scenes: sections, walls, a striker and a target given by `material` and `diameter`
//! instead of `mass`, `p` and `eta`. A scene is all program units or all SI, decided by its
//! sections ([`is_si`]); [`units`] refuses a mix. In an SI scene every number is in seconds,
//! metres, kilograms, newtons and joules.
//!
//! A sphere of material `rho`, `E`, `nu` and diameter `d` weighs `rho pi d^3 / 6`; two spheres
//! touch through Hertz's law `F = eta delta^(3/2)` with the pair's constant
//! (`units::hertz_eta`, Johnson 1985 section 4.2), a sphere and a flat wall through
//! `units::hertz_eta_flat`. A coefficient of restitution `e < 1` damps a contact with the
//! scale-respecting dashpot `c delta^(1/4) d(delta)/dt`, whose restitution does not depend on
//! the impact speed ([`hertz_damping`]).

use super::file::{EndFile, LawFile, MaterialFile, SceneFile};
use super::parts::Ctx;
use super::restitution::Collision;
use crate::chain::material::{diameter_problem, hertz_eta, hertz_eta_flat, Bead, Material};
use crate::chain::{ContactLaw, DampingModel};
use crate::error::InputError;
use crate::run::RunError;

/// Whether the scene is an SI scene: some section gives `material`.
pub(super) fn is_si(f: &SceneFile) -> bool {
    f.chain.sections.iter().any(|s| s.law.material.is_some())
}

/// The key of the first section giving `material`, for messages.
fn si_key(f: &SceneFile) -> String {
    let i = f
        .chain
        .sections
        .iter()
        .position(|s| s.law.material.is_some())
        .unwrap_or(0);
    format!("chain.sections[{i}].material")
}

/// The keys of a law a material replaces, refused beside it: `p`, `eta`, `delta0`, `tension`,
/// `contact_damping`, under `key`.
fn no_program_law(c: &Ctx, key: &str, l: &LawFile) -> Result<(), InputError> {
    let given = [
        ("p", l.p.is_some()),
        ("eta", l.eta.is_some()),
        ("delta0", l.delta0.is_some()),
        ("tension", l.tension.is_some()),
        ("contact_damping", l.contact_damping.is_some()),
    ];
    if let Some((k, _)) = given.iter().find(|(_, g)| *g) {
        let why = match *k {
            "p" | "eta" => "the law of a material's contacts is Hertz's with the pair's constant",
            "contact_damping" => "damp a material's contacts with `restitution`",
            _ => "not available with materials",
        };
        return Err(c.err(
            format!("{key}.{k}"),
            format!("not with `material` ({why}); this is an SI scene"),
        ));
    }
    Ok(())
}

/// That the scene is all program units or all SI, and that an SI scene gives what has no
/// default in SI: refuses a mix (file, key, what is wrong), SI keys in a program-unit scene,
/// program-unit keys in an SI scene, an outer medium in an SI scene, and an SI scene without
/// `integrator.dt` (the default step, 1e-4, is in program units; a scene's duration and output
/// interval are required anyway) or, with dopri5, without `integrator.atol` (the default
/// 1e-10 is an absolute tolerance in program units).
pub(super) fn units(c: &Ctx, f: &SceneFile) -> Result<(), InputError> {
    let program = "program-unit";
    if !is_si(f) {
        let si_only = |key: String, what: &str| {
            c.err(
                key,
                format!(
                    "{what} needs an SI scene (sections given by `material` and `diameter`); \
                     this scene's sections are in program units (`mass`, `p`, `eta`), and the \
                     two cannot be mixed"
                ),
            )
        };
        for (i, s) in f.chain.sections.iter().enumerate() {
            if s.diameter.is_some() {
                return Err(si_only(
                    format!("chain.sections[{i}].diameter"),
                    "`diameter` (with `material`)",
                ));
            }
            if s.law.restitution.is_some() {
                return Err(si_only(
                    format!("chain.sections[{i}].restitution"),
                    "`restitution`",
                ));
            }
        }
        if f.chain.restitution.is_some() {
            return Err(si_only("chain.restitution".into(), "`restitution`"));
        }
        for (side, e) in [("left", &f.chain.left), ("right", &f.chain.right)] {
            if let Some(EndFile::Wall(l)) = e {
                if l.material.is_some() {
                    return Err(si_only(
                        format!("chain.{side}.material"),
                        "a wall's `material`",
                    ));
                }
                if l.restitution.is_some() {
                    return Err(si_only(
                        format!("chain.{side}.restitution"),
                        "`restitution`",
                    ));
                }
            }
        }
        if let Some(s) = &f.striker {
            for (k, given) in [
                ("material", s.material.is_some()),
                ("diameter", s.diameter.is_some()),
                ("restitution", s.restitution.is_some()),
            ] {
                if given {
                    return Err(si_only(format!("striker.{k}"), &format!("`{k}`")));
                }
            }
        }
        if let Some(t) = &f.target {
            for (k, given) in [
                ("material", t.material.is_some()),
                ("diameter", t.diameter.is_some()),
                ("restitution", t.restitution.is_some()),
            ] {
                if given {
                    return Err(si_only(format!("target.{k}"), &format!("`{k}`")));
                }
            }
        }
        return Ok(());
    }
    let first = si_key(f);
    let mixed = |key: String, what: &str| {
        c.err(
            key,
            format!(
                "{what}: this is an SI scene (`{first}`), where every section gives `material` \
                 and `diameter`; program units (`mass`, `p`, `eta`) and SI cannot be mixed"
            ),
        )
    };
    if f.chain.outer.is_some() {
        return Err(c.err(
            "chain.outer",
            format!("outer media are for {program} container scenes, not an SI scene (`{first}`)"),
        ));
    }
    for (i, s) in f.chain.sections.iter().enumerate() {
        let key = format!("chain.sections[{i}]");
        if s.law.material.is_none() {
            return Err(mixed(format!("{key}.material"), "missing"));
        }
        if s.mass.is_some() {
            return Err(mixed(
                format!("{key}.mass"),
                "not with `material` (the mass is the sphere's, rho pi d^3 / 6)",
            ));
        }
        no_program_law(c, &key, &s.law)?;
    }
    for (side, e) in [("left", &f.chain.left), ("right", &f.chain.right)] {
        if let Some(EndFile::Wall(l)) = e {
            let key = format!("chain.{side}");
            if l.material.is_none() {
                return Err(mixed(
                    format!("{key}.material"),
                    "missing: a wall of an SI scene is a flat of a material",
                ));
            }
            no_program_law(c, &key, l)?;
        }
    }
    if let Some(s) = &f.striker {
        if s.material.is_none() {
            return Err(mixed(
                "striker.material".into(),
                "missing: the striker of an SI scene is a sphere of a material (with `diameter`)",
            ));
        }
        for (k, given) in [
            ("mass", s.mass.is_some()),
            ("p", s.p.is_some()),
            ("eta", s.eta.is_some()),
        ] {
            if given {
                return Err(mixed(format!("striker.{k}"), "not with `material`"));
            }
        }
    }
    let i = f.integrator.as_ref();
    if i.and_then(|i| i.dt).is_none() {
        return Err(c.err(
            "integrator.dt",
            format!(
                "missing: an SI scene gives its step in seconds (the default, 1e-4, is in \
                 program units; `{first}` makes this an SI scene)"
            ),
        ));
    }
    let adaptive = i
        .and_then(|i| i.method)
        .is_some_and(|m| m.information().adaptive);
    if adaptive && i.and_then(|i| i.atol).is_none() {
        return Err(c.err(
            "integrator.atol",
            "missing: an SI scene with an adaptive method gives its absolute tolerance (the \
             default, 1e-10, is in program units)",
        ));
    }
    Ok(())
}

/// The material `m` names or gives, under `key`: [`Material::named`] or
/// [`Material::explicit`], their messages under `key`.
pub(super) fn material(c: &Ctx, key: &str, m: &MaterialFile) -> Result<Material, InputError> {
    match m {
        MaterialFile::Named(name) => Material::named(name),
        MaterialFile::Custom(x) => Material::explicit(x.name.as_deref(), x.young, x.nu, x.rho),
    }
    .map_err(|why| c.err(key, why))
}

/// A diameter in metres ([`diameter_problem`]), under `key`; missing: an error saying that a
/// sphere of a material needs it.
fn diameter(c: &Ctx, key: &str, d: Option<f64>) -> Result<f64, InputError> {
    let Some(d) = d else {
        return Err(c.err(
            key,
            "missing: a sphere of a material needs its diameter in metres",
        ));
    };
    match diameter_problem(d) {
        Some(why) => Err(c.err(key, why)),
        None => Ok(d),
    }
}

/// The sphere of `table` (`{table}.material`, `{table}.diameter`).
pub(super) fn sphere(
    c: &Ctx,
    table: &str,
    m: &MaterialFile,
    d: Option<f64>,
) -> Result<Bead, InputError> {
    Ok(Bead {
        material: material(c, &format!("{table}.material"), m)?,
        diameter: diameter(c, &format!("{table}.diameter"), d)?,
    })
}

/// What a bead touches: another bead, or a flat face of `material` on a body of `mass` kg
/// (infinite: a wall).
#[derive(Clone, Copy, Debug)]
pub(crate) enum Other {
    /// A sphere.
    Bead(Bead),
    /// A flat face.
    Flat {
        /// The face's material.
        material: Material,
        /// The body's mass, kg (`f64::INFINITY`: a rigid wall).
        mass: f64,
    },
}

/// A contact of a chain of beads: its law, Hertz's constant and the two masses (kg; the second
/// infinite against a wall), which set its contact time.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Contact {
    /// Hertz's law with its dashpot, if any.
    pub law: ContactLaw,
    /// Hertz's constant, N/m^1.5.
    pub eta: f64,
    /// The bead's mass and the other body's, kg.
    pub masses: (f64, f64),
}

/// The one place a chain of beads gets a contact (SI scenes and `protector::layout`): bead `a`
/// on `b`, Hertz's law with the pair's constant from the effective modulus and radius
/// ([`hertz_eta`], against a flat [`hertz_eta_flat`]), damped for restitution `e` (< 1) by the
/// scale-respecting dashpot ([`hertz_damping`]).
pub(crate) fn contact(a: &Bead, b: &Other, e: Option<f64>) -> Result<Contact, RunError> {
    let (eta, m2) = match b {
        Other::Bead(b) => (
            hertz_eta(&a.material, a.diameter, &b.material, b.diameter),
            b.mass(),
        ),
        Other::Flat { material, mass } => {
            (hertz_eta_flat(&a.material, a.diameter, material), *mass)
        }
    };
    let m1 = a.mass();
    Ok(Contact {
        law: damped(eta, m1, m2, e)?,
        eta,
        masses: (m1, m2),
    })
}

/// A run of equal beads as the chain holds it: the beads' mass (kg), the law of the contacts
/// inside the run, and the run's joint with the run before it (none for the first).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Run {
    /// Each bead's mass, kg.
    pub mass: f64,
    /// The contacts between two of its beads.
    pub inner: Contact,
    /// The contact with the last bead of the run before.
    pub joint: Option<Contact>,
}

/// The one function from beads to a chain's sections (SI scenes and `protector::layout`, which
/// cannot drift apart): a run of `bead`s after a run of `prev`s (none: the first run), the
/// contacts inside it with restitution `inner` and its joint with `joint` ([`contact`]). The
/// ends are [`contact`]s of the end beads with a flat (a wall, a target's face) or a sphere (a
/// striker, a target).
pub(crate) fn run(
    bead: &Bead,
    prev: Option<&Bead>,
    inner: Option<f64>,
    joint: Option<f64>,
) -> Result<Run, RunError> {
    Ok(Run {
        mass: bead.mass(),
        inner: contact(bead, &Other::Bead(*bead), inner)?,
        joint: prev
            .map(|p| contact(p, &Other::Bead(*bead), joint))
            .transpose()?,
    })
}

/// Hertz's law `eta` between masses `m1` and `m2` (`m2` infinite: a wall), damped for
/// restitution `e` when given.
fn damped(eta: f64, m1: f64, m2: f64, e: Option<f64>) -> Result<ContactLaw, RunError> {
    let law = ContactLaw::hertz(eta);
    Ok(match e {
        Some(e) => law.with_damping(
            DampingModel::ScaleRespecting,
            hertz_damping(eta, m1, m2, e)?,
        ),
        None => law,
    })
}

/// The restitution of a contact: its own (`own`, under its key) or the chain's
/// (`chain.restitution`); `None` when neither is given or it is 1 (elastic). In [0.05, 1].
pub(super) fn restitution(
    c: &Ctx,
    f: &SceneFile,
    own: Option<(String, f64)>,
) -> Result<Option<(String, f64)>, InputError> {
    let given = own.or_else(|| f.chain.restitution.map(|e| ("chain.restitution".into(), e)));
    let Some((key, e)) = given else {
        return Ok(None);
    };
    if !(e.is_finite() && (0.05..=1.0).contains(&e)) {
        return Err(c.err(
            key,
            format!("must be a coefficient of restitution from 0.05 to 1 (elastic), got {e}"),
        ));
    }
    Ok((e < 1.0).then_some((key, e)))
}

/// A [`RunError`] of a contact's dashpot under the key of its restitution (`e`'s).
pub(super) fn at_key<T>(
    c: &Ctx,
    e: Option<&(String, f64)>,
    x: Result<T, RunError>,
) -> Result<T, InputError> {
    x.map_err(|err| {
        c.err(
            e.map_or_else(String::new, |(k, _)| k.clone()),
            err.to_string(),
        )
    })
}

/// The Hertz law of a given `eta` between grains of masses `m1` and `m2` (`m2` infinite: a
/// wall), damped for restitution `e` when given (its key names a failure): a target's contact
/// given by `eta` in an SI scene.
pub(super) fn hertz_law(
    c: &Ctx,
    eta: f64,
    m1: f64,
    m2: f64,
    e: Option<&(String, f64)>,
) -> Result<ContactLaw, InputError> {
    at_key(c, e, damped(eta, m1, m2, e.map(|(_, e)| *e)))
}

/// The coefficient `c` of the scale-respecting dashpot `c delta^(1/4) d(delta)/dt`
/// ([`DampingModel::ScaleRespecting`]) that gives a Hertz contact `eta` between masses `m1` and
/// `m2` (`m2` infinite: a wall) the coefficient of restitution `e` (0.05 <= e < 1).
///
/// The relative motion is `mu x'' = -eta x^(3/2) - c x^(1/4) x'` with `mu` the reduced mass;
/// in units where `mu`, `eta` and the impact speed are 1 (length `A = v T`, time
/// `T = (mu / (eta v^(1/2)))^(2/5)`) it is `x'' = -x^(3/2) - (c / sqrt(eta mu)) x^(1/4) x'`, so
/// the restitution depends on `c / sqrt(eta mu)` alone, at every speed. That number is found
/// once per `e` by [`Collision::damping_for_restitution`] (the bisection of
/// `problems::TwoGrainCollision`, the same code) on the collision with `eta = 1` and two grains
/// of mass 2 (reduced mass 1), remembered for the process, and scaled by `sqrt(eta mu)`.
pub(crate) fn hertz_damping(eta: f64, m1: f64, m2: f64, e: f64) -> Result<f64, RunError> {
    use std::collections::HashMap;
    use std::sync::{Mutex, OnceLock};
    static MEMO: OnceLock<Mutex<HashMap<u64, f64>>> = OnceLock::new();
    let mu = if m2.is_infinite() {
        m1
    } else {
        m1 * m2 / (m1 + m2)
    };
    let memo = MEMO.get_or_init(Default::default);
    let known = memo.lock().ok().and_then(|m| m.get(&e.to_bits()).copied());
    let unit = match known {
        Some(x) => x,
        None => {
            // The elastic collision of the unit problem: largest overlap (5/4)^(2/5) and contact
            // time 2 delta_max I_{3/2} (physics.md 4, mu = eta = v = 1).
            let overlap = 1.25f64.powf(0.4);
            let x = Collision {
                p: 1.5,
                eta: 1.0,
                striker_mass: 2.0,
                grain_mass: 2.0,
                speed: 1.0,
                contact_time: 2.0 * overlap * super::restitution::HERTZ_CONTACT_INTEGRAL,
            }
            .damping_for_restitution(DampingModel::ScaleRespecting, e)?;
            if let Ok(mut m) = memo.lock() {
                m.insert(e.to_bits(), x);
            }
            x
        }
    };
    Ok(unit * (eta * mu).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::chain::material::{PTFE, STEEL};

    /// The scaled damping gives the asked restitution on a real pair (a 6 mm steel bead on a
    /// 6 mm PTFE bead at 1 m/s, and at 0.01 m/s: the same restitution at every speed), run by
    /// the collision itself at its own scale. Tolerance 1e-6: the bisection's unit problem and
    /// the real pair are integrated at the same steps per contact time (blanes-moan4 at 1/4096),
    /// and with the scale-respecting dashpot they are the same equation in scaled variables, so
    /// they carry the same first-order error of the damped contact (about 1e-5 against an
    /// independent solution: `validation/protector_reference.rs`) up to rounding.
    #[test]
    fn scaled_damping_gives_the_restitution_on_a_real_pair() {
        let d = 6e-3;
        let (a, b) = (STEEL.sphere_mass(d), PTFE.sphere_mass(d));
        let eta = hertz_eta(&STEEL, d, &PTFE, d);
        let c = hertz_damping(eta, a, b, 0.9).unwrap();
        for v in [1.0, 0.01] {
            let mu = a * b / (a + b);
            let overlap = (2.5 * mu * v * v / (2.0 * eta)).powf(0.4);
            let p = Collision {
                p: 1.5,
                eta,
                striker_mass: a,
                grain_mass: b,
                speed: v,
                contact_time: 2.0 * overlap / v * crate::scene::restitution::HERTZ_CONTACT_INTEGRAL,
            };
            let e = p.restitution(DampingModel::ScaleRespecting, c).unwrap();
            assert!((e - 0.9).abs() < 1e-6, "v = {v}: e = {e}");
        }
    }
}
