"""Physical speed bounds of a scenario: flag runs that move faster than physics allows.

A rocking stack can only gain kinetic energy from gravity and from the base. A
point of the stack that falls the whole stack height ``H`` reaches at most
``sqrt(2 g H)``; the base drags the blocks at most at its peak speed. So no
block centroid can move faster than::

    v_max = factor · (sqrt(2 g H + 2 E₀/m) + 2 max|u̇_g|) + v_floor

(E₀ the kinetic energy a moving start gives, m the lightest body's mass) and no
block can spin faster than ``ω_max = v_max / k_min`` (``k_min`` the smallest
centroidal radius of gyration about y, or about any axis for a start out of the
x–z plane: a block whose rotational energy ½ m k² ω² exceeded ½ m v_max² would
violate the same energy bound).

The check uses finite differences of sampled poses, i.e. mean speeds over a
sample interval, which never exceed the peak speed: an honest trajectory can
not trip it. The engine watchdog applies it to every chunk of samples while a
run goes on, and :func:`rockbench.runner.run_job` to every finished trajectory
(:func:`check_trajectory`), which also covers engines that bypass the watchdog.
:func:`check_trajectory` also makes a block past 90° an ``overturned`` run,
whatever status the engine gave.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from rockbench.scenarios import Scenario
from rockbench.trajectory import Status, Trajectory

__all__ = ["SpeedBound", "check_trajectory", "SAFETY_FACTOR"]

#: Safety factor on the energy bound (an exploding solver is orders of magnitude off).
SAFETY_FACTOR = 3.0
#: Additive floor in m/s so that tiny blocks keep some slack for contact noise.
SPEED_FLOOR = 0.5


@dataclass(frozen=True)
class SpeedBound:
    """Largest physically possible centroid speed and spin of any block.

    Attributes
    ----------
    v_max : float
        Bound on each block centroid's speed in the x–z plane (m/s).
    omega_max : float
        Bound on each block's rocking rate |dθ/dt| (rad/s).
    """

    v_max: float
    omega_max: float

    @classmethod
    def for_scenario(cls, scenario: Scenario, factor: float = SAFETY_FACTOR,
                     v_base: float | None = None) -> SpeedBound:
        """The bound derived from the stack height and the peak base speed.

        Parameters
        ----------
        scenario : Scenario
            The simulated problem.
        factor : float
            Safety factor on the energy bound.
        v_base : float, optional
            Bound on the base speed (m/s) when the caller has it; from the
            base motion's :meth:`~rockbench.scenarios.BaseMotion.motion_bounds` otherwise.
        """
        height = scenario.geometry.total_height
        if v_base is None:
            v_base = scenario.motion.motion_bounds(scenario.duration)[1]
        # a body that starts moving has its kinetic energy to spend besides gravity's work
        fall = (2.0 * scenario.g * height
                + 2.0 * scenario.initial_kinetic_energy() / min(b.m for b in scenario.blocks))
        v_max = factor * (math.sqrt(fall) + 2.0 * v_base) + SPEED_FLOOR
        # in the plane a body turns about y only; a 3D start may spin it about any axis
        axes = slice(1, 2) if scenario.planar_start else slice(0, 3)
        k_min = min(math.sqrt(float(b.inertia[axes].min()) / b.m) for b in scenario.blocks)
        return cls(v_max=v_max, omega_max=v_max / k_min)

    def violation(
        self, dt: float, dxz: np.ndarray | None, dtheta: np.ndarray
    ) -> str | None:
        """Describe a bound violation over one sample interval, or None.

        Parameters
        ----------
        dt : float
            Sample interval (s).
        dxz : ndarray, shape (n_blocks, 2), optional
            Centroid displacement over the interval (None or NaN: unknown).
        dtheta : ndarray, shape (n_blocks,)
            Change of rocking angle over the interval (rad, unwrapped).
        """
        if dxz is not None:
            speed = np.hypot(dxz[:, 0], dxz[:, 1]) / dt
            if np.any(speed > self.v_max):
                i = int(np.nanargmax(speed))
                return (f"explosion: block {i + 1} centroid speed {speed[i]:.3g} m/s exceeds "
                        f"the physical bound {self.v_max:.3g} m/s")
        spin = np.abs(dtheta) / dt
        if np.any(spin > self.omega_max):
            i = int(np.nanargmax(spin))
            return (f"explosion: block {i + 1} rocking rate {spin[i]:.3g} rad/s exceeds "
                    f"the physical bound {self.omega_max:.3g} rad/s")
        return None


def check_trajectory(traj: Trajectory, scenario: Scenario) -> Trajectory:
    """Give a finished trajectory the status its samples show.

    A block past 90° (|θ| ≥ π/2, θ wrapped to (−π, π]) has overturned, whatever
    the engine reported: the trajectory is cut after the first such sample (as
    the engine watchdog stops) and gets status ``overturned``. This applies to
    ``ok``, ``overturned`` and ``unstable`` trajectories, the last only when
    the samples up to the overturn pass the checks below (the block fell over
    before the engine failed).

    Then ``ok`` and ``overturned`` trajectories holding NaN or non-physical
    speeds are cut after the first offending sample and get status
    ``unstable`` with the reason. Unknown positions (all-NaN ``x``/``z``
    columns, as in analytic references) are not checked. A trajectory that
    passes is returned unchanged.

    Parameters
    ----------
    traj : Trajectory
        A run's result.
    scenario : Scenario
        The problem it solves.

    Returns
    -------
    Trajectory
        ``traj`` itself or a truncated copy with status ``overturned`` or ``unstable``.
    """
    if traj.t.size == 0 or not (traj.status.completed or traj.status is Status.UNSTABLE):
        return traj
    over = _first_past_90(traj)
    if over is None:
        return _check_physical(traj, scenario) if traj.status.completed else traj
    i, block = over
    if traj.status is Status.OVERTURNED and i == traj.t.size - 1:
        return _check_physical(traj, scenario)  # the engine cut it there itself
    cut = _cut(traj, i, Status.OVERTURNED, f"block {block + 1} past 90° at t = "
               f"{traj.t[i]:.4g} s (the engine reported {traj.status})")
    checked = _check_physical(cut, scenario)
    if checked.status is Status.UNSTABLE and traj.status is Status.UNSTABLE:
        return traj  # it failed before it fell: the engine's verdict stands
    return checked


def _first_past_90(traj: Trajectory) -> tuple[int, int] | None:
    """(sample, block) of the first sample with a block past 90°, or None."""
    wrapped = np.abs(np.remainder(traj.theta + math.pi, 2.0 * math.pi) - math.pi)
    with np.errstate(invalid="ignore"):
        past = wrapped >= 0.5 * math.pi  # NaN compares False: the NaN check reports it
    rows = np.any(past, axis=1)
    if not np.any(rows):
        return None
    i = int(np.argmax(rows))
    return i, int(np.argmax(past[i]))


def _turns(traj: Trajectory) -> np.ndarray:
    """Each block's rotation between successive samples (rad, about any axis), from θ, the
    roll and the twist: θ alone is ill-defined for a block falling about x.

    The orientation is rebuilt as the swing that takes z to the body's z axis,
    b ∝ sgn(R₂₂) (tan θ, −tan roll, 1) (θ and the roll share R₂₂'s sign), after the twist
    about z; the rotation between two is 2 acos |q₀ · q₁|.
    """
    th, roll = traj.theta, traj.roll
    sign = np.where(np.cos(th) < 0.0, -1.0, 1.0)
    b = sign[..., None] * np.stack([np.tan(th), -np.tan(roll), np.ones_like(th)], axis=-1)
    b /= np.linalg.norm(b, axis=-1, keepdims=True)
    half = 0.5 * np.arccos(np.clip(b[..., 2], -1.0, 1.0))
    across = np.hypot(b[..., 0], b[..., 1])
    scale = np.divide(np.sin(half), across, out=np.zeros_like(across), where=across > 0.0)
    # swing (cos h, −b_y s, b_x s, 0) times twist (cos t, 0, 0, sin t)
    sw = np.stack([np.cos(half), -b[..., 1] * scale, b[..., 0] * scale,
                   np.zeros_like(half)], axis=-1)
    c, s = np.cos(0.5 * traj.twist), np.sin(0.5 * traj.twist)
    q = np.stack([sw[..., 0] * c - sw[..., 3] * s, sw[..., 1] * c + sw[..., 2] * s,
                  sw[..., 2] * c - sw[..., 1] * s, sw[..., 3] * c + sw[..., 0] * s], axis=-1)
    dot = np.abs(np.sum(q[1:] * q[:-1], axis=-1))
    return 2.0 * np.arccos(np.clip(dot, 0.0, 1.0))


def _check_physical(traj: Trajectory, scenario: Scenario) -> Trajectory:
    """``traj``, or a copy cut at its first NaN or non-physical speed with status unstable."""
    bad = ~np.all(np.isfinite(traj.theta), axis=1)
    known = np.all(np.isfinite(traj.x), axis=0) & np.all(np.isfinite(traj.z), axis=0)
    partly = np.any(np.isfinite(traj.x), axis=0) & ~known
    if np.any(partly):  # positions reported, then lost: NaN in the run
        bad |= np.any(~np.isfinite(traj.x[:, partly]) | ~np.isfinite(traj.z[:, partly]), axis=1)
    if np.any(bad):
        i = int(np.argmax(bad))
        return _cut(traj, i, Status.UNSTABLE, f"NaN or infinite pose at t = {traj.t[i]:.4g} s")
    if traj.t.size < 2:
        return traj
    bound = SpeedBound.for_scenario(scenario)
    dt = np.diff(traj.t)
    turn = (np.abs(np.diff(np.unwrap(traj.theta, axis=0), axis=0)) if traj.planar
            else _turns(traj))
    spin = turn / dt[:, None]
    fast = np.any(spin > bound.omega_max, axis=1)
    if np.any(known):
        dx = np.diff(traj.x[:, known], axis=0)
        dz = np.diff(traj.z[:, known], axis=0)
        fast |= np.any(np.hypot(dx, dz) / dt[:, None] > bound.v_max, axis=1)
    if not np.any(fast):
        return traj
    k = int(np.argmax(fast))
    xz = None
    if np.all(known):
        xz = np.column_stack([traj.x[k + 1] - traj.x[k], traj.z[k + 1] - traj.z[k]])
    msg = bound.violation(float(dt[k]), xz, turn[k]) or "explosion: non-physical speed"
    return _cut(traj, k + 1, Status.UNSTABLE, f"{msg} at t = {traj.t[k + 1]:.4g} s")


def _cut(traj: Trajectory, i: int, status: Status, message: str) -> Trajectory:
    n = i + 1
    return replace(traj, t=traj.t[:n], theta=traj.theta[:n], x=traj.x[:n], z=traj.z[:n],
                   wobble=traj.wobble[:n], y=traj.y[:n], roll=traj.roll[:n],
                   twist=traj.twist[:n], status=status, message=message)
