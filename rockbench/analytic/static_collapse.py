"""Limit analysis of planar rigid-block assemblies: collapse load factor and mechanism.

The reference for quasi-static collapse (tilting table, pulse-to-collapse at low
frequency): the smallest horizontal acceleration, as a fraction α of g, that
starts a mechanism in an :class:`~rockbench.geometry.Geometry`.

Model
-----
Rigid blocks; joints (the interfaces found by the assembly) carry no tension,
have infinite compressive strength and Coulomb friction ``|t| ≤ μ n`` (``μ =
inf``: no sliding). The loads are the weights ``m g`` (−z) plus ``α m g`` along
``direction · x̂`` at each block's centre of gravity: the inertial forces of a
base acceleration ``−direction · α g``. Since a positive base acceleration
tips a resting block to θ < 0, ``direction = −1`` is the case of a positive
base acceleration. The analysis is first order: geometry is that at rest.

Each interface carries a normal force ``N ≥ 0`` and a shear ``T`` at each of
the two end points of its segment; any statically admissible stress
distribution over a straight joint is such a pair (the resultant lies in the
segment), which is why two points are exact.

*Static (lower-bound) LP*: maximise α subject to equilibrium of every block,
``N ≥ 0`` and ``|T| ≤ μ N``.

*Kinematic (upper-bound) LP*, its dual: per-block virtual velocities
``q = (u_x, u_z, ω)`` with unit power of the horizontal loads; minimise the
power spent against gravity, subject to kinematic admissibility at every
contact point: the relative velocity of body b with respect to body a has an
opening ``δ_n ≥ μ |δ_t|`` (``δ_t = 0`` when μ = inf). That is the
*associative* flow rule: sliding comes with a dilatancy angle equal to the
friction angle. With it the static and kinematic problems are dual linear
programmes and their optima coincide (the static and kinematic theorems of
limit analysis, which hold for associative materials): :class:`LimitResult`
carries both and they agree to the solver's tolerance.

Real Coulomb friction is *non-associative* (a sliding joint does not dilate);
the collapse load is then the solution of a complementarity problem, not an
LP, and may be *lower* than the associative value: the associative solution
is an upper bound (Drucker 1954, "Coulomb friction, plasticity, and limit
loads", J. Appl. Mech. 21:71–74; Ferris & Tin-Loi 2001, Int. J. Mech. Sci.
43:209–224; Gilbert, Casapulla & Ahmed 2006, Comput. Struct. 84:873–887).
The associative LP is exact where no joint slides (pure rocking: μ does not
enter), and also where sliding joints are pressed only by the weight of what
slides on them with nothing to hold them back (a block or a rigid sub-stack
sliding on its base: α = μ either way). It overestimates when a sliding
joint's dilatancy does work against other blocks, e.g. a voussoir slipping
inside an arch or a block sliding while its neighbours rotate ("mixed"
mechanisms), and where the optimum leans on friction at joints pressed only
by a self-equilibrated prestress that nothing in a dry-stacked assembly
creates: the head (vertical) joints of a running-bond wall. Their cone
δ_n ≥ μ |δ_t| also forbids a head joint to open while its sides move along it,
which is how a stepped wedge of the wall turns out of it. A 6 × 3 wall of
0.24 × 0.12 m bricks (μ = 1) has the associative factor 0.992; its wedge of
nine bricks above the first course turns about the course's leeward corner at
11/19 = 0.579 (virtual work: Σ m (x_pivot − x) / Σ m (z − z_pivot)), which
pymunk and MuJoCo find on the tilting table.

``flow="non-associative"`` solves real Coulomb joints by the iterative LP of
Gilbert, Casapulla & Ahmed (2006): each joint point gets the fixed shear
strength μ N of the previous iterate (a non-dilatant, Tresca-like joint,
whose flow is δ_n ≥ 0 with slip dissipating μ N |δ_t|), the static LP is
solved again, and N is relaxed toward its new value until α is stationary
and the forces satisfy |T| ≤ μ N themselves. The result is an equilibrium
of Coulomb joints (so α ≤ the associative factor) with a mechanism whose
joints either stay closed, slip without dilating, or open: a collapse state
of the non-associative problem. It is not proven to be the smallest one
(the problem is non-convex), and it equals the associative factor wherever
that is exact (every rocking mechanism here: one iteration).

Where sliding governs: a single block of half-width b and half-height h
rocks at α = b/h and slides at α = μ, so slender blocks (b/h < μ: columns,
drums, parapets) rock and squat blocks on a low-friction joint (μ < b/h)
slide. For assemblies the LP decides and :attr:`LimitResult.governing_mode`
says which.

The static solution is a vertex of the LP: for a statically indeterminate
assembly the interface forces it reports are one admissible distribution at
collapse, not *the* distribution (limit analysis does not determine it).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

import numpy as np
from scipy import sparse
from scipy.optimize import OptimizeResult, linprog

from rockbench.errors import ScenarioError
from rockbench.geometry import Geometry

__all__ = [
    "BlockMotion",
    "InterfaceForce",
    "InterfaceMotion",
    "LimitResult",
    "limit_analysis",
    "minimum_stable",
    "stands",
]

Status = Literal["collapse", "unstable", "no_mechanism"]
Flow = Literal["associative", "non-associative"]
Mode = Literal["rocking", "sliding", "mixed"]
MotionKind = Literal["rest", "rotation", "translation"]
JointKind = Literal["closed", "hinge", "lift", "slide", "slide-rotate"]

#: Relative tolerance of the mechanism classification (velocities normalised to 1).
CLASSIFY_TOL = 1e-6
#: HiGHS feasibility tolerances; forces are in units of the total weight, so 1e-10
#: keeps α and the equilibrium residuals at ~1e-10 (the default 1e-7 shows in tilt angles).
_HIGHS = {"primal_feasibility_tolerance": 1e-10, "dual_feasibility_tolerance": 1e-10}
#: Non-associative iteration: the new normal forces enter the next shear strengths with
#: this weight (the undamped update oscillates on the running-bond walls; 0.5 settles
#: the 6 × 3 wall in 90 iterations, the 10 × 3 one in 53).
RELAXATION = 0.5
#: Iterations allowed before the non-associative solution is declared unconverged.
MAX_ITERATIONS = 1000
#: The iteration's α is stationary when it changes by less than this.
ITERATION_TOL = 1e-9


@dataclass(frozen=True, eq=False)
class BlockMotion:
    """What one block does in the collapse mechanism.

    Attributes
    ----------
    block : int
        Block index.
    velocity : ndarray (3,)
        Virtual velocity (u_x, u_z, ω) of its centre of gravity (m/s, m/s,
        rad/s), normalised so that the fastest point of any block moves at 1.
        ω is about +y: ω > 0 turns the block's top toward +x.
    kind : {"rest", "rotation", "translation"}
    centre : ndarray (2,) or None
        Instantaneous centre of rotation (x, z) for a rotation.
    pivot : int or None
        Index of the block's own vertex at the centre, if there is one (the
        block rocks on that corner).
    """

    block: int
    velocity: np.ndarray
    kind: MotionKind
    centre: np.ndarray | None
    pivot: int | None

    @property
    def rotation_sign(self) -> int:
        """+1 if the block turns toward +x (θ̇ > 0), −1 toward −x, 0 if it does not turn."""
        if self.kind != "rotation":
            return 0
        return 1 if self.velocity[2] > 0 else -1


@dataclass(frozen=True, eq=False)
class InterfaceMotion:
    """Relative motion at one interface in the collapse mechanism.

    Attributes
    ----------
    interface : int
        Index into ``Geometry.interfaces``.
    opening, slip : ndarray (2,)
        Relative velocity of body b with respect to body a at the end points
        p0, p1, along the interface normal (opening > 0) and tangent.
    kind : {"closed", "hinge", "lift", "slide", "slide-rotate"}
        ``hinge``: relative rotation about one end point; ``lift``: both ends
        open without slip; ``slide``: slip without relative rotation;
        ``slide-rotate``: both.
    """

    interface: int
    opening: np.ndarray
    slip: np.ndarray
    kind: JointKind

    @property
    def slides(self) -> bool:
        """True if the joint slips."""
        return self.kind in ("slide", "slide-rotate")


@dataclass(frozen=True, eq=False)
class InterfaceForce:
    """Contact forces of one interface at collapse (the static LP's solution).

    Attributes
    ----------
    interface : int
        Index into ``Geometry.interfaces``.
    normal : ndarray (2,)
        Compressive normal force at the end points p0, p1 (N), ≥ 0.
    shear : ndarray (2,)
        Tangential force at p0, p1 on body b, along the interface tangent (N).
    """

    interface: int
    normal: np.ndarray
    shear: np.ndarray

    @property
    def resultant(self) -> tuple[float, float]:
        """Total normal and shear force (N)."""
        return float(self.normal.sum()), float(self.shear.sum())

    def centre_of_pressure(self, p0: np.ndarray, p1: np.ndarray) -> np.ndarray | None:
        """Where the normal resultant acts on the segment p0–p1 (the thrust line), or None."""
        n = float(self.normal.sum())
        if n <= 0:
            return None
        return (self.normal[0] * np.asarray(p0) + self.normal[1] * np.asarray(p1)) / n


@dataclass(frozen=True, eq=False)
class LimitResult:
    """Collapse load factor and mechanism of an assembly.

    Attributes
    ----------
    status : {"collapse", "unstable", "no_mechanism"}
        ``collapse``: the assembly stands under its weight and collapses at
        α = :attr:`load_factor`; ``unstable``: it cannot stand under its weight
        alone (:attr:`load_factor` is then the largest α whose loads the joints
        could balance, NaN if there is none: a push is needed to hold it);
        ``no_mechanism``: no admissible mechanism does positive work under the
        horizontal loads (α = inf).
    load_factor : float
        Static (lower-bound) α: collapse at a horizontal acceleration α g.
    kinematic_load_factor : float
        Kinematic α of the mechanism; equal to ``load_factor`` to the LP
        tolerance (duality; for non-associative flow, of the last iteration's
        LP), NaN unless ``status == "collapse"``.
    direction : int
        +1: horizontal loads toward +x (base acceleration toward −x); −1 the reverse.
    friction : float
        Coulomb μ at every joint (inf: no sliding).
    mechanism : tuple of BlockMotion
        One per block (empty unless ``status == "collapse"``).
    joints : tuple of InterfaceMotion
        One per interface (empty unless ``status == "collapse"``).
    governing_mode : {"rocking", "sliding", "mixed"} or None
        ``rocking``: no joint slips; ``sliding``: joints slip and no block
        rotates; ``mixed``: both.
    interface_forces : tuple of InterfaceForce
        One per interface, at collapse (one admissible distribution); for an
        ``unstable`` assembly, at the largest α the joints could balance.
    flow : {"associative", "non-associative"}
        The joints' flow rule (see the module docstring).
    iterations : int
        Static LPs of the non-associative iteration (0 for associative flow).
    """

    status: Status
    load_factor: float
    kinematic_load_factor: float
    direction: int
    friction: float
    mechanism: tuple[BlockMotion, ...]
    joints: tuple[InterfaceMotion, ...]
    governing_mode: Mode | None
    interface_forces: tuple[InterfaceForce, ...]
    flow: Flow = "associative"
    iterations: int = 0

    @property
    def tilt_angle(self) -> float:
        """atan(α) (rad): the tilting-table angle at which the assembly collapses."""
        return math.atan(self.load_factor)

    @property
    def moving_blocks(self) -> tuple[int, ...]:
        """Indices of the blocks that move in the mechanism."""
        return tuple(m.block for m in self.mechanism if m.kind != "rest")


@dataclass(frozen=True)
class _System:
    """The LP data of an assembly, in units of total weight and assembly size."""

    h_n: sparse.csr_matrix  # (3 nb, np) generalised force of a unit normal force
    h_t: sparse.csr_matrix  # (3 nb, np) ... of a unit tangential force
    dead: np.ndarray  # (3 nb,) weights / total weight
    live: np.ndarray  # (3 nb,) horizontal loads / (α · total weight)
    weight: float  # total weight (N)
    length: float  # length scale L (m): moments are divided by it


def _system(assembly: Geometry, direction: int, g: float) -> _System:
    nb = assembly.n_bodies
    length = assembly.size
    masses = assembly.masses
    centroids = assembly.centroids
    total = float(masses.sum())
    rows: list[int] = []
    cols: list[int] = []
    vn: list[float] = []
    vt: list[float] = []
    for k, itf in enumerate(assembly.interfaces):
        n, t = itf.normal, itf.tangent
        for e, p in enumerate((itf.p0, itf.p1)):
            j = 2 * k + e
            for body, sign in ((itf.a, -1.0), (itf.b, 1.0)):
                if assembly.is_fixed(body):
                    continue
                r = (p - centroids[body]) / length
                rows += [3 * body, 3 * body + 1, 3 * body + 2]
                cols += [j, j, j]
                # moment about +y of a force f at r: r_z f_x − r_x f_z
                vn += [sign * n[0], sign * n[1], sign * (r[1] * n[0] - r[0] * n[1])]
                vt += [sign * t[0], sign * t[1], sign * (r[1] * t[0] - r[0] * t[1])]
    shape = (3 * nb, 2 * len(assembly.interfaces))
    h_n = sparse.csr_matrix((vn, (rows, cols)), shape=shape)
    h_t = sparse.csr_matrix((vt, (rows, cols)), shape=shape)
    dead = np.zeros(3 * nb)
    live = np.zeros(3 * nb)
    dead[1::3] = -masses / total
    live[0::3] = direction * masses / total
    return _System(h_n, h_t, dead, live, total * g, length)


def _check_inputs(friction: float, direction: int, g: float) -> float:
    mu = float(friction)
    if math.isnan(mu) or mu < 0:
        raise ScenarioError(f"friction must be >= 0 (or inf for no sliding), got {friction!r}")
    if direction not in (1, -1):
        raise ScenarioError(f"direction must be +1 or -1, got {direction!r}")
    if not (math.isfinite(g) and g > 0):
        raise ScenarioError(f"g must be finite and > 0, got {g!r}")
    return mu


def _solved(res: OptimizeResult, which: str) -> None:
    """Accept optimal, infeasible and unbounded outcomes; anything else is a solver failure."""
    if res.status not in (0, 2, 3):
        raise RuntimeError(f"{which} LP: HiGHS did not conclude (status {res.status}: "
                           f"{res.message})")


def _static(sys: _System, mu: float, alpha: float | None) -> tuple[int, np.ndarray | None]:
    """Static LP over x = (N, T[, α]); maximise α, or only check feasibility at a fixed α."""
    npt = sys.h_n.shape[1]
    free_alpha = alpha is None
    blocks = [sys.h_n, sys.h_t] + ([sparse.csr_matrix(sys.live[:, None])] if free_alpha else [])
    a_eq = sparse.hstack(blocks, format="csr")
    b_eq = -sys.dead - (0.0 if free_alpha else alpha * sys.live)
    nvar = 2 * npt + free_alpha
    c = np.zeros(nvar)
    if free_alpha:
        c[-1] = -1.0
    bounds = [(0.0, None)] * npt + [(None, None)] * (npt + free_alpha)
    a_ub = b_ub = None
    if math.isfinite(mu) and npt:
        eye = sparse.identity(npt, format="csr")
        zero = sparse.csr_matrix((npt, nvar - 2 * npt))
        a_ub = sparse.vstack([sparse.hstack([-mu * eye, eye, zero]),
                              sparse.hstack([-mu * eye, -eye, zero])], format="csr")
        b_ub = np.zeros(2 * npt)
    res = linprog(c, A_ub=a_ub, b_ub=b_ub, A_eq=a_eq, b_eq=b_eq, bounds=bounds, method="highs",
                  options=_HIGHS)
    _solved(res, "static")
    return res.status, (res.x if res.status == 0 else None)


def _kinematic(sys: _System, mu: float) -> tuple[int, float, np.ndarray | None]:
    """Kinematic LP over q (3 per block): minimise the power against gravity, unit live power."""
    nq = sys.h_n.shape[0]
    dn, dt = sys.h_n.T.tocsr(), sys.h_t.T.tocsr()
    a_eq = sparse.csr_matrix(sys.live[None, :])
    b_eq = [1.0]
    if math.isfinite(mu):
        a_ub = sparse.vstack([-dn + mu * dt, -dn - mu * dt], format="csr")
    else:
        a_ub = -dn
        a_eq = sparse.vstack([a_eq, dt], format="csr")
        b_eq = b_eq + [0.0] * dt.shape[0]
    res = linprog(-sys.dead, A_ub=a_ub, b_ub=np.zeros(a_ub.shape[0]), A_eq=a_eq,
                  b_eq=np.array(b_eq), bounds=[(None, None)] * nq, method="highs",
                  options=_HIGHS)
    _solved(res, "kinematic")
    if res.status != 0:
        return res.status, math.nan, None
    return 0, float(res.fun), res.x


def _static_capped(sys: _System, cap: np.ndarray) -> np.ndarray | None:
    """Static LP with a fixed shear strength ``|T| ≤ cap`` per point; maximise α."""
    npt = sys.h_n.shape[1]
    a_eq = sparse.hstack([sys.h_n, sys.h_t, sparse.csr_matrix(sys.live[:, None])], format="csr")
    c = np.zeros(2 * npt + 1)
    c[-1] = -1.0
    bounds = [(0.0, None)] * npt + [(-float(k), float(k)) for k in cap] + [(None, None)]
    res = linprog(c, A_eq=a_eq, b_eq=-sys.dead, bounds=bounds, method="highs", options=_HIGHS)
    _solved(res, "static (non-associative)")
    return res.x if res.status == 0 else None


def _kinematic_capped(sys: _System, cap: np.ndarray) -> tuple[float, np.ndarray | None]:
    """Dual of :func:`_static_capped`: δ_n ≥ 0, slip dissipating cap · |δ_t|, unit live power."""
    nq, npt = sys.h_n.shape
    dn, dt = sys.h_n.T.tocsr(), sys.h_t.T.tocsr()
    eye = sparse.identity(npt, format="csr")
    zero = sparse.csr_matrix((npt, npt))
    # variables (q, s) with s ≥ |δ_t|
    a_ub = sparse.vstack([sparse.hstack([-dn, zero]), sparse.hstack([dt, -eye]),
                          sparse.hstack([-dt, -eye])], format="csr")
    a_eq = sparse.hstack([sparse.csr_matrix(sys.live[None, :]), sparse.csr_matrix((1, npt))],
                         format="csr")
    res = linprog(np.concatenate([-sys.dead, cap]), A_ub=a_ub, b_ub=np.zeros(3 * npt),
                  A_eq=a_eq, b_eq=[1.0], bounds=[(None, None)] * nq + [(0.0, None)] * npt,
                  method="highs", options=_HIGHS)
    _solved(res, "kinematic (non-associative)")
    if res.status != 0:
        return math.nan, None
    return float(res.fun), res.x[:nq]


def _consistent(sys: _System, mu: float, alpha: float, q: np.ndarray) -> np.ndarray | None:
    """Coulomb forces in equilibrium at ``alpha`` that the mechanism ``q`` is consistent with.

    Complementarity of real (non-dilatant) Coulomb joints: no force where a
    point opens, |T| = μ N against the slip where a closed point slips,
    |T| ≤ μ N where it sticks. None if there are none (``q`` is then no
    collapse mechanism of Coulomb joints at ``alpha``).
    """
    nq, npt = sys.h_n.shape
    opening, slip = sys.h_n.T @ q, sys.h_t.T @ q
    scale = float(max(np.abs(opening).max(), np.abs(slip).max()))
    tol = CLASSIFY_TOL * scale
    a_eq = sparse.hstack([sys.h_n, sys.h_t], format="csr")
    b_eq = -sys.dead - alpha * sys.live
    eye = sparse.identity(npt, format="csr")
    # |T| ≤ μ N everywhere; at a slipping closed point also −sign(slip) T ≥ μ N
    sign = np.where(np.abs(slip) > tol, np.sign(slip), 0.0)
    sliding = (sign != 0) & (opening <= tol)
    pick = sparse.diags(sliding.astype(float))
    a_ub = sparse.vstack([sparse.hstack([-mu * eye, eye]), sparse.hstack([-mu * eye, -eye]),
                          sparse.hstack([mu * pick, pick @ sparse.diags(sign)])], format="csr")
    bounds = [(0.0, 0.0) if o > tol else (0.0, None) for o in opening] + [(None, None)] * npt
    res = linprog(np.zeros(2 * npt), A_ub=a_ub, b_ub=np.zeros(3 * npt), A_eq=a_eq, b_eq=b_eq,
                  bounds=bounds, method="highs", options=_HIGHS)
    _solved(res, "consistency")
    return np.append(res.x, alpha) if res.status == 0 else None


def _non_associative(sys: _System, mu: float, x: np.ndarray
                     ) -> tuple[np.ndarray, float, np.ndarray, int]:
    """Gilbert, Casapulla & Ahmed's iteration from the associative solution ``x``.

    Once α is stationary, the mechanism of the last LP and Coulomb forces
    consistent with it (:func:`_consistent`) certify a collapse state of the
    non-associative problem. Returns those forces (with α), the mechanism's
    kinematic factor and velocities, and the number of static LPs solved.
    """
    npt = sys.h_n.shape[1]
    normal = x[:npt].copy()
    alpha = float(x[-1])
    for k in range(1, MAX_ITERATIONS + 1):
        cap = mu * normal
        new = _static_capped(sys, cap)
        if new is None:
            raise RuntimeError(f"non-associative iteration {k}: the joints' shear strengths "
                               "balance no load")
        stationary = abs(new[-1] - alpha) <= ITERATION_TOL
        alpha = float(new[-1])
        if stationary:
            alpha_k, q = _kinematic_capped(sys, cap)
            forces = None if q is None else _consistent(sys, mu, alpha, q)
            if forces is not None and q is not None:
                return forces, alpha_k, q, k
        # the LP's forces jump between vertices of equal α: relax toward them
        normal = RELAXATION * new[:npt] + (1.0 - RELAXATION) * normal
    raise RuntimeError(f"non-associative iteration did not converge in {MAX_ITERATIONS} LPs "
                       f"(last α = {alpha:.9g})")


def _classify(assembly: Geometry, sys: _System, q: np.ndarray,
              normal: np.ndarray | None = None
              ) -> tuple[tuple[BlockMotion, ...], tuple[InterfaceMotion, ...], Mode]:
    """Block motions, joint kinds and governing mode of the mechanism ``q``.

    With associative flow (``normal`` None) a slipping point also opens, so
    any slip is sliding. With non-associative flow a point slides only if it
    slips while closed and pressed (``normal``: its force, units of the total
    weight); one that opens, or grazes unpressed, while its sides move along
    the joint separates.
    """
    vel = q.reshape(-1, 3).copy()
    vel[:, 2] /= sys.length  # back to rad/s
    speeds = []
    cents = assembly.centroids
    verts = [assembly.world_vertices(i) for i in range(assembly.n_bodies)]
    for v, c, (ux, uz, w) in zip(verts, cents, vel, strict=True):
        d = v - c
        speeds.append(float(np.hypot(ux + w * d[:, 1], uz - w * d[:, 0]).max()))
    vmax = max(speeds)
    vel /= vmax
    tol = CLASSIFY_TOL
    motions = []
    for i, v in enumerate(verts):
        ux, uz, w = vel[i]
        size = float(np.ptp(v, axis=0).max())
        if speeds[i] / vmax < tol:
            motions.append(BlockMotion(i, vel[i], "rest", None, None))
        elif abs(w) * size < tol:
            motions.append(BlockMotion(i, vel[i], "translation", None, None))
        else:
            centre = cents[i] + np.array([uz / w, -ux / w])
            dist = np.hypot(*(v - centre).T)
            pivot = int(np.argmin(dist)) if dist.min() < tol * size else None
            motions.append(BlockMotion(i, vel[i], "rotation", centre, pivot))
    qn = q / vmax
    opening = (sys.h_n.T @ qn).reshape(-1, 2)
    slip = (sys.h_t.T @ qn).reshape(-1, 2)
    joints = []
    omega = np.append(vel[:, 2], np.zeros(len(assembly.fixed)))
    for k, itf in enumerate(assembly.interfaces):
        o, s = opening[k], slip[k]
        slipping = np.abs(s) > tol
        if normal is not None:
            slipping &= (o <= tol) & (normal[2 * k:2 * k + 2] > tol)
        slips = bool(slipping.any())
        turns = abs(omega[itf.b] - omega[itf.a]) * itf.length > tol
        kind: JointKind
        if max(np.abs(o).max(), np.abs(s).max()) <= tol:
            kind = "closed"
        elif slips:
            kind = "slide-rotate" if turns else "slide"
        elif turns and o.min() <= tol:
            kind = "hinge"
        else:
            kind = "lift"
        joints.append(InterfaceMotion(k, o, s, kind))
    mode: Mode = "rocking"
    if any(j.slides for j in joints):
        rotating = any(m.kind == "rotation" for m in motions)
        mode = "mixed" if rotating else "sliding"
    return tuple(motions), tuple(joints), mode


def _forces(sys: _System, x: np.ndarray, n_itf: int) -> tuple[InterfaceForce, ...]:
    npt = 2 * n_itf
    nn = x[:npt].reshape(-1, 2) * sys.weight
    tt = x[npt:2 * npt].reshape(-1, 2) * sys.weight
    return tuple(InterfaceForce(k, nn[k], tt[k]) for k in range(n_itf))


def limit_analysis(assembly: Geometry, *, friction: float = math.inf, direction: int = 1,
                   g: float = 9.81, flow: Flow = "associative") -> LimitResult:
    """Collapse load factor and mechanism of ``assembly`` under horizontal inertial loads.

    Parameters
    ----------
    assembly : Geometry
        Blocks, supports and their interfaces.
    friction : float
        Coulomb μ of every joint; ``math.inf`` for no sliding.
    direction : {+1, -1}
        Sense of the horizontal loads ``α m g`` (+1 toward +x). A base
        acceleration toward +x loads the blocks toward −x (``direction=-1``).
    g : float
        Gravity (m/s²); α is dimensionless, the forces scale with g.
    flow : {"associative", "non-associative"}
        The joints' flow rule: associative (one LP pair, dilatant slip) or
        real Coulomb joints (the iteration of the module docstring, which
        needs a finite μ). Whether the assembly stands and whether it has a
        mechanism at all are decided by the associative LP either way.

    Returns
    -------
    LimitResult
        Static and kinematic factors (equal to the LP tolerance), the
        normalised mechanism with its classification, and the interface
        forces at collapse.

    Raises
    ------
    ScenarioError
        (a ValueError) friction < 0, direction not ±1, g not > 0, an unknown
        flow, or non-associative flow without finite friction.
    """
    mu = _check_inputs(friction, direction, g)
    if flow not in ("associative", "non-associative"):
        raise ScenarioError(f"flow must be 'associative' or 'non-associative', got {flow!r}")
    if flow == "non-associative" and not math.isfinite(mu):
        raise ScenarioError("non-associative flow needs a finite friction (inf is the "
                            "associative no-sliding limit)")
    sys = _system(assembly, direction, g)
    n_itf = len(assembly.interfaces)
    status, x = _static(sys, mu, None)
    if status == 3:
        return LimitResult("no_mechanism", math.inf, math.nan, direction, mu, (), (), None, ())
    if x is None or (x[-1] < 0 or _static(sys, mu, 0.0)[0] != 0):
        alpha = math.nan if x is None else float(x[-1])
        forces = () if x is None else _forces(sys, x, n_itf)
        return LimitResult("unstable", alpha, math.nan, direction, mu, (), (), None, forces)
    q: np.ndarray | None
    if flow == "non-associative":
        x, alpha_k, q, iterations = _non_associative(sys, mu, x)
    else:
        iterations = 0
        _, alpha_k, q = _kinematic(sys, mu)
    if q is None:
        raise RuntimeError(f"kinematic LP failed although the static LP found "
                           f"α = {x[-1]:.6g}")
    pressed = x[:2 * n_itf] if flow == "non-associative" else None
    motions, joints, mode = _classify(assembly, sys, q, pressed)
    return LimitResult("collapse", float(x[-1]), alpha_k, direction, mu, motions, joints, mode,
                       _forces(sys, x, n_itf), flow, iterations)


def stands(assembly: Geometry, *, friction: float = math.inf, g: float = 9.81) -> bool:
    """True if ``assembly`` can be in equilibrium under its own weight alone.

    The static LP's feasibility at α = 0: there are compressive, frictionally
    admissible interface forces that balance every block's weight.
    """
    mu = _check_inputs(friction, 1, g)
    return _static(_system(assembly, 1, g), mu, 0.0)[0] == 0


def minimum_stable(build: Callable[[float], Geometry], lo: float, hi: float, *,
                   friction: float = math.inf, xtol: float = 1e-7) -> float:
    """Smallest parameter for which ``build(parameter)`` stands under its own weight.

    Bisection on the static LP's feasibility (:func:`stands`), assuming the
    assembly stands for every parameter above the threshold and for none below
    (e.g. the thickness of an arch).

    Parameters
    ----------
    build : callable
        Parameter → Geometry.
    lo, hi : float
        Bracket: ``build(lo)`` must not stand and ``build(hi)`` must.
    friction : float
        Coulomb μ (inf: no sliding).
    xtol : float
        Absolute tolerance on the parameter.

    Raises
    ------
    ScenarioError
        (a ValueError) the bracket does not bracket the threshold.
    """
    if stands(build(lo), friction=friction):
        raise ScenarioError(f"minimum_stable: the assembly already stands at lo = {lo!r}")
    if not stands(build(hi), friction=friction):
        raise ScenarioError(f"minimum_stable: the assembly does not stand at hi = {hi!r}")
    while hi - lo > xtol:
        mid = 0.5 * (lo + hi)
        if stands(build(mid), friction=friction):
            hi = mid
        else:
            lo = mid
    return 0.5 * (lo + hi)
