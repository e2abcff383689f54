//! `grainchain export lammps SCENE`: the scene as a LAMMPS input deck (`in.lammps`) and data file
//! (`data.lammps`), for LAMMPS's `pair_style granular` (Debian's `lammps` package, 29 Sep 2021,
//! has it). Everything comes from the checked [`Scene`]: the built chain's masses and the law of
//! every contact as grainchain built it (`Chain::contact_law`, the interface rule and joints
//! already applied), the initial displacements and velocities of the scene's simulation (the
//! striker's speed and `[[initial]]`), its step and output interval. Nothing is re-derived from
//! the scene file.
//!
//! # The mapping (source: <https://docs.lammps.org/pair_granular.html>)
//!
//! LAMMPS's granular normal force on a pair of spheres of radii `R_i`, `R_j` at overlap
//! `delta = R_i + R_j - |r_ij|` is, for the normal models grainchain's laws need,
//!
//! - `hooke`: `F = k_n delta`, so grainchain's linear law (`p = 1`, `F = eta delta`) is
//!   `k_n = eta`;
//! - `hertz`: `F = k_n R_eff^(1/2) delta^(3/2)` with `R_eff = R_i R_j / (R_i + R_j)`, so
//!   grainchain's Hertz law (`p = 3/2`, `F = eta delta^(3/2)`) is `k_n = eta / sqrt(R_eff)`. Every
//!   atom here has the same diameter `d` (a wall atom too), so `R_eff = d / 4` and
//!   `k_n = 2 eta / sqrt(d)`.
//!
//! grainchain's laws carry no radius: only overlaps matter in one dimension. The diameter is a
//! length scale chosen so that no overlap the run's energy allows comes near it: `d` is the
//! smallest power of ten at least ten times the largest overlap any contact can reach with the
//! whole initial energy in it (`delta0 + ((p + 1) E0 / eta)^(1 / (p + 1))`). It is not the beads'
//! diameter of an SI scene; a 2-D or 3-D run with real radii must change `d` and `k_n` together.
//!
//! Contact damping (grainchain: `c delta^q d(delta)/dt`, total force clipped at zero) maps to the
//! damping term `-eta_n v_n` of the same page with `limit_damping` (LAMMPS then clips the total
//! normal force at zero, as grainchain does): `q = 0` (`viscous`, and `scale-respecting` on a
//! linear law) is `damping velocity` with `eta_n0 = c`; `q = 1/2` (`kuwabara-kono`) is `damping
//! viscoelastic`, `eta_n = eta_n0 a m_eff` with `a = sqrt(R_eff delta)`, so
//! `eta_n0 = c / (sqrt(R_eff) m_eff)` with the pair's effective mass. A section's viscous rate `c`
//! (`dv/dt = a - c v`) is `fix viscous` with `gamma = c m`.
//!
//! # The layout
//!
//! Grain `i` (internal index, a left striker 0) is atom `i + 1` on the x axis at its rest
//! position (`x_0 = 0`, each next one `d - delta0` further, so a precompressed contact starts at
//! its `delta0`) plus its initial displacement; its type is its section's (a striker has its
//! own), so every pair of neighbouring types has one law, the one grainchain built for that
//! contact (refused otherwise). A wall is a fixed atom one contact beyond the end grain (its own
//! type, in no integration fix, at rest): grainchain's wall is "a contact with an immovable
//! grain", so the same pair law describes it, where `fix wall/gran` would need its own mapping
//! (a flat wall's `R_eff` is the sphere's radius). Type pairs that are never neighbours get a
//! zero-stiffness `hooke` law: they never touch in the 1-D chain, and the scene defines no law
//! for them (a 2-D or 3-D run must set them). The box is three-dimensional (shrink-wrapped in x,
//! periodic and ten diameters wide in y and z); `fix setforce NULL 0 0` keeps the grains on the
//! axis, and `fix nve` integrates them with velocity Verlet (`run_style verlet`) at the scene's
//! step, shortened as grainchain shortens it so a whole number of steps fits an output interval
//! (an adaptive method's initial step; multirate's fast step everywhere).
//!
//! # What it records
//!
//! Per output interval, the thermo line (`log.lammps`): time, the kinetic energy of the whole
//! chain and of every region (`compute ke`). LAMMPS's granular styles tally no potential energy,
//! so each region is also dumped (`region-<name>.dump`: atom id, x, vx, every output; the region
//! and its two neighbours, whose contacts count half in the region's energy): with the rest
//! positions in the data file, the overlaps and so grainchain's region energies follow. The
//! scene's snapshots are `snapshots.dump` (the snapshot range's atoms at the snapshot times).
//! Pulses, tracks and probes are grainchain's analysis of these and are not in the deck.
//!
//! # What is refused (exit code 2, naming the scene file, the part and why)
//!
//! An exponent other than 1 and 3/2 (LAMMPS has no other power-law normal force), a two-sided
//! (tension) contact (LAMMPS's granular contacts are compression-only), damping with
//! `delta^(1/4)` (`scale-respecting` on a Hertz law: LAMMPS's damping forms go as `delta^0` or
//! `delta^(1/2)`), a type pair whose contacts would need two laws (not possible with one
//! type per section, checked anyway), and gravity (`chain.gravity`: LAMMPS's `fix gravity`
//! would give the body force, but the column's static state on its floor is not exported, and
//! no comparison with LAMMPS checks it yet: refused rather than exported untested).

use crate::error::Error;
use crate::report::atomic::AtomicFile;
use crate::report::csv_number;
use grainchain_engine::{ContactLaw, InputError, Scene};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The input deck's file name.
pub const INPUT: &str = "in.lammps";
/// The data file's file name (read by the deck).
pub const DATA: &str = "data.lammps";
/// The snapshot dump's file name (written by LAMMPS).
pub const SNAPSHOTS: &str = "snapshots.dump";

/// A region's per-output dump.
#[derive(Clone, Debug, PartialEq)]
pub struct RegionDump {
    /// The region's name, as in the scene.
    pub name: String,
    /// The dump's file name (written by LAMMPS in its working directory).
    pub file: String,
    /// The region's grains (internal indices, inclusive).
    pub grains: (usize, usize),
    /// The grains dumped: the region and its neighbours (internal indices, inclusive).
    pub dumped: (usize, usize),
}

/// A scene as LAMMPS input: the deck's and data file's text, and what a reader of LAMMPS's
/// outputs needs to turn them back into grainchain's quantities.
#[derive(Clone, Debug)]
pub struct Deck {
    /// `in.lammps`.
    pub input: String,
    /// `data.lammps`.
    pub data: String,
    /// Every atom's diameter (see the module's mapping).
    pub diameter: f64,
    /// The time step LAMMPS takes.
    pub dt: f64,
    /// Steps per output interval.
    pub steps_per_output: u64,
    /// Output intervals in the run.
    pub outputs: u64,
    /// Rest position (x) of every grain, by internal index: a grain's displacement is its atom's
    /// x minus this.
    pub rest: Vec<f64>,
    /// The regions' dumps, in the scene's order (empty without `output.energies`).
    pub regions: Vec<RegionDump>,
    /// Output indices at which [`SNAPSHOTS`] holds a frame (empty without snapshots).
    pub snapshots: Vec<u64>,
}

/// How a contact is named in a refusal: the scene key it comes from and words for it.
fn contact_words(scene: &Scene, k: usize) -> (String, String) {
    let chain = scene.chain();
    let n = chain.len();
    let section_of = |i: usize| {
        chain
            .sections()
            .iter()
            .find(|s| s.first <= i && i <= s.last)
    };
    if k == 0 {
        return ("chain.left".into(), "the left wall's contact".into());
    }
    if k == n {
        return ("chain.right".into(), "the right wall's contact".into());
    }
    match (section_of(k - 1), section_of(k)) {
        (Some(a), Some(b)) if a.name == b.name => (
            "chain.sections".into(),
            format!("the contacts of section `{}`", a.name),
        ),
        (Some(a), Some(b)) => (
            "chain.interface".into(),
            format!(
                "the contact between sections `{}` and `{}` (the interface rule's or a joint's law)",
                a.name, b.name
            ),
        ),
        _ => ("striker".into(), "the striker's contact".into()),
    }
}

/// The LAMMPS `pair_coeff` arguments (after the two types) of a law at effective radius
/// `r_eff` between grains of effective mass `m_eff`, or why it cannot be one.
fn pair_args(law: &ContactLaw, r_eff: f64, m_eff: f64) -> Result<String, String> {
    if law.tension {
        return Err(
            "two-sided (`tension = true`), and LAMMPS's granular contacts are \
             compression-only (a pair beyond contact feels no force)"
                .into(),
        );
    }
    let normal = if law.p == 1.0 {
        format!("hooke {}", csv_number(law.eta))
    } else if law.p == 1.5 {
        format!("hertz {}", csv_number(law.eta / r_eff.sqrt()))
    } else {
        return Err(format!(
            "p = {}, and LAMMPS's pair_style granular has only the hooke (p = 1) and hertz \
             (p = 3/2) normal forces",
            law.p
        ));
    };
    let (eta_n0, model, limit) = match law.damping {
        None => (0.0, "velocity", ""),
        Some(d) => {
            let q = d.model.exponent(law.p);
            if q == 0.0 {
                (d.c, "velocity", " limit_damping")
            } else if q == 0.5 {
                (
                    d.c / (r_eff.sqrt() * m_eff),
                    "viscoelastic",
                    " limit_damping",
                )
            } else {
                return Err(format!(
                    "`{}` damping, force c delta^{} d(delta)/dt, and LAMMPS's damping forms go \
                     as delta^0 (velocity) or delta^(1/2) (viscoelastic)",
                    d.model.name(),
                    q
                ));
            }
        }
    };
    Ok(format!(
        "{normal} {} tangential linear_nohistory 0.0 0.0 damping {model}{limit}",
        csv_number(eta_n0)
    ))
}

/// A name LAMMPS takes as a group or compute ID: letters, digits and underscores.
fn ident(prefix: &str, k: usize, name: &str) -> String {
    let clean: String = name
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    format!("{prefix}{k}_{clean}")
}

/// The scene as a LAMMPS deck, or a refusal naming the scene file, the part that cannot be
/// represented and why (see the module).
pub fn deck(scene: &Scene) -> Result<Deck, InputError> {
    let refuse = |key: String, message: String| InputError::Invalid {
        file: scene.path().to_path_buf(),
        key,
        message: format!("cannot export to LAMMPS: {message}"),
    };
    let chain = scene.chain();
    if chain.gravity() != 0.0 {
        return Err(refuse(
            "chain.gravity".into(),
            "gravity is not exported (LAMMPS's `fix gravity` would give the body force, but \
             the column's static state on its floor is not mapped, and no comparison with LAMMPS \
             checks it)"
                .into(),
        ));
    }
    let n = chain.len();
    let mass = chain.mass();
    let sim = scene.simulation().map_err(|e| {
        refuse(
            "chain".into(),
            format!("its simulation cannot be built: {e}"),
        )
    })?;
    let state = sim.state();
    let energy = sim.initial_energy();

    // Every contact's law, as grainchain built it.
    let laws: Vec<Option<ContactLaw>> = (0..=n).map(|k| chain.contact_law(k)).collect();

    // The diameter: overlaps stay below a tenth of it.
    let mut reach: f64 = 0.0;
    for law in laws.iter().flatten() {
        let free = ((law.p + 1.0) * energy.max(0.0) / law.eta).powf(1.0 / (law.p + 1.0));
        reach = reach.max(law.delta0 + free);
    }
    let diameter = if reach > 0.0 && reach.is_finite() {
        10f64.powf((10.0 * reach).log10().ceil())
    } else {
        1.0
    };
    let r_eff = diameter / 4.0;

    // Types: one per section, one per grain in none (a striker), one per wall.
    let mut names: Vec<String> = Vec::new();
    let mut type_of = vec![0usize; n];
    for (s, span) in chain.sections().iter().enumerate() {
        names.push(span.name.clone());
        for t in &mut type_of[span.first..=span.last] {
            *t = s + 1;
        }
    }
    for (i, t) in type_of.iter_mut().enumerate() {
        if *t == 0 {
            let is_striker = chain.striker().is_some_and(|(s, _)| s == i);
            names.push(if is_striker {
                "striker".into()
            } else {
                format!("grain {}", chain.grain_number(i))
            });
            *t = names.len();
        }
    }
    let wall_type = |names: &mut Vec<String>, side: &str| {
        names.push(format!("{side} wall"));
        names.len()
    };
    let left_wall = laws[0].map(|_| wall_type(&mut names, "left"));
    let right_wall = laws[n].map(|_| wall_type(&mut names, "right"));
    // A wall atom's mass: its neighbour's (it is never integrated; the mass enters only
    // viscoelastic damping's m_eff, computed with it).
    let wall_mass = |i: usize| mass[i];

    // Pair laws by (type, type), the lower type first; conflicting laws are refused.
    let mut pairs: BTreeMap<(usize, usize), (ContactLaw, f64, usize)> = BTreeMap::new();
    for (k, law) in laws.iter().enumerate() {
        let Some(law) = law else { continue };
        let (ta, tb, ma, mb) = if k == 0 {
            (left_wall.unwrap_or(0), type_of[0], wall_mass(0), mass[0])
        } else if k == n {
            (
                type_of[n - 1],
                right_wall.unwrap_or(0),
                mass[n - 1],
                wall_mass(n - 1),
            )
        } else {
            (type_of[k - 1], type_of[k], mass[k - 1], mass[k])
        };
        let key = (ta.min(tb), ta.max(tb));
        let m_eff = ma * mb / (ma + mb);
        match pairs.get(&key) {
            None => {
                pairs.insert(key, (*law, m_eff, k));
            }
            Some((other, m_other, k_other)) => {
                let damped = law.damping.is_some();
                if other != law || (damped && *m_other != m_eff) {
                    let (key_a, a) = contact_words(scene, *k_other);
                    let (_, b) = contact_words(scene, k);
                    return Err(refuse(
                        key_a,
                        format!(
                            "{a} and {b} join the same pair of LAMMPS atom types but differ \
                             (law or effective mass), and a type pair has one law"
                        ),
                    ));
                }
            }
        }
    }
    let mut coeffs = Vec::new();
    for (&(a, b), (law, m_eff, k)) in &pairs {
        let args = pair_args(law, r_eff, *m_eff).map_err(|why| {
            let (key, what) = contact_words(scene, *k);
            refuse(key, format!("{what}: {why}"))
        })?;
        coeffs.push(format!("pair_coeff {a} {b} {args}"));
    }

    // Rest positions: each contact's spacing is d - delta0.
    let mut rest = vec![0.0; n];
    for i in 1..n {
        let delta0 = laws[i].map_or(0.0, |l| l.delta0);
        rest[i] = rest[i - 1] + (diameter - delta0);
    }

    // Step and schedule, as grainchain's run takes them.
    let interval = scene.output_interval();
    let steps_per_output = scene.params().steps_per_output(interval).max(1);
    let dt = interval / steps_per_output as f64;
    let outputs = scene.outputs();

    // The data file.
    let types = names.len();
    let walls = usize::from(left_wall.is_some()) + usize::from(right_wall.is_some());
    let atoms = n + walls;
    let volume = std::f64::consts::PI / 6.0 * diameter.powi(3);
    let lo = rest[0] - 2.0 * diameter;
    let hi = rest[n - 1] + 2.0 * diameter;
    let half = 5.0 * diameter;
    let mut data = String::new();
    let num = csv_number;
    let _ = writeln!(
        data,
        "LAMMPS data file of grainchain scene `{}` ({}), written by {}\n",
        scene.name(),
        scene.path().display(),
        crate::program()
    );
    let _ = writeln!(data, "{atoms} atoms\n{types} atom types\n");
    let _ = writeln!(data, "{} {} xlo xhi", num(lo), num(hi));
    let _ = writeln!(data, "{} {} ylo yhi", num(-half), num(half));
    let _ = writeln!(data, "{} {} zlo zhi\n", num(-half), num(half));
    let _ = writeln!(
        data,
        "Atoms # sphere: id type diameter density x y z (density = mass / (pi d^3 / 6))\n"
    );
    let mut atom_line = |id: usize, t: usize, m: f64, x: f64| {
        let _ = writeln!(
            data,
            "{id} {t} {} {} {} 0 0",
            num(diameter),
            num(m / volume),
            num(x)
        );
    };
    for i in 0..n {
        atom_line(i + 1, type_of[i], mass[i], rest[i] + state.u[i]);
    }
    let mut wall_ids = Vec::new();
    if let (Some(t), Some(law)) = (left_wall, laws[0]) {
        wall_ids.push(n + wall_ids.len() + 1);
        atom_line(
            n + wall_ids.len(),
            t,
            wall_mass(0),
            rest[0] - (diameter - law.delta0),
        );
    }
    if let (Some(t), Some(law)) = (right_wall, laws[n]) {
        wall_ids.push(n + wall_ids.len() + 1);
        atom_line(
            n + wall_ids.len(),
            t,
            wall_mass(n - 1),
            rest[n - 1] + (diameter - law.delta0),
        );
    }
    let _ = writeln!(data, "\nVelocities # id vx vy vz wx wy wz\n");
    for i in 0..n {
        let _ = writeln!(data, "{} {} 0 0 0 0 0", i + 1, num(state.v[i]));
    }
    for id in &wall_ids {
        let _ = writeln!(data, "{id} 0 0 0 0 0 0");
    }

    // The deck.
    let mut input = String::new();
    let w = &mut input;
    let _ = writeln!(
        w,
        "# grainchain scene `{}` ({}) for LAMMPS, written by {}",
        scene.name(),
        scene.path().display(),
        crate::program()
    );
    if !scene.description().is_empty() {
        let _ = writeln!(w, "# {}", scene.description());
    }
    let _ = writeln!(
        w,
        "# Run it in this folder: lmp -in {INPUT}. The mapping of grainchain's laws to \
         pair_style granular\n# (https://docs.lammps.org/pair_granular.html): linear F = eta \
         delta is hooke k_n = eta; Hertz\n# F = eta delta^(3/2) is hertz k_n = eta / \
         sqrt(R_eff), R_eff = d / 4 with every diameter d = {}.\n# Grain i (grainchain's \
         internal index; printed grain number i + {}) is atom i + 1.",
        num(diameter),
        chain.grain_number(0)
    );
    let _ = writeln!(w, "# Atom types:");
    for (t, name) in names.iter().enumerate() {
        let _ = writeln!(w, "#   {} {name}", t + 1);
    }
    if scene.params().method.name() != "verlet" {
        let _ = writeln!(
            w,
            "# grainchain integrates this scene with {}; LAMMPS with velocity Verlet at the step \
             below.",
            scene.params().method.name()
        );
    }
    if scene.params().sleep.is_some() {
        let _ = writeln!(
            w,
            "# The scene's sleep rule (an approximation) is not exported: every grain is \
             integrated."
        );
    }
    let _ = writeln!(w);
    let units = if scene.is_si() { "si" } else { "lj" };
    let _ = writeln!(
        w,
        "units {units}\ndimension 3\nboundary s p p\natom_style sphere\natom_modify map array\n\
         comm_modify vel yes\nread_data {DATA}\n"
    );
    let _ = writeln!(
        w,
        "group grains id 1:{n}\ngroup walls subtract all grains\n\npair_style granular"
    );
    let _ = writeln!(
        w,
        "# Type pairs that are never neighbours never touch in the chain: no law (zero stiffness)."
    );
    let _ = writeln!(
        w,
        "pair_coeff * * hooke 0.0 0.0 tangential linear_nohistory 0.0 0.0 damping velocity"
    );
    for c in &coeffs {
        let _ = writeln!(w, "{c}");
    }
    let _ = writeln!(
        w,
        "\nneighbor {} bin\nneigh_modify delay 0 every 1 check yes\n",
        num(diameter / 10.0)
    );
    for (s, span) in chain.sections().iter().enumerate() {
        if span.damping > 0.0 {
            let g = ident("damped", s + 1, &span.name);
            let _ = writeln!(
                w,
                "group {g} id {}:{}\nfix {g} {g} viscous {}",
                span.first + 1,
                span.last + 1,
                num(span.damping * span.mass)
            );
        }
    }
    let _ = writeln!(
        w,
        "run_style verlet\ntimestep {}\nfix integrate grains nve\nfix axis grains setforce NULL \
         0.0 0.0\n",
        num(dt)
    );

    // Thermo: time, kinetic energy of the chain and of every region, every output.
    let _ = writeln!(w, "compute ke grains ke");
    let mut columns = vec!["step".to_string(), "time".into(), "c_ke".into()];
    let mut regions = Vec::new();
    for (r, region) in scene.regions().iter().enumerate() {
        let (first, last) = scene
            .region_grains(&region.name)
            .map(|g| (*g.start(), *g.end()))
            .map_err(|e| refuse("regions".into(), e.to_string()))?;
        let g = ident("region", r + 1, &region.name);
        let _ = writeln!(
            w,
            "group {g} id {}:{}\ncompute ke_{g} {g} ke",
            first + 1,
            last + 1
        );
        columns.push(format!("c_ke_{g}"));
        if scene.output().energies {
            let dumped = (first.saturating_sub(1), (last + 1).min(n - 1));
            // A file name LAMMPS reads as one word, whatever the region's name holds.
            let safe: String = region
                .name
                .chars()
                .map(|c| {
                    if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                        c
                    } else {
                        '_'
                    }
                })
                .collect();
            let file = format!("region-{safe}.dump");
            let _ = writeln!(
                w,
                "group dump_{g} id {}:{}\ndump {g} dump_{g} custom {steps_per_output} {file} id \
                 x vx\ndump_modify {g} sort id format float %.17g",
                dumped.0 + 1,
                dumped.1 + 1
            );
            regions.push(RegionDump {
                name: region.name.clone(),
                file,
                grains: (first, last),
                dumped,
            });
        }
    }
    let _ = writeln!(
        w,
        "thermo_style custom {}\nthermo_modify norm no format float %.17g\nthermo \
         {steps_per_output}\n",
        columns.join(" ")
    );

    // Snapshots at their output times, else one run.
    let mut snapshots = Vec::new();
    let snap_spec = scene.output().snapshots.as_ref();
    if let Some(spec) = snap_spec {
        let first = chain.index_of(spec.first).unwrap_or(0);
        let last = chain.index_of(spec.last).unwrap_or(n - 1);
        let _ = writeln!(w, "group snapshot id {}:{}", first + 1, last + 1);
        let schedule = spec.schedule();
        snapshots = (0..=outputs).filter(|&k| schedule.wants(k)).collect();
    }
    let write_snap = |w: &mut String| {
        let _ = writeln!(
            w,
            "write_dump snapshot custom {SNAPSHOTS} id x vx modify sort id format float %.17g \
             append yes"
        );
    };
    let mut done = 0;
    for &k in &snapshots {
        if k > done {
            let _ = writeln!(w, "run {}", (k - done) * steps_per_output);
            done = k;
        }
        write_snap(w);
    }
    if outputs > done {
        let _ = writeln!(w, "run {}", (outputs - done) * steps_per_output);
    }
    Ok(Deck {
        input,
        data,
        diameter,
        dt,
        steps_per_output,
        outputs,
        rest,
        regions,
        snapshots,
    })
}

/// Write [`INPUT`] and [`DATA`] into `dir` (each complete or not at all); returns their names.
pub fn write(deck: &Deck, dir: &Path) -> Result<Vec<String>, Error> {
    AtomicFile::write_all(dir.join(DATA), deck.data.as_bytes())?;
    AtomicFile::write_all(dir.join(INPUT), deck.input.as_bytes())?;
    Ok(vec![DATA.to_string(), INPUT.to_string()])
}

/// The default output folder of `grainchain export lammps`: `out/lammps-<scene name>`.
pub fn default_out_dir(scene: &Scene) -> PathBuf {
    PathBuf::from(format!("out/lammps-{}", scene.name()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A striker (m = 2) on three Hertz beads (eta = 100) against a linear wall (eta = 50), the
    /// expected deck worked out by hand from the module's mapping.
    #[test]
    fn the_deck_carries_the_mapping() {
        let text = "[chain]\nright = { kind = \"wall\", p = 1.0, eta = 50.0 }\n\
            [[chain.sections]]\nname = \"beads\"\ncount = 3\nmass = 1.0\np = 1.5\neta = 100.0\n\
            [striker]\nend = \"left\"\nmass = 2.0\nspeed = 1.0\n\
            [integrator]\nmethod = \"verlet\"\ndt = 0.003\n\
            [run]\nduration = 1.0\noutput_interval = 0.125\n";
        let scene = Scene::parse(text, Path::new("mapping.toml")).expect("scene");
        let deck = deck(&scene).expect("exports");
        // E0 = 1: the linear wall's reach sqrt(2 E0 / 50) = 0.2 is the largest (the Hertz
        // beads': (2.5 E0 / 100)^0.4 = 0.023); ten times it is 2, so d = 10.
        assert_eq!(deck.diameter, 10.0);
        assert_eq!(deck.rest, vec![0.0, 10.0, 20.0, 30.0]);
        // 0.125 / 0.003 = 41.7: 42 steps per output, as grainchain's run takes them.
        assert_eq!(deck.steps_per_output, 42);
        assert_eq!(deck.dt, 0.125 / 42.0);
        assert_eq!(deck.outputs, 8);
        // Types: beads 1, striker 2, right wall 3; Hertz k_n = eta / sqrt(d / 4).
        let kn = 100.0 / 2.5f64.sqrt();
        let tail = "0 tangential linear_nohistory 0.0 0.0 damping velocity";
        for line in [
            format!("pair_coeff 1 1 hertz {kn} {tail}"),
            format!("pair_coeff 1 2 hertz {kn} {tail}"),
            format!("pair_coeff 1 3 hooke 50 {tail}"),
        ] {
            assert!(deck.input.contains(&line), "{line}\n{}", deck.input);
        }
        // Atoms: id type diameter density x; the striker moving at 1, the wall one diameter
        // beyond the last bead.
        let volume = std::f64::consts::PI / 6.0 * 1000.0;
        for line in [
            format!("1 2 10 {} 0 0 0", 2.0 / volume),
            format!("4 1 10 {} 30 0 0", 1.0 / volume),
            format!("5 3 10 {} 40 0 0", 1.0 / volume),
            "1 1 0 0 0 0 0".to_string(),
        ] {
            assert!(
                deck.data.lines().any(|l| l == line),
                "{line}\n{}",
                deck.data
            );
        }
        assert!(deck.input.contains("run 336"), "8 outputs of 42 steps");
    }
}
