"""Geometry: one model of what rocks, for every scene.

Bodies (rectangular :class:`Block`, convex :class:`Prism`, :class:`Cylinder`) at poses on the base
and on fixed :class:`Support` s make a :class:`Geometry`, whose contacts at rest
are found when it is built; builders make the single block, the stack and the
masonry families. The scenarios, the analytic references and the engines all
read this one model.
"""

from rockbench.geometry.bodies import (
    Block,
    Body,
    Cylinder,
    Prism,
    Support,
    Upright,
    footprint_pivot,
)
from rockbench.geometry.builders import (
    drum_column,
    parapet,
    running_bond_wall,
    semicircular_arch,
    single,
    stack,
    voussoir_arch,
)
from rockbench.geometry.rocking import RockingProperties, rocking_about
from rockbench.geometry.structure import Column, Geometry, Interface, Pose

__all__ = ["Block", "Prism", "Cylinder", "Upright", "footprint_pivot", "Support", "Body",
           "Geometry",
           "Interface", "Column", "Pose", "RockingProperties", "rocking_about", "single",
           "stack", "drum_column", "parapet", "running_bond_wall", "voussoir_arch",
           "semicircular_arch"]
