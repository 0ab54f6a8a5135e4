"""Automatic tuning: the cheapest settings of an engine that meet a target error.

:func:`tune` walks ladders of the engine's cost knobs (time steps, iterations,
sub-steps) from its defaults, refining until the target holds and then
coarsening while it still does; every run goes through
:func:`rockbench.studies.sweep.run_points` (measured, recorded as ``tune``).
"""

from __future__ import annotations

import math
import typing
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rockbench.engines import KnobRole, engine_class
from rockbench.runner import ExecutionOptions
from rockbench.scenarios import Scenario
from rockbench.studies.sweep import SweepError, SweepPoint, run_points

__all__ = ["tune", "TuneResult", "tunable_knobs", "KIND"]

#: The store's ``kind`` of runs made by this study.
KIND = "tune"
#: The roles whose knobs are tuned by default: what sets the cost.
COST_ROLES = (KnobRole.TIME_STEP, KnobRole.ITERATIONS, KnobRole.SUBSTEPS)


def tunable_knobs(engine: str) -> dict[str, str]:
    """The cost knobs of an engine (its time step, iterations and sub-steps, as it declares
    them in ``knob_roles``) that hold a number: knob → ``"smaller"`` or ``"larger"``.

    ``smaller`` means a smaller value is finer (time steps, tolerances),
    ``larger`` a larger one (iterations, sub-steps).
    """
    cls = engine_class(engine)
    hints = typing.get_type_hints(cls.Settings)
    return {k: role.finer for k, role in cls.knob_roles.items()
            if role in COST_ROLES and role.finer is not None and hints[k] in (int, float)}


def _ladder(default: Any, direction: str, kind: type) -> list[Any]:
    """Values of a knob from the coarsest (cheapest) to the finest."""
    if direction == "smaller":
        return [float(f"{default * 2.0 ** k:.6g}") for k in (3, 2, 1, 0, -1, -2, -3)]
    vals = sorted({max(1, round(default * 2.0 ** k)) for k in (-3, -2, -1, 0, 1, 2, 3)})
    return [kind(v) for v in vals]


@dataclass
class TuneResult:
    """Outcome of :func:`tune`."""

    engine: str
    target: float
    metric: str
    best: SweepPoint | None
    evaluated: list[SweepPoint]
    ladders: dict[str, list[Any]]


def tune(
    scenario: Scenario,
    engine: str,
    target: float,
    *,
    knobs: Sequence[str] | None = None,
    base: Mapping[str, Any] | None = None,
    metric: str = "max_error",
    budget: int = 30,
    db: Path | None = None,
    execution: ExecutionOptions | None = None,
    on_point: Callable[[SweepPoint], None] | None = None,
) -> TuneResult:
    """Search the cheapest settings of ``engine`` that meet ``target`` on ``scenario``.

    Each tuned knob gets a ladder of values around its default (×2 steps, from
    8× coarser to 8× finer). Starting from the defaults, while the target is
    not met every round evaluates (in parallel) the points one rung finer in
    each knob and moves to the one with the smallest error; once it is met,
    it moves one rung coarser in the knob that saves most while the target
    still holds. At most ``budget`` runs. Among the points that meet the
    target and cost within 15 % of the cheapest (wall times are noisy), the
    coarsest settings win.

    Parameters
    ----------
    scenario : Scenario
        The problem.
    engine : str
        Engine to tune.
    target : float
        Largest acceptable error metric.
    knobs : sequence of str, optional
        Knobs to tune (default: :func:`tunable_knobs`).
    base : mapping, optional
        Other settings (preset, fixed knobs).
    metric : str
        One of :data:`ERROR_METRICS`.
    budget : int
        Largest number of runs.
    db, execution, on_point
        As in :func:`rockbench.studies.sweep.run_sweep`.

    Raises
    ------
    SweepError
        No tunable knob, or an unknown one.
    """
    auto = tunable_knobs(engine)
    cls = engine_class(engine)
    hints = typing.get_type_hints(cls.Settings)
    if knobs:
        bad = [k for k in knobs if k not in hints]
        if bad:
            raise SweepError(f"engine {engine!r} has no knob {bad[0]!r}; knobs: "
                             f"{', '.join(hints)}")
        kinds = {k: auto.get(k, "larger" if hints[k] is int else "smaller") for k in knobs}
        wrong = [k for k in knobs if hints[k] not in (int, float)]
        if wrong:
            raise SweepError(f"--knob {wrong[0]} is not numeric: it cannot be tuned")
    else:
        kinds = auto
    if not kinds:
        raise SweepError(f"no cost knob of {engine!r} recognised; name them with --knob")
    base = dict(base or {})
    preset = base.get("preset")
    defaults = cls.settings(preset, **{k: v for k, v in base.items() if k != "preset"})
    ladders = {k: _ladder(getattr(defaults, k), d, hints[k]) for k, d in kinds.items()}
    names = list(ladders)
    seen: dict[tuple[int, ...], SweepPoint] = {}

    def evaluate(idxs: list[tuple[int, ...]]) -> None:
        idxs = [i for i in dict.fromkeys(idxs) if i not in seen][:max(0, budget - len(seen))]
        if not idxs:
            return
        wanted = {tuple(ladders[n][j] for n, j in zip(names, i, strict=True)): i for i in idxs}
        todo = [(engine, dict(zip(names, v, strict=True)),
                 {**base, **dict(zip(names, v, strict=True))}) for v in wanted]
        for p in run_points(scenario, todo, db=db, kind=KIND, execution=execution)[0]:
            i = wanted[tuple(p.knobs[n] for n in names)]
            seen[i] = p
            if on_point is not None:
                on_point(p)

    def score(i: tuple[int, ...]) -> tuple[float, float]:
        p = seen[i]
        e = p.error(metric)
        ok = p.as_reference and not p.drift and math.isfinite(e)
        return (e if ok else math.inf, p.cost)

    # start from the (calibrated) defaults: refine until the target holds, then coarsen
    cur = tuple(ladders[n].index(_closest(ladders[n], getattr(defaults, n))) for n in names)
    evaluate([cur])
    while len(seen) < budget and not seen[cur].meets(target, metric):
        nbrs = [tuple(j + (1 if n == k else 0) for n, j in zip(range(len(names)), cur,
                                                                strict=True))
                for k in range(len(names)) if cur[k] + 1 < len(ladders[names[k]])]
        if not nbrs:
            break
        evaluate(nbrs)
        done = [i for i in nbrs if i in seen]
        if not done:
            break
        cur = min(done, key=score)
    # coarsen while the target still holds
    while len(seen) < budget and cur in seen and seen[cur].meets(target, metric):
        nbrs = [tuple(j - (1 if n == k else 0) for n, j in zip(range(len(names)), cur,
                                                                strict=True))
                for k in range(len(names)) if cur[k] > 0]
        nbrs = [i for i in nbrs if i not in seen]
        if not nbrs:
            break
        evaluate(nbrs)
        better = [i for i in nbrs if i in seen and seen[i].meets(target, metric)]
        if not better:
            break
        cur = min(better, key=lambda i: seen[i].cost)
    # wall times are noisy: among points within 15 % of the cheapest, take the coarsest
    meeting = [(i, p) for i, p in seen.items() if p.meets(target, metric)]
    best = None
    if meeting:
        c_min = min(p.cost for _, p in meeting)
        near = [(i, p) for i, p in meeting if p.cost <= 1.15 * c_min]
        best = min(near, key=lambda ip: (sum(ip[0]), ip[1].cost))[1]
    return TuneResult(engine, target, metric, best, list(seen.values()), ladders)


def _closest(ladder: list[Any], value: Any) -> Any:
    return min(ladder, key=lambda v: abs(math.log(max(v, 1e-300) / max(value, 1e-300))))

