//! The headline numbers of a run's [`Results`], as the golden tests snapshot them. Each unit's
//! analysis is in its file under [`super::figures`] ([`super::unit::FigureUnit::analyse`]).

use super::figures::{ContainerFit, Results};

/// Headline numbers (the insta snapshot of the golden tests).
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct Headline {
    /// Fig. 1's headline (`None` when Fig. 1 did not run).
    pub fig1: Option<Fig1Headline>,
    /// Fig. 3's headline (`None` when Fig. 3 did not run).
    pub fig3: Option<Fig3Headline>,
    /// Fig. 5's headline, one per container in file-name order (empty when the containers did
    /// not run).
    pub fig5: Vec<Fig5Headline>,
}

/// Fig. 1's headline numbers (the paper: about as many transmitted waves as the mass ratio,
/// [`grainchain_engine::paper::MASS_RATIO`]). Fractions are of the incident wave's energy.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Fig1Headline {
    /// Energy of the incident solitary wave in the heavy section (the first listed snapshot);
    /// the reference of the fractions below (not the striker's energy E0).
    pub incident_energy: f64,
    /// Pulses found in the light section in the figure's snapshot, however small.
    pub transmitted_pulses: usize,
    /// Transmitted waves carrying at least 1 % of the incident energy.
    pub transmitted_above_1_percent: usize,
    /// Transmitted waves carrying at least 0.1 % of the incident energy.
    pub transmitted_above_0_1_percent: usize,
    /// The leading (rightmost) transmitted wave's energy as a fraction of the incident energy
    /// (0 when none was found).
    pub leading_fraction: f64,
    /// Reflected energy ([`super::Fig1::reflected`]) as a fraction of the incident energy.
    pub reflected_fraction: f64,
}

/// Fig. 3's headline numbers (the paper: [`grainchain_engine::paper::LEFT_PERCENT`] and
/// [`grainchain_engine::paper::RIGHT_PERCENT`]). Percentages are of the incident wave's energy.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Fig3Headline {
    /// Energy of the incident solitary wave right of the container in the first listed
    /// snapshot; the reference of the percentages below.
    pub incident_energy: f64,
    /// The leading wave left of the container in the figure's snapshot, % of the incident
    /// energy (`None`: no pulse there).
    pub left_lead_percent: Option<f64>,
    /// The leading wave right of the container in the figure's snapshot, % of the incident
    /// energy (`None`: no pulse there).
    pub right_lead_percent: Option<f64>,
    /// Energy still in the container in the figure's snapshot, % of the incident energy.
    pub container_percent: f64,
}

/// Fig. 5's headline numbers of one container (the paper: gamma = [`grainchain_engine::paper::GAMMA`] for
/// all, alpha in [`grainchain_engine::paper::ALPHA`]).
#[derive(Clone, Debug, serde::Serialize)]
pub struct Fig5Headline {
    /// The container's key (`a` .. `e`).
    pub container: String,
    /// The exponent of `E_R / E0 ~ t^-gamma` over the fit window (`None`: too few points).
    pub gamma: Option<f64>,
    /// 95 % confidence interval of gamma, (low, high).
    pub gamma_ci: Option<(f64, f64)>,
    /// The time rescaling onto (a): `E_R(t) = E_R^(a)(alpha t)`; 1 for (a) itself (`None`: no
    /// collapse found).
    pub alpha: Option<f64>,
}

impl Headline {
    /// The headline numbers of `r`.
    pub fn of(r: &Results) -> Headline {
        Headline {
            fig1: r.fig1.as_ref().map(|f| Fig1Headline {
                incident_energy: f.incident.energy,
                transmitted_pulses: f.transmitted.len(),
                transmitted_above_1_percent: f.above_1_percent,
                transmitted_above_0_1_percent: f.above_0_1_percent,
                leading_fraction: f.transmitted.first().map_or(0.0, |p| p.fraction),
                reflected_fraction: f.reflected_fraction,
            }),
            fig3: r.fig3.as_ref().map(|f| Fig3Headline {
                incident_energy: f.incident.energy,
                left_lead_percent: f.left_lead.as_ref().map(|p| p.percent),
                right_lead_percent: f.right_lead.as_ref().map(|p| p.percent),
                container_percent: f.container_percent,
            }),
            fig5: r.fits.iter().flatten().map(Fig5Headline::of).collect(),
        }
    }
}

impl Fig5Headline {
    fn of(c: &ContainerFit) -> Self {
        Fig5Headline {
            container: c.key.clone(),
            gamma: c.fit.map(|f| f.gamma),
            gamma_ci: c.fit.map(|f| (f.ci_lo, f.ci_hi)),
            alpha: c.collapse.map(|x| x.alpha),
        }
    }
}
