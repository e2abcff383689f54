//! Checking a parsed scene file, one table at a time, in the order the scene's errors are
//! reported (the first problem found is the one named). Each function names the scene key at
//! fault ([`Ctx::err`]).

use super::file::{EndFile, LawFile, RunFile, SceneFile};
use super::parts::{Ctx, InitialGrain, OutputSpec, PulseSpec, Region, SnapshotSpec, TrackSpec};
use super::si;
use crate::chain::material::Bead;
use crate::chain::{
    Chain, ChainBuilder, ChainError, ContactLaw, End, InterfaceRule, Section, Striker, StrikerEnd,
};
use crate::error::InputError;
use crate::integrators::{IntegrationParams, Method, MultirateParams, Sleep};
use crate::observables::{PulseRule, TrackRule};
use crate::run::Horizon;

/// The printed numbers of the first and last grain (a striker included).
#[derive(Clone, Copy, Debug)]
pub(super) struct Numbers {
    pub lo: i64,
    pub hi: i64,
    /// How far `chain.outer` moved every grain number of the file (0 without it): an error
    /// subtracts it again, so it names the numbers the file wrote.
    pub moved: i64,
}

impl Numbers {
    pub fn new(total: usize, striker_end: Option<StrikerEnd>, moved: i64) -> Numbers {
        // `total` is at most 1e8 grains (checked in `chain`).
        let (lo, hi) = match striker_end {
            Some(StrikerEnd::Left) => (0i64, total as i64),
            Some(StrikerEnd::Right) => (1, total as i64 + 1),
            None => (1, total as i64),
        };
        Numbers { lo, hi, moved }
    }

    /// Grain number `g` of the chain as the file wrote it.
    pub fn written(self, g: i64) -> i64 {
        g.saturating_sub(self.moved)
    }

    /// The chain's grains in the file's numbers, for messages.
    pub fn range(self) -> String {
        if self.moved == 0 {
            format!("grains {} to {}", self.lo, self.hi)
        } else {
            format!(
                "grains {} to {} as this file numbers them, after `chain.outer` resized the \
                 outer chains",
                self.written(self.lo),
                self.written(self.hi)
            )
        }
    }

    /// `g` if it is a grain of the chain, else an error under `key`.
    pub fn ok(self, c: &Ctx, key: String, g: i64) -> Result<i64, InputError> {
        if g < self.lo || g > self.hi {
            Err(c.err(
                key,
                format!(
                    "grain {} is outside the chain ({})",
                    self.written(g),
                    self.range()
                ),
            ))
        } else {
            Ok(g)
        }
    }
}

/// `chain.outer` with a damped medium needs a method that applies damping
/// ([`super::outer::method_problem`]), reported under `chain.outer`.
pub(super) fn outer_method(
    c: &Ctx,
    f: &SceneFile,
    medium: super::outer::OuterMedium,
) -> Result<(), InputError> {
    match super::outer::method_problem(f, medium) {
        Some(m) => Err(c.err("chain.outer", m)),
        None => Ok(()),
    }
}

/// The most grains a scene's chain may have: sections, target and striker together.
pub const MAX_GRAINS: usize = 100_000_000;

/// What `[chain]` built: the builder, the number of section grains, the key of the first damped
/// contact or section, and in an SI scene each section's sphere.
pub(super) struct Built {
    pub builder: ChainBuilder,
    pub total: usize,
    pub damped_key: Option<String>,
    pub spheres: Option<Vec<Bead>>,
}

/// `[chain]`: sections and ends (an SI scene's from their materials, [`super::si`]).
pub(super) fn chain(c: &Ctx, f: &SceneFile) -> Result<Built, InputError> {
    let ch = &f.chain;
    if ch.sections.is_empty() {
        return Err(c.err("chain.sections", "the chain needs at least one section"));
    }
    let si = si::is_si(f);
    let mut builder =
        ChainBuilder::new().interface(ch.interface.unwrap_or(InterfaceRule::MinExponent));
    if let Some(g) = ch.gravity {
        if !g.is_finite() {
            return Err(c.err("chain.gravity", format!("must be a finite number, got {g}")));
        }
        builder = builder.gravity(g);
    }
    let mut total: usize = 0;
    let mut damped_key: Option<String> = None;
    // A set, not a list: a scene of 1e5 one-grain sections took 80 s in this check (issue 38).
    let mut names: std::collections::HashSet<String> = std::collections::HashSet::new();
    let mut spheres: Vec<Bead> = Vec::new();
    for (i, s) in ch.sections.iter().enumerate() {
        let key = format!("chain.sections[{i}]");
        if s.count == 0 {
            return Err(c.err(format!("{key}.count"), "must be at least 1"));
        }
        total = total
            .checked_add(s.count as usize)
            .filter(|&t| t <= MAX_GRAINS)
            .ok_or_else(|| {
                c.err(
                    format!("{key}.count"),
                    "the chain may have at most 100000000 grains",
                )
            })?;
        let (mass, law, joint) = if let (true, Some(m)) = (si, &s.law.material) {
            let sphere = si::sphere(c, &key, m, s.diameter)?;
            let e = si::restitution(
                c,
                f,
                s.law.restitution.map(|e| (format!("{key}.restitution"), e)),
            )?;
            if let Some((k, _)) = &e {
                damped_key.get_or_insert_with(|| k.clone());
            }
            let run = si::at_key(c, e.as_ref(), {
                let e = e.as_ref().map(|(_, e)| *e);
                si::run(&sphere, spheres.last(), e, e)
            })?;
            let (m, law, joint) = (run.mass, run.inner.law, run.joint.map(|j| j.law));
            spheres.push(sphere);
            (m, law, joint)
        } else {
            let mass = s.mass.ok_or_else(|| {
                c.err(
                    format!("{key}.mass"),
                    "missing: give `mass`, `p` and `eta` (program units), or `material` and \
                     `diameter` (SI)",
                )
            })?;
            c.positive(&format!("{key}.mass"), mass)?;
            let law = c.law(&key, &s.law)?;
            if law.damping.is_some_and(|d| d.c > 0.0) && damped_key.is_none() {
                damped_key = Some(format!("{key}.contact_damping"));
            }
            (mass, law, None)
        };
        let name = s
            .name
            .clone()
            .unwrap_or_else(|| format!("section {}", i + 1));
        // Sections are looked up by name (regions, multirate, studies): a name given twice
        // would make the lookup ambiguous.
        if names.contains(&name) {
            return Err(c.err(
                format!("{key}.name"),
                format!("section `{name}` is named twice (names must be unique)"),
            ));
        }
        if f.target.is_some() && name == TARGET {
            return Err(c.err(
                format!("{key}.name"),
                format!("`{TARGET}` names the `[target]` body; give this section another name"),
            ));
        }
        names.insert(name.clone());
        let damping = c.non_negative(&format!("{key}.damping"), s.damping.unwrap_or(0.0))?;
        if damping > 0.0 && damped_key.is_none() {
            damped_key = Some(format!("{key}.damping"));
        }
        let mut section = Section::new(name, s.count as usize, mass, law).with_damping(damping);
        if let Some(j) = joint {
            section = section.with_joint(j);
        }
        builder = builder.section(section);
    }
    for (side, e) in [("left", &ch.left), ("right", &ch.right)] {
        let end = match e {
            None | Some(EndFile::Free) => End::Free,
            Some(EndFile::Wall(l)) => {
                let key = format!("chain.{side}");
                let law = match (si, &l.material) {
                    (true, Some(m)) => {
                        let wall = si::material(c, &format!("{key}.material"), m)?;
                        let bead = if side == "left" {
                            spheres[0]
                        } else {
                            spheres[spheres.len() - 1]
                        };
                        let e = si::restitution(
                            c,
                            f,
                            l.restitution.map(|e| (format!("{key}.restitution"), e)),
                        )?;
                        if let Some((k, _)) = &e {
                            damped_key.get_or_insert_with(|| k.clone());
                        }
                        let wall = si::Other::Flat {
                            material: wall,
                            mass: f64::INFINITY,
                        };
                        let x = si::contact(&bead, &wall, e.as_ref().map(|(_, e)| *e));
                        si::at_key(c, e.as_ref(), x)?.law
                    }
                    _ => c.law(&key, l)?,
                };
                if law.damping.is_some_and(|d| d.c > 0.0) && damped_key.is_none() {
                    damped_key = Some(format!("chain.{side}.contact_damping"));
                }
                End::Wall(law)
            }
        };
        builder = if side == "left" {
            builder.left(end)
        } else {
            builder.right(end)
        };
    }
    Ok(Built {
        builder,
        total,
        damped_key,
        spheres: si.then_some(spheres),
    })
}

/// The name of the section `[target]` builds, which [`crate::scene::Scene::protected_contact`]
/// looks for.
pub const TARGET: &str = "target";

/// `[striker]`: checked and added to the builder (in an SI scene a sphere of its material,
/// touching the end bead through the pair's Hertz constant). Returns the key of a damped
/// striker contact.
pub(super) fn striker(
    c: &Ctx,
    f: &SceneFile,
    mut builder: ChainBuilder,
    spheres: Option<&[Bead]>,
) -> Result<(ChainBuilder, Option<StrikerEnd>, Option<String>), InputError> {
    let ch = &f.chain;
    let mut striker_end = None;
    let mut damped = None;
    if let Some(s) = &f.striker {
        let end = s.end;
        let (mass, law) = match (spheres, &s.material) {
            (Some(spheres), Some(m)) => {
                let sphere = si::sphere(c, "striker", m, s.diameter)?;
                c.positive("striker.speed", s.speed)?;
                let bead = match end {
                    StrikerEnd::Left => spheres[0],
                    StrikerEnd::Right => spheres[spheres.len() - 1],
                };
                let e = si::restitution(
                    c,
                    f,
                    s.restitution
                        .map(|e| ("striker.restitution".to_string(), e)),
                )?;
                damped = e.as_ref().map(|(k, _)| k.clone());
                let x = si::contact(&sphere, &si::Other::Bead(bead), e.as_ref().map(|(_, e)| *e));
                (sphere.mass(), Some(si::at_key(c, e.as_ref(), x)?.law))
            }
            _ => {
                let mass = s.mass.ok_or_else(|| {
                    c.err(
                        "striker.mass",
                        "missing: give `mass` (program units), or `material` and `diameter` (SI)",
                    )
                })?;
                c.positive("striker.mass", mass)?;
                c.positive("striker.speed", s.speed)?;
                let law = match (s.p, s.eta) {
                    (None, None) => None,
                    (Some(p), Some(eta)) => Some(c.law("striker", &LawFile::new(p, eta))?),
                    _ => {
                        return Err(c.err(
                            "striker",
                            "give both `p` and `eta` for the striker's contact, or neither",
                        ))
                    }
                };
                (mass, law)
            }
        };
        let wall = match end {
            StrikerEnd::Left => matches!(ch.left, Some(EndFile::Wall(_))),
            StrikerEnd::Right => matches!(ch.right, Some(EndFile::Wall(_))),
        };
        if wall {
            return Err(c.err(
                "striker.end",
                "that end of the chain is a wall; a striker needs a free end",
            ));
        }
        if end == StrikerEnd::Right && f.target.is_some() {
            return Err(c.err(
                "striker.end",
                "the right end holds the `[target]`; strike the chain from the left",
            ));
        }
        striker_end = Some(end);
        builder = builder.striker(Striker {
            end,
            mass,
            speed: s.speed,
            law,
        });
    }
    Ok((builder, striker_end, damped))
}

/// `[target]`: the protected body, one grain joined to the last section's last grain (a section
/// named [`TARGET`]), the right end a linear spring to the ground (`spring`) or free. Its
/// contact with the last bead: Hertz from the materials in an SI scene (a sphere with
/// `diameter`, a flat face with `mass`), or `p` and `eta`; in a program-unit scene by default
/// the last section's law. Returns the builder and the key of a damped contact.
pub(super) fn target(
    c: &Ctx,
    f: &SceneFile,
    mut builder: ChainBuilder,
    spheres: Option<&[Bead]>,
) -> Result<(ChainBuilder, Option<String>), InputError> {
    let Some(t) = &f.target else {
        return Ok((builder, None));
    };
    if matches!(f.chain.right, Some(EndFile::Wall(_))) {
        return Err(c.err(
            "target",
            "the target is the chain's right end; give a `[target]` or a right wall \
             (`chain.right`), not both",
        ));
    }
    let explicit = match (t.p, t.eta) {
        (None, None) => None,
        (Some(p), Some(eta)) => Some(c.law("target", &LawFile::new(p, eta))?),
        _ => {
            return Err(c.err(
                "target",
                "give both `p` and `eta` for the target's contact, or neither",
            ))
        }
    };
    let mut damped = None;
    let (mass, law) =
        match spheres {
            Some(spheres) => {
                let bead = spheres[spheres.len() - 1];
                let e = si::restitution(
                    c,
                    f,
                    t.restitution.map(|e| ("target.restitution".to_string(), e)),
                )?;
                let hertz = |face: si::Other| {
                    let x = si::contact(&bead, &face, e.as_ref().map(|(_, e)| *e));
                    si::at_key(c, e.as_ref(), x).map(|x| x.law)
                };
                let (mass, law) =
                    match (&t.material, t.diameter, t.mass, explicit) {
                        (Some(_), _, _, Some(_)) => return Err(c.err(
                            "target.p",
                            "not with `material` (the contact is Hertz's from the two materials)",
                        )),
                        (Some(m), Some(_), Some(_), None) => {
                            let _ = si::material(c, "target.material", m)?;
                            return Err(c.err(
                                "target.mass",
                                "not with `diameter`: a sphere's mass is its material's; give \
                         `diameter` (a sphere) or `mass` (a body with a flat face), not both",
                            ));
                        }
                        (Some(m), Some(_), None, None) => {
                            let s = si::sphere(c, "target", m, t.diameter)?;
                            (s.mass(), hertz(si::Other::Bead(s))?)
                        }
                        (Some(m), None, Some(mass), None) => {
                            let material = si::material(c, "target.material", m)?;
                            let mass = c.positive("target.mass", mass)?;
                            (mass, hertz(si::Other::Flat { material, mass })?)
                        }
                        (None, _, Some(mass), Some(law)) => {
                            let mass = c.positive("target.mass", mass)?;
                            if t.diameter.is_some() {
                                return Err(c.err("target.diameter", "goes with `material` only"));
                            }
                            if law.p != 1.5 && e.is_some() {
                                return Err(c.err(
                                    e.map_or_else(String::new, |(k, _)| k),
                                    format!(
                                "a restitution damps Hertz contacts (p = 1.5); the target's \
                                 contact has p = {}",
                                law.p
                            ),
                                ));
                            }
                            let law = if law.p == 1.5 {
                                si::hertz_law(c, law.eta, bead.mass(), mass, e.as_ref())?
                            } else {
                                law
                            };
                            (mass, law)
                        }
                        _ => return Err(c.err(
                            "target",
                            "give `material` and `diameter` (a sphere), `material` and `mass` (a \
                         body with a flat face), or `mass`, `p` and `eta` (N/m^p)",
                        )),
                    };
                if let Some((k, _)) = &e {
                    damped = Some(k.clone());
                }
                (mass, law)
            }
            None => {
                let mass = t.mass.ok_or_else(|| {
                    c.err(
                        "target.mass",
                        "missing: the target's mass (program units; or an SI scene's `material`)",
                    )
                })?;
                let mass = c.positive("target.mass", mass)?;
                let last = f.chain.sections.len() - 1;
                let law = match explicit {
                    Some(l) => l,
                    // The last section's law, checked with it.
                    None => c.law(
                        &format!("chain.sections[{last}]"),
                        &f.chain.sections[last].law,
                    )?,
                };
                if law.damping.is_some_and(|d| d.c > 0.0) {
                    damped = Some(format!("chain.sections[{last}].contact_damping"));
                }
                (mass, law)
            }
        };
    let spring = match t.spring {
        Some(k) => End::Wall(ContactLaw::linear_spring(c.positive("target.spring", k)?)),
        None => End::Free,
    };
    builder = builder
        .section(Section::new(TARGET, 1, mass, law).with_joint(law))
        .right(spring);
    Ok((builder, damped))
}

/// `[[initial]]`: per-grain initial displacements and velocities, one entry per grain.
pub(super) fn initial(
    c: &Ctx,
    f: &SceneFile,
    num: Numbers,
) -> Result<Vec<InitialGrain>, InputError> {
    let mut initial = Vec::new();
    for (i, g) in f.initial.iter().enumerate() {
        let key = format!("initial[{i}]");
        // Errors name the key the file used: `grain`, or `first` and `last`.
        let (first, last, first_key, last_key) = match (g.grain, g.first, g.last) {
            (Some(n), None, None) => (n, n, "grain", "grain"),
            (None, Some(a), Some(b)) => (a, b, "first", "last"),
            _ => return Err(c.err(key, "give either `grain`, or both `first` and `last`")),
        };
        num.ok(c, format!("{key}.{first_key}"), first)?;
        num.ok(c, format!("{key}.{last_key}"), last)?;
        if first > last {
            return Err(c.err(
                format!("{key}.last"),
                format!("last ({last}) is before first ({first})"),
            ));
        }
        if g.velocity.is_none() && g.displacement.is_none() {
            return Err(c.err(key, "give a `velocity` or a `displacement`"));
        }
        if let Some(v) = g.velocity {
            if !v.is_finite() {
                return Err(c.err(
                    format!("{key}.velocity"),
                    format!("must be a finite number, got {v}"),
                ));
            }
        }
        if let Some(u) = g.displacement {
            if !u.is_finite() {
                return Err(c.err(
                    format!("{key}.displacement"),
                    format!("must be a finite number, got {u}"),
                ));
            }
        }
        for n in first..=last {
            initial.push((n, g.displacement, g.velocity));
        }
    }
    Ok(initial)
}

/// The most output times a scene's run may have (`run.duration / run.output_interval`), and so
/// the longest run a sweep's or `reproduce`'s `snapshots` may ask for: 1e9.
pub const MAX_OUTPUTS: u64 = 1_000_000_000;

/// The longest name, in bytes, that becomes a file or folder name (a scene's `name`, a study's
/// container key): 200, so that the name with what grainchain appends to it (`-m12345.json`) fits
/// in the 255 bytes a file name may have on Linux's file systems (issue 38: a 300-byte name
/// passed `check`, and `run` then failed with "File name too long").
pub const NAME_MAX_BYTES: usize = 200;

/// `name`: the scene's name, which names its default output folder `out/<name>`, so it must be
/// one plain folder name (not empty, no path separator, not `.` or `..`, no control character,
/// at most [`NAME_MAX_BYTES`]).
pub(super) fn name(c: &Ctx, name: Option<&str>) -> Result<(), InputError> {
    let Some(n) = name else { return Ok(()) };
    if n.len() > NAME_MAX_BYTES {
        return Err(c.err(
            "name",
            format!(
                "is {} bytes long; at most {NAME_MAX_BYTES} (it names the output folder \
                 out/<name>, and a file name has at most 255 bytes)",
                n.len()
            ),
        ));
    }
    let bad = if n.trim().is_empty() {
        Some("must not be empty (it names the output folder out/<name>)")
    } else if n.contains(['/', '\\']) || n.chars().any(char::is_control) {
        Some("must be a plain folder name, without `/`, `\\` or control characters (it names the output folder out/<name>)")
    } else if n == "." || n == ".." {
        Some("must not be `.` or `..` (it names the output folder out/<name>)")
    } else {
        None
    };
    match bad {
        Some(m) => Err(c.err("name", m.to_string())),
        None => Ok(()),
    }
}

/// `[run]`: duration and output interval.
pub(super) fn run_times(c: &Ctx, r: &RunFile) -> Result<(f64, f64), InputError> {
    let (duration, interval) = (r.duration, r.output_interval);
    crate::run::validate_schedule(duration, interval).map_err(|e| c.params(e))?;
    // The scenes' own limit (a library run may have more).
    if duration / interval > MAX_OUTPUTS as f64 {
        return Err(c.err(
            "run.output_interval",
            "more than 1e9 output times; use a longer interval",
        ));
    }
    Ok((duration, interval))
}

/// `run.horizon`: the causal horizon, which needs a method with [`crate::integrators::MethodInfo::horizon`]
/// and grains at rest skipped.
pub(super) fn horizon(
    c: &Ctx,
    r: &RunFile,
    params: &IntegrationParams,
) -> Result<Option<Horizon>, InputError> {
    let Some(h) = &r.horizon else {
        return Ok(None);
    };
    let speed = h.speed;
    // Speed, method and skipping, in the one place their rules live (`Horizon::validate`, which
    // reads the horizon's speed only).
    Horizon {
        speed,
        ..Horizon::DEFAULT
    }
    .validate(params)
    .map_err(|e| c.params(e))?;
    let pad = h.pad.unwrap_or(Horizon::DEFAULT_PAD);
    // The run adds the pad to a grain count: bounded by the most grains a chain may have, so
    // the sum cannot wrap (a larger pad would keep the whole chain anyway).
    if pad > MAX_GRAINS {
        return Err(c.err(
            "run.horizon.pad",
            format!("must be at most {MAX_GRAINS} grains (the most a chain may have), got {pad}"),
        ));
    }
    let unsafe_speed = h.unsafe_speed.unwrap_or(false);
    if unsafe_speed && speed.is_none() {
        return Err(c.err(
            "run.horizon.unsafe",
            "applies to an explicit `speed` below the bound only (without `speed` the horizon \
             takes the bound)",
        ));
    }
    Ok(Some(Horizon {
        speed,
        pad,
        unsafe_speed,
    }))
}

/// The envelope `[lo, hi)` (internal indices) of the grain ranges `grainchain run` protects from
/// the causal horizon, as `report::run_output::scene_recorder` records them and
/// `Recorder` protects them: every region, the snapshot range if a snapshot falls within the
/// run, the whole chain when pulses are detected within it or tracks are followed. `None`:
/// nothing protected (the horizon then drops nothing). `index` turns a printed grain number into
/// an internal index; `outputs` is the run's number of outputs after t = 0.
pub(super) fn protected_envelope(
    n: usize,
    regions: &[Region],
    output: &OutputSpec,
    outputs: u64,
    index: impl Fn(i64) -> usize,
) -> Option<(usize, usize)> {
    let within =
        |every: u64, at: &[u64]| every > 0 && (at.is_empty() || at.iter().any(|&k| k <= outputs));
    let mut ranges: Vec<(usize, usize)> = regions
        .iter()
        .map(|r| (index(r.first), index(r.last)))
        .collect();
    if let Some(s) = output.snapshots.as_ref().filter(|s| within(s.every, &s.at)) {
        ranges.push((index(s.first), index(s.last)));
    }
    let pulses = output
        .pulses
        .as_ref()
        .is_some_and(|p| within(p.every, &p.at));
    if pulses || output.tracks.is_some() {
        ranges.push((0, n.saturating_sub(1)));
    }
    // `Simulation::protect`: a range inside the chain, its end clipped to it.
    ranges
        .into_iter()
        .filter(|&(a, b)| a <= b && a < n)
        .map(|(a, b)| (a, (b + 1).min(n)))
        .reduce(|(a, b), (x, y)| (a.min(x), b.max(y)))
}

/// `run.horizon.speed` against the bound the run will compute: [`Horizon::speed_bound`] over
/// the contacts outside the protected `envelope` ([`protected_envelope`]) at the run's initial
/// energy ([`crate::run::initial_energy`], the same arithmetic as the run's). A speed below it is
/// refused unless `run.horizon.unsafe` (then the warning the run records too). Returns the
/// bound (`None`: no horizon, or nothing protected) and the warning.
pub(super) fn horizon_bound(
    c: &Ctx,
    horizon: Option<Horizon>,
    chain: &Chain,
    params: &IntegrationParams,
    initial: &[(usize, Option<f64>, Option<f64>)],
    envelope: Option<(usize, usize)>,
) -> Result<(Option<f64>, Option<String>), InputError> {
    let (Some(h), Some((lo, hi))) = (horizon, envelope) else {
        return Ok((None, None));
    };
    let e0 = crate::run::initial_energy(chain, params, initial)
        .map_err(|e| c.err("initial", e.to_string()))?;
    let bound = Horizon::speed_bound(chain, e0, lo, hi);
    let speed = h.speed.unwrap_or(bound);
    if h.unsafe_speed {
        return Ok((Some(bound), Horizon::warning(speed, bound)));
    }
    match Horizon::refusal(speed, bound) {
        Some(why) => Err(c.err("run.horizon.speed", why)),
        None => Ok((Some(bound), None)),
    }
}

/// `chain.gravity` against the run's settings (`run::gravity_settings`): a splitting method, no
/// sleep rule, no causal horizon.
pub(super) fn gravity(
    c: &Ctx,
    f: &SceneFile,
    params: &IntegrationParams,
    horizon: Option<&Horizon>,
) -> Result<(), InputError> {
    if f.chain.gravity.is_some_and(|g| g != 0.0) {
        crate::run::gravity_settings(params, horizon.is_some())
            .map_err(|why| c.err("chain.gravity", why))?;
    }
    Ok(())
}

/// `[integrator]`: the integration parameters (damped sections need a splitting method).
pub(super) fn integrator(
    c: &Ctx,
    f: &SceneFile,
    damped_key: Option<String>,
    interval: f64,
) -> Result<IntegrationParams, InputError> {
    let i = f.integrator.as_ref();
    let mut params = IntegrationParams::default();
    if let Some(i) = i {
        params.method = i.method.unwrap_or(Method::Verlet);
        let info = params.method.information();
        params.dt = i.dt.unwrap_or(params.dt);
        params.rtol = i.rtol.unwrap_or(params.rtol);
        params.atol = i.atol.unwrap_or(params.atol);
        params.skip_untouched = i.skip_untouched.unwrap_or(params.skip_untouched);
        params.events = i.events.unwrap_or(params.events);
        if let Some(x) = i.max_energy_error {
            // Stricter than the library's rule (where infinity switches the energy check off):
            // a scene cannot switch it off.
            params.max_energy_error = c.positive("integrator.max_energy_error", x)?;
        }
        params.sleep = i.sleep.map(|s| Sleep {
            velocity: s.velocity,
            force: s.force,
        });
        // Every value is checked here, in the one place the rules live
        // (`IntegrationParams::validate_values`), under its scene key.
        params.validate_values().map_err(|e| c.params(e))?;
        if !info.adaptive && (i.rtol.is_some() || i.atol.is_some()) {
            return Err(c.err(
                "integrator.rtol",
                format!(
                    "tolerances apply to adaptive methods only; {} takes a fixed dt",
                    info.name
                ),
            ));
        }
    }
    let info = params.method.information();
    if let Some(key) = damped_key {
        if !info.damping {
            return Err(c.err(
                key,
                format!(
                    "damping needs a splitting method ({}), not {}",
                    Method::names_with(|i| i.damping, "or"),
                    info.name
                ),
            ));
        }
    }
    params.validate_steps(interval).map_err(|e| c.params(e))?;
    Ok(params)
}

/// `[[regions]]`: named grain ranges.
pub(super) fn regions(c: &Ctx, f: &SceneFile, num: Numbers) -> Result<Vec<Region>, InputError> {
    let mut regions = Vec::new();
    // Names seen, as a set (a list made 1e5 regions quadratic: 33 s, issue 38).
    let mut seen = std::collections::HashSet::new();
    for (i, g) in f.regions.iter().enumerate() {
        let key = format!("regions[{i}]");
        if g.name.trim().is_empty() || g.name.contains(|ch: char| ch == ',' || ch.is_control()) {
            return Err(c.err(
                format!("{key}.name"),
                "must be a non-empty name without commas",
            ));
        }
        if !seen.insert(g.name.as_str()) {
            return Err(c.err(
                format!("{key}.name"),
                format!("region `{}` is defined twice", g.name),
            ));
        }
        num.ok(c, format!("{key}.first"), g.first)?;
        num.ok(c, format!("{key}.last"), g.last)?;
        if g.first > g.last {
            return Err(c.err(
                format!("{key}.last"),
                format!("last ({}) is before first ({})", g.last, g.first),
            ));
        }
        regions.push(Region {
            name: g.name.clone(),
            first: g.first,
            last: g.last,
        });
    }
    Ok(regions)
}

/// An `at` list of output indices (`output.snapshots.at`, `output.pulses.at`): increasing, each
/// index once, none after the run's last output `outputs` (issue 38: an index beyond the run was
/// accepted and recorded nothing, and a million repeats of five indices were estimated as a
/// million snapshots). Linear in the list's length.
fn at_list(c: &Ctx, key: &str, at: &[u64], outputs: u64) -> Result<(), InputError> {
    if let Some(w) = at.windows(2).position(|w| w[1] <= w[0]) {
        return Err(c.err(
            format!("{key}[{}]", w + 1),
            format!(
                "output indices must increase, each listed once: {} follows {}",
                at[w + 1],
                at[w]
            ),
        ));
    }
    match at.last() {
        Some(&k) if k > outputs => Err(c.err(
            format!("{key}[{}]", at.len() - 1),
            format!(
                "output {k} is after the run's last output, {outputs} (run.duration / \
                 run.output_interval)"
            ),
        )),
        _ => Ok(()),
    }
}

/// `[output]`: what `grainchain run` writes; `outputs` is the run's number of outputs after
/// t = 0.
pub(super) fn output(
    c: &Ctx,
    f: &SceneFile,
    num: Numbers,
    params: &IntegrationParams,
    outputs: u64,
) -> Result<OutputSpec, InputError> {
    let mut output = OutputSpec {
        energies: true,
        ..Default::default()
    };
    if let Some(o) = &f.output {
        output.energies = o.energies.unwrap_or(true);
        if let Some(s) = &o.snapshots {
            if s.fields.is_empty() {
                return Err(c.err("output.snapshots.fields", "name at least one field"));
            }
            let every = s.every.unwrap_or(1);
            if every == 0 {
                return Err(c.err("output.snapshots.every", "must be at least 1"));
            }
            let first = num.ok(
                c,
                "output.snapshots.first".into(),
                s.first.unwrap_or(num.lo),
            )?;
            let last = num.ok(c, "output.snapshots.last".into(), s.last.unwrap_or(num.hi))?;
            if first > last {
                return Err(c.err(
                    "output.snapshots.last",
                    format!("last ({last}) is before first ({first})"),
                ));
            }
            at_list(c, "output.snapshots.at", &s.at, outputs)?;
            output.snapshots = Some(SnapshotSpec {
                fields: s.fields.clone(),
                every,
                at: s.at.clone(),
                first,
                last,
            });
        }
        if let Some(p) = &o.pulses {
            let (every, rule) = pulse_rule(c, "output.pulses", p.every, p.threshold, p.valley)?;
            at_list(c, "output.pulses.at", &p.at, outputs)?;
            output.pulses = Some(PulseSpec {
                every,
                at: p.at.clone(),
                rule,
            });
        }
        if let Some(p) = &o.tracks {
            let (every, rule) = pulse_rule(c, "output.tracks", p.every, p.threshold, p.valley)?;
            let max_jump = p.max_jump.unwrap_or(f64::INFINITY);
            if !(max_jump > 0.0) {
                return Err(c.err(
                    "output.tracks.max_jump",
                    format!("must be positive, got {max_jump}"),
                ));
            }
            let info = params.method.information();
            if !info.tracks {
                return Err(c.err(
                    "output.tracks",
                    format!(
                        "the true peak velocity needs per-step velocities, which {} keep and {} \
                         does not",
                        Method::names_with(|i| i.tracks, "and"),
                        info.name
                    ),
                ));
            }
            output.tracks = Some(TrackSpec {
                every,
                rule,
                track: TrackRule { max_jump },
            });
        }
    }
    Ok(output)
}

/// What only the whole chain can tell (precompression balance), checked by the builder; the
/// chain built is the scene's.
pub(super) fn whole_chain(
    c: &Ctx,
    f: &SceneFile,
    builder: ChainBuilder,
) -> Result<Chain, InputError> {
    // The end without a wall is the one to change (issue 38: the left wall was blamed).
    let wall = |e: &Option<EndFile>| matches!(e, Some(EndFile::Wall(_)));
    let free_end = if wall(&f.chain.left) {
        "chain.right"
    } else {
        "chain.left"
    };
    builder.build().map_err(|e| match e {
        ChainError::PrecompressionWithoutWalls => c.err(
            free_end,
            "precompression (delta0 > 0) needs walls at both ends to hold it, and this end has \
             none",
        ),
        e @ (ChainError::Gravity(_)
        | ChainError::GravityWithPrecompression
        | ChainError::GravityBetweenWalls) => c.err("chain.gravity", e.to_string()),
        other => c.err("chain", other.to_string()),
    })
}

/// Multiple time stepping: the ratio dividing the steps of an output interval, the fast region
/// by name (widened by the margin), as internal indices of `chain`.
pub(super) fn multirate(
    c: &Ctx,
    f: &SceneFile,
    params: &IntegrationParams,
    interval: f64,
    regions: &[Region],
    num: Numbers,
    chain: &Chain,
) -> Result<Option<MultirateParams>, InputError> {
    let i = f.integrator.as_ref();
    let mr = i.and_then(|i| i.multirate.as_ref());
    let info = params.method.information();
    let Some(m) = mr else {
        if info.multirate {
            return Err(c.err(
                "integrator.multirate",
                "method multirate needs `multirate = { ratio = .., fast = \"<region>\" }`",
            ));
        }
        return Ok(None);
    };
    if !info.multirate {
        return Err(c.err(
            "integrator.multirate",
            format!("applies to method multirate only, not {}", info.name),
        ));
    }
    params
        .validate_ratio(m.ratio, interval)
        .map_err(|e| c.params(e))?;
    let r = regions.iter().find(|r| r.name == m.fast).ok_or_else(|| {
        c.err(
            "integrator.multirate.fast",
            format!("`{}` is not a region of this scene", m.fast),
        )
    })?;
    // Any margin past the chain's ends is clamped to them (saturating: a margin near the
    // integer's maximum neither wraps nor panics).
    let margin = i64::try_from(m.margin.unwrap_or(0)).unwrap_or(i64::MAX);
    // Inside the chain: the region is, and the margin is clamped to its ends.
    let index = |g: i64| {
        chain.index_of(g).ok_or_else(|| {
            c.err(
                "integrator.multirate.fast",
                format!(
                    "grain {} is outside the chain ({})",
                    num.written(g),
                    num.range()
                ),
            )
        })
    };
    let p = MultirateParams {
        ratio: m.ratio,
        first: index(r.first.saturating_sub(margin).max(num.lo))?,
        last: index(r.last.saturating_add(margin).min(num.hi))?,
    };
    IntegrationParams {
        multirate: Some(p),
        ..*params
    }
    .validate_multirate(interval, Some(chain.len()))
    .map_err(|e| c.params(e))?;
    Ok(Some(p))
}

/// The detection settings of `output.pulses` or `output.tracks` (`table`): `every` (default 1,
/// at least 1), `threshold` in (0, 1) and `valley` in (0, 1] (defaults of [`PulseRule`]).
fn pulse_rule(
    c: &Ctx,
    table: &str,
    every: Option<u64>,
    threshold: Option<f64>,
    valley: Option<f64>,
) -> Result<(u64, PulseRule), InputError> {
    let every = every.unwrap_or(1);
    if every == 0 {
        return Err(c.err(format!("{table}.every"), "must be at least 1"));
    }
    let rule = PulseRule {
        threshold: threshold.unwrap_or(PulseRule::default().threshold),
        valley: valley.unwrap_or(PulseRule::default().valley),
    };
    if !(rule.threshold.is_finite() && rule.threshold > 0.0 && rule.threshold < 1.0) {
        return Err(c.err(
            format!("{table}.threshold"),
            format!("must be between 0 and 1, got {}", rule.threshold),
        ));
    }
    if !(rule.valley.is_finite() && rule.valley > 0.0 && rule.valley <= 1.0) {
        return Err(c.err(
            format!("{table}.valley"),
            format!("must be in (0, 1], got {}", rule.valley),
        ));
    }
    Ok((every, rule))
}
