//! The outputs of `[tolerances]`: the spread of the reported columns' peaks
//! ([`crate::design::tolerance`]) as `tolerances.csv`, `sensitivities.csv`, a DESIGN.md section and
//! `sensitivity.svg`. Without the table none of this runs and nothing here is written.

use super::chart::Chart;
use crate::design::phases::Phases;
use crate::design::tolerance::{first_order, spread_of, Property, Spread, Tolerances};
use crate::error::{DesignFailure, Error};
use crate::report::atomic::csv_rows;
use crate::report::csv_number as num;
use crate::report::plot::{Scale, Series};
use grainchain_engine::protector::{gradients_many, Bead, Gradients, Impact, Protected, Settings};
use std::fmt::Write as _;
use std::path::Path;

/// A reported column: what it is called, its beads and the speed it is analysed at.
pub struct Column<'a> {
    /// `design` (a ranked design) or `baseline`.
    pub kind: &'static str,
    /// Its rank, or the baseline's name.
    pub name: String,
    /// The column in words.
    pub described: String,
    /// Its beads.
    pub beads: &'a [Bead],
    /// The index of the file's speed whose nominal peak is largest (the reported runs').
    pub worst: usize,
}

/// The spreads of the reported columns, and for each column the first-order standard deviation
/// of its peak at every speed where it was computed (every speed with `every_speed`, the p95
/// objective's need; else only the worst, the others NaN).
pub struct Analysis {
    /// One per column, at its worst speed.
    pub spreads: Vec<Spread>,
    /// Per column, per speed.
    pub sd: Vec<Vec<f64>>,
}

/// Analyse every column: the peak's derivatives (one batch per speed, [`gradients_many`]),
/// then each column's Monte Carlo at its worst speed on `threads` threads.
pub fn analyse(
    file: &Path,
    columns: &[Column],
    impacts: &[Impact],
    protected: &Protected,
    settings: &Settings,
    tol: &Tolerances,
    (threads, every_speed, phases): (usize, bool, &Phases),
) -> Result<Analysis, Error> {
    let failed = |source| {
        Error::Design(DesignFailure::Evaluation {
            file: file.to_path_buf(),
            source,
        })
    };
    let n = columns.len();
    let mut at_worst: Vec<Option<Gradients>> = vec![None; n];
    let mut sd = vec![vec![f64::NAN; impacts.len()]; n];
    let bar = phases.bar(
        impacts.len() as u64,
        "tolerances: the peaks' derivatives, one batch per speed",
    );
    for (s, imp) in impacts.iter().enumerate() {
        bar.inc(1);
        let which: Vec<usize> = (0..n)
            .filter(|&i| every_speed || columns[i].worst == s)
            .collect();
        if which.is_empty() {
            continue;
        }
        let beads: Vec<Vec<Bead>> = which.iter().map(|&i| columns[i].beads.to_vec()).collect();
        let runs = gradients_many(&beads, imp, protected, settings, threads).map_err(failed)?;
        for (&i, g) in which.iter().zip(runs) {
            let g = g.map_err(failed)?;
            let b = columns[i].beads;
            sd[i][s] = first_order(b, imp.speed, g.evaluation.peak_force, &g.peak, tol).sd;
            if columns[i].worst == s {
                at_worst[i] = Some(g);
            }
        }
    }
    bar.finish_and_clear();
    let bar = phases.bar(
        (n * tol.samples) as u64,
        &format!("tolerances: Monte Carlo, {} columns of {n}", tol.samples),
    );
    let mut spreads = Vec::with_capacity(n);
    for (c, g) in columns.iter().zip(at_worst) {
        let g = g.expect("every column's worst speed was run");
        let imp = &impacts[c.worst];
        spreads.push(
            spread_of(
                g,
                c.beads,
                imp,
                protected,
                settings,
                tol,
                (threads, &bar, phases.journal()),
            )
            .map_err(failed)?,
        );
    }
    bar.finish_and_clear();
    Ok(Analysis { spreads, sd })
}

/// `tolerances.csv`'s header: per column its peak's spread (first order and Monte Carlo) and
/// each property's share of the first-order variance.
pub const TOLERANCES_HEADER: &str = "kind,name,design,speed_m_s,nominal_peak_n,nominal_bound,tie,first_order_sd_n,first_order_p95_n,mc_mean_n,mc_sd_n,mc_p95_n,samples,bounds,diameter_share,young_share,density_share,speed_share";

/// `sensitivities.csv`'s header: per column, per bead, the peak's derivatives in SI units
/// (N per m, per kg/m^3, per Pa, per unit of Poisson ratio; the speed's and the striker mass's,
/// N s/m and N/kg, repeated on each bead's row) and the bead's share of the first-order variance.
pub const SENSITIVITIES_HEADER: &str = "kind,name,bead,material,diameter_m,density_kg_m3,young_pa,dpeak_ddiameter,dpeak_ddensity,dpeak_dyoung,dpeak_dpoisson,dpeak_dspeed,dpeak_dstriker_mass,variance_share";

/// A number as Rust's `{:e}`: the shortest digits that read back to the same bits, which Python's
/// `float()` reads back to them too.
fn exact<S: serde::Serializer>(x: &f64, s: S) -> Result<S::Ok, S::Error> {
    s.collect_str(&format_args!("{x:e}"))
}

use crate::report::serialize_number as number;

/// A row of `tolerances.csv` ([`TOLERANCES_HEADER`]).
#[derive(serde::Serialize)]
pub struct ToleranceRow {
    kind: &'static str,
    name: String,
    design: String,
    #[serde(serialize_with = "number")]
    speed_m_s: f64,
    #[serde(serialize_with = "number")]
    nominal_peak_n: f64,
    nominal_bound: bool,
    tie: bool,
    #[serde(serialize_with = "number")]
    first_order_sd_n: f64,
    #[serde(serialize_with = "number")]
    first_order_p95_n: f64,
    #[serde(serialize_with = "number")]
    mc_mean_n: f64,
    #[serde(serialize_with = "number")]
    mc_sd_n: f64,
    #[serde(serialize_with = "number")]
    mc_p95_n: f64,
    samples: usize,
    bounds: usize,
    #[serde(serialize_with = "number")]
    diameter_share: f64,
    #[serde(serialize_with = "number")]
    young_share: f64,
    #[serde(serialize_with = "number")]
    density_share: f64,
    #[serde(serialize_with = "number")]
    speed_share: f64,
}

/// A row of `sensitivities.csv` ([`SENSITIVITIES_HEADER`]): every number exact.
#[derive(serde::Serialize)]
pub struct SensitivityRow {
    kind: &'static str,
    name: String,
    bead: usize,
    material: &'static str,
    #[serde(serialize_with = "exact")]
    diameter_m: f64,
    #[serde(serialize_with = "exact")]
    density_kg_m3: f64,
    #[serde(serialize_with = "exact")]
    young_pa: f64,
    #[serde(serialize_with = "exact")]
    dpeak_ddiameter: f64,
    #[serde(serialize_with = "exact")]
    dpeak_ddensity: f64,
    #[serde(serialize_with = "exact")]
    dpeak_dyoung: f64,
    #[serde(serialize_with = "exact")]
    dpeak_dpoisson: f64,
    #[serde(serialize_with = "exact")]
    dpeak_dspeed: f64,
    #[serde(serialize_with = "exact")]
    dpeak_dstriker_mass: f64,
    #[serde(serialize_with = "exact")]
    variance_share: f64,
}

/// What `[tolerances]` writes, computed: the rows of `tolerances.csv` and `sensitivities.csv`
/// and the chart of `sensitivity.svg`.
pub struct Tables {
    tolerances: Vec<ToleranceRow>,
    sensitivities: Vec<SensitivityRow>,
    chart: Chart,
}

impl Tables {
    /// Every column's rows, and the best design's (the first column's) chart.
    pub fn new(columns: &[Column], a: &Analysis, impacts: &[Impact]) -> Tables {
        Tables {
            tolerances: tolerance_rows(columns, a, impacts),
            sensitivities: sensitivity_rows(columns, a),
            chart: chart(&columns[0], &a.spreads[0]),
        }
    }

    /// Write `tolerances.csv`, `sensitivities.csv` and `sensitivity.svg`; the names written.
    pub fn write(&self, out: &Path) -> Result<Vec<String>, Error> {
        csv_rows(&out.join("tolerances.csv"), &self.tolerances)?;
        csv_rows(&out.join("sensitivities.csv"), &self.sensitivities)?;
        self.chart.write(&out.join("sensitivity.svg"))?;
        Ok(vec![
            "tolerances.csv".into(),
            "sensitivities.csv".into(),
            "sensitivity.svg".into(),
        ])
    }
}

/// The rows of `tolerances.csv`: each column's spread at its worst speed.
fn tolerance_rows(columns: &[Column], a: &Analysis, impacts: &[Impact]) -> Vec<ToleranceRow> {
    columns
        .iter()
        .zip(&a.spreads)
        .map(|(c, s)| {
            let (f, m, e) = (&s.first, &s.monte_carlo, &s.gradients.evaluation);
            ToleranceRow {
                kind: c.kind,
                name: c.name.clone(),
                design: c.described.clone(),
                speed_m_s: impacts[c.worst].speed,
                nominal_peak_n: f.peak,
                nominal_bound: !e.complete,
                tie: s.gradients.tie.is_some(),
                first_order_sd_n: f.sd,
                first_order_p95_n: f.p95(),
                mc_mean_n: m.mean,
                mc_sd_n: m.sd,
                mc_p95_n: m.p95,
                samples: m.samples,
                bounds: m.bounds,
                diameter_share: f.property_share(Property::Diameter),
                young_share: f.property_share(Property::Young),
                density_share: f.property_share(Property::Density),
                speed_share: f.property_share(Property::Speed),
            }
        })
        .collect()
}

/// The rows of `sensitivities.csv`: every bead's derivatives of the peak.
fn sensitivity_rows(columns: &[Column], a: &Analysis) -> Vec<SensitivityRow> {
    columns
        .iter()
        .zip(&a.spreads)
        .flat_map(|(c, s)| {
            let d = &s.gradients.peak;
            c.beads
                .iter()
                .enumerate()
                .map(move |(i, b)| SensitivityRow {
                    kind: c.kind,
                    name: c.name.clone(),
                    bead: i + 1,
                    material: b.material.name,
                    diameter_m: b.diameter,
                    density_kg_m3: b.material.density,
                    young_pa: b.material.young,
                    dpeak_ddiameter: d.diameter[i],
                    dpeak_ddensity: d.density[i],
                    dpeak_dyoung: d.young[i],
                    dpeak_dpoisson: d.poisson[i],
                    dpeak_dspeed: d.speed,
                    dpeak_dstriker_mass: d.striker_mass,
                    variance_share: s.first.bead_share(i),
                })
        })
        .collect()
}

/// `x` to four significant digits.
fn sig(x: f64) -> String {
    if !x.is_finite() || x == 0.0 {
        return format!("{x}");
    }
    let decimals = (3 - x.abs().log10().floor() as i32).max(0) as usize;
    format!("{x:.decimals$}")
}

/// A share as a percentage, one decimal.
fn pct(x: f64) -> String {
    format!("{:.1} %", 100.0 * x)
}

/// `sensitivity.svg`: the best design's relative sensitivities `d ln P / d ln x_i` of the
/// diameter, modulus and density of each bead, against its number.
fn chart(best: &Column, s: &Spread) -> Chart {
    let d = &s.gradients.peak;
    let p = s.first.peak;
    let along = |f: &dyn Fn(usize, &Bead) -> f64| -> Vec<(f64, f64)> {
        best.beads
            .iter()
            .enumerate()
            .map(|(i, b)| ((i + 1) as f64, f(i, b) / p))
            .collect()
    };
    let series = vec![
        Series {
            name: "diameter: d ln P / d ln d_i".into(),
            points: along(&|i, b| d.diameter[i] * b.diameter),
            markers: true,
            ..Default::default()
        },
        Series {
            name: "modulus: d ln P / d ln E_i".into(),
            points: along(&|i, b| d.young[i] * b.material.young),
            markers: true,
            ..Default::default()
        },
        Series {
            name: "density: d ln P / d ln rho_i".into(),
            points: along(&|i, b| d.density[i] * b.material.density),
            markers: true,
            ..Default::default()
        },
    ];
    Chart {
        title: "the best design's peak force: relative sensitivity along the column".into(),
        x_label: "bead (1: struck end)",
        y_label: "relative sensitivity of the peak",
        y_scale: Scale::Linear,
        series,
    }
}

/// The rows of the top terms of the best design's first-order variance.
const TOP_TERMS: usize = 8;

/// DESIGN.md's section on the tolerances: the spreads of every reported column, then what
/// dominates the best design's.
pub fn section(
    columns: &[Column],
    a: &Analysis,
    impacts: &[Impact],
    tol: &Tolerances,
    settings: &Settings,
    p95: bool,
) -> String {
    let mut md = String::new();
    let _ = writeln!(md, "## Manufacturing tolerances\n");
    let _ = writeln!(
        md,
        "Each bead's diameter, Young's modulus and density off by relative standard deviations \
         of {}, {} and {}, each bead drawn independently, and the striker's speed by {} \
         (`[tolerances]`; normal, cut at 4 standard deviations). Each design at its worst speed \
         (the one of the largest nominal peak), at the search's step and the reported runs' time \
         cap, not extended (blanes-moan4, events, {} steps per contact time, {} contact-time \
         sums): the \
         first-order spread `sigma_1` from the peak's exact derivatives and its 95th percentile \
         `P + 1.645 sigma_1`, against a Monte Carlo of {} perturbed columns (seed {}; sample \
         standard deviation; 95th percentile by linear interpolation between order statistics, \
         numpy's default). `bounds`: Monte Carlo runs that reached the time cap before the stop \
         rule proved their peak (they count with that lower bound). `tolerances.csv` and \
         `sensitivities.csv` (every derivative, to the last bit) hold it all; `sensitivity.svg` \
         draws the best design's sensitivities along the column.\n",
        tol.diameter,
        tol.young,
        tol.density,
        tol.speed,
        num(settings.steps_per_contact),
        num(settings.time_cap),
        tol.samples,
        tol.seed,
    );
    if p95 {
        let _ = writeln!(
            md,
            "The objective is the first-order p95 (`minimize = \"p95\"`) relative to the \
             monodisperse column's nominal peak at each speed, the worst over the speeds: the \
             reported designs' and baselines' objectives above take the peak from their finer \
             runs and `sigma_1` at each speed from the runs of this section.\n"
        );
    }
    let _ = writeln!(
        md,
        "| design | speed (m/s) | nominal peak (N) | sigma_1 (N) | first-order p95 (N) | MC mean \
         (N) | MC sd (N) | MC p95 (N) | MC sd / sigma_1 | bounds | share: diameter / E / rho / \
         speed |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|---|---|---|---|---|");
    let mut ties = false;
    for (c, s) in columns.iter().zip(&a.spreads) {
        let (f, m) = (&s.first, &s.monte_carlo);
        let tie = s.gradients.tie.is_some();
        ties |= tie;
        let label = if c.kind == "design" {
            format!("rank {}", c.name)
        } else {
            c.name.clone()
        };
        let _ = writeln!(
            md,
            "| {label}{} | {} | {}{} | {} | {} | {} | {} | {} | {} | {} | {} / {} / {} / {} |",
            if tie { " †" } else { "" },
            num(impacts[c.worst].speed),
            if s.gradients.evaluation.complete {
                ""
            } else {
                "≥ "
            },
            sig(f.peak),
            sig(f.sd),
            sig(f.p95()),
            sig(m.mean),
            sig(m.sd),
            sig(m.p95),
            if f.sd > 0.0 {
                format!("{:.3}", m.sd / f.sd)
            } else {
                "-".into()
            },
            m.bounds,
            pct(f.property_share(Property::Diameter)),
            pct(f.property_share(Property::Young)),
            pct(f.property_share(Property::Density)),
            pct(f.property_share(Property::Speed)),
        );
    }
    if ties {
        let _ = writeln!(
            md,
            "\n†: the nominal peak is reached twice within 1e-12 (a kink of the peak as a \
             function of the beads): its first order is one branch's, and the Monte Carlo, which \
             sees both, is the number to trust."
        );
    }
    let (best, s) = (&columns[0], &a.spreads[0]);
    let _ = writeln!(
        md,
        "\n### What dominates the best design's spread\n\nThe largest terms of its first-order \
         variance (`(dP/dx sigma_x x)^2`), with the peak's relative sensitivity `d ln P / d ln \
         x` to each:\n"
    );
    let _ = writeln!(
        md,
        "| bead | material | diameter (mm) | property | share of the variance | d ln P / d ln x |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|");
    let d = &s.gradients.peak;
    for t in s.first.top(TOP_TERMS) {
        let share = t.variance / (s.first.sd * s.first.sd);
        let (bead, material, diameter, x, dx) = match t.bead {
            Some(i) => {
                let b = &best.beads[i];
                let (x, dx) = match t.property {
                    Property::Diameter => (b.diameter, d.diameter[i]),
                    Property::Young => (b.material.young, d.young[i]),
                    _ => (b.material.density, d.density[i]),
                };
                (
                    (i + 1).to_string(),
                    b.material.name.to_string(),
                    format!("{:.3}", b.diameter * 1e3),
                    x,
                    dx,
                )
            }
            None => (
                "striker".into(),
                "-".into(),
                "-".into(),
                impacts[best.worst].speed,
                d.speed,
            ),
        };
        let _ = writeln!(
            md,
            "| {bead} | {material} | {diameter} | {} | {} | {:.4} |",
            t.property.name(),
            pct(share),
            dx * x / s.first.peak,
        );
    }
    let mut beads: Vec<usize> = (0..best.beads.len()).collect();
    beads.sort_by(|&x, &y| s.first.bead_share(y).total_cmp(&s.first.bead_share(x)));
    let _ = writeln!(
        md,
        "\nBy bead (all three properties): {}.\n",
        beads
            .iter()
            .take(5)
            .map(|&i| format!("bead {} {}", i + 1, pct(s.first.bead_share(i))))
            .collect::<Vec<_>>()
            .join(", ")
    );
    md
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Four significant digits, whatever the size.
    #[test]
    fn four_significant_digits() {
        assert_eq!(sig(12.34567), "12.35");
        assert_eq!(sig(0.001234567), "0.001235");
        assert_eq!(sig(98765.4), "98765");
        assert_eq!(sig(0.0), "0");
    }

    /// `{:e}` is the shortest form that reads back to the same bits, through a row as written.
    #[test]
    fn exact_numbers_read_back() {
        #[derive(serde::Serialize)]
        struct One {
            #[serde(serialize_with = "exact")]
            x: f64,
        }
        let written = |x: f64| {
            let mut w = csv::WriterBuilder::new()
                .has_headers(false)
                .from_writer(Vec::new());
            w.serialize(One { x }).unwrap();
            String::from_utf8(w.into_inner().unwrap())
                .unwrap()
                .trim_end()
                .to_string()
        };
        for x in [
            0.1 + 0.2,
            -1.2345678901234567e-300,
            6e-3,
            2e11,
            f64::MIN_POSITIVE,
        ] {
            assert_eq!(written(x).parse::<f64>().unwrap().to_bits(), x.to_bits());
        }
        assert_eq!(written(0.006), "6e-3");
    }

    /// The published headers are the row structs'.
    #[test]
    fn the_headers_are_the_rows() {
        fn header<T: serde::Serialize>(row: T) -> String {
            let mut w = csv::Writer::from_writer(Vec::new());
            w.serialize(row).unwrap();
            let text = String::from_utf8(w.into_inner().unwrap()).unwrap();
            text.lines().next().unwrap().to_string()
        }
        let t = ToleranceRow {
            kind: "design",
            name: "1".into(),
            design: "x".into(),
            speed_m_s: 1.0,
            nominal_peak_n: 1.0,
            nominal_bound: false,
            tie: false,
            first_order_sd_n: 1.0,
            first_order_p95_n: 1.0,
            mc_mean_n: 1.0,
            mc_sd_n: 1.0,
            mc_p95_n: 1.0,
            samples: 1,
            bounds: 0,
            diameter_share: 1.0,
            young_share: 0.0,
            density_share: 0.0,
            speed_share: 0.0,
        };
        assert_eq!(header(&t), TOLERANCES_HEADER);
        let s = SensitivityRow {
            kind: "design",
            name: "1".into(),
            bead: 1,
            material: "steel",
            diameter_m: 1.0,
            density_kg_m3: 1.0,
            young_pa: 1.0,
            dpeak_ddiameter: 1.0,
            dpeak_ddensity: 1.0,
            dpeak_dyoung: 1.0,
            dpeak_dpoisson: 1.0,
            dpeak_dspeed: 1.0,
            dpeak_dstriker_mass: 1.0,
            variance_share: 1.0,
        };
        assert_eq!(header(&s), SENSITIVITIES_HEADER);
    }
}
