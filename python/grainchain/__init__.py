"""grainchain from Python: one-dimensional power-law granular chains (Hong, PRL 94, 108001, 2005).

Scenes (a file, a TOML string or a dict), runs with NumPy arrays out, the problems catalogue, the
analysis of the remaining energy, chains built in code, granular protectors in real materials
evaluated for your own optimiser (``grainchain.protector``), and the harness's studies and paper
reproduction. The numbers are those of the ``grainchain`` command-line tool, bit for bit: the
same engine, the same recorder.

>>> import grainchain
>>> r = grainchain.run("scenes/containers/a-standard.toml")     # doctest: +SKIP
>>> r.energies["E_container"]                                   # doctest: +SKIP
array([0., 0., ..., 0.0123])

The engine runs without the GIL (other Python threads go on), Ctrl-C stops a run within half a
second with ``KeyboardInterrupt``, a run left going in a daemon thread ends quietly with the
interpreter at exit, and every error is an exception carrying the CLI's text:
``SceneError`` (a ``ValueError``: file, key, what is wrong), ``BlowUpError`` (time, step, grain),
``RunError``, ``StudyError``, ``DesignError`` (a ``ValueError``: a protector design's place and
key), and ``InternalError`` for a Rust panic.
"""

from __future__ import annotations

import os
from typing import Any, Callable, Dict, Mapping, Optional, Union

import numpy as np

from . import _grainchain
from ._grainchain import (  # noqa: F401  (re-exported)
    BlowUpError,
    DesignError,
    InternalError,
    RunError,
    Scene,
    SceneError,
    StudyError,
    __version__,
    check,
    reproduce,
    study,
)

from . import analysis, problems, protector  # noqa: E402,F401  (namespaces)
from .builder import SceneBuilder  # noqa: E402
from .studies import Study, read_study, read_table  # noqa: E402

SceneLike = Union["Scene", str, "os.PathLike[str]", Mapping[str, Any]]

__all__ = [
    "BlowUpError",
    "DesignError",
    "InternalError",
    "RunError",
    "RunResult",
    "Scene",
    "SceneBuilder",
    "Study",
    "SceneError",
    "StudyError",
    "analysis",
    "problems",
    "protector",
    "check",
    "read_study",
    "read_table",
    "reproduce",
    "run",
    "study",
]


class RunResult:
    """The outputs of one run, as NumPy arrays.

    Attributes:
        scene: the scene's name.
        finished: whether the run reached its end (False when the callback stopped it).
        energies: ``dict`` from the column names of ``energies.csv`` (``index``, ``time``,
            ``kinetic``, ``potential``, ``total``, ``momentum``, [``dissipated``], ``E_<region>``,
            ``P_<region>``, [``D_<region>``]) to 1-D float64 arrays, one value per output; empty
            when the scene does not ask for energies.
        snapshots: ``dict`` from field name (``displacement``, ``velocity``, ...) to a 2-D float64
            array of shape (snapshots, grains), row k taken at ``snapshot_time[k]``.
        snapshot_index, snapshot_time: output index (int64) and time (float64) of each snapshot.
        snapshot_grains: printed grain number (int64) of each snapshot column.
        pulses, tracks: ``dict`` of 1-D float64 columns with the names of ``pulses.csv`` /
            ``tracks.csv``, or None when the scene does not ask for them.
        summary: the run's ``summary.json`` as a dict (steps, force and grain evaluations, the
            timings of the run loop, energy errors, wall time).
    """

    __slots__ = (
        "scene",
        "finished",
        "energies",
        "snapshots",
        "snapshot_index",
        "snapshot_time",
        "snapshot_grains",
        "pulses",
        "tracks",
        "summary",
    )

    def __init__(self, raw: Dict[str, Any]) -> None:
        for k in self.__slots__:
            setattr(self, k, raw[k])

    def to_pandas(self, table: str = "energies") -> Any:
        """One table as a ``pandas.DataFrame`` (pandas must be installed; it is not a dependency).

        ``table`` is ``"energies"``, ``"pulses"``, ``"tracks"`` or ``"snapshots"`` (long format,
        as ``snapshots.csv``: index, time, grain, then one column per field).
        """
        import pandas as pd  # only here: pandas is optional

        if table == "energies":
            return pd.DataFrame(self.energies)
        if table in ("pulses", "tracks"):
            cols = getattr(self, table)
            if cols is None:
                raise ValueError(f"the scene asks for no {table}")
            return pd.DataFrame(cols)
        if table == "snapshots":
            n, g = len(self.snapshot_index), len(self.snapshot_grains)
            d = {
                "index": np.repeat(self.snapshot_index, g),
                "time": np.repeat(self.snapshot_time, g),
                "grain": np.tile(self.snapshot_grains, n),
            }
            for name, a in self.snapshots.items():
                d[name] = a.reshape(-1)
            return pd.DataFrame(d)
        raise ValueError(f"no table {table!r}: energies, snapshots, pulses or tracks")

    def __repr__(self) -> str:
        n = len(self.energies.get("time", ()))
        return (
            f"RunResult({self.scene!r}, {n} rows, {len(self.snapshot_index)} snapshots, "
            f"finished={self.finished})"
        )


def run(
    scene: SceneLike,
    *,
    on_output: Optional[Callable[[float, Dict[str, float]], object]] = None,
    allow_large_output: bool = False,
) -> RunResult:
    """Run a scene and return its outputs as NumPy arrays (a :class:`RunResult`).

    Args:
        scene: a :class:`Scene`, a path to a scene file, TOML text, or a dict with the scene
            file's tables and keys.
        on_output: called at t = 0 and at every output time as ``on_output(time, values)``, with
            ``values`` the row of ``energies.csv`` at that output (column name -> float; empty
            when the scene records no energies). Returning a false value stops the run, by
            Python's truth (``False``, ``numpy.False_``, ``0``; but ``None``, what a function
            without ``return`` gives, goes on): the result then has ``finished = False`` and what
            was recorded so far. An exception it raises (or its return value's ``__bool__``
            raises) stops the run and propagates.
        allow_large_output: run even if the outputs, or the simulation's memory, are estimated
            at more than 1 GB (the CLI's ``--allow-large-output``).

    Raises:
        SceneError: the scene cannot be used (the message names the file and the key).
        BlowUpError: a numerical blow-up (attributes ``time``, ``step``, ``grain``).
        RunError: other run failures. KeyboardInterrupt: Ctrl-C (within half a second).
    """
    return RunResult(
        _grainchain._run(scene, on_output=on_output, allow_large_output=allow_large_output)
    )
