"""grainchain.run: scenes from every source, the arrays' dtypes and shapes, the CLI's numbers bit
for bit, determinism, the callback, and check()."""

import re
import subprocess
from pathlib import Path

import numpy as np
import pytest

import grainchain
from conftest import CONTAINER_A, SCENES, csv_columns, read_csv

# Container (a) as shipped (4000 snapshots), with snapshots of three fields of the container's
# 180 grains every 400 outputs added: one run gives energies.csv and snapshots.csv.
A_WITH_SNAPSHOTS = CONTAINER_A.read_text().replace(
    "[output]\nenergies = true\n",
    "[output]\nenergies = true\n"
    'snapshots = { fields = ["displacement", "velocity", "energy"], every = 400, '
    "first = 4001, last = 4180 }\n",
)
assert "snapshots" in A_WITH_SNAPSHOTS  # the replacement above found its anchor

SMALL = """
name = "small"
[chain]
[[chain.sections]]
count = 60
mass = 1.0
p = 1.5
eta = 5657.0
[striker]
end = "left"
mass = 1.0
speed = 1.0
[integrator]
method = "verlet"
dt = 1e-4
[run]
duration = 2.0
output_interval = 0.125
[[regions]]
name = "front"
first = 1
last = 20
[output]
energies = true
snapshots = { fields = ["velocity", "force"], every = 4 }
pulses = { every = 4 }
tracks = { every = 1 }
"""


@pytest.fixture(scope="module")
def a_both(cli, tmp_path_factory):
    """Container (a) with snapshots, run by the CLI and from Python."""
    d = tmp_path_factory.mktemp("a")
    scene = d / "a.toml"
    scene.write_text(A_WITH_SNAPSHOTS)
    out = d / "out"
    subprocess.run([cli, "run", str(scene), "--out", str(out)], check=True, capture_output=True)
    return out, grainchain.run(scene)


def test_container_a_energies_bit_for_bit_with_the_cli(a_both):
    out, r = a_both
    header, _ = read_csv(out / "energies.csv")
    # The exact contract: the CSV's column names, in order, to float64 arrays.
    assert list(r.energies) == header
    want = csv_columns(out / "energies.csv")
    assert len(want["time"]) == 4001
    for name in header:
        assert np.array_equal(r.energies[name], want[name]), name


def test_protected_load_columns_and_rebound_match_the_cli(cli, tmp_path):
    """A scene with a protected wall: energies has the load columns (the force on the wall at
    each output, its peak and impulse so far) and summary the striker's rebound, the CLI's
    exactly."""
    import json

    scene = SCENES / "steel-ptfe-protector.toml"
    out = tmp_path / "out"
    subprocess.run([cli, "run", str(scene), "--out", str(out)], check=True, capture_output=True)
    r = grainchain.run(scene)
    header, _ = read_csv(out / "energies.csv")
    assert header[-3:] == ["load", "load_peak", "load_impulse"]
    assert list(r.energies) == header
    want = csv_columns(out / "energies.csv")
    for name in header:
        assert np.array_equal(r.energies[name], want[name]), name
    summary = json.loads((out / "summary.json").read_text())
    assert r.summary["striker_rebound"] == summary["striker_rebound"] < 0.0
    assert r.energies["load_peak"][-1] == summary["load"]["peak"]
    # The column is the force at output instants: never above the peak over every step.
    assert np.all(r.energies["load"] <= r.energies["load_peak"])


def test_container_a_snapshot_bit_for_bit_with_the_cli(a_both):
    out, r = a_both
    header, rows = read_csv(out / "snapshots.csv")
    assert header == ["index", "time", "grain", "displacement", "velocity", "energy"]
    cols = csv_columns(out / "snapshots.csv")
    grains = 180
    n = len(rows) // grains
    assert n == 11  # outputs 0, 400, ..., 4000
    assert np.array_equal(r.snapshot_index, cols["index"][::grains].astype(np.int64))
    assert np.array_equal(r.snapshot_time, cols["time"][::grains])
    assert np.array_equal(r.snapshot_grains, cols["grain"][:grains].astype(np.int64))
    for field in ["displacement", "velocity", "energy"]:
        assert np.array_equal(r.snapshots[field], cols[field].reshape(n, grains)), field
    # The last snapshot is not all zeros: the comparison compared something.
    assert np.any(r.snapshots["velocity"][-1] != 0.0)


def test_summary_is_summary_json(a_both):
    import json

    out, r = a_both
    want = json.loads((out / "summary.json").read_text())
    assert set(r.summary) == set(want)
    # The work counters are the CLI's exactly; wall times differ from run to run.
    for k in ["steps", "force_evaluations", "grain_evaluations", "grains", "outputs", "dt"]:
        assert r.summary[k] == want[k], k
    assert set(r.summary["timings"]) == {"integrate", "checks", "output"}


def test_dtypes_and_shapes():
    r = grainchain.run(SMALL)
    rows = 17  # t = 0 and 16 outputs
    for name, a in r.energies.items():
        assert a.dtype == np.float64 and a.shape == (rows,), name
    assert list(r.energies)[:6] == ["index", "time", "kinetic", "potential", "total", "momentum"]
    assert "E_front" in r.energies and "P_front" in r.energies
    for field in ["velocity", "force"]:
        a = r.snapshots[field]
        assert a.dtype == np.float64 and a.shape == (5, 61), field  # 60 grains + the striker
        assert a.flags["C_CONTIGUOUS"]
        # One buffer of exactly rows x grains float64s: no Python object per element.
        assert a.nbytes == 5 * 61 * 8
    assert r.snapshot_index.dtype == np.int64 and list(r.snapshot_index) == [0, 4, 8, 12, 16]
    assert r.snapshot_grains.dtype == np.int64 and r.snapshot_grains[0] == 0  # the striker
    assert list(r.pulses) == [
        "index", "time", "pulse", "first", "last", "position", "peak_velocity", "energy"
    ]
    assert len(r.pulses["time"]) > 0 and len(r.tracks["track"]) > 0
    assert all(a.dtype == np.float64 for a in r.pulses.values())
    assert r.finished


def test_small_scene_pulses_and_tracks_match_the_cli(cli, tmp_path):
    scene = tmp_path / "small.toml"
    scene.write_text(SMALL)
    subprocess.run([cli, "run", str(scene), "--out", str(tmp_path / "o")], check=True,
                   capture_output=True)
    r = grainchain.run(scene)
    for table in ["pulses", "tracks"]:
        want = csv_columns(tmp_path / "o" / f"{table}.csv")
        got = getattr(r, table)
        assert list(got) == list(want)
        for k in want:
            # NaN (a one-point track's missing speed) equals NaN here.
            assert np.array_equal(got[k], want[k], equal_nan=True), (table, k)


SMALL_DICT = {
    "name": "small",
    "chain": {"sections": [{"count": 60, "mass": 1.0, "p": 1.5, "eta": 5657.0}]},
    "striker": {"end": "left", "mass": 1.0, "speed": 1.0},
    "integrator": {"method": "verlet", "dt": 1e-4},
    "run": {"duration": 2.0, "output_interval": 0.125},
    "regions": [{"name": "front", "first": 1, "last": 20}],
    "output": {
        "energies": True,
        "snapshots": {"fields": ["velocity", "force"], "every": 4},
        "pulses": {"every": 4},
        "tracks": {"every": 1},
    },
}


def test_scene_sources_agree(tmp_path):
    """A file (str and Path), TOML text, a dict and a Scene give the same run."""
    p = tmp_path / "small.toml"
    p.write_text(SMALL)
    runs = [
        grainchain.run(str(p)),
        grainchain.run(p),
        grainchain.run(SMALL),
        grainchain.run(SMALL_DICT),
        grainchain.run(grainchain.Scene.from_dict(SMALL_DICT)),
        grainchain.run(grainchain.Scene.load(p)),
    ]
    for r in runs[1:]:
        assert list(r.energies) == list(runs[0].energies)
        for k, a in runs[0].energies.items():
            assert np.array_equal(r.energies[k], a), k
        assert np.array_equal(r.snapshots["force"], runs[0].snapshots["force"])
    s = grainchain.Scene.from_toml(SMALL)
    assert (s.name, s.grains, s.outputs, s.method) == ("small", 61, 16, "verlet")
    assert dict(s.regions) == {"front": (1, 20)}


def test_deterministic_across_calls_and_threads():
    """The same scene run twice, and in two threads at once, gives the same bits."""
    import threading

    first = grainchain.run(SMALL).energies
    results = [None, None]

    def go(k):
        results[k] = grainchain.run(SMALL).energies

    ts = [threading.Thread(target=go, args=(k,)) for k in range(2)]
    for t in ts:
        t.start()
    for t in ts:
        t.join()
    for r in results:
        for k, a in first.items():
            assert np.array_equal(r[k], a), k


def test_callback_sees_every_output_and_can_stop():
    seen = []

    def on_output(t, values):
        seen.append((t, values["E_front"]))
        if t >= 1.0:
            return False  # stop at t = 1 (output 8)
        return None

    r = grainchain.run(SMALL, on_output=on_output)
    assert not r.finished
    assert [t for t, _ in seen] == [0.125 * k for k in range(9)]
    # What was recorded stops where the callback stopped it, and the callback saw those values.
    assert np.array_equal(r.energies["time"], [t for t, _ in seen])
    assert np.array_equal(r.energies["E_front"], [e for _, e in seen])
    full = grainchain.run(SMALL)
    assert full.finished and len(full.energies["time"]) == 17


def test_callback_exception_propagates():
    class Boom(Exception):
        pass

    def on_output(t, values):
        if t > 0.5:
            raise Boom("from the callback")

    with pytest.raises(Boom, match="from the callback"):
        grainchain.run(SMALL, on_output=on_output)


def human_bytes(b):
    """The CLI's form of a size (main.rs `human_bytes`), to compare check() with its text."""
    for lim, unit in [(1e9, "GB"), (1e6, "MB"), (1e3, "kB")]:
        if b >= lim:
            return f"{b / lim:.1f} {unit}"
    return f"{b} B"


@pytest.mark.parametrize("scene", ["containers/a-standard.toml", "single-solitary-wave.toml",
                                   "fig1-heavy-to-light.toml"])
def test_check_is_the_cli_estimate(cli, scene):
    path = SCENES / scene
    text = subprocess.run([cli, "check", str(path)], check=True, capture_output=True,
                          text=True).stdout
    c = grainchain.check(path)
    first = re.search(r": ok \((\d+) grains, (\S+) with dt ([^ ,]+)", text)
    assert first and int(first[1]) == c["grains"] and first[2] == c["method"]
    assert float(first[3]) == c["dt"]
    assert f"{c['outputs']} output times after t = 0 ({c['rows']} rows" in text
    assert f"estimate: {c['steps']} steps, {c['grains']} grains" in text
    assert f"energies.csv {human_bytes(c['energies_bytes'])}" in text
    if c["snapshots_bytes"]:
        assert f"snapshots.csv {human_bytes(c['snapshots_bytes'])}" in text
    assert f"memory: at most about {human_bytes(c['memory_bytes'])}" in text
    assert f"{c['memory_per_grain']} bytes per grain" in text


def test_to_pandas_tables():
    pd = pytest.importorskip("pandas")  # optional: grainchain never needs it
    r = grainchain.run(SMALL)
    e = r.to_pandas()
    assert list(e.columns) == list(r.energies) and len(e) == 17
    s = r.to_pandas("snapshots")
    assert list(s.columns) == ["index", "time", "grain", "velocity", "force"]
    assert len(s) == 5 * 61
    # Long format as snapshots.csv: row k * 61 + g is snapshot k, grain column g.
    assert s["force"].iloc[2 * 61 + 7] == r.snapshots["force"][2, 7]
    assert isinstance(r.to_pandas("pulses"), pd.DataFrame)
    with pytest.raises(ValueError, match="no table"):
        r.to_pandas("nothing")
