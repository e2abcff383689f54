"""Shared fixtures: the repository root, the `grainchain` CLI (built by cargo if needed), helpers
to read the CLI's CSV files."""

import csv
import json
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "scenes"
CONTAINER_A = SCENES / "containers" / "a-standard.toml"


@pytest.fixture(scope="session")
def root() -> Path:
    return ROOT


@pytest.fixture(scope="session")
def cli() -> str:
    """The `grainchain` binary: $GRAINCHAIN_CLI, else built with `cargo build --release` (a no-op
    when it is up to date) and found through cargo's own report of the executable."""
    if os.environ.get("GRAINCHAIN_CLI"):
        return os.environ["GRAINCHAIN_CLI"]
    out = subprocess.run(
        ["cargo", "build", "--release", "--bin", "grainchain", "--message-format=json"],
        cwd=ROOT,
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    for line in out.splitlines():
        msg = json.loads(line)
        if msg.get("reason") == "compiler-artifact" and msg.get("executable"):
            if msg["target"]["name"] == "grainchain":
                return msg["executable"]
    raise RuntimeError("cargo built no grainchain executable")


def read_csv(path: Path):
    """A CSV file of the CLI as (header, rows of strings)."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return rows[0], rows[1:]


def csv_columns(path: Path) -> dict:
    """A CSV file of the CLI as column name -> float64 array. The CLI writes the shortest text
    that reads back as the same float (Rust's `{}` for f64), so `float()` of it is the exact
    value: comparing with == is comparing the bits."""
    header, rows = read_csv(path)
    return {
        name: np.array([float(r[k]) if r[k] != "" else np.nan for r in rows], dtype=np.float64)
        for k, name in enumerate(header)
    }
