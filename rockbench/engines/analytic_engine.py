"""``--engine analytic``: the analytic references behind the engine interface.

A thin adapter so that the CLI, the report and the matrix treat the reference
like any engine. It overrides :meth:`simulate` because there is no time
stepping to share; everything else follows the engine contract.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

import rockbench
from rockbench import analytic
from rockbench.engines.base import Capabilities, Engine
from rockbench.engines.settings import EngineSettings
from rockbench.errors import UnsupportedScenario
from rockbench.scenarios import Scenario
from rockbench.trajectory import Status, Trajectory

__all__ = ["AnalyticEngine", "AnalyticSettings"]


@dataclass(frozen=True)
class AnalyticSettings(EngineSettings):
    """Knobs of the analytic reference (its tolerances are fixed: rtol 1e-10).

    Attributes
    ----------
    linear : bool
        Housner's linearised equation for single blocks (slender-block theory).
    """

    linear: bool = False


class AnalyticEngine(Engine):
    """Housner (one block) and the two-block model of Psycharis / Spanos et al."""

    name: ClassVar[str] = "analytic"
    capabilities: ClassVar[Capabilities] = Capabilities(dimensions=2, max_blocks=2,
                                                        analytic=True)
    Settings: ClassVar[type[EngineSettings]] = AnalyticSettings
    presets: ClassVar[dict] = {"accurate": {}, "fast": {}, "linear": {"linear": True}}

    @classmethod
    def version(cls) -> str:
        return rockbench.__version__

    def _check_supported(self, scenario: Scenario) -> None:
        if not analytic.has_reference(scenario):
            raise UnsupportedScenario(
                "analytic references exist for one block or two centred stacked blocks only"
            )

    def simulate(self, scenario: Scenario, settings: Any = None) -> Trajectory:  # noqa: D102
        s = self.resolve_settings(settings)
        meta = dict(engine=self.name, engine_version=self.version(), settings=s.to_dict(),
                    scenario=scenario.name)
        try:
            self.check_supported(scenario)
        except UnsupportedScenario as exc:
            return Trajectory.failed(Status.UNSUPPORTED, str(exc), n_blocks=scenario.n_blocks,
                                     **meta)
        start = time.perf_counter()
        try:
            traj = analytic.reference(scenario, linear=s.linear)
        except UnsupportedScenario as exc:
            return Trajectory.failed(Status.UNSUPPORTED, str(exc), n_blocks=scenario.n_blocks,
                                     **meta)
        traj.engine, traj.engine_version = self.name, self.version()
        traj.settings = {**traj.settings, **meta["settings"]}
        traj.wall_time = time.perf_counter() - start
        return traj

    # the hooks are never reached: simulate() is overridden above
    def _build(self, scenario: Scenario, settings: EngineSettings) -> float:
        raise NotImplementedError

    def _drive_base(self, t: float, dt: float) -> None:
        raise NotImplementedError

    def _advance(self, n: int) -> None:
        raise NotImplementedError

    def _read_poses(self) -> np.ndarray:
        raise NotImplementedError
