"""Granular protectors in real materials (Rust: ``grainchain_engine::protector``): evaluate a
column of spheres between a striker and what it protects by the force on the protected face, for
scripts that drive their own optimisers. SI units throughout (m, kg, s, N, J).

A design is a list of beads from the struck end to the protected one; a bead is a
``(material, diameter)`` pair (or a dict ``{"material", "diameter"}``), the material a name of
:func:`materials` (``"steel"``, ``"ptfe"``, ...) or a dict ``{"E": Pa, "nu": -, "rho": kg/m^3}``
(with an optional ``"name"``, checked as a scene file's), the diameter in metres::

    from grainchain import protector

    beads = [("steel", 6e-3)] * 20 + [("ptfe", 6e-3)] * 20
    r = protector.evaluate(beads, striker=("steel", 6e-3), speed=1.0)
    r["peak_force"]                        # N, the largest force on the wall over every step

    designs = [beads, beads[::-1], [("steel", 6e-3)] * 40]
    batch = protector.evaluate_many(designs, striker=("steel", 6e-3), speed=1.0, threads=2)
    batch["peak_force"]                    # float64 array, one value per design, input order

:func:`evaluate` gives a dict for one design, :func:`evaluate_many` a dict of NumPy arrays (one
per field, one entry per design in input order), each entry the same bits as :func:`evaluate` of
that design alone, at every thread count.
:func:`estimate` evaluates one design three times (at twice the step given, at it and at half of
it) and returns the finest run with each number's error and whether its peak is only a lower bound
(``bound``), as ``grainchain design`` reports its designs; ``accuracy`` sets the step by the design
file's rule.

The fields (both forms): ``peak_force`` (N, the largest force on the protected face over every
step), ``peak_time`` (s), ``impulse`` (N s, the force's integral up to the end of the run: final
with ``need="everything"`` and ``complete``), ``duration`` (s at or above ``fraction`` of the
peak: final with ``need="duration"`` or ``"everything"``), ``target_energy`` (J, the target's
largest energy; 0 for a wall), ``rebound`` (m/s, the striker's velocity at the end, negative when
it bounced back; final when ``rebound_final``), ``rebound_final`` (bool), ``mass`` (kg) and
``length`` (m) of the column, ``time`` (s reached), ``steps`` (int), ``dt`` (s, the step),
``complete`` (bool: the exact stop rule ended the run, else the time cap did, or the run gave
up), ``given_up`` (bool: it gave up at ``give_up_above``; ``peak_force`` is a lower bound).

With ``gradients=True``, :func:`evaluate` also returns the exact derivatives of its numbers with
respect to every bead's diameter and material constants and to the striker's speed and mass
(``r["gradients"]["peak"]["diameter"][k]``: N per m of ``beads[k]``'s diameter), for an optimiser
that follows slopes; :func:`evaluate`'s doc gives the structure.

A run stops as soon as no later step can change what ``need`` asks for (the rule and its proof:
``engine/src/protector/stop.rs``), so ``need="peak"`` is the cheapest. Bad input raises
:class:`DesignError` (a ``ValueError``) naming the place (``beads[2]``, ``designs[1][2]``:
indices into your lists, from 0) and the key; a numerical blow-up raises ``BlowUpError``.
"""

from __future__ import annotations

from typing import Any, Callable, Dict, Iterable, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _grainchain
from ._grainchain import DesignError  # noqa: F401  (re-exported)

MaterialLike = Union[str, Mapping[str, float]]
BeadLike = Union[Tuple[MaterialLike, float], Sequence[Any], Mapping[str, Any]]

__all__ = ["DesignError", "estimate", "evaluate", "evaluate_many", "materials", "monte_carlo"]


def materials() -> Dict[str, Dict[str, float]]:
    """The materials table: ``{name: {"E": Pa, "nu": -, "rho": kg/m^3}}`` (typical data-sheet
    values; a grade's own sheet may differ by 5-10 %). Any name, or any dict of these three keys,
    is a material for :func:`evaluate`."""
    return _grainchain.protector_materials()


def evaluate(
    beads: Sequence[BeadLike],
    *,
    striker: BeadLike,
    speed: float,
    wall: Optional[MaterialLike] = None,
    target: Optional[Mapping[str, Any]] = None,
    restitution: Optional[float] = None,
    restitution_pairs: Optional[Sequence[Tuple[MaterialLike, MaterialLike, float]]] = None,
    need: str = "peak",
    fraction: Optional[float] = None,
    accuracy: Optional[float] = None,
    steps_per_contact: Optional[float] = None,
    check_every: Optional[int] = None,
    time_cap: Optional[float] = None,
    give_up_above: Optional[float] = None,
    gradients: bool = False,
) -> Dict[str, Any]:
    """Evaluate one design; a dict of the fields listed in the module's doc (with
    ``gradients=True`` also ``"gradients"``, below).

    Args:
        beads: the column, from the struck end to the protected one: ``(material, diameter)``
            pairs (or dicts ``{"material", "diameter"}``), diameters in metres.
        striker: the striker sphere, a ``(material, diameter)`` pair.
        speed: its speed towards the column, m/s.
        wall: the material of the rigid wall the column ends on (default ``"steel"``); or
        target: instead of a wall, a body ``{"mass": kg, "material": ..., "spring": N/m}`` held
            by a linear spring to ground (``spring`` 0 or left out: a free body).
        restitution: every contact's coefficient of restitution, in [0.05, 1) (None: elastic),
            but for the pairs of ``restitution_pairs``.
        restitution_pairs: pairs of materials with a restitution of their own, a list of
            ``(material, material, restitution)`` triples (materials as a bead's, in either
            order; the same one twice: its contacts with itself; restitution in [0.05, 1], 1
            elastic): ``[("steel", "ptfe", 0.9)]`` damps every steel-PTFE contact, the striker's,
            the wall's and the target's included. Materials are matched by name. Every contact's
            dashpot is the scale-respecting one, whose restitution is the same at every speed.
        need: what must be exact, ``"peak"`` (the peak force), ``"duration"`` (and the time above
            ``fraction`` of it) or ``"everything"`` (run until nothing can touch the face again).
        fraction: the fraction of the peak ``duration`` counts above (None: 0.5).
        accuracy: the relative error wanted of the peak force (and of the impulse and the
            duration where they are final), 1e-9 to 1e-2: sets ``steps_per_contact`` to
            ``max(8, 20 * (1e-5 / accuracy) ** 0.4)`` (the design file's ``[search] accuracy`` rule,
            calibrated on a 40-bead column; a column whose peak comes after many reflections
            needs more: :func:`estimate` tells). Give it or ``steps_per_contact``, not both.
        steps_per_contact: steps per contact time of the stiffest pair at the whole impact
            energy, of blanes-moan4 with contact events (None: 20, accuracy 1e-5: the peak force
            to 6e-7 on the 40-bead reference column, to about 4e-5 on a column whose peak comes
            after many reflections).
        check_every: steps between two checks of the stop rule (None: 32).
        time_cap: the run ends at this many times the sum of every contact's time if the rule
            has not stopped it (None: 100; ``complete`` says which).
        give_up_above: with ``need="peak"``, a force in N: the run gives up on the design once
            its peak reaches it and the force has fallen back below half the peak (the pulse
            has passed); ``peak_force`` is then a lower bound and ``given_up`` is True. For an
            optimiser that only needs to know a design is worse than its best (None: never).
        gradients: also the derivatives of the numbers (``True`` or ``False``; default False,
            when the result is what it always was). The fields above stay the same bits.

    With ``gradients=True`` the dict has one more key, ``"gradients"``: the exact derivatives of
    the *discrete* run as evaluated (the same step, method, contact events, located peak and
    stop rule), not of the exact motion the run approximates. They are computed in reverse
    mode: the run recorded, then one sweep back through it with every reported number's
    adjoint (the engine's ``grainchain_engine::protector::gradients``, bit for bit), which
    costs about 8 plain runs on the 40-bead reference column whatever the number of beads
    (BENCHMARKS.md), plus the plain run that gives the fields above. A run whose record would
    pass 1 GB or 1e9 grain-steps at its time cap is refused before it starts (key
    ``"gradients"``). The GIL is released meanwhile, and Ctrl-C stops the run within a second
    (KeyboardInterrupt).
    It holds:

    - ``"peak"``, ``"impulse"``, ``"duration"``, ``"target_energy"``, ``"rebound"``: the
      derivatives of ``peak_force``, ``impulse``, ``duration``, ``target_energy`` and
      ``rebound``, each a dict of float64 arrays of ``len(beads)`` entries (struck end first),
      keyed as a material's dict: ``"diameter"`` (per m), ``"rho"`` (per kg/m^3), ``"E"`` (per
      Pa), ``"nu"`` (per unit of Poisson's ratio), and floats ``"speed"`` (per m/s) and
      ``"striker_mass"`` (per kg: the striker's density changed at its diameter). The units are
      the number's over the parameter's: ``r["gradients"]["peak"]["E"][3]`` is N per Pa of
      ``beads[3]``'s Young's modulus. The duration counts whole steps, so its derivative is
      that of the step alone; a number that is zero throughout (``target_energy`` with a wall)
      has zero derivatives.
    - ``"tie"``: None, or a dict ``{"time": s, "force": N, "peak": {...}}`` when another
      instant reaches the peak force within 1e-12 of it: the peak is then the larger of two
      branches and has no derivative; ``"peak"`` above is one branch's slope, this the other's
      (along a direction, the peak's one-sided slope is the larger of the two).
    - ``"step_shared"``: True when several contacts share the shortest contact time that sets
      the step (a column of equal beads): the step is the minimum of equal branches, and the
      part of each derivative that comes through the step (of the size of the method's error)
      is the first such contact's.
    - ``"evaluation"``: the numbers of the run the derivatives are of, the fields above as the
      run with derivatives finds them, equal to the dict's to rounding (about 1e-12 relative: it
      sums the same terms in another order).

    Gradients refuse damped contacts: with ``restitution`` or a pair below 1 they raise
    :class:`DesignError` (key ``"gradients"``).

    Raises:
        DesignError: bad input (the message names the place and the key).
        BlowUpError: a numerical blow-up.
        TypeError: ``gradients`` is not a bool.
    """
    return _grainchain.protector_evaluate(
        beads,
        striker=striker,
        speed=speed,
        wall=wall,
        target=target,
        restitution=restitution,
        restitution_pairs=restitution_pairs,
        need=need,
        fraction=fraction,
        accuracy=accuracy,
        steps_per_contact=steps_per_contact,
        check_every=check_every,
        time_cap=time_cap,
        give_up_above=give_up_above,
        gradients=gradients,
    )


def evaluate_many(
    designs: Iterable[Sequence[BeadLike]],
    *,
    striker: BeadLike,
    speed: float,
    wall: Optional[MaterialLike] = None,
    target: Optional[Mapping[str, Any]] = None,
    restitution: Optional[float] = None,
    restitution_pairs: Optional[Sequence[Tuple[MaterialLike, MaterialLike, float]]] = None,
    need: str = "peak",
    fraction: Optional[float] = None,
    accuracy: Optional[float] = None,
    steps_per_contact: Optional[float] = None,
    check_every: Optional[int] = None,
    time_cap: Optional[float] = None,
    give_up_above: Optional[float] = None,
    threads: int = 1,
) -> Dict[str, np.ndarray]:
    """Evaluate a batch of designs on ``threads`` threads, all under the same load and settings
    (the arguments of :func:`evaluate`).

    Returns a dict of NumPy arrays, one per field of the module's doc (float64; ``steps`` uint64;
    ``rebound_final``, ``complete`` and ``given_up`` bool), entry ``k`` for ``designs[k]``: the same bits as
    ``evaluate(designs[k], ...)`` at every thread count. ``np.argmin(r["peak_force"])`` is the
    best design of the batch by the peak force.

    The GIL is released while designs run; Ctrl-C stops the batch (``KeyboardInterrupt``) after
    the chunk under way, sized to take about 0.1 s (at least one design per thread; a design is
    not interrupted, and a dear one, millions of steps, takes seconds). The whole
    batch fails on the first bad design (its index is the exception's ``design``).
    """
    return _grainchain.protector_evaluate_many(
        designs,
        striker=striker,
        speed=speed,
        wall=wall,
        target=target,
        restitution=restitution,
        restitution_pairs=restitution_pairs,
        need=need,
        fraction=fraction,
        accuracy=accuracy,
        steps_per_contact=steps_per_contact,
        check_every=check_every,
        time_cap=time_cap,
        give_up_above=give_up_above,
        threads=threads,
    )


def estimate(
    beads: Sequence[BeadLike],
    *,
    striker: BeadLike,
    speed: float,
    wall: Optional[MaterialLike] = None,
    target: Optional[Mapping[str, Any]] = None,
    restitution: Optional[float] = None,
    restitution_pairs: Optional[Sequence[Tuple[MaterialLike, MaterialLike, float]]] = None,
    need: str = "peak",
    fraction: Optional[float] = None,
    accuracy: Optional[float] = None,
    steps_per_contact: Optional[float] = None,
    check_every: Optional[int] = None,
    time_cap: Optional[float] = None,
    to_end: bool = False,
) -> Dict[str, Any]:
    """Evaluate one design three times, at twice the step the arguments give, at it and at half
    of it, and state each number's error, as ``grainchain design`` reports its designs (the
    arguments of :func:`evaluate`).

    Returns a dict: ``value`` (the finest run's fields, as :func:`evaluate` returns them: the
    numbers to report), ``coarse`` (the run at the step given), ``coarsest`` (at twice it, and at
    least 4 steps per contact time), ``peak_error`` (N, the larger of ``|value - coarse|`` and
    ``|coarse - coarsest|`` of the peak force: one difference can be small by chance where a
    Hertz peak converges erratically; the larger bounded the error on two brute-forced spaces
    checked against an independent integration), ``impulse_error`` (N s, likewise; None when the
    impulse is not final: ``need`` is not ``"everything"`` or a run reached its cap),
    ``duration_error`` (s; None when the duration is not final: ``need="peak"`` or a run
    reached its cap), ``bound`` (True when a run reached its time cap before the stop rule
    proved the peak: the peak is then at least ``value["peak_force"] - peak_error``, which is
    what ``grainchain design`` reports) and ``time_cap`` (the cap the runs had). With ``to_end=True`` a bound is run again at ten times the cap, until
    the peak is proven or the finer run would pass 1e8 force evaluations of the chain (1.7e7
    steps of blanes-moan4, whose step is six evaluations; the step limit of 1e8 steps for
    Verlet).

    Raises:
        DesignError: bad input (the message names the place and the key).
        BlowUpError: a numerical blow-up.
    """
    return _grainchain.protector_estimate(
        beads,
        striker=striker,
        speed=speed,
        wall=wall,
        target=target,
        restitution=restitution,
        restitution_pairs=restitution_pairs,
        need=need,
        fraction=fraction,
        accuracy=accuracy,
        steps_per_contact=steps_per_contact,
        check_every=check_every,
        time_cap=time_cap,
        to_end=to_end,
    )


def monte_carlo(
    beads: Sequence[BeadLike],
    *,
    striker: BeadLike,
    speed: float,
    tolerances: Mapping[str, float],
    samples: int,
    seed: int = 1,
    stream: int = 0,
    statistic: str = "p95",
    wall: Optional[MaterialLike] = None,
    target: Optional[Mapping[str, Any]] = None,
    restitution: Optional[float] = None,
    restitution_pairs: Optional[Sequence[Tuple[MaterialLike, MaterialLike, float]]] = None,
    accuracy: Optional[float] = None,
    steps_per_contact: Optional[float] = None,
    check_every: Optional[int] = None,
    time_cap: Optional[float] = None,
    threads: int = 1,
    progress: Optional[Callable[[int, int], Any]] = None,
) -> Dict[str, Any]:
    """The peak force of one design under manufacturing tolerances, by a seeded Monte Carlo with
    the common random numbers of ``grainchain design``'s robust objectives: the draws depend only
    on ``seed``, ``stream``, the tolerances and the number of beads, so every design of one
    length meets the same draws, and the first ``k`` of ``samples`` draws are those of
    ``samples=k``. With the design file's seed, stream 0 and ``samples`` its ``screen`` (or
    ``confirm``), the peaks are its search's (finalists.csv); with stream 1 and its ``samples``,
    its winners' fresh draws (winners.csv), bit for bit.

    Args:
        beads, striker, speed, wall, target, restitution, restitution_pairs, accuracy,
            steps_per_contact, check_every, time_cap: as for :func:`evaluate` (the peak is what
            is needed).
        tolerances: relative standard deviations ``{"diameter", "E", "rho", "speed"}`` (any of
            them; 0.01 is 1 %, each in [0, 0.2]): each bead's diameter, modulus and density is
            multiplied by ``1 + sigma z`` (``z`` standard normal cut at 4), the speed once per
            draw.
        samples: the draws, 1 to 100000.
        seed, stream: the ChaCha8 stream the draws come from (the design file's
            ``[tolerances] seed``, default its search's; stream 0 is the search's, 1 the fresh
            draws the winners are judged on).
        statistic: ``"mean"`` or a percentile ``"pNN"`` (``"p95"``, ``"p99.9"``).
        threads: threads for the draws (the results do not depend on it).
        progress: called as ``progress(done, total)`` after each chunk of draws, on the calling
            thread: ``tqdm`` is ``bar = tqdm(total=n)`` and ``progress=lambda d, t: bar.update(d -
            bar.n)``. Ctrl-C is seen between chunks (a tenth of a second of draws each).

    Returns a dict: ``statistic`` (its name), ``value`` (N), ``low`` and ``high`` (its 95 %
    interval: the mean's from its standard error, a percentile's distribution-free from the
    order statistics), ``mean`` and ``sd`` (N), ``samples``, ``bounds`` (draws whose run reached
    its time cap before its peak was proven: their peak, a lower bound, counts), ``peaks`` (N,
    float64, in draw order) and ``complete`` (bool, per draw).

    Raises:
        DesignError: bad input (the message names the key).
        BlowUpError: a numerical blow-up.
    """
    return _grainchain.protector_monte_carlo(
        beads,
        striker=striker,
        speed=speed,
        tolerances=tolerances,
        samples=samples,
        seed=seed,
        stream=stream,
        statistic=statistic,
        wall=wall,
        target=target,
        restitution=restitution,
        restitution_pairs=restitution_pairs,
        accuracy=accuracy,
        steps_per_contact=steps_per_contact,
        check_every=check_every,
        time_cap=time_cap,
        threads=threads,
        progress=progress,
    )
