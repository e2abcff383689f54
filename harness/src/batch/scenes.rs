//! Loading the figure scenes and deriving their variants.
//!
//! The scene files in `scenes/` are the source of truth for every layout. A file is read and
//! parsed once ([`SceneSource`]); every variant edits a copy of the parse. The edits any scene
//! takes are here, each a named transformation of the parsed file ([`SceneFile`]): the run
//! length, the step size (step-size check), the interface rule and one- or two-sided walls (the
//! open choices of docs/containers.md), a section's mass, and a tiny change of the striker's speed
//! (the chaos twin). The edits of a container's parts (outer chains, outer medium, damping,
//! speed, multirate, the energy budget) are methods of `ContainerScene` (`container.rs`)
//! (`batch::container`). Each variant is checked again by [`Scene::from_file`].
//!
//! The container files share a contract, stated in their comments: sections named `outer-left`
//! and `beyond-striker` (the long outer chains) and `outer-right`, a region named `container`,
//! and the striker given either as `[striker]` or as an `[[initial]]` velocity.

use crate::error::Error;
pub(crate) use grainchain_engine::file::{OuterMedium, MIN_OUTER_DISTANCE as MIN_DISTANCE};
use grainchain_engine::file::{Parsed, SceneFile, SectionFile};
use grainchain_engine::InputError;
use grainchain_engine::InterfaceRule;
use grainchain_engine::Scene;
use std::path::{Path, PathBuf};

/// Relative change of the striker's speed in the chaos twin (and between ensemble members):
/// far below any integrator error, so whatever it changes no step size can pin down.
pub const TWIN_EPS: f64 = 1e-12;

/// A scene file, read and parsed once: the TOML value as parsed (what a study's digest
/// records), the typed file its variants are made from (its own outer medium, `chain.outer`,
/// applied so every edit sees the sections the scene will have), and with [`SceneSource::load`]
/// the scene as the file stands, checked and built.
#[derive(Clone, Debug)]
pub struct SceneSource {
    /// The file's path, named in error messages and by the built scenes.
    pub path: PathBuf,
    /// The file as parsed ([`grainchain_engine::file::Parsed::value`]).
    value: toml::Value,
    /// The typed file, its own outer medium applied.
    file: SceneFile,
    /// The file's own outer medium (`chain.outer`), when it has ends (not `long`).
    own: Option<OuterMedium>,
    /// The scene as the file stands, when [`SceneSource::load`] checked it.
    checked: Option<Scene>,
}

impl SceneSource {
    /// Read and parse the scene file at `path` once (no scene is built: a study checks the
    /// scenes it makes of it, `study::check_scenes`).
    pub fn read(path: impl AsRef<Path>) -> Result<Self, Error> {
        let path = path.as_ref().to_path_buf();
        let text = grainchain_engine::file::read_text(&path)?;
        // One parse of the text: the typed file and the value both come from its tree.
        let parsed = grainchain_engine::file::parse_toml::<SceneFile>(
            &text,
            &path,
            grainchain_engine::file::FileKind::Scene,
        )?;
        Self::from_parsed(path, parsed)
    }

    /// The scene file at `path` already read and parsed ([`SceneFiles`]).
    fn from_parsed(path: PathBuf, parsed: Parsed<SceneFile>) -> Result<Self, Error> {
        let (value, mut file) = (parsed.value, parsed.typed);
        let invalid = |message: String| {
            Error::Input(InputError::Invalid {
                file: path.clone(),
                key: "chain.outer".into(),
                message,
            })
        };
        let own = file.chain.outer.take();
        if let Some(m) = own {
            grainchain_engine::file::apply_outer(&mut file, m).map_err(invalid)?;
            // As the scene check does (`Scene::from_file`), which sees the file after this.
            if let Some(e) = grainchain_engine::file::outer_method_problem(&file, m) {
                return Err(invalid(e));
            }
        }
        Ok(SceneSource {
            path,
            value,
            file,
            own: own.filter(|m| m.has_ends()),
            checked: None,
        })
    }

    /// [`SceneSource::read`], and check that the file builds as it stands, so that a bad file
    /// fails before anything runs; the scene built is kept ([`SceneSource::checked`]).
    pub fn load(path: impl AsRef<Path>) -> Result<Self, Error> {
        Self::read(path)?.with_check()
    }

    /// The source with its scene checked and kept.
    fn with_check(mut self) -> Result<Self, Error> {
        self.checked = Some(self.scene(|_| Ok(()))?);
        Ok(self)
    }

    /// The scene as the file stands: the one [`SceneSource::load`] checked, else built now.
    pub fn checked(&self) -> Result<Scene, Error> {
        match &self.checked {
            Some(s) => Ok(s.clone()),
            None => self.scene(|_| Ok(())),
        }
    }

    /// The file as parsed, a TOML value: what a study's digest records of it.
    pub fn value(&self) -> &toml::Value {
        &self.value
    }

    /// The parsed file, its own outer medium (`chain.outer`) applied, so every edit sees the
    /// sections the scene will have.
    pub fn file(&self) -> &SceneFile {
        &self.file
    }

    /// The scene's own outer medium (`chain.outer`), if it gives one other than `long`: the
    /// outer chains are then the file's choice, which a sweep's `outer_chains`, `free_ends`
    /// or `outer` would otherwise silently replace.
    pub fn own_outer(&self) -> Option<OuterMedium> {
        self.own
    }

    /// The scene after `change`, checked.
    pub fn scene(
        &self,
        change: impl FnOnce(&mut SceneFile) -> Result<(), Error>,
    ) -> Result<Scene, Error> {
        let mut f = self.file.clone();
        change(&mut f)?;
        Ok(Scene::from_file(f, &self.path)?)
    }

    pub(crate) fn invalid(&self, key: &str, message: impl Into<String>) -> Error {
        Error::Input(InputError::Invalid {
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
    // The outputs listed after the new end would record nothing, and the check refuses them.
    if let Some(o) = f.output.as_mut() {
        if let Some(s) = o.snapshots.as_mut() {
            s.at.retain(|&k| k <= n);
        }
        if let Some(p) = o.pulses.as_mut() {
            p.at.retain(|&k| k <= n);
        }
    }
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
            events: None,
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
        if s.law.p == Some(1.0) {
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

/// Give section `name` the mass of section `like` (Fig. 1's control run without the interface).
pub fn copy_mass(
    src: &SceneSource,
    f: &mut SceneFile,
    name: &str,
    like: &str,
) -> Result<(), Error> {
    let index = |name: &str| {
        f.chain
            .sections
            .iter()
            .position(|s| s.name.as_deref() == Some(name))
            .ok_or_else(|| src.missing(&format!("a section named `{name}`")))
    };
    let (from, to) = (index(like)?, index(name)?);
    let SectionFile { mass, law, .. } = &f.chain.sections[from];
    let (mass, law) = (*mass, law.clone());
    f.chain.sections[to].mass = mass;
    f.chain.sections[to].law = law;
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

/// Scene files a command has read and parsed already (`reproduce` digests its whole scene
/// folder before it runs, [`SceneFiles::read_folder`]): loading one of them takes it from here
/// instead of reading and parsing the file again (a file is read once). Empty: every load reads
/// its file.
#[derive(Clone, Debug, Default)]
pub struct SceneFiles(std::sync::Arc<std::collections::BTreeMap<PathBuf, Parsed<SceneFile>>>);

impl SceneFiles {
    /// Read every `*.toml` of `dirs` once, sorted by path: each file's digest as parsed
    /// (`report::outdir::value_digest`: comments and spelling do not count), and the files that
    /// parse as scenes kept for [`SceneFiles::load`]. A file that is TOML but not a scene counts
    /// in the digest (its error is reported if it is loaded); one that is not TOML is an error.
    /// `unreadable` says why a folder cannot be listed.
    pub fn read_folder(
        dirs: &[PathBuf],
        unreadable: impl Fn(&Path, std::io::Error) -> Error,
    ) -> Result<(Vec<(PathBuf, String)>, SceneFiles), Error> {
        let mut files = Vec::new();
        for dir in dirs {
            let rd = std::fs::read_dir(dir).map_err(|e| unreadable(dir, e))?;
            for e in rd.flatten() {
                let p = e.path();
                if p.extension().is_some_and(|x| x == "toml") {
                    files.push(p);
                }
            }
        }
        files.sort();
        let mut digests = Vec::new();
        let mut parsed = std::collections::BTreeMap::new();
        for f in files {
            let text = grainchain_engine::file::read_text(&f)?;
            let kind = grainchain_engine::file::FileKind::Scene;
            let digest = match grainchain_engine::file::parse_toml::<SceneFile>(&text, &f, kind) {
                Ok(p) => {
                    let d = crate::report::outdir::value_digest(&p.value)?;
                    parsed.insert(f.clone(), p);
                    d
                }
                // Not a scene: its values only (a second parse, on this path alone).
                Err(_) => crate::report::outdir::value_digest(
                    &grainchain_engine::file::parse_toml::<toml::Value>(&text, &f, kind)?.value,
                )?,
            };
            digests.push((f, digest));
        }
        Ok((digests, SceneFiles(std::sync::Arc::new(parsed))))
    }

    /// [`SceneSource::load`] of the file at `path`: from the files read already if it is one of
    /// them, else read now.
    pub fn load(&self, path: &Path) -> Result<SceneSource, Error> {
        match self.0.get(path) {
            Some(p) => SceneSource::from_parsed(path.to_path_buf(), p.clone())?.with_check(),
            None => SceneSource::load(path),
        }
    }
}

/// Every `*.toml` in `dir`, sorted by file name; the key is the file name up to the first `-`.
/// Files in `read` are not read again.
pub fn container_sources(dir: &Path, read: &SceneFiles) -> Result<Vec<ContainerSource>, Error> {
    let bad = |source: std::io::Error| {
        Error::Input(grainchain_engine::InputError::Read {
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
            source: read.load(&p)?,
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The one parse gives what the scene parser and the digest's reader give on their own:
    /// the typed file of `scene::parse_file` (its own outer medium applied as the scene check
    /// applies it) and the TOML value of `report::outdir::read_toml`, for every shipped scene.
    #[test]
    fn one_parse_gives_the_typed_file_and_the_digests_value() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let mut files = Vec::new();
        for dir in ["scenes", "scenes/containers"] {
            for e in std::fs::read_dir(root.join(dir)).unwrap() {
                let p = e.unwrap().path();
                if p.extension().is_some_and(|x| x == "toml") {
                    files.push(p);
                }
            }
        }
        assert!(files.len() >= 10, "{files:?}");
        for p in files {
            let s = SceneSource::read(&p).unwrap();
            let text = std::fs::read_to_string(&p).unwrap();
            let mut f = grainchain_engine::file::parse_file(&text, &p).unwrap();
            if let Some(m) = f.chain.outer.take() {
                grainchain_engine::file::apply_outer(&mut f, m).unwrap();
            }
            assert_eq!(
                format!("{:?}", s.file()),
                format!("{f:?}"),
                "{}",
                p.display()
            );
            assert_eq!(
                s.value(),
                &crate::report::outdir::read_toml(&p).unwrap(),
                "{}",
                p.display()
            );
        }
    }

    /// A file the typed parse refuses is reported as the scene parser reports it.
    #[test]
    fn a_bad_file_is_reported_as_the_scene_parser_reports_it() {
        let dir = std::env::temp_dir().join(format!("grainchain-scenes-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("bad.toml");
        let text = "[chain]\nsections = []\nnot_a_key = 1\n";
        std::fs::write(&p, text).unwrap();
        let e = SceneSource::read(&p).unwrap_err().to_string();
        let want =
            Error::Input(grainchain_engine::file::parse_file(text, &p).unwrap_err()).to_string();
        assert_eq!(e, want);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
