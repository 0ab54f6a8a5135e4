"""Builders of the geometries rockbench knows: blocks, stacks and the masonry families.

Each returns a :class:`~rockbench.geometry.structure.Geometry`; the catalog, the
scenario files and the tests build every scene through these.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from rockbench import checks
from rockbench.errors import ScenarioError
from rockbench.geometry.bodies import Block, Body, Cylinder, Prism, Support, Upright
from rockbench.geometry.structure import Geometry, Pose

__all__ = ["single", "stack", "stack_poses", "drum_column", "parapet", "running_bond_wall",
           "voussoir_arch", "semicircular_arch"]


def single(block: Upright) -> Geometry:
    """One block standing centred on the base."""
    return stack((block,))


def stack_poses(blocks: Sequence[Upright], offsets: Sequence[float]) -> tuple[Pose, ...]:
    """Poses of blocks stacked bottom first, each centre at its offset along x."""
    out, z = [], 0.0
    for b, x in zip(blocks, offsets, strict=True):
        out.append((x, z + b.h, 0.0))
        z += b.height
    return tuple(out)


def stack(blocks: Sequence[Upright], offsets: Sequence[float] = ()) -> Geometry:
    """Blocks stacked bottom to top, each on the one below.

    Parameters
    ----------
    blocks : sequence of Block
        Bottom first.
    offsets : sequence of float, optional
        Horizontal position (m) of each block's centre along x (default: all
        0, centred). The blocks above each contact must have their common
        centre of mass strictly inside it (between the pivots both faces share),
        else the stack could not stand at rest.

    Raises
    ------
    ScenarioError
        No blocks, a body that is not a Block, offsets not one per block, or a
        stack that cannot stand.
    """
    blocks = tuple(blocks)
    if not blocks:
        raise ScenarioError("a stack needs at least one block")
    if not all(isinstance(b, (Block, Cylinder)) for b in blocks):
        raise ScenarioError("stack blocks must be Block or Cylinder instances")
    offs = tuple(checks.coordinate(o, "stack offset") for o in offsets) \
        or (0.0,) * len(blocks)
    if len(offs) != len(blocks):
        raise ScenarioError(f"stack offsets must be one per block: {len(offs)} offsets "
                            f"for {len(blocks)} blocks")
    _check_stands(blocks, offs)
    return Geometry(blocks, stack_poses(blocks, offs))


def _check_stands(blocks: Sequence[Upright], offsets: Sequence[float]) -> None:
    """Refuse a stack whose upper blocks' centre of mass lies off a contact."""
    ms = [b.m for b in blocks]
    for i in range(1, len(blocks)):
        lo, up = blocks[i - 1], blocks[i]
        left = max(offsets[i - 1] - lo.pivot_half_width, offsets[i] - up.pivot_half_width)
        right = min(offsets[i - 1] + lo.pivot_half_width, offsets[i] + up.pivot_half_width)
        m_above = sum(ms[i:])
        x_above = sum(m * x for m, x in zip(ms[i:], offsets[i:], strict=True)) / m_above
        if not left < right:
            raise ScenarioError(
                f"block #{i + 1} does not touch block #{i}: their faces span x from "
                f"{offsets[i] - up.pivot_half_width:g} to {offsets[i] + up.pivot_half_width:g} m "
                f"and from {offsets[i - 1] - lo.pivot_half_width:g} to "
                f"{offsets[i - 1] + lo.pivot_half_width:g} m (offsets are from the bottom "
                f"block's centre)")
        if not left < x_above < right:
            raise ScenarioError(
                f"block #{i + 1} is off its support: the centre of mass of the blocks from "
                f"#{i + 1} up is at x = {x_above:g} m, outside the contact with block #{i} "
                f"(x from {left:g} to {right:g} m; offsets are from the bottom block's "
                f"centre)")


def drum_column(n: int, *, width: float = 0.6, drum_height: float = 0.5, depth: float = 0.6,
                density: float = 2600.0) -> Geometry:
    """A column of ``n`` equal drums (rectangular in the x–z plane) on the base, centred."""
    n = int(checks.integer(n, "drum column n", low=1))
    blk = Block(width, depth, drum_height, density=density)
    return Geometry((blk,) * n, tuple((0.0, (k + 0.5) * drum_height, 0.0) for k in range(n)))


def parapet(offset: float, *, wall: tuple[float, float] = (0.6, 1.2),
            top: tuple[float, float] = (0.3, 0.8), depth: float = 0.4,
            density: float = 2000.0) -> Geometry:
    """A parapet block on a wall block, its centre ``offset`` (m) from the wall's along x.

    ``wall`` and ``top`` are (width, height) in m; an offset beyond half the
    difference of the widths makes the parapet overhang the wall's edge, which
    shortens its lever on that side.
    """
    (ww, wh), (pw, ph) = wall, top
    return Geometry((Block(ww, depth, wh, density=density), Block(pw, depth, ph, density=density)),
                    ((0.0, 0.5 * wh, 0.0), (float(offset), wh + 0.5 * ph, 0.0)))


def running_bond_wall(courses: int, bricks: int, *, length: float = 0.24, height: float = 0.12,
                      depth: float = 0.12, density: float = 1800.0) -> Geometry:
    """A dry-stack wall panel in running bond, centred on x = 0.

    ``courses`` courses of ``bricks`` bricks ``length`` × ``height``; every
    second course (from the second) is shifted by half a brick, with half
    bricks at both ends, so that every course spans ``bricks · length``.
    """
    nc = int(checks.integer(courses, "wall courses", low=1))
    nb = int(checks.integer(bricks, "wall bricks per course", low=1))
    full = Block(length, depth, height, density=density)
    half = Block(0.5 * length, depth, height, density=density)
    x0 = -0.5 * nb * length
    blocks: list[Body] = []
    poses: list[Pose] = []
    for c in range(nc):
        z = (c + 0.5) * height
        if c % 2 == 0:
            row = [(full, x0 + (k + 0.5) * length) for k in range(nb)]
        else:
            row = [(half, x0 + 0.25 * length)]
            row += [(full, x0 + (k + 1.0) * length) for k in range(nb - 1)]
            row.append((half, -x0 - 0.25 * length))
        for blk, x in row:
            blocks.append(blk)
            poses.append((x, z, 0.0))
    return Geometry(tuple(blocks), tuple(poses))


def _voussoirs(n: int, thickness: float, radius: float, arc_points: int
               ) -> tuple[list[np.ndarray], list[np.ndarray], float]:
    """Polygons (world, the mean circle's centre at the origin) of a semicircular arch's
    ``n`` voussoirs, each sector's centre of gravity, and the sector's area."""
    if int(n) != n or n < 1:
        raise ScenarioError(f"an arch needs n >= 1 voussoirs, got {n!r}")
    r = checks.length(radius, "arch radius")
    t = checks.length(thickness, "arch thickness")
    if t >= 2 * r:
        raise ScenarioError(f"arch thickness {t} must be smaller than twice the radius {r}")
    ri, re = r - 0.5 * t, r + 0.5 * t
    dth = math.pi / n
    # centroid radius of an annular sector of angle dth
    rg = (2.0 / 3.0) * (re**3 - ri**3) / (re**2 - ri**2) * math.sin(0.5 * dth) / (0.5 * dth)
    polys, cgs = [], []
    for k in range(n):
        a0, a1 = k * dth, (k + 1) * dth
        arc = np.linspace(a0, a1, arc_points + 1)
        pts = [(ri * math.cos(a0), ri * math.sin(a0))]
        pts += [(re * math.cos(a), re * math.sin(a)) for a in arc]
        pts.append((ri * math.cos(a1), ri * math.sin(a1)))
        v = np.array(pts)
        # springings sit exactly on z = 0 (sin π is not 0 in floating point)
        v[np.abs(v[:, 1]) < 1e-12 * r, 1] = 0.0
        polys.append(v)
        am = 0.5 * (a0 + a1)
        cgs.append(np.array([rg * math.cos(am), rg * math.sin(am)]))
    return polys, cgs, r * t * dth


def _springers(thickness: float, radius: float, lift: float) -> tuple[Support, Support]:
    """The two fixed pads under an arch's springings, ``thickness`` high, tops at ``lift``."""
    t = thickness
    ri, re = radius - 0.5 * t, radius + 0.5 * t
    pad = t
    return (Support.rectangle(ri - pad, re + pad, lift - t, lift),
            Support.rectangle(-re - pad, -ri + pad, lift - t, lift))


def semicircular_arch(n: int, thickness: float, radius: float = 1.0, *, depth: float = 1.0,
                      density: float = 2000.0, arc_points: int = 4) -> Geometry:
    """A semicircular arch of ``n`` equal voussoirs with radial joints on two fixed supports.

    The limit-analysis arch: the centre of the mean circle is the origin; the
    springings lie on z = 0 and each rests on a support below it (no base
    plane). Each voussoir is an annular sector of mean radius ``radius`` and
    ``thickness``: its mass and centre of gravity are the sector's exactly;
    its polygon replaces the (concave) intrados arc by its chord and the
    extrados arc by ``arc_points`` chords, so that it is convex and its joints
    are exact.
    """
    polys, cgs, area = _voussoirs(n, thickness, radius, arc_points)
    mass = density * depth * area
    bodies = tuple(Prism(tuple(map(tuple, v.tolist())), depth, mass=mass,
                         centre_of_gravity=(float(c[0]), float(c[1])))
                   for v, c in zip(polys, cgs, strict=True))
    return Geometry(bodies, ((0.0, 0.0, 0.0),) * len(bodies),
                    _springers(float(thickness), float(radius), 0.0), base=False)


def voussoir_arch(n: int, thickness: float, radius: float = 1.0, *, depth: float = 0.5,
                  density: float = 2000.0) -> Geometry:
    """A semicircular arch of ``n`` voussoirs on two fixed supports standing on the base.

    The voussoirs are the convex polygons of :func:`semicircular_arch`, with the
    mass and centroid of those polygons (what an engine's collision shape
    holds); its two supports, ``thickness`` high, stand on the base, so the
    springings lie at z = ``thickness`` and the mean circle's centre at
    (0, thickness).
    """
    polys, _, _ = _voussoirs(n, thickness, radius, 4)
    lift = np.array([0.0, float(thickness)])
    bodies = tuple(Prism(tuple(map(tuple, (v + lift).tolist())), depth, density=density)
                   for v in polys)
    return Geometry(bodies, ((0.0, 0.0, 0.0),) * len(bodies),
                    _springers(float(thickness), float(radius), float(thickness)))
