"""Per-body friction coefficients for engines that combine two bodies' values.

Bullet, Blender's Bullet and Chipmunk (pymunk) give a contact pair the product of
its two bodies' coefficients, PhysX and Newton their mean; a scene with one friction
for the base and another between blocks needs each body's value chosen so that every
pair's product (:func:`product_frictions`) or mean (:func:`mean_frictions`) is the
scenario's.
"""

from __future__ import annotations

import math

from rockbench.geometry import Geometry

__all__ = ["product_frictions", "mean_frictions"]


def product_frictions(geometry: Geometry, mu: float, mu_if: float) -> list[float]:
    """Per-body coefficients whose pairwise products are μ (body–base or support) and μ_if.

    Equal coefficients: √μ on every body. A column (each block touches only the
    ones below and above it): the base μ, the blocks alternating 1 and μ_if.
    Any other geometry, whose blocks may touch other blocks and the base at
    once: √μ_if on every block and μ / √μ_if on the base and supports (which
    needs μ_if > 0 unless μ = 0 too).

    Parameters
    ----------
    geometry : Geometry
        What is built.
    mu : float
        Friction between a block and the base or a support.
    mu_if : float
        Friction between two blocks.

    Returns
    -------
    list of float
        The base's (and supports') coefficient, then one per body.
    """
    n = geometry.n_bodies
    if mu_if == mu:
        return [math.sqrt(mu)] * (n + 1)
    if geometry.column is not None:
        return [mu] + [1.0 if i % 2 == 0 else mu_if for i in range(n)]
    root = math.sqrt(mu_if)
    return [mu / root] + [root] * n


def mean_frictions(geometry: Geometry, mu: float, mu_if: float) -> list[float] | None:
    """Per-body coefficients whose pairwise means are μ (body–base or support) and μ_if.

    PhysX's default combine mode averages the two materials' coefficients. Equal
    coefficients: μ on every body. A column (each block touches only the ones below
    and above it): the base 2μ − x, the blocks alternating x and 2μ_if − x with
    x = min(μ, μ_if), so that none is negative. Any other geometry, whose blocks may
    touch other blocks and the base at once: μ_if on every block and 2μ − μ_if on the
    base and supports, which needs 2μ ≥ μ_if (else None: no coefficients exist).

    Parameters
    ----------
    geometry : Geometry
        What is built.
    mu : float
        Friction between a block and the base or a support.
    mu_if : float
        Friction between two blocks.

    Returns
    -------
    list of float or None
        The base's (and supports') coefficient, then one per body; None when no
        non-negative coefficients give both means.
    """
    n = geometry.n_bodies
    if mu_if == mu:
        return [mu] * (n + 1)
    if geometry.column is not None:
        x = min(mu, mu_if)
        return [2.0 * mu - x] + [x if i % 2 == 0 else 2.0 * mu_if - x for i in range(n)]
    if 2.0 * mu < mu_if:
        return None
    return [2.0 * mu - mu_if] + [mu_if] * n
