"""A consensus reference where no closed form exists: converged engines of independent models.

From the converged ladders (:mod:`rockbench.studies.convergence`) of several
engines on one scenario, the consensus takes one value per *contact-model
family* (``Engine.contact_model``: soft constraints, impulses, compliant point
contact, penalty DEM, non-smooth contact dynamics), the median of that family's
engines, so that two engines sharing a model count once. Then:

1. the outcome is the one most families agree on; a family that ends otherwise
   is outside the consensus;
2. each quantity (peaks per block, overturning time) is the median of the
   remaining families' values; a family farther from it than the tolerance
   plus its own uncertainty is outside the consensus, and the median is taken
   again without it;
3. the consensus stands when at least two families remain: its uncertainty is
   the largest distance of a remaining family from the median plus the largest
   remaining family uncertainty.

Engines that did not converge take no part; every engine outside the consensus
is named with the reason.
"""

from __future__ import annotations

import math
import statistics
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from functools import partial

from rockbench.engines import engine_class
from rockbench.evaluation import PEAK_FLOOR
from rockbench.studies.convergence import Convergence, ConvergenceTolerances, Estimate
from rockbench.trajectory import Status

__all__ = ["Consensus", "consensus", "outcome_consensus", "contact_family", "MIN_FAMILIES"]

#: Independent contact-model families a consensus needs.
MIN_FAMILIES = 2

#: Reads one estimate (a peak, the overturning time) off a ladder.
Getter = Callable[[Convergence], Estimate | None]


@dataclass(frozen=True)
class Consensus:
    """The consensus of converged engines on one scenario.

    Attributes
    ----------
    scenario : str
        Scenario name.
    formed : bool
        At least :data:`MIN_FAMILIES` families agree.
    outcome : Status or None
        The agreed outcome.
    peaks : tuple of Estimate
        Per block, the agreed max |θ_i|/λ with its spread.
    overturn_time : Estimate or None
        The agreed overturning time (s), when it overturns.
    members : tuple of (str, str)
        The methods inside the consensus: (label, contact-model family).
    outliers : tuple of (str, str)
        Methods outside it and why.
    note : str
        Why there is no consensus, when there is none.
    """

    scenario: str
    formed: bool
    outcome: Status | None
    peaks: tuple[Estimate, ...]
    overturn_time: Estimate | None
    members: tuple[tuple[str, str], ...]
    outliers: tuple[tuple[str, str], ...]
    note: str = ""

    @property
    def families(self) -> int:
        """Number of contact-model families inside the consensus."""
        return len({f for _, f in self.members})


def contact_family(engine: str) -> str:
    """The contact-model family of a registered engine (its name when it declares none)."""
    return engine_class(engine).contact_model or engine


def _family(c: Convergence) -> str:
    return contact_family(c.method.engine)


def _peak(i: int, c: Convergence) -> Estimate | None:
    """The peak estimate of block ``i`` of a ladder."""
    return c.peaks[i]


def _agree(value: float, centre: float, unc: float, tol: float, floor: float) -> bool:
    return abs(value - centre) <= tol * max(abs(centre), floor) + unc


def consensus(ladders: Sequence[Convergence],
              tolerances: ConvergenceTolerances | None = None) -> Consensus:
    """The consensus of ``ladders`` (one scenario; several engines and presets).

    One ladder per engine takes part: its converged ladder with the smallest
    peak uncertainty. ``tolerances`` (default :class:`ConvergenceTolerances`)
    say how far a family may lie from the median.
    """
    tolerances = tolerances or ConvergenceTolerances()
    name = ladders[0].scenario.name if ladders else ""
    best: dict[str, Convergence] = {}
    for c in ladders:
        if not c.converged or engine_class(c.method.engine).capabilities.analytic:
            continue
        unc = max((e.uncertainty for e in c.peaks if e is not None), default=math.inf)
        old = best.get(c.method.engine)
        if old is None or unc < max((e.uncertainty for e in old.peaks if e is not None),
                                    default=math.inf):
            best[c.method.engine] = c
    outliers: list[tuple[str, str]] = []
    fams: dict[str, list[Convergence]] = {}
    for c in best.values():
        fams.setdefault(_family(c), []).append(c)
    # 1. the outcome most families agree on (a converged ladder has one)
    outcomes = {f: statistics.mode(c.outcome for c in cs if c.outcome is not None)
                for f, cs in fams.items()}
    if not outcomes:
        return Consensus(name, False, None, (), None, (), (), "no engine converged")
    count = {o: sum(v is o for v in outcomes.values()) for o in set(outcomes.values())}
    outcome = max(count, key=lambda o: (count[o], o is Status.OK))
    for cs in fams.values():
        for c in cs:
            if c.outcome is not outcome:
                outliers.append((c.method.label, f"ends {c.outcome.value if c.outcome else '?'}"
                                 f" where the consensus ends {outcome.value}"))
    keep = {f: [c for c in cs if c.outcome is outcome] for f, cs in fams.items()}
    keep = {f: cs for f, cs in keep.items() if cs}
    n_blocks = len(next(iter(keep.values()))[0].peaks) if keep else 0

    def family_value(cs: list[Convergence], get: Getter) -> tuple[float, float] | None:
        vals = [v for v in (get(c) for c in cs) if v is not None]
        if not vals:
            return None
        return (statistics.median(v.value for v in vals), max(v.uncertainty for v in vals))

    quantities: list[tuple[str, Getter, float, float]] = [
        (f"peak {i + 1}", partial(_peak, i), tolerances.peak, PEAK_FLOOR)
        for i in range(n_blocks)]
    if outcome is Status.OVERTURNED:
        quantities.append(("overturning time", lambda c: c.overturn_time,
                           tolerances.overturn_time, 0.0))
    # 2. drop the families farther than the tolerance from the median, quantity by quantity
    changed = True
    while changed and len(keep) >= MIN_FAMILIES:
        changed = False
        for what, get, tol, floor in quantities:
            found = {f: family_value(cs, get) for f, cs in keep.items()}
            values = {f: v for f, v in found.items() if v is not None}
            if len(values) < MIN_FAMILIES:
                continue
            centre = statistics.median(v for v, _ in values.values())
            far = [f for f, (v, u) in values.items() if not _agree(v, centre, u, tol, floor)]
            if far and len(values) - len(far) >= 1:
                # the farthest family goes first; the median is taken again without it
                f = max(far, key=lambda f: abs(values[f][0] - centre))
                for c in keep.pop(f):
                    outliers.append((c.method.label, f"{what} {values[f][0]:.4g} against the "
                                     f"others' median {centre:.4g}"))
                changed = True
                break
    members = tuple((c.method.label, f) for f, cs in keep.items() for c in cs)
    if len(keep) < MIN_FAMILIES:
        return Consensus(name, False, outcome, (), None, members, tuple(outliers),
                         f"{len(keep)} contact-model famil{'y' if len(keep) == 1 else 'ies'} "
                         f"agree; a consensus needs {MIN_FAMILIES} independent ones")

    def agreed(get: Getter) -> Estimate | None:
        values = [fv for fv in (family_value(cs, get) for cs in keep.values()) if fv is not None]
        if len(values) < MIN_FAMILIES:
            return None
        centre = statistics.median(v for v, _ in values)
        spread = max(abs(v - centre) for v, _ in values)
        return Estimate(centre, spread + max(u for _, u in values))

    peaks = tuple(agreed(partial(_peak, i)) for i in range(n_blocks))
    over = agreed(lambda c: c.overturn_time) if outcome is Status.OVERTURNED else None
    return Consensus(name, True, outcome, tuple(p for p in peaks if p is not None), over,
                     members, tuple(outliers))


def outcome_consensus(by_family: Mapping[str, Sequence[bool | None]]) -> bool | None:
    """The consensus of a yes/no outcome (e.g. overturned) over contact-model families.

    Step 1 of :func:`consensus` for one run's outcome: each family's outcome is the
    majority of its methods' (None: a tie, or none of its methods has an outcome); the
    consensus is the outcome that most families give, when at least
    :data:`MIN_FAMILIES` of them give it; otherwise None (no consensus).

    Parameters
    ----------
    by_family : mapping of str to sequence of bool or None
        Per family, its methods' outcomes (None: the run has no outcome).
    """
    votes = []
    for outcomes in by_family.values():
        known = [o for o in outcomes if o is not None]
        yes = sum(known)
        if known and 2 * yes != len(known):
            votes.append(2 * yes > len(known))
    yes, no = sum(votes), len(votes) - sum(votes)
    if max(yes, no) < MIN_FAMILIES or yes == no:
        return None
    return yes > no
