//! Why a chain cannot be built: below the chain and its builder, which both name it.

use super::law::LawError;

/// Why a chain cannot be built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ChainError {
    /// No sections were given.
    #[error("the chain has no grains")]
    Empty,
    /// A section with zero grains.
    #[error("section {index} ({name}): count must be at least 1")]
    SectionCount {
        /// Position of the section in the builder (0-based).
        index: usize,
        /// Name of the section.
        name: String,
    },
    /// A section whose grain mass is not finite and positive.
    #[error("section {index} ({name}): mass must be a finite number > 0, got {mass}")]
    SectionMass {
        /// Position of the section in the builder (0-based).
        index: usize,
        /// Name of the section.
        name: String,
        /// The rejected mass.
        mass: f64,
    },
    /// A section whose contact law is invalid.
    #[error("section {index} ({name}): {source}")]
    SectionLaw {
        /// Position of the section in the builder (0-based).
        index: usize,
        /// Name of the section.
        name: String,
        /// What is wrong with the law.
        source: LawError,
    },
    /// A section whose damping rate is negative or not finite.
    #[error("section {index} ({name}): damping must be a finite number >= 0, got {damping}")]
    SectionDamping {
        /// Position of the section in the builder (0-based).
        index: usize,
        /// Name of the section.
        name: String,
        /// The rejected damping rate.
        damping: f64,
    },
    /// A wall whose contact law is invalid.
    #[error("{end} wall: {source}")]
    WallLaw {
        /// `"left"` or `"right"`.
        end: &'static str,
        /// What is wrong with the law.
        source: LawError,
    },
    /// The striker's mass is not finite and positive.
    #[error("striker: mass must be a finite number > 0, got {0}")]
    StrikerMass(f64),
    /// The striker's speed is not finite and positive.
    #[error("striker: speed must be a finite number > 0, got {0}")]
    StrikerSpeed(f64),
    /// The striker's own contact law is invalid.
    #[error("striker: {0}")]
    StrikerLaw(LawError),
    /// The striker was put at an end that is a wall (`"left"` or `"right"`).
    #[error("striker: the {0} end is a wall; a striker needs a free end")]
    StrikerAtWall(&'static str),
    /// A precompressed contact (delta0 > 0) in a chain without walls at both ends.
    #[error("precompression needs walls at both ends to hold it")]
    PrecompressionWithoutWalls,
    /// The static contact forces on the two sides of a grain differ beyond round-off, so the
    /// precompressed chain is not in equilibrium.
    #[error(
        "precompression is not in equilibrium at grain {grain}: the contact forces on its two \
         sides are {left} and {right}; give every contact the same static force eta*delta0^p"
    )]
    PrecompressionUnbalanced {
        /// The grain, as its printed grain number (1-based chain grains; a left striker is 0).
        grain: i64,
        /// Static force of the contact on its left.
        left: f64,
        /// Static force of the contact on its right.
        right: f64,
    },
    /// The gravity is not a finite number.
    #[error("gravity must be a finite number, got {0}")]
    Gravity(f64),
    /// Gravity together with a precompression (delta0 > 0): under gravity the builder computes
    /// every contact's static overlap itself (the weight of the grains above it).
    #[error(
        "gravity and precompression (delta0 > 0) together are not supported: under gravity every \
         static overlap is the weight of the grains above the contact, computed by the builder"
    )]
    GravityWithPrecompression,
    /// Gravity in a chain with walls at both ends: its static state is not determined by the
    /// weights alone.
    #[error(
        "gravity with walls at both ends is not supported (the static state between two walls \
         is not determined by the weights); give a free end at the top"
    )]
    GravityBetweenWalls,
    /// The chain (with its striker) has `u32::MAX` grains or more.
    #[error("the chain has {0} grains; at most {max} are supported", max = u32::MAX)]
    TooLong(usize),
    /// Two sections share a name, so a lookup by name would be ambiguous.
    #[error("section {index} ({name}): another section already has this name")]
    DuplicateSection {
        /// Position of the later of the two sections in the builder (0-based).
        index: usize,
        /// The shared name.
        name: String,
    },
    /// A lookup by name found no section of that name.
    #[error("no section named `{name}` (sections: {known})")]
    UnknownSection {
        /// The name looked up.
        name: String,
        /// The chain's section names, comma-separated, in chain order.
        known: String,
    },
    /// A range of sections by name whose first section lies to the right of its last.
    #[error("section `{from}` lies to the right of section `{to}`")]
    SectionsReversed {
        /// Name of the section meant to start the range.
        from: String,
        /// Name of the section meant to end the range.
        to: String,
    },
}
