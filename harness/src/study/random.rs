//! Random containers, drawn from the stated, seeded distribution of a sweep's `[random]` table,
//! and the member perturbations.
//!
//! A random container is a sequence of interior sections, each with a grain count drawn uniformly
//! from `grains`, a mass drawn uniformly from the list `masses` and an exponent drawn uniformly
//! from `exponents` (all contacts of the template's `eta`), with walls (linear, p = 1, of
//! `wall_grains` grains of mass `wall_mass`, like the paper's) laid out by a wall kind drawn
//! uniformly from `walls`: `none`, `ends` (a wall at each end), `ends-and-middle` (and one after
//! the middle interior section, like container (a)). The number of interior sections is drawn
//! uniformly from `sections`. It replaces the container of the template scene (the sections
//! between `outer-left` and `outer-right`); outer chains, striker, integrator and snapshot
//! interval stay. Container `i` (1-based) uses the ChaCha8 stream seeded with `seed` and
//! stream number `i`, so adding containers never changes the earlier ones.

use super::sweep::{Perturbation, RandomSpec, Walls};
use crate::batch::{ContainerScene, Part};
use crate::error::Error;
use grainchain_engine::file::{InitialFile, LawFile, SectionFile};
use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

/// The design of one random container, for the report and for correlating gamma with it.
#[derive(Clone, Debug, Serialize)]
pub struct Design {
    /// The container's key (`r-001`, ...).
    pub key: String,
    /// The wall layout drawn.
    pub walls: Walls,
    /// Interior sections (walls excluded).
    pub sections: usize,
    /// Grains in the container, walls included.
    pub grains: u64,
    /// Largest over smallest interior mass.
    pub mass_ratio: f64,
    /// Fraction of interior grains with each exponent 1, 1.5, 2 (other exponents are not
    /// counted).
    pub frac_p1: f64,
    /// Fraction of interior grains with exponent 1.5 (Hertz).
    pub frac_p15: f64,
    /// Fraction of interior grains with exponent 2.
    pub frac_p2: f64,
    /// The section list, written as `count x m<mass> p<p>` joined by ` | `.
    pub layout: String,
}

fn stream(seed: u64, stream: u64) -> ChaCha8Rng {
    let mut r = ChaCha8Rng::seed_from_u64(seed);
    r.set_stream(stream);
    r
}

/// The study's dimensions of random containers and member perturbations, as edits of a
/// container scene.
impl ContainerScene<'_> {
    /// Replace the container (the template's) by random container `i` (1-based) of `spec`.
    pub fn random_container(&mut self, spec: &RandomSpec, i: u64) -> Result<Design, Error> {
        random_container(self, spec, i)
    }

    /// Apply member `k`'s perturbation `p` (the scene has a region named `container`).
    pub fn perturb(&mut self, p: Perturbation, k: u64) -> Result<(), Error> {
        perturb(self, p, k)
    }
}

fn random_container(c: &mut ContainerScene, spec: &RandomSpec, i: u64) -> Result<Design, Error> {
    let mut rng = stream(spec.seed, i);
    let src = c.source();
    let left = c.section(Part::OuterLeft)?;
    let right = c.section(Part::OuterRight)?;
    let f = c.file_mut();
    if right <= left {
        return Err(src.missing("`outer-left` before `outer-right`"));
    }
    let eta = f.chain.sections[left].law.eta.ok_or_else(|| {
        src.invalid(
            &format!("chain.sections[{left}].eta"),
            "random containers need program-unit outer chains (`mass`, `p`, `eta`)",
        )
    })?;
    let n = rng.gen_range(spec.sections[0]..=spec.sections[1]) as usize;
    let walls = *spec.walls.choose(&mut rng).expect("checked non-empty");
    let mut interior = Vec::with_capacity(n);
    for _ in 0..n {
        let count = rng.gen_range(spec.grains[0]..=spec.grains[1]);
        let mass = *spec.masses.choose(&mut rng).expect("checked non-empty");
        let p = *spec.exponents.choose(&mut rng).expect("checked non-empty");
        interior.push((count, mass, p));
    }
    let wall = |k: usize| SectionFile {
        name: Some(format!("wall-{k}")),
        count: spec.wall_grains,
        mass: Some(spec.wall_mass),
        diameter: None,
        damping: None,
        law: LawFile::new(1.0, eta),
    };
    let mut secs = Vec::new();
    let mut walls_made = 0;
    let mut add_wall = |secs: &mut Vec<SectionFile>| {
        walls_made += 1;
        secs.push(wall(walls_made));
    };
    if walls != Walls::None {
        add_wall(&mut secs);
    }
    for (j, &(count, mass, p)) in interior.iter().enumerate() {
        secs.push(SectionFile {
            name: Some(format!("S{}", j + 1)),
            count,
            mass: Some(mass),
            diameter: None,
            damping: None,
            law: LawFile::new(p, eta),
        });
        if walls == Walls::EndsAndMiddle && j + 1 == n.div_ceil(2) && j + 1 < n {
            add_wall(&mut secs);
        }
    }
    if walls != Walls::None {
        add_wall(&mut secs);
    }
    let old: u64 = f.chain.sections[left + 1..right]
        .iter()
        .map(|s| s.count)
        .sum();
    let new: u64 = secs.iter().map(|s| s.count).sum();
    let shift = new as i64 - old as i64;
    let first = f.chain.sections[..=left]
        .iter()
        .map(|s| s.count as i64)
        .sum::<i64>()
        + 1;
    let old_last = first + old as i64 - 1;
    let layout = secs
        .iter()
        .map(|s| {
            // Every section here was made above, with a mass and an exponent.
            let (m, p) = (s.mass.unwrap_or(f64::NAN), s.law.p.unwrap_or(f64::NAN));
            format!("{} x m{m} p{p}", s.count)
        })
        .collect::<Vec<_>>()
        .join(" | ");
    f.chain.sections.splice(left + 1..right, secs);
    let region = f
        .regions
        .iter_mut()
        .find(|r| r.name == "container")
        .ok_or_else(|| src.missing("a region named `container`"))?;
    region.first = first;
    region.last = first + new as i64 - 1;
    for g in f.initial.iter_mut() {
        for x in [&mut g.grain, &mut g.first, &mut g.last]
            .into_iter()
            .flatten()
        {
            if *x > old_last {
                *x += shift;
            }
        }
    }
    let total: u64 = interior.iter().map(|s| s.0).sum();
    let frac = |q: f64| {
        interior
            .iter()
            .filter(|s| s.2 == q)
            .map(|s| s.0)
            .sum::<u64>() as f64
            / total as f64
    };
    let (mmin, mmax) = interior.iter().fold((f64::INFINITY, 0.0f64), |(a, b), s| {
        (a.min(s.1), b.max(s.1))
    });
    Ok(Design {
        key: super::KeyKind::random(i),
        walls,
        sections: n,
        grains: new,
        mass_ratio: mmax / mmin,
        frac_p1: frac(1.0),
        frac_p15: frac(1.5),
        frac_p2: frac(2.0),
        layout,
    })
}

fn perturb(c: &mut ContainerScene, p: Perturbation, k: u64) -> Result<(), Error> {
    match p {
        Perturbation::StrikerSpeed { epsilon } => {
            if k > 0 {
                crate::batch::scenes::perturb_striker(c.file_mut(), k as f64 * epsilon);
            }
        }
        Perturbation::Displacement { amplitude, seed } => {
            let (a, b) = c.container()?;
            let f = c.file_mut();
            // Stream 0 of random containers is never used, so member streams live apart: the
            // member stream is 2^32 + k.
            let mut rng = stream(seed, (1u64 << 32) + k);
            for g in a..=b {
                let u: f64 = rng.gen_range(-1.0..=1.0);
                f.initial.push(InitialFile {
                    grain: Some(g),
                    first: None,
                    last: None,
                    velocity: None,
                    displacement: Some(amplitude * u),
                });
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::batch::SceneSource;
    use grainchain_engine::Scene;
    use std::path::Path;

    fn src() -> SceneSource {
        SceneSource::load(
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/containers/a-standard.toml"),
        )
        .unwrap()
    }

    fn displacements(k: u64, seed: u64) -> Vec<(i64, f64)> {
        let s = src();
        let mut c = s.container();
        let before = c.file().initial.len();
        let p = Perturbation::Displacement {
            amplitude: 1e-12,
            seed,
        };
        c.perturb(p, k).unwrap();
        c.file().initial[before..]
            .iter()
            .map(|g| (g.grain.unwrap(), g.displacement.unwrap()))
            .collect()
    }

    #[test]
    fn displacement_fields_are_seeded_per_member() {
        let a = displacements(3, 1);
        // One entry per container grain (grains 4001-4180 of the scene), within the amplitude.
        assert_eq!(a.len(), 180);
        assert_eq!((a[0].0, a[179].0), (4001, 4180));
        assert!(a.iter().all(|&(_, u)| u.abs() <= 1e-12));
        assert!(a.iter().any(|&(_, u)| u > 0.0) && a.iter().any(|&(_, u)| u < 0.0));
        // The same member and seed: the same field, bit for bit; another member or seed: not.
        assert_eq!(a, displacements(3, 1));
        assert_ne!(a, displacements(4, 1));
        assert_ne!(a, displacements(3, 2));
    }

    #[test]
    fn random_containers_follow_their_distribution() {
        let spec = RandomSpec {
            count: 50,
            members: 1,
            seed: 9,
            template: "a-standard.toml".into(),
            sections: [2, 4],
            grains: [5, 9],
            masses: vec![0.5, 1.0],
            exponents: vec![1.5, 2.0],
            walls: vec![Walls::None, Walls::EndsAndMiddle],
            wall_grains: 20,
            wall_mass: 2.0,
        };
        let s = src();
        for i in 1..=50 {
            let mut c = s.container();
            let striker_before = c.file().initial[0].grain.unwrap();
            let d = c.random_container(&spec, i).unwrap();
            let f = c.file().clone();
            assert!((2..=4).contains(&d.sections), "{d:?}");
            let walls = match d.walls {
                Walls::None => 0,
                _ => 3,
            };
            // Interior grains within [5, 9] per section, plus 20 per wall.
            let interior = d.grains - 20 * walls;
            assert!(interior >= 5 * d.sections as u64 && interior <= 9 * d.sections as u64);
            let r = f.regions.iter().find(|r| r.name == "container").unwrap();
            assert_eq!((r.last - r.first + 1) as u64, d.grains);
            // The striker moved with the container's end: 180 grains before, d.grains now.
            assert_eq!(
                f.initial[0].grain.unwrap(),
                striker_before + d.grains as i64 - 180
            );
            // Same seed and index: the same container.
            assert_eq!(
                s.container().random_container(&spec, i).unwrap().layout,
                d.layout
            );
            // The scene is valid.
            Scene::from_file(f, Path::new("x.toml")).unwrap();
        }
    }
}
