# ---
# jupyter:
#   jupytext:
#     formats: py:percent
#     text_representation:
#       extension: .py
#       format_name: percent
#   kernelspec:
#     display_name: Python 3
#     language: python
#     name: python3
# ---

# %% [markdown]
# # Hong (2005) from Python: containers (a)-(e), Fig. 4, Fig. 5, gamma and a small ensemble
#
# Every number here comes from `grainchain` called from Python: the same engine and the same
# recorder as `grainchain run`, so the curves are those of `grainchain reproduce` bit for bit.
# Run it from the repository root (`jupytext --to ipynb examples/notebooks/paper.py`, then open
# or execute the notebook; CI executes it with nbclient). Figures are written to
# `$GRAINCHAIN_FIGURES` (default `out/notebook`).

# %%
import os
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files, no display needed
import matplotlib.pyplot as plt
import numpy as np

import grainchain
from grainchain import analysis

FIGURES = Path(os.environ.get("GRAINCHAIN_FIGURES", "out/notebook"))
FIGURES.mkdir(parents=True, exist_ok=True)
SCENES = Path("scenes/containers")
CONTAINERS = {
    "a": "a-standard.toml",
    "b": "b-right-half-reversed.toml",
    "c": "c-uniform-sides.toml",
    "d": "d-long-sections.toml",
    "e": "e-no-walls.toml",
}

# %% [markdown]
# ## The five containers
# Each run records `E_container`, the energy remaining inside the container, at 4000
# snapshots (500 time units); `check()` tells beforehand what a run costs.

# %%
print(grainchain.check(SCENES / CONTAINERS["a"]))
runs = {}
for key, file in CONTAINERS.items():
    t0 = time.perf_counter()
    runs[key] = grainchain.run(SCENES / file)
    s = runs[key].summary
    print(f"({key}) {file}: {s['steps']} steps, {time.perf_counter() - t0:.1f} s")

# %% [markdown]
# ## Fig. 4: the energy remaining in each container
# E_R in percent of the striker's energy (the run's initial energy), against time in snapshots.

# %%
er = {k: r.energies["E_container"] for k, r in runs.items()}
e0 = {k: r.summary["initial_energy"] for k, r in runs.items()}
percent = {k: 100.0 * er[k] / e0[k] for k in runs}
t = np.arange(len(er["a"]))

fig, ax = plt.subplots(figsize=(6, 4.5))
for k in runs:
    ax.loglog(t[1:], percent[k][1:], label=f"({k})")
ax.set_xlabel("t (snapshots)")
ax.set_ylabel("E_R (% of the striker's energy)")
ax.set_title("Fig. 4: energy remaining in the containers")
ax.legend()
fig.savefig(FIGURES / "fig4.png", dpi=120)

# %% [markdown]
# ## gamma and alpha, as `grainchain reproduce` fits them
# The leak onset is where E_R has fallen to half its maximum; gamma is fitted over the last
# decade `[n/10, n]` (never before the onset), 20 log bins per decade; alpha is the time factor
# that collapses each curve's bins (from the onset on) onto (a)'s.

# %%
n = len(er["a"]) - 1
fits, bins = {}, {}
for k in runs:
    onset = analysis.leak_onset(er[k], 0.5)
    bins[k] = analysis.log_bins(er[k], onset, n, 20)
    lo = max(n // 10, onset)
    fits[k] = analysis.fit_power_law(analysis.log_bins(percent[k], lo, n, 20))
    fits[k]["window"] = (lo, n)
alpha = {"a": 1.0}
for k in "bcde":
    alpha[k] = analysis.collapse_alpha(bins["a"], bins[k])["alpha"]
for k in runs:
    f = fits[k]
    print(f"({k}) gamma over {f['window']} = {f['gamma']:.3f} "
          f"[{f['ci_lo']:.3f}, {f['ci_hi']:.3f}], alpha = {alpha[k]:.2f}")

# %% [markdown]
# The same numbers as the README's table of `grainchain reproduce` (gamma over [400, 4000]:
# (a) 0.849, (b) 0.827, (c) 0.813, (d) 0.699, (e) 0.816; alpha (b)-(e) 1.16, 1.93, 0.30, 1.13),
# to the digits printed there:

# %%
readme_gamma = {"a": 0.849, "b": 0.827, "c": 0.813, "d": 0.699, "e": 0.816}
readme_alpha = {"b": 1.16, "c": 1.93, "d": 0.30, "e": 1.13}
for k, g in readme_gamma.items():
    assert abs(fits[k]["gamma"] - g) <= 0.0005 + 1e-12, (k, fits[k]["gamma"], g)
for k, a in readme_alpha.items():
    assert abs(alpha[k] - a) <= 0.005 + 1e-12, (k, alpha[k], a)

# %% [markdown]
# ## Fig. 5: the curves collapsed onto (a), with the power law of (a)
# Each curve against `alpha t`; if the containers leaked alike the curves would lie on one.

# %%
fig, ax = plt.subplots(figsize=(6, 4.5))
for k in runs:
    peak = int(np.argmax(er[k]))
    m = (t > peak) & (er[k] > 0)
    ax.loglog(alpha[k] * t[m], percent[k][m], label=f"({k}) alpha = {alpha[k]:.2f}")
f = fits["a"]
tt = np.geomspace(*f["window"], 21)
ax.loglog(tt, f["a"] * tt ** -f["gamma"], "k--", label=f"(a) fit: gamma = {f['gamma']:.3f}")
ax.set_xlabel("alpha t (snapshots)")
ax.set_ylabel("E_R (%)")
ax.set_title("Fig. 5: collapse onto (a) and the power law")
ax.legend(fontsize=8)
fig.savefig(FIGURES / "fig5.png", dpi=120)

# %% [markdown]
# ## A small ensemble of (a)
# Four members whose striker speed differs by 1e-12 relative (the dynamics is chaotic, so the
# curves separate), 1000 snapshots each: the band over members and gamma of the mean curve
# with its jackknife interval over members.

# %%
text = (SCENES / CONTAINERS["a"]).read_text().replace("duration = 500.0", "duration = 125.0")
assert "velocity = -10.0" in text
members = []
for j in range(4):
    v = -10.0 * (1.0 + j * 1e-12)
    r = grainchain.run(text.replace("velocity = -10.0", f"velocity = {v!r}"))
    members.append(r.energies["E_container"] / r.summary["initial_energy"])
members = np.vstack(members)
band = analysis.ensemble_bands(members)
m = len(band["mean"]) - 1
onset = analysis.leak_onset(band["mean"], 0.5)
g = analysis.ensemble_gamma(members, max(m // 10, onset), m, 20)
print(f"ensemble of {len(members)}: gamma of the mean over [{max(m // 10, onset)}, {m}] = "
      f"{g['value']:.3f} [{g['ci_lo']:.3f}, {g['ci_hi']:.3f}]")

fig, ax = plt.subplots(figsize=(6, 4.5))
tt = np.arange(len(band["mean"]))
ax.fill_between(tt[1:], band["p05"][1:], band["p95"][1:], alpha=0.3, label="5-95 %")
ax.loglog(tt[1:], band["mean"][1:], label="mean")
ax.set_xlabel("t (snapshots)")
ax.set_ylabel("E_R / E_0")
ax.set_title("Container (a): 4 members")
ax.legend()
fig.savefig(FIGURES / "ensemble.png", dpi=120)
