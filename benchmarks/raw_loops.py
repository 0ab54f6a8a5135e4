"""Minimal raw loops: each engine stepped by the cheapest direct library calls.

Each loop builds the scene with the engine plugin's own ``_build`` (so the scene,
the time step and the precomputed base kinematics are identical to
:meth:`Engine.simulate`), then steps it with plain library calls bound to local
names, writes the block poses into one preallocated array at the output rate
only, and converts them to θ once at the end. The base is driven with the same
values as the adapter: the plugin's own precomputed base kinematics, or, where
the plugin samples them lazily, the same :class:`~rockbench.engines.drive.BaseDrive`
(set on the engine before ``_build``, as ``simulate()`` does) sampled on the same
step grid as the engine module (bit-identical trajectories are expected; the
benchmark checks it); and held still with the plugin's own ``_fix_base`` once the
base motion has ended (at the same sample as the adapter does).

The ratio ``simulate() wall / raw wall`` is the adapter's overhead: the
template loop, hook dispatch, per-step ``_drive_base`` bookkeeping and the
watchdog. Only whole-step (aligned) output sampling is covered: every preset of
every engine divides the 1 kHz output interval.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from rockbench.engines import angles_from_quaternions, get_engine
from rockbench.engines.drive import BaseDrive
from rockbench.scenarios import Scenario

__all__ = ["RAW_LOOPS", "run_raw", "driven_samples"]


def driven_samples(scenario: Scenario, dt: float, k: int) -> int:
    """Number of output samples during which the base is driven (as the base loop does).

    ``Engine._sample_aligned`` drives sample after sample and fixes the base after
    the first sample whose end ``i·k·dt`` is past the base drive's ``end_time``.
    """
    drive = BaseDrive(scenario.motion, scenario.duration)
    n_out = scenario.output_times().size
    if not drive.moving:
        return 0
    end = drive.end_time
    if not math.isfinite(end):
        return n_out - 1
    for i in range(1, n_out):
        if i * k * dt > end:
            return i
    return n_out - 1


# ---------------------------------------------------------------------- MuJoCo
def _mujoco(eng: Any, sc: Scenario, dt: float, k: int, poses: np.ndarray) -> None:
    import mujoco

    m, d, step = eng._model, eng._data, mujoco.mj_step
    nb = sc.n_blocks
    view = d.qpos[: 7 * nb].reshape(nb, 7)
    n_out = poses.shape[0]
    ns = driven_samples(sc, dt, k)
    if ns:
        # the plugin's chunks (``_load_chunk``): u, v at (start + i)·dt, force from diff(v)
        drive = eng.drive
        t = drive.grid(dt, ns * k + 1)
        v = drive.velocity(t)[:, 0]
        u = drive.displacement(t)[:, 0].tolist()
        f = (eng._mbase * np.diff(v) / dt).tolist()
        v = v.tolist()
        qpos, qvel, qfrc, jq, jv = d.qpos, d.qvel, d.qfrc_applied, eng._jq, eng._jv
        j = 0
        for i in range(1, ns + 1):
            for uu, vv, ff in zip(u[j:j + k], v[j:j + k], f[j:j + k], strict=True):
                qpos[jq] = uu
                qvel[jv] = vv
                qfrc[jv] = ff
                step(m, d)
            j += k
            poses[i] = view
        eng._fix_base()
    for i in range(ns + 1, n_out):
        step(m, d, k)
        poses[i] = view


# ---------------------------------------------------------------------- pybullet
def _bullet(eng: Any, sc: Scenario, dt: float, k: int, poses: np.ndarray,
            position_reset: bool = True) -> None:
    import pybullet as pb

    from rockbench.engines.bullet_engine import _substeps_exact

    cid, bodies, g, gz = eng._cid, eng._bodies, eng._ground, eng._ground_z
    stepsim, getpose = pb.stepSimulation, pb.getBasePositionAndOrientation
    n_out = poses.shape[0]
    ns = driven_samples(sc, dt, k)
    nb = len(bodies)

    def read(i: int) -> None:
        for b in range(nb):
            (x, y, z), (qx, qy, qz, qw) = getpose(bodies[b], cid)
            poses[i, b] = (x, y, z, qw, qx, qy, qz)

    if ns:
        reset_pose, reset_vel = pb.resetBasePositionAndOrientation, pb.resetBaseVelocity
        u, v = eng._u, eng._v
        ident, zero = (0.0, 0.0, 0.0, 1.0), (0.0, 0.0, 0.0)
        j = 0
        for i in range(1, ns + 1):
            for uu, vv in zip(u[j:j + k], v[j:j + k], strict=True):
                if position_reset:
                    reset_pose(g, (uu, 0.0, gz), ident, cid)
                reset_vel(g, (vv, 0.0, 0.0), zero, cid)
                stepsim(cid)
            j += k
            read(i)
        eng._fix_base()
    if ns + 1 < n_out:
        if _substeps_exact(k, dt):
            pb.setPhysicsEngineParameter(fixedTimeStep=k * dt, numSubSteps=k,
                                         physicsClientId=cid)
            for i in range(ns + 1, n_out):
                stepsim(cid)
                read(i)
        else:
            for i in range(ns + 1, n_out):
                for _ in range(k):
                    stepsim(cid)
                read(i)


def _bullet_velocity_only(eng: Any, sc: Scenario, dt: float, k: int, poses: np.ndarray) -> None:
    """pybullet driven by the base velocity only (Bullet integrates the base position)."""
    _bullet(eng, sc, dt, k, poses, position_reset=False)


# ---------------------------------------------------------------------- DART
def _dart(eng: Any, sc: Scenario, dt: float, k: int, poses: np.ndarray) -> None:
    step, skels = eng._world.step, eng._skels
    n_out = poses.shape[0]
    ns = driven_samples(sc, dt, k)
    nb = len(skels)
    raw = np.empty((n_out, nb, 6))  # rotation vector + translation, converted at the end
    raw[0] = [sk.getPositions() for sk in skels]
    getp = [sk.getPositions for sk in skels]
    if ns:
        setc, cmd = eng._set_command, eng._cmd
        j = 0
        for i in range(1, ns + 1):
            for c in cmd[j:j + k]:
                setc(0, c)
                step()
            j += k
            for b in range(nb):
                raw[i, b] = getp[b]()
        eng._fix_base()
    rk = range(k)
    for i in range(ns + 1, n_out):
        for _ in rk:
            step()
        for b in range(nb):
            raw[i, b] = getp[b]()
    rv = raw[..., :3]
    a = np.linalg.norm(rv, axis=-1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        scale = np.where(a > 1e-12, np.sin(0.5 * a) / np.where(a > 0, a, 1.0), 0.5)
    poses[..., :3] = raw[..., 3:]
    poses[..., 3:4] = np.cos(0.5 * a)
    poses[..., 4:] = rv * scale


# ---------------------------------------------------------------------- pymunk
def _pymunk(eng: Any, sc: Scenario, dt: float, k: int, poses: np.ndarray) -> None:
    from pymunk._chipmunk import lib

    step, ptr = lib.cpSpaceStep, eng._space_ptr
    get_pos, get_angle = lib.cpBodyGetPosition, lib.cpBodyGetAngle
    bps = eng._body_ptrs
    n_out = poses.shape[0]
    ns = driven_samples(sc, dt, k)
    nb = len(bps)
    rows: list[tuple[float, float, float]] = []  # x, z, angle; converted at the end
    add = rows.append

    def read() -> None:
        for bp in bps:
            p = get_pos(bp)
            add((p.x, p.y, get_angle(bp)))

    read()
    if ns:
        if eng._uz_list is not None:
            raise ValueError("the raw pymunk loop drives the base along x only")
        set_pos, set_vel, bptr = lib.cpBodySetPosition, lib.cpBodySetVelocity, eng._base._body
        last = len(eng._v_mid) - 1
        idx = np.minimum(np.arange(ns * k), last)
        # the plugin's precomputed base x: u at the step start, v at mid-step
        u, v = eng._u_start[idx, 0].tolist(), eng._v_mid[idx, 0].tolist()
        j = 0
        for _ in range(ns):
            for uu, vv in zip(u[j:j + k], v[j:j + k], strict=True):
                set_pos(bptr, (uu, 0.0))
                set_vel(bptr, (vv, 0.0))
                step(ptr, dt)
            j += k
            read()
        eng._fix_base()
    rk = range(k)
    for _ in range(ns + 1, n_out):
        for _ in rk:
            step(ptr, dt)
        read()
    raw = np.array(rows).reshape(n_out, nb, 3)
    half = -0.5 * raw[..., 2]
    poses[..., 0] = raw[..., 0]
    poses[..., 1] = 0.0
    poses[..., 2] = raw[..., 1]
    poses[..., 3] = np.cos(half)
    poses[..., 4] = 0.0
    poses[..., 5] = np.sin(half)
    poses[..., 6] = 0.0


# ---------------------------------------------------------------------- Drake
def _drake(eng: Any, sc: Scenario, dt: float, k: int, poses: np.ndarray) -> None:
    sim, state, idx = eng._sim, eng._state, eng._idx
    advance = sim.AdvanceTo
    n_out = poses.shape[0]
    ns = driven_samples(sc, dt, k)
    if ns:
        # the plugin's chunks: u at i·dt, v at (i + φ)·dt (φ = base_velocity_phase)
        drive, joint, pc = eng.drive, eng._joint, eng._pc
        u = drive.displacement(drive.grid(dt, ns * k))[:, 0].tolist()
        v = drive.velocity(drive.grid(dt, ns * k, phase=eng._phase))[:, 0].tolist()
        set_x, set_v = joint.set_translation, joint.set_translation_rate
        j = 0
        for i in range(1, ns + 1):
            for uu, vv in zip(u[j:j + k], v[j:j + k], strict=True):
                set_x(pc, uu)
                set_v(pc, vv)
                j += 1
                advance(j * dt)
            np.take(state.value(), idx, out=poses[i])
        eng._fix_base()
    for i in range(ns + 1, n_out):
        advance(i * k * dt)
        np.take(state.value(), idx, out=poses[i])


# ---------------------------------------------------------------------- dem2d
def _dem2d(eng: Any, sc: Scenario, dt: float, k: int, poses: np.ndarray) -> None:
    from rockbench.engines import dem2d_kernels as K

    # the same compiled multi-sample kernel as the plugin: one call for the driven
    # samples, one for the rest (the kernel writes the poses itself)
    sample, args = K.sample, eng._args
    n_out = poses.shape[0]
    ns = driven_samples(sc, dt, k)
    if ns:
        # the plugin's base positions (``_base_positions``): u_x at i·dt
        drive = eng.drive
        u = np.ascontiguousarray(drive.displacement(drive.grid(dt, ns * k))[:, 0], float)
        sample(ns, k, dt, *args, u, poses[1:ns + 1])
        eng._fix_base()
    if ns + 1 < n_out:
        sample(n_out - ns - 1, k, dt, *args, eng._still, poses[ns + 1:])


# ---------------------------------------------------------------------- OpenSees
def _opensees(eng: Any, sc: Scenario, dt: float, k: int, poses: np.ndarray) -> None:
    # the UniformExcitation pattern carries the base acceleration inside ``analyze``: the
    # driven and the free samples are the same calls (``_fix_base`` is a no-op, as in the
    # plugin); a step Newton does not converge goes to the plugin's own fallback
    ops = eng._ops
    analyze, disp, get_time = ops.analyze, ops.nodeDisp, ops.getTime
    tags = eng._centroids
    n_out, nb = poses.shape[0], len(tags)
    raw = np.empty((n_out, nb, 3))  # ux, uz, r_z; converted at the end
    raw[0] = [disp(t) for t in tags]
    step = 0
    for i in range(1, n_out):
        target = i * k
        while step < target:
            if analyze(target - step, dt) == 0:
                step = target
                break
            step = int(round(get_time() / dt))
            eng._retry_step(ops, dt)
            step += 1
        for b in range(nb):
            raw[i, b] = disp(tags[b])
    u = np.asarray(eng._u, float)
    ub = u[np.minimum(np.arange(n_out) * k, u.size - 1)]
    half = -0.5 * raw[..., 2]
    poses[..., 0] = eng._x0 + raw[..., 0] + ub[:, None]
    poses[..., 1] = 0.0
    poses[..., 2] = eng._z0 + raw[..., 1]
    poses[..., 3] = np.cos(half)
    poses[..., 4] = 0.0
    poses[..., 5] = np.sin(half)
    poses[..., 6] = 0.0


# ---------------------------------------------------------------------- Blender
def _blender(eng: Any, sc: Scenario, dt: float, k: int, poses: np.ndarray) -> None:
    # one physics "step" of the plugin is one Blender frame (its sub-steps inside)
    frame_set = eng._scene.frame_set
    mats = [ob.matrix_world for ob in eng._blocks]
    n_out = poses.shape[0]
    ns = driven_samples(sc, dt, k)
    nb = len(mats)

    def read(i: int) -> None:
        for b in range(nb):
            m = mats[b]
            q, p = m.to_quaternion(), m.translation
            poses[i, b] = (p.x, p.y, p.z, q.w, q.x, q.y, q.z)

    if ns and (eng._motor is not None or eng._tilt):
        raise ValueError("the raw blender loop drives a kinematic base only")
    frame = 1
    if ns:
        # the base placed at the end of each frame before Blender steps into it (the
        # kinematic drive; a motor drive is not covered)
        loc, update, u = eng._base.location, eng._view_layer.update, eng._u
        last = len(u) - 1
        for i in range(1, ns + 1):
            for _ in range(k):
                loc.x = u[min(frame, last)]
                update()
                frame += 1
                frame_set(frame)
            read(i)
        eng._fix_base()
    for i in range(ns + 1, n_out):
        for _ in range(k):
            frame += 1
            frame_set(frame)
        read(i)


#: engine name → raw loop (scene built by the plugin's ``_build``).
RAW_LOOPS: dict[str, Callable[..., None]] = {
    "mujoco": _mujoco,
    "bullet": _bullet,
    "dart": _dart,
    "pymunk": _pymunk,
    "drake": _drake,
    "dem2d": _dem2d,
    "opensees": _opensees,
    "blender": _blender,
}
#: Extra raw variants that change the driving call (not bit-identical to the adapter).
RAW_VARIANTS: dict[str, tuple[str, Callable[..., None]]] = {
    "bullet": ("velocity only", _bullet_velocity_only),
}


def run_raw(name: str, scenario: Scenario, settings: Any = None,
            loop: Callable[..., None] | None = None) -> np.ndarray:
    """θ (n_out, n_blocks) of ``scenario`` on engine ``name`` by its raw loop.

    Raises
    ------
    KeyError
        No raw loop for this engine.
    ValueError
        The time step does not divide the output interval.
    """
    loop = loop or RAW_LOOPS[name]
    eng = get_engine(name)
    s = eng.resolve_settings(settings)
    n_out = scenario.output_times().size
    # what ``simulate()`` sets before ``_build``
    eng.drive = BaseDrive(scenario.motion, scenario.duration)
    try:
        dt = float(eng._build(scenario, s))
        ratio = 1.0 / (scenario.output_rate * dt)
        k = int(round(ratio))
        if not (k >= 1 and abs(ratio - k) <= 1e-6 * ratio):
            raise ValueError(f"{name}: time step {dt} does not divide the output interval")
        poses = np.empty((n_out, scenario.n_blocks, 7))
        poses[0] = eng._read_poses()
        loop(eng, scenario, dt, k, poses)
    finally:
        eng._teardown()
    theta, _ = angles_from_quaternions(poses[..., 3:])
    return theta
