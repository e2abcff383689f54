//! The on-disk form of a scene: serde structs that reject unknown keys.
//!
//! ```toml
//! name = "standard-container"
//! description = "Hong 2005, Fig. 3"
//!
//! [chain]
//! interface = "min-exponent"       # min-exponent | max-exponent | left | right
//! left = { kind = "free" }         # or { kind = "wall", p = 1.5, eta = 5657.0 }
//!
//! [[chain.sections]]
//! name = "outer"                   # optional
//! count = 120
//! mass = 100.0
//! p = 1.5
//! eta = 5657.0
//! delta0 = 0.0                     # optional precompression overlap (needs walls)
//! tension = false                  # optional two-sided linear spring (p = 1 only)
//! damping = 0.0                    # optional viscous damping rate (absorbing layer; verlet
//!                                  # and blanes-moan4 only)
//!
//! [striker]
//! end = "right"
//! mass = 100.0
//! speed = 10.0                     # towards the chain
//!
//! [[initial]]                      # optional per-grain initial conditions
//! grain = 5                        # or first = 5, last = 9
//! velocity = 1.0
//! displacement = 0.0
//!
//! [integrator]
//! method = "verlet"                # verlet | blanes-moan4 | gear5 | dopri5
//! dt = 1e-4                        # fixed step (initial step of dopri5)
//! rtol = 1e-8                      # dopri5 only
//! atol = 1e-10                     # dopri5 only
//! skip_untouched = true
//! max_energy_error = 1e-2
//! sleep = { velocity = 1e-9, force = 1e-9 }   # optional, off by default: grains slower than
//!                                  # `velocity` with a net force below `force` are put to rest
//!                                  # (approximate; verlet and blanes-moan4 only)
//!
//! [run]
//! duration = 35.0
//! output_interval = 0.125
//!
//! [[regions]]
//! name = "container"
//! first = 121
//! last = 300
//!
//! [output]
//! energies = true
//! snapshots = { fields = ["velocity"], every = 1, at = [280], first = 1, last = 420 }
//!                                  # fields: velocity, displacement, force, overlap, energy, mass
//! pulses = { every = 1, threshold = 1e-4, valley = 0.25 }
//! tracks = { every = 1, threshold = 1e-4, valley = 0.25, max_jump = 50.0 }
//!                                  # pulses followed from one detection (every `every`-th
//!                                  # output) to the next, with speed and true peak velocity
//!                                  # (tracks.csv); max_jump: largest move in grains between
//!                                  # detections (default: no limit); verlet, blanes-moan4 and
//!                                  # dopri5 only
//! ```

use crate::chain::{InterfaceRule, StrikerEnd};
use crate::integrators::Method;
use crate::observables::Field;
use serde::Deserialize;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    pub name: Option<String>,
    pub description: Option<String>,
    pub chain: ChainFile,
    pub striker: Option<StrikerFile>,
    #[serde(default)]
    pub initial: Vec<InitialFile>,
    pub integrator: Option<IntegratorFile>,
    pub run: RunFile,
    #[serde(default)]
    pub regions: Vec<RegionFile>,
    pub output: Option<OutputFile>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ChainFile {
    pub interface: Option<InterfaceRule>,
    pub left: Option<EndFile>,
    pub right: Option<EndFile>,
    #[serde(default)]
    pub sections: Vec<SectionFile>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SectionFile {
    pub name: Option<String>,
    pub count: u64,
    pub mass: f64,
    /// Viscous damping rate of every grain of the section (`dv/dt = ... - damping * v`, per
    /// time unit; default 0): an absorbing layer. Needs a splitting method.
    pub damping: Option<f64>,
    #[serde(flatten)]
    pub law: LawFile,
}

#[derive(Debug, Clone, Copy, Deserialize)]
pub struct LawFile {
    pub p: f64,
    pub eta: f64,
    pub delta0: Option<f64>,
    pub tension: Option<bool>,
}

/// An end: `{ kind = "free" }` or `{ kind = "wall", p = .., eta = .., delta0 = .. }`.
#[derive(Debug, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum EndFile {
    Free,
    Wall(LawFile),
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StrikerFile {
    pub end: StrikerEnd,
    pub mass: f64,
    pub speed: f64,
    pub p: Option<f64>,
    pub eta: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InitialFile {
    pub grain: Option<i64>,
    pub first: Option<i64>,
    pub last: Option<i64>,
    pub velocity: Option<f64>,
    pub displacement: Option<f64>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IntegratorFile {
    pub method: Option<Method>,
    pub dt: Option<f64>,
    pub rtol: Option<f64>,
    pub atol: Option<f64>,
    pub skip_untouched: Option<bool>,
    pub max_energy_error: Option<f64>,
    pub sleep: Option<SleepFile>,
    pub multirate: Option<MultirateFile>,
}

/// `multirate = { ratio = 8, fast = "container", margin = 20 }`: the fast region is the named
/// region widened by `margin` grains on each side (see `integrators::multirate`).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MultirateFile {
    pub ratio: u64,
    pub fast: String,
    pub margin: Option<u64>,
}

#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SleepFile {
    pub velocity: f64,
    pub force: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunFile {
    pub duration: f64,
    pub output_interval: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RegionFile {
    pub name: String,
    pub first: i64,
    pub last: i64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputFile {
    pub energies: Option<bool>,
    pub snapshots: Option<SnapshotFile>,
    pub pulses: Option<PulsesFile>,
    pub tracks: Option<TracksFile>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SnapshotFile {
    pub fields: Vec<Field>,
    pub every: Option<u64>,
    #[serde(default)]
    pub at: Vec<u64>,
    pub first: Option<i64>,
    pub last: Option<i64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PulsesFile {
    pub every: Option<u64>,
    #[serde(default)]
    pub at: Vec<u64>,
    pub threshold: Option<f64>,
    pub valley: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TracksFile {
    pub every: Option<u64>,
    pub threshold: Option<f64>,
    pub valley: Option<f64>,
    pub max_jump: Option<f64>,
}

/// A one-line description of a TOML error: where, which key, what.
pub fn describe_toml_error(e: &toml::de::Error, text: &str) -> String {
    let msg = e.message().trim().replace('\n', " ");
    let Some(span) = e.span() else {
        return msg;
    };
    let start = span.start.min(text.len());
    let line_no = text[..start].matches('\n').count() + 1;
    let line_start = text[..start].rfind('\n').map_or(0, |i| i + 1);
    let column = text[line_start..start].chars().count() + 1;
    let line_text = text[line_start..].lines().next().unwrap_or("").trim();
    let mut key = key_at(text, line_start);
    // A missing top-level table is reported at the start of the file: name it as the key.
    if key.is_none() {
        if let Some(rest) = msg.strip_prefix("missing field `") {
            key = rest.split('`').next().map(str::to_string);
        }
    }
    // serde points an unknown field at its table; name the field itself.
    if let (Some(k), Some(rest)) = (key.as_mut(), msg.strip_prefix("unknown field `")) {
        if let Some(field) = rest.split('`').next() {
            if !k.ends_with(&format!(".{field}")) && k != field {
                *k = format!("{k}.{field}");
            }
        }
    }
    match key {
        Some(key) => format!("key `{key}` (line {line_no}, column {column}): {msg}"),
        None => format!("line {line_no}, column {column} (`{line_text}`): {msg}"),
    }
}

/// The dotted key path of the assignment or table header on the line starting at `line_start`.
fn key_at(text: &str, line_start: usize) -> Option<String> {
    let line = text[line_start..].lines().next()?.trim();
    let header = |l: &str| -> Option<(String, bool)> {
        let l = l.trim();
        if let Some(h) = l.strip_prefix("[[") {
            return Some((h.split("]]").next()?.trim().to_string(), true));
        }
        if let Some(h) = l.strip_prefix('[') {
            return Some((h.split(']').next()?.trim().to_string(), false));
        }
        None
    };
    if let Some((h, array)) = header(line) {
        let idx = text[..line_start]
            .lines()
            .filter(|l| header(l) == Some((h.clone(), true)))
            .count();
        return Some(if array { format!("{h}[{idx}]") } else { h });
    }
    let key = line.split('=').next()?.trim();
    if key.is_empty() || line.starts_with('#') || !line.contains('=') {
        return None;
    }
    // Find the enclosing table header, and its array index if it is an array of tables.
    let before = &text[..line_start];
    let mut table = None;
    for (i, l) in before
        .lines()
        .enumerate()
        .collect::<Vec<_>>()
        .into_iter()
        .rev()
    {
        if let Some((h, array)) = header(l) {
            let offset: usize = before.lines().take(i).map(|x| x.len() + 1).sum();
            let idx = before[..offset]
                .lines()
                .filter(|x| header(x) == Some((h.clone(), true)))
                .count();
            table = Some(if array { format!("{h}[{idx}]") } else { h });
            break;
        }
    }
    Some(match table {
        Some(t) => format!("{t}.{key}"),
        None => key.to_string(),
    })
}
