"""grainchain.protector: the engine's protector evaluation from Python. The numbers are the Rust
API's (the example's printed values, to the digit it prints; a batch the same bits as its
designs alone, at every thread count), a single bead's limit against Hertz's closed form, the
errors name the place and the key, and a user's own optimiser loop runs on batches."""

import json
import math
import re
import subprocess

import numpy as np
import pytest

import grainchain
from grainchain import protector
from conftest import ROOT, read_csv

D = 6e-3
STEEL_PTFE = [("steel", D)] * 20 + [("ptfe", D)] * 20
LOAD = dict(striker=("steel", D), speed=1.0)
FIELDS = {
    "peak_force",
    "peak_time",
    "impulse",
    "duration",
    "target_energy",
    "rebound",
    "rebound_final",
    "mass",
    "length",
    "time",
    "steps",
    "dt",
    "complete",
    "given_up",
}


def bits(a):
    """An array's bytes: equal bytes are equal bits (== would call -0.0 and 0.0 equal)."""
    return np.ascontiguousarray(a).tobytes()


@pytest.fixture(scope="module")
def example_lines():
    """The printed lines of `examples/protector.rs` (the Rust API on the same three designs),
    built by cargo (a no-op when up to date) and found through cargo's own report."""
    out = subprocess.run(
        ["cargo", "build", "--release", "--example", "protector", "--message-format=json"],
        cwd=ROOT,
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    exe = None
    for line in out.splitlines():
        msg = json.loads(line)
        if msg.get("reason") == "compiler-artifact" and msg.get("executable"):
            if msg["target"]["name"] == "protector":
                exe = msg["executable"]
    assert exe, "cargo built no protector example"
    return subprocess.run([exe], check=True, capture_output=True, text=True).stdout.splitlines()


def test_materials_table():
    m = protector.materials()
    assert list(m) == [
        "steel",
        "stainless-steel",
        "brass",
        "aluminium",
        "ptfe",
        "glass",
        "tungsten-carbide",
    ]
    # engine/src/units.rs: steel (AISI 52100-like) 7800 kg/m^3, 200 GPa, 0.29.
    assert m["steel"] == {"E": 200e9, "nu": 0.29, "rho": 7800.0}


def test_one_design_matches_the_rust_example(example_lines):
    """The example prints the Rust API's evaluation of the same designs: every printed number,
    formatted as the example formats it (both languages round the exact binary value
    correctly), and the step count exactly."""
    designs = [
        STEEL_PTFE,
        STEEL_PTFE[::-1],
        [("steel", D)] * 40,
    ]
    assert len(example_lines) == 3
    for beads, line in zip(designs, example_lines):
        e = protector.evaluate(beads, **LOAD)
        assert set(e) == FIELDS
        m = re.search(
            r"peak (\S+) N at (\S+) ms, impulse (\S+) N s, (\d+) steps to (\S+) ms "
            r"\(stopped by the rule: (true|false)\)",
            line,
        )
        assert m, line
        assert m.group(1) == f"{e['peak_force']:.1f}"
        assert m.group(2) == f"{e['peak_time'] * 1e3:.3f}"
        # Rust's {:.4e} writes `1.9021e-3`, Python's `1.9021e-03`.
        mant, exp = f"{e['impulse']:.4e}".split("e")
        assert m.group(3) == f"{mant}e{int(exp)}"
        assert int(m.group(4)) == e["steps"]
        assert m.group(5) == f"{e['time'] * 1e3:.3f}"
        assert m.group(6) == str(e["complete"]).lower()


def test_a_batch_is_its_designs_alone_at_every_thread_count():
    rng = np.random.default_rng(7)
    names = ["steel", "ptfe", "brass", "tungsten-carbide"]
    designs = [
        [(names[rng.integers(4)], float(rng.choice([3e-3, 4.5e-3, 6e-3]))) for _ in range(n)]
        for n in rng.integers(3, 25, size=40)
    ]
    one = protector.evaluate_many(designs, **LOAD, threads=1)
    two = protector.evaluate_many(designs, **LOAD, threads=2)
    assert set(one) == FIELDS
    assert one["steps"].dtype == np.uint64 and one["complete"].dtype == np.bool_
    for k in FIELDS:
        assert len(one[k]) == len(designs)
        assert bits(one[k]) == bits(two[k]), k
    for i, d in enumerate(designs):
        e = protector.evaluate(d, **LOAD)
        for k in FIELDS:
            assert bits(np.asarray(e[k], dtype=one[k].dtype)) == bits(one[k][i : i + 1]), (i, k)
    # A batch runs in chunks (the first one design per thread, then sized by the pace): 80
    # designs span several and keep their order.
    many = protector.evaluate_many(designs * 2, **LOAD, threads=1)
    assert bits(many["peak_force"]) == bits(np.concatenate([one["peak_force"]] * 2))


def test_a_custom_material_with_steels_constants_is_steel():
    steel = protector.materials()["steel"]
    a = protector.evaluate([("steel", D)] * 5, **LOAD)
    b = protector.evaluate([(steel, D)] * 5, striker=({"material": steel, "diameter": D}), speed=1.0)
    assert a == b


def test_a_named_material_is_its_constants_and_its_name_is_checked():
    steel = dict(protector.materials()["steel"])
    a = protector.evaluate([("steel", D)] * 5, **LOAD)
    b = protector.evaluate([(dict(steel, name="bearing steel"), D)] * 5, **LOAD)
    assert a == b
    with pytest.raises(grainchain.DesignError, match=r"`steel` is a material of the table"):
        protector.evaluate([(dict(steel, name="steel"), D)], **LOAD)
    with pytest.raises(grainchain.DesignError, match=r"material.name: must be a string, got int"):
        protector.evaluate([(dict(steel, name=3), D)], **LOAD)


def test_a_light_bead_is_two_hertz_contacts_in_series():
    """A 1 mm tungsten-carbide bead between a large steel striker and a steel wall: when the
    bead's mass is negligible beside the striker's, the bead is a massless link, and the two
    Hertz contacts in series make one of constant eta = (eta1^(-2/3) + eta2^(-2/3))^(-3/2) (the
    overlaps add at equal force). The striker's energy at the deepest point is all in it,
    (2/5) eta x^(5/2), so the peak force is eta x^(3/2) (Johnson, Contact Mechanics, 1985,
    section 11.4). Constants by hand from the table: E* and R* of each pair (Johnson Eq.
    4.22-4.23)."""
    m = protector.materials()
    st, wc = m["steel"], m["tungsten-carbide"]
    db, v = 1e-3, 0.5

    def compliance(x):
        return (1 - x["nu"] ** 2) / x["E"]

    def closed_form(ds):
        e_star = 1 / (compliance(st) + compliance(wc))
        r_sb = (ds / 2) * (db / 2) / (ds / 2 + db / 2)
        eta1 = 4 / 3 * e_star * math.sqrt(r_sb)
        eta2 = 4 / 3 * e_star * math.sqrt(db / 2)  # the bead on the steel flat: R* = R
        eta = (eta1 ** (-2 / 3) + eta2 ** (-2 / 3)) ** -1.5
        mass = st["rho"] * math.pi * ds**3 / 6
        x = (0.5 * mass * v * v / (0.4 * eta)) ** 0.4
        return eta * x**1.5

    err = {}
    for ds, spc in [(50e-3, 40), (100e-3, 40), (100e-3, 160)]:
        # The light bead rattles between the receding striker and the wall for many contact
        # times before it can no longer catch the striker: a cap of 1000 contact-time sums lets
        # the stop rule prove the peak.
        e = protector.evaluate(
            [("tungsten-carbide", db)],
            striker=("steel", ds),
            speed=v,
            steps_per_contact=spc,
            time_cap=1000.0,
        )
        assert e["complete"]
        err[ds, spc] = e["peak_force"] / closed_form(ds) - 1
    # Elastic: the striker leaves with nearly all of its speed, back (the bead keeps at most its
    # share of the energy, m/M below 2e-5). A run that needs the peak stops once the pair moves
    # away from the wall (the stop rule counts its momentum), before the striker's speed is
    # final; one that needs everything runs until nothing can touch the wall again.
    e = protector.evaluate(
        [("tungsten-carbide", db)],
        striker=("steel", 100e-3),
        speed=v,
        need="everything",
        time_cap=1000.0,
    )
    assert e["complete"] and e["rebound_final"]
    assert e["rebound"] == pytest.approx(-v, rel=1e-4)
    # What the massless link leaves out is the bead's own inertia: the residual falls as the
    # striker grows (measured 4.9e-3 at 50 mm, 1.9e-3 at 100 mm, i.e. like (m/M)^0.45), not with
    # the step (4x the steps per contact change it by under 1e-5). A wrong constant (a factor
    # 4/3, sqrt(2), the series rule) is off by more than 5 %.
    assert 0 < err[100e-3, 40] < 2.5e-3
    assert err[50e-3, 40] > 2 * err[100e-3, 40]
    assert abs(err[100e-3, 160] - err[100e-3, 40]) < 1e-5
    e = protector.evaluate([("tungsten-carbide", db)], striker=("steel", 0.1), speed=v)
    assert e["mass"] == pytest.approx(wc["rho"] * math.pi * db**3 / 6, rel=1e-15)


def test_a_target_body_takes_energy():
    e = protector.evaluate(
        STEEL_PTFE,
        **LOAD,
        target={"mass": 0.1, "material": "aluminium", "spring": 1e4},
        need="everything",
    )
    assert e["target_energy"] > 0.0
    assert e["impulse"] > 0.0


def test_need_changes_what_is_final_not_the_peak():
    peak = protector.evaluate(STEEL_PTFE, **LOAD)
    every = protector.evaluate(STEEL_PTFE, **LOAD, need="everything")
    # The stop rule is exact for the peak: the run to the end finds the same bits.
    assert peak["peak_force"] == every["peak_force"]
    assert every["time"] >= peak["time"]


def test_giving_up_reports_a_lower_bound():
    """give_up_above: a design whose peak reaches it is given up on once that pulse has passed,
    with a lower bound of its peak; below it, the run is the plain one, bit for bit."""
    plain = protector.evaluate(STEEL_PTFE, **LOAD)
    assert not plain["given_up"]
    cut = protector.evaluate(STEEL_PTFE, **LOAD, give_up_above=0.5 * plain["peak_force"])
    assert cut["given_up"] and not cut["complete"]
    assert 0.5 * plain["peak_force"] <= cut["peak_force"] <= plain["peak_force"]
    assert cut["steps"] < plain["steps"]
    above = protector.evaluate(STEEL_PTFE, **LOAD, give_up_above=2.0 * plain["peak_force"])
    assert above == plain
    many = protector.evaluate_many(
        [STEEL_PTFE], **LOAD, give_up_above=0.5 * plain["peak_force"], threads=1
    )
    assert many["given_up"].dtype == np.bool_ and bool(many["given_up"][0])
    assert many["peak_force"][0] == cut["peak_force"]


def test_an_estimate_is_three_evaluations_and_their_larger_difference():
    """estimate: the finest run (twice the steps) is evaluate's at those steps, bit for bit, the
    coarse one evaluate's at the steps given, the coarsest at half of them, and the error the
    larger of the two differences; with need="peak" impulse and duration are not final (no
    error). accuracy sets the steps by the engine's rule (1e-5: the default 20; 1e-7: 20 *
    100^(2/5) = 126.19...)."""
    est = protector.estimate(STEEL_PTFE, **LOAD)
    assert est["value"] == protector.evaluate(STEEL_PTFE, **LOAD, steps_per_contact=40)
    assert est["coarse"] == protector.evaluate(STEEL_PTFE, **LOAD)
    assert est["coarsest"] == protector.evaluate(STEEL_PTFE, **LOAD, steps_per_contact=10)

    def larger(key, e=est):
        v, c, cc = e["value"][key], e["coarse"][key], e["coarsest"][key]
        return max(abs(v - c), abs(c - cc))

    assert est["peak_error"] == larger("peak_force")
    assert est["impulse_error"] is None and est["duration_error"] is None
    assert est["bound"] is False and est["time_cap"] == 100.0
    assert protector.evaluate(STEEL_PTFE, **LOAD, accuracy=1e-5) == est["coarse"]
    fine = protector.evaluate(STEEL_PTFE, **LOAD, accuracy=1e-7)
    assert fine == protector.evaluate(STEEL_PTFE, **LOAD, steps_per_contact=20 * 100 ** 0.4)
    # At the least steps (4) the coarsest run is the coarse one.
    least = protector.estimate(STEEL_PTFE, **LOAD, steps_per_contact=4)
    assert least["coarsest"] == least["coarse"]
    # Ten steel beads pushing a free body away: every number final, each with its error.
    free = protector.estimate(
        [("steel", D)] * 10, **LOAD, target={"mass": 0.01, "material": "steel"}, need="everything"
    )
    assert not free["bound"]
    assert free["impulse_error"] == larger("impulse", free)
    # The duration counts whole steps: its error adds the coarse step.
    assert free["duration_error"] == pytest.approx(
        larger("duration", free) + free["coarse"]["dt"],
        rel=1e-12,  # the sum's rounding
    )


def test_a_bound_is_said_and_run_to_the_end():
    """A cap too short for the stop rule: the estimate is a bound (its peak a lower bound); with
    to_end=True it runs again at ten times the cap until the rule proves the peak, and finds the
    default cap's estimate (the stop rule ends both runs at the same step)."""
    cut = protector.estimate(STEEL_PTFE, **LOAD, time_cap=0.5)
    assert cut["bound"] and not cut["value"]["complete"]
    whole = protector.estimate(STEEL_PTFE, **LOAD)
    assert cut["value"]["peak_force"] <= whole["value"]["peak_force"]
    ended = protector.estimate(STEEL_PTFE, **LOAD, time_cap=0.5, to_end=True)
    assert not ended["bound"] and ended["time_cap"] > 0.5
    assert ended["value"]["peak_force"] == whole["value"]["peak_force"]
    assert ended["peak_error"] == whole["peak_error"]


@pytest.mark.parametrize(
    "call, where, key, text",
    [
        (
            lambda: protector.evaluate([("steel", D), ("stel", D)], **LOAD),
            (None, 1),
            "material",
            r"beads\[1\]: material: unknown material `stel` \(known: steel, stainless-steel, "
            r"brass, aluminium, ptfe, glass, tungsten-carbide; or give its constants E, nu, rho and "
            r"an optional name\)",
        ),
        (
            lambda: protector.evaluate([("steel", D), ("ptfe", 0.0)], **LOAD),
            (None, 1),
            "diameter",
            r"beads\[1\]: diameter: a diameter must lie in \[1e-6, 1\] m \(Hertz's elastic spheres, "
            r"from above colloids to boulders\), got 0",
        ),
        (
            lambda: protector.evaluate([("steel", "6mm")], **LOAD),
            (None, 0),
            "diameter",
            r"beads\[0\]: diameter: must be a number \(m\), got str",
        ),
        (
            lambda: protector.evaluate([({"E": 1e9, "nu": 0.7, "rho": 1e3}, D)], **LOAD),
            (None, 0),
            "material",
            r"beads\[0\]: material: Poisson's ratio nu must lie in \(-1, 0.5\], got 0.7",
        ),
        (
            lambda: protector.evaluate([({"E": 1e9, "rho": 1e3}, D)], **LOAD),
            (None, 0),
            "material",
            r"nu is missing",
        ),
        (
            lambda: protector.evaluate([STEEL_PTFE], **LOAD),
            (None, 0),
            "",
            r"beads\[0\]: expected a \(material, diameter\) pair, got a sequence of 40 items "
            r"\(a list of designs goes to evaluate_many\)",
        ),
        (
            lambda: protector.evaluate([], **LOAD),
            (None, None),
            "beads",
            r"beads: a design needs at least one bead",
        ),
        (
            lambda: protector.evaluate(STEEL_PTFE, **LOAD, need="max"),
            (None, None),
            "need",
            r"need: must be \"peak\", \"duration\" or \"everything\", got \"max\"",
        ),
        (
            lambda: protector.evaluate(STEEL_PTFE, striker=("steel", D), speed=-1.0),
            (None, None),
            "speed",
            r"^speed: must be a finite number > 0 m/s, got -1$",  # the engine's own text
        ),
        (
            lambda: protector.evaluate(STEEL_PTFE, striker=("gold", D), speed=1.0),
            (None, None),
            "striker.material",
            r"striker.material: unknown material `gold`",
        ),
        (
            lambda: protector.evaluate(STEEL_PTFE, **LOAD, wall="steel", target={"mass": 1}),
            (None, None),
            "wall",
            r"give a wall or a target, not both",
        ),
        (
            lambda: protector.evaluate(STEEL_PTFE, **LOAD, target={"mass": 1.0}),
            (None, None),
            "target.material",
            r"target.material: is missing",
        ),
        (
            lambda: protector.evaluate(STEEL_PTFE, **LOAD, restitution=1.5),
            (None, None),
            "restitution",
            r"restitution: must lie in \[0.05, 1\)",
        ),
        (
            lambda: protector.evaluate(STEEL_PTFE, **LOAD, restitution_pairs="steel"),
            (None, None),
            "restitution_pairs",
            r"restitution_pairs: must be a list of \(material, material, restitution\) triples, "
            r"got str",
        ),
        (
            lambda: protector.evaluate(STEEL_PTFE, **LOAD, restitution_pairs=[("steel", "ptfe")]),
            (None, None),
            "restitution_pairs[0]",
            r"restitution_pairs\[0\]: must be a \(material, material, restitution\) triple, "
            r"got tuple",
        ),
        (
            lambda: protector.evaluate(
                STEEL_PTFE, **LOAD, restitution_pairs=[("steel", "cheese", 0.9)]
            ),
            (None, None),
            "restitution_pairs[0][1]",
            r"restitution_pairs\[0\]\[1\]: unknown material",
        ),
        (
            lambda: protector.evaluate(
                STEEL_PTFE, **LOAD, restitution_pairs=[("steel", "ptfe", "high")]
            ),
            (None, None),
            "restitution_pairs[0][2]",
            r"restitution_pairs\[0\]\[2\]: must be a number, got str",
        ),
        (
            lambda: protector.evaluate(
                STEEL_PTFE, **LOAD, restitution_pairs=[("steel", "ptfe", 1.5)]
            ),
            (None, None),
            "restitution_pairs",
            r"restitution_pairs: pair 1 \(steel and ptfe\): must be a coefficient of restitution "
            r"from 0.05 to 1 \(elastic\), got 1.5",
        ),
        (
            lambda: protector.evaluate_many([STEEL_PTFE, [("steel", D), ("ptfe", -D)]], **LOAD),
            (1, 1),
            "diameter",
            r"designs\[1\]\[1\]: diameter: a diameter must lie in",
        ),
        (
            lambda: protector.evaluate(STEEL_PTFE, **LOAD, give_up_above=0.0),
            (None, None),
            "give_up_above",
            r"give_up_above: must be a force > 0 N \(infinite: never give up\), got 0",
        ),
        (
            lambda: protector.evaluate(STEEL_PTFE, **LOAD, accuracy=0.0),
            (None, None),
            "accuracy",
            r"accuracy: must be a relative error of the peak force in \[1e-9, 1e-2\] .*got 0",
        ),
        (
            lambda: protector.estimate(STEEL_PTFE, **LOAD, accuracy=float("nan")),
            (None, None),
            "accuracy",
            r"accuracy: must be a relative error of the peak force in \[1e-9, 1e-2\] .*got NaN",
        ),
        (
            lambda: protector.evaluate(STEEL_PTFE, **LOAD, accuracy=1e-5, steps_per_contact=160),
            (None, None),
            "accuracy",
            r"accuracy: give accuracy or steps_per_contact, not both",
        ),
        (
            lambda: protector.evaluate_many([STEEL_PTFE], **LOAD, threads=0),
            (None, None),
            "threads",
            r"^threads: must be an integer from 1 to \d+, got 0$",
        ),
    ],
)
def test_bad_input_names_the_place_and_the_key(call, where, key, text):
    with pytest.raises(grainchain.DesignError) as info:
        call()
    assert isinstance(info.value, ValueError)
    assert re.search(text, str(info.value)), str(info.value)
    assert (info.value.design, info.value.bead) == where
    assert info.value.key == key


def test_restitution_by_pair_of_materials():
    """Every pair of the column's materials listed at 0.9 is every contact at 0.9, bit for bit,
    in one evaluation, a batch and the Monte Carlo; a pair at 1 (elastic) among contacts at 0.9
    changes the peak; and with a damped pair the gradients refuse, with an elastic one they
    run."""
    beads = [("steel", D)] * 4 + [("ptfe", D)] * 4 + [("brass", 0.005)] * 2
    names = ["steel", "ptfe", "brass"]
    every_pair = [(a, b, 0.9) for i, a in enumerate(names) for b in names[i:]]
    every = protector.evaluate(beads, **LOAD, restitution=0.9)
    listed = protector.evaluate(beads, **LOAD, restitution_pairs=every_pair)
    assert listed == every
    many = protector.evaluate_many([beads, beads[::-1]], **LOAD, restitution_pairs=every_pair)
    assert many["peak_force"][0] == every["peak_force"]
    tol = {"diameter": 0.01}
    mc = dict(tolerances=tol, samples=4, time_cap=3.0)
    assert (
        protector.monte_carlo(beads, **LOAD, **mc, restitution=0.9)["peaks"].tobytes()
        == protector.monte_carlo(beads, **LOAD, **mc, restitution_pairs=every_pair)[
            "peaks"
        ].tobytes()
    )
    elastic_steel = protector.evaluate(
        beads, **LOAD, restitution=0.9, restitution_pairs=[("steel", "steel", 1.0)]
    )
    assert elastic_steel["peak_force"] != every["peak_force"]
    # A material given as a dict is matched by its name too.
    soft = {"E": 1e9, "nu": 0.35, "rho": 1200.0, "name": "soft"}
    column = [("steel", D)] * 3 + [(soft, D)] * 3
    damped = protector.evaluate(column, **LOAD, restitution_pairs=[(dict(soft), "steel", 0.7)])
    assert damped["peak_force"] != protector.evaluate(column, **LOAD)["peak_force"]
    with pytest.raises(grainchain.DesignError) as info:
        protector.evaluate(
            beads, **LOAD, restitution_pairs=[("ptfe", "steel", 0.8)], gradients=True
        )
    assert info.value.key == "gradients"
    g = protector.evaluate(
        beads, **LOAD, restitution_pairs=[("ptfe", "steel", 1.0)], gradients=True
    )
    assert g["peak_force"] == protector.evaluate(beads, **LOAD)["peak_force"]


def test_a_users_own_search_beats_the_monodisperse_chains():
    """What the library is for: a script's own optimiser. A seeded (1 + 32) evolution over
    16-bead columns of steel and PTFE (6 mm) under one load, in batches on two threads: a random
    first batch, then each batch the best so far with one to three beads flipped. It must beat
    both monodisperse columns of the same count (all steel, and all PTFE, the softer), improve on
    its own first batch, and its winner must evaluate alone to the same bits (the batch's order
    is the input's)."""
    n, steel, ptfe = 16, ("steel", D), ("ptfe", D)
    mono = min(protector.evaluate([m] * n, **LOAD)["peak_force"] for m in (steel, ptfe))
    rng = np.random.default_rng(2005)
    batch = [[steel if x else ptfe for x in rng.random(n) < 0.5] for _ in range(32)]
    best, best_peak, first = None, math.inf, None
    for _ in range(6):
        r = protector.evaluate_many(batch, **LOAD, threads=2)
        k = int(np.argmin(r["peak_force"]))
        if r["peak_force"][k] < best_peak:
            best, best_peak = batch[k], float(r["peak_force"][k])
        first = best_peak if first is None else first
        batch = []
        for _ in range(32):
            child = list(best)
            for i in rng.choice(n, size=rng.integers(1, 4), replace=False):
                child[i] = ptfe if child[i] == steel else steel
            batch.append(child)
    assert best_peak < mono
    assert best_peak < first
    assert protector.evaluate(best, **LOAD)["peak_force"] == best_peak


def test_ctrl_c_stops_a_batch_within_half_a_second():
    """As a run does (test_errors.py): the batch looks for Ctrl-C between chunks of about 0.1 s."""
    import signal
    import sys
    import textwrap
    import time

    child = textwrap.dedent(
        f"""
        import sys, time
        from grainchain import protector
        print("running", flush=True)
        try:
            # 5000 evaluations of about 0.6 ms each: seconds of work.
            protector.evaluate_many([{STEEL_PTFE!r}] * 5000, striker=("steel", {D}), speed=1.0)
        except KeyboardInterrupt:
            print("interrupted", repr(time.time()), flush=True)
            sys.exit(3)
        print("finished", flush=True)
        """
    )
    p = subprocess.Popen([sys.executable, "-c", child], stdout=subprocess.PIPE, text=True)
    assert p.stdout.readline().strip() == "running"
    time.sleep(0.5)  # the batch is under way
    sent = time.time()
    p.send_signal(signal.SIGINT)
    out, _ = p.communicate(timeout=60)
    assert p.returncode == 3, out
    word, when = out.split()
    assert word == "interrupted"
    # Chunks aim at 0.1 s (64 designs of 0.6 ms: about 40 ms here); half a second has margin
    # for a loaded machine, as the run's test.
    assert float(when) - sent < 0.5


# Gradients (evaluate(..., gradients=True)): an 8-bead column of unequal beads (no two contacts
# share the contact time that sets the step, so the step has one derivative), steel then PTFE
# with one brass bead, as the engine's own test of its derivatives.
GRAD_NAMES = ["steel"] * 4 + ["ptfe", "brass", "ptfe", "ptfe"]
GRAD_DIAMETERS = [D * (1 + 0.037 * i) for i in range(8)]
NUMBERS = ["peak", "impulse", "duration", "target_energy", "rebound"]
PARAMETERS = ["diameter", "rho", "E", "nu"]


def grad_beads(bead=None, key=None, factor=1.0):
    """The gradient column, its materials as dicts, with `beads[bead]`'s `key` (diameter, or a
    material constant: rho, E, nu) times `factor`."""
    table = protector.materials()
    out = []
    for i, (name, d) in enumerate(zip(GRAD_NAMES, GRAD_DIAMETERS)):
        m = dict(table[name])
        if i == bead and key == "diameter":
            d *= factor
        elif i == bead:
            m[key] *= factor
        out.append((m, d))
    return out


def central(f, bead, key, h):
    """The central difference of `f(beads)` in `beads[bead]`'s `key` at relative step `h`, per
    unit of the parameter; and the parameter's value."""
    x = GRAD_DIAMETERS[bead] if key == "diameter" else protector.materials()[GRAD_NAMES[bead]][key]
    up, down = f(grad_beads(bead, key, 1 + h)), f(grad_beads(bead, key, 1 - h))
    return (up - down) / (2 * h * x), x


def as_bits(v):
    return np.asarray(v).tobytes()


@pytest.mark.parametrize(
    "beads, kw",
    [
        (grad_beads(), {}),
        (STEEL_PTFE[:10], {"need": "everything"}),
        (
            [("steel", D)] * 6,
            {"target": {"mass": 0.01, "material": "aluminium", "spring": 1e4}, "need": "duration"},
        ),
        (grad_beads(), {"give_up_above": 10.0, "accuracy": 1e-6}),
    ],
)
def test_gradients_leave_the_evaluation_the_same_bits(beads, kw):
    """gradients=True adds one key; every other field is the same bits as without (the dict is
    evaluate's; the run with derivatives' own numbers, under "evaluation", agree to rounding)."""
    plain = protector.evaluate(beads, **LOAD, **kw)
    both = protector.evaluate(beads, **LOAD, **kw, gradients=True)
    assert protector.evaluate(beads, **LOAD, **kw, gradients=False) == plain
    assert set(both) == FIELDS | {"gradients"}
    for k in FIELDS:
        assert type(both[k]) is type(plain[k]), k
        assert as_bits(both[k]) == as_bits(plain[k]), k
    own = both["gradients"]["evaluation"]
    assert set(own) == FIELDS
    for k in ["steps", "complete", "given_up", "rebound_final", "dt", "mass", "length"]:
        assert own[k] == plain[k], k
    # 1e-12: the rounding of a few thousand steps' sums, added in another order (the engine's
    # test of the same agreement).
    for k in ["peak_force", "impulse", "duration", "target_energy", "rebound"]:
        assert abs(own[k] - plain[k]) <= 1e-12 * abs(plain[k]), k


def test_gradients_have_one_array_per_bead_and_parameter():
    n = len(GRAD_NAMES)
    r = protector.evaluate(grad_beads(), **LOAD, need="everything", gradients=True)
    g = r["gradients"]
    assert set(g) == set(NUMBERS) | {"tie", "step_shared", "evaluation"}
    for number in NUMBERS:
        assert set(g[number]) == set(PARAMETERS) | {"speed", "striker_mass"}, number
        for key in PARAMETERS:
            a = g[number][key]
            assert isinstance(a, np.ndarray), (number, key)
            assert a.dtype == np.float64 and a.shape == (n,), (number, key)
            assert np.all(np.isfinite(a)), (number, key)
        for key in ["speed", "striker_mass"]:
            assert type(g[number][key]) is float, (number, key)
    assert g["tie"] is None and g["step_shared"] is False
    # A wall has no energy: its derivatives are zeros. The peak depends on every bead.
    assert not np.any(g["target_energy"]["E"]) and g["target_energy"]["speed"] == 0.0
    assert np.all(g["peak"]["diameter"] != 0.0)
    # The duration counts whole steps: its derivative is their count times the step's, the
    # step (the shortest contact time over the steps per contact) a closed form of the beads,
    # so a central difference of `dt` finds it to rounding over the step (1e-15 / 1e-6).
    above = round(r["duration"] / r["dt"])
    assert above > 0 and r["duration"] == above * r["dt"]
    assert np.any(g["duration"]["diameter"])  # the beads of the contact that sets the step
    for key in PARAMETERS:
        for b in range(n):
            fd, x = central(lambda beads: protector.evaluate(beads, **LOAD)["dt"], b, key, 1e-6)
            assert abs(above * fd - g["duration"][key][b]) * x <= 1e-8 * r["duration"], (key, b)
    # Equal beads share the contact time that sets the step: said.
    equal = protector.evaluate([("steel", D)] * 6, **LOAD, gradients=True)
    assert equal["gradients"]["step_shared"] is True
    assert equal["gradients"]["peak"]["E"].shape == (6,)


def test_the_peaks_gradient_is_its_finite_difference():
    """The derivatives are of the discrete run evaluate makes, so a central difference of
    evaluate itself converges to them. At a relative step h = 1e-6 the difference's truncation
    is about h^2 = 1e-12 of the derivative (the run is smooth in its parameters: contact events
    cut the steps where contacts close and open); its rounding is the peak's rounding (measured
    about 1e-15 of it, at most 1e-13: a few thousand steps' sums) over 2 h, at most 5e-8 of
    peak / parameter. Beads[4], the first PTFE bead after the steel, moves the peak by more
    than 0.05 of it per unit of its log-diameter and log-modulus (0.43 and 0.12; asserted
    below), so that rounding is at most 1e-6 of the derivative: 1e-5 holds with margin
    (measured: 2e-9 for the diameter, 1.3e-8 for E). Then every parameter of every bead, the
    speed and the striker's mass, in
    the error of the elasticity x dF/dx / F, bounded the same way by 5e-8 (measured at most
    4e-9): a derivative under the wrong key or bead is off by far more."""
    h = 1e-6
    r = protector.evaluate(grad_beads(), **LOAD, gradients=True)
    g, peak = r["gradients"]["peak"], r["peak_force"]

    def f(beads):
        return protector.evaluate(beads, **LOAD)["peak_force"]

    for key in ["diameter", "E"]:
        fd, x = central(f, 4, key, h)
        exact = g[key][4]
        assert abs(exact) * x / peak > 0.05, key
        assert abs(fd - exact) <= 1e-5 * abs(exact), (key, fd, exact)
    for key in PARAMETERS:
        for b in range(len(GRAD_NAMES)):
            fd, x = central(f, b, key, h)
            assert abs(fd - g[key][b]) * x <= 1e-7 * peak, (key, b, fd, g[key][b])
    steel = protector.materials()["steel"]
    mass = steel["rho"] * math.pi * D**3 / 6
    up, down = [
        protector.evaluate(grad_beads(), striker=(dict(steel, rho=steel["rho"] * s), D), speed=1.0)
        for s in (1 + h, 1 - h)
    ]
    fd = (up["peak_force"] - down["peak_force"]) / (2 * h * mass)
    assert abs(fd - g["striker_mass"]) * mass <= 1e-7 * peak
    up, down = [
        protector.evaluate(grad_beads(), striker=("steel", D), speed=s) for s in (1 + h, 1 - h)
    ]
    fd = (up["peak_force"] - down["peak_force"]) / (2 * h)
    assert abs(fd - g["speed"]) <= 1e-7 * peak


def test_gradients_refuse_a_restitution_with_the_engines_words():
    with pytest.raises(grainchain.DesignError) as info:
        protector.evaluate(grad_beads(), **LOAD, restitution=0.9, gradients=True)
    assert info.value.key == "gradients"
    assert (info.value.design, info.value.bead) == (None, None)
    assert re.fullmatch(
        r"gradients: are built for elastic contacts only \(leave out the restitution and its "
        r"pairs\)",
        str(info.value),
    ), str(info.value)
    # Without gradients the same design evaluates.
    assert protector.evaluate(grad_beads(), **LOAD, restitution=0.9)["peak_force"] > 0.0


def test_a_gradient_past_its_bounds_is_refused_before_it_starts():
    """Issue 49: 40,000 beads with gradients aborted the interpreter on a 25 GB allocation. The
    reverse run takes them now (some 800 steps at that time cap); 100,000 beads would need more
    than the bound of 1 GB (MAX_GRADIENT_BYTES: checkpoints and a segment's record), and the
    engine refuses them before the run starts, naming the beads (the plain run before it, at
    this time cap, takes a tenth of a second)."""
    with pytest.raises(grainchain.DesignError) as info:
        protector.evaluate([("steel", D)] * 100_000, **LOAD, time_cap=0.001, gradients=True)
    assert info.value.key == "beads", str(info.value)
    assert "give fewer beads" in str(info.value), str(info.value)


@pytest.mark.parametrize(
    "bad, name", [(1, "int"), ("yes", "str"), (None, "NoneType"), ([True], "list")]
)
def test_gradients_take_a_bool_and_nothing_else(bad, name):
    """Not truthiness: 1 and "yes" are mistakes, refused by name before anything runs."""
    text = rf"^argument 'gradients': must be True or False, got {name}$"
    with pytest.raises(TypeError, match=text):
        protector.evaluate(grad_beads(), **LOAD, gradients=bad)


def test_gradients_take_numpys_bools():
    r = protector.evaluate([("steel", D)] * 3, **LOAD, gradients=np.True_)
    assert "gradients" in r
    assert "gradients" not in protector.evaluate([("steel", D)] * 3, **LOAD, gradients=np.False_)


def test_the_gil_is_released_while_gradients_run():
    """Another Python thread makes progress while the derivatives are computed (as during a
    run: test_errors.py)."""
    import threading
    import time

    done = threading.Event()
    ticks = []

    failed = []

    def go():
        # 40 beads at 160 steps per contact: some 0.3 s (the run and its sweep back, 20k steps;
        # 2026-11-29, the 2-core machine), a few hundred ticks of the loop below.
        try:
            protector.evaluate(STEEL_PTFE, **LOAD, steps_per_contact=160, gradients=True)
        except Exception as e:  # the main loop waits for `done` either way
            failed.append(e)
        finally:
            done.set()

    t = threading.Thread(target=go)
    t.start()
    while not done.is_set():
        ticks.append(time.perf_counter())
        time.sleep(0.001)
    t.join()
    assert not failed, failed
    # Held, the GIL would let this loop tick a few times at most in the whole call.
    assert len(ticks) > 50


TINY_DESIGN = """
[space]
beads = 6
sections = 3
materials = ["steel", "ptfe"]
diameters = [0.005, 0.007]

[load]
striker = { material = "steel", diameter = 0.006 }
speeds = [1.0]
wall = "steel"

[search]
seed = 1
population = 8
generations = 2
stale = 2

[tolerances]
diameter = 0.01
E = 0.05
samples = 100
"""


def test_gradients_are_the_clis_bit_for_bit(cli, tmp_path):
    """`grainchain design` with `[tolerances]` writes every derivative of each reported design's
    peak to `sensitivities.csv` (shortest round-trip text: `float()` reads the exact bits), from
    runs at the search's step (`accuracy` 1e-5: 20 steps per contact time) and the engine's time
    cap, which are evaluate's defaults: the same design evaluated here with gradients must give
    the same bits."""
    design = tmp_path / "tiny.toml"
    design.write_text(TINY_DESIGN)
    out = tmp_path / "out"
    subprocess.run([cli, "design", str(design), "--out", str(out), "--threads", "1"],
                   check=True, capture_output=True)
    header, rows = read_csv(out / "sensitivities.csv")
    col = {name: k for k, name in enumerate(header)}
    best = [r for r in rows if r[col["kind"]] == "design" and r[col["name"]] == "1"]
    assert len(best) == 6
    beads = [(r[col["material"]], float(r[col["diameter_m"]])) for r in best]
    res = protector.evaluate(beads, striker=("steel", 0.006), speed=1.0, wall="steel",
                             gradients=True)
    peak = res["gradients"]["peak"]
    for key, column in [("diameter", "dpeak_ddiameter"), ("rho", "dpeak_ddensity"),
                        ("E", "dpeak_dyoung"), ("nu", "dpeak_dpoisson")]:
        cli_values = np.array([float(r[col[column]]) for r in best])
        assert np.array_equal(peak[key], cli_values), key
    assert peak["speed"] == float(best[0][col["dpeak_dspeed"]])
    assert peak["striker_mass"] == float(best[0][col["dpeak_dstriker_mass"]])


# A robust design file (validation/robust.rs's): 4 sections of 3 beads, steel or PTFE, 1 %
# diameter and 5 % modulus tolerances.
ROBUST = (ROOT / "validation" / "designs" / "robust-small.toml").read_text()
TOLERANCES = {"diameter": 0.01, "E": 0.05}


def column(genes: str):
    """A design of ROBUST from its genes (`1.0.0.1`): 3 beads per section."""
    return [(["steel", "ptfe"][int(g)], D) for g in genes.split(".") for _ in range(3)]


def test_monte_carlo_is_the_design_commands_bit_for_bit(cli, tmp_path):
    """`protector.monte_carlo` meets the design command's common draws: stream 1 gives each
    winner's fresh-draw statistics of winners.csv (mean, p95, p99 and their intervals, at the
    engine's cap) and stream 0 at the search's cap (10) each finalist's screening statistic of
    finalists.csv (over the reference column's nominal peak), to the last bit; and the progress
    callback counts to the end."""
    f = tmp_path / "robust.toml"
    f.write_text(ROBUST)
    out = tmp_path / "out"
    subprocess.run(
        [cli, "design", str(f), "--out", str(out), "--threads", "2"], check=True, capture_output=True
    )
    header, rows = read_csv(out / "winners.csv")
    at = {name: k for k, name in enumerate(header)}
    calls = []
    for row in rows:
        beads = column(row[at["genes"]])
        for stat, key in [("mean", "mean"), ("p95", "p95"), ("p99", "p99")]:
            r = protector.monte_carlo(
                beads, **LOAD, wall="steel", tolerances=TOLERANCES, samples=100, stream=1,
                statistic=stat, threads=2, progress=lambda d, t: calls.append((d, t)),
            )
            assert r["value"] == float(row[at[f"{key}_n"]]), (row, stat)
            assert r["low"] == float(row[at[f"{key}_low_n"]])
            assert r["high"] == float(row[at[f"{key}_high_n"]])
            assert r["bounds"] == int(row[at["bounds"]])
            assert r["peaks"].shape == (100,) and r["complete"].dtype == np.bool_
    assert calls[-1] == (100, 100) and all(d <= t for d, t in calls)
    reference = protector.evaluate([("steel", D)] * 12, **LOAD, wall="steel", time_cap=10.0)
    header, rows = read_csv(out / "finalists.csv")
    at = {name: k for k, name in enumerate(header)}
    for row in rows:
        r = protector.monte_carlo(
            column(row[at["genes"]]), **LOAD, wall="steel", tolerances=TOLERANCES, samples=32,
            time_cap=10.0,
        )
        assert r["value"] / reference["peak_force"] == float(row[at["screened"]]), row


def test_monte_carlo_with_pairs_is_the_design_commands_bit_for_bit(cli, tmp_path):
    """With dissipation by pair of materials in the design file and the same pairs from Python,
    `protector.monte_carlo` on stream 1 gives each winner's fresh-draw p95 of winners.csv to the
    last bit (the CLI and Python lay the contacts out through the same engine call)."""
    pairs = [("ptfe", "steel", 0.8), ("ptfe", "ptfe", 0.9)]
    toml_pairs = ", ".join(
        f'{{ between = ["{a}", "{b}"], restitution = {e} }}' for a, b, e in pairs
    )
    f = tmp_path / "robust-pairs.toml"
    f.write_text(
        ROBUST.replace('wall = "steel"', f'wall = "steel"\nrestitution_pairs = [{toml_pairs}]')
    )
    out = tmp_path / "out"
    subprocess.run(
        [cli, "design", str(f), "--out", str(out), "--threads", "2"], check=True, capture_output=True
    )
    assert "Dissipation: every contact is elastic but for these pairs' own" in (
        out / "DESIGN.md"
    ).read_text()
    header, rows = read_csv(out / "winners.csv")
    at = {name: k for k, name in enumerate(header)}
    assert rows
    for row in rows:
        r = protector.monte_carlo(
            column(row[at["genes"]]), **LOAD, wall="steel", tolerances=TOLERANCES, samples=100,
            stream=1, threads=2, restitution_pairs=pairs,
        )
        assert r["value"] == float(row[at["p95_n"]]), row
        elastic = protector.monte_carlo(
            column(row[at["genes"]]), **LOAD, wall="steel", tolerances=TOLERANCES, samples=100,
            stream=1, threads=2,
        )
        assert elastic["value"] != r["value"]


@pytest.mark.parametrize(
    "kwargs, key",
    [
        (dict(tolerances={"diameter": 0.3}), r'tolerances\["diameter"\]'),
        (dict(tolerances={"d": 0.01}), r'tolerances\["d"\]'),
        (dict(tolerances=[0.01]), "tolerances"),
        (dict(statistic="p100"), "statistic"),
        (dict(statistic="median"), "statistic"),
        (dict(samples=0), "samples"),
        (dict(progress=3), "progress"),
    ],
)
def test_monte_carlo_refuses_bad_input_by_key(kwargs, key):
    args = dict(tolerances=TOLERANCES, samples=4)
    args.update(kwargs)
    with pytest.raises(grainchain.DesignError, match=key):
        protector.monte_carlo(column("0.1.0.1"), **LOAD, **args)
