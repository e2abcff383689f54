//! The CSV tables of a study (and, through `plots` and `report`, its SVG figures and STUDY.md).

use super::*;
use crate::error::Error;
use crate::report::atomic::AtomicFile;
use std::path::Path;

// Every number in the one CSV form of grainchain (CONTRIBUTING.md, "CSV conventions").
use crate::report::{csv_number as num, csv_opt as opt};

/// A free-text cell: quoted (it may hold commas), empty when there is nothing to say.
fn note(text: Option<&str>) -> String {
    text.map_or_else(String::new, |t| format!("\"{}\"", t.replace('"', "\"\"")))
}

use crate::report::atomic::csv_file;

/// Write the CSV tables, SVG figures and STUDY.md.
pub fn write(study: &Study, out: &Path) -> Result<(), Error> {
    csv_file(
        &out.join("ensemble.csv"),
        "key,snapshot,mean,median,p05,p95",
        all(study).flat_map(|k| {
            k.band.iter().enumerate().map(move |(t, b)| {
                format!(
                    "{},{t},{},{},{},{}",
                    k.key,
                    num(b.mean),
                    num(b.median),
                    num(b.p05),
                    num(b.p95)
                )
            })
        }),
    )?;
    csv_file(
        &out.join("budget.csv"),
        "key,region,snapshot,mean_fraction",
        study.containers.iter().flat_map(|k| {
            k.regions.iter().enumerate().flat_map(move |(r, name)| {
                k.budget_at
                    .iter()
                    .zip(&k.budget[r])
                    .map(move |(t, x)| format!("{},{name},{t},{}", k.key, num(*x)))
            })
        }),
    )?;
    csv_file(
        &out.join("gauges.csv"),
        &["key", "member", "window_lo", "window_hi", "er_fraction"]
            .map(String::from)
            .into_iter()
            .chain(crate::batch::Gauge::ALL.map(|g| g.field()))
            .collect::<Vec<_>>()
            .join(","),
        study.containers.iter().flat_map(|k| {
            k.gauges.iter().flat_map(move |g| {
                g.members.iter().enumerate().map(move |(m, x)| {
                    let values: Vec<String> = x.iter().map(|v| num(*v)).collect();
                    format!(
                        "{},{m},{},{},{},{}",
                        k.key,
                        g.window.0,
                        g.window.1,
                        num(g.er[m]),
                        values.join(",")
                    )
                })
            })
        }),
    )?;
    if !study.search.is_empty() {
        csv_file(
            &out.join("search.csv"),
            "reading,wall_mass,masses,exponents,interface,medium,t_from,members,gamma_a,alpha_c,alpha_d,alpha_e,distance,gamma_a_decades,note",
            study.search.iter().map(|r| {
                let x = &r.reading;
                let slashed = crate::study::search::slashed;
                let decades: Vec<String> = r.decades.iter().map(|d| opt(*d)).collect();
                format!(
                    "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
                    r.index,
                    num(x.wall_mass),
                    slashed(x.masses),
                    slashed(x.exponents),
                    x.interface.name(),
                    x.medium.label(),
                    r.origin.name(),
                    r.members,
                    opt(r.score.gamma),
                    opt(r.score.alpha[0]),
                    opt(r.score.alpha[1]),
                    opt(r.score.alpha[2]),
                    num(r.score.distance),
                    decades.join("/"),
                    note(r.note.as_deref())
                )
            }),
        )?;
    }
    let mut fits = Vec::new();
    for k in all(study) {
        let row = |what: String, w: &WindowFit| {
            let e = w.est;
            format!(
                "{},{what},{},{},{},{},{},{},{},{}",
                k.key,
                w.t_lo,
                w.t_hi,
                opt(e.map(|e| e.value)),
                opt(e.map(|e| e.se)),
                opt(e.map(|e| e.ci_lo)),
                opt(e.map(|e| e.ci_hi)),
                e.map_or(0, |e| e.n),
                note(w.withheld.as_deref())
            )
        };
        fits.push(row("mean".into(), &k.fit));
        for d in &k.decades {
            fits.push(row("decade".into(), d));
        }
        for (m, g) in k.member_gamma.iter().enumerate() {
            fits.push(format!(
                "{},member-{m},{},{},{},,,,1,{}",
                k.key,
                k.fit.t_lo,
                k.fit.t_hi,
                opt(*g),
                note(k.fit.withheld.as_deref())
            ));
        }
    }
    csv_file(
        &out.join("fits.csv"),
        "key,fit,t_lo,t_hi,gamma,se,ci_lo,ci_hi,members,note",
        fits.into_iter(),
    )?;
    csv_file(
        &out.join("slope.csv"),
        "key,t,slope,se,ci_lo,ci_hi",
        all(study).flat_map(|k| {
            k.slope.iter().map(move |s| {
                format!(
                    "{},{},{},{},{},{}",
                    k.key,
                    num(s.t),
                    num(s.slope),
                    num(s.se),
                    num(s.ci_lo),
                    num(s.ci_hi)
                )
            })
        }),
    )?;
    csv_file(
        &out.join("alpha.csv"),
        "key,level,t_ref,t_key,alpha,ci_lo,ci_hi",
        study.alpha.iter().map(|a| {
            format!(
                "{},{},{},{},{},{},{}",
                a.key,
                num(a.level),
                opt(a.t_ref),
                opt(a.t_key),
                opt(a.alpha),
                num(a.ci_lo),
                num(a.ci_hi)
            )
        }),
    )?;
    if !study.random.is_empty() {
        csv_file(
            &out.join("random.csv"),
            "key,walls,sections,grains,mass_ratio,frac_p1,frac_p15,frac_p2,members,gamma,ci_lo,ci_hi,max_energy_error,layout",
            study.random.iter().map(|k| {
                let d = k.design.as_ref();
                let e = k.fit.est;
                format!(
                    "{},{},{},{},{},{},{},{},{},{},{},{},{},\"{}\"",
                    k.key,
                    d.map_or("", |d| d.walls.name()),
                    d.map_or(0, |d| d.sections),
                    d.map_or(0, |d| d.grains),
                    num(d.map_or(f64::NAN, |d| d.mass_ratio)),
                    num(d.map_or(f64::NAN, |d| d.frac_p1)),
                    num(d.map_or(f64::NAN, |d| d.frac_p15)),
                    num(d.map_or(f64::NAN, |d| d.frac_p2)),
                    k.members,
                    opt(e.map(|e| e.value)),
                    opt(e.map(|e| e.ci_lo)),
                    opt(e.map(|e| e.ci_hi)),
                    num(k.max_energy_error),
                    d.map_or("", |d| d.layout.as_str())
                )
            }),
        )?;
    }
    super::plots::plots(study, out)?;
    if !study.mechanism.is_empty() {
        super::mechanism::write(&study.mechanism, out)?;
    }
    AtomicFile::write_all(out.join("STUDY.md"), report(study).as_bytes())
}
