"""Errors: the CLI's text as Python exceptions (SceneError with file and key, BlowUpError with
time, step and grain), a Rust panic as InternalError, the GIL released during a run, Ctrl-C."""

import subprocess
import sys
import textwrap
import threading
import time

import pytest

import grainchain
from conftest import CONTAINER_A

BAD_MASS = """
[chain]
[[chain.sections]]
count = 10
mass = -1.0
p = 1.5
eta = 5657.0
[run]
duration = 1.0
output_interval = 0.125
"""


def cli_error(cli, *args):
    """The CLI's error text (stderr without its `error: ` prefix)."""
    p = subprocess.run([cli, *args], capture_output=True, text=True)
    assert p.returncode != 0
    # The last line (a `note:` about a shortened step may come first).
    last = p.stderr.strip().splitlines()[-1]
    assert last.startswith("error: ")
    return last[len("error: "):]


def test_malformed_scene_file_has_the_cli_text(cli, tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text(BAD_MASS)
    with pytest.raises(grainchain.SceneError) as e:
        grainchain.run(path)
    assert isinstance(e.value, ValueError)
    msg = str(e.value)
    assert str(path) in msg and "chain.sections[0].mass" in msg
    assert (e.value.file, e.value.key) == (str(path), "chain.sections[0].mass")
    assert msg == cli_error(cli, "check", str(path))
    assert msg == cli_error(cli, "run", str(path), "--out", str(tmp_path / "o"))


def test_unknown_key_in_a_file_is_a_parse_error(cli, tmp_path):
    path = tmp_path / "typo.toml"
    path.write_text(BAD_MASS.replace("mass = -1.0", "mas = 1.0"))
    with pytest.raises(grainchain.SceneError) as e:
        grainchain.Scene.load(path)
    assert "mas" in str(e.value) and str(path) in str(e.value) and e.value.key is None
    assert str(e.value) == cli_error(cli, "check", str(path))


def test_malformed_scene_from_a_dict_names_the_key():
    d = {
        "chain": {"sections": [{"count": 10, "mass": 1.0, "p": -2.0, "eta": 5657.0}]},
        "run": {"duration": 1.0, "output_interval": 0.125},
    }
    with pytest.raises(grainchain.SceneError) as e:
        grainchain.run(d)
    assert e.value.file == "<dict>" and e.value.key == "chain.sections[0].p"
    assert str(e.value).startswith("<dict>: key `chain.sections[0].p`: ")
    with pytest.raises(ValueError, match="unknown field `colour`"):
        grainchain.Scene.from_dict({**d, "colour": "red"})


def test_missing_file_is_a_scene_error(tmp_path):
    with pytest.raises(grainchain.SceneError, match="cannot read"):
        grainchain.run(tmp_path / "nowhere.toml")


def test_not_a_scene_is_a_type_error():
    with pytest.raises(TypeError, match="a scene is"):
        grainchain.run(42)


BLOW_UP = """
name = "blow-up"
[chain]
[[chain.sections]]
count = 20
mass = 1.0
p = 1.5
eta = 5657.0
[striker]
end = "left"
mass = 1.0
speed = 100.0
[integrator]
method = "verlet"
dt = 0.0625
[run]
duration = 5.0
output_interval = 0.125
"""


def test_blow_up_is_its_own_exception_with_time_step_grain(cli, tmp_path):
    with pytest.raises(grainchain.BlowUpError) as e:
        grainchain.run(BLOW_UP)
    err = e.value
    assert isinstance(err, grainchain.RunError) and isinstance(err, RuntimeError)
    assert isinstance(err.time, float) and err.time > 0
    assert isinstance(err.step, int) and err.step > 0
    assert isinstance(err.grain, int)
    assert str(err).startswith("numerical blow-up at t = ")
    assert f"step {err.step}" in str(err)
    path = tmp_path / "blow-up.toml"
    path.write_text(BLOW_UP)
    assert str(err) == cli_error(cli, "run", str(path), "--out", str(tmp_path / "o"))


def test_a_rust_panic_becomes_an_exception():
    with pytest.raises(grainchain.InternalError, match="a Rust panic.*boom at the boundary"):
        grainchain._grainchain._panic_for_test("boom at the boundary")
    # An ordinary Exception (PyO3's own PanicException is a BaseException), and the interpreter
    # goes on.
    assert issubclass(grainchain.InternalError, Exception)
    assert grainchain.run(BLOW_UP.replace("dt = 0.0625", "dt = 1e-4")).finished


def test_the_gil_is_released_during_a_run():
    """Another Python thread makes progress while a run is under way."""
    done = threading.Event()
    ticks = []

    def go():
        grainchain.run(CONTAINER_A)
        done.set()

    t = threading.Thread(target=go)
    t.start()
    while not done.is_set():
        ticks.append(time.perf_counter())
        time.sleep(0.001)
    t.join()
    # Container (a) runs for seconds; with the GIL held the loop above could not tick until the
    # run ended (a few ticks at most). Released, it ticks about every millisecond throughout.
    assert len(ticks) > 200
    gaps = [b - a for a, b in zip(ticks, ticks[1:])]
    # No stretch of the run held the interpreter: the longest gap is far below the run's
    # seconds (1 s leaves room for a loaded machine descheduling this thread).
    assert max(gaps) < 1.0


def test_ctrl_c_stops_a_run_within_half_a_second(tmp_path):
    child = textwrap.dedent(
        f"""
        import sys, time
        import grainchain
        print("running", flush=True)
        try:
            grainchain.run({str(CONTAINER_A)!r})
        except KeyboardInterrupt:
            print("interrupted", repr(time.time()), flush=True)
            sys.exit(3)
        print("finished", flush=True)
        """
    )
    p = subprocess.Popen([sys.executable, "-c", child], stdout=subprocess.PIPE, text=True)
    assert p.stdout.readline().strip() == "running"
    time.sleep(0.5)  # the run is under way (it takes seconds)
    import signal

    sent = time.time()
    p.send_signal(signal.SIGINT)
    out, _ = p.communicate(timeout=60)
    assert p.returncode == 3, out
    word, when = out.split()
    assert word == "interrupted"
    latency = float(when) - sent
    print(f"Ctrl-C latency {latency:.3f} s")
    # The contract: the run stops within half a second (signals are looked at every
    # 50 ms of the run; container (a) takes about 0.6 ms per output, so the bound has margin).
    assert latency < 0.5
