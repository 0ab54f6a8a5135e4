"""Per-body friction coefficients for engines that combine two bodies' values as a product.

Bullet, Blender's Bullet and Chipmunk (pymunk) give a contact pair the product of
its two bodies' coefficients; a scene with one friction for the base and another
between blocks needs each body's value chosen so that every pair's product is
the scenario's.
"""

from __future__ import annotations

import math

from rockbench.geometry import Geometry

__all__ = ["product_frictions"]


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
