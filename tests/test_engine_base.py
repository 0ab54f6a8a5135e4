"""The Engine template method: sampling, driving, status detection, settings, registry."""

import math
import sys
from dataclasses import dataclass

import numpy as np
import pytest

from rockbench.bounds import check_trajectory
from rockbench.engines import (
    Capabilities,
    Engine,
    EngineSettings,
    SettingsError,
    angles_from_quaternions,
    engine_class,
    get_engine,
    list_engines,
    orientation_from_quaternions,
    parse_set_options,
    register,
    resolve_engine_names,
    unregister,
)
from rockbench.engines.base import OVERTURN_MARGIN, Watchdog, install_hint
from rockbench.engines.drive import BaseDrive
from rockbench.errors import EngineUnavailable, UnknownEngine
from rockbench.geometry import Geometry, Support, stack
from rockbench.scenarios import Block, Scenario, SinePulse
from rockbench.trajectory import Status, Trajectory


@dataclass(frozen=True)
class CarrySettings(EngineSettings):
    """Knobs of the test engine."""

    timestep: float = 1e-3
    spin: float = 0.0  # prescribed rocking rate (rad/s), to provoke overturning
    poison_at: float = math.inf  # time from which poses are NaN
    fly_at: float = math.inf  # time from which block 1 is thrown far away
    rise_at: float = math.inf  # time from which block 1 is lifted (energy gain)
    jump_at: float = math.inf  # time from which block 1 is shifted 0.5 m along x (speed)


class CarryEngine(Engine):
    """A stand-in engine: blocks ride rigidly on the base, optionally spinning."""

    name = "carry"
    capabilities = Capabilities(dimensions=2, max_blocks=2, chamfer=False)
    Settings = CarrySettings
    presets = {"accurate": {}, "fast": {"timestep": 0.005}}

    @classmethod
    def version(cls) -> str:
        return "1.0"

    def _build(self, scenario, settings):
        self.sc, self.s = scenario, settings
        p0 = scenario.initial_poses()
        self.c0, self.th0 = p0[:, :2], p0[:, 2]
        self.t = 0.0
        self.u = 0.0
        self.drives: list[float] = []
        self.fixed = False
        self.out = np.zeros((scenario.n_blocks, 7))
        return settings.timestep

    def _drive_base(self, t, dt):
        self.drives.append(t)
        self.u = float(self.drive.displacement(t + dt)[0])

    def _fix_base(self):
        self.fixed = True
        return True

    def _advance(self, n):
        self.t += n * self.s.timestep

    def _read_poses(self):
        th = self.th0 + self.s.spin * self.t
        self.out[:, 0] = self.c0[:, 0] + self.u
        self.out[:, 2] = self.c0[:, 1]
        self.out[:, 3] = np.cos(th / 2)
        self.out[:, 5] = np.sin(th / 2)
        if self.t >= self.s.poison_at:
            self.out[0, 0] = np.nan
        if self.t >= self.s.fly_at:
            self.out[0, 0] = 1e3
        if self.t >= self.s.jump_at:  # 0.5 m within one sample, yet still in the scene
            self.out[0, 0] += 0.5
        if self.t >= self.s.rise_at:  # a slow, steady lift: energy from nowhere
            self.out[0, 2] += 0.5 * (self.t - self.s.rise_at)
        return self.out


B = Block(0.5, 0.2, 1.0, mass=1.0)


@pytest.fixture
def carry():
    register("carry", CarryEngine)
    yield get_engine("carry")
    unregister("carry")


def test_quaternion_angles_sign_convention():
    th = 0.3
    q = np.array([math.cos(th / 2), 0.0, math.sin(th / 2), 0.0])  # rotation about +y
    theta, wobble = angles_from_quaternions(q)
    assert theta == pytest.approx(th) and wobble == pytest.approx(0.0)
    # about +y by θ moves the body's z axis toward +x: R02 = sin θ > 0
    q_x = np.array([math.cos(0.05), math.sin(0.05), 0.0, 0.0])  # about x: wobble only
    theta, wobble = angles_from_quaternions(q_x)
    assert theta == pytest.approx(0.0, abs=1e-12) and wobble == pytest.approx(0.1)


def test_orientation_of_rotations_about_each_axis_and_combined():
    c, s = math.cos, math.sin
    about_y = np.array([c(0.15), 0.0, s(0.15), 0.0])  # θ = 0.3 about +y
    o = orientation_from_quaternions(about_y)
    assert (o.theta, o.roll, o.twist) == pytest.approx((0.3, 0.0, 0.0), abs=1e-15)
    about_x = np.array([c(0.1), s(0.1), 0.0, 0.0])  # 0.2 about +x: the top toward −y
    o = orientation_from_quaternions(about_x)
    assert (o.theta, o.roll, o.twist, o.wobble) == pytest.approx((0.0, 0.2, 0.0, 0.2),
                                                                 abs=1e-15)
    about_z = np.array([c(0.35), 0.0, 0.0, s(0.35)])  # 0.7 about +z: twist only
    o = orientation_from_quaternions(about_z)
    assert (o.theta, o.roll, o.twist) == pytest.approx((0.0, 0.0, 0.7), abs=1e-15)
    # a twist of 0.7 then a lean of 0.3 toward +x (world frame): the lean is unchanged and
    # the twist is the rotation about the body's own axis
    w1, v1 = about_y[0], about_y[1:]
    w2, v2 = about_z[0], about_z[1:]
    q = np.array([w1 * w2 - v1 @ v2, *(w1 * v2 + w2 * v1 + np.cross(v1, v2))])
    o = orientation_from_quaternions(q)
    assert (o.theta, o.roll) == pytest.approx((0.3, 0.0), abs=1e-12)
    assert o.twist == pytest.approx(0.7, abs=1e-12)
    # the twist is wrapped to (−π, π]: −q is the same rotation
    assert orientation_from_quaternions(-about_z).twist == pytest.approx(0.7, abs=1e-12)


def test_samples_at_output_rate_and_drives_each_step(carry):
    sc = Scenario("p", B, excitation=SinePulse(5.0, 0.002), duration=0.5, output_rate=100.0)
    traj = carry.simulate(sc)
    assert traj.status is Status.OK
    np.testing.assert_allclose(traj.t, np.arange(51) / 100.0)
    # the base is driven before every step while it moves, then fixed and batched
    assert carry.drives[:3] == pytest.approx([0.0, 0.001, 0.002])
    assert carry.fixed and max(carry.drives) == pytest.approx(0.2, abs=0.011)
    assert traj.x[-1, 0] == pytest.approx(sc.excitation.displacement(1.0), rel=1e-9)
    assert traj.engine == "carry" and traj.engine_version == "1.0"
    assert traj.settings["steps_per_sample"] == 10
    assert traj.wall_time > 0


def test_overturning_nan_explosion_and_energy_gain_become_statuses(carry):
    sc = Scenario("f", B, initial_tilt=0.5, duration=2.0, output_rate=100.0)
    over = carry.simulate(sc, {"spin": 2.0})
    assert over.status is Status.OVERTURNED and "block 1" in over.message
    assert abs(over.theta[-1, 0]) >= math.pi / 2 and over.t[-1] < 1.0
    assert carry.simulate(sc, {"poison_at": 0.5}).status is Status.UNSTABLE
    fast = carry.simulate(sc, {"spin": 60.0})  # beyond any free-fall rotation rate
    assert fast.status is Status.UNSTABLE and "rocking rate" in fast.message
    assert fast.t[-1] == pytest.approx(0.01)  # the first sample, against the start pose
    fly = carry.simulate(sc, {"fly_at": 0.5})
    assert fly.status is Status.UNSTABLE and "explosion" in fly.message
    rise = carry.simulate(sc, {"rise_at": 0.5})
    assert rise.status is Status.UNSTABLE and "energy" in rise.message
    assert 0.5 < rise.t[-1] < 0.55


@pytest.mark.parametrize("at", [0.1, Watchdog.PERIOD, Watchdog.PERIOD + 0.01, 1.99])
def test_watchdog_cuts_at_the_first_bad_sample_across_chunks(carry, at):
    # the watchdog checks chunks of PERIOD seconds of samples: a jump into the
    # first sample of a chunk is seen against the last sample of the one before
    sc = Scenario("f", B, initial_tilt=0.5, duration=2.0, output_rate=100.0)
    assert carry.simulate(sc).status is Status.OK
    jump = carry.simulate(sc, {"jump_at": at - 1e-6})
    assert jump.status is Status.UNSTABLE and "centroid speed" in jump.message
    assert jump.t[-1] == pytest.approx(at) and f"t = {at:.4g} s" in jump.message
    nan = carry.simulate(sc, {"poison_at": at - 1e-6})
    assert "NaN" in nan.message and nan.t[-1] == pytest.approx(at)


def test_watchdog_sees_nan_in_every_pose_component():
    # y and the wobble components enter no physical bound; NaN there is still caught
    sc = Scenario("f", B, initial_tilt=0.5, duration=1.0, output_rate=100.0)
    p0 = sc.initial_poses()
    c, th = p0[:, :2], float(p0[0, 2])
    poses = np.zeros((11, 1, 7))
    poses[:, 0, 0], poses[:, 0, 2] = c[0, 0], c[0, 1]
    poses[:, 0, 3], poses[:, 0, 5] = math.cos(th / 2), math.sin(th / 2)
    t = np.arange(1, 11) / 100.0
    drive = BaseDrive(sc.motion, sc.duration)
    assert Watchdog(sc, drive).check(poses, t) is None
    for col in range(7):
        bad = poses.copy()
        bad[4, 0, col] = np.nan
        with np.errstate(invalid="ignore"):
            j, (status, msg) = Watchdog(sc, drive).check(bad, t)
        assert (j, status) == (3, Status.UNSTABLE) and "NaN" in msg, col


def test_an_engine_that_cannot_hold_the_base_keeps_driving_it(carry):
    class Unfixed(CarryEngine):
        def _fix_base(self):
            return False

    eng = Unfixed()
    sc = Scenario("p", B, excitation=SinePulse(5.0, 0.002), duration=0.5, output_rate=100.0)
    traj = eng.simulate(sc)
    assert traj.status is Status.OK and traj.t.size == 51
    assert len(eng.drives) == 500 and max(eng.drives) == pytest.approx(0.499)


def test_unsupported_is_a_status(carry):
    three = Scenario("s", stack((B, B, B)), duration=0.1)
    traj = carry.simulate(three)
    assert traj.status is Status.UNSUPPORTED and "at most 2" in traj.message
    chamfered = Scenario("c", Block(0.5, 0.2, 1.0, mass=1.0, chamfer=0.01), duration=0.1)
    assert carry.simulate(chamfered).status is Status.UNSUPPORTED


def test_settings_presets_and_overrides(carry):
    assert carry.settings("fast").timestep == 0.005
    s = carry.settings(None, timestep="0.002", spin="1")
    assert s.timestep == 0.002 and s.spin == 1.0
    assert s.digest() != carry.settings().digest()
    # user-facing: the engine's name and its knobs, no class names
    with pytest.raises(SettingsError, match="^engine 'carry' has no knob 'dt'; knobs: ") as bad:
        carry.settings(None, dt=1)
    assert "spin" in str(bad.value) and "Settings" not in str(bad.value)
    with pytest.raises(SettingsError, match="no preset"):
        carry.settings("slow")
    with pytest.raises(SettingsError, match="must be a number"):
        carry.settings(None, timestep="abc")
    assert parse_set_options(["carry.timestep=1e-4", "mujoco.preset=fast"]) == {
        "carry": {"timestep": "1e-4"}, "mujoco": {"preset": "fast"}}
    with pytest.raises(SettingsError):
        parse_set_options(["timestep=3"])


def test_registry_names_and_errors(carry):
    assert "carry" in [i.name for i in list_engines()]
    assert engine_class("reference").name == "analytic"
    with pytest.raises(UnknownEngine, match="did you mean 'carry'"):
        engine_class("cary")
    assert resolve_engine_names("carry,analytic") == ["carry", "analytic"]
    assert "carry" in resolve_engine_names("all")
    register("broken", "rockbench.engines.no_such_module:Nothing")
    try:
        with pytest.raises(EngineUnavailable, match="broken"):
            engine_class("broken")
        info = {i.name: i for i in list_engines()}["broken"]
        assert not info.available and "pip install" in info.reason
        assert "broken" not in resolve_engine_names("all")
    finally:
        unregister("broken")


def test_steps_longer_than_the_output_interval_are_refused(carry):
    sc = Scenario("spin", B, initial_tilt=0.1, duration=0.6, output_rate=100.0)
    with pytest.raises(SettingsError, match="longer than the output interval"):
        carry.simulate(sc, {"timestep": 0.03, "spin": 0.5})


@pytest.mark.parametrize("dt", [3e-3, 7e-3])
def test_steps_that_do_not_divide_the_output_interval_are_interpolated(carry, dt):
    # a block spinning at a constant rate: interpolated samples must sit exactly
    # on θ0 + ω t at the requested output times, with no drift of the clock
    sc = Scenario("spin", B, initial_tilt=0.1, duration=0.6, output_rate=100.0)
    traj = carry.simulate(sc, {"timestep": dt, "spin": 0.5})
    np.testing.assert_allclose(traj.t, np.arange(61) / 100.0)
    np.testing.assert_allclose(traj.theta[:, 0], sc.theta0 + 0.5 * traj.t, atol=1e-3)


def _poses(xz_theta: list[tuple[float, float, float]]) -> np.ndarray:
    """One sample of poses (x, y, z, w, qx, qy, qz) from (x, z, θ) per block."""
    return np.array([[x, 0.0, z, math.cos(0.5 * th), 0.0, math.sin(0.5 * th), 0.0]
                     for x, z, th in xz_theta])


def test_the_watchdog_stops_a_run_where_unmodelled_bodies_overlap() -> None:
    # two blocks 1 cm apart beside a support; pairs named unmodelled: block 1 and block 2,
    # block 2 and the support (body 2), block 1 and the base (body 3)
    scene = Geometry((Block(0.2, 0.2, 0.8, mass=1.0), Block(0.4, 0.2, 0.4, mass=1.0)),
                     ((-0.11, 0.4, 0.0), (0.21, 0.2, 0.0)),
                     (Support.rectangle(0.42, 0.6, 0.0, 0.3),))
    # a base that barely moves (no energy check) and samples far apart (no speed bound)
    sc = Scenario("gap", scene, excitation=SinePulse(2.0, 1e-9), duration=1.0,
                  output_rate=10.0)
    rest = _poses([(-0.11, 0.4, 0.0), (0.21, 0.2, 0.0)])
    drive = BaseDrive(sc.motion, sc.duration)
    watch = Watchdog(sc, drive, ((0, 1), (1, 2), (0, 3)))
    chunk = np.repeat(rest[None], 5, axis=0)
    assert watch.check(chunk, np.arange(1, 5) * 0.1) is None
    # block 1 turned by 0.1 rad about its lower right corner reaches 2.1 cm into block 2
    # (0.8 · sin 0.1 − 1 cm, less the corner's drop): stopped there, named
    leaning = _poses([(-0.01 - 0.1 * math.cos(0.1) + 0.4 * math.sin(0.1),
                       0.1 * math.sin(0.1) + 0.4 * math.cos(0.1), 0.1), (0.21, 0.2, 0.0)])
    chunk[3] = leaning
    j, (status, message) = watch.check(chunk, np.arange(1, 5) * 0.1)
    assert (j, status) == (2, Status.UNSTABLE)
    assert "block 1 and block 2 overlap" in message and "t = 0.3 s" in message
    # block 2 slid 2 cm, 1 cm into the support; block 1 sunk 1 cm into the base
    for poses, what in (([(-0.11, 0.4, 0.0), (0.23, 0.2, 0.0)], "block 2 and support 1"),
                        ([(-0.11, 0.39, 0.0), (0.21, 0.2, 0.0)], "block 1 and the base")):
        chunk[3] = _poses(poses)
        found = watch.check(chunk, np.arange(1, 5) * 0.1)
        assert found is not None and f"{what} overlap by 0.01 m" in found[1][1], found
    # pairs the engine models are not watched
    assert Watchdog(sc, drive).check(chunk, np.arange(1, 5) * 0.1) is None


def _falling_about_x(n: int, rate: float, h: float) -> tuple[np.ndarray, np.ndarray]:
    """Poses of B (0.5 × 0.2 × 1 m) turning about its −y bottom edge at ``rate`` rad/s,
    sampled every ``h`` s, with a hint of θ so that R₀₂ is not exactly 0."""
    t = np.arange(n) * h
    phi = rate * t  # about +x: the top moves toward −y
    th = 1e-4
    q = np.zeros((n, 1, 7))
    cy, sy = math.cos(th / 2), math.sin(th / 2)
    # about x by φ, after a tiny θ about y
    q[:, 0, 3] = np.cos(phi / 2) * cy
    q[:, 0, 4] = np.sin(phi / 2) * cy
    q[:, 0, 5] = np.cos(phi / 2) * sy
    q[:, 0, 6] = -np.sin(phi / 2) * sy
    # the centroid (0.1 m from the edge across, 0.5 m up) turns about the edge at y = −0.1
    q[:, 0, 1] = -0.1 + 0.1 * np.cos(phi) - 0.5 * np.sin(phi)
    q[:, 0, 2] = 0.1 * np.sin(phi) + 0.5 * np.cos(phi)
    return q, t


def test_a_block_falling_about_x_is_overturned_not_unstable():
    # θ = atan2(R02, R22) swings wildly as R22 → 0 in a fall about x; the rotation per
    # sample is measured about any axis (2 acos |q0 · q1|), so the watchdog and the
    # trajectory check both see a fall at a physical rate, then the overturn
    # (a shaken base: the turn is driven, no energy bound applies)
    sc = Scenario("fall", B, excitation=SinePulse(5.0, 1e-4), duration=2.0, output_rate=100.0)
    drive = BaseDrive(sc.motion, sc.duration)
    poses, t = _falling_about_x(200, 1.5, 0.01)
    j, (status, message) = Watchdog(sc, drive).check(poses, t[1:])
    assert status is Status.OVERTURNED and "overturned" in message
    # the sample where the tilt first reaches π/2 − OVERTURN_MARGIN
    assert 1.5 * t[j + 1] == pytest.approx(math.pi / 2 - OVERTURN_MARGIN, abs=0.015)
    o = orientation_from_quaternions(poses[: j + 2, :, 3:])
    traj = Trajectory(t=t[: j + 2], theta=o.theta, x=poses[: j + 2, :, 0],
                      z=poses[: j + 2, :, 2], wobble=o.wobble, y=poses[: j + 2, :, 1],
                      roll=o.roll, twist=o.twist, status=Status.OVERTURNED)
    assert np.max(np.abs(np.diff(traj.theta[:, 0]))) > 0.1  # θ itself jumps
    assert check_trajectory(traj, sc) is traj  # nothing non-physical about it


def test_the_install_hint_names_the_python_an_extra_needs():
    # Box2D's and Jolt's wheels exist for Python >= 3.12, bpy 5.0 for 3.11 only: their
    # extras install nothing elsewhere, and the hint says so (from rockbench's metadata)
    here = sys.version_info[:2]
    for extra, module in (("box2d", "box2d"), ("jolt", "culverin")):
        hint = install_hint(extra, module)
        assert hint.startswith(f"pip install 'rockbench[{extra}]'")
        assert ("under Python ≥ 3.12" in hint) == (here < (3, 12)), hint
    assert ("under Python 3.11 (this is" in install_hint("blender", "bpy")) == (here != (3, 11))
    assert install_hint("mujoco", "mujoco") == "pip install 'rockbench[mujoco]'"
    assert install_hint("", "thelib") == "pip install thelib"
