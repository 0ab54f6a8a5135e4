"""``--engine analytic``: the analytic references behind the engine interface.

A thin adapter so that the CLI, the report and the matrix treat the reference
like any engine. It replaces the time-stepping loop (``Engine._run``) by the
reference solution; :meth:`~rockbench.engines.Engine.simulate` still resolves
the settings, refuses unsupported scenarios and times the run.

See :doc:`the engine's page </engines/analytic>` in the documentation for the
models it picks and their cost.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from rockbench import analytic, provenance
from rockbench.engines.base import Capabilities, Engine
from rockbench.engines.settings import EngineSettings
from rockbench.errors import UnsupportedScenario
from rockbench.scenarios import Scenario
from rockbench.trajectory import Trajectory

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
    """Housner (one block), the two-block model, Coulomb sliding and the rolling cylinder."""

    name: ClassVar[str] = "analytic"
    capabilities: ClassVar[Capabilities] = Capabilities(
        dimensions=2, max_blocks=2, analytic=True, base_axes="xyz", cylinders=True,
        start3d=True, moving_start=True,
        no_assemblies="no dynamic closed form exists; an assembly's reference is its "
                      "limit-analysis collapse factor (rockbench collapse)")
    Settings: ClassVar[type[EngineSettings]] = AnalyticSettings
    presets: ClassVar[dict] = {"accurate": {}, "fast": {}, "linear": {"linear": True}}
    contact_model: ClassVar[str] = "analytic"
    # rockbench's own code on its core dependencies (NumPy, SciPy): nothing to install
    requires: ClassVar[tuple[str, ...]] = ()
    extra: ClassVar[str] = ""

    @classmethod
    def version(cls) -> str:
        return provenance.code_version("reference")

    def _check_supported(self, scenario: Scenario) -> None:
        why = analytic.coverage(scenario)
        if why:
            raise UnsupportedScenario(why)

    def _run(self, scenario: Scenario, settings: EngineSettings, meta: dict) -> Trajectory:
        assert isinstance(settings, AnalyticSettings)  # resolve_settings made it one
        traj = analytic.reference(scenario, linear=settings.linear)
        traj.engine, traj.engine_version = meta["engine"], meta["engine_version"]
        traj.settings = {**traj.settings, **meta["settings"]}
        return traj

    # the stepping hooks are never reached: _run() is replaced above
    def _build(self, scenario: Scenario, settings: EngineSettings) -> float:
        raise NotImplementedError

    def _drive_base(self, t: float, dt: float) -> None:
        raise NotImplementedError

    def _advance(self, n: int) -> None:
        raise NotImplementedError

    def _read_poses(self) -> np.ndarray:
        raise NotImplementedError
