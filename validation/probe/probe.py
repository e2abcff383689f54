#!/usr/bin/env python3
"""An adversarial probe of the grainchain binary: mutated scenes and sweeps, and the folder rules.

What it does, seeded and so repeatable:

- **mutations**: for every shipped scene (scenes/*.toml, scenes/containers/*.toml) and sweep
  (studies/*.toml), a random sample of edits: an unknown key put into one table, one value
  replaced by an absurd one (negative, zero, 1e300, 1e-300, the largest integer, a string, a
  boolean, an empty array), one key removed. Each mutant is given to `check` (`study --check`
  for a sweep) and then to `run` (`study`, into a fresh folder), each with a time limit.
- **folders**: a fake project folder (source, README, the scene itself, a nested folder, a
  symlink) used as `--out` with `--force` by `run`, `study` and `reproduce --only fig1`; every
  byte of it must be intact afterwards.

- **structure** (issue 38): TOML nested hundreds deep, dotted unknown keys, missing tables, a
  name too long for a folder, outputs listed after the run or repeated, a byte that is not UTF-8,
  `/dev/zero` as a scene, `reproduce` outside the repository or with an absurd `--snapshots`;
- **subfolders**: a user's file inside `members/` or `evaluations/`, with and without `--force`;
- **damaged files**: a tiny study and a two-island design run well, then a member's JSON or CSV,
  or a design journal (a line cut in the middle, an objective edited, a byte that is not UTF-8,
  an island missing), damaged before `--merge` or `--resume`;
- **extreme values**: design files with materials or diameters a run cannot compute;
- **Python** (`--python PY`, a Python with the module installed): self-referencing and deeply
  nested dicts, `None`, NumPy scalars, huge integers, negative thread counts, a callback's
  NumPy `False`, a run in a daemon thread at interpreter exit, each in a child interpreter.

What it counts: invocations, exit codes, panics (exit 101, a signal, or "panicked" on stderr),
verdicts where `check` passes and the run then refuses the input as bad (exit 2 in under a
second, a reason knowable before running), mutants whose unknown key is accepted, and folders
that lost a byte, silent wrong results (a bad input accepted: exit 0, or a merge of damaged
files) and refusals that do not name what to change. It prints a table and exits 1 when it found
a panic, a lost byte, an accepted unknown key, a silent wrong result or a refusal without a name.

    cargo build --release
    python3 validation/probe/probe.py --bin target/release/grainchain --count 300 --seed 1 \
        [--python .venv/bin/python]

It runs the binary only (no Python package needed) and needs Python 3.11 (tomllib).
"""

import argparse
import collections
import hashlib
import math
import os
import random
import shutil
import subprocess
import sys
import tempfile
import time
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


# --- a small TOML writer (the standard library reads TOML but does not write it) -----------------

def _key(k):
    return k if k.replace("_", "").replace("-", "").isalnum() else '"' + k + '"'


def _value(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, list):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{_key(k)} = {_value(x)}" for k, x in v.items()) + " }"
    raise TypeError(type(v))


def dumps(doc):
    """TOML text of `doc`: scalars and inline values first, then tables and arrays of tables."""
    out = []

    def table(d, path):
        scalars = {k: v for k, v in d.items() if not _is_table(v) and not _is_table_array(v)}
        for k, v in scalars.items():
            out.append(f"{_key(k)} = {_value(v)}")
        for k, v in d.items():
            if _is_table(v):
                out.append("")
                out.append("[" + ".".join(_key(x) for x in path + [k]) + "]")
                table(v, path + [k])
            elif _is_table_array(v):
                for item in v:
                    out.append("")
                    out.append("[[" + ".".join(_key(x) for x in path + [k]) + "]]")
                    table(item, path + [k])

    table(doc, [])
    return "\n".join(out) + "\n"


def _is_table(v):
    return isinstance(v, dict)


def _is_table_array(v):
    return isinstance(v, list) and v and all(isinstance(x, dict) for x in v)


# --- mutations ------------------------------------------------------------------------------------

def tables(doc, path=()):
    """Every table of `doc` (inline ones and array-of-table entries included) with its path."""
    yield path, doc
    for k, v in doc.items():
        if isinstance(v, dict):
            yield from tables(v, path + (k,))
        elif isinstance(v, list):
            for i, x in enumerate(v):
                if isinstance(x, dict):
                    yield from tables(x, path + (k, i))


def leaves(doc, path=()):
    for k, v in doc.items():
        if isinstance(v, dict):
            yield from leaves(v, path + (k,))
        elif isinstance(v, list) and v and all(isinstance(x, dict) for x in v):
            for i, x in enumerate(v):
                yield from leaves(x, path + (k, i))
        else:
            yield path + (k,), v


def get(doc, path):
    for p in path:
        doc = doc[p]
    return doc


ABSURD = [-1, 0, 1e300, 1e-300, -1e300, 2**63 - 1, "text", True, [], float("nan"), float("inf")]


def mutate(doc, rng):
    """One mutant of `doc` and a description of the edit; `unknown` is the key put in, if any."""
    doc = tomllib.loads(dumps(doc))  # a deep copy
    kind = rng.choice(["unknown", "value", "value", "remove"])
    if kind == "unknown":
        path, t = rng.choice(list(tables(doc)))
        key = "probe_" + "".join(rng.choice("abcdefghij") for _ in range(5))
        t[key] = 1
        return doc, f"unknown key {key} in {fmt(path) or 'top level'}", key
    path, old = rng.choice(list(leaves(doc)))
    parent = get(doc, path[:-1])
    if kind == "remove":
        del parent[path[-1]]
        return doc, f"removed {fmt(path)}", None
    new = rng.choice(ABSURD)
    parent[path[-1]] = new
    return doc, f"{fmt(path)} = {_value(new)} (was {_value(old)})", None


def fmt(path):
    s = ""
    for p in path:
        s += f"[{p}]" if isinstance(p, int) else ("." if s else "") + p
    return s


# --- running --------------------------------------------------------------------------------------

Result = collections.namedtuple("Result", "code stderr seconds timed_out stdout", defaults=("",))


def call(binary, args, cwd, limit):
    start = time.monotonic()
    try:
        p = subprocess.run([binary, *args], cwd=cwd, capture_output=True, text=True, timeout=limit)
        return Result(p.returncode, p.stderr, time.monotonic() - start, False, p.stdout)
    except subprocess.TimeoutExpired as e:
        err = e.stderr.decode() if isinstance(e.stderr, bytes) else (e.stderr or "")
        return Result(None, err, time.monotonic() - start, True)


def panicked(r):
    return (r.code is not None and (r.code == 101 or r.code < 0)) or "panicked" in r.stderr


def snapshot(folder):
    """Every path below `folder` with the hash of its bytes (a link: its target)."""
    out = {}
    for dirpath, dirs, files in os.walk(folder, followlinks=False):
        for name in dirs + files:
            p = Path(dirpath, name)
            rel = str(p.relative_to(folder))
            if p.is_symlink():
                out[rel] = "link -> " + os.readlink(p)
            elif p.is_file():
                out[rel] = hashlib.sha256(p.read_bytes()).hexdigest()
            else:
                out[rel] = "dir"
    return out


# --- the classes of issue 38: structure, subfolders, damaged files, extreme values, Python --------

def tally(counts, findings, label, r, want_code=2, name=None):
    """Count one invocation that must be refused: exit `want_code` naming `name` (a key, a flag,
    a file) on stderr. A panic or abort, an exit 0 (a silent wrong result: the input is bad) and
    a refusal that does not say what to change are findings."""
    counts["invocations"] += 1
    counts[f"{label.split(':')[0]} exit {'timeout' if r.timed_out else r.code}"] += 1
    if panicked(r):
        counts["panics"] += 1
        findings.append(f"PANIC {label}: {r.stderr.strip()[-300:]}")
    elif r.code == 0 or r.timed_out:
        counts["silent wrong results"] += 1
        findings.append(f"ACCEPTED {label}: exit {r.code}, {r.seconds:.1f} s")
    elif r.code != want_code or (name and name not in r.stderr):
        counts["refusals without a name"] += 1
        findings.append(f"REFUSED BADLY {label}: exit {r.code} (want {want_code} naming {name!r}): "
                        f"{r.stderr.strip()[-300:]}")


SMALL_SCENE = """name = "{name}"
[chain]
[[chain.sections]]
count = 10
mass = 1.0
p = 1.5
eta = 1.0
[striker]
end = "left"
mass = 1.0
speed = 1.0
[integrator]
method = "verlet"
dt = 1e-3
[run]
duration = 1.0
output_interval = 0.1
"""


def structural(binary, work, counts, findings):
    """TOML whose structure, not a value, is wrong, and input that is no scene at all."""
    base = SMALL_SCENE.format(name="s")
    cases = [
        ("nested header 100 deep", base + "[" + ".".join(["a"] * 100) + "]\nx = 1\n", "line "),
        ("inline tables 200 deep", base + "x = " + "{ a = " * 200 + "1" + " }" * 200 + "\n", "line "),
        ("arrays 200 deep", base + "x = " + "[" * 200 + "]" * 200 + "\n", "line "),
        ("dotted unknown key", base + "[output]\nfoo.bar.baz = 1\n", "key `output.foo`"),
        ("no [run] after name", base.split("[run]")[0], "key `run`"),
        ("no [chain]", 'name = "x"\n[run]\nduration = 1.0\noutput_interval = 0.1\n', "key `chain`"),
        ("name of 300 bytes", SMALL_SCENE.format(name="n" * 300), "key `name`"),
        ("name with a slash", SMALL_SCENE.format(name="a/b"), "key `name`"),
        ("snapshot after the run", base + '[output]\nsnapshots = { fields = ["velocity"], at = [50] }\n',
         "key `output.snapshots.at[0]`"),
        ("a million repeated snapshot indices",
         base + '[output]\nsnapshots = { fields = ["velocity"], at = ['
         + ", ".join(str(i % 5) for i in range(1_000_000)) + "] }\n", "key `output.snapshots.at["),
        ("precompression, free right end",
         '[chain]\nleft = { kind = "wall", p = 1.5, eta = 1.0 }\n[[chain.sections]]\ncount = 10\n'
         'mass = 1.0\np = 1.5\neta = 1.0\ndelta0 = 0.01\n[run]\nduration = 1.0\noutput_interval = 0.1\n',
         "key `chain.right`"),
    ]
    for label, text, name in cases:
        f = work / "structural.toml"
        f.write_text(text)
        for cmd in (["check", str(f)], ["run", str(f), "--out", str(work / "structural-out")]):
            tally(counts, findings, f"structural {cmd[0]}: {label}", call(binary, cmd, work, 60),
                  name=name)
        if (work / "structural-out").exists():
            counts["silent wrong results"] += 1
            findings.append(f"OUTPUT LEFT BEHIND: structural run: {label}")
            shutil.rmtree(work / "structural-out")
    f = work / "not-utf8.toml"
    f.write_bytes(base.encode().replace(b'name = "s"', b'name = "s\xff"'))
    tally(counts, findings, "structural check: a byte that is not UTF-8",
          call(binary, ["check", str(f)], work, 60), name="line 1")
    tally(counts, findings, "structural check: /dev/zero as the scene",
          call(binary, ["check", "/dev/zero"], work, 60), name="/dev/zero")
    tally(counts, findings, "structural reproduce: outside the repository",
          call(binary, ["reproduce", "--out", str(work / "r")], work, 60), name="--scenes")
    tally(counts, findings, "structural reproduce: --snapshots 1e11",
          call(binary, ["reproduce", "--snapshots", "100000000000", "--out", str(work / "r")],
               ROOT, 60), name="--snapshots")


TINY_SWEEP = """name = "tiny"
snapshots = 20
members = 2
perturbation = {{ kind = "striker-speed", epsilon = 1e-12 }}
outer_chains = 50
reference = "a"
[[containers]]
key = "a"
scene = "{scene}"
"""

TINY_DESIGN = """[space]
beads = 4
materials = ["steel", "ptfe"]
diameters = [0.006]
[load]
striker = {{ material = "steel", diameter = 0.006 }}
speeds = [1.0]
wall = "steel"
[search]
seed = 1
population = 4
generations = {generations}
stale = 1
"""


def tiny_inputs(work):
    sweep = work / "tiny-sweep.toml"
    sweep.write_text(TINY_SWEEP.format(scene=ROOT / "scenes/containers/a-standard.toml"))
    design = work / "tiny-design.toml"
    design.write_text(TINY_DESIGN.format(generations=2))
    return sweep, design


def subfolders(binary, work, counts, findings):
    """A user's file inside a subfolder grainchain writes (`members/`, `evaluations/`), with and
    without --force: never replaced (issue 38, item 1)."""
    sweep, design = tiny_inputs(work)
    cases = [
        ("study members/a-m0.csv", ["study", str(sweep), "--threads", "1"], "members/a-m0.csv"),
        ("study members/a-m1.json", ["study", str(sweep), "--threads", "1"], "members/a-m1.json"),
        ("design evaluations/island-1-of-1.csv", ["design", str(design), "--threads", "1"],
         "evaluations/island-1-of-1.csv"),
        ("design --shard 1/2 evaluations/island-1-of-2.csv",
         ["design", str(design), "--threads", "1", "--shard", "1/2"], "evaluations/island-1-of-2.csv"),
    ]
    for label, args, user_file in cases:
        out = work / ("sub-" + label.replace(" ", "-").replace("/", "-"))
        (out / user_file).parent.mkdir(parents=True)
        (out / user_file).write_text("my own data, not grainchain's\n")
        before = snapshot(out)
        for extra in ([], ["--force"]):
            r = call(binary, [*args, "--out", str(out), *extra], work, 120)
            counts["invocations"] += 1
            counts[f"subfolder {' '.join(extra) or 'plain'} exit {r.code}"] += 1
            if panicked(r):
                counts["panics"] += 1
                findings.append(f"PANIC subfolder {label}: {r.stderr.strip()[-300:]}")
        if snapshot(out).get(user_file) != before[user_file]:
            counts["folders that lost bytes"] += 1
            findings.append(f"LOST in subfolder: {label}")


def damaged(binary, work, counts, findings):
    """Files a --merge or --resume reads back, damaged by hand after a good run: each must be
    refused naming the file, never merged into different numbers (issue 38, item 4)."""
    sweep, design = tiny_inputs(work)
    # Study members: a JSON edited (its number halved), a CSV edited.
    good = work / "damaged-study"
    r = call(binary, ["study", str(sweep), "--out", str(good), "--threads", "1"], work, 300)
    counts["invocations"] += 1
    if r.code != 0:
        findings.append(f"damaged: the tiny study failed: {r.stderr.strip()[-300:]}")
        return
    def edit_json(p):
        t = p.read_text()
        i = t.index('"initial_energy": ') + len('"initial_energy": ')
        j = i + next(k for k, c in enumerate(t[i:]) if c in ",\n}")
        p.write_text(t[:i] + repr(float(t[i:j]) / 2) + t[j:])
    def edit_csv(p):
        lines = p.read_text().splitlines(keepends=True)
        lines[5] = lines[5].replace("1", "2", 1) if "1" in lines[5] else lines[5] + "0"
        p.write_text("".join(lines))
    for label, file, edit in [("member JSON, initial_energy halved", "members/a-m0.json", edit_json),
                              ("member CSV, a digit changed", "members/a-m1.csv", edit_csv)]:
        for mode in ("--merge", "--resume"):
            d = work / f"damaged-study-{mode[2:]}-{file.replace('/', '-')}"
            shutil.copytree(good, d)
            edit(d / file)
            r = call(binary, ["study", str(sweep), "--out", str(d), mode, "--threads", "1"], work, 300)
            if mode == "--resume" and r.code == 0:
                # --resume runs a damaged member again: right if it says so and every table is
                # the good run's, byte for byte.
                counts["invocations"] += 1
                counts["damaged study --resume exit 0"] += 1
                same = all((d / t.name).read_bytes() == t.read_bytes() for t in good.glob("*.csv"))
                if not (same and "ran again" in r.stdout and file in r.stdout):
                    counts["silent wrong results"] += 1
                    findings.append(f"WRONG damaged study --resume: {label}: tables equal {same}, "
                                    f"said: {r.stdout.strip()[:200]}")
                continue
            tally(counts, findings, f"damaged study {mode}: {label}", r,
                  want_code=r.code if r.code not in (0, None) else 2, name=file.split("/")[1])
    # Design journals: two islands, then one damaged in four ways, then --merge.
    good = work / "damaged-design"
    for k in ("1/2", "2/2"):
        r = call(binary, ["design", str(design), "--out", str(good), "--shard", k, "--threads", "1"],
                 work, 300)
        counts["invocations"] += 1
        if r.code != 0:
            findings.append(f"damaged: the tiny design island {k} failed: {r.stderr.strip()[-300:]}")
            return
    journal = "evaluations/island-1-of-2.csv"
    def cut_middle(p):
        lines = p.read_text().splitlines(keepends=True)
        lines[2] = lines[2][: len(lines[2]) // 2] + "\n"
        p.write_text("".join(lines))
    def better_objective(p):
        lines = p.read_text().splitlines(keepends=True)
        cells = lines[-1].split(",")
        for i, c in enumerate(cells):
            try:
                if "." in c or "e" in c:
                    cells[i] = repr(float(c) / 1000)
                    break
            except ValueError:
                pass
        lines[-1] = ",".join(cells)
        p.write_text("".join(lines))
    def not_utf8(p):
        p.write_bytes(p.read_bytes().replace(b"\n", b"\xff\n", 2))
    def missing(p):
        p.unlink()
    for label, edit in [("a line cut in the middle", cut_middle),
                        ("an objective edited", better_objective),
                        ("a byte that is not UTF-8", not_utf8),
                        ("an island missing", missing)]:
        d = work / f"damaged-design-{label.replace(' ', '-')}"
        shutil.copytree(good, d)
        edit(d / journal)
        r = call(binary, ["design", str(design), "--out", str(d), "--merge"], work, 300)
        tally(counts, findings, f"damaged design --merge: {label}", r,
              want_code=r.code if r.code not in (0, None) else 2, name="island-1-of-2")


def extreme(binary, work, counts, findings):
    """Values each within its own documented range, or just beyond, that together or alone
    take a run out of what it can compute: refused at once with the key (issue 38, item 9)."""
    cases = [
        ("density 1e300", '["steel", { E = 1e9, nu = 0.3, rho = 1e300 }]', "[0.006]",
         "space.materials[1]"),
        ("modulus 1e-300", '["steel", { E = 1e-300, nu = 0.3, rho = 1000 }]', "[0.006]",
         "space.materials[1]"),
        ("diameters 1 um and 1 m", '["steel"]', "[1e-6, 1.0]", "space.diameters"),
        ("1000 diameters", '["steel"]', "[" + ", ".join(str(0.001 + 1e-6 * i) for i in range(1000)) + "]",
         "space.diameters"),
    ]
    for label, materials, diameters, name in cases:
        f = work / "extreme.toml"
        f.write_text(TINY_DESIGN.format(generations=1).replace('["steel", "ptfe"]', materials)
                     .replace("diameters = [0.006]", "diameters = " + diameters))
        out = work / "extreme-out"
        r = call(binary, ["design", str(f), "--out", str(out)], work, 30)
        tally(counts, findings, f"extreme design: {label}", r, name=name)
        if out.exists():
            counts["silent wrong results"] += 1
            findings.append(f"OUTPUT LEFT BEHIND: extreme design: {label}")
            shutil.rmtree(out)
    # An SI scene with a material beyond the ranges.
    f = work / "extreme-scene.toml"
    f.write_text('[chain]\n[[chain.sections]]\ncount = 10\n'
                 'material = { E = 1e-300, nu = 0.3, rho = 1000 }\ndiameter = 0.01\n'
                 '[striker]\nend = "left"\nmaterial = "steel"\ndiameter = 0.01\nspeed = 1.0\n'
                 '[integrator]\ndt = 1e-7\n[run]\nduration = 1e-4\noutput_interval = 1e-5\n')
    tally(counts, findings, "extreme check: an SI scene of modulus 1e-300",
          call(binary, ["check", str(f)], work, 30), name="chain.sections[0].material")


# Each snippet runs in a child interpreter; it prints "refused: <message>" for a refusal of
# grainchain's (an exception the module raises with a message), "ok" when it did what was asked.
# A crash (a signal, a panic, an abort) or a wrong "ok" is a finding.
PY_PRELUDE = """
import sys, threading, numpy, grainchain
SCENE = {"chain": {"sections": [{"count": 10, "mass": 1.0, "p": 1.5, "eta": 1.0}]},
         "striker": {"end": "left", "mass": 1.0, "speed": 1.0},
         "integrator": {"method": "verlet", "dt": 1e-3},
         "run": {"duration": 1.0, "output_interval": 0.1}}
def refused(f):
    try:
        f()
    except Exception as e:
        print("refused:", type(e).__name__, e)
    else:
        print("ok")
"""
PY_CASES = [
    ("a dict holding itself", "d = dict(SCENE); d['chain'] = dict(d['chain']); d['chain']['self'] = d\n"
     "refused(lambda: grainchain.check(d))", "refused"),
    ("a list holding itself", "d = dict(SCENE); l = []; l.append(l); d['x'] = l\n"
     "refused(lambda: grainchain.check(d))", "refused"),
    ("a dict 10,000 deep", "d = dict(SCENE); x = d\nfor _ in range(10000):\n    x['a'] = {}; x = x['a']\n"
     "refused(lambda: grainchain.check(d))", "refused"),
    ("None as a value", "d = dict(SCENE); d['name'] = None\nrefused(lambda: grainchain.check(d))",
     "name"),
    ("numpy.int64 count", "import copy; d = copy.deepcopy(SCENE); "
     "d['chain']['sections'][0]['count'] = numpy.int64(10)\nrefused(lambda: grainchain.check(d))", "ok"),
    ("10**30 as a count", "import copy; d = copy.deepcopy(SCENE); "
     "d['chain']['sections'][0]['count'] = 10**30\nrefused(lambda: grainchain.check(d))", "count"),
    ("threads=-1", "from grainchain import protector\n"
     "refused(lambda: protector.evaluate_many([[('steel', 6e-3)] * 3], striker=('steel', 6e-3), "
     "speed=1.0, threads=-1))", "threads"),
    ("check_every=-1", "from grainchain import protector\n"
     "refused(lambda: protector.evaluate([('steel', 6e-3)] * 3, striker=('steel', 6e-3), "
     "speed=1.0, check_every=-1))", "check_every"),
    ("a column of 1 um and 1 m beads", "from grainchain import protector\n"
     "refused(lambda: protector.evaluate([('steel', 1e-6), ('steel', 1.0)], "
     "striker=('steel', 6e-3), speed=1.0))", "steps"),
    ("a material of density 1e300", "from grainchain import protector\n"
     "refused(lambda: protector.evaluate([({'E': 1e9, 'nu': 0.3, 'rho': 1e300}, 6e-3)] * 3, "
     "striker=('steel', 6e-3), speed=1.0))", "density"),
    ("on_output returning numpy.bool_(False)",
     "n = []\nr = grainchain.run(SCENE, on_output=lambda *a: (n.append(1), numpy.bool_(False))[1])\n"
     "print('ok' if len(n) == 1 else f'ran on after False: {len(n)} outputs')", "ok"),
    ("a run in a daemon thread at exit",
     "import copy; d = copy.deepcopy(SCENE); d['run']['duration'] = 1e4\n"
     "threading.Thread(target=lambda: grainchain.run(d), daemon=True).start()\n"
     "import time; time.sleep(0.5); print('ok')", "ok"),
]


def python_inputs(python, work, counts, findings):
    """The Python module's inputs (issue 38, items 7 and 11), each in a child interpreter."""
    for label, body, want in PY_CASES:
        start = time.monotonic()
        try:
            p = subprocess.run([python, "-c", PY_PRELUDE + body], cwd=work, capture_output=True,
                               text=True, timeout=120)
            r = Result(p.returncode, p.stderr, time.monotonic() - start, False)
            out = p.stdout.strip()
        except subprocess.TimeoutExpired:
            r, out = Result(None, "", time.monotonic() - start, True), ""
        counts["invocations"] += 1
        counts[f"python exit {'timeout' if r.timed_out else r.code}"] += 1
        if panicked(r) or "Segmentation" in r.stderr or "Fatal Python" in r.stderr:
            counts["panics"] += 1
            findings.append(f"CRASH python: {label}: exit {r.code}: {r.stderr.strip()[-300:]}")
        elif want == "ok" and out != "ok":
            counts["silent wrong results"] += 1
            findings.append(f"WRONG python: {label}: {out[-300:]} {r.stderr.strip()[-200:]}")
        elif want != "ok" and not (out.startswith("refused") and want in out):
            counts["refusals without a name"] += 1
            findings.append(f"REFUSED BADLY python: {label}: {out[-300:]} {r.stderr.strip()[-200:]}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--bin", default=str(ROOT / "target/release/grainchain"))
    ap.add_argument("--count", type=int, default=300, help="mutants in all")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--limit", type=float, default=20.0, help="seconds per invocation")
    ap.add_argument("--verbose", action="store_true")
    ap.add_argument("--python", help="a Python with the grainchain module installed: also probe "
                    "the module's inputs (each in a child interpreter)")
    a = ap.parse_args()
    binary = str(Path(a.bin).resolve())
    rng = random.Random(a.seed)
    work = Path(tempfile.mkdtemp(prefix="grainchain-probe-"))
    counts = collections.Counter()
    findings = []

    scenes = sorted((ROOT / "scenes").glob("*.toml")) + sorted((ROOT / "scenes/containers").glob("*.toml"))
    sweeps = sorted((ROOT / "studies").glob("*.toml"))
    # Sweeps name their scenes relative to themselves: mutants are written beside the original.
    for n in range(a.count):
        src = rng.choice(scenes + sweeps)
        sweep = src in sweeps
        doc = tomllib.loads(src.read_text())
        try:
            mutant, what, unknown = mutate(doc, rng)
            text = dumps(mutant)
        except (TypeError, ValueError, KeyError, IndexError):
            counts["mutation not writable"] += 1
            continue
        f = src.parent / f".probe-{n}-{src.name}"
        f.write_text(text)
        out = work / f"out-{n}"
        try:
            if sweep:
                check = call(binary, ["study", str(f), "--check"], ROOT, a.limit)
                run = call(binary, ["study", str(f), "--out", str(out), "--threads", "1"], ROOT, a.limit)
            else:
                check = call(binary, ["check", str(f)], ROOT, a.limit)
                run = call(binary, ["run", str(f), "--out", str(out)], ROOT, a.limit)
        finally:
            f.unlink()
        for name, r in (("check", check), ("run", run)):
            counts["invocations"] += 1
            counts[f"{name} exit {'timeout' if r.timed_out else r.code}"] += 1
            if panicked(r):
                counts["panics"] += 1
                findings.append(f"PANIC {name}: {src.name}: {what}: {r.stderr.strip()[-300:]}")
        if unknown is not None:
            counts["unknown keys tried"] += 1
            if check.code != 2 or unknown not in check.stderr:
                counts["unknown keys accepted"] += 1
                findings.append(f"UNKNOWN KEY ACCEPTED: {src.name}: {what}: check exit {check.code}")
        if run.code == 1:
            # A run that failed (a blow-up, a run-time refusal): listed, not counted as a defect.
            findings.append(f"run failed (exit 1): {src.name}: {what}: {run.stderr.strip()[-200:]}")
        if check.code == 0 and run.code == 2 and run.seconds < 1.0:
            counts["check passed, run refused at once"] += 1
            findings.append(f"CHECK/RUN DIFFER: {src.name}: {what}: {run.stderr.strip()[-300:]}")
        if a.verbose:
            print(f"{n:4} {src.name:32} {what[:70]:70} check {check.code} run {run.code}")
        shutil.rmtree(out, ignore_errors=True)

    # The folder rule: --force never costs a byte the user wrote.
    scene = ROOT / "scenes/single-solitary-wave.toml"
    for label, args in [
        ("run", ["run", "scene.toml"]),
        ("study", ["study", str(ROOT / "studies/smoke.toml"), "--threads", "1"]),
        ("reproduce", ["reproduce", "--only", "fig1", "--scenes", str(ROOT / "scenes")]),
    ]:
        proj = work / f"project-{label}"
        (proj / "src/nested").mkdir(parents=True)
        (proj / "src/lib.rs").write_text("pub fn f() {}\n")
        (proj / "src/nested/data.csv").write_text("t,e\n0,1\n")
        (proj / "README.md").write_text("# my project\n")
        shutil.copy(scene, proj / "scene.toml")
        outside = work / f"outside-{label}"
        outside.mkdir()
        (outside / "keep.txt").write_text("keep\n")
        (proj / "link").symlink_to(outside)
        before = snapshot(proj) | {"outside/" + k: v for k, v in snapshot(outside).items()}
        for extra in ([], ["--force"]):
            r = call(binary, [*args, "--out", ".", *extra], proj, 120)
            counts["invocations"] += 1
            counts[f"folder {label} {' '.join(extra) or 'plain'} exit {r.code}"] += 1
            if panicked(r):
                counts["panics"] += 1
                findings.append(f"PANIC folder {label}: {r.stderr.strip()[-300:]}")
        after = snapshot(proj) | {"outside/" + k: v for k, v in snapshot(outside).items()}
        lost = [k for k, v in before.items() if after.get(k) != v]
        if lost:
            counts["folders that lost bytes"] += 1
            findings.append(f"LOST in {label} --force: {lost}")

    structural(binary, work, counts, findings)
    subfolders(binary, work, counts, findings)
    damaged(binary, work, counts, findings)
    extreme(binary, work, counts, findings)
    if a.python:
        python_inputs(a.python, work, counts, findings)

    shutil.rmtree(work, ignore_errors=True)
    width = max(len(k) for k in counts)
    for k in sorted(counts):
        print(f"{k:{width}}  {counts[k]}")
    for f in findings:
        print(f)
    bad = (counts["panics"] + counts["folders that lost bytes"] + counts["unknown keys accepted"]
           + counts["silent wrong results"] + counts["refusals without a name"])
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
