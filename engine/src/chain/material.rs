//! Materials and Hertz's constant of a pair: the physics of a contact between real spheres,
//! below the scene (which builds SI chains from them); reached at `units::` (the façade).

use serde::Serialize;

/// A material.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Material {
    /// Its name, as `grainchain units` and every output print it: the table's, the one a file
    /// gives an explicit material, or one made of its constants ([`constants_name`]).
    pub name: &'static str,
    /// Density, kg/m^3.
    pub density: f64,
    /// Young's modulus, Pa.
    pub young: f64,
    /// Poisson ratio.
    pub poisson: f64,
}

/// Stainless steel (AISI 316-like): 8000 kg/m^3, 193 GPa, 0.30.
pub const STAINLESS_STEEL: Material = Material {
    name: "stainless steel (AISI 316-like)",
    density: 8000.0,
    young: 193e9,
    poisson: 0.30,
};

/// Chrome or carbon steel (bearing balls, AISI 52100-like): 7800 kg/m^3, 200 GPa, 0.29.
pub const STEEL: Material = Material {
    name: "steel",
    density: 7800.0,
    young: 200e9,
    poisson: 0.29,
};

/// Brass (CW614N-like): 8500 kg/m^3, 103 GPa, 0.34.
pub const BRASS: Material = Material {
    name: "brass",
    density: 8500.0,
    young: 103e9,
    poisson: 0.34,
};

/// Aluminium alloy (6061-like): 2700 kg/m^3, 69 GPa, 0.33.
pub const ALUMINIUM: Material = Material {
    name: "aluminium",
    density: 2700.0,
    young: 69e9,
    poisson: 0.33,
};

/// PTFE (Teflon): 2200 kg/m^3, 1.46 GPa, 0.46, the values of Daraio, Nesterenko, Herbold and
/// Jin, PRE 73, 026610 (2006), whose PTFE chains are the soft half of the steel/PTFE designs.
pub const PTFE: Material = Material {
    name: "ptfe",
    density: 2200.0,
    young: 1.46e9,
    poisson: 0.46,
};

/// Soda-lime glass: 2500 kg/m^3, 70 GPa, 0.22.
pub const GLASS: Material = Material {
    name: "glass",
    density: 2500.0,
    young: 70e9,
    poisson: 0.22,
};

/// Tungsten carbide (cobalt-bonded): 15600 kg/m^3, 600 GPa, 0.22.
pub const TUNGSTEN_CARBIDE: Material = Material {
    name: "tungsten carbide",
    density: 15600.0,
    young: 600e9,
    poisson: 0.22,
};

/// The materials scene and design files name, by their key: typical data-sheet values (a
/// grade's own sheet may differ by 5-10 %; a scene may give `{ E, nu, rho }` instead).
pub const MATERIALS: [(&str, Material); 7] = [
    ("steel", STEEL),
    ("stainless-steel", STAINLESS_STEEL),
    ("brass", BRASS),
    ("aluminium", ALUMINIUM),
    ("ptfe", PTFE),
    ("glass", GLASS),
    ("tungsten-carbide", TUNGSTEN_CARBIDE),
];

impl Material {
    /// The material called `key` in [`MATERIALS`], or `None`.
    pub fn by_key(key: &str) -> Option<Material> {
        MATERIALS.iter().find(|(k, _)| *k == key).map(|(_, m)| *m)
    }

    /// The material called `key` in [`MATERIALS`], or the one message of an unknown name (scene
    /// files, design files and Python give it; the caller adds the file and key).
    pub fn named(key: &str) -> Result<Material, String> {
        Material::by_key(key).ok_or_else(|| {
            format!(
                "unknown material `{key}` (known: {}; or give its constants E, nu, rho and an \
                 optional name)",
                MATERIALS.map(|(k, _)| k).join(", ")
            )
        })
    }

    /// A material from its constants, unchecked ([`Material::explicit`] checks), named by them
    /// ([`constants_name`]).
    pub fn custom(density: f64, young: f64, poisson: f64) -> Material {
        Material {
            name: intern(&constants_name(young, poisson, density)),
            density,
            young,
            poisson,
        }
    }

    /// The one validator of a material given by its constants (scene files, design files,
    /// Python): `E` (Pa), `nu` and `rho` (kg/m^3) as [`Material::problem`] wants them, `name`
    /// as [`name_problem`] wants it; without a name, one made of the constants
    /// ([`constants_name`]), so that two materials never print alike. The error is the one
    /// message; the caller adds the file and key.
    pub fn explicit(
        name: Option<&str>,
        young: f64,
        poisson: f64,
        density: f64,
    ) -> Result<Material, String> {
        if let Some(n) = name {
            if let Some(p) = name_problem(n) {
                return Err(p);
            }
        }
        let m = Material::custom(density, young, poisson);
        if let Some(p) = m.problem() {
            return Err(p);
        }
        Ok(match name {
            Some(n) => Material {
                name: intern(n),
                ..m
            },
            None => m,
        })
    }

    /// What is wrong with the constants, if anything: density within [`DENSITY_RANGE_KG_M3`],
    /// Young's modulus within [`YOUNG_RANGE_PA`], Poisson's ratio in (-1, 1/2] (thermodynamic
    /// bounds of an isotropic solid).
    pub fn problem(&self) -> Option<String> {
        let (lo, hi) = DENSITY_RANGE_KG_M3;
        if !(self.density >= lo && self.density <= hi) {
            return Some(format!(
                "density rho must lie in [{lo}, {hi}] kg/m^3 (the solids from aerogels to beyond \
                 osmium), got {}",
                crate::number::Num(self.density)
            ));
        }
        let (lo, hi) = YOUNG_RANGE_PA;
        if !(self.young >= lo && self.young <= hi) {
            return Some(format!(
                "Young's modulus E must lie in [{lo:e}, {hi:e}] Pa (the solids from soft gels to \
                 beyond diamond), got {}",
                crate::number::Num(self.young)
            ));
        }
        if !(self.poisson > -1.0 && self.poisson <= 0.5) {
            return Some(format!(
                "Poisson's ratio nu must lie in (-1, 0.5], got {}",
                crate::number::Num(self.poisson)
            ));
        }
        None
    }

    /// `(1 - nu^2) / E`, the material's share of the pair's compliance `1 / E*`.
    fn compliance(&self) -> f64 {
        (1.0 - self.poisson * self.poisson) / self.young
    }

    /// Mass of a sphere of diameter `d` metres, kg: `rho pi d^3 / 6`.
    pub fn sphere_mass(&self, d: f64) -> f64 {
        self.density * std::f64::consts::PI * d.powi(3) / 6.0
    }
}

/// Hertz's constant of two elastic spheres in contact, N/m^1.5: the force is
/// `F = eta delta^(3/2)` with `eta = (4/3) E* sqrt(R*)`, `1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2`,
/// `1/R* = 1/R1 + 1/R2` (K. L. Johnson, *Contact Mechanics*, Cambridge 1985, section 4.2,
/// Eq. 4.22-4.23; Landau and Lifshitz, *Theory of Elasticity*, section 9). Diameters `d1`, `d2` in
/// metres. For two equal spheres it is Hong's Eq. 1, `E sqrt(2R) / (3 (1 - nu^2))`.
pub fn hertz_eta(m1: &Material, d1: f64, m2: &Material, d2: f64) -> f64 {
    let (r1, r2) = (0.5 * d1, 0.5 * d2);
    let e_star = 1.0 / (m1.compliance() + m2.compliance());
    let r_star = r1 * r2 / (r1 + r2);
    4.0 / 3.0 * e_star * r_star.sqrt()
}

/// Hertz's constant of a sphere (material `m`, diameter `d`) against a flat wall of material
/// `wall`, N/m^1.5: [`hertz_eta`] with the wall's radius infinite, `R* = R`.
pub fn hertz_eta_flat(m: &Material, d: f64, wall: &Material) -> f64 {
    let e_star = 1.0 / (m.compliance() + wall.compliance());
    4.0 / 3.0 * e_star * (0.5 * d).sqrt()
}

/// The densities a material may have, kg/m^3: from the lightest solids (silica aerogels, about
/// 1 kg/m^3) to four times the densest element (osmium, 22,590 kg/m^3). Outside it a grain is no
/// solid sphere, and the masses and time units leave what an `f64` holds well (issue 38: a
/// density of 1e300 made every force 0 N, and the design search failed on an internal setting).
pub const DENSITY_RANGE_KG_M3: (f64, f64) = (1.0, 1e5);

/// The Young's moduli a material may have, Pa: from soft gels (about 1 kPa) to ten times
/// diamond's (about 1.1e12 Pa), for the same reasons (a modulus of 1e-300 Pa made a contact
/// last longer than any run).
pub const YOUNG_RANGE_PA: (f64, f64) = (1e3, 1e13);

/// The grain diameters `grainchain units` accepts, metres: from a micrometre (below it a grain
/// is a colloid, where adhesion and Brownian motion matter more than Hertz's law) to a metre
/// (boulders); Hertz's law needs elastic, smooth spheres and holds over that whole range. Outside
/// it the mass or the time unit also leaves what an `f64` holds well (`1e-300` m gives a mass of
/// 0 kg and an infinite time unit).
pub const DIAMETER_RANGE_M: (f64, f64) = (1e-6, 1.0);

/// The one validator of a diameter, m (scene files, the protector, design files, Python):
/// within [`DIAMETER_RANGE_M`]. The message says what is wrong; the caller adds where.
pub fn diameter_problem(d: f64) -> Option<String> {
    let (lo, hi) = DIAMETER_RANGE_M;
    if d >= lo && d <= hi {
        return None;
    }
    Some(format!(
        "a diameter must lie in [{lo:e}, {hi}] m (Hertz's elastic spheres, from above colloids \
         to boulders), got {}",
        crate::number::Num(d)
    ))
}

/// The longest name of an explicit material, characters.
pub const MAX_NAME_CHARS: usize = 40;

/// What is wrong with the name a file gives an explicit material, if anything: 1 to
/// [`MAX_NAME_CHARS`] characters without quotes, `|` or control characters (it is printed
/// into quoted CSV fields and Markdown tables), no space at either end, and not a key of
/// [`MATERIALS`] (a name is how every output tells materials apart).
pub fn name_problem(name: &str) -> Option<String> {
    let chars = name.chars().count();
    let bad = name.chars().any(|c| c == '"' || c == '|' || c.is_control());
    if chars == 0 || chars > MAX_NAME_CHARS || bad || name.trim() != name {
        return Some(format!(
            "a material's name must be 1 to {MAX_NAME_CHARS} characters without quotes, `|`, \
             control characters or spaces at either end, got {name:?}"
        ));
    }
    if Material::by_key(name).is_some() {
        return Some(format!(
            "`{name}` is a material of the table; give yours another name (or leave `name` out)"
        ));
    }
    None
}

/// The name of an explicit material given no name: its constants, each the shortest text that
/// reads back to the same number (`E=2e11,nu=0.3,rho=7900`), so that two materials with
/// different constants never share one.
pub fn constants_name(young: f64, poisson: f64, density: f64) -> String {
    format!("E={young:e},nu={poisson},rho={density}")
}

/// The name as a `&'static str` (a material stays `Copy`, the search copies beads by the
/// million): each distinct name is kept once for the life of the process, so the memory is
/// bounded by the names a process reads, not by how often it reads them.
fn intern(name: &str) -> &'static str {
    use std::collections::HashSet;
    use std::sync::{Mutex, OnceLock};
    static NAMES: OnceLock<Mutex<HashSet<&'static str>>> = OnceLock::new();
    let mut names = NAMES
        .get_or_init(Default::default)
        .lock()
        .unwrap_or_else(|e| e.into_inner());
    if let Some(n) = names.get(name) {
        return n;
    }
    let n: &'static str = Box::leak(name.to_owned().into_boxed_str());
    names.insert(n);
    n
}

/// A sphere of a material.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Bead {
    /// Its material.
    pub material: Material,
    /// Its diameter, m.
    pub diameter: f64,
}

impl Bead {
    /// Its mass, kg.
    pub fn mass(&self) -> f64 {
        self.material.sphere_mass(self.diameter)
    }

    /// What is wrong with it, if anything: [`Material::problem`], then [`diameter_problem`].
    pub fn problem(&self) -> Option<String> {
        self.material
            .problem()
            .or_else(|| diameter_problem(self.diameter))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An explicit material is named as given, or by its constants, which tell two materials
    /// apart (the outputs' names, issue 39); the same name is kept once however often it is read.
    #[test]
    fn explicit_materials_are_named_apart() {
        let a = Material::explicit(None, 2e11, 0.3, 7900.0).unwrap();
        let b = Material::explicit(None, 2e11, 0.3, 7901.0).unwrap();
        assert_eq!(a.name, "E=2e11,nu=0.3,rho=7900");
        assert_ne!(a.name, b.name);
        let c = Material::explicit(Some("maraging"), 2e11, 0.3, 7900.0).unwrap();
        assert_eq!(c.name, "maraging");
        assert_eq!(
            (c.young, c.poisson, c.density),
            (a.young, a.poisson, a.density)
        );
        let again = Material::explicit(Some("maraging"), 1e9, 0.3, 1000.0).unwrap();
        assert!(std::ptr::eq(c.name, again.name), "one copy of a name");
        for bad in [
            "",
            " x",
            "x ",
            "a\"b",
            "a|b",
            "a\nb",
            "steel",
            &"x".repeat(41),
        ] {
            assert!(
                Material::explicit(Some(bad), 2e11, 0.3, 7900.0).is_err(),
                "{bad:?}"
            );
        }
        assert!(Material::explicit(Some(&"x".repeat(40)), 2e11, 0.3, 7900.0).is_ok());
        // The constants are checked whatever the name.
        assert!(Material::explicit(Some("ok"), 2e11, 0.7, 7900.0)
            .unwrap_err()
            .contains("Poisson"));
        assert!(Material::named("steel").is_ok());
        assert!(Material::named("stel")
            .unwrap_err()
            .contains("unknown material `stel`"));
    }

    /// The ends of the diameter range pass, beyond them and non-numbers do not.
    #[test]
    fn the_diameter_validator_takes_the_range() {
        let (lo, hi) = DIAMETER_RANGE_M;
        for d in [lo, 6e-3, hi] {
            assert_eq!(diameter_problem(d), None, "{d}");
        }
        for d in [0.0, lo * 0.999, hi * 1.001, f64::NAN, f64::INFINITY, -1.0] {
            assert!(diameter_problem(d).is_some(), "{d}");
        }
    }
}
