//! Building a [`Chain`] from sections, ends, an interface rule and an optional striker.

use super::error::ChainError;
use super::law::ContactLaw;
use super::{Chain, SectionSpan, Segment};
use serde::{Deserialize, Serialize};

/// A run of identical grains.
#[derive(Clone, Debug, PartialEq)]
pub struct Section {
    /// Name of the section, unique in the chain: how scenes, regions and lookups
    /// ([`Chain::section`], [`Chain::grains_of`]) refer to it.
    pub name: String,
    /// Number of grains in the section (at least 1).
    pub count: usize,
    /// Mass of each of its grains (finite, > 0).
    pub mass: f64,
    /// Law of the contacts inside the section.
    pub law: ContactLaw,
    /// Viscous damping rate of its grains (`dv/dt = a - damping v`; 0: none): an absorbing
    /// layer. Only the splitting methods apply it (see `Chain::damp`).
    pub damping: f64,
    /// Law of the contact joining this section's first grain to the grain on its left (the
    /// previous section's last grain), when it is neither section's own law: two spheres of
    /// different materials or sizes touch through their pair's Hertz constant
    /// (`units::hertz_eta`). `None`: the chain's [`InterfaceRule`] picks one of the two laws.
    /// Ignored on the first section (a left striker's contact is the striker's law).
    pub joint: Option<ContactLaw>,
}

impl Section {
    /// A section of `count` grains of `mass` whose internal contacts follow `law`, undamped.
    pub fn new(name: impl Into<String>, count: usize, mass: f64, law: ContactLaw) -> Self {
        Section {
            name: name.into(),
            count,
            mass,
            law,
            damping: 0.0,
            joint: None,
        }
    }

    /// The same section joined to the grain on its left by `law` instead of the interface rule's
    /// pick (see [`Section::joint`]).
    pub fn with_joint(mut self, law: ContactLaw) -> Self {
        self.joint = Some(law);
        self
    }

    /// The same section with viscous damping rate `c` (an absorbing layer).
    pub fn with_damping(mut self, c: f64) -> Self {
        self.damping = c;
        self
    }
}

/// An end of the chain.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum End {
    /// Nothing beyond the last grain.
    Free,
    /// A rigid wall: a contact with an immovable grain, with its own law.
    Wall(ContactLaw),
}

/// Which law a contact between two sections of different laws uses.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(rename_all = "kebab-case")]
pub enum InterfaceRule {
    /// The law of the section with the smaller exponent (ties: the left one). Symmetric in
    /// the exponents, so a mirror-symmetric container stays mirror-symmetric.
    #[default]
    MinExponent,
    /// The law of the section with the larger exponent (ties: the left one).
    MaxExponent,
    /// Always the law of the section on the left.
    Left,
    /// Always the law of the section on the right.
    Right,
}

impl InterfaceRule {
    /// The rule's name as in scene files (`min-exponent`, `max-exponent`, `left`, `right`).
    pub fn name(self) -> &'static str {
        match self {
            InterfaceRule::MinExponent => "min-exponent",
            InterfaceRule::MaxExponent => "max-exponent",
            InterfaceRule::Left => "left",
            InterfaceRule::Right => "right",
        }
    }

    /// The law of a contact between a grain with law `left` and one with law `right` (the two
    /// sections' own laws) under this rule.
    pub fn pick(self, left: ContactLaw, right: ContactLaw) -> ContactLaw {
        match self {
            InterfaceRule::MinExponent => {
                if right.p < left.p {
                    right
                } else {
                    left
                }
            }
            InterfaceRule::MaxExponent => {
                if right.p > left.p {
                    right
                } else {
                    left
                }
            }
            InterfaceRule::Left => left,
            InterfaceRule::Right => right,
        }
    }
}

/// Which end a striker hits.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(rename_all = "kebab-case")]
pub enum StrikerEnd {
    /// The striker sits left of the first chain grain (internal index 0, printed grain 0) and
    /// moves right.
    Left,
    /// The striker sits right of the last chain grain (internal index n - 1, printed grain
    /// N + 1) and moves left.
    Right,
}

/// An extra grain that hits one end of the chain.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Striker {
    /// Which end of the chain it hits (that end must be free).
    pub end: StrikerEnd,
    /// Mass of the striker (finite, > 0).
    pub mass: f64,
    /// Speed towards the chain (> 0).
    pub speed: f64,
    /// Law of its contact with the end grain; default: the end section's law.
    pub law: Option<ContactLaw>,
}

/// Builds a [`Chain`] (diffsol-style builder).
#[derive(Clone, Debug)]
pub struct ChainBuilder {
    sections: Vec<Section>,
    interface: InterfaceRule,
    left: End,
    right: End,
    striker: Option<Striker>,
    gravity: f64,
}

impl Default for ChainBuilder {
    fn default() -> Self {
        Self::new()
    }
}

impl ChainBuilder {
    /// An empty builder: no sections, free ends, the [`InterfaceRule::MinExponent`] rule, no
    /// striker.
    pub fn new() -> Self {
        ChainBuilder {
            sections: Vec::new(),
            interface: InterfaceRule::default(),
            left: End::Free,
            right: End::Free,
            striker: None,
            gravity: 0.0,
        }
    }

    /// Append a section on the right.
    pub fn section(mut self, s: Section) -> Self {
        self.sections.push(s);
        self
    }

    /// Append `count` grains of `mass` with `law` (named after their position).
    pub fn grains(self, count: usize, mass: f64, law: ContactLaw) -> Self {
        let name = format!("section {}", self.sections.len() + 1);
        self.section(Section::new(name, count, mass, law))
    }

    /// The rule picking the law of a contact between sections of different laws (default:
    /// [`InterfaceRule::MinExponent`]).
    pub fn interface(mut self, rule: InterfaceRule) -> Self {
        self.interface = rule;
        self
    }

    /// The left end (default: [`End::Free`]).
    pub fn left(mut self, end: End) -> Self {
        self.left = end;
        self
    }

    /// The right end (default: [`End::Free`]).
    pub fn right(mut self, end: End) -> Self {
        self.right = end;
        self
    }

    /// Add a striker, an extra grain outside the sections hitting one free end (it becomes internal
    /// grain 0 for a left striker, the last grain for a right one).
    pub fn striker(mut self, s: Striker) -> Self {
        self.striker = Some(s);
        self
    }

    /// A constant acceleration `g` on every grain (a striker included), positive towards the
    /// right end (default 0: none). The chain then starts in its static equilibrium under
    /// gravity: with a wall at the end gravity points to (the floor) and a free end at the
    /// other, every contact's static force is the weight of the chain grains above it (a striker
    /// excluded: it arrives with its speed) and its overlap `delta0 = (W / eta)^(1/p)`; with a
    /// free end below, every contact starts at zero force and the chain falls. Refused: a
    /// precompression (delta0 > 0) with gravity, walls at both ends.
    ///
    /// ```
    /// use grainchain_engine::{ChainBuilder, ContactLaw, End};
    /// let law = ContactLaw::hertz(1.0);
    /// let chain = ChainBuilder::new().grains(3, 2.0, law).right(End::Wall(law)).gravity(0.5).build()?;
    /// // The floor carries the weight of all three grains, the contact below the top one its own.
    /// assert!((chain.contact_law(3).unwrap().static_force() - 3.0).abs() < 1e-12);
    /// assert!((chain.contact_law(1).unwrap().static_force() - 1.0).abs() < 1e-12);
    /// # Ok::<(), grainchain_engine::ChainError>(())
    /// ```
    pub fn gravity(mut self, g: f64) -> Self {
        self.gravity = g;
        self
    }

    /// Check every section, end and the striker, then lay out the grains and contacts. Errors:
    /// [`ChainError`]; a precompressed chain must have walls at both ends and balanced static
    /// forces.
    pub fn build(self) -> Result<Chain, ChainError> {
        self.check()?;
        let ChainBuilder {
            sections,
            interface,
            left,
            right,
            striker,
            gravity,
        } = self;
        let grains = Grains::lay_out(&sections, striker.as_ref());
        let n = grains.mass.len();
        let mut claw = interior_laws(&grains.own, &sections, interface);
        let wall_law = |e: &End| match e {
            End::Wall(l) => Some(*l),
            End::Free => None,
        };
        let (mut left_law, mut right_law) = (wall_law(&left), wall_law(&right));
        let striker_at = striker.map(|s| match s.end {
            StrikerEnd::Left => 0,
            StrikerEnd::Right => n - 1,
        });
        if gravity != 0.0 {
            settle(
                &mut claw,
                &mut left_law,
                &mut right_law,
                &grains.mass,
                striker_at,
                gravity,
            )?;
        }
        let (segments, contact_segment) = segments(&claw);
        let forms = super::Forms::of(&claw);
        let (lw, rw) = (
            left_law.map(|l| (l, l.kernel())),
            right_law.map(|l| (l, l.kernel())),
        );
        let number_offset = if grains.left_striker { 0 } else { 1 };
        let weights = (gravity != 0.0).then_some((&grains.mass[..], gravity));
        let static_force = static_forces(&claw, left_law, right_law, number_offset, weights)?;
        let inv_mass = grains.mass.iter().map(|m| 1.0 / m).collect();
        let damped = grains
            .spans
            .iter()
            .filter(|s| s.damping > 0.0)
            .map(|s| (s.first, s.last + 1, s.damping))
            .collect();
        let striker = striker.map(|s| match s.end {
            StrikerEnd::Right => (n - 1, -s.speed),
            StrikerEnd::Left => (0, s.speed),
        });
        let mut chain = Chain {
            damped,
            damped_contacts: Vec::new(),
            damped_grains: Vec::new(),
            mass: grains.mass,
            inv_mass,
            segments,
            contact_segment,
            forms,
            left: lw,
            right: rw,
            static_force,
            number_offset,
            sections: grains.spans,
            striker,
            gravity,
        };
        chain.damped_contacts = chain.damped_runs();
        chain.damped_grains = chain.damped_spans();
        Ok(chain)
    }

    /// Every check that needs no layout: sections, wall laws, the striker, the length.
    fn check(&self) -> Result<(), ChainError> {
        let sections = &self.sections;
        if sections.is_empty() {
            return Err(ChainError::Empty);
        }
        let mut seen = std::collections::HashSet::new();
        for (index, s) in sections.iter().enumerate() {
            let name = s.name.clone();
            if !seen.insert(s.name.as_str()) {
                return Err(ChainError::DuplicateSection { index, name });
            }
            if s.count == 0 {
                return Err(ChainError::SectionCount { index, name });
            }
            if !(s.mass.is_finite() && s.mass > 0.0) {
                return Err(ChainError::SectionMass {
                    index,
                    name,
                    mass: s.mass,
                });
            }
            if !(s.damping.is_finite() && s.damping >= 0.0) {
                return Err(ChainError::SectionDamping {
                    index,
                    name,
                    damping: s.damping,
                });
            }
            s.law.validate().map_err(|source| ChainError::SectionLaw {
                index,
                name: name.clone(),
                source,
            })?;
            if let Some(joint) = &s.joint {
                joint.validate().map_err(|source| ChainError::SectionLaw {
                    index,
                    name,
                    source,
                })?;
            }
        }
        for (end, e) in [("left", &self.left), ("right", &self.right)] {
            if let End::Wall(l) = e {
                l.validate()
                    .map_err(|source| ChainError::WallLaw { end, source })?;
            }
        }
        if let Some(s) = &self.striker {
            self.check_striker(s)?;
        }
        if !self.gravity.is_finite() {
            return Err(ChainError::Gravity(self.gravity));
        }
        let total: usize = sections.iter().map(|s| s.count).sum();
        let n = total + usize::from(self.striker.is_some());
        if n >= u32::MAX as usize {
            return Err(ChainError::TooLong(n));
        }
        Ok(())
    }

    fn check_striker(&self, s: &Striker) -> Result<(), ChainError> {
        if !(s.mass.is_finite() && s.mass > 0.0) {
            return Err(ChainError::StrikerMass(s.mass));
        }
        if !(s.speed.is_finite() && s.speed > 0.0) {
            return Err(ChainError::StrikerSpeed(s.speed));
        }
        if let Some(l) = &s.law {
            l.validate().map_err(ChainError::StrikerLaw)?;
        }
        match (s.end, &self.left, &self.right) {
            (StrikerEnd::Left, End::Wall(_), _) => Err(ChainError::StrikerAtWall("left")),
            (StrikerEnd::Right, _, End::Wall(_)) => Err(ChainError::StrikerAtWall("right")),
            _ => Ok(()),
        }
    }
}

/// Marks the striker in [`Grains::own`] (it belongs to no section).
const STRIKER: usize = usize::MAX;

/// The grains laid out in chain order: masses, each grain's own law and section, the spans.
struct Grains {
    mass: Vec<f64>,
    /// `(law, section index)` of each grain; the striker's section is [`STRIKER`] and its law
    /// the one it was given, else the law of the section it hits.
    own: Vec<(ContactLaw, usize)>,
    spans: Vec<SectionSpan>,
    left_striker: bool,
}

impl Grains {
    fn lay_out(sections: &[Section], striker: Option<&Striker>) -> Grains {
        let n = sections.iter().map(|s| s.count).sum::<usize>() + usize::from(striker.is_some());
        let mut g = Grains {
            mass: Vec::with_capacity(n),
            own: Vec::with_capacity(n),
            spans: Vec::new(),
            left_striker: striker.is_some_and(|s| s.end == StrikerEnd::Left),
        };
        if let Some(s) = striker.filter(|s| s.end == StrikerEnd::Left) {
            g.mass.push(s.mass);
            g.own.push((s.law.unwrap_or(sections[0].law), STRIKER));
        }
        for (si, s) in sections.iter().enumerate() {
            let first = g.mass.len();
            for _ in 0..s.count {
                g.mass.push(s.mass);
                g.own.push((s.law, si));
            }
            g.spans.push(SectionSpan {
                name: s.name.clone(),
                first,
                last: g.mass.len() - 1,
                mass: s.mass,
                law: s.law,
                damping: s.damping,
            });
        }
        if let Some(s) = striker.filter(|s| s.end == StrikerEnd::Right) {
            g.mass.push(s.mass);
            let last = sections.last().map(|s| s.law);
            g.own
                .push((s.law.or(last).unwrap_or(sections[0].law), STRIKER));
        }
        g
    }
}

/// Laws of the interior contacts `1..n`: a section's own law inside it, the striker's law at its
/// contact, and between two sections the right one's joint law if it has one, else the
/// interface rule's pick.
fn interior_laws(
    own: &[(ContactLaw, usize)],
    sections: &[Section],
    interface: InterfaceRule,
) -> Vec<ContactLaw> {
    own.windows(2)
        .map(|w| {
            let ((l, ls), (r, rs)) = (w[0], w[1]);
            if ls == STRIKER {
                l // left striker's contact
            } else if rs == STRIKER {
                r // right striker's contact
            } else if ls == rs {
                l
            } else if let Some(joint) = sections[rs].joint {
                joint
            } else {
                interface.pick(l, r)
            }
        })
        .collect()
}

/// Runs of equal law among the interior contacts, and the segment of each contact `0..=n`.
fn segments(claw: &[ContactLaw]) -> (Vec<Segment>, Vec<u32>) {
    let mut segments: Vec<Segment> = Vec::new();
    let mut contact_segment = vec![0u32; claw.len() + 2];
    for (j, law) in claw.iter().enumerate() {
        let k = j + 1;
        match segments.last_mut() {
            Some(seg) if seg.law == *law && seg.c1 == k => seg.c1 = k + 1,
            _ => segments.push(Segment {
                c1: k + 1,
                law: *law,
                kernel: law.kernel(),
            }),
        }
        contact_segment[k] = (segments.len() - 1) as u32;
    }
    (segments, contact_segment)
}

/// The static state under gravity `g` (`ChainBuilder::gravity`): with a wall at the end `g`
/// points to and a free end at the other, each contact's overlap `delta0 = (W / eta)^(1/p)`
/// holds `W`, the weight `|g| m` of the chain grains above it (a striker excluded); with a free
/// end below, nothing (every contact starts at zero force). Refuses a precompression given with
/// gravity and walls at both ends.
fn settle(
    claw: &mut [ContactLaw],
    left: &mut Option<ContactLaw>,
    right: &mut Option<ContactLaw>,
    mass: &[f64],
    striker: Option<usize>,
    g: f64,
) -> Result<(), ChainError> {
    let precompressed = claw.iter().any(|l| l.delta0 != 0.0)
        || left.is_some_and(|l| l.delta0 != 0.0)
        || right.is_some_and(|l| l.delta0 != 0.0);
    if precompressed {
        return Err(ChainError::GravityWithPrecompression);
    }
    if left.is_some() && right.is_some() {
        return Err(ChainError::GravityBetweenWalls);
    }
    let n = mass.len();
    let weight = |i: usize| {
        if Some(i) == striker {
            0.0
        } else {
            g.abs() * mass[i]
        }
    };
    let hold = |law: &mut ContactLaw, w: f64| {
        if w > 0.0 {
            law.delta0 = (w / law.eta).powf(1.0 / law.p);
        }
    };
    if g > 0.0 {
        let Some(floor) = right.as_mut() else {
            return Ok(());
        };
        // Contact k (1..n) holds grains 0..k; the floor (contact n) all of them.
        let mut w = 0.0;
        for k in 1..n {
            w += weight(k - 1);
            hold(&mut claw[k - 1], w);
        }
        hold(floor, w + weight(n - 1));
    } else {
        let Some(floor) = left.as_mut() else {
            return Ok(());
        };
        // Contact k (0..n-1) holds grains k..n; the floor (contact 0) all of them.
        let mut w = 0.0;
        for k in (1..n).rev() {
            w += weight(k);
            hold(&mut claw[k - 1], w);
        }
        hold(floor, w + weight(0));
    }
    Ok(())
}

/// Force of each contact `0..=n` with every grain at rest; a precompression must be held by walls
/// at both ends and be the same on both sides of every grain, or under gravity (`weights`: the
/// masses and g) differ by the grain's weight.
fn static_forces(
    claw: &[ContactLaw],
    left: Option<ContactLaw>,
    right: Option<ContactLaw>,
    number_offset: i64,
    weights: Option<(&[f64], f64)>,
) -> Result<Vec<f64>, ChainError> {
    let precompressed = claw.iter().any(|l| l.delta0 != 0.0)
        || left.is_some_and(|l| l.delta0 != 0.0)
        || right.is_some_and(|l| l.delta0 != 0.0);
    if precompressed && weights.is_none() && (left.is_none() || right.is_none()) {
        return Err(ChainError::PrecompressionWithoutWalls);
    }
    let n = claw.len() + 1;
    let mut static_force = vec![0.0; n + 1];
    static_force[0] = left.map_or(0.0, |l| l.static_force());
    static_force[n] = right.map_or(0.0, |l| l.static_force());
    for k in 1..n {
        static_force[k] = claw[k - 1].static_force();
    }
    for i in 0..n {
        let (fl, fr) = (static_force[i], static_force[i + 1]);
        // Under gravity a grain at rest on the floor carries its weight (a striker, moving,
        // none: its contact starts at zero force; it is then the only unbalanced grain).
        let w = match weights {
            Some((m, g)) if fl != 0.0 || fr != 0.0 => g * m[i],
            _ => 0.0,
        };
        // Walls hold a balanced precompression exactly only when both sides compute the same
        // number; a mismatch beyond round-off is a mistake in the scene. Under gravity the
        // builder computed the overlaps (`settle`): a mismatch would be its own mistake.
        if (fl + w - fr).abs() > 1e-12 * fl.abs().max(fr.abs()) {
            return Err(ChainError::PrecompressionUnbalanced {
                grain: i as i64 + number_offset,
                left: fl,
                right: fr,
            });
        }
    }
    Ok(static_force)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hertz() -> ContactLaw {
        ContactLaw::hertz(5657.0)
    }

    /// A section's joint law is the law of the contact with the grain on its left, whatever the
    /// interface rule would pick; contacts inside the sections keep their own laws.
    #[test]
    fn a_joint_law_overrides_the_interface_rule_at_its_contact_only() {
        let (a, b, joint) = (hertz(), ContactLaw::new(1.0, 7.0), ContactLaw::hertz(3.0));
        let chain = ChainBuilder::new()
            .section(Section::new("a", 2, 1.0, a))
            .section(Section::new("b", 2, 1.0, b).with_joint(joint))
            .build()
            .unwrap();
        assert_eq!(chain.contact_law(1), Some(a));
        assert_eq!(chain.contact_law(2), Some(joint));
        assert_eq!(chain.contact_law(3), Some(b));
        let bad = ChainBuilder::new()
            .section(Section::new("a", 2, 1.0, a))
            .section(Section::new("b", 2, 1.0, b).with_joint(ContactLaw::hertz(-1.0)))
            .build();
        assert!(
            matches!(bad, Err(ChainError::SectionLaw { index: 1, .. })),
            "{bad:?}"
        );
    }

    /// Under gravity each contact holds the weight of the chain grains above it, the floor at
    /// either end (g > 0: the right wall; g < 0: the left one); a striker's weight is not held
    /// (it arrives moving); no floor: no static force; refusals by their variant.
    #[test]
    fn gravity_settles_the_chain_on_its_floor() {
        let masses = [1.0, 2.0, 0.5];
        let build = |g: f64, left: End, right: End, striker: bool| {
            let mut b = ChainBuilder::new()
                .section(Section::new("a", 1, masses[0], hertz()))
                .section(Section::new("b", 1, masses[1], ContactLaw::new(1.0, 300.0)))
                .section(Section::new("c", 1, masses[2], hertz()))
                .left(left)
                .right(right)
                .gravity(g);
            if striker {
                b = b.striker(Striker {
                    end: StrikerEnd::Left,
                    mass: 7.0,
                    speed: 1.0,
                    law: None,
                });
            }
            b.build()
        };
        let force = |c: &Chain, k: usize| c.contact_law(k).map_or(0.0, |l| l.static_force());
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-14 * b.abs().max(1.0);
        // g = 2 towards the right floor: contact k carries 2 (m_0 + .. + m_(k-1)).
        let c = build(2.0, End::Free, End::Wall(hertz()), false).unwrap();
        let down = [0.0, 2.0, 6.0, 7.0];
        for (k, w) in down.iter().enumerate() {
            assert!(
                close(force(&c, k), *w),
                "contact {k}: {} vs {w}",
                force(&c, k)
            );
        }
        // g = -2 towards the left floor: contact k carries 2 (m_k + .. + m_2).
        let c = build(-2.0, End::Wall(hertz()), End::Free, false).unwrap();
        let up = [7.0, 5.0, 1.0, 0.0];
        for (k, w) in up.iter().enumerate() {
            assert!(
                close(force(&c, k), *w),
                "contact {k}: {} vs {w}",
                force(&c, k)
            );
        }
        // A left striker (grain 0) on top: its contact starts at zero force, the rest as before.
        let c = build(2.0, End::Free, End::Wall(hertz()), true).unwrap();
        assert_eq!(force(&c, 1), 0.0);
        for (k, w) in down.iter().enumerate().skip(1) {
            assert!(close(force(&c, k + 1), *w), "contact {}", k + 1);
        }
        // No floor: the chain falls, every contact at zero force.
        let c = build(2.0, End::Wall(hertz()), End::Free, false).unwrap();
        assert!((0..=3).all(|k| force(&c, k) == 0.0));
        assert_eq!(c.gravity(), 2.0);
        assert!(matches!(
            build(1.0, End::Wall(hertz()), End::Wall(hertz()), false),
            Err(ChainError::GravityBetweenWalls)
        ));
        assert!(matches!(
            build(f64::NAN, End::Free, End::Free, false),
            Err(ChainError::Gravity(_))
        ));
        let pre = hertz().with_precompression(0.01);
        assert!(matches!(
            build(1.0, End::Free, End::Wall(pre), false),
            Err(ChainError::GravityWithPrecompression)
        ));
    }

    /// `Chain::potential_energy` (one dispatch per segment) gives the bits of the plain sum of
    /// `contact_energy` over every range of contacts, for every law kind, precompression and
    /// tension, walls at both ends.
    #[test]
    fn potential_energy_equals_the_plain_sum_bit_for_bit() {
        let mixed = ChainBuilder::new()
            .grains(7, 1.0, hertz())
            .grains(5, 2.0, ContactLaw::new(1.0, 5657.0))
            .grains(6, 0.5, ContactLaw::new(2.0, 300.0))
            .grains(5, 0.5, ContactLaw::new(2.5, 300.0))
            .grains(6, 1.0, ContactLaw::linear_spring(3.0))
            .left(End::Wall(hertz()))
            .right(End::Wall(ContactLaw::new(1.0, 5657.0)))
            .build()
            .unwrap();
        let pre = hertz().with_precompression(0.01);
        let precompressed = ChainBuilder::new()
            .grains(12, 1.0, pre)
            .left(End::Wall(pre))
            .right(End::Wall(pre))
            .build()
            .unwrap();
        for c in [mixed, precompressed] {
            check_potential_sums(&c);
        }
    }

    fn check_potential_sums(c: &Chain) {
        let n = c.len();
        let u: Vec<f64> = (0..n)
            .map(|i| 0.02 * ((i * 7919 % 61) as f64 / 61.0 - 0.5))
            .collect();
        for k0 in 0..=n {
            for k1 in k0..=n {
                let mut plain = 0.0;
                for k in k0..=k1 {
                    plain += c.contact_energy(&u, k);
                }
                let fast = c.potential_energy(&u, k0, k1);
                assert_eq!(plain.to_bits(), fast.to_bits(), "contacts {k0}..={k1}");
            }
        }
    }

    #[test]
    fn segments_follow_sections_and_interface_rule() {
        let lin = ContactLaw::new(1.0, 5657.0);
        let c = ChainBuilder::new()
            .grains(3, 1.0, hertz())
            .grains(2, 2.0, lin)
            .grains(3, 1.0, hertz())
            .build()
            .unwrap();
        assert_eq!(c.len(), 8);
        // contacts 1..8: 1,2 hertz (inside s1); 3 interface -> linear (min rule); 4 linear;
        // 5 interface -> linear; 6,7 hertz.
        let laws: Vec<f64> = (1..8).map(|k| c.contact_law(k).unwrap().p).collect();
        assert_eq!(laws, vec![1.5, 1.5, 1.0, 1.0, 1.0, 1.5, 1.5]);
        assert!(c.contact_law(0).is_none() && c.contact_law(8).is_none());
        assert_eq!(c.segments.len(), 3);
        let c = ChainBuilder::new()
            .grains(3, 1.0, hertz())
            .grains(2, 2.0, lin)
            .interface(InterfaceRule::MaxExponent)
            .build()
            .unwrap();
        assert_eq!(c.contact_law(3).unwrap().p, 1.5);
    }

    #[test]
    fn striker_numbering() {
        let s = Striker {
            end: StrikerEnd::Right,
            mass: 100.0,
            speed: 10.0,
            law: None,
        };
        let c = ChainBuilder::new()
            .grains(5, 1.0, hertz())
            .striker(s)
            .build()
            .unwrap();
        assert_eq!(c.len(), 6);
        assert_eq!(c.grain_number(0), 1);
        assert_eq!(c.grain_number(5), 6);
        assert_eq!(c.striker(), Some((5, -10.0)));
        let s = Striker {
            end: StrikerEnd::Left,
            ..s
        };
        let c = ChainBuilder::new()
            .grains(5, 1.0, hertz())
            .striker(s)
            .build()
            .unwrap();
        assert_eq!(c.grain_number(0), 0);
        assert_eq!(c.index_of(1), Some(1));
        assert_eq!(c.striker(), Some((0, 10.0)));
    }

    #[test]
    fn bad_input_is_an_error() {
        assert_eq!(ChainBuilder::new().build().unwrap_err(), ChainError::Empty);
        assert!(matches!(
            ChainBuilder::new().grains(2, -1.0, hertz()).build(),
            Err(ChainError::SectionMass { .. })
        ));
        assert!(matches!(
            ChainBuilder::new().grains(0, 1.0, hertz()).build(),
            Err(ChainError::SectionCount { .. })
        ));
        let pre = hertz().with_precompression(0.1);
        assert_eq!(
            ChainBuilder::new().grains(3, 1.0, pre).build().unwrap_err(),
            ChainError::PrecompressionWithoutWalls
        );
        let unbalanced = ChainBuilder::new()
            .grains(3, 1.0, pre)
            .left(End::Wall(pre))
            .right(End::Wall(hertz().with_precompression(0.2)))
            .build();
        assert!(matches!(
            unbalanced,
            Err(ChainError::PrecompressionUnbalanced { grain: 3, .. })
        ));
        let ok = ChainBuilder::new()
            .grains(3, 1.0, pre)
            .left(End::Wall(pre))
            .right(End::Wall(pre))
            .build()
            .unwrap();
        assert!(ok.static_imbalance().is_none());
        let s = Striker {
            end: StrikerEnd::Left,
            mass: 1.0,
            speed: 1.0,
            law: None,
        };
        assert_eq!(
            ChainBuilder::new()
                .grains(3, 1.0, hertz())
                .left(End::Wall(hertz()))
                .striker(s)
                .build()
                .unwrap_err(),
            ChainError::StrikerAtWall("left")
        );
    }

    #[test]
    fn sections_by_name() {
        let wall = ContactLaw::new(1.0, 5657.0);
        let c = ChainBuilder::new()
            .section(Section::new("outer", 4, 10.0, hertz()))
            .section(Section::new("wall-left", 2, 2.0, wall))
            .section(Section::new("inside", 3, 0.1, hertz()))
            .section(Section::new("wall-right", 2, 2.0, wall))
            .striker(Striker {
                end: StrikerEnd::Left,
                mass: 1.0,
                speed: 1.0,
                law: None,
            })
            .build()
            .unwrap();
        // The left striker is internal grain 0, so "outer" starts at 1.
        assert_eq!(c.grains_of("outer").unwrap(), 1..=4);
        assert_eq!(c.grains_of("inside").unwrap(), 7..=9);
        assert_eq!(c.grains_between("wall-left", "wall-right").unwrap(), 5..=11);
        assert_eq!(c.section("inside").unwrap().mass, 0.1);
        assert!(c.section("striker").is_none());
        assert_eq!(
            c.grains_of("container").unwrap_err(),
            ChainError::UnknownSection {
                name: "container".into(),
                known: "outer, wall-left, inside, wall-right".into()
            }
        );
        assert!(matches!(
            c.grains_between("wall-right", "wall-left"),
            Err(ChainError::SectionsReversed { .. })
        ));
        let twice = ChainBuilder::new()
            .section(Section::new("a", 2, 1.0, hertz()))
            .section(Section::new("b", 2, 1.0, hertz()))
            .section(Section::new("a", 2, 1.0, hertz()))
            .build();
        assert_eq!(
            twice.unwrap_err(),
            ChainError::DuplicateSection {
                index: 2,
                name: "a".into()
            }
        );
    }
}
