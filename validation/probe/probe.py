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

What it counts: invocations, exit codes, panics (exit 101, a signal, or "panicked" on stderr),
verdicts where `check` passes and the run then refuses the input as bad (exit 2 in under a
second, a reason knowable before running), mutants whose unknown key is accepted, and folders
that lost a byte. It prints a table and exits 1 when it found a panic, a lost byte or an
accepted unknown key.

    cargo build --release
    python3 validation/probe/probe.py --bin target/release/grainchain --count 300 --seed 1

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

Result = collections.namedtuple("Result", "code stderr seconds timed_out")


def call(binary, args, cwd, limit):
    start = time.monotonic()
    try:
        p = subprocess.run([binary, *args], cwd=cwd, capture_output=True, text=True, timeout=limit)
        return Result(p.returncode, p.stderr, time.monotonic() - start, False)
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


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--bin", default=str(ROOT / "target/release/grainchain"))
    ap.add_argument("--count", type=int, default=300, help="mutants in all")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--limit", type=float, default=20.0, help="seconds per invocation")
    ap.add_argument("--verbose", action="store_true")
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

    shutil.rmtree(work, ignore_errors=True)
    width = max(len(k) for k in counts)
    for k in sorted(counts):
        print(f"{k:{width}}  {counts[k]}")
    for f in findings:
        print(f)
    bad = counts["panics"] + counts["folders that lost bytes"] + counts["unknown keys accepted"]
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
