"""The engines against the 3D references: a drum in the plane, a corner release, a precession.

Three scenes with an answer known in closed form, each of which a planar case
cannot reveal:

- **drum release** (:func:`drum_release`): a stone drum (R 0.15 m, H 1.0 m)
  released in the x–z plane at 0.5 λ rocks on its rim as Housner's block of
  half-width R with the cylinder's inertia; its first impact;
- **corner release** (:func:`corner_release`): a square pillar (0.3 × 0.3 ×
  1.2 m) released from rest on a corner along its diagonal rocks in the diagonal
  plane until it lands (:func:`corner_landing_time`), without leaving it;
- **steady precession** (:func:`precession`): a slender cylinder (R 0.3 m,
  H 1.5 m) started rolling on its rim at 0.2 rad of tilt in the steady precession
  of :func:`~rockbench.analytic.steady_precession` holds that tilt and
  precesses at the closed-form rate Ω.

:func:`measure` runs one method on the three and returns the errors
(:class:`Errors3D`); ``python -m benchmarks.references_3d`` tabulates them per
engine and preset, with the time step halved for convergence.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rockbench.analytic import (
    SteadyPrecession,
    quarter_period,
    reference,
    rolling_start,
    steady_precession,
)
from rockbench.engines import get_engine
from rockbench.geometry import Block, Cylinder, rocking_about, single
from rockbench.method import Method
from rockbench.scenarios import Scenario
from rockbench.trajectory import Status, Trajectory

__all__ = ["DRUM", "SLENDER_CYLINDER", "PILLAR", "drum_release", "corner_release",
           "precession", "corner_landing_time", "first_zero", "Errors3D", "measure"]

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
    return Scenario("corner-free", single(PILLAR), initial_tilt=0.5, initial_azimuth=0.25 * math.pi,
                    duration=duration)


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


def first_zero(t: np.ndarray, theta: np.ndarray) -> float:
    """The first time θ changes sign (linear interpolation), or NaN."""
    s = np.sign(theta)
    i = np.nonzero(s[:-1] * s[1:] < 0)[0]
    if not i.size:
        return math.nan
    j = int(i[0])
    return float(t[j] - theta[j] * (t[j + 1] - t[j]) / (theta[j + 1] - theta[j]))


@dataclass(frozen=True)
class Errors3D:
    """One method's errors against the three references (NaN where a run failed).

    Attributes
    ----------
    method : Method
        The engine and its settings.
    drum_impact : float
        Relative error of the drum's first impact time.
    corner_landing : float
        Relative error of the corner release's landing time.
    off_diagonal : float
        Largest |θ + roll| before the landing (rad): how far it left the diagonal plane.
    tilt_drift : float
        Largest |tilt − 0.2| of the precession (rad).
    rate_error : float
        Relative error of the mean precession rate.
    cpu_per_s : float
        CPU seconds per simulated second of the precession.
    failures : tuple of str
        The runs whose status was not ``ok``, with the engine's message.
    """

    method: Method
    drum_impact: float
    corner_landing: float
    off_diagonal: float
    tilt_drift: float
    rate_error: float
    cpu_per_s: float
    failures: tuple[str, ...]


def measure(method: Method, precession_duration: float = 5.0) -> Errors3D:
    """Run ``method`` on the three scenes and measure its errors."""
    engine = get_engine(method.engine)
    settings = method.settings
    failures: list[str] = []

    def run(sc: Scenario) -> Trajectory | None:
        tr = engine.simulate(sc, settings)
        if tr.status is Status.OK:
            return tr
        failures.append(f"{sc.name}: {tr.status} ({tr.message})")
        return None

    nan = math.nan
    drum = drum_release()
    ref = reference(drum)
    t_ref = first_zero(ref.t, ref.theta[:, 0])
    tr = run(drum)
    drum_err = nan if tr is None else first_zero(tr.t, tr.theta[:, 0]) / t_ref - 1.0
    corner = corner_release()
    t_land = corner_landing_time(PILLAR, corner.theta0, corner.g)
    tr = run(corner)
    land_err = off = nan
    if tr is not None:
        land_err = first_zero(tr.t, tr.theta[:, 0]) / t_land - 1.0
        before = tr.t < 0.95 * t_land
        off = float(np.max(np.abs(tr.theta[before, 0] + tr.roll[before, 0])))
    sc, sp = precession(precession_duration)
    tr = run(sc)
    drift = rate = cost = nan
    if tr is not None:
        drift = float(np.max(np.abs(tr.tilt[:, 0] - sp.theta)))
        az = np.unwrap(tr.azimuth[:, 0])
        rate = float((az[-1] - az[0]) / (tr.t[-1] - tr.t[0]) / sp.psi_dot - 1.0)
        cost = tr.cpu_time / sc.duration
    return Errors3D(method, drum_err, land_err, off, drift, rate, cost, tuple(failures))
