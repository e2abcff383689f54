//! Shared helpers of the validation suite: report rows, the report files, and the small pieces
//! of independent mathematics the checks compare against (ln-gamma, the Beta function, Bessel
//! functions, quadrature, least-squares slopes).
//!
//! # The report
//!
//! Every check records its rows with [`record`] *before* it asserts, so a failing check still
//! appears in the report. The suite is one test binary (`validation/main.rs`), and libtest runs
//! its tests on several threads, so each call writes its rows to its own file,
//! `target/validation/rows/<module>--<check>--<parameters>.csv` (temporary file + rename; the
//! module is the file of `validation/` the call is written in), and then regenerates
//! `target/validation/REPORT.md` and `target/validation/report.csv` from every row file, under a
//! file lock. The report groups the rows by module. After a full `cargo test` the report
//! therefore holds every row.
//!
//! When the suite runs unfiltered (no test-name filter, no `--skip`, not `--ignored`), its first
//! recorded row deletes every row file of earlier runs (only this binary writes them), so a
//! renamed or removed check does not linger in the report. Filtered runs (one module, one test)
//! only add or replace rows.
#![allow(dead_code)]

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// Outcome of one row.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    Pass,
    Fail,
    /// Measured and reported, no assertion (e.g. the order an integrator reaches on a
    /// non-smooth problem).
    Info,
}

impl Status {
    pub fn of(ok: bool) -> Status {
        if ok {
            Status::Pass
        } else {
            Status::Fail
        }
    }
    fn as_str(self) -> &'static str {
        match self {
            Status::Pass => "pass",
            Status::Fail => "FAIL",
            Status::Info => "info",
        }
    }
}

/// One row of the validation report.
#[derive(Clone, Debug)]
pub struct Row {
    /// Name of the check (stable; rows are grouped and sorted by it).
    pub check: String,
    /// The point of the parameter grid, e.g. `p=1.5, ratio=10`.
    pub parameters: String,
    /// Where the expected value comes from: a section of physics.md, a paper, an exact property.
    pub source: String,
    pub expected: String,
    pub measured: String,
    pub tolerance: String,
    pub status: Status,
}

impl Row {
    pub fn new(check: &str, parameters: impl Into<String>, source: &str) -> Row {
        Row {
            check: check.to_string(),
            parameters: parameters.into(),
            source: source.to_string(),
            expected: String::new(),
            measured: String::new(),
            tolerance: String::new(),
            status: Status::Info,
        }
    }
    pub fn expected(mut self, s: impl Into<String>) -> Row {
        self.expected = s.into();
        self
    }
    pub fn measured(mut self, s: impl Into<String>) -> Row {
        self.measured = s.into();
        self
    }
    pub fn tolerance(mut self, s: impl Into<String>) -> Row {
        self.tolerance = s.into();
        self
    }
    pub fn pass(mut self, ok: bool) -> Row {
        self.status = Status::of(ok);
        self
    }
    pub fn info(mut self) -> Row {
        self.status = Status::Info;
        self
    }
}

/// A number with 4 significant digits (scientific notation outside [1e-3, 1e5)).
pub fn g(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let a = x.abs();
    if (1e-3..1e5).contains(&a) {
        let digits = (3 - a.log10().floor() as i32).max(0) as usize;
        format!("{x:.digits$}")
    } else {
        format!("{x:.3e}")
    }
}

/// Blanes-Moan's fourth-order splitting at step `dt` (the suite's accurate fixed-step runs).
pub fn bm4(dt: f64) -> grainchain_engine::IntegrationParams {
    grainchain_engine::IntegrationParams {
        method: grainchain_engine::Method::BlanesMoan4,
        dt,
        ..Default::default()
    }
}

/// A clean solitary wave of a uniform Hertz chain (p = 3/2) of unit masses (eta = 1): launched by an
/// equal-mass striker at speed 1, followed until its peak is at grain 100, then cut out with
/// `HALF` grains on each side (the tails there are below 1e-20 of the peak, see the width check).
/// Returns (u, v) of the cut, peak at index HALF. By the mass symmetry (physics.md 3) the wave of
/// a chain of mass M is this one with velocities divided by sqrt(M) and time slowed by sqrt(M).
pub const HALF: usize = 20;
pub fn unit_wave() -> &'static (Vec<f64>, Vec<f64>) {
    static W: OnceLock<(Vec<f64>, Vec<f64>)> = OnceLock::new();
    W.get_or_init(|| {
        let chain = grainchain_engine::problems::SolitaryWave::unit(1.5, 160, 1.0)
            .chain()
            .unwrap();
        let mut sim = grainchain_engine::SimulationBuilder::new(chain)
            .params(bm4(2e-3))
            .schedule(1e4, 0.01)
            .build()
            .unwrap();
        let mut cut = None;
        let _ = sim.run(
            |fr: &grainchain_engine::Frame| -> Result<(), grainchain_engine::RunError> {
                let v = &fr.state.v;
                let k = (0..v.len())
                    .max_by(|&a, &b| v[a].abs().total_cmp(&v[b].abs()))
                    .unwrap();
                if k >= 100 {
                    let r = k - HALF..=k + HALF;
                    cut = Some((fr.state.u[r.clone()].to_vec(), v[r].to_vec()));
                    return Err(grainchain_engine::RunError::Settings("stop".into()));
                }
                Ok(())
            },
        );
        cut.expect("wave reached grain 100")
    })
}

/// The index of the entry of largest magnitude (the first of equals).
pub fn argmax_abs(v: &[f64]) -> usize {
    (0..v.len()).fold(0, |b, i| if v[i].abs() > v[b].abs() { i } else { b })
}

/// A relative difference.
pub fn rel(measured: f64, expected: f64) -> f64 {
    (measured - expected).abs() / expected.abs()
}

/// The `target/` directory of this build.
pub fn target_dir() -> PathBuf {
    // CARGO_TARGET_TMPDIR is `<target>/tmp` for integration tests.
    let tmp = Path::new(env!("CARGO_TARGET_TMPDIR"));
    match tmp.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => Path::new(env!("CARGO_MANIFEST_DIR")).join("target"),
    }
}

pub fn report_dir() -> PathBuf {
    target_dir().join("validation")
}

fn rows_dir() -> PathBuf {
    report_dir().join("rows")
}

/// The module of the validation suite a source file belongs to: `validation/<module>.rs`, or a
/// file under `validation/<module>/` (the file a [`record`] call is written in).
fn module_of(file: &str) -> String {
    let parts: Vec<String> = Path::new(file)
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    let first = match parts.iter().rposition(|c| c == "validation") {
        Some(i) if i + 1 < parts.len() => parts[i + 1].as_str(),
        _ => parts.last().map_or("", |s| s.as_str()),
    };
    first.strip_suffix(".rs").unwrap_or(first).to_string()
}

const HEADER: [&str; 7] = [
    "check",
    "parameters",
    "source of expected value",
    "expected",
    "measured",
    "tolerance",
    "pass/fail",
];

fn slug(s: &str) -> String {
    let mut out: String = s
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    out.truncate(120);
    out
}

/// True when this process runs every (non-ignored) test of the suite.
fn unfiltered_run() -> bool {
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--skip" | "--ignored" | "--exact" => return false,
            "--test-threads" | "--format" | "--color" | "-Z" | "--logfile" => {
                args.next();
            }
            s if s.starts_with('-') => {}
            _ => return false, // a name filter
        }
    }
    true
}

/// Once per process: remove the rows of earlier runs when the run is unfiltered.
fn init() -> &'static PathBuf {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = rows_dir();
        fs::create_dir_all(&dir).expect("create target/validation/rows");
        if unfiltered_run() {
            if let Ok(entries) = fs::read_dir(&dir) {
                for e in entries.flatten() {
                    let name = e.file_name().to_string_lossy().into_owned();
                    if name.contains("--") && name.ends_with(".csv") {
                        let _ = fs::remove_file(e.path());
                    }
                }
            }
        }
        dir
    })
}

fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut tmp = tempfile::Builder::new()
        .prefix(".tmp-")
        .suffix(".partial")
        .tempfile_in(dir)?;
    tmp.write_all(bytes)?;
    tmp.flush()?;
    tmp.persist(path).map_err(|e| e.error)?;
    Ok(())
}

fn rows_to_csv(rows: &[Row]) -> Vec<u8> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(HEADER).unwrap();
    for r in rows {
        w.write_record([
            r.check.as_str(),
            r.parameters.as_str(),
            r.source.as_str(),
            r.expected.as_str(),
            r.measured.as_str(),
            r.tolerance.as_str(),
            r.status.as_str(),
        ])
        .unwrap();
    }
    w.into_inner().unwrap()
}

fn read_rows(path: &Path) -> Vec<[String; 7]> {
    let Ok(mut r) = csv::Reader::from_path(path) else {
        return Vec::new();
    };
    r.records()
        .flatten()
        .filter(|rec| rec.len() == 7)
        .map(|rec| std::array::from_fn(|i| rec[i].to_string()))
        .collect()
}

/// Split into text and number tokens: "p=1.5, r=10" -> ["p=", 1.5, ", r=", 10].
fn natural_key(s: &str) -> Vec<(String, f64)> {
    let mut out = Vec::new();
    let b = s.as_bytes();
    let mut i = 0;
    let mut text = String::new();
    while i < b.len() {
        let starts_number =
            b[i].is_ascii_digit() || (b[i] == b'-' && i + 1 < b.len() && b[i + 1].is_ascii_digit());
        if starts_number {
            let mut j = i + 1;
            while j < b.len()
                && (b[j].is_ascii_digit()
                    || b[j] == b'.'
                    || ((b[j] == b'e' || b[j] == b'E')
                        && j + 1 < b.len()
                        && (b[j + 1].is_ascii_digit() || b[j + 1] == b'-')))
            {
                j += if b[j] == b'e' || b[j] == b'E' { 2 } else { 1 };
            }
            let num = s[i..j].parse::<f64>().unwrap_or(f64::NAN);
            out.push((std::mem::take(&mut text), num));
            i = j;
        } else {
            text.push(b[i] as char);
            i += 1;
        }
    }
    out.push((text, f64::NEG_INFINITY));
    out
}

fn natural_cmp(a: &str, b: &str) -> std::cmp::Ordering {
    let (ka, kb) = (natural_key(a), natural_key(b));
    for (x, y) in ka.iter().zip(&kb) {
        let o = x.0.cmp(&y.0).then(x.1.total_cmp(&y.1));
        if o != std::cmp::Ordering::Equal {
            return o;
        }
    }
    ka.len().cmp(&kb.len())
}

fn md_cell(s: &str) -> String {
    s.replace('|', "\\|").replace('\n', " ")
}

/// Rebuild REPORT.md and report.csv from every row file.
fn regenerate() -> std::io::Result<()> {
    let dir = report_dir();
    let lock = fs::OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .open(dir.join(".lock"))?;
    lock.lock()?;
    let mut files: Vec<PathBuf> = fs::read_dir(rows_dir())?
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "csv"))
        .collect();
    files.sort();
    let mut all: Vec<(String, [String; 7])> = Vec::new();
    for f in &files {
        let name = f.file_name().unwrap().to_string_lossy().into_owned();
        let module = name.split("--").next().unwrap_or("").to_string();
        for r in read_rows(f) {
            all.push((module.clone(), r));
        }
    }
    // Sorted by module, then check, then parameters in natural order (numbers by value).
    all.sort_by(|a, b| {
        (&a.0, &a.1[0])
            .cmp(&(&b.0, &b.1[0]))
            .then_with(|| natural_cmp(&a.1[1], &b.1[1]))
    });

    let mut csv = csv::Writer::from_writer(Vec::new());
    let mut header = vec!["module"];
    header.extend(HEADER);
    csv.write_record(&header).unwrap();
    for (t, r) in &all {
        let mut rec = vec![t.as_str()];
        rec.extend(r.iter().map(|s| s.as_str()));
        csv.write_record(&rec).unwrap();
    }
    write_atomic(&dir.join("report.csv"), &csv.into_inner().unwrap())?;

    let count = |s: &str| all.iter().filter(|(_, r)| r[6] == s).count();
    let mut md = String::new();
    md.push_str("# grainchain validation report\n\n");
    md.push_str(
        "Written by `cargo test` (validation/common/mod.rs); the same rows are in `report.csv`. \
         Expected values come from `docs/physics.md` (\"physics.md N\" is its section N), the paper \
         (`docs/paper.md`), or an exact property of the equations; every tolerance's reason is in \
         the test source next to it. `info` rows are measured and reported without an assertion.\n\n",
    );
    md.push_str(&format!(
        "{} rows: {} pass, {} FAIL, {} info.\n",
        all.len(),
        count("pass"),
        count("FAIL"),
        count("info")
    ));
    let mut current = String::new();
    for (t, r) in &all {
        if *t != current {
            current = t.clone();
            md.push_str(&format!(
                "\n## `{t}` (validation/{t}.rs)\n\n| {} |\n|{}\n",
                HEADER.join(" | "),
                "---|".repeat(HEADER.len())
            ));
        }
        let cells: Vec<String> = r.iter().map(|s| md_cell(s)).collect();
        md.push_str(&format!("| {} |\n", cells.join(" | ")));
    }
    write_atomic(&dir.join("REPORT.md"), md.as_bytes())?;
    Ok(())
}

/// Record the rows of one check at one parameter point (replacing an earlier run's), and
/// regenerate the report. Call this before asserting. The rows belong to the module the call is
/// written in.
#[track_caller]
pub fn record(rows: &[Row]) {
    if rows.is_empty() {
        return;
    }
    let module = module_of(std::panic::Location::caller().file());
    let dir = init();
    let key = format!("{}--{}", rows[0].check, rows[0].parameters);
    let path = dir.join(format!("{module}--{}.csv", slug(&key)));
    write_atomic(&path, &rows_to_csv(rows)).expect("write a report row file");
    regenerate().expect("regenerate target/validation/REPORT.md");
}

/// The command that runs the deep tier: the suite's checks too slow for a plain `cargo test`
/// (minutes on 2 cores), each an ignored test whose name starts with `deep_`. CI runs it
/// (`.ci/run`); README.md's test section names it.
pub const DEEP_TIER: &str = "cargo test --test validation deep_ -- --ignored";

/// The report's row of a deep-tier check `what` in a plain run: skipped, and how to run it. The
/// deep test itself replaces it ([`deep_ran`]: the same check and parameters) when it runs.
#[track_caller]
pub fn deep_skipped(what: &str) {
    record(
        &[Row::new("deep tier", what, "validation/main.rs, deep tier")
            .measured(format!(
                "skipped by a plain `cargo test`; run it with `{DEEP_TIER}` (CI does)"
            ))
            .info()],
    );
}

/// The report's row of a deep-tier check `what` that runs now (its own rows follow).
#[track_caller]
pub fn deep_ran(what: &str) {
    record(
        &[Row::new("deep tier", what, "validation/main.rs, deep tier")
            .measured(format!("ran (`{DEEP_TIER}`): its rows are in this module"))
            .info()],
    );
}

/// Record one row and return whether it passed (info rows count as passed).
#[track_caller]
pub fn record_one(row: Row) -> bool {
    let ok = row.status != Status::Fail;
    record(std::slice::from_ref(&row));
    ok
}

// ------------------------------------------------------------------------------------------
// Independent mathematics (nothing here calls grainchain).
// ------------------------------------------------------------------------------------------

/// ln Gamma(x) for x > 0: Lanczos approximation (g = 7, 9 terms), relative error ~1e-15,
/// with the reflection-free shift for x < 0.5 via Gamma(x) = Gamma(x + 1) / x.
pub fn ln_gamma(x: f64) -> f64 {
    assert!(x > 0.0, "ln_gamma needs x > 0");
    if x < 0.5 {
        return ln_gamma(x + 1.0) - x.ln();
    }
    const G: f64 = 7.0;
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + G + 0.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// Euler's Beta function B(a, b) = Gamma(a) Gamma(b) / Gamma(a + b).
pub fn beta(a: f64, b: f64) -> f64 {
    (ln_gamma(a) + ln_gamma(b) - ln_gamma(a + b)).exp()
}

/// Bessel function of the first kind J_n(x): the catalogue's (the linear spring chain's
/// reference), checked below against tabulated values and the independent power series.
pub use grainchain_engine::problems::bessel_j;

/// J_n(x) from its power series (only for small x: cancellation grows like e^x).
pub fn bessel_j_series(n: u32, x: f64) -> f64 {
    let mut term = (0.5 * x).powi(n as i32) / (1..=n).map(f64::from).product::<f64>();
    let mut sum = term;
    for k in 1..60 {
        term *= -(0.25 * x * x) / (k as f64 * (k + n) as f64);
        sum += term;
    }
    sum
}

/// Composite Simpson's rule on [a, b] with `n` (even) intervals.
pub fn simpson(f: impl Fn(f64) -> f64, a: f64, b: f64, n: usize) -> f64 {
    let n = n + n % 2;
    let h = (b - a) / n as f64;
    let mut s = f(a) + f(b);
    for i in 1..n {
        let w = if i % 2 == 1 { 4.0 } else { 2.0 };
        s += w * f(a + i as f64 * h);
    }
    s * h / 3.0
}

/// Least-squares slope and intercept of y against x, with the standard error of the slope.
pub fn fit_line(x: &[f64], y: &[f64]) -> (f64, f64, f64) {
    let n = x.len() as f64;
    let mx = x.iter().sum::<f64>() / n;
    let my = y.iter().sum::<f64>() / n;
    let sxx: f64 = x.iter().map(|a| (a - mx).powi(2)).sum();
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let slope = sxy / sxx;
    let icpt = my - slope * mx;
    let sse: f64 = x
        .iter()
        .zip(y)
        .map(|(a, b)| (b - icpt - slope * a).powi(2))
        .sum();
    let se = if x.len() > 2 {
        (sse / (n - 2.0) / sxx).sqrt()
    } else {
        0.0
    };
    (slope, icpt, se)
}

/// Peak of samples `y` (equally spaced by `h`, first at `t0`) refined by the parabola through
/// the largest sample and its neighbours: (time, value).
pub fn parabolic_peak(y: &[f64], t0: f64, h: f64) -> (f64, f64) {
    let (k, _) =
        y.iter().enumerate().fold(
            (0, f64::NEG_INFINITY),
            |b, (i, &v)| if v > b.1 { (i, v) } else { b },
        );
    if k == 0 || k + 1 >= y.len() {
        return (t0 + k as f64 * h, y[k]);
    }
    let (a, b, c) = (y[k - 1], y[k], y[k + 1]);
    let den = a - 2.0 * b + c;
    if den == 0.0 {
        return (t0 + k as f64 * h, b);
    }
    let d = 0.5 * (a - c) / den;
    (t0 + (k as f64 + d) * h, b - 0.25 * (a - c) * d)
}

/// Relative energy error (energy computed here, not by grainchain) at every one of `outputs`
/// output times of a `steps`-step run of four Hertz grains (eta 1, mass 1) between walls, grain 1
/// at speed 1 and grain 3 at -0.5. Returns the errors and the steps taken.
pub fn box_energy_errors(
    p: grainchain_engine::IntegrationParams,
    steps: u64,
    outputs: u64,
) -> (Vec<f64>, u64) {
    use grainchain_engine::problems::GrainsInABox;
    use grainchain_engine::{Frame, RunError};
    // The catalogue's named box: four Hertz grains, grain 1 at speed 1 and grain 3 at -0.5.
    let t = p.dt * steps as f64;
    let mut sim = GrainsInABox::default()
        .builder()
        .unwrap()
        // The energy is checked here; the run's own bound must not stop it.
        .params(grainchain_engine::IntegrationParams {
            max_energy_error: 1.0,
            ..p
        })
        .schedule(t, t / outputs as f64)
        .build()
        .unwrap();
    let mut errs = Vec::new();
    let mut e0 = None;
    sim.run(|fr: &Frame| {
        let (u, v) = (&fr.state.u, &fr.state.v);
        let pot = |x: f64| x.max(0.0).powf(2.5) / 2.5;
        let mut e = pot(-u[0]) + pot(u[3]);
        for vi in v.iter().take(4) {
            e += 0.5 * vi * vi;
        }
        for i in 1..4 {
            e += pot(u[i - 1] - u[i]);
        }
        let e0 = *e0.get_or_insert(e);
        errs.push((e - e0).abs() / e0);
        Ok::<(), RunError>(())
    })
    .unwrap();
    (errs, sim.stats().steps)
}

/// Max of `errs` over each tenth of the outputs (the initial output excluded).
pub fn tenth_maxima(errs: &[f64]) -> Vec<f64> {
    let k = (errs.len() - 1) / 10;
    (0..10)
        .map(|j| {
            errs[1 + j * k..1 + (j + 1) * k]
                .iter()
                .cloned()
                .fold(0.0, f64::max)
        })
        .collect()
}

/// Run the `grainchain` binary of this build in the crate root: (exit code, stdout, stderr).
/// `GRAINCHAIN_TEST_BIN` names another binary instead (to see a check fail on an older build).
pub fn grainchain(args: &[&str]) -> (Option<i32>, String, String) {
    let bin = std::env::var("GRAINCHAIN_TEST_BIN")
        .unwrap_or_else(|_| env!("CARGO_BIN_EXE_grainchain").to_string());
    let out = std::process::Command::new(bin)
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("run grainchain");
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// A path as the `&str` a command line takes (temporary paths are UTF-8).
pub fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 temp path")
}

/// What a finished command wrote on stderr, as text.
pub fn err(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[cfg(test)]
mod self_tests {
    use super::*;
    use approx::assert_relative_eq;

    // Cheap; they run once, in the suite's one binary.

    #[test]
    fn math_helpers_match_known_values() {
        // Gamma(1/2) = sqrt(pi), Gamma(5) = 24 (exact values; Lanczos is good to ~1e-15).
        assert_relative_eq!(
            ln_gamma(0.5).exp(),
            std::f64::consts::PI.sqrt(),
            max_relative = 1e-13
        );
        assert_relative_eq!(ln_gamma(5.0).exp(), 24.0, max_relative = 1e-13);
        // I_1 = B(1/2, 1/2)/2 = pi/2 (linear spring: half an oscillation period).
        assert_relative_eq!(
            beta(0.5, 0.5) / 2.0,
            std::f64::consts::FRAC_PI_2,
            max_relative = 1e-13
        );
        // Bessel: integral representation against the series (independent formulas) and against
        // tabulated J_0(1) = 0.7651976865579666, J_1(1) = 0.4400505857449335 (A&S table 9.1).
        assert_relative_eq!(bessel_j(0, 1.0), 0.765_197_686_557_966_6, epsilon = 1e-15);
        assert_relative_eq!(bessel_j(1, 1.0), 0.440_050_585_744_933_5, epsilon = 1e-15);
        for n in [0u32, 2, 4, 10] {
            for x in [0.5, 3.0, 8.0] {
                assert_relative_eq!(
                    bessel_j(n as i64, x),
                    bessel_j_series(n, x),
                    epsilon = 1e-13
                );
            }
        }
        // Simpson on a polynomial of degree 3 is exact.
        assert_relative_eq!(
            simpson(|x| x * x * x, 0.0, 2.0, 4),
            4.0,
            max_relative = 1e-15
        );
    }
}

/// Stops a run early from its output callback (`Err(Stop::Done)`), or carries the run's error.
#[derive(Debug)]
pub enum Stop {
    Done,
    #[allow(dead_code)] // carried for the Debug output of a failed run
    Run(grainchain_engine::RunError),
}

impl From<grainchain_engine::RunError> for Stop {
    fn from(e: grainchain_engine::RunError) -> Self {
        Stop::Run(e)
    }
}
