"""Three 3D scenes whose answer is known in closed form: a drum, a corner, a precession.

- **drum release** (:func:`drum_release`): a stone drum (R 0.15 m, H 1.0 m)
  released in the x–z plane at 0.5 λ rocks on its rim as Housner's block of
  half-width R with the cylinder's inertia (:func:`~rockbench.analytic.reference`);
- **corner release** (:func:`corner_release`): a square pillar (0.3 × 0.3 × 1.2 m)
  released from rest on a corner along its diagonal rocks in the diagonal plane
  until it lands (:func:`corner_landing_time`), without leaving it;
- **steady precession** (:func:`precession`): a slender cylinder (R 0.3 m, H 1.5 m)
  started rolling on its rim at 0.2 rad of tilt in the steady precession of
  :func:`~rockbench.analytic.rolling_cylinder.steady_precession` holds that tilt
  and precesses at the closed-form rate Ω.

The engines' conformance kit and ``rockbench references-3d`` run them.
"""

from __future__ import annotations

import math

from rockbench.analytic.closed_forms import quarter_period
from rockbench.analytic.cylinder_reference import rolling_start
from rockbench.analytic.rolling_cylinder import SteadyPrecession, steady_precession
from rockbench.geometry import Block, Cylinder, rocking_about, single
from rockbench.scenarios import Scenario

__all__ = ["DRUM", "SLENDER_CYLINDER", "PILLAR", "PRECESSION_TILT", "drum_release",
           "corner_release", "precession", "corner_landing_time"]

#: A stone drum, a slender cylinder and a square pillar.
DRUM = Cylinder(0.15, 1.0, density=2500.0)
SLENDER_CYLINDER = Cylinder(0.3, 1.5, density=2000.0)
PILLAR = Block(0.3, 0.3, 1.2, density=2000.0)
#: Tilt (rad) of the steady precession.
PRECESSION_TILT = 0.2


def drum_release(duration: float = 0.8) -> Scenario:
    """The drum released from rest in the x–z plane at 0.5 λ."""
    return Scenario("drum-free", single(DRUM), initial_tilt=0.5, duration=duration)


def corner_release(duration: float = 0.8) -> Scenario:
    """The pillar released from rest on its corner at 0.5 λ of its diagonal (azimuth 45°)."""
    return Scenario("corner-free", single(PILLAR), initial_tilt=0.5,
                    initial_azimuth=0.25 * math.pi, duration=duration)


def precession(duration: float = 5.0) -> tuple[Scenario, SteadyPrecession]:
    """The slender cylinder in steady precession at 0.2 rad of tilt, on a contact circle of
    its own radius (its centre of mass circles the origin), sampled at 200 Hz."""
    c = SLENDER_CYLINDER
    sp = steady_precession(c, PRECESSION_TILT, contact_radius=c.radius)
    start = rolling_start(c, sp.theta, 0.0, 0.0, sp.psi_dot, sp.phi_dot)
    return Scenario("cylinder-precession", single(c), **start._asdict(), duration=duration,
                    output_rate=200.0), sp


def corner_landing_time(block: Block, tilt: float, g: float = 9.81) -> float:
    """Time for a square-based block released from rest on a corner, tilted by ``tilt`` (rad)
    along its diagonal, to land: Housner's quarter period in the diagonal plane, with the
    half-diagonal as lever and the inertia about the horizontal axis across the diagonal
    (every horizontal axis of a square base has the same)."""
    lever = math.hypot(block.b, 0.5 * block.depth)
    rock = rocking_about(block.m, lever, block.h, block.inertia[0], g)
    return float(quarter_period(rock.p, rock.lam, tilt))
