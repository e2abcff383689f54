//! The numbers Hong (2005), PRL 94, 108001, states: its program units and every figure's value
//! that grainchain compares with (`docs/paper.md` lists them, with the paper's setting and the
//! project's reading of each). One module, so `reproduce`, `study`, the problem catalogue and the unit
//! conversion never disagree about what the paper says.

/// Length unit: 1e-5 m (a grain diameter is 100 of them).
pub const LENGTH_M: f64 = 1e-5;
/// Mass unit: 2.36e-5 kg.
pub const MASS_KG: f64 = 2.36e-5;
/// Time unit: 1.0102e-3 s.
pub const TIME_S: f64 = 1.0102e-3;
/// Grain diameter in length units (1 mm).
pub const DIAMETER: f64 = 100.0;
/// Stiffness eta of the Hertz contact between two grains, in program units.
pub const ETA: f64 = 5657.0;
/// The paper's time step, in time units.
pub const DT: f64 = 1.25e-5;
/// Time between snapshots (1e4 steps of [`DT`]), in time units.
pub const SNAPSHOT_INTERVAL: f64 = 0.125;

/// Fig. 5: the universal exponent of `E_R(t) = A t^-gamma`, the same for every container.
pub const GAMMA: f64 = 0.7055;
/// Fig. 5: time rescaling alpha per container. The text rescales (c), (d) and (e) by 2, 0.22
/// and 9 and chooses alpha = 1 for the standard container (a); (b) is plotted without
/// rescaling, which is alpha = 1 (the text names no value for it: `docs/paper.md`; the
/// caption's 2/9 for (d) is 0.22).
pub const ALPHA: [(&str, f64); 5] = [("a", 1.0), ("b", 1.0), ("c", 2.0), ("d", 0.22), ("e", 9.0)];
/// Fig. 3: the leading wave leaving the container at the right, % of the incident energy.
pub const RIGHT_PERCENT: f64 = 3.3;
/// Fig. 3: the leading wave leaving the container at the left, % of the incident energy.
pub const LEFT_PERCENT: f64 = 7.7;
/// Fig. 1: the number of transmitted waves is "about the mass ratio".
pub const MASS_RATIO: f64 = 10.0;
/// Fig. 3 text: a solitary wave is about 5 grains wide.
pub const WAVE_GRAINS: f64 = 5.0;
/// Fig. 5: A = 65.31 alpha^gamma (normalisation unstated).
pub const A: f64 = 65.31;

/// The paper's alpha of the container with key `key` (`"a"` .. `"e"`, from [`ALPHA`]); `None`
/// for any other key.
pub fn alpha(key: &str) -> Option<f64> {
    ALPHA.iter().find(|(k, _)| *k == key).map(|(_, a)| *a)
}
