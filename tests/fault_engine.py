"""A test-only engine plugin that injects faults on demand (never shipped to users).

Tests register it at run time::

    from rockbench.engines import register
    register("fault", FaultEngine)

and select the fault with its knobs, e.g. ``--set fault.fault=segfault``. Until
``at`` seconds of simulated time the stack simply stays at its initial pose.
"""

from __future__ import annotations

import ctypes
import faulthandler
import math
import os
import signal
import time
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from rockbench import analytic
from rockbench.engines import Capabilities, Engine, EngineSettings, KnobRole
from rockbench.scenarios import Scenario
from rockbench.trajectory import Trajectory

__all__ = ["FaultEngine", "FaultSettings", "FAULTS", "reference"]

#: Fault kinds and what they do at time ``at``.
FAULTS = {
    "none": "nothing: the stack stays at its initial pose",
    "exception": "raise RuntimeError",
    "segfault": "dereference a NULL pointer (SIGSEGV)",
    "abort": "SIGABRT, as a failed C assertion",
    "exit": "os._exit(3)",
    "hang": "sleep forever",
    "nan": "report NaN poses",
    "explode": "throw the top block 100 m away",
    "speed": "move the blocks at 40 m/s for 20 ms (stays in the scene)",
    "energy": "lift the blocks at 0.5 m/s (energy gain in free motion)",
}


@dataclass(frozen=True)
class FaultSettings(EngineSettings):
    """Knobs of the fault engine.

    Parameters
    ----------
    fault : str
        One of :data:`FAULTS`.
    at : float
        Simulated time (s) at which the fault strikes.
    timestep : float
        Step size (s); also a cost knob for sweeps.
    iterations : int
        Dummy solver iterations (a second sweep axis).
    follow : bool
        Follow the analytic reference with a relative error of
        ``10 · timestep / iterations`` instead of standing still.
    unstable_dt : float
        A timestep above this reports NaN poses from ``at`` on (a stability limit).
    crash_below : int
        Fewer iterations than this raise an exception at ``at``.
    """

    fault: str = "none"
    at: float = 0.05
    timestep: float = 1e-3
    iterations: int = 10
    follow: bool = False
    unstable_dt: float = math.inf
    crash_below: int = 0

    def __post_init__(self) -> None:
        if self.fault not in FAULTS:
            raise ValueError(f"fault must be one of {', '.join(FAULTS)}, got {self.fault!r}")


_REFS: dict[Scenario, Trajectory] = {}


def reference(scenario: Scenario) -> Trajectory:
    """The analytic reference, cached per scenario (warm it in the parent before forking)."""
    if scenario not in _REFS:
        _REFS[scenario] = analytic.reference(scenario)
    return _REFS[scenario]


class FaultEngine(Engine):
    """Holds the stack still, then fails as told by its ``fault`` knob."""

    name: ClassVar[str] = "fault"
    capabilities: ClassVar[Capabilities] = Capabilities(dimensions=2)
    Settings: ClassVar[type[EngineSettings]] = FaultSettings
    presets: ClassVar[dict[str, dict[str, object]]] = {
        "accurate": {}, "fast": {"timestep": 2e-3},
    }
    knob_roles: ClassVar[dict[str, KnobRole]] = {"timestep": KnobRole.TIME_STEP,
                                                 "iterations": KnobRole.ITERATIONS}

    @classmethod
    def version(cls) -> str:
        return "0.0-test"

    def _build(self, scenario: Scenario, settings: EngineSettings) -> float:
        assert isinstance(settings, FaultSettings)
        self.s = settings
        self.t = 0.0
        p0 = scenario.initial_poses()
        self.pose = np.zeros((scenario.n_blocks, 7))
        self.pose[:, 0], self.pose[:, 2] = p0[:, 0], p0[:, 1]
        self.pose[:, 3], self.pose[:, 5] = np.cos(p0[:, 2] / 2), np.sin(p0[:, 2] / 2)
        self.scenario = scenario
        self.dt = float(settings.timestep)
        self.ref = None
        if settings.follow:
            self.ref = reference(scenario)
            self.gain = 1.0 + 10.0 * settings.timestep / settings.iterations
        return self.dt

    def _drive_base(self, t: float, dt: float) -> None:
        pass

    def _advance(self, n: int) -> None:
        time.sleep(1e-5 * n * self.s.iterations)  # a cost that grows with the knobs
        t0, self.t = self.t, self.t + n * self.dt
        if self.t < self.s.at:
            return
        f = self.s.fault
        if self.s.timestep > self.s.unstable_dt:
            f = "nan"
        if self.s.iterations < self.s.crash_below:
            f = "exception"
        if f == "exception":
            raise RuntimeError("injected fault")
        if f in ("segfault", "abort"):
            faulthandler.disable()  # keep pytest's crash dump out of the test log
        if f == "segfault":
            ctypes.string_at(0)
        if f == "abort":
            os.kill(os.getpid(), signal.SIGABRT)
        if f == "exit":
            os._exit(3)
        if f == "hang":
            while True:
                time.sleep(1.0)
        if f == "nan":
            self.pose[:] = np.nan
        if f == "explode":
            self.pose[-1, 0] += 100.0
        span = self.t - max(t0, self.s.at)
        if f == "speed" and self.t <= self.s.at + 0.02 + 1e-12:
            self.pose[:, 0] += 40.0 * span
        if f == "energy":
            self.pose[:, 2] += 0.5 * span

    def _read_poses(self) -> np.ndarray:
        if self.ref is not None and np.all(np.isfinite(self.pose)):
            th = np.array([np.interp(self.t, self.ref.t, self.ref.theta[:, i])
                           for i in range(self.pose.shape[0])]) * self.gain
            self.pose[:, 3], self.pose[:, 4] = np.cos(th / 2), 0.0
            self.pose[:, 5], self.pose[:, 6] = np.sin(th / 2), 0.0
            # the bottom block rocks on its pivots without sliding; the others ride on it
            b, sc = self.scenario.blocks[0], self.scenario
            s, t0 = np.sign(th[0]), th[0]
            u = float(self.drive.displacement(self.t)[0])
            px = u + s * b.pivot_half_width
            c = sc.geometry.centroids
            dx, dz = c[:, 0] - s * b.pivot_half_width, c[:, 1]
            self.pose[:, 0] = px + dx * np.cos(t0) + dz * np.sin(t0)
            self.pose[:, 2] = -dx * np.sin(t0) + dz * np.cos(t0)
        return self.pose.copy()
