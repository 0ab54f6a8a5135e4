"""Predictability horizon t* of a scenario: how long its analytic solution is well posed.

A stack driven for seconds is often chaotic: an input perturbed by one part in
10⁹ gives, after a few seconds, another trajectory (and sometimes another
outcome). Comparing an engine's time history with the reference one-to-one is
meaningful only up to the time at which such tiny perturbations have grown
visible. This module measures that time.

Definitions
-----------
* **Ensemble**: the nominal scenario and ``members`` perturbed copies
  (:func:`perturbed`). Member ``k`` (1-based) has its input amplitude scaled
  by ``1 + s_k a_k`` and its initial tilt shifted by ``σ_k d_k`` λ, with the
  magnitudes ``a_k`` (relative) and ``d_k`` (fraction of λ) geometrically
  spaced over ``Perturbation.low .. Perturbation.high`` (1e-9 .. 1e-6 by
  default), and signs ``s_k, σ_k`` and the pairing of the two magnitudes drawn
  from ``Perturbation.seed``. Excitations without an amplitude (free rocking)
  get the tilt perturbation only; the amplitude is the displacement amplitude
  of pulses and sinusoids and the scale of records.
* **Spread** s(t): the largest, over the blocks, of (max − min over the
  members of θ_i(t))/λ. A member that stopped (overturned) keeps its last
  sample, so that a member that falls while the others rock spreads the
  ensemble.
* **Horizon** t*: the first output time at which s(t) > ``fraction`` (0.02 λ
  by default); the scenario's duration if the spread never gets there (the
  case is well posed over the whole run).

:func:`predictability` runs the ensembles through
:func:`rockbench.campaign.references.references` (the one dispatcher,
isolated, parallel or on Dask; members are cached in the results store by
scenario content like every reference).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from rockbench import analytic
from rockbench.campaign.references import references
from rockbench.runner import ExecutionOptions
from rockbench.scenarios import Scenario
from rockbench.store import Store
from rockbench.trajectory import Trajectory

__all__ = ["Perturbation", "Predictability", "perturbed", "ensemble_scenarios", "spread_curve",
           "horizon_of", "predictability", "DEFAULT_MEMBERS", "DEFAULT_FRACTION"]

#: Perturbed members of the ensemble that measures t* (besides the nominal run).
DEFAULT_MEMBERS = 8
#: Spread (fraction of λ) at which the ensemble has diverged.
DEFAULT_FRACTION = 0.02


@dataclass(frozen=True)
class Perturbation:
    """The tiny perturbations of an ensemble (see the module docstring).

    Attributes
    ----------
    low, high : float
        Smallest and largest magnitude: relative for the input amplitude,
        fraction of λ for the initial tilt.
    amplitude, tilt : bool
        Which quantities are perturbed.
    seed : int
        Draws the signs and the pairing of the magnitudes.
    """

    low: float = 1e-9
    high: float = 1e-6
    amplitude: bool = True
    tilt: bool = True
    seed: int = 0

    def __post_init__(self) -> None:
        if not 0.0 < self.low <= self.high < 1e-2:
            raise ValueError(f"perturbation magnitudes must satisfy 0 < low <= high < 1e-2, "
                             f"got {self.low!r}, {self.high!r}")
        if not (self.amplitude or self.tilt):
            raise ValueError("a perturbation must perturb the amplitude or the tilt")

    def draws(self, n: int) -> tuple[np.ndarray, np.ndarray]:
        """Signed relative amplitude changes and tilt changes (λ) of members 1..n."""
        mags = np.geomspace(self.low, self.high, n) if n > 1 else np.array([self.high])
        rng = np.random.default_rng(self.seed)
        signs = rng.choice((-1.0, 1.0), size=(2, n))
        amp = signs[0] * mags if self.amplitude else np.zeros(n)
        tilt = signs[1] * rng.permutation(mags) if self.tilt else np.zeros(n)
        return amp, tilt

    def describe(self) -> str:
        """One line for reports."""
        what = " and ".join(w for w, on in (("input amplitude (relative)", self.amplitude),
                                             ("initial tilt (λ)", self.tilt)) if on)
        return f"{what} perturbed by ±{self.low:.0e} .. ±{self.high:.0e} (seed {self.seed})"


@dataclass(frozen=True)
class Predictability:
    """The predictability horizon of one scenario.

    Attributes
    ----------
    scenario : str
        Its name.
    t_star : float
        Horizon t* in s (``duration`` when the case is well posed).
    spread : float
        Largest spread of the ensemble over the run (fraction of λ).
    members : int
        Perturbed members (the nominal run comes on top).
    perturbation : Perturbation
        How they were perturbed.
    fraction : float
        The spread (λ) that defines t*.
    duration : float
        The scenario's duration (s).
    diverged_outcome : bool
        Members end differently (some overturn, others do not).
    """

    scenario: str
    t_star: float
    spread: float
    members: int
    perturbation: Perturbation
    fraction: float = DEFAULT_FRACTION
    duration: float = 0.0
    diverged_outcome: bool = False

    @property
    def well_posed(self) -> bool:
        """The spread stays below ``fraction`` over the whole run."""
        return self.t_star >= self.duration

    def describe(self) -> str:
        """``well posed over 10 s`` or ``chaotic after t* = 3.6 s``."""
        if self.well_posed:
            return f"well posed over {self.duration:g} s"
        return f"chaotic after t* = {self.t_star:.2f} s"


def _perturb_amplitude(scenario: Scenario, rel: float) -> Scenario:
    # any kind of excitation: its amplitude field, where it has one, is found by name
    exc: Any = scenario.excitation
    names = {f.name for f in dataclasses.fields(exc)} if dataclasses.is_dataclass(exc) else set()
    for name in ("amplitude", "scale"):
        if name in names:
            new = dataclasses.replace(exc, **{name: getattr(exc, name) * (1.0 + rel)})
            return dataclasses.replace(scenario, excitation=new)
    return scenario  # free rocking: nothing to scale


def perturbed(scenario: Scenario, k: int, perturbation: Perturbation, n: int) -> Scenario:
    """Member ``k`` (1 ≤ k ≤ n) of the ``n``-member ensemble of ``scenario``."""
    if not 1 <= k <= n:
        raise ValueError(f"member {k} of an ensemble of {n}")
    amp, tilt = perturbation.draws(n)
    out = scenario
    if amp[k - 1] and not scenario.excitation.is_free:
        out = _perturb_amplitude(out, float(amp[k - 1]))
    if tilt[k - 1]:
        out = dataclasses.replace(out, initial_tilt=out.initial_tilt + float(tilt[k - 1]))
    return dataclasses.replace(out, name=f"{scenario.name}~p{k}")


def ensemble_scenarios(scenario: Scenario, n: int,
                       perturbation: Perturbation) -> list[Scenario]:
    """Members 1..n of the ensemble (the nominal scenario not included)."""
    return [perturbed(scenario, k, perturbation, n) for k in range(1, n + 1)]


def spread_curve(trajs: Sequence[Trajectory], t: np.ndarray, lam: float) -> np.ndarray:
    """s(t): largest spread over the blocks of θ across the members, in λ.

    Each trajectory is taken at the output times ``t``; one that ended earlier
    keeps its last sample (an empty one is left out).
    """
    rows = []
    for tr in trajs:
        if tr.t.size == 0:
            continue
        th = np.full((t.size, tr.theta.shape[1]), np.nan)
        n = min(tr.t.size, t.size)
        th[:n] = tr.theta[:n]
        th[n:] = tr.theta[n - 1]
        rows.append(th)
    if len(rows) < 2:
        return np.zeros(t.size)
    stack = np.stack(rows)  # members × samples × blocks
    return np.max(np.max(stack, axis=0) - np.min(stack, axis=0), axis=1) / lam


def horizon_of(t: np.ndarray, spread: np.ndarray, fraction: float, duration: float) -> float:
    """First time with ``spread > fraction`` (``duration`` if none)."""
    past = np.nonzero(spread > fraction)[0]
    return float(t[past[0]]) if past.size else float(duration)


def predictability(
    scenarios: Sequence[Scenario],
    *,
    members: int = DEFAULT_MEMBERS,
    perturbation: Perturbation | None = None,
    fraction: float = DEFAULT_FRACTION,
    store: Store | None = None,
    execution: ExecutionOptions | None = None,
    nominal: Mapping[str, Trajectory | None] | None = None,
) -> dict[str, Predictability]:
    """The horizon t* of every scenario that has an analytic reference.

    Parameters
    ----------
    scenarios : sequence of Scenario
        Names unique; those without an analytic model are left out of the result.
    members : int
        Perturbed members per scenario (>= 1).
    perturbation : Perturbation, optional
        Default :class:`Perturbation` ``()``.
    fraction : float
        Spread (λ) that defines t*.
    store : Store, optional
        Reference cache (members are cached by content).
    execution : ExecutionOptions, optional
        How the analytic runs are dispatched.
    nominal : mapping, optional
        Scenario name → its already computed reference (else it is computed too).
    """
    if members < 1:
        raise ValueError(f"an ensemble needs at least one perturbed member, got {members}")
    pert = perturbation or Perturbation()
    cases = [s for s in scenarios if analytic.has_reference(s)]
    todo = [m for s in cases for m in ensemble_scenarios(s, members, pert)]
    todo += [s for s in cases if nominal is None or nominal.get(s.name) is None]
    refs, _ = references(todo, store, execution=execution)
    out = {}
    for s in cases:
        nom = refs.get(s.name) if nominal is None or nominal.get(s.name) is None \
            else nominal[s.name]
        trajs = [nom] + [refs[f"{s.name}~p{k}"] for k in range(1, members + 1)]
        done = [tr for tr in trajs if tr is not None]
        t = s.output_times()
        curve = spread_curve(done, t, analytic.critical_angle(s.geometry))
        ends = {tr.status for tr in done}
        out[s.name] = Predictability(
            scenario=s.name, t_star=horizon_of(t, curve, fraction, s.duration),
            spread=float(np.max(curve)) if curve.size else 0.0, members=members,
            perturbation=pert, fraction=fraction, duration=s.duration,
            diverged_outcome=len(ends) > 1)
    return out
