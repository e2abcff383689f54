//! A scene given as a Python dict, into TOML text. A walk by hand rather than `pythonize`, for
//! three reasons: a dict that holds itself (or one nested thousands deep) made the recursive
//! conversion overflow the stack and kill the interpreter with SIGSEGV; a value no scene file can
//! hold (`None`, an integer beyond 64 bits, a key that is not a string) came back without its key;
//! and NumPy's scalars were refused or accepted by accident of their class (`numpy.float64` is a
//! `float`, `numpy.int64` is no `int`). Here every container is entered at most [`MAX_DEPTH`]
//! levels deep and never while it is already open on the path (a cycle, found by identity), the
//! walk converts at most [`MAX_VALUES`] values (shared containers counted at each place), and
//! every refusal is a `SceneError` naming the key path (`chain.sections[0].mass`).

use crate::errors;
use grainchain_engine::InputError as EngineSceneError;
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{
    PyBool, PyByteArray, PyBytes, PyDict, PyFloat, PyFrozenSet, PyInt, PyList, PyMapping,
    PySequence, PySet, PyString, PyTuple,
};
use std::path::PathBuf;

/// The deepest a scene dict may nest, counting the dict itself as level 1 and each table or
/// array inside as one more. A scene file nests at most 5 (`chain.sections[0].contact_damping`),
/// so 64 is far beyond any scene; it bounds the walk's recursion (a few kilobytes of stack a
/// level at most) long before a thread's stack could run out, and keeps the TOML text within the TOML parser's
/// own nesting limit (80 in toml 0.9), so a dict inside the limit always reaches the scene check.
pub const MAX_DEPTH: usize = 64;

/// The most values a scene dict may hold, each table, array and scalar counted once per place it
/// appears. Shared containers are no cycle, but a list holding the same list twice, forty levels
/// deep (`x = [x, x]` over and over), has 2^40 places: converted, it filled 24 GB in two seconds
/// and the kernel killed the interpreter. A scene file holds tens of values, a generated one with
/// an `[[initial]]` table per grain of a chain of a million grains about four million (a range
/// `first`..`last` says the same in one table). Measured on that shared list, the walk stops at
/// this bound in about a second with the process at about 0.4 GB, under half the 1 GB at which
/// the engine's memory guard refuses a simulation without `allow_large_output`.
pub const MAX_VALUES: u64 = 1 << 22;

/// Values converted between two looks for Ctrl-C: a walk up to [`MAX_VALUES`] takes up to a
/// second or so, and looking costs about a microsecond, so at most 64 looks.
const SIGNAL_EVERY: u64 = 1 << 16;

/// The file name of a scene given as a dict, in messages.
const FILE: &str = "<dict>";

/// One step of a key path: a table's key or an array's index.
enum Step {
    Key(String),
    Index(usize),
}

/// The walk's state: where it is (the key path and the containers open along it, by identity)
/// and how many values it has converted.
struct Walk<'py> {
    py: Python<'py>,
    path: Vec<Step>,
    /// The address of each container open on the path (the dict itself first): the same object
    /// met again below itself is a cycle.
    open: Vec<usize>,
    values: u64,
}

/// `d` (a dict, or any mapping) as the TOML text of a scene file.
pub fn to_toml(d: &Bound<'_, PyAny>) -> PyResult<String> {
    let mut walk = Walk {
        py: d.py(),
        path: Vec::new(),
        open: Vec::new(),
        values: 0,
    };
    let table = match walk.value(d)? {
        toml::Value::Table(t) => t,
        _ => {
            return Err(parse_error(format!(
                "not a scene table: a scene is a dict of tables and keys, not {}",
                type_name(d)
            )))
        }
    };
    toml::to_string(&table).map_err(|e| parse_error(format!("not a scene table: {e}")))
}

fn parse_error(message: String) -> PyErr {
    errors::scene(EngineSceneError::Parse {
        file: PathBuf::from(FILE),
        message,
    })
}

fn type_name(obj: &Bound<'_, PyAny>) -> String {
    obj.get_type()
        .qualname()
        .map_or_else(|_| "?".into(), |n| n.to_string())
}

/// A key path as the engine writes it (`chain.sections[0].mass`).
fn key_of(path: &[Step]) -> String {
    let mut k = String::new();
    for s in path {
        match s {
            Step::Key(name) => {
                if !k.is_empty() {
                    k.push('.');
                }
                k.push_str(name);
            }
            Step::Index(i) => k.push_str(&format!("[{i}]")),
        }
    }
    k
}

impl<'py> Walk<'py> {
    /// The key path so far.
    fn key(&self) -> String {
        key_of(&self.path)
    }

    /// A refusal of the value at the current key path (the dict itself when the path is empty).
    fn bad(&self, message: String) -> PyErr {
        if self.path.is_empty() {
            return parse_error(format!("not a scene table: {message}"));
        }
        errors::scene(EngineSceneError::Invalid {
            file: PathBuf::from(FILE),
            key: self.key(),
            message,
        })
    }

    /// One value of any kind.
    fn value(&mut self, obj: &Bound<'py, PyAny>) -> PyResult<toml::Value> {
        self.count(1)?;
        // The cheap exact checks first (bool before int: a bool is an int in Python).
        if obj.is_none() {
            return Err(self.bad(
                "None is not a value a scene file can hold (TOML has no null): leave the key out \
                 for its default"
                    .into(),
            ));
        }
        if let Ok(b) = obj.cast::<PyBool>() {
            return Ok(toml::Value::Boolean(b.is_true()));
        }
        if let Ok(i) = obj.cast::<PyInt>() {
            return self.integer(i);
        }
        if let Ok(x) = obj.cast::<PyFloat>() {
            return Ok(toml::Value::Float(x.value()));
        }
        if let Ok(s) = obj.cast::<PyString>() {
            return Ok(toml::Value::String(s.to_cow()?.into_owned()));
        }
        if let Ok(d) = obj.cast::<PyDict>() {
            return self.table(obj, d.items().into_any());
        }
        if obj.is_instance_of::<PyList>() || obj.is_instance_of::<PyTuple>() {
            return self.array(obj);
        }
        if let Some(v) = self.numpy(obj)? {
            return Ok(v);
        }
        if obj.is_instance_of::<PyBytes>() || obj.is_instance_of::<PyByteArray>() {
            return Err(self.unsupported(obj));
        }
        // Sets as arrays in their iteration order, other sequences and mappings by their
        // protocols (as pythonize took them before).
        if obj.is_instance_of::<PySet>()
            || obj.is_instance_of::<PyFrozenSet>()
            || obj.cast::<PySequence>().is_ok()
        {
            return self.array(obj);
        }
        if let Ok(m) = obj.cast::<PyMapping>() {
            return self.table(obj, m.items()?.into_any());
        }
        // Any other integer-like (`operator.index` takes it): its integer.
        if obj.hasattr("__index__")? {
            let i = self
                .py
                .import("operator")?
                .call_method1("index", (obj,))?
                .cast_into::<PyInt>()?;
            return self.integer(&i);
        }
        Err(self.unsupported(obj))
    }

    /// Count `n` more values against [`MAX_VALUES`], looking for Ctrl-C every [`SIGNAL_EVERY`].
    fn count(&mut self, n: u64) -> PyResult<()> {
        let before = self.values;
        self.values = self.values.saturating_add(n);
        if self.values > MAX_VALUES {
            return Err(self.too_many());
        }
        if before / SIGNAL_EVERY != self.values / SIGNAL_EVERY {
            self.py.check_signals()?;
        }
        Ok(())
    }

    fn too_many(&self) -> PyErr {
        self.bad(format!(
            "the scene holds more than {MAX_VALUES} values (a list or dict counted once for each \
             place it appears in), far beyond any scene file"
        ))
    }

    fn unsupported(&self, obj: &Bound<'py, PyAny>) -> PyErr {
        self.bad(format!(
            "unsupported type {}: a scene value is a str, int, float, bool, list or dict",
            type_name(obj)
        ))
    }

    /// An integer: TOML's are 64-bit signed.
    fn integer(&self, i: &Bound<'py, PyInt>) -> PyResult<toml::Value> {
        match i.extract::<i64>() {
            Ok(v) => Ok(toml::Value::Integer(v)),
            Err(_) => Err(self.bad(format!(
                "{} is out of range: a scene file's integers are 64-bit, from {} to {}",
                i.str()?,
                i64::MIN,
                i64::MAX
            ))),
        }
    }

    /// A NumPy scalar (`numpy.int64`, `numpy.bool_`, `numpy.float32`, ...) as the Python value
    /// its `item()` gives, a NumPy array as the nested lists of its `tolist()`; None when `obj`
    /// is neither (or NumPy was never imported, so nothing can be one).
    fn numpy(&mut self, obj: &Bound<'py, PyAny>) -> PyResult<Option<toml::Value>> {
        let modules = self.py.import("sys")?.getattr("modules")?;
        let Ok(np) = modules.get_item("numpy") else {
            return Ok(None);
        };
        if obj.is_instance(&np.getattr("generic")?)? {
            let item = obj.call_method0("item")?;
            // A scalar's item is a Python bool, int, float or str; anything else (a datetime,
            // a complex, bytes) is no scene value, named by the NumPy type.
            let plain = item.is_instance_of::<PyBool>()
                || item.is_instance_of::<PyInt>()
                || item.is_instance_of::<PyFloat>()
                || item.is_instance_of::<PyString>();
            return if plain {
                self.value(&item).map(Some)
            } else {
                Err(self.unsupported(obj))
            };
        }
        if obj.is_instance(&np.getattr("ndarray")?)? {
            // Too many elements refused before `tolist` makes each a Python object (the walk of
            // the list counts them).
            let size: u64 = obj.getattr("size")?.extract()?;
            if self.values.saturating_add(size) > MAX_VALUES {
                return Err(self.too_many());
            }
            let list = obj.call_method0("tolist")?;
            return self.value(&list).map(Some);
        }
        Ok(None)
    }

    /// Enter the container `obj`: refused when it is already open on the path (a cycle) or
    /// would be nested deeper than [`MAX_DEPTH`].
    fn enter(&mut self, obj: &Bound<'py, PyAny>) -> PyResult<()> {
        let id = obj.as_ptr() as usize;
        if let Some(k) = self.open.iter().position(|&o| o == id) {
            // The container open at level k was entered at the first k steps of the path.
            let outer = match k {
                0 => "the scene dict itself".to_string(),
                _ => format!(
                    "`{}` itself, the container that holds it",
                    key_of(&self.path[..k])
                ),
            };
            return Err(self.bad(format!(
                "is {outer}: a cycle (a container inside itself), which no scene file can hold"
            )));
        }
        if self.open.len() >= MAX_DEPTH {
            return Err(self.bad(format!(
                "nested more than {MAX_DEPTH} tables and arrays deep (a scene nests at most 5)"
            )));
        }
        self.open.push(id);
        Ok(())
    }

    /// A table from `items`, an iterable of `(key, value)` pairs of the container `obj`.
    fn table(
        &mut self,
        obj: &Bound<'py, PyAny>,
        items: Bound<'py, PyAny>,
    ) -> PyResult<toml::Value> {
        self.enter(obj)?;
        let mut t = toml::Table::new();
        for pair in items.try_iter()? {
            let (k, v): (Bound<'py, PyAny>, Bound<'py, PyAny>) = pair?.extract()?;
            let Ok(k) = k.cast::<PyString>() else {
                return Err(self.bad(format!(
                    "has the key {} ({}), not a string: a scene's keys are strings",
                    k.repr()?,
                    type_name(&k)
                )));
            };
            let k = k.to_cow()?.into_owned();
            self.path.push(Step::Key(k.clone()));
            let v = self.value(&v)?;
            self.path.pop();
            t.insert(k, v);
        }
        self.open.pop();
        Ok(toml::Value::Table(t))
    }

    /// An array from the items of `obj` (a list, tuple, set or other sequence).
    fn array(&mut self, obj: &Bound<'py, PyAny>) -> PyResult<toml::Value> {
        self.enter(obj)?;
        let iter = obj
            .try_iter()
            .map_err(|_| PyTypeError::new_err(format!("{}: not iterable", type_name(obj))))?;
        let mut a = Vec::new();
        for (i, x) in iter.enumerate() {
            self.path.push(Step::Index(i));
            a.push(self.value(&x?)?);
            self.path.pop();
        }
        self.open.pop();
        Ok(toml::Value::Array(a))
    }
}
