"""Incidence angles: a horizontal base motion, or a pair of them, turned about the vertical.

A block's axes are fixed (width along x, depth along y); an earthquake's are not. A
horizontal pair of records (H1, H2) arriving at an incidence angle α, measured from the
block's x axis toward +y, shakes the base with::

    x = H1 cos α − H2 sin α,        y = H1 sin α + H2 cos α

(:func:`rotate_pair`); one motion P along the direction α is the same with H2 = 0
(:func:`along`). The rotation is exact: the resultant |(x, y)| is |(H1, H2)| at every
instant, so the peak of the resultant does not depend on α.

Records are combined sample by sample on the union of their sample times (each is
linear between its samples, so nothing is lost), from their baseline-corrected
accelerations with their scale; pulses and sinusoids along one direction are scaled by
their amplitude, exactly.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from rockbench.errors import ScenarioError
from rockbench.scenarios.excitation import (
    AxialExcitation,
    Components,
    CosinePulse,
    Free,
    Record,
    SinePulse,
    Sinusoid,
)

__all__ = ["ZERO", "scaled", "along", "rotate_pair", "horizontal_pair"]

#: A direction cosine below this is taken as exactly zero (cos 90° is 6·10⁻¹⁷ in floats).
ZERO = 1e-12


def scaled(motion: AxialExcitation, factor: float) -> AxialExcitation:
    """``motion`` times ``factor`` (acceleration, velocity and displacement alike).

    Parameters
    ----------
    motion : AxialExcitation
        A pulse, a sinusoid, a record, or no motion.
    factor : float
        The factor (any sign); below :data:`ZERO` in magnitude the result is no motion.

    Raises
    ------
    ScenarioError
        A kind of motion that cannot be scaled exactly (e.g. a tilting table).
    """
    factor = float(factor)
    if motion.is_free or abs(factor) < ZERO:
        return Free()
    if factor == 1.0:
        return motion
    if isinstance(motion, (SinePulse, CosinePulse, Sinusoid)):
        return dataclasses.replace(motion, amplitude=motion.amplitude * factor)
    if isinstance(motion, Record):
        return dataclasses.replace(motion, scale=motion.scale * factor)
    raise ScenarioError(f"a {motion.kind!r} base motion cannot be turned to an incidence "
                        f"angle (pulses, sinusoids and records can)")


def along(motion: AxialExcitation, angle: float, z: AxialExcitation | None = None
          ) -> Components:
    """One horizontal ``motion`` along the direction ``angle`` (degrees from +x toward +y).

    Parameters
    ----------
    motion : AxialExcitation
        The horizontal motion.
    angle : float
        Incidence angle α in degrees: x = P cos α, y = P sin α.
    z : AxialExcitation, optional
        The vertical component, unchanged.
    """
    a = math.radians(float(angle))
    return Components(x=scaled(motion, math.cos(a)), y=scaled(motion, math.sin(a)),
                      z=z if z is not None else Free())


def _samples(motion: AxialExcitation) -> np.ndarray:
    if motion.is_free:
        return np.zeros(0)
    if not isinstance(motion, Record):
        raise ScenarioError(f"a horizontal pair is rotated sample by sample: both components "
                            f"must be records, got a {motion.kind!r}")
    return np.asarray(motion.times, dtype=float)


def rotate_pair(h1: AxialExcitation, h2: AxialExcitation, angle: float,
                z: AxialExcitation | None = None) -> Components:
    """The horizontal pair (H1, H2) arriving at the incidence ``angle``.

    Parameters
    ----------
    h1, h2 : AxialExcitation
        The two horizontal components (records; one of them may be no motion, and a
        pulse or a sinusoid alone is turned exactly by :func:`along`).
    angle : float
        Incidence angle α in degrees, from the block's x axis toward +y:
        x = H1 cos α − H2 sin α, y = H1 sin α + H2 cos α.
    z : AxialExcitation, optional
        The vertical component, unchanged.

    Returns
    -------
    Components
        α = 0 gives (H1, H2) themselves; α = 90° gives (−H2, H1).

    Raises
    ------
    ScenarioError
        Two moving components that are not both records.
    """
    a = math.radians(float(angle))
    c, s = math.cos(a), math.sin(a)
    c = 0.0 if abs(c) < ZERO else c
    s = 0.0 if abs(s) < ZERO else s
    vertical = z if z is not None else Free()
    if h2.is_free:
        return Components(x=scaled(h1, c), y=scaled(h1, s), z=vertical)
    if h1.is_free:
        return Components(x=scaled(h2, -s), y=scaled(h2, c), z=vertical)
    if s == 0.0:  # α = 0 or 180°: the pair itself, or both reversed
        return Components(x=scaled(h1, c), y=scaled(h2, c), z=vertical)
    if c == 0.0:  # α = ±90°
        return Components(x=scaled(h2, -s), y=scaled(h1, s), z=vertical)
    t = np.union1d(_samples(h1), _samples(h2))
    a1 = np.asarray(h1.acceleration(t), dtype=float)
    a2 = np.asarray(h2.acceleration(t), dtype=float)
    source = ", ".join(x for x in (getattr(h1, "source", ""), getattr(h2, "source", "")) if x)
    note = f"rotated {float(angle):g}°" + (f" from {source}" if source else "")
    return Components(x=Record(t, c * a1 - s * a2, source=note),
                      y=Record(t, s * a1 + c * a2, source=note), z=vertical)


def horizontal_pair(excitation: object) -> tuple[AxialExcitation, AxialExcitation,
                                                 AxialExcitation]:
    """(H1, H2, vertical) of a scenario's excitation: an axial one is (P, none, none).

    Raises
    ------
    ScenarioError
        No horizontal motion along x (a motion along y alone has no H1).
    """
    if isinstance(excitation, Components):
        h1, h2, z = excitation.x, excitation.y, excitation.z
    elif isinstance(excitation, AxialExcitation):
        h1, h2, z = excitation, Free(), Free()
    else:
        raise ScenarioError(f"unknown excitation {excitation!r}")
    if h1.is_free:
        raise ScenarioError("the excitation has no horizontal component along x to turn "
                            "(give the first horizontal component as x)")
    return h1, h2, z
