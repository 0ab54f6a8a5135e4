"""Per-body friction coefficients for engines that combine two bodies' values as a product.

Bullet, Blender's Bullet and Chipmunk (pymunk) give a contact pair the product of
its two bodies' coefficients; a scene with one friction for the base and another
between blocks needs each body's value chosen so that every pair's product is
the scenario's.
"""

from __future__ import annotations

import math

__all__ = ["assembly_frictions"]


def assembly_frictions(mu: float, mu_if: float, n_blocks: int) -> list[float]:
    """Per-body coefficients (ground and supports first) for the blocks of an assembly.

    A block of an assembly may touch other blocks and the base at once, so every
    block gets sqrt(μ_if) and the base μ / sqrt(μ_if): block pairs get μ_if, block
    and base μ. Needs μ_if > 0 unless μ = 0 too.

    Parameters
    ----------
    mu : float
        Friction between a block and the base or a support.
    mu_if : float
        Friction between two blocks.
    n_blocks : int
        Number of blocks.

    Returns
    -------
    list of float
        The base's (and supports') coefficient, then one per block.
    """
    if mu_if == mu:
        return [math.sqrt(mu)] * (n_blocks + 1)
    root = math.sqrt(mu_if)
    return [mu / root] + [root] * n_blocks
