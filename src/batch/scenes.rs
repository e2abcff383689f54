//! Loading the figure scenes and deriving their variants.
//!
//! The scene files in `scenes/` are the source of truth for every layout. `reproduce` changes
//! only what a figure needs, each change a named transformation of the parsed file
//! ([`SceneFile`]) so that a variant of a container follows whatever layout its file holds:
//! the run length, the step size (step-size check), the interface rule and one- or two-sided
//! walls (the open choices of containers.md), the outer-chain lengths, and a tiny change of the
//! striker's speed (the chaos twin). Each variant is checked again by [`Scene::from_file`].
//!
//! The container files share a contract, stated in their comments: sections named `outer-left`
//! and `beyond-striker` (the long outer chains) and `outer-right`, a region named `container`,
//! and the striker given either as `[striker]` or as an `[[initial]]` velocity.

use crate::error::Error;
use grainchain_engine::file::{RegionFile, SceneFile, SectionFile};
use grainchain_engine::InterfaceRule;
use grainchain_engine::Scene;
use grainchain_engine::SceneError;
use std::path::{Path, PathBuf};

/// Relative change of the striker's speed in the chaos twin (and between ensemble members):
/// far below any integrator error, so whatever it changes no step size can pin down.
pub const TWIN_EPS: f64 = 1e-12;

/// A scene file's text, parsed afresh for every variant.
#[derive(Clone, Debug)]
pub struct SceneSource {
    /// The file's path, named in error messages and by the built scenes.
    pub path: PathBuf,
    text: String,
}

impl SceneSource {
    /// Read the scene file at `path` and check that it builds as it stands, so that a bad file
    /// fails before anything runs.
    pub fn load(path: impl AsRef<Path>) -> Result<Self, Error> {
        let path = path.as_ref().to_path_buf();
        let text = std::fs::read_to_string(&path).map_err(|source| {
            Error::Scene(SceneError::Read {
                file: path.clone(),
                source,
            })
        })?;
        let s = SceneSource { path, text };
        s.scene(|_| Ok(()))?; // check it once, so a bad file fails before anything runs
        Ok(s)
    }

    /// The parsed file, its own outer medium (`chain.outer`) applied, so every edit sees the
    /// sections the scene will have.
    pub fn file(&self) -> Result<SceneFile, Error> {
        let mut f = grainchain_engine::file::parse_file(&self.text, &self.path)?;
        if let Some(m) = f.chain.outer.take() {
            grainchain_engine::file::apply_outer(&mut f, m)
                .map_err(|e| self.invalid("chain.outer", e))?;
            // As the scene check does (`Scene::from_file`), which sees the file after this.
            if let Some(e) = grainchain_engine::file::outer_method_problem(&f, m) {
                return Err(self.invalid("chain.outer", e));
            }
        }
        Ok(f)
    }

    /// The scene's own outer medium (`chain.outer`), if it gives one other than `long`: the
    /// outer chains are then the file's choice, which a sweep's `outer_chains`, `free_ends`
    /// or `outer` would otherwise silently replace.
    pub fn own_outer(&self) -> Option<OuterMedium> {
        let f = grainchain_engine::file::parse_file(&self.text, &self.path).ok()?;
        f.chain.outer.filter(|m| m.has_ends())
    }

    /// The scene after `change`, checked.
    pub fn scene(
        &self,
        change: impl FnOnce(&mut SceneFile) -> Result<(), Error>,
    ) -> Result<Scene, Error> {
        let mut f = self.file()?;
        change(&mut f)?;
        Ok(Scene::from_file(f, &self.path)?)
    }

    fn invalid(&self, key: &str, message: impl Into<String>) -> Error {
        Error::Scene(SceneError::Invalid {
            file: self.path.clone(),
            key: key.into(),
            message: message.into(),
        })
    }

    /// Error for a missing section or region the figure needs.
    pub fn missing(&self, what: &str) -> Error {
        self.invalid(
            what,
            format!("`grainchain reproduce` needs {what} in this scene (see scenes/containers/)"),
        )
    }
}

/// Run for `n` output intervals.
pub fn set_snapshots(f: &mut SceneFile, n: u64) {
    f.run.duration = n as f64 * f.run.output_interval;
}

/// Make the step `factor` times smaller: the fixed step of fixed-step methods; for the adaptive
/// method both tolerances by `factor^5` (its error per step scales as h^5, so its steps shrink
/// by about `factor`).
pub fn refine_step(f: &mut SceneFile, factor: f64) {
    let i = f
        .integrator
        .get_or_insert(grainchain_engine::file::IntegratorFile {
            method: None,
            dt: None,
            rtol: None,
            atol: None,
            skip_untouched: None,
            max_energy_error: None,
            sleep: None,
            multirate: None,
        });
    let defaults = grainchain_engine::IntegrationParams::default();
    let method = i.method.unwrap_or(defaults.method);
    if method.is_adaptive() {
        i.rtol = Some(i.rtol.unwrap_or(defaults.rtol) / factor.powi(5));
        i.atol = Some(i.atol.unwrap_or(defaults.atol) / factor.powi(5));
        i.dt = Some(i.dt.unwrap_or(defaults.dt) / factor);
    } else {
        i.dt = Some(i.dt.unwrap_or(defaults.dt) / factor);
    }
}

/// Use `rule` at interfaces between sections of different exponents.
pub fn set_interface(f: &mut SceneFile, rule: InterfaceRule) {
    f.chain.interface = Some(rule);
}

/// Make every linear (p = 1) section two-sided (`tension = true`).
pub fn two_sided_walls(f: &mut SceneFile) -> usize {
    let mut k = 0;
    for s in f.chain.sections.iter_mut() {
        if s.law.p == 1.0 {
            s.law.tension = Some(true);
            k += 1;
        }
    }
    k
}

/// Multiply the striker's speed by `1 + eps` (the `[striker]`, or every `[[initial]]` velocity).
pub fn perturb_striker(f: &mut SceneFile, eps: f64) {
    if let Some(s) = f.striker.as_mut() {
        s.speed *= 1.0 + eps;
    }
    for g in f.initial.iter_mut() {
        if let Some(v) = g.velocity.as_mut() {
            *v *= 1.0 + eps;
        }
    }
}

/// The Hertz time scale of an impact at speed `v` relative to one at `v0`: `(v0 / v)^(1/5)`
/// (a chain of Hertz contacts is the same chain at speed `32 v`, time `t / 2`, overlap
/// `16 delta`). Exact (a power of two) where `v0 / v` is a power of 32.
pub fn hertz_time_scale(v0: f64, v: f64) -> f64 {
    let r = v0 / v;
    let e = r.log2();
    if e.fract() == 0.0 && (e as i64) % 5 == 0 && r == 2f64.powi(e as i32) {
        2f64.powi(e as i32 / 5)
    } else {
        r.powf(0.2)
    }
}

/// The scene's striker speed (`[striker]`, or the first `[[initial]]` velocity), unsigned: what
/// [`set_striker_speed`] scales from.
pub fn striker_speed(f: &SceneFile) -> Option<f64> {
    f.striker
        .as_ref()
        .map(|s| s.speed.abs())
        .or_else(|| f.initial.iter().find_map(|g| g.velocity.map(f64::abs)))
}

/// Strike at speed `v` (program units) instead of the scene's, in the Hertz time scale of the
/// impact: the output interval and run length are multiplied by `s = (v0 / v)^(1/5)`
/// ([`hertz_time_scale`], `v0` the scene's striker speed), so the snapshots of a chain of Hertz
/// contacts fall at the same scaled times at every speed; the step by `min(s, 1)` (a faster
/// impact needs a shorter step; a slower one keeps the scene's, which the linear walls' fixed
/// frequency needs). For container (e), all Hertz, a speed `32^k v0` with `k >= 0` is then
/// the same run scaled exactly (energies times `1024^k`, bit for bit).
pub fn set_striker_speed(src: &SceneSource, f: &mut SceneFile, v: f64) -> Result<(), Error> {
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
    let v0 =
        v0.ok_or_else(|| src.missing("a striker (`[striker]` or an `[[initial]]` velocity)"))?;
    let s = hertz_time_scale(v0, v);
    f.run.output_interval *= s;
    f.run.duration *= s;
    let interval = f.run.output_interval;
    if let Some(i) = f.integrator.as_mut() {
        let ratio = i.multirate.as_ref().map_or(1, |m| m.ratio.max(1));
        if let Some(dt) = i.dt.as_mut() {
            if s <= 1.0 {
                *dt *= s;
            } else {
                // The scene's step or shorter, a whole number of multirate slow steps per output.
                let slow = (interval / (*dt * ratio as f64)).ceil();
                *dt = interval / (slow * ratio as f64);
            }
        }
    }
    Ok(())
}

fn section_index(src: &SceneSource, f: &SceneFile, name: &str) -> Result<usize, Error> {
    f.chain
        .sections
        .iter()
        .position(|s| s.name.as_deref() == Some(name))
        .ok_or_else(|| src.missing(&format!("a section named `{name}`")))
}

/// Give section `outer-left` `count` grains, shifting every grain number to its right.
pub fn set_outer_left(src: &SceneSource, f: &mut SceneFile, count: u64) -> Result<(), Error> {
    let k = section_index(src, f, "outer-left")?;
    if k != 0 {
        return Err(src.invalid("chain.sections", "`outer-left` must be the first section"));
    }
    // Saturating: a count past i64 (a sweep's `outer_chains` is bounded far below) cannot wrap.
    let shift = i64::try_from(count)
        .unwrap_or(i64::MAX)
        .saturating_sub(i64::try_from(f.chain.sections[0].count).unwrap_or(i64::MAX));
    f.chain.sections[0].count = count;
    grainchain_engine::file::shift_grains(f, shift);
    Ok(())
}

/// Give section `beyond-striker` `count` grains, or remove it (`0`: the striker is then the last
/// grain, a free striker at the end of the chain as in Fig. 3).
pub fn set_beyond_striker(src: &SceneSource, f: &mut SceneFile, count: u64) -> Result<(), Error> {
    let k = section_index(src, f, "beyond-striker")?;
    if k + 1 != f.chain.sections.len() {
        return Err(src.invalid(
            "chain.sections",
            "`beyond-striker` must be the last section",
        ));
    }
    if count == 0 {
        f.chain.sections.pop();
    } else {
        f.chain.sections[k].count = count;
    }
    Ok(())
}

/// The number of grains of a section.
pub fn section_count(src: &SceneSource, f: &SceneFile, name: &str) -> Result<u64, Error> {
    Ok(f.chain.sections[section_index(src, f, name)?].count)
}

/// Give section `name` the mass of section `like` (Fig. 1's control run without the interface).
pub fn copy_mass(
    src: &SceneSource,
    f: &mut SceneFile,
    name: &str,
    like: &str,
) -> Result<(), Error> {
    let from = section_index(src, f, like)?;
    let to = section_index(src, f, name)?;
    let SectionFile { mass, law, .. } = &f.chain.sections[from];
    let (mass, law) = (*mass, *law);
    f.chain.sections[to].mass = mass;
    f.chain.sections[to].law = law;
    Ok(())
}

pub use grainchain_engine::file::{OuterMedium, MIN_OUTER_DISTANCE as MIN_DISTANCE};

/// Surround the container with `medium` (the scene key `chain.outer`, applied now so that
/// every later edit sees the new sections: [`grainchain_engine::file::apply_outer`]), and integrate a
/// damped medium with blanes-moan4 at the scene's dt (multirate applies no damping). A scene
/// that gives its own outer medium (other than `long`) is refused: the two would not add up
/// (the second would cut the first's layers), and which one the user meant is theirs to say.
/// Errors name the scene file; a sweep puts them under its own key.
pub fn set_outer_medium(
    src: &SceneSource,
    f: &mut SceneFile,
    medium: OuterMedium,
) -> Result<(), Error> {
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
    grainchain_engine::file::apply_outer(f, medium).map_err(|m| src.invalid("chain.outer", m))?;
    if medium.damps() {
        let i = f.integrator.get_or_insert_with(Default::default);
        i.method = Some(grainchain_engine::Method::BlanesMoan4);
        i.multirate = None;
    }
    Ok(())
}

/// A container scene file and its key (`a` for `a-standard.toml`).
#[derive(Clone, Debug)]
pub struct ContainerSource {
    /// The file name up to the first `-` (`a` for `a-standard.toml`).
    pub key: String,
    /// The rest of the file name, dashes as spaces (`standard`), in the figures' legends.
    pub label: String,
    /// The scene file, checked once when loaded.
    pub source: SceneSource,
}

/// Every `*.toml` in `dir`, sorted by file name; the key is the file name up to the first `-`.
pub fn container_sources(dir: &Path) -> Result<Vec<ContainerSource>, Error> {
    let bad = |source: std::io::Error| {
        Error::Scene(grainchain_engine::SceneError::Read {
            file: dir.to_path_buf(),
            source,
        })
    };
    let rd = std::fs::read_dir(dir).map_err(bad)?;
    let mut paths: Vec<PathBuf> = rd
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    paths.sort();
    let mut out = Vec::new();
    for p in paths {
        let stem = p
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let (key, label) = match stem.split_once('-') {
            Some((k, l)) => (k.to_string(), l.replace('-', " ")),
            None => (stem.clone(), stem.clone()),
        };
        out.push(ContainerSource {
            key,
            label,
            source: SceneSource::load(&p)?,
        });
    }
    if out.is_empty() {
        return Err(bad(std::io::Error::new(
            std::io::ErrorKind::NotFound,
            "no container scenes (*.toml)",
        )));
    }
    if !out.iter().any(|c| c.key == "a") {
        return Err(bad(std::io::Error::new(
            std::io::ErrorKind::NotFound,
            "the reference container `a-*.toml` is missing (Fig. 5 rescales time relative to it)",
        )));
    }
    Ok(out)
}

/// First and last grain numbers of the scene's region `container` (the container contract).
pub fn container_region(src: &SceneSource, f: &SceneFile) -> Result<(i64, i64), Error> {
    f.regions
        .iter()
        .find(|r| r.name == "container")
        .map(|r| (r.first, r.last))
        .ok_or_else(|| src.missing("a region named `container`"))
}

/// Integrate a container scene with multiple time stepping: the fast region runs from the
/// container's first grain to the striker (the path of the strong incident wave, and the
/// container), widened by `margin` grains on each side (region `fast`, added to the scene or
/// replacing the scene's own); the
/// outer chains beyond it step at `ratio` times the scene's dt.
pub fn use_multirate(
    src: &SceneSource,
    f: &mut SceneFile,
    ratio: u64,
    margin: u64,
) -> Result<(), Error> {
    let (c_first, c_last) = container_region(src, f)?;
    let mut first = 1i64;
    let mut striker = None;
    for s in &f.chain.sections {
        if s.name.as_deref() == Some("striker") {
            striker = Some(first + s.count as i64 - 1);
        }
        first += s.count as i64;
    }
    let striker = striker.ok_or_else(|| src.missing("a section named `striker`"))?;
    let region = RegionFile {
        name: "fast".into(),
        first: c_first.min(striker),
        last: c_last.max(striker),
    };
    // The container scenes declare this region themselves (they run multirate by default).
    f.regions.retain(|r| r.name != "fast");
    f.regions.push(region);
    let i = f.integrator.get_or_insert_with(Default::default);
    i.method = Some(grainchain_engine::Method::Multirate);
    i.multirate = Some(grainchain_engine::file::MultirateFile {
        ratio,
        fast: "fast".into(),
        margin: Some(margin),
    });
    Ok(())
}

/// Damp every contact of the scene's sections with `model` (`contact_damping`), each section's
/// coefficient chosen so that two of its grains colliding head-on part with restitution `e`
/// ([`grainchain_engine::problems::TwoGrainCollision::damping_for_restitution`]; an interface contact takes
/// the damping of the law the interface rule picks, so its restitution differs where the masses
/// do). The multirate method cannot apply contact damping: the scene is integrated by
/// blanes-moan4 at its own dt instead.
pub fn set_contact_damping(
    src: &SceneSource,
    f: &mut SceneFile,
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
    for (i, s) in f.chain.sections.iter_mut().enumerate() {
        let key = (
            s.law.p.to_bits(),
            s.law.eta.to_bits(),
            s.mass.to_bits(),
            model,
            e.to_bits(),
        );
        let known = memo.lock().ok().and_then(|m| m.get(&key).copied());
        let c = match known {
            Some(c) => c,
            None => {
                let c = grainchain_engine::problems::TwoGrainCollision {
                    p: s.law.p,
                    eta: s.law.eta,
                    striker_mass: s.mass,
                    grain_mass: s.mass,
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
    let i = f.integrator.get_or_insert_with(Default::default);
    i.method = Some(grainchain_engine::Method::BlanesMoan4);
    i.multirate = None;
    Ok(())
}

/// Add a region per section lying wholly outside the `container` region (named after the
/// section) and return their names.
pub fn budget_regions(src: &SceneSource, f: &mut SceneFile) -> Result<Vec<String>, Error> {
    if f.striker.is_some() {
        return Err(src.missing("the striker as an `[[initial]]` velocity (not `[striker]`)"));
    }
    let (cf, cl) = container_region(src, f)?;
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

#[cfg(test)]
mod tests {
    use super::*;

    fn src() -> SceneSource {
        SceneSource::load(
            Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/containers/a-standard.toml"),
        )
        .unwrap()
    }

    #[test]
    fn outer_left_shift_moves_regions_and_striker() {
        let s = src();
        let base = s.scene(|_| Ok(())).unwrap();
        let f0 = s.file().unwrap();
        let n0 = section_count(&s, &f0, "outer-left").unwrap();
        let sc = s.scene(|f| set_outer_left(&s, f, n0 - 1000)).unwrap();
        assert_eq!(sc.grains + 1000, base.grains);
        let r0 = base.regions.iter().find(|r| r.name == "container").unwrap();
        let r1 = sc.regions.iter().find(|r| r.name == "container").unwrap();
        assert_eq!(r0.first - 1000, r1.first);
        assert_eq!(r0.last - r0.first, r1.last - r1.first);
    }

    #[test]
    fn missing_section_is_a_clear_error() {
        let s = SceneSource::load(
            Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/fig1-heavy-to-light.toml"),
        )
        .unwrap();
        let e = s.scene(|f| set_beyond_striker(&s, f, 0)).unwrap_err();
        let msg = e.to_string();
        assert!(
            msg.contains("fig1-heavy-to-light.toml") && msg.contains("beyond-striker"),
            "{msg}"
        );
    }
}
