"""A cylinder's scenario and its rolling reference: the start on the rim, the sampled trajectory.

:func:`rolling_start` gives the scenario fields (tilt, azimuth, velocities) of a
cylinder rolling on its rim without slipping at given rates, e.g. a steady
precession (:func:`~rockbench.analytic.rolling_cylinder.steady_precession`);
:func:`rolling_reference` reads such a scenario back and returns the rolling
model's :class:`~rockbench.trajectory.Trajectory`, with the cylinder's full
pose at every sample, for comparison with the engines.
"""

from __future__ import annotations

import math
import time
from typing import NamedTuple

import numpy as np
from scipy.spatial.transform import Rotation

from rockbench.analytic.rolling_cylinder import RollingOutcome, euler_rates, frame, solve_rolling
from rockbench.errors import UnsupportedScenario
from rockbench.geometry import Cylinder
from rockbench.scenarios import Scenario
from rockbench.trajectory import Status, Trajectory, orientation_from_quaternions

__all__ = ["RollingStart", "rolling_start", "rolling_reference", "LANDING_ANGLE"]

#: Tilt (rad) at which a 3D rolling reference counts as landed flat: the rolling disk's
#: precession rate grows as 1/sin²θ toward upright, where the rim model has no meaning left.
LANDING_ANGLE = 1e-3

#: A start whose centre-of-mass velocity differs from ω × (G − P) by more than this
#: fraction of R|ω| (plus 1e-9 m/s) slips at the contact: the rolling model does not apply.
_NO_SLIP_RTOL = 1e-6


class RollingStart(NamedTuple):
    """The :class:`~rockbench.scenarios.Scenario` fields of a cylinder starting to roll.

    ``Scenario(name, cylinder, **start._asdict(), ...)`` builds the scenario.
    """

    initial_tilt: float
    initial_azimuth: float
    initial_velocity: tuple[float, float, float]
    initial_angular_velocity: tuple[float, float, float]


def rolling_start(cylinder: Cylinder, theta: float, psi: float = 0.0, theta_dot: float = 0.0,
                  psi_dot: float = 0.0, phi_dot: float = 0.0, g: float = 9.81) -> RollingStart:
    """The start of a cylinder on its rim at tilt θ toward azimuth ψ, rolling without slipping.

    Parameters
    ----------
    cylinder : Cylinder
        The body.
    theta : float
        Tilt, 0 < θ < its λ = atan(R/h) (rad): it leans on its rim.
    psi : float
        Azimuth of the lean, from +x toward +y (rad).
    theta_dot, psi_dot, phi_dot : float
        Rates of tilt, azimuth and spin (rad/s) (:mod:`~rockbench.analytic.rolling_cylinder`).
    g : float
        Gravity (m/s²), for λ.

    Returns
    -------
    RollingStart
        Tilt as a fraction of λ, the azimuth, the centre of mass's velocity
        ω × (G − P) (the contact P at rest) and ω, in world axes.
    """
    lam = cylinder.rocking(g).lam
    if not 0.0 < theta < lam:
        raise UnsupportedScenario(f"a rolling start leans on its rim: 0 < tilt < λ = "
                                  f"{lam:.6g} rad, got {theta!r}")
    _, a1, a2, e3 = frame(theta, psi)
    w = theta_dot * a1 + psi_dot * math.sin(theta) * a2 \
        + (psi_dot * math.cos(theta) + phi_dot) * e3
    v = np.cross(w, cylinder.radius * a2 + cylinder.h * e3)
    return RollingStart(theta / lam, psi, tuple(map(float, v)),  # type: ignore[arg-type]
                        tuple(map(float, w)))  # type: ignore[arg-type]


def rolling_reference(scenario: Scenario) -> Trajectory:
    """The rolling model's trajectory of a single cylinder that starts on its rim.

    The cylinder rolls on its rim without slipping
    (:func:`~rockbench.analytic.rolling_cylinder.solve_rolling`, the scenario's
    friction checked) under the three-component base motion. The model has no
    impact law: a cylinder that lands flat (tilt below :data:`LANDING_ANGLE`),
    leaves the ground or slips ends the reference there, with status
    ``unsupported`` and the reason; samples after it are absent.

    Raises
    ------
    UnsupportedScenario
        Not one cylinder, no tilt, or a start that slips at the contact.
    """
    body = scenario.blocks[0]
    if scenario.n_blocks != 1 or not isinstance(body, Cylinder) or scenario.theta0 == 0.0:
        raise UnsupportedScenario("the rolling reference needs one cylinder tilted on its rim")
    st = scenario.initial_states()[0]
    theta = abs(scenario.theta0)
    u_xy = st[:2] - np.array([scenario.geometry.poses[0][0], 0.0])
    psi = math.atan2(u_xy[1], u_xy[0])
    u, a1, a2, e3 = frame(theta, psi)
    contact = np.array([scenario.geometry.poses[0][0], 0.0, 0.0]) + body.radius * u
    w, v = st[10:13], st[7:10]
    slip = np.linalg.norm(v - np.cross(w, st[:3] - contact))
    if slip > _NO_SLIP_RTOL * body.radius * np.linalg.norm(w) + 1e-9:
        raise UnsupportedScenario(
            f"the rolling reference starts rolling without slipping: the initial velocity "
            f"differs from ω × (G − P) by {slip:.3g} m/s")
    w1, w2, w3 = float(w @ a1), float(w @ a2), float(w @ e3)
    psi_dot, phi_dot = euler_rates(theta, w2, w3)
    motion = scenario.motion
    planar = scenario.planar_start and "y" not in motion.axes
    start, cpu = time.perf_counter(), time.process_time()
    sol = solve_rolling(
        body, theta, psi, w1, float(psi_dot), float(phi_dot),
        scenario.duration, phi0=-psi, contact0=(float(contact[0]), float(contact[1])),
        g=scenario.g,
        base_acceleration=None if motion.is_free else lambda t: motion.acceleration(t).tolist(),
        breakpoints=motion.breakpoints, t_eval=scenario.output_times(),
        friction=scenario.contact.friction,
        landing_angle=0.0 if planar else LANDING_ANGLE)
    # orientation Rz(ψ) Ry(θ) Rz(φ); the centre of mass moves with the base
    rot = Rotation.from_euler("ZYZ", np.column_stack([sol.psi, sol.theta, sol.phi]))
    q = np.roll(rot.as_quat(), 1, axis=1)
    com = sol.com + np.asarray(motion.displacement(sol.t), float).reshape(-1, 3)
    poses = np.concatenate([com, q], axis=1)[:, None, :]
    o = orientation_from_quaternions(poses[..., 3:])
    status = {RollingOutcome.OK: Status.OK,
              RollingOutcome.OVERTURNED: Status.OVERTURNED}.get(sol.outcome, Status.UNSUPPORTED)
    message = "" if status is Status.OK else f"rolling reference: {sol.message}"
    return Trajectory(t=sol.t, theta=o.theta, x=poses[..., 0], z=poses[..., 2], wobble=o.wobble,
                      y=poses[..., 1], roll=o.roll, twist=o.twist, status=status,
                      message=message, wall_time=time.perf_counter() - start,
                      cpu_time=time.process_time() - cpu,
                      engine="analytic", scenario=scenario.name,
                      settings={"model": "rolling cylinder"})
