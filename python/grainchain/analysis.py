"""The analysis of the remaining energy E_R(t) on NumPy arrays (Rust: ``grainchain_engine::analysis``).

Time is counted in snapshots (index into the curve), as in the paper. Typical use::

    e = result.energies["E_container"]
    onset = leak_onset(e, 0.9)
    fit = fit_power_law(log_bins(e, onset, len(e) - 1, 5))
    fit["gamma"], fit["ci_lo"], fit["ci_hi"]
"""

from ._grainchain import (  # noqa: F401  (re-exported)
    collapse_alpha,
    ensemble_bands,
    ensemble_gamma,
    fit_power_law,
    leak_onset,
    local_slope,
    log_bins,
)

__all__ = [
    "collapse_alpha",
    "ensemble_bands",
    "ensemble_gamma",
    "fit_power_law",
    "leak_onset",
    "local_slope",
    "log_bins",
]
