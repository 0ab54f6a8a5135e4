"""A solid cylinder rolling on its bottom rim without slipping (3D rocking and wobbling).

The classical rolling disk (Routh; O'Reilly 1996; Goldstein) with the disk
replaced by the bottom rim of radius R of a uniform cylinder whose centre of
mass G sits h = H/2 above the rim's centre on the symmetry axis: the
"rolling" (wobbling) mode of Vassiliou et al. (2017).

Geometry (z up, rockbench's axes). The orientation is the ZYZ rotation
``Rz(ψ) Ry(θ) Rz(φ)``: the symmetry axis e₃ is tilted by θ ≥ 0 from +z toward
the horizontal unit vector u = (cos ψ, sin ψ, 0) (ψ is the **azimuth** toward
which the top leans, θ the **tilt**, φ the spin about e₃). With ψ = φ = 0 this
is a rotation by θ about +y: rockbench's planar θ (θ > 0 when the top moves
toward +x, pivot on the +x edge). The cylinder touches the base at the lowest
rim point P, which lies on the lean side, at azimuth ψ from the base centre.
In the frame a₁ = n = ẑ × u (line of nodes), a₂ = e₃ × n, a₃ = e₃::

    ω   = (w₁, w₂, w₃) = (θ̇, ψ̇ sin θ, ψ̇ cos θ + φ̇)
    r_PG = R a₂ + h a₃              (contact → centre of mass)
    v_G = ω × r_PG                  (no slip: the material point at P is at rest)
        = (h w₂ − R w₃, −h w₁, R w₁)

The contact point itself moves along the ground with velocity −R φ̇ n: the arc
rolled off on the ground equals the arc rolled off the rim.

Equations of motion (Newton–Euler about G, contact force eliminated, moments
about P; I₁ = m(3R² + H²)/12, I₃ = mR²/2, r² = R² + h², ψ̇ cos θ = w₂ cot θ,
g_e = g + a_z, a_u and a_n the base acceleration along u and n)::

    (I₁ + m r²) ẇ₁ = −I₃ w₂ w₃ + I₁ w₂² cot θ
                     + m (R h w₂² − R² w₂ w₃ + h² w₂² cot θ − R h w₂ w₃ cot θ)
                     − m g_e (R cos θ − h sin θ) − m a_u (R sin θ + h cos θ)

    [I₁ + m h²   −m h R  ] [ẇ₂]   [(I₃ w₃ − I₁ w₂ cot θ − m h (R w₂ + h w₂ cot θ)) w₁ − m h a_n]
    [−m h R    I₃ + m R²] [ẇ₃] = [m R (R w₂ + h w₂ cot θ) w₁ + m R a_n                       ]

and θ̇ = w₁, ψ̇ = w₂ / sin θ, φ̇ = w₃ − w₂ cot θ; the horizontal motion of G
follows from v_G (positions are relative to the base, which translates with
the acceleration (a_x, a_y, a_z): its inertial force −m a acts at G).

With w₂ = w₃ = 0 (ψ̇ = φ̇ = 0) and a_n = 0 the last two equations give
ẇ₂ = ẇ₃ = 0: the motion stays planar and the first equation is Housner's,
θ̈ = −(m g r / I₀) [(g_e/g) sin(α − θ) + (a_u/g) cos(α − θ)], I₀ = I₁ + m r²,
α = atan(R/h).

**Steady precession** (θ = θ₀, ψ̇ = Ω, φ̇ constant, fixed base) satisfies the
second equation identically and the first when

    Ω ω₃ [(I₃ + m R²) sin θ₀ + m h R cos θ₀]
      − Ω² sin θ₀ [I₁ cos θ₀ + m h (R sin θ₀ + h cos θ₀)] = −m g r sin(α − θ₀),

ω₃ = Ω cos θ₀ + φ̇: a one-parameter family at each tilt
(:func:`steady_precession`).

Events: **landing** when θ returns to 0 (the cylinder lands flat on its base;
no impact law is applied, in 3D nor in the plane: the solution stops there and
reports the state; ``landing_angle`` > 0 lands it earlier, see
:func:`solve_rolling`), **overturning** when θ reaches ``overturn_angle`` (π/2 by default, the
cylinder lying on its side, as in Housner's reference), **flight** when the
normal contact force N = m (z̈_G + g + a_z) reaches 0 (in particular when
g + a_z < 0 for a slowly moving body), **slip** when the horizontal contact
force exceeds μ N (only when a friction coefficient is given), and, not
terminal, the times when θ crosses α (the centre of mass passes over the
contact point). Every step is also scanned at 8 interior points for a margin
(θ, N, μN − |F_h|) that dipped below 0 and recovered within the step, which
solve_ivp's step-end test of events misses. In planar rocking N vanishes while
the cylinder falls over, before θ = π/2: the solution then ends in flight
where Housner's reference (which never checks N) runs on to overturning.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from enum import Enum
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from rockbench import checks
from rockbench.errors import ScenarioError
from rockbench.geometry import Cylinder

__all__ = [
    "Cylinder", "RollingState", "RollingEvent", "RollingSolution", "RollingOutcome",
    "EventKind", "SteadyPrecession", "BaseAcceleration", "solve_rolling",
    "steady_precession", "energy", "frame", "euler_rates",
]

#: Base acceleration (a_x, a_y) or (a_x, a_y, a_z) in m/s² at time t (s).
BaseAcceleration = Callable[[float], Sequence[float]]

_N_STATE = 8  # θ, ψ, φ, w1, w2, w3, x_G, y_G


class RollingOutcome(str, Enum):
    """How a rolling solution ended."""

    OK = "ok"                  # rolled on the rim until the end
    LANDED = "landed"          # θ returned to 0: lands flat on its base (stops there)
    OVERTURNED = "overturned"  # θ reached the overturning angle
    FLIGHT = "flight"          # the normal contact force vanished
    SLIPPED = "slipped"        # the friction needed exceeded μ N

    def __str__(self) -> str:
        return self.value


class EventKind(str, Enum):
    """Kinds of event along a rolling solution."""

    LANDING = "landing"
    OVERTURN = "overturn"
    FLIGHT = "flight"
    SLIP = "slip"
    BALANCE = "balance"        # θ crosses α: the centre of mass passes over the contact

    def __str__(self) -> str:
        return self.value


@dataclass(frozen=True)
class RollingState:
    """The state of the rolling cylinder at one time.

    Attributes
    ----------
    t : float
        Time (s).
    theta, psi, phi : float
        Tilt, azimuth of the contact point (and of the lean), spin (rad).
    theta_dot, psi_dot, phi_dot : float
        Their rates (rad/s).
    contact_x, contact_y : float
        Contact point on the base, relative to the base (m).
    angular_velocity : (float, float, float)
        ω in world axes (rad/s): defined also at θ = 0, where ψ̇ and φ̇ are not.
    """

    t: float
    theta: float
    psi: float
    phi: float
    theta_dot: float
    psi_dot: float
    phi_dot: float
    contact_x: float
    contact_y: float
    angular_velocity: tuple[float, float, float]


@dataclass(frozen=True)
class RollingEvent:
    """An event along the solution: its kind, time and the state then."""

    kind: EventKind
    t: float
    state: RollingState


@dataclass(frozen=True)
class RollingSolution:
    """Response of a cylinder rolling on its rim, sampled at the output times.

    Attributes
    ----------
    t : ndarray
        Output times (s), up to the terminal event.
    theta, psi, phi : ndarray
        Tilt, azimuth, spin (rad).
    theta_dot, psi_dot, phi_dot : ndarray
        Their rates (rad/s).
    contact_x, contact_y : ndarray
        Contact point's path on the base, relative to the base (m).
    com : ndarray
        Centre of mass (n, 3), horizontally relative to the base, z above it (m).
    energy : ndarray
        Kinetic energy relative to the base plus m g z_G (J); conserved on a fixed base.
    normal_force : ndarray
        Normal contact force N (N).
    friction_demand : ndarray
        |horizontal contact force| / N: the friction coefficient no slip needs.
    outcome : RollingOutcome
        How the solution ended.
    events : tuple of RollingEvent
        Balance crossings and the terminal event, in time order.
    message : str
        Human-readable outcome.
    """

    t: np.ndarray
    theta: np.ndarray
    psi: np.ndarray
    phi: np.ndarray
    theta_dot: np.ndarray
    psi_dot: np.ndarray
    phi_dot: np.ndarray
    contact_x: np.ndarray
    contact_y: np.ndarray
    com: np.ndarray
    energy: np.ndarray
    normal_force: np.ndarray
    friction_demand: np.ndarray
    outcome: RollingOutcome
    events: tuple[RollingEvent, ...]
    message: str = ""

    def first(self, kind: EventKind) -> RollingEvent | None:
        """The first event of ``kind``, or None."""
        return next((e for e in self.events if e.kind is kind), None)

    @property
    def end_time(self) -> float:
        """Time of the terminal event, or the last output time."""
        terminal = [e for e in self.events if e.kind is not EventKind.BALANCE]
        return terminal[-1].t if terminal else float(self.t[-1]) if self.t.size else 0.0


@dataclass(frozen=True)
class SteadyPrecession:
    """A steady precession: tilt θ₀ held while the cylinder rolls in a circle.

    Attributes
    ----------
    theta : float
        Tilt θ₀ (rad).
    psi_dot : float
        Precession rate Ω (rad/s).
    phi_dot : float
        Spin rate φ̇ (rad/s).
    contact_radius : float
        Signed radius ρ = −R φ̇ / Ω of the contact point's circle: its centre is at
        P − ρ u (ρ > 0: on the side of the base centre, away from the lean).
    com_radius : float
        Radius of the circle of the centre of mass (m).
    normal_force : float
        m g (N).
    friction_demand : float
        m Ω² · com_radius / N: the friction coefficient no slip needs.
    """

    theta: float
    psi_dot: float
    phi_dot: float
    contact_radius: float
    com_radius: float
    normal_force: float
    friction_demand: float


def _constants(c: Cylinder) -> tuple[float, float, float, float, float]:
    return c.m, c.radius, c.h, c.i_transverse, c.i_axial


def _dynamics(c: Cylinder, y: Any, ge: Any, ax: Any, ay: Any) -> tuple[Any, ...]:
    """Rates of the state and the contact force; works on floats and arrays alike.

    Returns (θ̇, ψ̇, φ̇, ẇ₁, ẇ₂, ẇ₃, ẋ_G, ẏ_G, N, F_h, v²) with F_h the
    horizontal contact force magnitude and v² = |v_G|².
    """
    m, R, h, i1, i3 = _constants(c)
    th, ps, w1, w2, w3 = y[0], y[1], y[3], y[4], y[5]
    s, co = np.sin(th), np.cos(th)
    sp, cp = np.sin(ps), np.cos(ps)
    with np.errstate(divide="ignore", invalid="ignore"):   # θ = 0: landed (w₂ = 0 there
        cot = co / s                                       # unless it lands precessing)
        f3 = np.where(w2 == 0, 0.0, w2 * cot)              # ψ̇ cos θ
    au = ax * cp + ay * sp             # base acceleration along u and n
    an = -ax * sp + ay * cp
    r2 = R * R + h * h
    w1d = (-i3 * w2 * w3 + i1 * f3 * w2
           - m * (-R * h * w2 * w2 + R * R * w2 * w3 - h * h * f3 * w2 + h * R * f3 * w3)
           - m * ge * (R * co - h * s) - m * au * (R * s + h * co)) / (i1 + m * r2)
    k = R * w1 * w2 + h * f3 * w1
    b2 = -i1 * f3 * w1 + i3 * w1 * w3 - m * h * k - m * h * an
    b3 = m * R * k + m * R * an
    m11, m12, m22 = i1 + m * h * h, -m * h * R, i3 + m * R * R
    det = m11 * m22 - m12 * m12
    w2d = (m22 * b2 - m12 * b3) / det
    w3d = (m11 * b3 - m12 * b2) / det
    # velocity and acceleration of G in the frame (a1, a2, a3)
    v1, v2, v3 = h * w2 - R * w3, -h * w1, R * w1
    a1 = h * w2d - R * w3d + R * w1 * w2 + h * f3 * w1
    a2 = -h * w1d + f3 * (h * w2 - R * w3) - R * w1 * w1
    a3 = R * w1d - h * w1 * w1 - h * w2 * w2 + R * w2 * w3
    vu = -co * v2 + s * v3             # horizontal velocity of G along u
    normal = m * (s * a2 + co * a3 + ge)
    fn = m * (a1 + an)
    fu = m * (-co * a2 + s * a3 + au)
    with np.errstate(divide="ignore", invalid="ignore"):
        psi_dot = np.where(w2 == 0, 0.0, w2 / s)
    return (w1, psi_dot, w3 - f3, w1d, w2d, w3d, -v1 * sp + vu * cp, v1 * cp + vu * sp,
            normal, np.hypot(fn, fu), v1 * v1 + v2 * v2 + v3 * v3)


def _com_height(c: Cylinder, theta: Any) -> Any:
    return c.h * np.cos(theta) + c.radius * np.sin(theta)


def energy(cylinder: Cylinder, theta: Any, theta_dot: Any, psi_dot: Any, phi_dot: Any,
           g: float = 9.81) -> Any:
    """Total energy of the cylinder rolling on its rim on a fixed base (J).

    Kinetic energy ½ m |v_G|² + ½ (I₁ (w₁² + w₂²) + I₃ w₃²) with the no-slip
    v_G = ω × r_PG, plus the potential m g (h cos θ + R sin θ).

    Parameters
    ----------
    cylinder : Cylinder
        The body.
    theta, theta_dot, psi_dot, phi_dot : float or ndarray
        Tilt (rad) and the rates of tilt, azimuth and spin (rad/s).
    g : float
        Gravity (m/s²).

    Returns
    -------
    float or ndarray
        Energy, with the same shape as the inputs.
    """
    m, R, h, i1, i3 = _constants(cylinder)
    s, co = np.sin(theta), np.cos(theta)
    w1, w2, w3 = theta_dot, psi_dot * s, psi_dot * co + phi_dot
    v2 = (h * w2 - R * w3) ** 2 + (h * w1) ** 2 + (R * w1) ** 2
    kin = 0.5 * m * v2 + 0.5 * (i1 * (w1 * w1 + w2 * w2) + i3 * w3 * w3)
    return kin + m * g * _com_height(cylinder, theta)


def steady_precession(cylinder: Cylinder, theta0: float, *, contact_radius: float | None = None,
                      psi_dot: float | None = None, g: float = 9.81) -> SteadyPrecession:
    """The steady precession at tilt θ₀ (fixed base), a one-parameter family.

    Give exactly one of ``contact_radius`` (the signed radius ρ of the contact
    point's circle; ρ = 0 spins the cylinder about the vertical through a fixed
    contact point) and ``psi_dot`` (the precession rate Ω).

    Parameters
    ----------
    cylinder : Cylinder
        The body.
    theta0 : float
        Tilt, 0 < θ₀ < π/2 (rad).
    contact_radius : float, optional
        ρ (m): the contact circle's centre is at P − ρ u, u the lean direction.
        The positive Ω of the family is returned (−Ω, −φ̇ is the mirror motion).
    psi_dot : float, optional
        Ω (rad/s), non-zero; φ̇ follows linearly.
    g : float
        Gravity (m/s²).

    Returns
    -------
    SteadyPrecession

    Raises
    ------
    ScenarioError
        Bad input, or no steady precession with this tilt and contact radius
        (Ω² would be negative) or this Ω.
    """
    th = checks.number(theta0, "tilt theta0", low=0.0, unit="rad")
    if th >= 0.5 * math.pi:
        raise ScenarioError(f"tilt theta0 must be below π/2, got {theta0!r}")
    g = checks.number(g, "gravity g", low=0.0, unit="m/s²")
    if (contact_radius is None) == (psi_dot is None):
        raise ScenarioError("give exactly one of 'contact_radius' and 'psi_dot'")
    m, R, h, i1, i3 = _constants(cylinder)
    s, co = math.sin(th), math.cos(th)
    a = (i3 + m * R * R) * s + m * h * R * co
    b = s * (i1 * co + m * h * (R * s + h * co))
    rhs = -m * g * cylinder.r * math.sin(cylinder.alpha - th)
    if contact_radius is not None:
        rho = checks.coordinate(contact_radius, "contact_radius")
        d = (co - rho / R) * a - b       # Ω² d = rhs, with φ̇ = −ρ Ω / R
        if d == 0.0 or rhs / d <= 0.0:
            raise ScenarioError(
                f"no steady precession at tilt {th:g} rad with contact radius {rho:g} m "
                f"(the precession rate squared would be {'infinite' if d == 0 else rhs / d:g})")
        om = math.sqrt(rhs / d)
        phid = -rho * om / R
    else:
        om = checks.number(psi_dot, "psi_dot", unit="rad/s")
        if om == 0.0:
            raise ScenarioError("psi_dot must be non-zero (Ω = 0 is rest, not precession)")
        w3 = (rhs + om * om * b) / (om * a)
        phid = w3 - om * co
    rho_c = -R * phid / om
    # G's horizontal position: P + (h sin θ − R cos θ) u; the circle's centre is P − ρ u
    com_radius = abs(h * s - R * co + rho_c)
    normal = m * g
    return SteadyPrecession(theta=th, psi_dot=om, phi_dot=phid, contact_radius=rho_c,
                            com_radius=com_radius, normal_force=normal,
                            friction_demand=m * om * om * com_radius / normal)


def _first_crossing(steps: np.ndarray, sol: Callable[[np.ndarray], np.ndarray],
                    margins: Callable[[np.ndarray, np.ndarray], np.ndarray],
                    per_step: int = 8) -> tuple[float, int] | None:
    """The first time a margin turns ≤ 0 within the steps, located by Brent's method."""
    if steps.size < 2:
        return None
    frac = np.arange(1, per_step + 1) / per_step
    grid = (steps[:-1, None] + np.diff(steps)[:, None] * frac).ravel()
    grid = np.concatenate([[steps[0]], grid])
    mg = margins(grid, sol(grid))
    # the reported terminal crossing sits at the last step's end: ignore rounding there
    bad = np.nonzero(np.any(mg[:, 1:-1] <= 0.0, axis=0))[0]
    if bad.size == 0:
        return None
    j = int(bad[0]) + 1
    k = int(np.argmax(mg[:, j] <= 0.0))

    def f(t: float) -> float:
        return float(margins(np.array([t]), sol(np.array([t])))[k, 0])

    lo, hi = float(grid[j - 1]), float(grid[j])
    if f(lo) <= 0.0:
        return lo, k
    return float(brentq(f, lo, hi, xtol=1e-14, rtol=4 * np.finfo(float).eps)), k


def _base(base_acceleration: BaseAcceleration | None) -> Callable[[float], tuple[float, ...]]:
    if base_acceleration is None:
        return lambda t: (0.0, 0.0, 0.0)
    fn = base_acceleration
    if not callable(fn):
        raise ScenarioError("base_acceleration must be a function of time returning "
                            "(a_x, a_y) or (a_x, a_y, a_z)")

    def acc(t: float) -> tuple[float, ...]:
        a = tuple(float(v) for v in fn(t))
        if len(a) == 2:
            return (a[0], a[1], 0.0)
        if len(a) != 3 or not all(math.isfinite(v) for v in a):
            raise ScenarioError(f"base_acceleration({t:g}) must give 2 or 3 finite numbers, "
                                f"got {a!r}")
        return a
    return acc


def frame(theta: float, psi: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The lean direction u and the frame a₁ = n = ẑ × u, a₂ = e₃ × n, a₃ = e₃ (world axes)
    of the cylinder tilted by θ toward the azimuth ψ."""
    s, co = math.sin(theta), math.cos(theta)
    u = np.array([math.cos(psi), math.sin(psi), 0.0])
    n = np.array([-u[1], u[0], 0.0])
    zz = np.array([0.0, 0.0, 1.0])
    return u, n, -co * u + s * zz, s * u + co * zz


def euler_rates(theta: Any, w2: Any, w3: Any) -> tuple[Any, Any]:
    """ψ̇ = w₂ / sin θ and φ̇ = w₃ − w₂ cot θ; at θ = 0 with w₂ = 0: ψ̇ = 0, φ̇ = w₃.

    At θ = 0 only ψ̇ + φ̇ = w₃ is defined (ψ̇ → ∞ as the cylinder lands while precessing).
    """
    s, co = np.sin(theta), np.cos(theta)
    flat = (s == 0) & (w2 == 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        psi_dot = np.where(flat, 0.0, w2 / np.where(flat, 1.0, s))
        phi_dot = np.where(flat, w3, w3 - psi_dot * co)
    return psi_dot, phi_dot


def _state(c: Cylinder, t: float, y: np.ndarray) -> RollingState:
    th, ps = float(y[0]), float(y[1])
    s, co = math.sin(th), math.cos(th)
    off = c.h * s - c.radius * co      # horizontal offset of G from P along u
    psi_dot, phi_dot = euler_rates(th, float(y[4]), float(y[5]))
    w1, w2, w3 = float(y[3]), float(y[4]), float(y[5])
    _, a1, a2, a3 = frame(th, ps)
    omega = w1 * a1 + w2 * a2 + w3 * a3
    return RollingState(
        t=float(t), theta=th, psi=ps, phi=float(y[2]), theta_dot=w1,
        psi_dot=float(psi_dot), phi_dot=float(phi_dot),
        contact_x=float(y[6]) - off * math.cos(ps), contact_y=float(y[7]) - off * math.sin(ps),
        angular_velocity=(float(omega[0]), float(omega[1]), float(omega[2])))


def solve_rolling(
    cylinder: Cylinder,
    theta0: float,
    psi0: float = 0.0,
    theta_dot0: float = 0.0,
    psi_dot0: float = 0.0,
    phi_dot0: float = 0.0,
    duration: float = 5.0,
    *,
    phi0: float = 0.0,
    contact0: tuple[float, float] = (0.0, 0.0),
    g: float = 9.81,
    base_acceleration: BaseAcceleration | None = None,
    breakpoints: Sequence[float] = (),
    t_eval: Sequence[float] | np.ndarray | None = None,
    output_rate: float = 1000.0,
    friction: float | None = None,
    overturn_angle: float = 0.5 * math.pi,
    landing_angle: float = 0.0,
    rtol: float = 1e-10,
    atol: float = 1e-12,
) -> RollingSolution:
    """Integrate the cylinder rolling on its bottom rim without slipping.

    Parameters
    ----------
    cylinder : Cylinder
        The body.
    theta0 : float
        Initial tilt, ``landing_angle`` < θ₀ < ``overturn_angle`` (rad): it starts on its rim.
    psi0 : float
        Initial azimuth of the lean and of the contact point, from +x toward +y (rad).
    theta_dot0, psi_dot0, phi_dot0 : float
        Initial rates of tilt, azimuth and spin (rad/s).
    duration : float
        End time (s).
    phi0 : float
        Initial spin angle (rad).
    contact0 : (float, float)
        Initial contact point on the base (m).
    g : float
        Gravity (m/s²).
    base_acceleration : callable, optional
        t ↦ (a_x, a_y) or (a_x, a_y, a_z), the base's acceleration (m/s²); None: fixed base.
    breakpoints : sequence of float
        Times where the base acceleration is not smooth; the integration restarts there.
    t_eval : array_like, optional
        Output times in [0, duration], increasing; default: ``output_rate`` samples per second.
    output_rate : float
        Samples per second when ``t_eval`` is not given.
    friction : float, optional
        Coulomb coefficient μ: stop with ``slipped`` where the friction needed exceeds it.
    overturn_angle : float
        Tilt at which the cylinder counts as overturned (rad, default π/2: lying on its side).
    landing_angle : float
        Tilt at which it counts as landed flat (rad). The default 0 follows the rim
        model down to θ = 0, which a planar rocking reaches; in 3D any precession
        (ψ̇ ∝ 1/sin²θ near upright, the rolling disk's singular limit) turns it back at a
        tiny tilt with an enormous ψ̇ instead. A small positive angle (say 1e-3 rad,
        a base edge within R·θ of the ground) stops there as a landing.
    rtol, atol : float
        DOP853 tolerances.

    Returns
    -------
    RollingSolution

    Raises
    ------
    ScenarioError
        A value out of range or not a number.
    """
    c = cylinder
    if not isinstance(c, Cylinder):
        raise ScenarioError(f"cylinder must be a Cylinder, got {checks.describe(c)}")
    ot = checks.number(overturn_angle, "overturn_angle", low=0.0, high=0.5 * math.pi,
                       unit="rad")
    land = checks.number(landing_angle, "landing_angle", low=0.0, strict=False, unit="rad")
    if land >= ot:
        raise ScenarioError(f"landing_angle {land:g} must be below overturn_angle {ot:g}")
    th0 = checks.number(theta0, "tilt theta0", low=land, unit="rad")
    if th0 >= ot:
        raise ScenarioError(f"tilt theta0 must be below the overturning angle {ot:g} rad, "
                            f"got {theta0!r}")
    vals = [checks.number(v, name, unit=u) for v, name, u in (
        (psi0, "psi0", "rad"), (theta_dot0, "theta_dot0", "rad/s"),
        (psi_dot0, "psi_dot0", "rad/s"), (phi_dot0, "phi_dot0", "rad/s"), (phi0, "phi0", "rad"))]
    psi0, theta_dot0, psi_dot0, phi_dot0, phi0 = vals
    if not isinstance(contact0, (tuple, list)) or len(contact0) != 2:
        raise ScenarioError(f"contact0 must be (x, y) in metres, got {checks.describe(contact0)}")
    x0 = checks.coordinate(contact0[0], "contact0 x")
    y0 = checks.coordinate(contact0[1], "contact0 y")
    end = checks.number(duration, "duration", low=0.0, unit="s")
    g = checks.number(g, "gravity g", low=0.0, unit="m/s²")
    mu = None if friction is None else checks.number(friction, "friction", low=0.0)
    for tol, name in ((rtol, "rtol"), (atol, "atol")):
        checks.number(tol, name, low=0.0)
    if t_eval is None:
        rate = checks.number(output_rate, "output_rate", low=0.0, unit="1/s")
        n = int(math.floor(end * rate + 1e-9))
        tt = np.arange(n + 1) / rate
        if tt[-1] < end:
            tt = np.append(tt, end)
    else:
        tt = checks.number_array(t_eval, "t_eval")
        if tt.ndim != 1 or tt.size == 0 or np.any(np.diff(tt) <= 0) or tt[0] < 0 \
                or tt[-1] > end * (1 + 1e-12):
            raise ScenarioError("t_eval must be increasing times within [0, duration]")
    acc = _base(base_acceleration)

    s0, c0 = math.sin(th0), math.cos(th0)
    off0 = c.h * s0 - c.radius * c0
    y = np.array([th0, psi0, phi0, theta_dot0, psi_dot0 * s0, psi_dot0 * c0 + phi_dot0,
                  x0 + off0 * math.cos(psi0), y0 + off0 * math.sin(psi0)])

    def forces(t: float, yy: np.ndarray) -> tuple[Any, ...]:
        ax, ay, az = acc(t)
        return _dynamics(c, yy, g + az, ax, ay)

    def rhs(t: float, yy: np.ndarray) -> list[float]:
        return [float(v) for v in forces(t, yy)[:_N_STATE]]

    terminal = [EventKind.LANDING, EventKind.OVERTURN, EventKind.FLIGHT]
    if mu is not None:
        terminal.append(EventKind.SLIP)

    def margins(t: np.ndarray, yy: np.ndarray) -> np.ndarray:
        """Per terminal event, a margin that is positive while rolling may go on."""
        a = np.array([acc(float(ti)) for ti in t]).reshape(-1, 3).T
        f = _dynamics(c, yy, g + a[2], a[0], a[1])
        rows = [yy[0] - land, ot - yy[0], f[8]]
        if mu is not None:
            rows.append(mu * f[8] - f[9])
        return np.array(rows, dtype=float).reshape(len(terminal), -1)

    def event(k: int) -> Callable[[float, np.ndarray], float]:
        def fn(t: float, yy: np.ndarray) -> float:
            return float(margins(np.array([t]), yy.reshape(-1, 1))[k, 0])
        fn.terminal = True  # type: ignore[attr-defined]  # read by solve_ivp
        fn.direction = -1.0  # type: ignore[attr-defined]
        return fn

    def ev_balance(t: float, yy: np.ndarray) -> float:
        return float(yy[0]) - c.alpha

    kinds = [*terminal, EventKind.BALANCE]
    fns = [*(event(k) for k in range(len(terminal))), ev_balance]
    outcome_of = {EventKind.LANDING: RollingOutcome.LANDED,
                  EventKind.OVERTURN: RollingOutcome.OVERTURNED,
                  EventKind.FLIGHT: RollingOutcome.FLIGHT,
                  EventKind.SLIP: RollingOutcome.SLIPPED}

    events: list[RollingEvent] = []
    outcome = RollingOutcome.OK
    cuts = sorted({0.0, end, *(float(b) for b in breakpoints if 0.0 < float(b) < end)})
    out = np.full((_N_STATE, tt.size), np.nan)
    t_stop = end
    for ta, tb in zip(cuts[:-1], cuts[1:], strict=True):
        # the forcing may jump at a breakpoint: the contact may be lost right there
        m0 = margins(np.array([ta]), y.reshape(-1, 1))[:, 0]
        if np.any(m0[2:] <= 0.0):
            k = 2 + int(np.argmax(m0[2:] <= 0.0))
            events.append(RollingEvent(terminal[k], ta, _state(c, ta, y)))
            outcome, t_stop = outcome_of[terminal[k]], ta
            sel = tt == ta
            out[:, sel] = y[:, None]
            break
        res = solve_ivp(rhs, (ta, tb), y, method="DOP853", rtol=rtol, atol=atol,
                        dense_output=True, events=fns)
        if res.status < 0:
            raise ScenarioError(f"rolling cylinder: integration failed at t = {res.t[-1]:g} s: "
                                f"{res.message}")
        t_end = float(res.t[-1])
        found = [RollingEvent(kind, float(ti), _state(c, float(ti), yi))
                 for kind, te, ye in zip(kinds, res.t_events, res.y_events, strict=True)
                 for ti, yi in zip(te, ye, strict=True)]
        # a margin may dip below 0 and recover within one step, unseen by the step-end
        # test of solve_ivp: scan each step densely and take the first crossing
        early = _first_crossing(res.t, res.sol, margins)
        if early is not None and early[0] < t_end:
            t_end, k = early
            ye = res.sol(t_end)
            found = [e for e in found if e.t < t_end]
            found.append(RollingEvent(terminal[k], t_end, _state(c, t_end, ye)))
            stopped = True
        else:
            stopped = res.status == 1
        events.extend(found)
        if stopped:
            last = max((e for e in found if e.kind is not EventKind.BALANCE),
                       key=lambda e: e.t)
            outcome, t_stop = outcome_of[last.kind], t_end
        closed = stopped or tb == end   # the last piece keeps its end point
        sel = (tt >= ta) & ((tt <= t_end) if closed else (tt < tb))
        if np.any(sel):
            out[:, sel] = res.sol(tt[sel])
        if stopped:
            break
        y = res.y[:, -1]
    events.sort(key=lambda e: e.t)

    keep = ~np.isnan(out[0])
    t, st = tt[keep], out[:, keep]
    th, ps = st[0], st[1]
    off = c.h * np.sin(th) - c.radius * np.cos(th)
    psi_dot, phi_dot = euler_rates(th, st[4], st[5])
    acc_t = np.array([acc(float(ti)) for ti in t]).reshape(-1, 3).T
    dyn = _dynamics(c, st, g + acc_t[2], acc_t[0], acc_t[1])
    kin = 0.5 * c.m * dyn[10] + 0.5 * (c.i_transverse * (st[3] ** 2 + st[4] ** 2)
                                       + c.i_axial * st[5] ** 2)
    normal = np.asarray(dyn[8], dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        demand = np.where(normal > 0, np.asarray(dyn[9]) / normal, np.inf)
    messages = {
        RollingOutcome.OK: "rolled on its rim to the end",
        RollingOutcome.LANDED: f"landed flat on its base at t = {t_stop:.6g} s (stopped there)",
        RollingOutcome.OVERTURNED: f"overturned (tilt {ot:.4g} rad) at t = {t_stop:.6g} s",
        RollingOutcome.FLIGHT: f"left the ground (normal force 0) at t = {t_stop:.6g} s",
        RollingOutcome.SLIPPED: f"started to slip (friction {mu}) at t = {t_stop:.6g} s",
    }
    return RollingSolution(
        t=t, theta=th, psi=ps, phi=st[2], theta_dot=st[3], psi_dot=psi_dot, phi_dot=phi_dot,
        contact_x=st[6] - off * np.cos(ps), contact_y=st[7] - off * np.sin(ps),
        com=np.column_stack([st[6], st[7], _com_height(c, th)]),
        energy=kin + c.m * g * _com_height(c, th), normal_force=normal,
        friction_demand=demand, outcome=outcome, events=tuple(events),
        message=messages[outcome])
