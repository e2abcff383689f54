"""Reading a finished study (the output folder of ``grainchain.study`` or ``grainchain study``)
as arrays."""

from __future__ import annotations

import csv
import json
import os
from pathlib import Path
from typing import Any, Dict, List, Union

import numpy as np


def read_table(path: Union[str, "os.PathLike[str]"]) -> Dict[str, Any]:
    """A CSV file of grainchain as a dict of columns: float64 arrays for numeric columns (an
    empty field is NaN, as the files write a missing value), lists of str for the others (keys,
    notes). The files hold the shortest text that reads back as the same float, so the arrays
    are the values written, bit for bit."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    if not rows:
        return {}
    header, body = rows[0], rows[1:]
    out: Dict[str, Any] = {}
    for k, name in enumerate(header):
        col = [r[k] if k < len(r) else "" for r in body]
        try:
            out[name] = np.array([float(x) if x != "" else np.nan for x in col], dtype=np.float64)
        except ValueError:
            out[name] = col
    return out


class Study:
    """A finished study: ``tables`` (name -> dict of columns, one per CSV of the folder:
    ``ensemble``, ``fits``, ``slope``, ``alpha``, ``budget``, ...), ``members`` (member name,
    e.g. ``a-m0``, -> dict of columns of its member file), ``meta`` (member name -> its JSON:
    initial energy, steps, wall time, settings) and ``report`` (STUDY.md's text)."""

    def __init__(self, out: Union[str, "os.PathLike[str]"]) -> None:
        self.out = Path(out)
        if not (self.out / "STUDY.md").is_file():
            raise FileNotFoundError(f"{self.out}: no STUDY.md here (not a merged study folder)")
        self.report: str = (self.out / "STUDY.md").read_text()
        self.tables: Dict[str, Dict[str, Any]] = {
            p.stem: read_table(p) for p in sorted(self.out.glob("*.csv"))
        }
        self.members: Dict[str, Dict[str, Any]] = {
            p.stem: read_table(p) for p in sorted((self.out / "members").glob("*.csv"))
        }
        self.meta: Dict[str, Dict[str, Any]] = {
            p.stem: json.loads(p.read_text())
            for p in sorted((self.out / "members").glob("*.json"))
        }

    def member_names(self, key: str) -> List[str]:
        """The member names of container ``key`` (``a-m0``, ``a-m1``, ...), in member order."""
        names = sorted(
            (m for m in self.members if m.startswith(f"{key}-m")),
            key=lambda m: int(m.rsplit("-m", 1)[1]),
        )
        if not names:
            raise KeyError(f"no members of container {key!r} in {self.out}")
        return names

    def member_curves(self, key: str, column: str = "container", relative: bool = False) -> np.ndarray:
        """The members of container ``key`` as one 2-D array (members x snapshots) of one column
        of their member files (default the energy in the container, E_R); ``relative``: each
        member over its own initial energy, as the study's tables give E_R."""
        names = self.member_names(key)
        rows = [self.members[m][column] for m in names]
        if relative:
            rows = [r / self.meta[m]["initial_energy"] for r, m in zip(rows, names)]
        return np.vstack(rows)

    def __repr__(self) -> str:
        return f"Study({str(self.out)!r}, {len(self.members)} members, tables {list(self.tables)})"


def read_study(out: Union[str, "os.PathLike[str]"]) -> Study:
    """Read a finished (merged) study folder: its tables, member files and STUDY.md."""
    return Study(out)


__all__: List[str] = ["Study", "read_study", "read_table"]
