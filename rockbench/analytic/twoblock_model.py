"""Two stacked rigid blocks rocking on a rigid base: geometry, equations of motion, impacts.

This module holds the *algebra* of the two-block reference model of
``two-block-model.md`` (Psycharis 1990 / Spanos et al. 2001 tradition, derived
from first principles): motion patterns, mass matrices and accelerations (§2),
uplift indicators (§3.2, §3.3), the general impact law and the candidate
enumeration of impact outcomes (§3.4, §3.5), the start pattern from rest
(§3.1) and energy (§2.6). The time integration lives in
:mod:`rockbench.analytic.twoblock`.

Conventions: the spec's rocking plane (x, y) is rockbench's (x, z); θ is the
rotation about +y, positive when the top of a block moves toward +x. A positive
base acceleration tends to produce negative rotations.

Vertical base acceleration ü_z (spec §0: "replace g → g + ü_z everywhere"): in
the base's frame every block carries the inertial force −m ü_z besides its
weight, so wherever gravity enters the dynamics — the right-hand sides G of
pattern ``B`` (§2.5), Housner's equations of ``M`` and ``U`` (§2.3, §2.4), the
uplift indicators λ_if, λ_b (§3.2, §3.3) and the thresholds and start pattern
from rest (§3.1) — g becomes g_e = g + ü_z. In the methods below this is the
keyword ``az`` (m/s², positive up, default 0: the formulas are then exactly
the horizontal ones). The impact maps (§3.4) do not depend on g and are
unchanged; :meth:`TwoBlockModel.energy` keeps the potential energy of gravity
alone (the vertical inertial force does work instead, see
:mod:`rockbench.analytic.twoblock`). Where g + ü_z < 0 the base falls faster
than the blocks and they leave it: the model ends there.

Chamfered blocks (rockbench's departure from the spec): the pivots sit at the
chamfer corners *on* the faces, so every lever arm uses the pivot half-width
``b − chamfer`` while the centroidal inertia is that of the full box. With zero
chamfer this is exactly the spec.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

if TYPE_CHECKING:
    from rockbench.geometry import Upright

__all__ = ["BlockParams", "Pattern", "TwoBlockModel", "parse_pattern"]


@dataclass(frozen=True)
class BlockParams:
    """Planar parameters of one block of the two-block model.

    Parameters
    ----------
    b : float
        Pivot half-width (m): half the distance between the rocking pivots of
        the block's bottom face (``Block.pivot_half_width``).
    h : float
        Half-height (m).
    m : float
        Mass (kg, or kg/m per unit thickness).
    I : float
        Centroidal moment of inertia about the out-of-plane axis (kg m²); for a
        uniform full rectangle ``m (b² + h²) / 3`` with the full half-width.
    """

    b: float
    h: float
    m: float
    I: float  # noqa: E741 - the spec's symbol

    def __post_init__(self) -> None:
        for name in ("b", "h", "m", "I"):
            v = float(getattr(self, name))
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"BlockParams.{name} must be finite and > 0, got {v!r}")
            object.__setattr__(self, name, v)

    @classmethod
    def uniform(cls, b: float, h: float, m: float) -> BlockParams:
        """A uniform rectangle of half-width ``b``, half-height ``h`` and mass ``m``."""
        return cls(b, h, m, m * (b * b + h * h) / 3.0)

    @classmethod
    def from_block(cls, block: Upright) -> BlockParams:
        """Parameters of a block (pivots at the chamfer corners) or a drum (at its rim)."""
        return cls(
            float(block.pivot_half_width),
            float(block.h),
            float(block.m),
            float(block.inertia[1]),
        )


class Pattern(NamedTuple):
    """A motion pattern given by the state of the two contacts.

    ``base`` is the state of the base contact and ``iface`` that of the
    interface: ``0`` for a closed face contact, ``±1`` for rocking on the pivot
    on that side. Hence ``R`` = (0, 0), ``M(s)`` = (s, 0), ``U(s2)`` = (0, s2)
    and ``B(s1, s2)`` = (s1, s2); ``s2`` is the sign of the *relative* rotation.
    """

    base: int
    iface: int

    @property
    def kind(self) -> str:
        """One of ``"R"``, ``"M"``, ``"U"``, ``"B"``."""
        if self.base == 0:
            return "R" if self.iface == 0 else "U"
        return "M" if self.iface == 0 else "B"

    @property
    def name(self) -> str:
        """The spec's name, e.g. ``"B(+1,-1)"``."""
        k = self.kind
        if k == "R":
            return "R"
        if k == "M":
            return f"M({self.base:+d})"
        if k == "U":
            return f"U({self.iface:+d})"
        return f"B({self.base:+d},{self.iface:+d})"

    @property
    def ndof(self) -> int:
        """Number of degrees of freedom (0, 1 or 2)."""
        return (self.base != 0) + (self.iface != 0)

    def __str__(self) -> str:
        return self.name


_PAT_RE = re.compile(r"^\s*([RMUB])\s*(?:\(\s*([+-]?1)\s*(?:,\s*([+-]?1)\s*)?\))?\s*$")


def parse_pattern(name: str | Pattern) -> Pattern:
    """Parse a pattern name such as ``"R"``, ``"M(-1)"``, ``"U(+1)"`` or ``"B(+1,-1)"``."""
    if isinstance(name, Pattern):
        return name
    mt = _PAT_RE.match(str(name))
    if not mt:
        raise ValueError(f"invalid motion pattern {name!r}; use R, M(±1), U(±1) or B(±1,±1)")
    kind, a, b = mt.group(1), mt.group(2), mt.group(3)
    nargs = {"R": 0, "M": 1, "U": 1, "B": 2}[kind]
    if (a is not None) + (b is not None) != nargs:
        raise ValueError(f"pattern {name!r}: {kind} takes {nargs} sign(s)")
    if kind == "R":
        return Pattern(0, 0)
    if kind == "M":
        return Pattern(int(a), 0)
    if kind == "U":
        return Pattern(0, int(a))
    return Pattern(int(a), int(b))


def _rot(vx: float, vy: float, th: float) -> tuple[float, float]:
    """R(θ) v = (vx cos θ + vy sin θ, −vx sin θ + vy cos θ)."""
    c, s = math.cos(th), math.sin(th)
    return vx * c + vy * s, -vx * s + vy * c


def _sgn(x: float) -> int:
    return -1 if x < 0 else 1


class TwoBlockModel:
    """Constants and algebra of two stacked blocks on a rigid base.

    Parameters
    ----------
    lower, upper : BlockParams
        Lower block (1) and upper block (2).
    g : float
        Gravity (m/s²).

    Notes
    -----
    Attributes follow §1.4 of the spec: ``b1, h1, m1, I1, b2, h2, m2, I2, bc``,
    ``R1, alpha1, IO1, R2, alpha2, IC2, p2, eta2, ybar, RM, alphaM, IOM, pM,
    etaM`` and the static uplift thresholds ``thr_upper = g bc/h2``,
    ``thr_stack = g b1/ybar`` (m/s²), with ``threshold`` the smaller; under a
    vertical base acceleration ü_z each is multiplied by (g + ü_z)/g
    (:meth:`threshold_at`).
    """

    def __init__(self, lower: BlockParams, upper: BlockParams, g: float = 9.81) -> None:
        self.lower, self.upper, self.g = lower, upper, float(g)
        b1, h1, m1, i1 = lower.b, lower.h, lower.m, lower.I
        b2, h2, m2, i2 = upper.b, upper.h, upper.m, upper.I
        self.b1, self.h1, self.m1, self.I1 = b1, h1, m1, i1
        self.b2, self.h2, self.m2, self.I2 = b2, h2, m2, i2
        self.bc = bc = min(b1, b2)
        self.R1 = math.hypot(b1, h1)
        self.alpha1 = math.atan2(b1, h1)
        self.IO1 = i1 + m1 * self.R1**2
        self.R2 = math.hypot(bc, h2)
        self.alpha2 = math.atan2(bc, h2)
        self.IC2 = i2 + m2 * self.R2**2
        self.p2 = math.sqrt(m2 * self.g * self.R2 / self.IC2)
        self.eta2 = 1.0 - 2.0 * m2 * bc * bc / self.IC2
        self.mt = m1 + m2
        self.ybar = (m1 * h1 + m2 * (2 * h1 + h2)) / self.mt
        self.RM = math.hypot(b1, self.ybar)
        self.alphaM = math.atan2(b1, self.ybar)
        self.IOM = i1 + m1 * self.R1**2 + i2 + m2 * (b1 * b1 + (2 * h1 + h2) ** 2)
        self.pM = math.sqrt(self.mt * self.g * self.RM / self.IOM)
        self.etaM = 1.0 - 2.0 * self.mt * b1 * b1 / self.IOM
        self.thr_upper = self.g * bc / h2
        self.thr_stack = self.g * b1 / self.ybar
        self.threshold = min(self.thr_upper, self.thr_stack)

    def _ge(self, az: float) -> float:
        """Effective gravity g + ü_z (exactly ``g`` when ``az`` is 0)."""
        return self.g + az if az else self.g

    def threshold_at(self, az: float = 0.0) -> float:
        """Rest threshold of |ü_g| under a vertical base acceleration ``az``:
        (g + ü_z) min(tan α2, tan αM) (§3.1 with g → g + ü_z)."""
        return self.threshold * (1.0 + az / self.g) if az else self.threshold

    # ------------------------------------------------------------------ EOM
    def matrices_B(
        self, s1: int, s2: int, th1: float, th2: float, w1: float = 0.0, w2: float = 0.0,
        *, az: float = 0.0,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Mass matrix, C, G and B of pattern ``B(s1,s2)`` (§2.5).

        ``az`` is the vertical base acceleration ü_z: G is that of gravity g + ü_z.

        Returns
        -------
        M : ndarray (2, 2)
        C, G, B : ndarray (2,)
            With ``M q̈ + C + G = −ü_g B``.
        """
        m1, m2, g = self.m1, self.m2, self._ge(az)
        cx, cy = _rot(s2 * self.bc - s1 * self.b1, 2 * self.h1, th1)
        dx, dy = _rot(-s2 * self.bc, self.h2, th2)
        ex, ey = _rot(-s1 * self.b1, self.h1, th1)
        m12 = m2 * (cx * dx + cy * dy)
        sd = cx * dy - cy * dx
        mm = np.array([[self.IO1 + m2 * (cx * cx + cy * cy), m12], [m12, self.IC2]])
        cc = np.array([m2 * sd * w2 * w2, -m2 * sd * w1 * w1])
        gg = -g * np.array([m1 * ex + m2 * cx, m2 * dx])
        bb = np.array([m1 * ey + m2 * cy, m2 * dy])
        return mm, cc, gg, bb

    def accel_B(
        self, s1: int, s2: int, th1: float, th2: float, w1: float, w2: float, a: float,
        *, az: float = 0.0,
    ) -> np.ndarray:
        """Absolute accelerations (θ̈1, θ̈2) in pattern ``B(s1,s2)``."""
        mm, cc, gg, bb = self.matrices_B(s1, s2, th1, th2, w1, w2, az=az)
        return np.linalg.solve(mm, -a * bb - cc - gg)

    def accel_M(self, s: int, th: float, a: float, *, az: float = 0.0) -> float:
        """θ̈ of the monolithic pattern ``M(s)`` (Housner for the composite body, §2.3):
        θ̈ = −p_M² [(1 + ü_z/g) sin(s αM − θ) + (ü_g/g) cos(s αM − θ)]."""
        arg = s * self.alphaM - th
        if az:
            return -self.pM**2 * ((1.0 + az / self.g) * math.sin(arg)
                                  + a / self.g * math.cos(arg))
        return -self.pM**2 * (math.sin(arg) + a / self.g * math.cos(arg))

    def accel_U(self, s2: int, th2: float, a: float, *, az: float = 0.0) -> float:
        """θ̈2 of pattern ``U(s2)`` (upper block on the resting lower block, §2.4):
        θ̈2 = −p2² [(1 + ü_z/g) sin(s2 α2 − θ2) + (ü_g/g) cos(s2 α2 − θ2)]."""
        arg = s2 * self.alpha2 - th2
        if az:
            return -self.p2**2 * ((1.0 + az / self.g) * math.sin(arg)
                                  + a / self.g * math.cos(arg))
        return -self.p2**2 * (math.sin(arg) + a / self.g * math.cos(arg))

    def accelerations(
        self, pattern: Pattern | str, th1: float, th2: float, w1: float, w2: float, a: float,
        *, az: float = 0.0,
    ) -> tuple[float, float]:
        """Absolute accelerations (θ̈1, θ̈2) in any pattern (``az``: vertical ü_z)."""
        p = parse_pattern(pattern)
        k = p.kind
        if k == "R":
            return 0.0, 0.0
        if k == "M":
            dd = self.accel_M(p.base, th1, a, az=az)
            return dd, dd
        if k == "U":
            return 0.0, self.accel_U(p.iface, th2, a, az=az)
        d1, d2 = self.accel_B(p.base, p.iface, th1, th2, w1, w2, a, az=az)
        return float(d1), float(d2)

    # ------------------------------------------------------ uplift indicators
    def lambda_if(self, s: int, sigma: int, th: float, w: float, a: float,
                  *, az: float = 0.0) -> float:
        """Interface uplift indicator λ_if(σ) during ``M(s)`` (§3.2, gravity g + ``az``), N·m."""
        m2, g = self.m2, self._ge(az)
        cx, cy = _rot(sigma * self.bc - s * self.b1, 2 * self.h1, th)
        dx, dy = _rot(-sigma * self.bc, self.h2, th)
        m12 = m2 * (cx * dx + cy * dy)
        sd = cx * dy - cy * dx
        ddm = self.accel_M(s, th, a, az=az)
        return sigma * ((m12 + self.IC2) * ddm - m2 * sd * w * w - g * m2 * dx + a * m2 * dy)

    def lambda_b(self, s2: int, sigma: int, th2: float, w2: float, a: float,
                 *, az: float = 0.0) -> float:
        """Base uplift indicator λ_b(σ) during ``U(s2)`` (§3.3, gravity g + ``az``), N·m."""
        m1, m2, g = self.m1, self.m2, self._ge(az)
        cx, cy = s2 * self.bc - sigma * self.b1, 2 * self.h1
        dx, dy = _rot(-s2 * self.bc, self.h2, th2)
        ex, ey = -sigma * self.b1, self.h1
        m12 = m2 * (cx * dx + cy * dy)
        sd = cx * dy - cy * dx
        ddu = self.accel_U(s2, th2, a, az=az)
        return sigma * (m12 * ddu + m2 * sd * w2 * w2 - g * (m1 * ex + m2 * cx)
                        + a * (m1 * ey + m2 * cy))

    # ----------------------------------------------------- start from rest
    def start_pattern(self, a: float, *, az: float = 0.0) -> Pattern:
        """Pattern that starts from rest under a base acceleration ``a`` (§3.1).

        Returns ``R`` when ``|a|`` does not exceed ``(g + az) min(tan α2, tan αM)``
        (``az``: the vertical base acceleration ü_z); otherwise the unique
        consistent candidate (the one with the smallest violation of the
        consistency conditions, for robustness at ties).
        """
        if abs(a) <= self.threshold_at(az):
            return Pattern(0, 0)
        best, best_v = Pattern(0, 0), math.inf
        scale_m = self.mt * self.g * self.RM
        for p in self.candidates_from_rest():
            viol: list[float] = []
            if p.kind == "M":
                dd = self.accel_M(p.base, 0.0, a, az=az)
                viol.append(-p.base * dd / self.pM**2)
                viol += [-self.lambda_if(p.base, sg, 0.0, 0.0, a, az=az) / scale_m
                         for sg in (1, -1)]
            elif p.kind == "U":
                dd = self.accel_U(p.iface, 0.0, a, az=az)
                viol.append(-p.iface * dd / self.p2**2)
                viol += [-self.lambda_b(p.iface, sg, 0.0, 0.0, a, az=az) / scale_m
                         for sg in (1, -1)]
            else:
                d1, d2 = self.accel_B(p.base, p.iface, 0.0, 0.0, 0.0, 0.0, a, az=az)
                viol += [-p.base * d1 / self.pM**2, -p.iface * (d2 - d1) / self.p2**2]
            v = max(0.0, *viol)
            if v < best_v:
                best, best_v = p, v
        return best

    @staticmethod
    def candidates_from_rest() -> list[Pattern]:
        """All moving patterns (M, U, B) in a fixed order."""
        return [Pattern(1, 0), Pattern(-1, 0), Pattern(0, 1), Pattern(0, -1)] + [
            Pattern(a, b) for a in (1, -1) for b in (1, -1)
        ]

    # ------------------------------------------------------------ geometry
    def positions(
        self, th1: np.ndarray | float, th2: np.ndarray | float
    ) -> tuple[np.ndarray, np.ndarray]:
        """Centroids G1, G2 (each shape (..., 2): x, height) in the base frame.

        The origin is the centre of the lower block's bottom face when upright;
        the pivot sides are inferred from the signs of θ1 and φ = θ2 − θ1 (any
        side at zero gap gives the same positions).
        """
        th1 = np.asarray(th1, float)
        th2 = np.asarray(th2, float)
        s1 = np.where(th1 < 0, -1.0, 1.0)
        s2 = np.where(th2 - th1 < 0, -1.0, 1.0)
        c1, n1, c2, n2 = np.cos(th1), np.sin(th1), np.cos(th2), np.sin(th2)
        ox = s1 * self.b1

        def rot(vx: np.ndarray, vy: np.ndarray | float, c: np.ndarray,
                n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            return vx * c + vy * n, -vx * n + vy * c

        ex, ey = rot(-s1 * self.b1, self.h1, c1, n1)
        cx, cy = rot(s2 * self.bc - s1 * self.b1, 2 * self.h1, c1, n1)
        dx, dy = rot(-s2 * self.bc, self.h2, c2, n2)
        g1 = np.stack([ox + ex, ey], axis=-1)
        g2 = np.stack([ox + cx + dx, cy + dy], axis=-1)
        return g1, g2

    def _arms(self, th1: float, th2: float) -> tuple[float, ...]:
        s1 = _sgn(th1)
        s2 = _sgn(th2 - th1)
        ex, ey = _rot(-s1 * self.b1, self.h1, th1)
        cx, cy = _rot(s2 * self.bc - s1 * self.b1, 2 * self.h1, th1)
        dx, dy = _rot(-s2 * self.bc, self.h2, th2)
        return ex, ey, cx, cy, dx, dy

    def energy(
        self, th1: np.ndarray | float, th2: np.ndarray | float,
        w1: np.ndarray | float, w2: np.ndarray | float,
        s1: np.ndarray | float | None = None, s2: np.ndarray | float | None = None,
    ) -> np.ndarray:
        """Total mechanical energy T + V (J) relative to the base (height 0 at the base).

        Parameters
        ----------
        th1, th2, w1, w2 : array_like
            Absolute angles and rates (vectorised).
        s1, s2 : array_like, optional
            Active base and interface pivot sides (0 = closed/unknown). Needed
            only at a zero gap that rotates about the pivot on its negative
            side; otherwise the sides follow from the signs of θ1 and θ2 − θ1.

        Returns
        -------
        ndarray
            T + V in J.
        """
        th1, th2, w1, w2 = (np.asarray(v, float) for v in (th1, th2, w1, w2))
        inf1 = np.where(th1 < 0, -1.0, 1.0)
        inf2 = np.where(th2 - th1 < 0, -1.0, 1.0)
        s1 = inf1 if s1 is None else np.where(np.asarray(s1) != 0, np.sign(s1), inf1)
        s2 = inf2 if s2 is None else np.where(np.asarray(s2) != 0, np.sign(s2), inf2)
        c1, n1, c2, n2 = np.cos(th1), np.sin(th1), np.cos(th2), np.sin(th2)
        ex, ey = -s1 * self.b1 * c1 + self.h1 * n1, s1 * self.b1 * n1 + self.h1 * c1
        vx = s2 * self.bc - s1 * self.b1
        cx, cy = vx * c1 + 2 * self.h1 * n1, -vx * n1 + 2 * self.h1 * c1
        dx, dy = -s2 * self.bc * c2 + self.h2 * n2, s2 * self.bc * n2 + self.h2 * c2
        # CG velocity of a point at lever arm r: θ̇ r⊥, r⊥ = (r_y, −r_x)
        v1 = (w1 * ey) ** 2 + (w1 * ex) ** 2
        v2 = (w1 * cy + w2 * dy) ** 2 + (w1 * cx + w2 * dx) ** 2
        t = 0.5 * (self.m1 * v1 + self.I1 * w1**2 + self.m2 * v2 + self.I2 * w2**2)
        v = self.g * (self.m1 * ey + self.m2 * (cy + dy))
        return t + v

    # -------------------------------------------------------------- impacts
    def levers(self, pattern: Pattern | str, th1: float, th2: float) -> list[tuple]:
        """Lever arms of the pattern's generalised coordinates at configuration (θ1, θ2).

        Returns one tuple ``(r1x, r1y, ω1, r2x, r2y, ω2)`` per coordinate (§3.4
        table): the CG velocity of block b is ``q̇_i r_b,i⊥`` and its angular
        velocity ``q̇_i ω_b,i``. Pivots are those of ``pattern``.
        """
        p = parse_pattern(pattern)
        ex, ey, cx, cy, dx, dy = self._arms(th1, th2)
        # actual positions (relative to the actual base pivot side of the configuration)
        s1a = _sgn(th1)
        o1x = s1a * self.b1
        g1 = (o1x + ex, ey)
        cpt = (o1x + cx, cy)
        g2 = (cpt[0] + dx, cpt[1] + dy)
        k = p.kind
        if k == "R":
            return []
        if k == "U" or k == "B":
            # interface pivot C(s2) is a point of block 1: upright coords (s2 bc, 2 h1)
            vx, vy = _rot(p.iface * self.bc - s1a * self.b1, 2 * self.h1, th1)
            cpat = (o1x + vx, vy)
            arm2 = (g2[0] - cpat[0], g2[1] - cpat[1])
        if k == "M" or k == "B":
            o = (p.base * self.b1, 0.0)
            arm1 = (g1[0] - o[0], g1[1] - o[1])
        if k == "M":
            return [(arm1[0], arm1[1], 1.0, g2[0] - o[0], g2[1] - o[1], 1.0)]
        if k == "U":
            return [(0.0, 0.0, 0.0, arm2[0], arm2[1], 1.0)]
        return [
            (arm1[0], arm1[1], 1.0, cpat[0] - o[0], cpat[1] - o[1], 0.0),
            (0.0, 0.0, 0.0, arm2[0], arm2[1], 1.0),
        ]

    def _metric(self, la: list[tuple], lb: list[tuple]) -> np.ndarray:
        m1, m2, i1, i2 = self.m1, self.m2, self.I1, self.I2
        out = np.empty((len(la), len(lb)))
        for i, a in enumerate(la):
            for j, b in enumerate(lb):
                out[i, j] = (m1 * (a[0] * b[0] + a[1] * b[1]) + i1 * a[2] * b[2]
                             + m2 * (a[3] * b[3] + a[4] * b[4]) + i2 * a[5] * b[5])
        return out

    def impact_map(
        self, pre: Pattern | str, post: Pattern | str, th1: float, th2: float
    ) -> np.ndarray:
        """Matrix P with q̇⁺ = P q̇⁻ (pattern coordinates), from M⁺ q̇⁺ = N q̇⁻ (§3.4).

        Coordinates: ``B`` (θ1, θ2), ``M`` θ, ``U`` θ2. Shape (ndof⁺, ndof⁻).
        """
        lpre = self.levers(pre, th1, th2)
        lpost = self.levers(post, th1, th2)
        if not lpost:
            return np.zeros((0, len(lpre)))
        mp = self._metric(lpost, lpost)
        nn = self._metric(lpost, lpre)
        return np.linalg.solve(mp, nn)

    @staticmethod
    def coords(pattern: Pattern | str, w1: float, w2: float) -> np.ndarray:
        """Generalised velocities of ``pattern`` from absolute rates (θ̇1, θ̇2)."""
        k = parse_pattern(pattern).kind
        return {"R": np.zeros(0), "M": np.array([w1]), "U": np.array([w2]),
                "B": np.array([w1, w2])}[k]

    @staticmethod
    def absolute(pattern: Pattern | str, q: Sequence[float]) -> tuple[float, float]:
        """Absolute rates (θ̇1, θ̇2) from the generalised velocities of ``pattern``."""
        k = parse_pattern(pattern).kind
        if k == "R":
            return 0.0, 0.0
        if k == "M":
            return float(q[0]), float(q[0])
        if k == "U":
            return 0.0, float(q[0])
        return float(q[0]), float(q[1])

    def map_velocities(
        self, pre: Pattern | str, post: Pattern | str, th1: float, th2: float,
        w1: float, w2: float,
    ) -> tuple[float, float]:
        """Absolute post-impact rates of ``post`` from absolute pre-impact rates of ``pre``."""
        pmat = self.impact_map(pre, post, th1, th2)
        return self.absolute(post, pmat @ self.coords(pre, w1, w2))

    def kinetic_energy(
        self, pattern: Pattern | str, th1: float, th2: float, w1: float, w2: float
    ) -> float:
        """Kinetic energy ½ q̇ᵀ M q̇ of ``pattern`` at a configuration (J)."""
        lv = self.levers(pattern, th1, th2)
        if not lv:
            return 0.0
        q = self.coords(pattern, w1, w2)
        return float(0.5 * q @ self._metric(lv, lv) @ q)

    def impact_outcome(
        self, pre: Pattern | str, kind: str, th1: float, th2: float, w1: float, w2: float,
        *, legacy: bool = False, w_rest: float = 0.0,
    ) -> tuple[Pattern, float, float]:
        """Post-impact pattern and absolute rates by candidate enumeration (§3.5, §5.5).

        Parameters
        ----------
        pre : Pattern or str
            Pattern before the impact.
        kind : {"base", "interface"}
            Which gap closed (θ1 → 0 or φ → 0); the configuration must have that
            gap at zero.
        th1, th2, w1, w2 : float
            Configuration and absolute pre-impact rates.
        legacy : bool
            Simplified rule: ``M`` base impacts always give ``M(−s)``, ``U``
            interface impacts always ``U(−s2)``.
        w_rest : float
            Arrest threshold: if the impacting contact's post-impact gap rate is
            below it, that contact is closed instead (velocities from §3.4).

        Returns
        -------
        pattern : Pattern
        w1, w2 : float
            Absolute post-impact rates.
        """
        p = parse_pattern(pre)
        if kind not in ("base", "interface"):
            raise ValueError(f"impact kind must be 'base' or 'interface', got {kind!r}")
        ib = kind == "base"
        old = p.base if ib else p.iface
        if old == 0:
            raise ValueError(f"pattern {p.name} has no open {kind} contact to impact")
        other_closed = (p.iface if ib else p.base) == 0
        opts_k = [-old, 0]
        opts_o = [1, -1, 0] if other_closed else [p.iface if ib else p.base]
        if legacy and other_closed:
            opts_k, opts_o = [-old], [0]

        def mk(k: int, o: int) -> Pattern:
            return Pattern(k, o) if ib else Pattern(o, k)

        cache: dict[Pattern, tuple[float, float]] = {}

        def vel(c: Pattern) -> tuple[float, float]:
            if c not in cache:
                cache[c] = self.map_velocities(p, c, th1, th2, w1, w2)
            return cache[c]

        def rate(c: Pattern, base: bool) -> float:
            a1, a2 = vel(c)
            return a1 if base else a2 - a1

        best: Pattern | None = None
        best_v = math.inf
        for k in opts_k:
            for o in opts_o:
                c = mk(k, o)
                viol = 0.0
                # zero-gap contacts: the impacting one (ib) and, if it was closed, the other
                zero = [(ib, k, True)] + ([(not ib, o, False)] if other_closed else [])
                for is_base, st, impacting in zero:
                    if st != 0:
                        viol = max(viol, -st * rate(c, is_base))
                    else:
                        for sg in (1, -1):
                            if impacting and sg == old:
                                continue
                            c2 = Pattern(sg, c.iface) if is_base else Pattern(c.base, sg)
                            viol = max(viol, sg * rate(c2, is_base))
                if viol < best_v:
                    best, best_v = c, viol
        assert best is not None
        out = best
        if w_rest > 0:
            # §5.5 arrest: a zero-gap contact (the impacting one and, if it was closed, the
            # other) that would open slower than w_rest is closed instead; velocities of
            # the closed-contact pattern from the impact law. Repeated until nothing changes,
            # so that a micro-impact with all rates below w_rest ends at rest.
            zero_contacts = [ib] + ([not ib] if other_closed else [])
            for _ in range(2):
                changed = False
                for is_base in zero_contacts:
                    st = out.base if is_base else out.iface
                    if st != 0 and abs(rate(out, is_base)) < w_rest:
                        out = Pattern(0, out.iface) if is_base else Pattern(out.base, 0)
                        changed = True
                if not changed:
                    break
        a1, a2 = vel(out)
        return out, a1, a2
