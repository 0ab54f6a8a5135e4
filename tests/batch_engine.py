"""A test-only batch engine: Housner's equation stepped in many worlds at once.

Each world is one rectangular block rocking on a rigid base (θ'' = −p² [sin(sgn θ λ − θ)
+ (ü_g/g) cos(sgn θ λ − θ)], semi-implicit Euler, Housner's η at each impact), the base
acceleration being the change of the secant base velocity the loop writes per step.
It exists to test :class:`rockbench.engines.batch.BatchEngine`'s loop on every machine
(Newton, the real batch engine, is an optional extra): its single-run path is a batch of
one, so a world of a batch must equal the same scenario run alone bit for bit. The knobs
``nan_world`` and ``nan_at`` poison one world's state at a time, for isolation tests.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from rockbench.engines import Capabilities, EngineSettings, KnobRole
from rockbench.engines.batch import BatchEngine
from rockbench.scenarios import Scenario

__all__ = ["HousnerBatchEngine", "HousnerBatchSettings"]


@dataclass(frozen=True)
class HousnerBatchSettings(EngineSettings):
    """Knobs: the step (s), and a world whose state becomes NaN at ``nan_at`` (s)."""

    timestep: float = 1.0e-4
    nan_world: int = -1
    nan_at: float = 0.0


class HousnerBatchEngine(BatchEngine):
    """Housner's single block, vectorised over worlds (see the module docstring)."""

    name: ClassVar[str] = "housner-batch"
    capabilities: ClassVar[Capabilities] = Capabilities(dimensions=2, max_blocks=1,
                                                        chamfer=False, assemblies=False,
                                                        base_axes="x")
    Settings: ClassVar[type[EngineSettings]] = HousnerBatchSettings
    presets: ClassVar[dict[str, dict]] = {"accurate": {}, "fast": {"timestep": 1.0e-3}}
    knob_roles: ClassVar[dict[str, KnobRole]] = {"timestep": KnobRole.TIME_STEP}
    max_batch: ClassVar[int] = 16

    @classmethod
    def version(cls) -> str:
        return "1.0"

    def _build(self, scenario: Scenario, settings: EngineSettings) -> float:
        self.drives = [self.drive]
        return self._build_batch([scenario], settings)

    def _build_batch(self, scenarios: list[Scenario], settings: EngineSettings) -> float:
        assert isinstance(settings, HousnerBatchSettings)
        self._s = settings
        out_dt = 1.0 / scenarios[0].output_rate
        self._dt = dt = out_dt / max(1, round(out_dt / settings.timestep))
        rock = [sc.blocks[0].rocking(sc.g) for sc in scenarios]
        self._lam = np.array([r.lam for r in rock])
        self._p2 = np.array([r.p ** 2 for r in rock])
        self._eta = np.array([r.eta for r in rock])
        self._r = np.array([r.R for r in rock])
        self._g = np.array([sc.g for sc in scenarios])
        self._th = np.array([sc.theta0 for sc in scenarios], float)
        self._om = np.zeros(len(scenarios))
        self._v = np.zeros(len(scenarios))  # each base's velocity over the last step
        self._dv = np.zeros(len(scenarios))  # its change at the next step
        self._u = np.zeros(len(scenarios))
        self._t = 0.0
        return dt

    def _drive_worlds(self, worlds: list[int], u: np.ndarray, v: np.ndarray) -> None:
        idx = np.asarray(worlds)
        self._dv[idx] = v[:, 0] - self._v[idx]
        self._v[idx] = v[:, 0]
        self._u[idx] = u[:, 0]

    def _advance(self, n: int) -> None:
        self._advance_batch(n)

    def _advance_batch(self, n: int) -> None:
        dt, lam, p2 = self._dt, self._lam, self._p2
        for _ in range(n):
            a_g = self._dv / dt
            self._dv[:] = 0.0
            s = np.where(self._th != 0.0, np.sign(self._th), -np.sign(a_g))
            rest = (self._th == 0.0) & (np.abs(a_g) <= self._g * np.tan(lam))
            acc = -p2 * (np.sin(s * lam - self._th) + a_g / self._g * np.cos(s * lam - self._th))
            om = np.where(rest, 0.0, self._om + dt * acc)
            th = np.where(rest, 0.0, self._th + dt * om)
            cross = (th * self._th < 0.0)
            self._om = np.where(cross, self._eta * om, om)
            self._th = th
            self._t += dt
            w = self._s.nan_world
            if 0 <= w < len(th) and self._t >= self._s.nan_at:
                self._th[w] = self._om[w] = np.nan

    def _read_batch(self) -> list[np.ndarray]:
        th, lam, r = self._th, self._lam, self._r
        s = np.where(th >= 0.0, 1.0, -1.0)
        # the centre of gravity turning about the pivot (x = ±b) by θ about +y
        b, h = r * np.sin(lam), r * np.cos(lam)
        ct, st = np.cos(th), np.sin(th)
        x = self._u + s * b - s * b * ct + h * st
        z = s * b * st + h * ct
        out = np.zeros((len(th), 1, 7))
        out[:, 0, 0], out[:, 0, 2] = x, z
        out[:, 0, 3], out[:, 0, 5] = np.cos(0.5 * th), np.sin(0.5 * th)
        return list(out)

    def _read_poses(self) -> np.ndarray:
        return self._read_batch()[0]

