//! The known designs a search is measured against, on the same load, with the design space's
//! bead count: the monodisperse column of the reference bead; tapered columns (each bead's
//! diameter a fixed ratio of the one before, towards the wall and away from it; Doney and Sen,
//! PRE 72, 041304 (2005)); Hong's containers (a)-(c) in the reference material (diameters for
//! the containers' mass ratios, Hertz contacts throughout); a Fraternali-style pattern (the
//! hardest candidate at the struck end, the softest by the wall, alternating between;
//! Fraternali, Porter and Daraio, Mech. Adv. Mater. Struct. 17, 1 (2010)). Every baseline but
//! the pattern is scaled to the reference column's mass (a common factor on its diameters).

use super::file::DesignSpec;
use grainchain_engine::protector::Bead;

/// A named baseline column.
#[derive(Clone, Debug)]
pub struct Baseline {
    /// Its name in tables and plots.
    pub name: String,
    /// Its beads, struck end first.
    pub beads: Vec<Bead>,
}

/// Diameters scaled by one factor so the column of `material` weighs `mass`.
fn to_mass(mut beads: Vec<Bead>, mass: f64) -> Vec<Bead> {
    let now: f64 = beads.iter().map(Bead::mass).sum();
    let k = (mass / now).cbrt();
    for b in &mut beads {
        b.diameter *= k;
    }
    beads
}

/// Hong's section masses (the reconstruction in `docs/containers.md`; the
/// linear walls, which spheres cannot be, as beads of mass 2), nine sections over `n` beads.
fn container(masses: [f64; 9], n: usize) -> Vec<f64> {
    (0..n).map(|i| masses[i * 9 / n]).collect()
}

/// The baselines of `problem`.
pub fn baselines(problem: &DesignSpec) -> Vec<Baseline> {
    let n = problem.file.space.beads;
    let r = problem.reference;
    let mass = r.mass() * n as f64;
    let mut out = vec![Baseline {
        name: "monodisperse".into(),
        beads: vec![r; n],
    }];
    for q in [0.02f64, 0.05, 0.1] {
        for (dir, s) in [("towards the wall", -1.0f64), ("away from the wall", 1.0)] {
            let beads = (0..n)
                .map(|i| Bead {
                    material: r.material,
                    diameter: r.diameter * (1.0 + s * q).powi(i as i32),
                })
                .collect();
            out.push(Baseline {
                name: format!("tapered {} % {dir}", q * 100.0),
                beads: to_mass(beads, mass),
            });
        }
    }
    let l = 2.0;
    let hong = [
        ("Hong (a) standard", [l, 1.0, 0.5, 0.1, l, 0.1, 0.5, 1.0, l]),
        (
            "Hong (b) right half reversed",
            [l, 1.0, 0.5, 0.1, l, 1.0, 0.5, 0.1, l],
        ),
        (
            "Hong (c) uniform sides",
            [l, 0.1, 0.1, 0.1, l, 0.1, 0.1, 0.1, l],
        ),
    ];
    if n >= 9 {
        for (name, masses) in hong {
            let beads = container(masses, n)
                .into_iter()
                .map(|m| Bead {
                    material: r.material,
                    diameter: r.diameter * m.cbrt(),
                })
                .collect();
            out.push(Baseline {
                name: name.into(),
                beads: to_mass(beads, mass),
            });
        }
    }
    // The pattern in the candidates: hardest (largest modulus) first, softest last.
    let young = |b: &Bead| b.material.young;
    let hard = *problem
        .choices
        .iter()
        .max_by(|a, b| {
            young(a)
                .total_cmp(&young(b))
                .then(a.mass().total_cmp(&b.mass()))
        })
        .expect("choices");
    let soft = *problem
        .choices
        .iter()
        .min_by(|a, b| {
            young(a)
                .total_cmp(&young(b))
                .then(a.mass().total_cmp(&b.mass()))
        })
        .expect("choices");
    if hard != soft {
        let third = n / 3;
        let beads = (0..n)
            .map(|i| {
                if i < third {
                    hard
                } else if i >= n - third || (i - third).is_multiple_of(2) {
                    soft
                } else {
                    hard
                }
            })
            .collect();
        out.push(Baseline {
            name: "Fraternali-style (hard, alternating, soft)".into(),
            beads,
        });
    }
    out
}
