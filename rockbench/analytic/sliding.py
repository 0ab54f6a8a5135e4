"""Exact reference for a rigid block sliding on a moving base with Coulomb friction.

The block (or a stack sliding as one body) does not rock; it either sticks to
the base or slips on it. With s the slip (the block's displacement relative to
the base, positive toward +x) and σ = sgn(ṡ), the motion is event-driven:

* **stick** (ṡ = 0) while |ü_g| ≤ μ g: friction supplies m ü_g;
* **slip** once |ü_g| > μ g, in the direction σ = −sgn(ü_g) (the block lags
  behind the base), with s̈ = −ü_g − μ g σ;
* at ṡ = 0 the block sticks again if |ü_g| ≤ μ g, or slips back the other way.

Every slip phase starts with ṡ = 0 (from stick, or at a reversal). From t₀ and
s₀ the equation integrates in closed form against the exact base velocity and
displacement of every excitation::

    ṡ(t) = −(u̇_g(t) − u̇_g(t₀)) − μ g σ τ
    s(t) = s₀ − (u_g(t) − u_g(t₀) − u̇_g(t₀) τ) − ½ μ g σ τ²,   τ = t − t₀

so the solution is exact up to the location of the stick/slip events, found by
a fine scan of the event functions and Brent's method to machine precision. An
excursion of |ü_g| above μ g shorter than the scan step (default 0.1 ms) can be
missed; the slip it would cause is of order |d²ü_g/dt²|·step⁴ (5e-13 m for a
5 Hz pulse of 0.5 g).

Assumptions (those of the classical criteria below): a rigid block on a rigid,
horizontally moving base, no vertical base acceleration, Coulomb friction with
equal static and kinetic coefficients μ, no rocking. Sliding without rocking is
exact for any base motion when μ < b/h (b the pivot half-width, h the height of
the centre of mass): friction, the only horizontal force, accelerates the block
by at most μ g < g b/h, and during a slip the normal force stays inside the base
(its offset μ h is below b). For a stack, the same holds with μ below every
uplift ratio (each block on its support and the whole stack); with one friction
coefficient for every contact, the interfaces then carry exactly the friction
they can (the stack's absolute acceleration is at most μ g) and do not slip.

Regime criteria for a block at rest under a horizontal base acceleration a
(Ishiyama 1982, Shenton 1996): it stays at rest if |a| ≤ μ g and |a| ≤ g b/h;
it slides if μ < b/h and |a| > μ g; if μ ≥ b/h it starts rocking when
|a| > g b/h, and slide-rocking when the friction that incipient rocking about a
fixed pivot needs exceeds μ times the normal force. That last threshold is
derived here from the equations of incipient rocking (see
:func:`regime_thresholds`), as in Shenton's analysis.

Interface slip of a two-block stack (``Contact.interface_friction`` μᵢ below
the base friction μ): while the base holds the lower block, the upper block is a
block sliding on a base that moves like the lower one, so the same closed forms
with μᵢ give its slip on the lower block exactly. The base holds when
m₁ max|ü_g| + μᵢ m₂ g ≤ μ (m₁ + m₂) g (the largest friction the lower block
needs, whether the interface sticks or slips). Nothing rocks when μᵢ is below
the upper block's uplift ratio b_c/h₂ and the whole stack's (while stuck, the
stack accelerates at most μᵢ g), and when the lower block, loaded by the sliding
upper one (a horizontal μᵢ m₂ g at its top, the weight m₂ g off-centre by μᵢ h₂),
keeps its moment about a base pivot: m₁ max|ü_g| h₁ + 2 μᵢ m₂ g h₁ <
g (m₁ b₁ + m₂ (b₁ − μᵢ h₂)). Outside these bounds both contacts may slip, or
slip and rock, and there is no exact reference.

References: Y. Ishiyama, "Motions of rigid bodies and criteria for overturning
by earthquake excitations", Earthquake Engng Struct. Dyn. 10 (1982) 635–650;
H. W. Shenton III, "Criteria for initiation of slide, rock, and slide-rock
rigid-body modes", J. Eng. Mech. 122 (1996) 690–693.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from enum import Enum

import numpy as np
from scipy.optimize import brentq

from rockbench import provenance
from rockbench.analytic.normalisation import critical_angle
from rockbench.analytic.twoblock_model import BlockParams
from rockbench.errors import UnsupportedScenario
from rockbench.scenarios import Motion, Scenario
from rockbench.trajectory import Status, Trajectory

__all__ = [
    "Regime", "RegimeThresholds", "regime_thresholds", "onset_regime", "SlipPhase",
    "SlidingSolution", "solve_sliding", "slides", "sliding_reference", "slip_of",
    "interface_slips", "interface_slip_bounds",
]

#: Default scan step (s) of the event functions.
SCAN_STEP = 1e-4
#: Scan window (s): the event functions are evaluated this far ahead at a time.
_WINDOW = 0.25


class Regime(str, Enum):
    """Motion a block at rest enters under a base acceleration."""

    REST = "rest"
    SLIDE = "slide"
    ROCK = "rock"
    SLIDE_ROCK = "slide-rock"

    def __str__(self) -> str:
        return self.value


@dataclass(frozen=True)
class RegimeThresholds:
    """Base accelerations (m/s², magnitudes) at which a block at rest starts to move.

    Attributes
    ----------
    slide : float
        μ g: pure sliding above it when μ < b/h (``inf`` otherwise).
    rock : float
        g b/h: rocking above it when μ ≥ b/h (``inf`` otherwise).
    slide_rock : float
        Above it the rocking pivot slips too (``inf`` if never).
    """

    slide: float
    rock: float
    slide_rock: float

    def regime(self, accel: float) -> Regime:
        """The regime entered from rest under a base acceleration ``accel`` (either sign)."""
        a = abs(float(accel))
        if a > self.slide:
            return Regime.SLIDE
        if a > self.slide_rock:
            return Regime.SLIDE_ROCK
        if a > self.rock:
            return Regime.ROCK
        return Regime.REST


def regime_thresholds(mu: float, block: BlockParams, g: float) -> RegimeThresholds:
    """Ishiyama's and Shenton's onset thresholds of a block at rest on a rigid base.

    Parameters
    ----------
    mu : float
        Coulomb friction coefficient (static = kinetic).
    block : BlockParams
        Pivot half-width b, half-height h (height of the centre of mass above the
        base), mass m and centroidal inertia I about the out-of-plane axis.
    g : float
        Gravity (m/s²).

    Returns
    -------
    RegimeThresholds

    Notes
    -----
    Rocking about the trailing corner from rest under a > 0 has
    φ̈ = m (a h − g b) / I_O (I_O = I + m (b² + h²)); the pivot reactions are
    H = m (a − h φ̈) and V = m (g + b φ̈). The pivot holds while H ≤ μ V, a
    condition linear in a that holds with margin g (μ − b/h) at a = g b/h. It
    fails above::

        a_sr = g (μ − c b (μ b + h)) / (1 − c h (h + μ b)),   c = m / I_O

    when c h (h + μ b) < 1 (slender blocks), and never otherwise.
    """
    mu, g = float(mu), float(g)
    b, h = block.b, block.h
    ratio = b / h
    if mu < ratio:
        return RegimeThresholds(slide=mu * g, rock=math.inf, slide_rock=math.inf)
    c = block.m / (block.I + block.m * (b * b + h * h))
    slope = 1.0 - c * h * (h + mu * b)
    a_sr = g * (mu - c * b * (mu * b + h)) / slope if slope > 0 else math.inf
    return RegimeThresholds(slide=math.inf, rock=g * ratio, slide_rock=a_sr)


def onset_regime(accel: float, mu: float, block: BlockParams, g: float) -> Regime:
    """The regime a block at rest enters under base acceleration ``accel``.

    See :func:`regime_thresholds` for the parameters and the criteria.
    """
    return regime_thresholds(mu, block, g).regime(accel)


@dataclass(frozen=True)
class SlipPhase:
    """One interval of the motion: sticking or slipping one way.

    Attributes
    ----------
    start, end : float
        Times (s).
    direction : int
        0 when stuck, ±1 the sign of the slip rate ṡ.
    """

    start: float
    end: float
    direction: int


@dataclass(frozen=True)
class SlidingSolution:
    """Result of :func:`solve_sliding`.

    Attributes
    ----------
    t : ndarray (n,)
        Output times (s).
    slip, slip_rate : ndarray (n,)
        Slip s(t) of the block relative to the base (m, positive toward +x) and ṡ (m/s).
    phases : tuple of SlipPhase
        Stick and slip intervals covering [t[0], t[-1]].
    path : float
        Slip path ∫|ṡ| dt (m).
    mu, g : float
        Friction coefficient and gravity.
    """

    t: np.ndarray
    slip: np.ndarray
    slip_rate: np.ndarray
    phases: tuple[SlipPhase, ...]
    path: float
    mu: float
    g: float

    def dissipated(self, mass: float) -> float:
        """Energy dissipated by friction, μ m g × slip path (J)."""
        return self.mu * float(mass) * self.g * self.path

    @property
    def slip_times(self) -> np.ndarray:
        """Start times (s) of the slip phases."""
        return np.array([p.start for p in self.phases if p.direction != 0], float)


def _first(f: Callable[[np.ndarray], np.ndarray], ta: float, tb: float,
           step: float) -> tuple[float, float] | None:
    """First grid interval (t_i-1, t_i] of [ta, tb] with f(t_i) > 0, f(t_i-1) ≤ 0 or t_i-1 = ta."""
    t0 = ta
    while t0 < tb:
        t1 = min(t0 + _WINDOW, tb)
        n = max(2, int(math.ceil((t1 - t0) / step)) + 1)
        ts = np.linspace(t0, t1, n)
        hit = np.flatnonzero(f(ts[1:]) > 0)
        if hit.size:
            i = int(hit[0]) + 1
            return float(ts[i - 1]), float(ts[i])
        t0 = t1
    return None


def _root(f: Callable[[float], float], ta: float, tb: float) -> float:
    """Root of f between ta (f ≤ 0) and tb (f > 0)."""
    if f(ta) >= 0.0:
        return ta
    return float(brentq(f, ta, tb, xtol=1e-15, rtol=4 * np.finfo(float).eps))


class _Slider:
    """The event loop of one sliding run."""

    def __init__(self, exc: Motion, mu: float, g: float, t_end: float, step: float) -> None:
        self.acc, self.vel, self.disp = exc.acceleration, exc.velocity, exc.displacement
        self.mug = mu * g
        self.t_end = t_end
        self.step = step
        # after the base stops, nothing can start a slip
        self.t_quiet = min(exc.end_time, t_end)

    def excess(self, ts: np.ndarray) -> np.ndarray:
        """|ü_g| − μ g: positive where a stuck block starts to slip."""
        return np.abs(np.asarray(self.acc(ts), float)) - self.mug

    def rate(self, t0: float, sigma: int) -> Callable[[np.ndarray], np.ndarray]:
        """ṡ(t) in the slip phase started at t0 (ṡ(t0) = 0) in direction σ."""
        vg0 = float(self.vel(t0))
        mug = self.mug

        def v(ts: np.ndarray) -> np.ndarray:
            return -(np.asarray(self.vel(ts), float) - vg0) - mug * sigma * (ts - t0)

        return v

    def state(self, t0: float, s0: float, sigma: int,
              ts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(s, ṡ) at times ``ts`` of the phase started at t0 from s0 (σ = 0: stuck)."""
        if sigma == 0:
            return np.full(ts.shape, s0), np.zeros(ts.shape)
        tau = ts - t0
        ug0, vg0 = float(self.disp(t0)), float(self.vel(t0))
        s = (s0 - (np.asarray(self.disp(ts), float) - ug0 - vg0 * tau)
             - 0.5 * self.mug * sigma * tau * tau)
        return s, self.rate(t0, sigma)(ts)

    def stick_end(self, t0: float) -> float | None:
        """First time > t0 (or t0 itself) at which the stuck block starts to slip."""
        if self.excess(np.array([t0]))[0] > 0:
            return t0
        if t0 >= self.t_quiet:
            return None
        hit = _first(self.excess, t0, self.t_quiet, self.step)
        if hit is None:
            return None
        return _root(lambda t: float(self.excess(np.array([t]))[0]), *hit)

    def slip_end(self, t0: float, sigma: int) -> float | None:
        """First time > t0 at which σ ṡ returns to 0 (None: not before the end)."""
        v = self.rate(t0, sigma)

        def closing(ts: np.ndarray) -> np.ndarray:
            return -sigma * v(ts)

        step, end = self.step, self.t_end
        while True:
            hit = _first(closing, t0, end, step)
            if hit is None:
                return None
            ta, tb = hit
            if ta > t0:
                return _root(lambda t: float(closing(np.array([t]))[0]), ta, tb)
            # the slip closes within the first scan cell (ṡ = 0 at t0): look closer there
            if step < 1e-13 * max(1.0, t0):
                return tb
            step, end = step / 64.0, tb

    def slip_direction(self, t: float) -> int:
        """σ = −sgn(ü_g) of a slip starting at t (the acceleration just after t decides)."""
        a = float(self.acc(t))
        later = float(self.acc(t + 1e-9 * max(1.0, t)))
        if abs(later) > abs(a) or a == 0.0:
            a = later
        return -1 if a > 0 else 1

    def run(self, t0: float, max_phases: int) -> list[tuple[float, float, int, float]]:
        """Phases as (start, end, σ, s at start) from rest at t0."""
        phases: list[tuple[float, float, int, float]] = []
        t, s, sigma = t0, 0.0, 0
        while t < self.t_end:
            if len(phases) >= max_phases:
                raise RuntimeError(f"sliding: more than {max_phases} stick/slip phases by "
                                   f"t = {t:.6g} s")
            if sigma == 0:
                t1 = self.stick_end(t)
                if t1 is None:
                    phases.append((t, self.t_end, 0, s))
                    break
                if t1 > t:
                    phases.append((t, t1, 0, s))
                t, sigma = t1, self.slip_direction(t1)
                continue
            t1 = self.slip_end(t, sigma)
            phases.append((t, self.t_end if t1 is None else t1, sigma, s))
            if t1 is None:
                break
            s = float(self.state(t, s, sigma, np.array([t1]))[0][0])
            t = t1
            # at ṡ = 0 the block sticks unless the base drives it back the other way
            sigma = self.slip_direction(t1) if self.excess(np.array([t1]))[0] > 0 else 0
        return phases


def solve_sliding(
    excitation: Motion, mu: float, *, g: float, t_out: np.ndarray | list[float],
    scan_step: float = SCAN_STEP, max_phases: int = 100000,
) -> SlidingSolution:
    """Slip of a rigid block on a moving base with Coulomb friction, from rest.

    Parameters
    ----------
    excitation : Motion
        Base motion (its exact velocity and displacement enter the closed forms).
    mu : float
        Friction coefficient (≥ 0; static = kinetic).
    g : float
        Gravity (m/s²).
    t_out : array_like
        Increasing output times (s), from the start of the motion.
    scan_step : float
        Scan step of the event functions (s), before the events are refined by
        Brent's method.
    max_phases : int
        Guard against chattering.

    Returns
    -------
    SlidingSolution
    """
    t_out = np.asarray(t_out, float).reshape(-1)
    if t_out.size == 0 or np.any(np.diff(t_out) < 0):
        raise ValueError("t_out must be a non-empty increasing sequence of times")
    mu, g = float(mu), float(g)
    if not (math.isfinite(mu) and mu >= 0.0 and math.isfinite(g) and g > 0.0):
        raise ValueError(f"need mu >= 0 and g > 0, got mu={mu!r}, g={g!r}")
    slider = _Slider(excitation, mu, g, float(t_out[-1]), float(scan_step))
    raw = slider.run(float(t_out[0]), max_phases)
    slip = np.zeros(t_out.size)
    rate = np.zeros(t_out.size)
    path = 0.0
    for k, (ta, tb, sigma, s0) in enumerate(raw):
        i0 = int(np.searchsorted(t_out, ta, "left"))
        i1 = t_out.size if k == len(raw) - 1 else int(np.searchsorted(t_out, tb, "left"))
        slip[i0:i1], rate[i0:i1] = slider.state(ta, s0, sigma, t_out[i0:i1])
        if sigma != 0:  # ṡ keeps its sign within a phase
            path += abs(float(slider.state(ta, s0, sigma, np.array([tb]))[0][0]) - s0)
    phases = tuple(SlipPhase(float(a), float(b), int(sg)) for a, b, sg, _ in raw)
    return SlidingSolution(t=t_out, slip=slip, slip_rate=rate, phases=phases, path=path,
                           mu=mu, g=g)


def interface_slips(scenario: Scenario) -> bool:
    """True if the upper block of a two-block stack can slip on the lower one.

    That is: upright centred blocks at rest, an interface friction below the
    base friction (with equal coefficients the stack slides as one body) and a
    base acceleration that exceeds μᵢ g at some time.
    """
    c = scenario.contact
    col = scenario.geometry.column
    if col is None or len(col) != 2 or c.interface_friction is None:
        return False
    if scenario.initial_tilt != 0.0 or not col.centred:
        return False
    mu_i = c.interface_friction
    return mu_i < c.friction and (scenario.motion.peak_acceleration(scenario.duration)
                                  > mu_i * scenario.g)


def interface_slip_bounds(scenario: Scenario) -> tuple[str, ...]:
    """Why the exact interface-slip reference does not hold (empty: it holds).

    Checks the bounds of the module notes: the base holds the lower block, and
    neither the upper block, nor the stack, nor the loaded lower block rocks.
    """
    col = scenario.geometry.column
    if col is None or len(col) != 2:
        raise UnsupportedScenario("interface slip needs a stack of two blocks")
    lo, up = col.blocks
    g, mu, mu_i = scenario.g, scenario.contact.friction, scenario.contact.block_friction
    m1, m2 = lo.m, up.m
    a = scenario.motion.peak_acceleration(scenario.duration)
    b1, h1, h2 = lo.pivot_half_width, lo.h, up.h
    bc = min(lo.pivot_half_width, up.pivot_half_width)
    out = []
    if m1 * a + mu_i * m2 * g > mu * (m1 + m2) * g:
        out.append(f"the base friction {mu:g} may not hold the lower block (it needs up to "
                   f"{(m1 * a + mu_i * m2 * g) / ((m1 + m2) * g):.4g})")
    if mu_i >= bc / h2:
        out.append(f"interface friction {mu_i:g} at or above the upper block's uplift ratio "
                   f"{bc / h2:.4g} (it could rock)")
    lam_m = col.monolithic(g).lam
    if mu_i >= math.tan(lam_m):
        out.append(f"interface friction {mu_i:g} at or above the stack's uplift ratio "
                   f"{math.tan(lam_m):.4g} (the stuck stack could rock)")
    if m1 * a * h1 + 2.0 * mu_i * m2 * g * h1 >= g * (m1 * b1 + m2 * (b1 - mu_i * h2)):
        out.append("the lower block, loaded by the sliding upper one, could rock")
    return tuple(out)


def slides(scenario: Scenario) -> bool:
    """True if the exact sliding reference applies to ``scenario`` and a block slides.

    That is: one block or a centred stack, starting upright and at rest, friction
    below every uplift ratio (μ < tan λ of each block on its support and of the
    whole stack: no rocking, see the module notes) and a base acceleration that
    exceeds μ g at some time; or a two-block stack whose upper block slips on the
    lower one (:func:`interface_slips`; :func:`sliding_reference` then refuses
    the cases its bounds do not cover rather than leave them to a rocking model
    that assumes no slip).
    """
    col = scenario.geometry.column
    if col is None:  # no column: no sliding reference
        return False
    if interface_slips(scenario):
        return True
    if scenario.initial_tilt != 0.0 or not col.centred:
        return False
    mu = scenario.contact.friction
    if mu >= math.tan(critical_angle(scenario.geometry)):
        return False
    return scenario.motion.peak_acceleration(scenario.duration) > mu * scenario.g


def sliding_reference(scenario: Scenario, *, scan_step: float = SCAN_STEP) -> Trajectory:
    """Exact sliding trajectory of a block (or a stack sliding as one body) on its base.

    Parameters
    ----------
    scenario : Scenario
        Upright centred blocks at rest whose friction is below every uplift ratio,
        or a two-block stack whose upper block slips on the lower one within the
        bounds of :func:`interface_slip_bounds`.
    scan_step : float
        Scan step of the stick/slip events (s).

    Returns
    -------
    Trajectory
        θ = 0, centroid x = upright x + u_g + s (base displacement plus slip) and
        z upright, for every block (with interface slip: s = 0 for the lower
        block and the upper block's slip on it for the upper one); status ``ok``;
        ``extra`` holds the model name, the stick/slip phases, the final and
        largest slip and the slip path.

    Raises
    ------
    UnsupportedScenario
        Tilted or off-centre blocks, friction at or above an uplift ratio
        (the block could rock), or an interface slip outside the exact bounds.
    """
    col = scenario.geometry.column
    if scenario.initial_tilt != 0.0 or col is None or not col.centred:
        raise UnsupportedScenario("the sliding reference needs upright, centred blocks")
    on_interface = interface_slips(scenario)
    if on_interface:
        why = interface_slip_bounds(scenario)
        if why:
            raise UnsupportedScenario("no exact interface-slip reference: " + "; ".join(why))
        mu = scenario.contact.block_friction
    else:
        mu = scenario.contact.friction
        ratio = math.tan(critical_angle(scenario.geometry))
        if mu >= ratio:
            raise UnsupportedScenario(
                f"the sliding reference needs friction {mu:g} below the uplift ratio "
                f"{ratio:.4g} (the block could rock)"
            )
    exc = scenario.motion.x
    t_out = scenario.output_times()
    start = time.perf_counter()
    sol = solve_sliding(exc, mu, g=scenario.g, t_out=t_out, scan_step=scan_step)
    wall = time.perf_counter() - start
    c = scenario.geometry.centroids
    nb = scenario.n_blocks
    ug = np.asarray(exc.displacement(t_out), float)
    # which blocks carry the slip: all of them (one body on the base), or the upper one
    slipping = np.arange(nb) >= (1 if on_interface else 0)
    x = c[None, :, 0] + ug[:, None] + sol.slip[:, None] * slipping[None, :]
    z = np.broadcast_to(c[None, :, 1], (t_out.size, nb)).copy()
    where = "on the lower block" if on_interface else "on the base"
    return Trajectory(
        t=t_out, theta=np.zeros((t_out.size, nb)), x=x, z=z, status=Status.OK,
        message=f"slid {sol.path:.6g} m {where} in {sol.slip_times.size} slip phase(s)",
        wall_time=wall, engine="analytic",
        engine_version=f"sliding-{provenance.code_version('reference')}",
        settings={"scan_step": scan_step, "brentq_xtol": 1e-15}, scenario=scenario.name,
        extra={
            "model": "coulomb-interface-sliding" if on_interface else "coulomb-sliding",
            "phases": [[p.start, p.end, p.direction] for p in sol.phases],
            "final_slip": float(sol.slip[-1]),
            "max_slip": float(np.max(np.abs(sol.slip))),
            "slip_path": sol.path,
        },
    )


def slip_of(traj: Trajectory, scenario: Scenario, block: int = 0) -> np.ndarray:
    """Slip history of ``block`` relative to the base from a trajectory's centroid x (m).

    s = x − x_upright − u_g; meaningful while the block does not rock.
    """
    t = traj.t
    x0 = scenario.geometry.centroids[block, 0]
    return traj.x[:, block] - x0 - np.asarray(scenario.motion.x.displacement(t), float)
