"""Scenes built in code: the Python equivalent of ``ChainBuilder`` and ``SimulationBuilder``.

A :class:`SceneBuilder` assembles the tables of a scene file (sections with mass, exponent p,
stiffness eta, damping and contact damping; walls; a striker; initial conditions; the integrator;
the outer medium; regions; outputs), and :meth:`SceneBuilder.build` hands them to the engine's
scene check, so a chain built in code is checked exactly as a file is (errors name ``<dict>`` and
the key) and runs exactly as the same file would.

>>> from grainchain import SceneBuilder
>>> b = (SceneBuilder("two-sections")
...      .section(100, mass=1.0, p=1.5, eta=5657.0, name="heavy")
...      .section(100, mass=0.1, p=1.5, eta=5657.0, name="light")
...      .striker("left", mass=1.0, speed=1.0)
...      .integrator("blanes-moan4", dt=1e-3)
...      .schedule(duration=10.0, output_interval=0.125)
...      .region("light", 101, 200))
>>> b.build().grains
201
"""

from __future__ import annotations

import copy
from typing import Any, Dict, List, Optional, Tuple

from ._grainchain import Scene


def _law(p: float, eta: float, tension: Optional[bool], contact_damping: Optional[Tuple[str, float]]):
    d: Dict[str, Any] = {"p": p, "eta": eta}
    if tension is not None:
        d["tension"] = tension
    if contact_damping is not None:
        model, c = contact_damping
        d["contact_damping"] = {"model": model, "c": c}
    return d


class SceneBuilder:
    """Build a scene in code, section by section (left to right), then :meth:`build` it.

    Every method returns the builder, so calls chain. Grain numbers (regions, initial
    conditions) are the printed ones of scene files: chain grains from 1, a left striker 0.
    """

    def __init__(self, name: Optional[str] = None, description: Optional[str] = None) -> None:
        self._d: Dict[str, Any] = {"chain": {"sections": []}}
        if name is not None:
            self._d["name"] = name
        if description is not None:
            self._d["description"] = description

    def section(
        self,
        count: int,
        mass: float,
        p: float = 1.5,
        eta: float = 5657.0,
        *,
        name: Optional[str] = None,
        damping: Optional[float] = None,
        tension: Optional[bool] = None,
        contact_damping: Optional[Tuple[str, float]] = None,
    ) -> "SceneBuilder":
        """Add ``count`` grains of mass ``mass`` whose contacts follow ``F = eta delta^p``.

        ``damping``: a rate damping each grain against the ground; ``tension``: contacts that
        also pull; ``contact_damping``: ``(model, c)``, a dashpot in parallel with each contact
        (model ``"viscous"`` or the others of the scene file's ``contact_damping.model``).
        """
        s: Dict[str, Any] = {"count": count, "mass": mass, **_law(p, eta, tension, contact_damping)}
        if name is not None:
            s["name"] = name
        if damping is not None:
            s["damping"] = damping
        self._d["chain"]["sections"].append(s)
        return self

    def wall(
        self,
        side: str,
        p: float = 1.0,
        eta: float = 5657.0,
        *,
        delta0: Optional[float] = None,
        tension: Optional[bool] = None,
        contact_damping: Optional[Tuple[str, float]] = None,
    ) -> "SceneBuilder":
        """A rigid wall at the ``"left"`` or ``"right"`` end with its own contact law (an end is
        free unless a wall is put there)."""
        w = {"kind": "wall", **_law(p, eta, tension, contact_damping)}
        if delta0 is not None:
            w["delta0"] = delta0
        self._d["chain"][_side(side)] = w
        return self

    def interface(self, rule: str) -> "SceneBuilder":
        """The law of a contact between sections of different laws (e.g. ``"min-exponent"``)."""
        self._d["chain"]["interface"] = rule
        return self

    def outer(self, medium: str, **keys: Any) -> "SceneBuilder":
        """The outer medium of a container scene (``"long"``, ``"free-ends"``,
        ``"ground-damped"``, ``"dashpot"`` with their keys, e.g. ``distance=300``)."""
        self._d["chain"]["outer"] = {"medium": medium, **keys}
        return self

    def striker(
        self, end: str, mass: float, speed: float, *, p: Optional[float] = None,
        eta: Optional[float] = None,
    ) -> "SceneBuilder":
        """A striker grain at the free ``end`` (``"left"``/``"right"``) moving in at ``speed``."""
        s: Dict[str, Any] = {"end": end, "mass": mass, "speed": speed}
        if p is not None:
            s["p"] = p
        if eta is not None:
            s["eta"] = eta
        self._d["striker"] = s
        return self

    def initial(
        self, grain: Optional[int] = None, *, first: Optional[int] = None,
        last: Optional[int] = None, velocity: Optional[float] = None,
        displacement: Optional[float] = None,
    ) -> "SceneBuilder":
        """An initial velocity and/or displacement of one grain or of grains first..last."""
        g: Dict[str, Any] = {}
        for k, v in [("grain", grain), ("first", first), ("last", last), ("velocity", velocity),
                     ("displacement", displacement)]:
            if v is not None:
                g[k] = v
        self._d.setdefault("initial", []).append(g)
        return self

    def integrator(self, method: str, dt: Optional[float] = None, **keys: Any) -> "SceneBuilder":
        """The integration method and step, and any other key of ``[integrator]`` (``rtol``,
        ``atol``, ``skip_untouched``, ``max_energy_error``, ``sleep``, ``multirate``, ``events``)."""
        d: Dict[str, Any] = {"method": method, **keys}
        if dt is not None:
            d["dt"] = dt
        self._d["integrator"] = d
        return self

    def schedule(self, duration: float, output_interval: float, *,
                 horizon: Optional[Dict[str, Any]] = None) -> "SceneBuilder":
        """The run: simulated ``duration`` and time between outputs (``[run]``); ``horizon``:
        the causal horizon's table (``{}`` for the default)."""
        r: Dict[str, Any] = {"duration": duration, "output_interval": output_interval}
        if horizon is not None:
            r["horizon"] = horizon
        self._d["run"] = r
        return self

    def region(self, name: str, first: int, last: int) -> "SceneBuilder":
        """A named region, printed grains first..last: its energy and momentum are recorded."""
        self._d.setdefault("regions", []).append({"name": name, "first": first, "last": last})
        return self

    def output(self, *, energies: bool = True, snapshots: Optional[Dict[str, Any]] = None,
               pulses: Optional[Dict[str, Any]] = None,
               tracks: Optional[Dict[str, Any]] = None) -> "SceneBuilder":
        """What the run records (``[output]``): e.g. ``snapshots={"fields": ["velocity"],
        "every": 8}``."""
        o: Dict[str, Any] = {"energies": energies}
        for k, v in [("snapshots", snapshots), ("pulses", pulses), ("tracks", tracks)]:
            if v is not None:
                o[k] = v
        self._d["output"] = o
        return self

    def to_dict(self) -> Dict[str, Any]:
        """The scene as a dict with the tables and keys of a scene file (a copy)."""
        d = copy.deepcopy(self._d)
        d.setdefault("output", {"energies": True})
        return d

    def build(self, *, allow_large_output: bool = False) -> Scene:
        """Check the scene (``SceneError`` naming ``<dict>`` and the key) and return it."""
        return Scene.from_dict(self.to_dict(), allow_large_output=allow_large_output)


def _side(side: str) -> str:
    if side not in ("left", "right"):
        raise ValueError(f"a wall is at the 'left' or 'right' end, not {side!r}")
    return side


__all__: List[str] = ["SceneBuilder"]
