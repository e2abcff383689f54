//! Granular protectors from Python (`grainchain_engine::protector`): the materials table, one
//! design evaluated into a dict (with `gradients=True` also the derivatives of its numbers, the
//! engine's `gradients`, as NumPy arrays), a batch into NumPy columns (threads inside), for
//! scripts that drive their own optimisers. The numbers are the engine's `evaluate` /
//! `evaluate_many` / `gradients`, bit for bit; the GIL is released while designs run, and a batch
//! looks for Ctrl-C between chunks.
//!
//! Python's input is checked here, before the engine sees it, so that a bad bead is named by
//! its place in the caller's lists (`beads[2]`, `designs[1][2]`) and its key; the engine's own
//! checks (speed, settings, target, restitution) come back with its text.

use crate::args::{Flag, Whole};
use crate::errors;
use grainchain::design::tolerance::{
    evaluate_draws, sampled, Draws, Statistic, Tolerances, MAX_SIGMA,
};
use grainchain_engine::protector::{
    self, Bead, Derivatives, DesignError as EngineDesignError, Evaluation, Gradients, Impact, Need,
    PairRestitution, Protected, Settings, Tie,
};
use grainchain_engine::units::{diameter_problem, Material, MATERIALS, STEEL};
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyString, PyTuple};

/// The wall time a batch's chunk aims at between two looks for Ctrl-C. An evaluation takes from
/// 0.1 ms (a short column the stop rule ends early) to seconds (a column of millions of steps
/// or one run to the time cap; BENCHMARKS.md, "Protectors"), so the chunk is sized from the pace
/// so far: one design per thread at first, then as many as the last chunk's pace fits in this time,
/// at most [`MAX_PER_THREAD`] per thread (the engine builds its thread pool once per chunk, about
/// 0.1 ms, then under 1 % of a chunk of fast designs). A design under way is not interrupted:
/// one that takes seconds delays Ctrl-C by that much.
const CHUNK_TIME: f64 = 0.1;

/// The largest chunk, designs per thread.
const MAX_PER_THREAD: usize = 64;

/// The constants of a material given as a dict.
const MATERIAL_KEYS: [&str; 3] = ["E", "nu", "rho"];

/// The optional key of a material given as a dict: what outputs call it.
const NAME_KEY: &str = "name";

/// `designs[d][b]` or `beads[b]`: where a bead is in the caller's lists.
fn place(design: Option<usize>, bead: usize) -> String {
    match design {
        Some(d) => format!("designs[{d}][{bead}]"),
        None => format!("beads[{bead}]"),
    }
}

fn known_materials() -> String {
    MATERIALS
        .iter()
        .map(|(k, _)| *k)
        .collect::<Vec<_>>()
        .join(", ")
}

/// A material: a name of the table or a dict `{"E", "nu", "rho"}` (Pa, -, kg/m^3; an optional
/// `"name"`, what outputs call it: `Material::explicit`). `at` names
/// the place and `key` the key in errors.
fn material(obj: &Bound<'_, PyAny>, at: &Loc<'_>, key: &str) -> PyResult<Material> {
    if let Ok(s) = obj.cast::<PyString>() {
        let name = s.to_cow()?;
        return Material::named(&name).map_err(|why| at.err(key, why));
    }
    if let Ok(d) = obj.cast::<PyDict>() {
        for k in d.keys() {
            let k = k.str()?.to_string();
            if !MATERIAL_KEYS.contains(&k.as_str()) && k != NAME_KEY {
                return Err(at.err(
                    key,
                    format!("unknown key {k:?} of a custom material (E, nu, rho, name)"),
                ));
            }
        }
        let mut v = [0.0; 3];
        for (x, k) in v.iter_mut().zip(MATERIAL_KEYS) {
            let item = d.get_item(k)?.ok_or_else(|| {
                at.err(
                    key,
                    format!("a custom material needs E (Pa), nu and rho (kg/m^3); {k} is missing"),
                )
            })?;
            *x = item.extract::<f64>().map_err(|_| {
                at.err(
                    &format!("{key}.{k}"),
                    format!("must be a number, got {item}"),
                )
            })?;
        }
        let name = match d.get_item(NAME_KEY)? {
            Some(n) => Some(n.extract::<String>().map_err(|_| {
                at.err(
                    &format!("{key}.{NAME_KEY}"),
                    format!("must be a string, got {}", type_name(&n)),
                )
            })?),
            None => None,
        };
        return Material::explicit(name.as_deref(), v[0], v[1], v[2])
            .map_err(|why| at.err(key, why));
    }
    Err(at.err(
        key,
        format!(
            "must be a material name ({}) or a dict {{\"E\", \"nu\", \"rho\"}}, got {}",
            known_materials(),
            type_name(obj)
        ),
    ))
}

fn type_name(obj: &Bound<'_, PyAny>) -> String {
    obj.get_type()
        .name()
        .map_or_else(|_| "?".into(), |n| n.to_string())
}

/// A diameter, m ([`diameter_problem`]).
fn diameter(obj: &Bound<'_, PyAny>, at: &Loc<'_>, key: &str) -> PyResult<f64> {
    let d: f64 = obj
        .extract()
        .map_err(|_| at.err(key, format!("must be a number (m), got {}", type_name(obj))))?;
    match diameter_problem(d) {
        Some(why) => Err(at.err(key, why)),
        None => Ok(d),
    }
}

/// Where an error is: the place of a bead (or none) and a prefix of the key (`striker.`).
struct Loc<'a> {
    design: Option<usize>,
    bead: Option<usize>,
    prefix: &'a str,
}

impl Loc<'_> {
    fn err(&self, key: &str, problem: String) -> PyErr {
        let key = format!("{}{key}", self.prefix);
        let at = self.bead.map(|b| place(self.design, b));
        errors::design_error(self.design, self.bead, &key, at.as_deref(), &problem)
    }
}

/// A sphere: a `(material, diameter)` pair (tuple or list) or a dict `{"material", "diameter"}`.
fn bead(obj: &Bound<'_, PyAny>, at: &Loc<'_>) -> PyResult<Bead> {
    let (m, d) = if let Ok(dict) = obj.cast::<PyDict>() {
        for k in dict.keys() {
            let k = k.str()?.to_string();
            if k != "material" && k != "diameter" {
                return Err(at.err(&k, "unknown key (material, diameter)".into()));
            }
        }
        let get = |k: &str| {
            dict.get_item(k)?
                .ok_or_else(|| at.err(k, "is missing".into()))
        };
        (get("material")?, get("diameter")?)
    } else if obj.is_instance_of::<PyTuple>() || obj.is_instance_of::<PyList>() {
        let n = obj.len()?;
        let first = if n > 0 { Some(obj.get_item(0)?) } else { None };
        let nested = first
            .as_ref()
            .is_some_and(|f| f.is_instance_of::<PyTuple>() || f.is_instance_of::<PyList>());
        if n != 2 || nested {
            let hint = if nested && at.design.is_none() {
                " (a list of designs goes to evaluate_many)"
            } else {
                ""
            };
            return Err(at.err(
                "",
                format!("expected a (material, diameter) pair, got a sequence of {n} items{hint}"),
            ));
        }
        (obj.get_item(0)?, obj.get_item(1)?)
    } else {
        return Err(at.err(
            "",
            format!(
                "expected a (material, diameter) pair or a dict {{\"material\", \"diameter\"}}, \
                 got {}",
                type_name(obj)
            ),
        ));
    };
    Ok(Bead {
        material: material(&m, at, "material")?,
        diameter: diameter(&d, at, "diameter")?,
    })
}

/// One design: a non-empty sequence of beads.
fn design(obj: &Bound<'_, PyAny>, index: Option<usize>) -> PyResult<Vec<Bead>> {
    let whole = Loc {
        design: index,
        bead: None,
        prefix: "",
    };
    let what = index.map_or("beads".to_string(), |d| format!("designs[{d}]"));
    if obj.is_instance_of::<PyString>() || obj.is_instance_of::<PyDict>() {
        return Err(whole.err(
            &what,
            format!("must be a list of beads, got {}", type_name(obj)),
        ));
    }
    let items: Vec<Bound<'_, PyAny>> = obj
        .try_iter()
        .map_err(|_| {
            whole.err(
                &what,
                format!("must be a list of beads, got {}", type_name(obj)),
            )
        })?
        .collect::<PyResult<_>>()?;
    if items.is_empty() {
        return Err(whole.err(&what, "a design needs at least one bead".into()));
    }
    items
        .iter()
        .enumerate()
        .map(|(b, x)| {
            bead(
                x,
                &Loc {
                    design: index,
                    bead: Some(b),
                    prefix: "",
                },
            )
        })
        .collect()
}

/// `restitution_pairs`: `(material, material, restitution)` triples, each material a name or a
/// dict as a bead's (the engine checks the numbers and that no pair is given twice).
fn pairs(obj: &Bound<'_, PyAny>, at: &Loc<'_>) -> PyResult<Vec<PairRestitution>> {
    const SHAPE: &str = "must be a list of (material, material, restitution) triples";
    let shape = || {
        at.err(
            "restitution_pairs",
            format!("{SHAPE}, got {}", type_name(obj)),
        )
    };
    if obj.cast::<PyString>().is_ok() || obj.cast::<PyDict>().is_ok() {
        return Err(shape());
    }
    let items: Vec<Bound<'_, PyAny>> = obj
        .try_iter()
        .and_then(|i| i.collect())
        .map_err(|_| shape())?;
    items
        .iter()
        .enumerate()
        .map(|(i, item)| {
            let key = format!("restitution_pairs[{i}]");
            let triple: Vec<Bound<'_, PyAny>> = item
                .try_iter()
                .and_then(|t| t.collect())
                .ok()
                .filter(|t: &Vec<_>| t.len() == 3 && item.cast::<PyString>().is_err())
                .ok_or_else(|| {
                    at.err(
                        &key,
                        format!(
                            "must be a (material, material, restitution) triple, got {}",
                            type_name(item)
                        ),
                    )
                })?;
            let a = material(&triple[0], at, &format!("{key}[0]"))?;
            let b = material(&triple[1], at, &format!("{key}[1]"))?;
            let restitution: f64 = triple[2].extract().map_err(|_| {
                at.err(
                    &format!("{key}[2]"),
                    format!("must be a number, got {}", type_name(&triple[2])),
                )
            })?;
            Ok(PairRestitution {
                between: [a.name, b.name],
                restitution,
            })
        })
        .collect()
}

/// The load, what is protected and the settings, shared by one design and a batch.
struct Common {
    impact: Impact,
    protected: Protected,
    settings: Settings,
}

#[allow(clippy::too_many_arguments)]
fn common(
    striker: &Bound<'_, PyAny>,
    speed: f64,
    wall: Option<&Bound<'_, PyAny>>,
    target: Option<&Bound<'_, PyAny>>,
    restitution: Option<f64>,
    restitution_pairs: Option<&Bound<'_, PyAny>>,
    need: &str,
    fraction: Option<f64>,
    accuracy: Option<f64>,
    steps_per_contact: Option<f64>,
    check_every: Option<Whole>,
    time_cap: Option<f64>,
    give_up_above: Option<f64>,
) -> PyResult<Common> {
    let top = Loc {
        design: None,
        bead: None,
        prefix: "",
    };
    let striker = bead(
        striker,
        &Loc {
            design: None,
            bead: None,
            prefix: "striker.",
        },
    )?;
    let protected = match (wall, target) {
        (Some(_), Some(_)) => {
            return Err(top.err(
                "wall",
                "give a wall or a target, not both (the column ends on one of them)".into(),
            ))
        }
        (None, None) => Protected::Wall(STEEL),
        (Some(w), None) => Protected::Wall(material(w, &top, "wall")?),
        (None, Some(t)) => target_of(t, &top)?,
    };
    let need = match need {
        "peak" => Need::Peak,
        "duration" => Need::Duration,
        "everything" => Need::Everything,
        other => {
            return Err(top.err(
                "need",
                format!("must be \"peak\", \"duration\" or \"everything\", got {other:?}"),
            ))
        }
    };
    let d = Settings::default();
    let steps_per_contact = match (accuracy, steps_per_contact) {
        (Some(_), Some(_)) => {
            return Err(top.err(
                "accuracy",
                "give accuracy or steps_per_contact, not both (accuracy sets the steps)".into(),
            ))
        }
        (Some(a), None) => match protector::accuracy_problem(a) {
            Some(p) => return Err(top.err("accuracy", p)),
            None => protector::steps_for_accuracy(a),
        },
        (None, s) => s.unwrap_or(d.steps_per_contact),
    };
    // At least 1 step between checks of the stop rule (the engine's own bound).
    let check_every = match check_every {
        Some(c) => c.u32(1).map_err(|p| top.err("check_every", p))?,
        None => d.check_every,
    };
    Ok(Common {
        impact: Impact {
            striker,
            speed,
            restitution,
            restitution_pairs: match restitution_pairs {
                Some(obj) => pairs(obj, &top)?,
                None => Vec::new(),
            },
        },
        protected,
        settings: Settings {
            need,
            fraction: fraction.unwrap_or(d.fraction),
            steps_per_contact,
            check_every,
            time_cap: time_cap.unwrap_or(d.time_cap),
            method: d.method,
            events: d.events,
            give_up_above: give_up_above.unwrap_or(d.give_up_above),
        },
    })
}

/// A target body: a dict `{"mass" (kg), "material" (name or dict), "spring" (N/m, default 0: a
/// free body)}`. The engine checks the numbers.
fn target_of(obj: &Bound<'_, PyAny>, top: &Loc<'_>) -> PyResult<Protected> {
    let d = obj.cast::<PyDict>().map_err(|_| {
        top.err(
            "target",
            format!(
                "must be a dict {{\"mass\", \"material\", \"spring\"}}, got {}",
                type_name(obj)
            ),
        )
    })?;
    for k in d.keys() {
        let k = k.str()?.to_string();
        if !["mass", "material", "spring"].contains(&k.as_str()) {
            return Err(top.err(
                &format!("target.{k}"),
                "unknown key (mass, material, spring)".into(),
            ));
        }
    }
    let number = |k: &str, default: Option<f64>| -> PyResult<f64> {
        match (d.get_item(k)?, default) {
            (Some(x), _) => x.extract::<f64>().map_err(|_| {
                top.err(
                    &format!("target.{k}"),
                    format!("must be a number, got {}", type_name(&x)),
                )
            }),
            (None, Some(v)) => Ok(v),
            (None, None) => Err(top.err(&format!("target.{k}"), "is missing".into())),
        }
    };
    let m = d
        .get_item("material")?
        .ok_or_else(|| top.err("target.material", "is missing".into()))?;
    Ok(Protected::Target {
        mass: number("mass", None)?,
        material: material(&m, top, "target.material")?,
        spring: number("spring", Some(0.0))?,
    })
}

/// An engine error of one design (`design`: its index in a batch).
fn engine_error(e: EngineDesignError, design: Option<usize>) -> PyErr {
    let prefix = design.map(|d| format!("designs[{d}]: "));
    match e {
        EngineDesignError::Run(r) => errors::run_prefixed(r, prefix.as_deref().unwrap_or("")),
        EngineDesignError::Bad { what, problem } => errors::design_error(
            design,
            None,
            &what,
            design.map(|d| format!("designs[{d}]")).as_deref(),
            &problem,
        ),
        // Unreachable from here (designs are checked non-empty above), kept exact.
        EngineDesignError::Empty => errors::design_error(
            design,
            None,
            "beads",
            design.map(|d| format!("designs[{d}]")).as_deref(),
            &EngineDesignError::Empty.to_string(),
        ),
        // Only where the interpreter is exiting (a Ctrl-C comes back as KeyboardInterrupt).
        EngineDesignError::Stopped => errors::design_error(
            design,
            None,
            "gradients",
            None,
            &EngineDesignError::Stopped.to_string(),
        ),
    }
}

/// How often a run with derivatives looks for Ctrl-C: it asks at every check of the stop rule
/// (32 steps by default, milliseconds on a long column) and attaches to look at most this often.
const SIGNAL_CHECK: std::time::Duration = std::time::Duration::from_millis(50);

/// `protector::gradients_until`, looking for Ctrl-C every [`SIGNAL_CHECK`] from the detached run
/// (as `grainchain.run` does): an interrupt stops the run and comes back as the Python error
/// (`KeyboardInterrupt`), within a second even on a column of minutes, and before any NumPy
/// array is made (the first gradient call of a process imports NumPy's API when it makes one,
/// and an interrupt pending then made that import fail as a `PanicException`).
fn gradients_interruptible(
    beads: &[Bead],
    c: &Common,
) -> Result<Result<Gradients, EngineDesignError>, PyErr> {
    let mut signal: Option<PyErr> = None;
    let mut last = std::time::Instant::now();
    let r = protector::gradients_until(beads, &c.impact, &c.protected, &c.settings, &mut || {
        if last.elapsed() < SIGNAL_CHECK {
            return true;
        }
        last = std::time::Instant::now();
        match Python::try_attach(|py| py.check_signals()) {
            Some(Ok(())) => true,
            Some(Err(e)) => {
                signal = Some(e);
                false
            }
            // The interpreter is exiting: stop.
            None => false,
        }
    });
    match signal {
        Some(e) => Err(e),
        None => Ok(r),
    }
}

/// The materials of the table: `{name: {"E": Pa, "nu": -, "rho": kg/m^3}}`, in the table's
/// order. Any entry (or a dict of the same keys) is a material for `evaluate`.
#[pyfunction]
fn protector_materials(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let d = PyDict::new(py);
    for (k, m) in MATERIALS {
        let x = PyDict::new(py);
        x.set_item("E", m.young)?;
        x.set_item("nu", m.poisson)?;
        x.set_item("rho", m.density)?;
        d.set_item(k, x)?;
    }
    Ok(d)
}

/// One design's evaluation as a dict (every field of the engine's `Evaluation`).
fn evaluation_dict<'py>(py: Python<'py>, e: &Evaluation) -> PyResult<Bound<'py, PyAny>> {
    pythonize::pythonize(py, e).map_err(|e| errors::InternalError::new_err(e.to_string()))
}

/// The derivatives of one number as a dict: per-bead float64 arrays `diameter` (per m), `rho`
/// (per kg/m^3), `E` (per Pa) and `nu` (the keys of a material's dict), floats `speed` (per m/s)
/// and `striker_mass` (per kg). The vectors are handed to NumPy, not copied: the engine's bits.
fn derivatives_dict(py: Python<'_>, d: Derivatives) -> PyResult<Bound<'_, PyDict>> {
    // Every field by name, without `..`: a field added to `Derivatives` fails to compile here
    // until it has its key.
    let Derivatives {
        diameter,
        density,
        young,
        poisson,
        speed,
        striker_mass,
    } = d;
    let x = PyDict::new(py);
    x.set_item("diameter", PyArray1::from_vec(py, diameter))?;
    x.set_item("rho", PyArray1::from_vec(py, density))?;
    x.set_item("E", PyArray1::from_vec(py, young))?;
    x.set_item("nu", PyArray1::from_vec(py, poisson))?;
    x.set_item("speed", speed)?;
    x.set_item("striker_mass", striker_mass)?;
    Ok(x)
}

/// The engine's `Gradients` as the dict `evaluate(..., gradients=True)` puts under
/// `"gradients"`: a [`derivatives_dict`] per number, `tie` (None or `{"time", "force", "peak"}`),
/// `step_shared` and `evaluation` (the numbers of the run the derivatives are of).
fn gradients_dict(py: Python<'_>, g: Gradients) -> PyResult<Bound<'_, PyDict>> {
    // Every field by name, as in `derivatives_dict`.
    let Gradients {
        evaluation,
        peak,
        impulse,
        duration,
        target_energy,
        rebound,
        tie,
        step_shared,
    } = g;
    let x = PyDict::new(py);
    x.set_item("peak", derivatives_dict(py, peak)?)?;
    x.set_item("impulse", derivatives_dict(py, impulse)?)?;
    x.set_item("duration", derivatives_dict(py, duration)?)?;
    x.set_item("target_energy", derivatives_dict(py, target_energy)?)?;
    x.set_item("rebound", derivatives_dict(py, rebound)?)?;
    let tie = match tie {
        None => None,
        Some(Tie { time, force, peak }) => {
            let t = PyDict::new(py);
            t.set_item("time", time)?;
            t.set_item("force", force)?;
            t.set_item("peak", derivatives_dict(py, peak)?)?;
            Some(t)
        }
    };
    x.set_item("tie", tie)?;
    x.set_item("step_shared", step_shared)?;
    x.set_item("evaluation", evaluation_dict(py, &evaluation)?)?;
    Ok(x)
}

/// Evaluate one design; see `grainchain.protector.evaluate`.
#[pyfunction]
#[pyo3(signature = (beads, *, striker, speed, wall = None, target = None, restitution = None, restitution_pairs = None, need = "peak", fraction = None, accuracy = None, steps_per_contact = None, check_every = None, time_cap = None, give_up_above = None, gradients = Flag(false)))]
#[allow(clippy::too_many_arguments)]
fn protector_evaluate<'py>(
    py: Python<'py>,
    beads: &Bound<'py, PyAny>,
    striker: &Bound<'py, PyAny>,
    speed: f64,
    wall: Option<&Bound<'py, PyAny>>,
    target: Option<&Bound<'py, PyAny>>,
    restitution: Option<f64>,
    restitution_pairs: Option<&Bound<'py, PyAny>>,
    need: &str,
    fraction: Option<f64>,
    accuracy: Option<f64>,
    steps_per_contact: Option<f64>,
    check_every: Option<Whole>,
    time_cap: Option<f64>,
    give_up_above: Option<f64>,
    gradients: Flag,
) -> PyResult<Bound<'py, PyAny>> {
    let beads = design(beads, None)?;
    let c = common(
        striker,
        speed,
        wall,
        target,
        restitution,
        restitution_pairs,
        need,
        fraction,
        accuracy,
        steps_per_contact,
        check_every,
        time_cap,
        give_up_above,
    )?;
    if !gradients.0 {
        let r = errors::detached(py, || {
            protector::evaluate(&beads, &c.impact, &c.protected, &c.settings)
        })?;
        let e = r.map_err(|e| engine_error(e, None))?;
        return evaluation_dict(py, &e);
    }
    // The evaluation's fields are `evaluate`'s, so that `gradients=True` changes none of their
    // bits: the engine's run with derivatives sums the same terms in another order, equal only
    // to rounding (about 1e-12), so it runs beside it (the derivatives cost some eight plain
    // runs, so this adds an eighth). `evaluate` first: a design it refuses
    // or that blows up raises what it raises without gradients.
    let r = errors::detached(py, || {
        let e = match protector::evaluate(&beads, &c.impact, &c.protected, &c.settings) {
            Ok(e) => e,
            Err(x) => return Ok::<_, PyErr>(Err(x)),
        };
        Ok(gradients_interruptible(&beads, &c)?.map(|g| (e, g)))
    })??;
    let (e, g) = r.map_err(|e| engine_error(e, None))?;
    let d = evaluation_dict(py, &e)?;
    d.cast::<PyDict>()?
        .set_item("gradients", gradients_dict(py, g)?)?;
    Ok(d)
}

/// Estimate one design's numbers with their errors; see `grainchain.protector.estimate`.
#[pyfunction]
#[pyo3(signature = (beads, *, striker, speed, wall = None, target = None, restitution = None, restitution_pairs = None, need = "peak", fraction = None, accuracy = None, steps_per_contact = None, check_every = None, time_cap = None, to_end = false))]
#[allow(clippy::too_many_arguments)]
fn protector_estimate<'py>(
    py: Python<'py>,
    beads: &Bound<'py, PyAny>,
    striker: &Bound<'py, PyAny>,
    speed: f64,
    wall: Option<&Bound<'py, PyAny>>,
    target: Option<&Bound<'py, PyAny>>,
    restitution: Option<f64>,
    restitution_pairs: Option<&Bound<'py, PyAny>>,
    need: &str,
    fraction: Option<f64>,
    accuracy: Option<f64>,
    steps_per_contact: Option<f64>,
    check_every: Option<Whole>,
    time_cap: Option<f64>,
    to_end: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let beads = design(beads, None)?;
    let c = common(
        striker,
        speed,
        wall,
        target,
        restitution,
        restitution_pairs,
        need,
        fraction,
        accuracy,
        steps_per_contact,
        check_every,
        time_cap,
        None,
    )?;
    let r = errors::detached(py, || {
        if to_end {
            protector::estimate_to_end(&beads, &c.impact, &c.protected, &c.settings)
        } else {
            protector::estimate(&beads, &c.impact, &c.protected, &c.settings)
        }
    })?;
    let e = r.map_err(|e| engine_error(e, None))?;
    pythonize::pythonize(py, &e).map_err(|e| errors::InternalError::new_err(e.to_string()))
}

/// Columns of a batch's evaluations, one per field of `Evaluation`.
#[derive(Default)]
struct Columns {
    peak_force: Vec<f64>,
    peak_time: Vec<f64>,
    impulse: Vec<f64>,
    duration: Vec<f64>,
    target_energy: Vec<f64>,
    rebound: Vec<f64>,
    rebound_final: Vec<bool>,
    mass: Vec<f64>,
    length: Vec<f64>,
    time: Vec<f64>,
    steps: Vec<u64>,
    dt: Vec<f64>,
    complete: Vec<bool>,
    given_up: Vec<bool>,
}

impl Columns {
    fn push(&mut self, e: &Evaluation) {
        // Every field by name, without `..`: a field added to `Evaluation` fails to compile here
        // until it has its column.
        let Evaluation {
            peak_force,
            peak_time,
            impulse,
            duration,
            target_energy,
            rebound,
            rebound_final,
            mass,
            length,
            time,
            steps,
            dt,
            complete,
            given_up,
        } = *e;
        self.peak_force.push(peak_force);
        self.peak_time.push(peak_time);
        self.impulse.push(impulse);
        self.duration.push(duration);
        self.target_energy.push(target_energy);
        self.rebound.push(rebound);
        self.rebound_final.push(rebound_final);
        self.mass.push(mass);
        self.length.push(length);
        self.time.push(time);
        self.steps.push(steps);
        self.dt.push(dt);
        self.complete.push(complete);
        self.given_up.push(given_up);
    }

    /// The columns as a dict of NumPy arrays (each vector handed over, not copied).
    fn into_dict(self, py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("peak_force", PyArray1::from_vec(py, self.peak_force))?;
        d.set_item("peak_time", PyArray1::from_vec(py, self.peak_time))?;
        d.set_item("impulse", PyArray1::from_vec(py, self.impulse))?;
        d.set_item("duration", PyArray1::from_vec(py, self.duration))?;
        d.set_item("target_energy", PyArray1::from_vec(py, self.target_energy))?;
        d.set_item("rebound", PyArray1::from_vec(py, self.rebound))?;
        d.set_item("rebound_final", PyArray1::from_vec(py, self.rebound_final))?;
        d.set_item("mass", PyArray1::from_vec(py, self.mass))?;
        d.set_item("length", PyArray1::from_vec(py, self.length))?;
        d.set_item("time", PyArray1::from_vec(py, self.time))?;
        d.set_item("steps", PyArray1::from_vec(py, self.steps))?;
        d.set_item("dt", PyArray1::from_vec(py, self.dt))?;
        d.set_item("complete", PyArray1::from_vec(py, self.complete))?;
        d.set_item("given_up", PyArray1::from_vec(py, self.given_up))?;
        Ok(d)
    }
}

/// Evaluate a batch of designs on `threads` threads; see `grainchain.protector.evaluate_many`.
#[pyfunction]
#[pyo3(signature = (designs, *, striker, speed, wall = None, target = None, restitution = None, restitution_pairs = None, need = "peak", fraction = None, accuracy = None, steps_per_contact = None, check_every = None, time_cap = None, give_up_above = None, threads = Whole::new(1)))]
#[allow(clippy::too_many_arguments)]
fn protector_evaluate_many<'py>(
    py: Python<'py>,
    designs: &Bound<'py, PyAny>,
    striker: &Bound<'py, PyAny>,
    speed: f64,
    wall: Option<&Bound<'py, PyAny>>,
    target: Option<&Bound<'py, PyAny>>,
    restitution: Option<f64>,
    restitution_pairs: Option<&Bound<'py, PyAny>>,
    need: &str,
    fraction: Option<f64>,
    accuracy: Option<f64>,
    steps_per_contact: Option<f64>,
    check_every: Option<Whole>,
    time_cap: Option<f64>,
    give_up_above: Option<f64>,
    threads: Whole,
) -> PyResult<Bound<'py, PyDict>> {
    let top = Loc {
        design: None,
        bead: None,
        prefix: "",
    };
    let threads = threads.usize(1).map_err(|p| top.err("threads", p))?;
    // The one rule of every pool: at most what the machine runs at once (and one per design,
    // which `evaluate_many` applies per chunk).
    let threads = grainchain_engine::worker_threads(threads, usize::MAX);
    if designs.is_instance_of::<PyString>() || designs.is_instance_of::<PyDict>() {
        return Err(top.err(
            "designs",
            format!("must be a list of designs, got {}", type_name(designs)),
        ));
    }
    let designs: Vec<Vec<Bead>> = designs
        .try_iter()
        .map_err(|_| {
            top.err(
                "designs",
                format!("must be a list of designs, got {}", type_name(designs)),
            )
        })?
        .enumerate()
        .map(|(k, d)| design(&d?, Some(k)))
        .collect::<PyResult<_>>()?;
    let c = common(
        striker,
        speed,
        wall,
        target,
        restitution,
        restitution_pairs,
        need,
        fraction,
        accuracy,
        steps_per_contact,
        check_every,
        time_cap,
        give_up_above,
    )?;
    let mut cols = Columns::default();
    let (mut start, mut size) = (0, threads);
    while start < designs.len() {
        let chunk = &designs[start..(start + size).min(designs.len())];
        let clock = std::time::Instant::now();
        let r = errors::detached(py, || {
            protector::evaluate_many(chunk, &c.impact, &c.protected, &c.settings, threads)
        })?;
        // Settings and load are the same for every design: their error is the batch's.
        let r = r.map_err(|e| engine_error(e, None))?;
        for (i, e) in r.iter().enumerate() {
            cols.push(
                e.as_ref()
                    .map_err(|e| engine_error(e.clone(), Some(start + i)))?,
            );
        }
        py.check_signals()?;
        // The next chunk: as many designs as this one's pace fits in CHUNK_TIME.
        let per_design = clock.elapsed().as_secs_f64() / chunk.len() as f64;
        let fit = (CHUNK_TIME / per_design.max(1e-9)) as usize;
        start += chunk.len();
        size = fit.clamp(threads, MAX_PER_THREAD * threads);
    }
    cols.into_dict(py)
}

/// The tolerances of `monte_carlo`: a dict of relative standard deviations under the design
/// file's keys of `[tolerances]` (`diameter`, `E`, `rho`, `speed`), each in [0, 0.2].
fn tolerances_of(
    obj: &Bound<'_, PyAny>,
    samples: usize,
    seed: u64,
    top: &Loc<'_>,
) -> PyResult<Tolerances> {
    let d = obj.cast::<PyDict>().map_err(|_| {
        top.err(
            "tolerances",
            format!(
                "must be a dict of relative standard deviations {{\"diameter\", \"E\", \"rho\", \
                 \"speed\"}}, got {}",
                type_name(obj)
            ),
        )
    })?;
    let mut t = Tolerances {
        diameter: 0.0,
        young: 0.0,
        density: 0.0,
        speed: 0.0,
        samples,
        seed,
    };
    for (k, v) in d.iter() {
        let key: String = k
            .extract()
            .map_err(|_| top.err("tolerances", format!("has a key that is not a string: {k}")))?;
        let slot =
            match key.as_str() {
                "diameter" => &mut t.diameter,
                "E" => &mut t.young,
                "rho" => &mut t.density,
                "speed" => &mut t.speed,
                _ => return Err(top.err(
                    &format!("tolerances[{key:?}]"),
                    "is not a tolerance: the keys are \"diameter\", \"E\", \"rho\" and \"speed\""
                        .into(),
                )),
            };
        let x: f64 = v.extract().map_err(|_| {
            top.err(
                &format!("tolerances[{key:?}]"),
                format!("must be a number, got {}", type_name(&v)),
            )
        })?;
        if !(x.is_finite() && (0.0..=MAX_SIGMA).contains(&x)) {
            return Err(top.err(
                &format!("tolerances[{key:?}]"),
                format!(
                    "must be a relative standard deviation in [0, {MAX_SIGMA}] (0.01 is 1 %), got \
                     {x}"
                ),
            ));
        }
        *slot = x;
    }
    Ok(t)
}

/// `"mean"` or `"pNN"` (a percentile, `0 < NN < 100`).
fn statistic_of(name: &str, top: &Loc<'_>) -> PyResult<Statistic> {
    if name == "mean" {
        return Ok(Statistic::Mean);
    }
    match name.strip_prefix('p').and_then(|x| x.parse::<f64>().ok()) {
        Some(p) if p > 0.0 && p < 100.0 => Ok(Statistic::Quantile(p / 100.0)),
        _ => Err(top.err(
            "statistic",
            format!("must be \"mean\" or a percentile \"pNN\" with 0 < NN < 100 (\"p95\"), got {name:?}"),
        )),
    }
}

/// A Monte Carlo of one design under tolerances; see `grainchain.protector.monte_carlo`.
#[pyfunction]
#[pyo3(signature = (beads, *, striker, speed, tolerances, samples, seed = Whole::new(1), stream = Whole::new(0), statistic = "p95", wall = None, target = None, restitution = None, restitution_pairs = None, accuracy = None, steps_per_contact = None, check_every = None, time_cap = None, threads = Whole::new(1), progress = None))]
#[allow(clippy::too_many_arguments)]
fn protector_monte_carlo<'py>(
    py: Python<'py>,
    beads: &Bound<'py, PyAny>,
    striker: &Bound<'py, PyAny>,
    speed: f64,
    tolerances: &Bound<'py, PyAny>,
    samples: Whole,
    seed: Whole,
    stream: Whole,
    statistic: &str,
    wall: Option<&Bound<'py, PyAny>>,
    target: Option<&Bound<'py, PyAny>>,
    restitution: Option<f64>,
    restitution_pairs: Option<&Bound<'py, PyAny>>,
    accuracy: Option<f64>,
    steps_per_contact: Option<f64>,
    check_every: Option<Whole>,
    time_cap: Option<f64>,
    threads: Whole,
    progress: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let top = Loc {
        design: None,
        bead: None,
        prefix: "",
    };
    let beads = design(beads, None)?;
    let samples = samples
        .within(1, MAX_MONTE_CARLO as u64)
        .map_err(|p| top.err("samples", p))? as usize;
    let seed = seed.u64(0).map_err(|p| top.err("seed", p))?;
    let stream = stream.u64(0).map_err(|p| top.err("stream", p))?;
    let threads = threads.usize(1).map_err(|p| top.err("threads", p))?;
    let threads = grainchain_engine::worker_threads(threads, samples);
    let statistic = statistic_of(statistic, &top)?;
    let tol = tolerances_of(tolerances, samples, seed, &top)?;
    if let Some(p) = progress {
        if !p.is_callable() {
            return Err(top.err(
                "progress",
                format!(
                    "must be a callable progress(done, total), got {}",
                    type_name(p)
                ),
            ));
        }
    }
    let c = common(
        striker,
        speed,
        wall,
        target,
        restitution,
        restitution_pairs,
        "peak",
        None,
        accuracy,
        steps_per_contact,
        check_every,
        time_cap,
        None,
    )?;
    let draws = Draws::new(beads.len(), &tol, samples, stream);
    let mut evals: Vec<Evaluation> = Vec::with_capacity(samples);
    let (mut start, mut size) = (0, threads);
    while start < samples {
        let range = start..(start + size).min(samples);
        let n = range.len();
        let clock = std::time::Instant::now();
        let r = errors::detached(py, || {
            evaluate_draws(
                &beads,
                &c.impact,
                &c.protected,
                &c.settings,
                (&draws, range),
                (threads, None),
                None,
            )
        })?;
        evals.extend(r.map_err(|e| engine_error(e, None))?);
        py.check_signals()?;
        start += n;
        if let Some(p) = progress {
            p.call1((start, samples))?;
        }
        // The next chunk as `evaluate_many` sizes its own: what this one's pace fits in
        // CHUNK_TIME.
        let per = clock.elapsed().as_secs_f64() / n as f64;
        size = ((CHUNK_TIME / per.max(1e-9)) as usize).clamp(threads, MAX_PER_THREAD * threads);
    }
    let s = sampled(statistic, &evals);
    let peaks: Vec<f64> = evals.iter().map(|e| e.peak_force).collect();
    let (mean, sd) = grainchain_engine::analysis::statistics::mean_sd(&peaks);
    let d = PyDict::new(py);
    d.set_item("statistic", statistic.name())?;
    d.set_item("value", s.value)?;
    d.set_item("low", s.interval.0)?;
    d.set_item("high", s.interval.1)?;
    d.set_item("mean", mean)?;
    d.set_item("sd", sd)?;
    d.set_item("samples", samples)?;
    d.set_item("bounds", s.bounds)?;
    d.set_item("peaks", PyArray1::from_vec(py, peaks))?;
    d.set_item(
        "complete",
        PyArray1::from_vec(py, evals.iter().map(|e| e.complete).collect::<Vec<bool>>()),
    )?;
    Ok(d)
}

/// The most Monte Carlo columns of one call, as the design file's `[tolerances] samples`.
const MAX_MONTE_CARLO: usize = 100_000;

/// Add the protector's names to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(protector_materials, m)?)?;
    m.add_function(wrap_pyfunction!(protector_evaluate, m)?)?;
    m.add_function(wrap_pyfunction!(protector_evaluate_many, m)?)?;
    m.add_function(wrap_pyfunction!(protector_estimate, m)?)?;
    m.add_function(wrap_pyfunction!(protector_monte_carlo, m)?)?;
    Ok(())
}
