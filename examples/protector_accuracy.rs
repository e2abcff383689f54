//! The calibration of `[search] accuracy` (issue 40, item 3): the relative error of the peak
//! force, the impulse and the time above half the peak of one protector evaluation against
//! velocity Verlet's steps per contact time, on the reference column (`Case::steel_then_ptfe(40)`)
//! and on the best designs of `designs/*.toml`, against blanes-moan4 at `REFERENCE` steps per
//! contact time (whose own error is printed: its difference from half those steps). The peak
//! comes from a run stopped for the peak (`Need::Peak`, as the search runs), the impulse and
//! the duration from a run stopped when nothing can touch the face again (`Need::Everything`);
//! a number whose run reached the time cap is not final and printed in brackets.
//! The table is of the method the first argument names: `blanes-moan4+events` (the default:
//! the search's method) or `verlet` (the default before contact events).
//! Run: `cargo run --release --example protector_accuracy [-- verlet]` (minutes).

use grainchain_engine::protector::{Bead, Case, Evaluation, Need, Settings};
use grainchain_engine::units::{Material, PTFE, STEEL, TUNGSTEN_CARBIDE};
use grainchain_engine::Method;

/// Steps per contact time of the reference (blanes-moan4) and of its check.
const REFERENCE: f64 = 2560.0;

fn bead(material: Material, diameter: f64) -> Bead {
    Bead { material, diameter }
}

fn cases() -> Vec<(&'static str, Case)> {
    let reference = Case::steel_then_ptfe(40);
    let with = |beads: Vec<Bead>| Case {
        beads,
        ..reference.clone()
    };
    let (s6, p6) = (bead(STEEL, 6e-3), bead(PTFE, 6e-3));
    // designs/steel-ptfe.toml's best (genes 1.1.0.1.0.0.1.1, sections of 5).
    let steel_ptfe: Vec<Bead> = [p6, p6, s6, p6, s6, s6, p6, p6]
        .iter()
        .flat_map(|&b| vec![b; 5])
        .collect();
    // designs/multi-material.toml's best (genes 16.3.5.16.3.16.16.16.16.16, sections of 4).
    let (p4, w6, w8) = (
        bead(PTFE, 4e-3),
        bead(TUNGSTEN_CARBIDE, 6e-3),
        bead(TUNGSTEN_CARBIDE, 8e-3),
    );
    let multi: Vec<Bead> = [p4, w6, w8, p4, w6, p4, p4, p4, p4, p4]
        .iter()
        .flat_map(|&b| vec![b; 4])
        .collect();
    // The monodisperse steel column (the objective's unit).
    vec![
        ("protector-40", Case::steel_then_ptfe(40)),
        ("steel-ptfe best", with(steel_ptfe)),
        ("multi-material best", with(multi)),
        ("40 steel", with(vec![s6; 40])),
    ]
}

fn run(case: &Case, (method, events): (Method, bool), steps: f64, need: Need) -> Evaluation {
    let s = Settings {
        need,
        method,
        events,
        steps_per_contact: steps,
        ..Settings::default()
    };
    case.evaluate(&s).expect("evaluates")
}

fn main() {
    let verlet = std::env::args().nth(1).as_deref() == Some("verlet");
    let (method, steps_list): ((Method, bool), &[f64]) = if verlet {
        (
            (Method::Verlet, false),
            &[
                20.0, 40.0, 80.0, 113.0, 160.0, 226.0, 320.0, 506.0, 640.0, 1280.0,
            ],
        )
    } else {
        (
            (Method::BlanesMoan4, true),
            &[10.0, 14.0, 20.0, 28.0, 40.0, 56.0, 80.0, 160.0, 320.0],
        )
    };
    // The reference: blanes-moan4 with events (its peak located between steps).
    let reference = (Method::BlanesMoan4, true);
    for (name, case) in cases() {
        let peak_ref = run(&case, reference, REFERENCE, Need::Peak);
        let all_ref = run(&case, reference, REFERENCE, Need::Everything);
        let peak_chk = run(&case, reference, REFERENCE / 2.0, Need::Peak);
        let all_chk = run(&case, reference, REFERENCE / 2.0, Need::Everything);
        let rel = |a: f64, b: f64| ((a - b) / b).abs();
        println!(
            "## {name}: peak {} N (final {}), impulse {} N s, duration {} s (final {}); \
             reference's own error: peak {:.1e}, impulse {:.1e}, duration {:.1e}",
            peak_ref.peak_force,
            peak_ref.complete,
            all_ref.impulse,
            all_ref.duration,
            all_ref.complete,
            rel(peak_chk.peak_force, peak_ref.peak_force),
            rel(all_chk.impulse, all_ref.impulse),
            rel(all_chk.duration, all_ref.duration),
        );
        println!("| steps per contact | peak | impulse | duration | ms (peak run) |");
        println!("|---|---|---|---|---|");
        for &steps in steps_list {
            let t = std::time::Instant::now();
            let p = run(&case, method, steps, Need::Peak);
            let ms = t.elapsed().as_secs_f64() * 1e3;
            let a = run(&case, method, steps, Need::Everything);
            let mark = |x: f64, ok: bool| {
                if ok {
                    format!("{x:.1e}")
                } else {
                    format!("[{x:.1e}]")
                }
            };
            println!(
                "| {steps} | {} | {} | {} | {ms:.1} |",
                mark(rel(p.peak_force, peak_ref.peak_force), p.complete),
                mark(rel(a.impulse, all_ref.impulse), a.complete),
                mark(rel(a.duration, all_ref.duration), a.complete),
            );
        }
    }
}
