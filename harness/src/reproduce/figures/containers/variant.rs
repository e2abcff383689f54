//! The variants of container (a) for the comparisons of Fig. 4 and 5: each changes one open
//! choice of the reconstruction (outer chains, interface rule, walls) or the striker's speed.

use crate::batch::scenes;
use crate::batch::scenes::TWIN_EPS;
use crate::batch::{ContainerScene, Part};
use crate::error::Error;
use grainchain_engine::InterfaceRule;

/// A variant of container (a). The order of [`Variant::ALL`] is the order of the runs and of
/// every table that lists them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Variant {
    /// Outer-left and beyond-striker chains cut to half their grains.
    OuterShortened,
    /// The Fig. 3 geometry: free ends 120 grains from the container.
    FreeEnds,
    /// `chain.interface = "max-exponent"`.
    MaxExponent,
    /// `tension = true` on every linear section.
    TwoSidedWalls,
    /// Striker speed x (1 + [`TWIN_EPS`]).
    ChaosTwin,
}

impl Variant {
    /// Every variant, in the order of the runs and of the tables.
    pub const ALL: [Variant; 5] = [
        Variant::OuterShortened,
        Variant::FreeEnds,
        Variant::MaxExponent,
        Variant::TwoSidedWalls,
        Variant::ChaosTwin,
    ];

    /// Its name in the report, the CSV tables and the runs table.
    pub fn key(self) -> &'static str {
        match self {
            Variant::OuterShortened => "outer chains shortened",
            Variant::FreeEnds => "free ends (Fig. 3 geometry)",
            Variant::MaxExponent => "interface max-exponent",
            Variant::TwoSidedWalls => "two-sided linear walls",
            Variant::ChaosTwin => "chaos twin",
        }
    }

    /// What it changes in `containers/a-standard.toml`.
    pub fn change(self) -> &'static str {
        match self {
            Variant::OuterShortened => {
                "outer-left and beyond-striker cut to half their grains (still never reached)"
            }
            Variant::FreeEnds => "outer-left 120 grains, beyond-striker removed: free ends 120 grains from the container, the striker at the chain's end",
            Variant::MaxExponent => "chain.interface = \"max-exponent\"",
            Variant::TwoSidedWalls => "tension = true on every p = 1 section",
            Variant::ChaosTwin => "striker speed x (1 + 1e-12)",
        }
    }

    /// Ends that must stay untouched (false for the free-end variant, whose point is that they
    /// are reached).
    pub fn check_ends(self) -> bool {
        self != Variant::FreeEnds
    }

    /// Run only with `--check-step` (its result is known by construction: see the report).
    pub fn check_only(self) -> bool {
        self == Variant::OuterShortened
    }

    /// A variant of the outer chains (rather than of the container).
    pub fn is_outer_chain(self) -> bool {
        matches!(self, Variant::OuterShortened | Variant::FreeEnds)
    }

    /// Fig. 4 needs the outer-chain variants; Fig. 5 all of them (the outer-chain treatment is
    /// one of its open choices); the shortened chains only with `--check-step`.
    pub fn wanted(self, check_step: bool, fig5: bool) -> bool {
        (check_step || !self.check_only()) && (fig5 || self.is_outer_chain())
    }

    /// Edit container (a) into this variant.
    pub fn apply(self, c: &mut ContainerScene) -> Result<(), Error> {
        match self {
            Variant::OuterShortened => {
                let l = c.count(Part::OuterLeft)?;
                let r = c.count(Part::BeyondStriker)?;
                c.outer_chains(l / 2, r / 2)
            }
            Variant::FreeEnds => c.outer_chains(120, 0),
            Variant::MaxExponent => {
                scenes::set_interface(c.file_mut(), InterfaceRule::MaxExponent);
                Ok(())
            }
            Variant::TwoSidedWalls => {
                if scenes::two_sided_walls(c.file_mut()) == 0 {
                    return Err(c
                        .source()
                        .missing("a linear (p = 1) section for the two-sided-wall variant"));
                }
                Ok(())
            }
            Variant::ChaosTwin => {
                scenes::perturb_striker(c.file_mut(), TWIN_EPS);
                Ok(())
            }
        }
    }
}
