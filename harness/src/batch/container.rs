//! A container scene as a typed value: the parsed scene file of a container (the contract of
//! `scenes/containers/`, stated in their comments) with its parts named in the type, and every
//! variant a study or `reproduce` makes of it as a method.
//!
//! **The parts** ([`Part`] and the methods reading them): the outer chains (section
//! `outer-left`, first, and `beyond-striker`, last; `outer-right` between the container and the
//! striker), the container (region `container`), the striker (section `striker`: its last
//! grain), the incident path (from the container to the striker) and the fast region of
//! multirate (the incident path and the container). A part is looked up when an edit needs it,
//! so a scene that lacks one fails only the edits that need it, naming what is missing.
//!
//! **The edits** change the parsed file ([`SceneFile`]), so that a variant follows whatever
//! layout the file holds; [`ContainerScene::build`] checks the result as the scene check does
//! ([`Scene::from_file`]). The integrator is set in one place, [`ContainerScene::integrator`],
//! from every dimension that decides it ([`Stepping::decide`]).

use super::scenes::{hertz_time_scale, OuterMedium, SceneSource};
use crate::error::Error;
use grainchain_engine::file::{RegionFile, SceneFile};
use grainchain_engine::Scene;

/// A named section of the container contract.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Part {
    /// `outer-left`: the outer chain on the left, the first section.
    OuterLeft,
    /// `outer-right`: the grains from the container to the striker (the incident path).
    OuterRight,
    /// `striker`: its last grain is the striker.
    Striker,
    /// `beyond-striker`: the outer chain beyond the striker, the last section.
    BeyondStriker,
}

impl Part {
    /// The section's name in the scene file.
    pub const fn name(self) -> &'static str {
        match self {
            Part::OuterLeft => "outer-left",
            Part::OuterRight => "outer-right",
            Part::Striker => "striker",
            Part::BeyondStriker => "beyond-striker",
        }
    }
}

/// How a job is integrated, decided from all its dimensions by [`Stepping::decide`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stepping {
    /// The scene's own `[integrator]`.
    Scene,
    /// Multiple time stepping: region `fast` widened by `margin` grains at the scene's dt, the
    /// rest at `ratio` times it.
    Multirate {
        /// Slow steps are this many fast steps (at least 1).
        ratio: u64,
        /// Grains added to region `fast` on each side.
        margin: u64,
    },
    /// blanes-moan4 at the scene's dt, one rate (it applies damping; multirate applies none).
    Damped,
}

impl Stepping {
    /// The integrator of a job, from its dimensions: `multirate` (the setting asked for, the
    /// container's own before the sweep's: the caller picks) and `damped` (a damped outer
    /// medium or contact damping). The precedence, first that applies:
    /// 1. damping: [`Stepping::Damped`], whatever multirate asks (the container's damping is
    ///    more specific than the sweep's multirate; a container's own multirate beside it is
    ///    refused by the sweep check);
    /// 2. multirate asked for: [`Stepping::Multirate`];
    /// 3. the scene's own integrator.
    ///
    /// The striker's speed never changes the method; it rescales the step of whichever is
    /// chosen ([`ContainerScene::integrator`]).
    pub fn decide(multirate: Option<(u64, u64)>, damped: bool) -> Stepping {
        match (damped, multirate) {
            (true, _) => Stepping::Damped,
            (false, Some((ratio, margin))) => Stepping::Multirate { ratio, margin },
            (false, None) => Stepping::Scene,
        }
    }
}

/// A variant of a container scene in the making (see the module docs).
#[derive(Clone, Debug)]
pub struct ContainerScene<'a> {
    src: &'a SceneSource,
    file: SceneFile,
}

impl SceneSource {
    /// A container variant of the file to edit ([`ContainerScene`]).
    pub fn container(&self) -> ContainerScene<'_> {
        ContainerScene::new(self)
    }
}

impl<'a> ContainerScene<'a> {
    /// The scene file of `src` as parsed, to edit.
    pub fn new(src: &'a SceneSource) -> Self {
        ContainerScene {
            src,
            file: src.file().clone(),
        }
    }

    /// The scene file it is made from (named in errors).
    pub fn source(&self) -> &'a SceneSource {
        self.src
    }

    /// The file as edited so far.
    pub fn file(&self) -> &SceneFile {
        &self.file
    }

    /// The file, for the edits any scene takes (`batch::scenes::set_snapshots`, ...).
    pub fn file_mut(&mut self) -> &mut SceneFile {
        &mut self.file
    }

    /// The scene, checked ([`Scene::from_file`]).
    pub fn build(self) -> Result<Scene, Error> {
        Ok(Scene::from_file(self.file, &self.src.path)?)
    }

    // ---- the parts ----

    /// The index of `part`'s section, or the error that the scene lacks it.
    pub fn section(&self, part: Part) -> Result<usize, Error> {
        let name = part.name();
        self.file
            .chain
            .sections
            .iter()
            .position(|s| s.name.as_deref() == Some(name))
            .ok_or_else(|| self.src.missing(&format!("a section named `{name}`")))
    }

    /// The number of grains of `part`.
    pub fn count(&self, part: Part) -> Result<u64, Error> {
        Ok(self.file.chain.sections[self.section(part)?].count)
    }

    /// First and last grain numbers of the container (region `container`).
    pub fn container(&self) -> Result<(i64, i64), Error> {
        self.file
            .regions
            .iter()
            .find(|r| r.name == "container")
            .map(|r| (r.first, r.last))
            .ok_or_else(|| self.src.missing("a region named `container`"))
    }

    /// The grain number of the striker (the last grain of section `striker`).
    pub fn striker(&self) -> Result<i64, Error> {
        let mut first = 1i64;
        let mut striker = None;
        for s in &self.file.chain.sections {
            if s.name.as_deref() == Some(Part::Striker.name()) {
                striker = Some(first + s.count as i64 - 1);
            }
            first += s.count as i64;
        }
        striker.ok_or_else(|| self.src.missing("a section named `striker`"))
    }

    /// The fast region of multirate: the container and the incident path to the striker,
    /// first and last grain numbers.
    pub fn fast_region(&self) -> Result<(i64, i64), Error> {
        let (c_first, c_last) = self.container()?;
        let striker = self.striker()?;
        Ok((c_first.min(striker), c_last.max(striker)))
    }

    /// The striker's speed (`[striker]`, or the first `[[initial]]` velocity), unsigned: what
    /// [`ContainerScene::striker_speed`] scales from.
    pub fn speed(&self) -> Option<f64> {
        let f = &self.file;
        f.striker
            .as_ref()
            .map(|s| s.speed.abs())
            .or_else(|| f.initial.iter().find_map(|g| g.velocity.map(f64::abs)))
    }

    // ---- the edits ----

    /// Give `outer-left` `count` grains, shifting every grain number to its right.
    pub fn outer_left(&mut self, count: u64) -> Result<(), Error> {
        let k = self.section(Part::OuterLeft)?;
        if k != 0 {
            return Err(self
                .src
                .invalid("chain.sections", "`outer-left` must be the first section"));
        }
        let f = &mut self.file;
        // Saturating: a count past i64 (a sweep's `outer_chains` is bounded far below) cannot
        // wrap.
        let shift = i64::try_from(count)
            .unwrap_or(i64::MAX)
            .saturating_sub(i64::try_from(f.chain.sections[0].count).unwrap_or(i64::MAX));
        f.chain.sections[0].count = count;
        grainchain_engine::file::shift_grains(f, shift);
        Ok(())
    }

    /// Give `beyond-striker` `count` grains, or remove it (`0`: the striker is then the last
    /// grain, a free striker at the end of the chain as in Fig. 3).
    pub fn beyond_striker(&mut self, count: u64) -> Result<(), Error> {
        let k = self.section(Part::BeyondStriker)?;
        let sections = &mut self.file.chain.sections;
        if k + 1 != sections.len() {
            return Err(self.src.invalid(
                "chain.sections",
                "`beyond-striker` must be the last section",
            ));
        }
        if count == 0 {
            sections.pop();
        } else {
            sections[k].count = count;
        }
        Ok(())
    }

    /// The outer chains: `left` grains in `outer-left`, `beyond` in `beyond-striker` (0: none).
    pub fn outer_chains(&mut self, left: u64, beyond: u64) -> Result<(), Error> {
        self.outer_left(left)?;
        self.beyond_striker(beyond)
    }

    /// Surround the container with `medium` (the scene key `chain.outer`, applied now so that
    /// every later edit sees the new sections: [`grainchain_engine::file::apply_outer`]). The integrator
    /// is not touched: a damped medium is one of the dimensions of [`Stepping::decide`]. A scene
    /// that gives its own outer medium (other than `long`) is refused: the two would not add up
    /// (the second would cut the first's layers), and which one the user meant is theirs to say.
    /// Errors name the scene file; a sweep puts them under its own key.
    pub fn outer_medium(&mut self, medium: OuterMedium) -> Result<(), Error> {
        let src = self.src;
        if let Some(own) = src.own_outer().filter(|_| medium.has_ends()) {
            return Err(src.invalid(
                "chain.outer",
                format!(
                    "the scene gives its own outer medium ({}); a second one ({}) cannot apply too",
                    own.label(),
                    medium.label()
                ),
            ));
        }
        grainchain_engine::file::apply_outer(&mut self.file, medium)
            .map_err(|m| src.invalid("chain.outer", m))?;
        Ok(())
    }

    /// Mark the fast region of multirate ([`ContainerScene::fast_region`]) as region `fast`,
    /// added to the scene or replacing the scene's own (the container scenes declare it: they
    /// run multirate by default).
    pub fn mark_fast_region(&mut self) -> Result<(), Error> {
        let (first, last) = self.fast_region()?;
        let f = &mut self.file;
        f.regions.retain(|r| r.name != "fast");
        f.regions.push(RegionFile {
            name: "fast".into(),
            first,
            last,
        });
        Ok(())
    }

    /// Damp every contact of the scene's sections with `model` (`contact_damping`), each
    /// section's coefficient chosen so that two of its grains colliding head-on part with
    /// restitution `e` ([`grainchain_engine::problems::TwoGrainCollision::damping_for_restitution`]; an
    /// interface contact takes the damping of the law the interface rule picks, so its
    /// restitution differs where the masses do). The integrator is not touched: damping is one
    /// of the dimensions of [`Stepping::decide`] (multirate cannot apply it).
    pub fn dissipation(
        &mut self,
        model: grainchain_engine::DampingModel,
        e: f64,
    ) -> Result<(), Error> {
        use std::collections::HashMap;
        use std::sync::{Mutex, OnceLock};
        // The bisection runs about 40 collisions: remembered per law, mass, model and e for the
        // process (every member of a container asks the same).
        type Key = (u64, u64, u64, grainchain_engine::DampingModel, u64);
        static MEMO: OnceLock<Mutex<HashMap<Key, f64>>> = OnceLock::new();
        let memo = MEMO.get_or_init(Default::default);
        let src = self.src;
        for (i, s) in self.file.chain.sections.iter_mut().enumerate() {
            // A program-unit section (an SI section, given by `material`, has none of the three;
            // the scene check refuses it in a container scene's study with its own message).
            let (Some(p), Some(eta), Some(mass)) = (s.law.p, s.law.eta, s.mass) else {
                return Err(src.invalid(
                    &format!("chain.sections[{i}].restitution"),
                    "a dissipation of the study needs program-unit sections (`mass`, `p`, `eta`)",
                ));
            };
            let key = (
                p.to_bits(),
                eta.to_bits(),
                mass.to_bits(),
                model,
                e.to_bits(),
            );
            let known = memo.lock().ok().and_then(|m| m.get(&key).copied());
            let c = match known {
                Some(c) => c,
                None => {
                    let c = grainchain_engine::problems::TwoGrainCollision {
                        p,
                        eta,
                        striker_mass: mass,
                        grain_mass: mass,
                        speed: 1.0,
                    }
                    .damping_for_restitution(model, e)
                    .map_err(|err| {
                        src.invalid(
                            &format!("chain.sections[{i}].contact_damping"),
                            err.to_string(),
                        )
                    })?;
                    if let Ok(mut m) = memo.lock() {
                        m.insert(key, c);
                    }
                    c
                }
            };
            s.law.contact_damping = Some(grainchain_engine::file::ContactDampingFile { model, c });
        }
        Ok(())
    }

    /// Strike at speed `v` (program units) instead of the scene's, in the Hertz time scale of
    /// the impact: the output interval and run length are multiplied by `s = (v0 / v)^(1/5)`
    /// ([`hertz_time_scale`], `v0` the scene's striker speed), so the snapshots of a chain of
    /// Hertz contacts fall at the same scaled times at every speed. Returns `s`, by which
    /// [`ContainerScene::integrator`] rescales the step: by `min(s, 1)` (a faster impact needs
    /// a shorter step; a slower one keeps the scene's, which the linear walls' fixed frequency
    /// needs). For container (e), all Hertz, a speed `32^k v0` with `k >= 0` is then the same
    /// run scaled exactly (energies times `1024^k`, bit for bit).
    pub fn striker_speed(&mut self, v: f64) -> Result<f64, Error> {
        let f = &mut self.file;
        let mut v0 = None;
        if let Some(s) = f.striker.as_mut() {
            v0 = Some(s.speed.abs());
            s.speed = v * s.speed.signum();
        }
        for g in f.initial.iter_mut() {
            if let Some(x) = g.velocity.as_mut() {
                v0.get_or_insert(x.abs());
                *x = v * x.signum();
            }
        }
        let v0 = v0.ok_or_else(|| {
            self.src
                .missing("a striker (`[striker]` or an `[[initial]]` velocity)")
        })?;
        let s = hertz_time_scale(v0, v);
        f.run.output_interval *= s;
        f.run.duration *= s;
        Ok(s)
    }

    /// Set the integrator of the job: the one place it is set. `stepping` as decided from the
    /// job's dimensions ([`Stepping::decide`]); then, when the striker's speed stretched the
    /// time scale by `time_scale` ([`ContainerScene::striker_speed`]), the step of the chosen
    /// method is fitted to the new output interval: shortened by `time_scale` when it is below
    /// 1, else the scene's step or shorter, a whole number of multirate slow steps per output.
    pub fn integrator(&mut self, stepping: Stepping, time_scale: Option<f64>) {
        let f = &mut self.file;
        match stepping {
            Stepping::Scene => {}
            Stepping::Multirate { ratio, margin } => {
                let i = f.integrator.get_or_insert_with(Default::default);
                i.method = Some(grainchain_engine::Method::Multirate);
                i.multirate = Some(grainchain_engine::file::MultirateFile {
                    ratio,
                    fast: "fast".into(),
                    margin: Some(margin),
                });
            }
            Stepping::Damped => {
                let i = f.integrator.get_or_insert_with(Default::default);
                i.method = Some(grainchain_engine::Method::BlanesMoan4);
                i.multirate = None;
            }
        }
        let Some(s) = time_scale else {
            return;
        };
        let interval = f.run.output_interval;
        if let Some(i) = f.integrator.as_mut() {
            let ratio = i.multirate.as_ref().map_or(1, |m| m.ratio.max(1));
            if let Some(dt) = i.dt.as_mut() {
                if s <= 1.0 {
                    *dt *= s;
                } else {
                    // The scene's step or shorter, a whole number of multirate slow steps per
                    // output.
                    let slow = (interval / (*dt * ratio as f64)).ceil();
                    *dt = interval / (slow * ratio as f64);
                }
            }
        }
    }

    /// Add a region per section lying wholly outside the container (named after the section)
    /// and return their names: the energy budget.
    pub fn budget_regions(&mut self) -> Result<Vec<String>, Error> {
        if self.file.striker.is_some() {
            return Err(self
                .src
                .missing("the striker as an `[[initial]]` velocity (not `[striker]`)"));
        }
        let (cf, cl) = self.container()?;
        let f = &mut self.file;
        let mut first = 1i64;
        let mut names = Vec::new();
        let mut add = Vec::new();
        for s in &f.chain.sections {
            let last = first + s.count as i64 - 1;
            if let Some(name) = &s.name {
                if (last < cf || first > cl) && !f.regions.iter().any(|r| &r.name == name) {
                    names.push(name.clone());
                    add.push(RegionFile {
                        name: name.clone(),
                        first,
                        last,
                    });
                }
            }
            first = last + 1;
        }
        f.regions.extend(add);
        Ok(names)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn src(file: &str) -> SceneSource {
        SceneSource::load(Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(file)).unwrap()
    }

    #[test]
    fn outer_left_shift_moves_regions_and_striker() {
        let s = src("scenes/containers/a-standard.toml");
        let base = s.checked().unwrap();
        let mut c = s.container();
        let n0 = c.count(Part::OuterLeft).unwrap();
        let striker0 = c.striker().unwrap();
        c.outer_left(n0 - 1000).unwrap();
        assert_eq!(c.striker().unwrap() + 1000, striker0);
        let sc = c.build().unwrap();
        assert_eq!(sc.grains() + 1000, base.grains());
        let r0 = base
            .regions()
            .iter()
            .find(|r| r.name == "container")
            .unwrap();
        let r1 = sc.regions().iter().find(|r| r.name == "container").unwrap();
        assert_eq!(r0.first - 1000, r1.first);
        assert_eq!(r0.last - r0.first, r1.last - r1.first);
    }

    #[test]
    fn missing_section_is_a_clear_error() {
        let s = src("scenes/fig1-heavy-to-light.toml");
        let e = s.container().beyond_striker(0).unwrap_err();
        let msg = e.to_string();
        assert!(
            msg.contains("fig1-heavy-to-light.toml") && msg.contains("beyond-striker"),
            "{msg}"
        );
    }

    #[test]
    fn damping_wins_over_multirate_and_speed_rescales_the_chosen_step() {
        assert_eq!(Stepping::decide(Some((8, 20)), true), Stepping::Damped);
        assert_eq!(
            Stepping::decide(Some((8, 20)), false),
            Stepping::Multirate {
                ratio: 8,
                margin: 20
            }
        );
        assert_eq!(Stepping::decide(None, false), Stepping::Scene);
        let s = src("scenes/containers/a-standard.toml");
        let dt0 = s.file().integrator.as_ref().and_then(|i| i.dt).unwrap();
        let mut c = s.container();
        // 32 times faster: the time scale halves, and so does the step, whatever the method.
        let scale = c.striker_speed(32.0 * c.speed().unwrap()).unwrap();
        assert_eq!(scale, 0.5);
        c.integrator(Stepping::Damped, Some(scale));
        let i = c.file().integrator.as_ref().unwrap();
        assert_eq!(i.method, Some(grainchain_engine::Method::BlanesMoan4));
        assert!(i.multirate.is_none());
        assert_eq!(i.dt, Some(dt0 * 0.5));
    }
}
