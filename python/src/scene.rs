//! Scenes from a file, a TOML string or a dict, checked by the engine (`Scene::parse`), and their
//! estimate (`check`), the numbers `grainchain check` prints.

use crate::errors;
use grainchain::report::limits::{LimitWords, Refusal, OUTPUT_LIMIT_BYTES};
use grainchain_engine::{MemoryEstimate, Scene as EngineScene};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};
use std::path::{Path, PathBuf};

/// Python's words in the refusals of a scene or study over the engine's size limits
/// (`OUTPUT_LIMIT_BYTES`): the CLI's messages with the argument instead of the flag.
pub const WORDS: LimitWords = LimitWords {
    check: "`check()`",
    allow: "allow_large_output=True",
};

/// A checked scene: a chain, its initial conditions, the integrator, the run's schedule and the
/// outputs asked for. Make one with `Scene.load(path)`, `Scene.from_toml(text)` or
/// `Scene.from_dict(d)` (or pass any of those to `grainchain.run`).
#[pyclass(module = "grainchain", frozen)]
#[derive(Clone)]
pub struct Scene {
    pub inner: EngineScene,
    /// The TOML text it was read from.
    pub text: String,
    /// The memory estimate of the file as parsed (the counts as written, its outer medium
    /// applied), made from the one parse.
    pub memory: MemoryEstimate,
}

impl Scene {
    /// Check `text` (named `path` in messages), refusing first a simulation estimated to need
    /// more than 1 GB of memory unless `allow`, with the CLI's message.
    pub fn parse(text: String, path: &Path, allow: bool) -> PyResult<Scene> {
        use grainchain_engine::file::{parse_toml, FileKind};
        let parsed = parse_toml(&text, path, FileKind::Scene).map_err(errors::scene)?;
        let memory = MemoryEstimate::of_run(&parsed.typed);
        if let Some(e) = memory.refusal(path, WORDS).filter(|_| !allow) {
            return Err(errors::scene(e));
        }
        let inner = EngineScene::from_file(parsed.typed, path).map_err(errors::scene)?;
        Ok(Scene {
            inner,
            text,
            memory,
        })
    }

    /// Read the file at `path` and check it.
    pub fn load_path(path: PathBuf, allow: bool) -> PyResult<Scene> {
        let text = grainchain_engine::file::read_text(&path).map_err(errors::scene)?;
        Scene::parse(text, &path, allow)
    }

    /// A dict as TOML text (its keys are the scene file's): `scene_dict`'s walk, which names the
    /// key of any value a scene file cannot hold and refuses cycles and deep nesting.
    pub fn dict_text(d: &Bound<'_, PyAny>) -> PyResult<String> {
        crate::scene_dict::to_toml(d)
    }

    /// Anything `run` accepts as a scene: a `Scene`, a path (`str` or `os.PathLike`), TOML text
    /// (a `str` holding a newline or `=` that names no file), or a dict.
    pub fn from_any(obj: &Bound<'_, PyAny>, allow: bool) -> PyResult<Scene> {
        if let Ok(s) = obj.cast::<Scene>() {
            return Ok(s.get().clone());
        }
        if obj.is_instance_of::<PyDict>() {
            return Scene::parse(Scene::dict_text(obj)?, Path::new("<dict>"), allow);
        }
        if let Ok(s) = obj.cast::<PyString>() {
            let s = s.to_cow()?;
            let p = Path::new(s.as_ref());
            if !p.exists() && (s.contains('\n') || s.contains('=')) {
                return Scene::parse(s.into_owned(), Path::new("<string>"), allow);
            }
            return Scene::load_path(p.to_path_buf(), allow);
        }
        if let Ok(p) = obj.extract::<PathBuf>() {
            return Scene::load_path(p, allow);
        }
        Err(pyo3::exceptions::PyTypeError::new_err(format!(
            "a scene is a grainchain.Scene, a path, TOML text or a dict, not {}",
            obj.get_type().name()?
        )))
    }

    /// The estimate as a dict (see `check`).
    fn estimate_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let s = &self.inner;
        let est = s.estimate();
        let d = PyDict::new(py);
        d.set_item("file", s.path().display().to_string())?;
        d.set_item("name", s.name())?;
        d.set_item("grains", s.grains())?;
        d.set_item("method", s.params().method.name())?;
        d.set_item("dt", s.params().fitted_step(s.output_interval()))?;
        d.set_item("requested_dt", s.params().dt)?;
        d.set_item("outputs", s.outputs())?;
        d.set_item("rows", s.outputs() + 1)?;
        d.set_item("steps", est.steps)?;
        d.set_item("energies_bytes", est.energies_bytes)?;
        d.set_item("snapshots_bytes", est.snapshots_bytes)?;
        d.set_item("pulses", est.pulses)?;
        d.set_item("tracks", est.tracks)?;
        d.set_item("total_bytes", est.total_bytes())?;
        d.set_item("over_output_limit", est.total_bytes() > OUTPUT_LIMIT_BYTES)?;
        d.set_item("memory_bytes", self.memory.bytes)?;
        d.set_item("memory_per_grain", self.memory.per_grain)?;
        d.set_item("warnings", s.warnings().to_vec())?;
        Ok(d)
    }
}

#[pymethods]
impl Scene {
    /// Read and check a scene file (TOML). Raises `SceneError` naming the file, the key and what
    /// is wrong.
    #[staticmethod]
    #[pyo3(signature = (path, *, allow_large_output = false))]
    fn load(path: PathBuf, allow_large_output: bool) -> PyResult<Scene> {
        Scene::load_path(path, allow_large_output)
    }

    /// Check a scene given as TOML text; `name` stands for the file in error messages (and
    /// names the scene when the text has no `name`).
    #[staticmethod]
    #[pyo3(signature = (text, name = "<string>", *, allow_large_output = false))]
    fn from_toml(text: String, name: &str, allow_large_output: bool) -> PyResult<Scene> {
        Scene::parse(text, Path::new(name), allow_large_output)
    }

    /// Check a scene given as a dict with the scene file's tables and keys (e.g.
    /// `{"chain": {"sections": [...]}, "run": {...}}`); errors name `<dict>` and the key. NumPy
    /// scalars are taken as their Python values and arrays as lists; None, a cycle, nesting
    /// deeper than 64 levels or more than 2^22 values are refused, naming the key.
    #[staticmethod]
    #[pyo3(signature = (d, *, allow_large_output = false))]
    fn from_dict(d: &Bound<'_, PyAny>, allow_large_output: bool) -> PyResult<Scene> {
        Scene::parse(
            Scene::dict_text(d)?,
            Path::new("<dict>"),
            allow_large_output,
        )
    }

    /// The scene's name (its `name`, else the file's stem).
    #[getter]
    fn name(&self) -> String {
        self.inner.name().to_string()
    }
    /// The scene's description.
    #[getter]
    fn description(&self) -> String {
        self.inner.description().to_string()
    }
    /// The file it was read from (`<string>` or `<dict>` otherwise).
    #[getter]
    fn path(&self) -> String {
        self.inner.path().display().to_string()
    }
    /// Grains in the chain, a striker included.
    #[getter]
    fn grains(&self) -> usize {
        self.inner.grains()
    }
    /// Output times after t = 0.
    #[getter]
    fn outputs(&self) -> u64 {
        self.inner.outputs()
    }
    /// Simulated duration.
    #[getter]
    fn duration(&self) -> f64 {
        self.inner.duration()
    }
    /// Time between outputs.
    #[getter]
    fn output_interval(&self) -> f64 {
        self.inner.output_interval()
    }
    /// The integration method's name.
    #[getter]
    fn method(&self) -> &'static str {
        self.inner.params().method.name()
    }
    /// The step asked for (fixed-step methods take `check()["dt"]`, fitted to the interval).
    #[getter]
    fn dt(&self) -> f64 {
        self.inner.params().dt
    }
    /// Regions: name -> (first, last) printed grain numbers.
    #[getter]
    fn regions(&self) -> Vec<(String, (i64, i64))> {
        self.inner
            .regions()
            .iter()
            .map(|r| (r.name.clone(), (r.first, r.last)))
            .collect()
    }
    /// Warnings of the check (settings the scene allowed explicitly that may make numbers wrong).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.inner.warnings().to_vec()
    }
    /// The TOML text the scene was checked from.
    #[getter]
    fn toml(&self) -> String {
        self.text.clone()
    }
    /// The estimate `grainchain check` prints: grains, method, step taken and asked for, outputs
    /// and rows, steps (None for adaptive methods), output sizes in bytes, the memory upper
    /// bound, warnings.
    fn check<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        self.estimate_dict(py)
    }
    fn __repr__(&self) -> String {
        format!(
            "Scene({:?}, {} grains, {} outputs, {})",
            self.inner.name(),
            self.inner.grains(),
            self.inner.outputs(),
            self.inner.params().method.name()
        )
    }
}

/// Check a scene (a `Scene`, path, TOML text or dict) without running it and return the
/// estimate `grainchain check` prints (see `Scene.check`). Raises `SceneError`.
#[pyfunction]
#[pyo3(signature = (scene, *, allow_large_output = false))]
fn check<'py>(
    py: Python<'py>,
    scene: &Bound<'py, PyAny>,
    allow_large_output: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let s = Scene::from_any(scene, allow_large_output)?;
    s.estimate_dict(py)
}

/// Add the scene names to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Scene>()?;
    m.add_function(wrap_pyfunction!(check, m)?)?;
    Ok(())
}
