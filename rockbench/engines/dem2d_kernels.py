"""Compiled inner loop of the ``dem2d`` engine (Distinct Element Method, planar rigid blocks).

The functions are plain Python over NumPy arrays and scalars; when numba is installed
they are compiled with :func:`numba.njit` (``cache=True``: the few seconds of compilation
are paid once per machine, not once per process). Without numba the same code runs
interpreted, with identical results, about three orders of magnitude slower
(``HAVE_NUMBA`` tells which). :class:`~rockbench.engines.dem2d_engine.Dem2dEngine`
builds the arrays and calls :func:`advance`.

One time step is 3DEC's cycle in the x–z plane. Bodies are convex polygons; body
``nbody − 1`` is the kinematic base, and the bodies before it with zero inverse mass
(an assembly's fixed supports) translate with it. The contact of a candidate pair is
the pair of facing edges closest to anti-parallel (within 45°) with a non-empty
overlap, bounded by the vertices of either edge (the rocking pivots) and penetrating by
less than a tenth of the shorter edge. ``nsub`` sub-contacts are spread over the
overlap, ends included, with trapezoidal tributary lengths times the smaller depth of
the two bodies as areas. At each sub-contact, with the gap g along the outward normal
(negative: overlap) and the relative velocity (v_n, v_t) there:

* normal force  F_n = max(0, −k_n A g − β k_n A v_n)   (no tension; β of the pair),
* shear force   F_s += −k_s A v_t Δt, |F_s| ≤ μ F_n (Mohr–Coulomb, μ of the pair),
  plus the dashpot −β k_s A v_t while it sticks.

A sub-contact that opens, or whose edge pair changes, forgets its shear force. Forces
act at the mid-point of the overlap on both bodies (angular momentum conserved).
Motion is central differences, v(t + Δt/2) = v(t − Δt/2) + a(t) Δt and
x(t + Δt) = x(t) + v(t + Δt/2) Δt, the forces at t from positions at t and velocities
at t − Δt/2 (so the shear increment is the relative displacement of the last step).

Sign conventions: θ is the rotation about +y (top toward +x positive); a body vector
(r_x, r_z) is (r_x c + r_z s, −r_x s + r_z c) in the world; the velocity of a point at
arm r is ω (r_z, −r_x) and a force F at r gives the moment r_z F_x − r_x F_z.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

try:  # numba is an optional extra: rockbench[dem]
    from numba import njit

    HAVE_NUMBA = True
except ImportError:  # pragma: no cover - depends on the environment
    HAVE_NUMBA = False

    def njit(*args: Any, **kwargs: Any) -> Any:  # type: ignore[no-redef]  # numba absent
        """Identity decorator standing in for numba.njit."""
        if len(args) == 1 and callable(args[0]) and not kwargs:
            return args[0]
        return lambda f: f


__all__ = ["HAVE_NUMBA", "advance", "sample", "world_geometry", "write_poses"]

#: Edges closer than this to anti-parallel may form a contact (cos 45°).
_COS_MAX = math.cos(math.radians(45.0)) - 1e-9
#: Deepest penetration of a contact, as a fraction of the shorter of its two edges
#: (penalty contacts penetrate by ~1e-5 of a block's size).
_MAX_DEPTH = 0.1


@njit(cache=True)
def world_geometry(pos: np.ndarray, lverts: np.ndarray, lnorm: np.ndarray, nverts: np.ndarray,
                   wverts: np.ndarray, wnorm: np.ndarray) -> None:
    """World vertices and outward edge normals of every body (in place)."""
    for b in range(pos.shape[0]):
        c = math.cos(pos[b, 2])
        s = math.sin(pos[b, 2])
        for k in range(nverts[b]):
            rx = lverts[b, k, 0]
            rz = lverts[b, k, 1]
            wverts[b, k, 0] = pos[b, 0] + rx * c + rz * s
            wverts[b, k, 1] = pos[b, 1] - rx * s + rz * c
            nx = lnorm[b, k, 0]
            nz = lnorm[b, k, 1]
            wnorm[b, k, 0] = nx * c + nz * s
            wnorm[b, k, 1] = -nx * s + nz * c


@njit(cache=True)
def write_poses(pos: np.ndarray, poses: np.ndarray) -> None:
    """Poses (x, y, z, q_w, q_x, q_y, q_z) of the first ``len(poses)`` bodies (in place).

    A rotation θ about +y is the quaternion (cos θ/2, 0, sin θ/2, 0); y, q_x and
    q_z are 0 (written too, so that ``poses`` may be any buffer, e.g. NaN-filled).
    """
    for b in range(poses.shape[0]):
        half = 0.5 * pos[b, 2]
        poses[b, 0] = pos[b, 0]
        poses[b, 1] = 0.0
        poses[b, 2] = pos[b, 1]
        poses[b, 3] = math.cos(half)
        poses[b, 4] = 0.0
        poses[b, 5] = math.sin(half)
        poses[b, 6] = 0.0


@njit(cache=True)
def _select_edges(i: int, j: int, pos: np.ndarray, wverts: np.ndarray, wnorm: np.ndarray,
                  nverts: np.ndarray, out: np.ndarray) -> int:
    """Best facing edge pair (a of i, b of j) with overlap and some penetration.

    Returns a·KMAX + b (−1 if none) and writes the overlap [s_lo, s_hi] along
    edge b's tangent into ``out[0:2]``.
    """
    best = -1
    best_dot = 2.0
    best_gap = math.inf
    kmax = wverts.shape[1]
    cix = pos[i, 0]
    ciz = pos[i, 1]
    cjx = pos[j, 0]
    cjz = pos[j, 1]
    for a in range(nverts[i]):
        nax = wnorm[i, a, 0]
        naz = wnorm[i, a, 1]
        a0x = wverts[i, a, 0]
        a0z = wverts[i, a, 1]
        a1 = a + 1 if a + 1 < nverts[i] else 0
        a1x = wverts[i, a1, 0]
        a1z = wverts[i, a1, 1]
        # j's centroid must lie in front of edge a
        if (cjx - a0x) * nax + (cjz - a0z) * naz <= 0.0:
            continue
        for b in range(nverts[j]):
            nbx = wnorm[j, b, 0]
            nbz = wnorm[j, b, 1]
            d = nax * nbx + naz * nbz
            if d > -_COS_MAX or d > best_dot + 1e-12:
                continue
            b0x = wverts[j, b, 0]
            b0z = wverts[j, b, 1]
            if (cix - b0x) * nbx + (ciz - b0z) * nbz <= 0.0:
                continue
            b1 = b + 1 if b + 1 < nverts[j] else 0
            tx = wverts[j, b1, 0] - b0x
            tz = wverts[j, b1, 1] - b0z
            lb = math.sqrt(tx * tx + tz * tz)
            tx /= lb
            tz /= lb
            sa0 = (a0x - b0x) * tx + (a0z - b0z) * tz
            sa1 = (a1x - b0x) * tx + (a1z - b0z) * tz
            s_lo = max(min(sa0, sa1), 0.0)
            s_hi = min(max(sa0, sa1), lb)
            if s_hi <= s_lo:
                continue
            # gaps at the overlap ends (linear in between): along n_b to edge a's line
            inv = 1.0 / d
            g_lo = ((a0x - b0x - s_lo * tx) * nax + (a0z - b0z - s_lo * tz) * naz) * inv
            g_hi = ((a0x - b0x - s_hi * tx) * nax + (a0z - b0z - s_hi * tz) * naz) * inv
            gmin = min(g_lo, g_hi)
            if gmin >= 0.0:
                continue
            # a face of a side neighbour lies "behind" this one by a whole block (a wall's
            # brick above the head joint of two below): no contact goes that deep
            la = math.sqrt((a1x - a0x) ** 2 + (a1z - a0z) ** 2)
            if gmin < -_MAX_DEPTH * min(la, lb):
                continue
            if d < best_dot - 1e-12 or gmin < best_gap:
                best = a * kmax + b
                best_dot = d
                best_gap = gmin
                out[0] = s_lo
                out[1] = s_hi
    return best


@njit(cache=True)
def _contact_forces(pos: np.ndarray, vel: np.ndarray, wverts: np.ndarray, wnorm: np.ndarray,
                    nverts: np.ndarray, radius: np.ndarray, pairs: np.ndarray,
                    pair_depth: np.ndarray, pair_edges: np.ndarray, shear: np.ndarray,
                    kn: float, ks: float, pair_mu: np.ndarray, pair_beta: np.ndarray, dt: float,
                    force: np.ndarray, scratch: np.ndarray) -> None:
    """Add every contact's force and moment to ``force`` (n_bodies, 3)."""
    kmax = wverts.shape[1]
    nsub = shear.shape[1]
    for p in range(pairs.shape[0]):
        i = pairs[p, 0]
        j = pairs[p, 1]
        dx = pos[i, 0] - pos[j, 0]
        dz = pos[i, 1] - pos[j, 1]
        rr = radius[i] + radius[j]
        sel = -1
        if dx * dx + dz * dz <= rr * rr:
            sel = _select_edges(i, j, pos, wverts, wnorm, nverts, scratch)
        if sel < 0:
            pair_edges[p] = -1
            for k in range(nsub):
                shear[p, k] = 0.0
            continue
        if sel != pair_edges[p]:  # another pair of faces: shear history does not carry over
            pair_edges[p] = sel
            for k in range(nsub):
                shear[p, k] = 0.0
        beta = pair_beta[p]
        mu = pair_mu[p]
        a = sel // kmax
        b = sel - a * kmax
        nax = wnorm[i, a, 0]
        naz = wnorm[i, a, 1]
        nx = wnorm[j, b, 0]
        nz = wnorm[j, b, 1]
        b0x = wverts[j, b, 0]
        b0z = wverts[j, b, 1]
        # tangent of edge b (counter-clockwise polygons: t = (−n_z, n_x))
        tx = -nz
        tz = nx
        a0x = wverts[i, a, 0]
        a0z = wverts[i, a, 1]
        inv = 1.0 / (nax * nx + naz * nz)
        s_lo = scratch[0]
        s_hi = scratch[1]
        h = (s_hi - s_lo) / (nsub - 1)
        area_unit = h * pair_depth[p]
        for k in range(nsub):
            s = s_lo + k * h
            px = b0x + s * tx
            pz = b0z + s * tz
            g = ((a0x - px) * nax + (a0z - pz) * naz) * inv
            if g >= 0.0:  # open: zero tension, shear history lost
                shear[p, k] = 0.0
                continue
            area = area_unit * (0.5 if (k == 0 or k == nsub - 1) else 1.0)
            # contact point: middle of the overlap along n_b
            mx = px + 0.5 * g * nx
            mz = pz + 0.5 * g * nz
            rix = mx - pos[i, 0]
            riz = mz - pos[i, 1]
            rjx = mx - pos[j, 0]
            rjz = mz - pos[j, 1]
            vx = (vel[i, 0] + vel[i, 2] * riz) - (vel[j, 0] + vel[j, 2] * rjz)
            vz = (vel[i, 1] - vel[i, 2] * rix) - (vel[j, 1] - vel[j, 2] * rjx)
            vn = vx * nx + vz * nz
            vt = vx * tx + vz * tz
            kna = kn * area
            fn_spring = -kna * g
            fn = fn_spring - beta * kna * vn
            if fn < 0.0:
                fn = 0.0
            ksa = ks * area
            fs = shear[p, k] - ksa * vt * dt
            limit = mu * fn_spring
            if abs(fs) >= limit:  # Mohr–Coulomb slip (no cohesion)
                fs = math.copysign(limit, fs)
                shear[p, k] = fs
            else:
                shear[p, k] = fs
                fs = fs - beta * ksa * vt
                if abs(fs) > mu * fn:
                    fs = math.copysign(mu * fn, fs)
            fx = fn * nx + fs * tx
            fz = fn * nz + fs * tz
            force[i, 0] += fx
            force[i, 1] += fz
            force[i, 2] += riz * fx - rix * fz
            force[j, 0] -= fx
            force[j, 1] -= fz
            force[j, 2] -= rjz * fx - rjx * fz


@njit(cache=True)
def _steps(n: int, dt: float, pos: np.ndarray, vel: np.ndarray, inv_m: np.ndarray,
           inv_i: np.ndarray, lverts: np.ndarray, lnorm: np.ndarray, nverts: np.ndarray,
           radius: np.ndarray, pairs: np.ndarray, pair_depth: np.ndarray,
           pair_edges: np.ndarray, shear: np.ndarray, kn: float, ks: float, pair_mu: np.ndarray,
           pair_beta: np.ndarray, g: float, base_u: np.ndarray, off: int, wverts: np.ndarray,
           wnorm: np.ndarray, force: np.ndarray, scratch: np.ndarray) -> None:
    """``n`` steps (see :func:`advance`); the base at ``base_u[off + step]`` if driven."""
    base = pos.shape[0] - 1
    driven = base_u.shape[0] > 0
    # bodies with inv_m = 0 before the base: an assembly's supports, moving with it
    nfree = 0
    while nfree < base and inv_m[nfree] > 0.0:
        nfree += 1
    if not driven:
        for b in range(nfree, base + 1):
            vel[b, 0] = 0.0
    for step in range(n):
        if driven:  # base at u(t_k); its velocity over the last step, as the blocks'
            u = base_u[off + step]
            for b in range(nfree, base):
                pos[b, 0] += u - pos[base, 0]
            vel[base, 0] = (u - pos[base, 0]) / dt
            pos[base, 0] = u
            for b in range(nfree, base):
                vel[b, 0] = vel[base, 0]
        world_geometry(pos, lverts, lnorm, nverts, wverts, wnorm)
        force[:, :] = 0.0
        _contact_forces(pos, vel, wverts, wnorm, nverts, radius, pairs, pair_depth,
                        pair_edges, shear, kn, ks, pair_mu, pair_beta, dt, force, scratch)
        for b in range(nfree):
            vel[b, 0] += force[b, 0] * inv_m[b] * dt
            vel[b, 1] += (force[b, 1] * inv_m[b] - g) * dt
            vel[b, 2] += force[b, 2] * inv_i[b] * dt
            pos[b, 0] += vel[b, 0] * dt
            pos[b, 1] += vel[b, 1] * dt
            pos[b, 2] += vel[b, 2] * dt


@njit(cache=True)
def advance(n: int, dt: float, pos: np.ndarray, vel: np.ndarray, inv_m: np.ndarray,
            inv_i: np.ndarray, lverts: np.ndarray, lnorm: np.ndarray, nverts: np.ndarray,
            radius: np.ndarray, pairs: np.ndarray, pair_depth: np.ndarray,
            pair_edges: np.ndarray, shear: np.ndarray, kn: float, ks: float,
            pair_mu: np.ndarray, pair_beta: np.ndarray, g: float, poses: np.ndarray,
            base_u: np.ndarray) -> None:
    """Take ``n`` central-difference steps (state arrays updated in place).

    Parameters
    ----------
    n : int
        Number of steps.
    dt : float
        Time step (s).
    pos, vel : ndarray (n_bodies, 3)
        (x, z, θ) at the current step and (v_x, v_z, ω) at the previous half
        step; the last body is the base.
    inv_m, inv_i : ndarray (n_bodies,)
        Inverse mass and inverse moment of inertia about +y (0 for the base).
    lverts, lnorm : ndarray (n_bodies, KMAX, 2)
        Body-frame vertices (counter-clockwise) and outward normals of edge k
        (from vertex k to k + 1).
    nverts : ndarray (n_bodies,)
        Vertex count of each body.
    radius : ndarray (n_bodies,)
        Bounding radius about the centroid (broad phase).
    pairs : ndarray (n_pairs, 2)
        Candidate body pairs (i, j), the upper/moving body first.
    pair_depth : ndarray (n_pairs,)
        Out-of-plane contact depth (m) of each pair.
    pair_edges, shear : ndarray (n_pairs,), (n_pairs, nsub)
        Contact state: selected edge pair code and elastic shear force of each
        sub-contact.
    kn, ks : float
        Normal and shear stiffness per unit area (N/m³).
    pair_mu : ndarray (n_pairs,)
        Friction coefficient of each pair.
    pair_beta : ndarray (n_pairs,)
        Stiffness-proportional damping coefficient β of each pair's
        sub-contacts (s).
    g : float
        Gravity (m/s², along −z).
    poses : ndarray (n_bodies − 1, 7)
        Output: the blocks' poses after the last step (:func:`write_poses`),
        so that reading them costs the caller nothing.
    base_u : ndarray
        Base displacement at the start of each of the ``n`` steps; empty: the
        base holds its position with zero velocity.
    """
    nbody = pos.shape[0]
    kmax = lverts.shape[1]
    wverts = np.empty((nbody, kmax, 2))
    wnorm = np.empty((nbody, kmax, 2))
    force = np.empty((nbody, 3))
    scratch = np.empty(2)
    _steps(n, dt, pos, vel, inv_m, inv_i, lverts, lnorm, nverts, radius, pairs, pair_depth,
           pair_edges, shear, kn, ks, pair_mu, pair_beta, g, base_u, 0, wverts, wnorm, force,
           scratch)
    write_poses(pos, poses)


@njit(cache=True)
def sample(m: int, k: int, dt: float, pos: np.ndarray, vel: np.ndarray, inv_m: np.ndarray,
           inv_i: np.ndarray, lverts: np.ndarray, lnorm: np.ndarray, nverts: np.ndarray,
           radius: np.ndarray, pairs: np.ndarray, pair_depth: np.ndarray,
           pair_edges: np.ndarray, shear: np.ndarray, kn: float, ks: float, pair_mu: np.ndarray,
           pair_beta: np.ndarray, g: float, poses: np.ndarray, base_u: np.ndarray,
           out: np.ndarray) -> None:
    """``m`` runs of ``k`` steps, the blocks' poses after each written to ``out[j]``.

    The same steps as ``m`` calls of :func:`advance` (``k`` steps each, base
    displacements ``base_u[j·k:(j + 1)·k]``; empty ``base_u``: base still) in one
    compiled call. ``out`` is (m, n_bodies − 1, 7); ``poses`` gets the last sample.
    """
    nbody = pos.shape[0]
    kmax = lverts.shape[1]
    wverts = np.empty((nbody, kmax, 2))
    wnorm = np.empty((nbody, kmax, 2))
    force = np.empty((nbody, 3))
    scratch = np.empty(2)
    for j in range(m):
        _steps(k, dt, pos, vel, inv_m, inv_i, lverts, lnorm, nverts, radius, pairs,
               pair_depth, pair_edges, shear, kn, ks, pair_mu, pair_beta, g, base_u, j * k, wverts,
               wnorm, force, scratch)
        write_poses(pos, out[j])
    write_poses(pos, poses)
