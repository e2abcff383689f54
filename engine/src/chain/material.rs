//! Materials and Hertz's constant of a pair: the physics of a contact between real spheres,
//! below the scene (which builds SI chains from them); reached at `units::` (the façade).

use serde::Serialize;

/// A material.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Material {
    /// Its name, as `grainchain units` prints it.
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

    /// A material from its constants (`name` for messages).
    pub fn custom(density: f64, young: f64, poisson: f64) -> Material {
        Material {
            name: "custom",
            density,
            young,
            poisson,
        }
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
