"""Batched runs: many scenarios stepped together as the worlds of one engine model.

An engine that can step many independent worlds in one call (Newton, whose Warp
kernels run over every body of every world at once) subclasses :class:`BatchEngine`
and runs a batch of scenarios through :meth:`BatchEngine.simulate_many`: one model
with a world per scenario, one sampling loop, and for each world the same
trajectory, status and message as :meth:`~rockbench.engines.base.Engine.simulate`
gives that scenario alone (each world has its own base motion and its own
:class:`~rockbench.engines.base.Watchdog`; a world that fails is cut at its first
failing sample and the others go on). :func:`simulate_many` runs any engine this way,
one scenario at a time where the engine cannot batch.

Contract for implementers (beyond the :class:`~rockbench.engines.base.Engine`
rules, which the single-run path keeps):

1. :meth:`BatchEngine._build_batch` builds one model whose world ``w`` is
   ``scenarios[w]`` exactly as :meth:`~rockbench.engines.base.Engine._build` builds
   one scenario (no contact between worlds) and returns the physics step; the
   drives are in :attr:`BatchEngine.drives`.
2. :meth:`BatchEngine._drive_worlds` writes, for the worlds named, the base's
   displacement at the step's start and its secant velocity over the step.
3. :meth:`BatchEngine._advance_batch` takes ``n`` steps of every world.
4. :meth:`BatchEngine._read_batch` returns every world's block poses.

The batch's wall and CPU time are shared evenly among its worlds' trajectories, and
each trajectory's effective settings record the batch's size (``batch_worlds``).
"""

from __future__ import annotations

import time
from abc import abstractmethod
from collections.abc import Sequence
from typing import Any, ClassVar

import numpy as np

from rockbench.engines.base import Engine, Watchdog, trajectory_from_poses
from rockbench.engines.drive import BaseDrive
from rockbench.engines.settings import EngineSettings, SettingsError
from rockbench.errors import UnsupportedScenario
from rockbench.limits import check_memory
from rockbench.scenarios import Scenario
from rockbench.trajectory import Status, Trajectory

__all__ = ["BatchEngine", "simulate_many", "batch_key", "batch_size"]


def batch_key(scenario: Scenario) -> float:
    """What scenarios must share to be stepped together: the output rate (one sampling
    loop). Durations, geometry, contact and motion may differ per world."""
    return float(scenario.output_rate)


def batch_size(engine: type[Engine] | Engine) -> int:
    """The most worlds ``engine`` steps in one batch (1: it cannot batch)."""
    cls = engine if isinstance(engine, type) else type(engine)
    return cls.max_batch if issubclass(cls, BatchEngine) else 1


def simulate_many(engine: Engine, scenarios: Sequence[Scenario], settings: Any = None
                  ) -> list[Trajectory]:
    """Run ``scenarios`` with one settings on ``engine``: batched where it can.

    A :class:`BatchEngine` steps runs of equal :func:`batch_key` together, at most
    its ``max_batch`` at a time; any other engine runs them one by one. Either way
    the result is one trajectory per scenario, in order.
    """
    if not isinstance(engine, BatchEngine):
        return [engine.simulate(sc, settings) for sc in scenarios]
    return engine.simulate_many(scenarios, settings)


class BatchEngine(Engine):
    """An engine that also steps many scenarios as the worlds of one model.

    Subclasses implement the single-run hooks of :class:`Engine` and the batch hooks
    of this module's contract; users call :meth:`simulate` or :meth:`simulate_many`.
    """

    #: The most worlds one batch holds (a batch's memory grows with it).
    max_batch: ClassVar[int] = 64

    def __init__(self) -> None:
        self.drives: list[BaseDrive] = []

    # ------------------------------------------------------------------ public API
    def simulate_many(self, scenarios: Sequence[Scenario], settings: Any = None
                      ) -> list[Trajectory]:
        """Run ``scenarios`` as the worlds of shared models (see the module docstring).

        Scenarios of equal :func:`batch_key` go together, ``max_batch`` at most; an
        unsupported one gets status ``unsupported`` and takes no world. Never raises
        for physics failures; bad settings raise :class:`SettingsError`.
        """
        s = self.resolve_settings(settings)
        out: list[Trajectory | None] = [None] * len(scenarios)
        groups: dict[float, list[int]] = {}
        meta = dict(engine=self.name, engine_version=self.version(), settings=s.to_dict())
        for i, sc in enumerate(scenarios):
            check_memory(sc)
            self.drive = BaseDrive(sc.motion, sc.duration)
            try:
                self.check_supported(sc)
            except UnsupportedScenario as exc:
                out[i] = Trajectory.failed(Status.UNSUPPORTED, str(exc), n_blocks=sc.n_blocks,
                                           scenario=sc.name, **meta)
                continue
            groups.setdefault(batch_key(sc), []).append(i)
        for members in groups.values():
            # similar lengths together: a world that ends early is stepped idle to the end
            members.sort(key=lambda i: scenarios[i].duration)
            for b in range(0, len(members), self.max_batch):
                part = members[b:b + self.max_batch]
                for i, traj in zip(part, self._simulate_batch([scenarios[i] for i in part], s,
                                                              meta), strict=True):
                    out[i] = traj
        return [t for t in out if t is not None]

    def _simulate_batch(self, scenarios: list[Scenario], s: EngineSettings, meta: dict
                        ) -> list[Trajectory]:
        if len(scenarios) == 1:
            return [self.simulate(scenarios[0], s)]
        self.drives = [BaseDrive(sc.motion, sc.duration) for sc in scenarios]
        start, cpu = time.perf_counter(), time.process_time()
        try:
            trajs = self._run_batch(scenarios, s, meta)
        except UnsupportedScenario as exc:  # raised by _build_batch when it depends on settings
            trajs = [Trajectory.failed(Status.UNSUPPORTED, str(exc), n_blocks=sc.n_blocks,
                                       scenario=sc.name, **meta) for sc in scenarios]
        finally:
            self._teardown()
        wall = (time.perf_counter() - start) / len(scenarios)
        cpu = (time.process_time() - cpu) / len(scenarios)
        for traj in trajs:
            traj.wall_time, traj.cpu_time = wall, cpu
        return trajs

    # ------------------------------------------------------------------ the loop
    def _run_batch(self, scenarios: list[Scenario], s: EngineSettings, meta: dict
                   ) -> list[Trajectory]:
        """The sampling loop of :meth:`Engine._run`, every world at once."""
        sc0 = max(scenarios, key=lambda sc: sc.duration)
        t_out = sc0.output_times()
        n_out, worlds = t_out.size, len(scenarios)
        dt = float(self._build_batch(scenarios, s))
        ratio = 1.0 / (sc0.output_rate * dt)
        k = int(round(ratio))
        if k < 1 or abs(ratio - k) > 1e-6 * ratio:
            raise SettingsError(
                f"{self.name}: a batch needs a physics step {dt:.4g} s that divides the output "
                f"interval {1.0 / sc0.output_rate:.4g} s")
        drives = self.drives
        watches = [Watchdog(sc, d, self.unmodelled_pairs(sc))
                   for sc, d in zip(scenarios, drives, strict=True)]
        # each world's own samples (a shorter run's times are the first of the longest's)
        ends = [sc.output_times().size for sc in scenarios]
        poses = [np.full((n, sc.n_blocks, 7), np.nan) for n, sc in zip(ends, scenarios,
                                                                        strict=True)]
        for w, p in enumerate(self._read_batch()):
            poses[w][0] = p
        # as in Engine._sample_aligned: each base is driven up to the first sample that
        # ends past its motion (or its run), then held still where the motion left it
        finish = np.arange(1, n_out) * k * dt
        last_driven = [min(int(np.argmax(finish > d.end_time)) + 1
                           if (finish > d.end_time).any() else n_out, n - 1)
                       if d.moving else 0 for d, n in zip(drives, ends, strict=True)]
        held = [False] * worlds
        last = list(ends)
        verdicts: list[tuple[Status, str] | None] = [None] * worlds
        active = list(range(worlds))
        chunk = watches[0].chunk
        i = 1
        with np.errstate(invalid="ignore", over="ignore"):
            while i < n_out and active:
                m = min(chunk, n_out - i)
                for j in range(i, i + m):
                    driven = [w for w in active if drives[w].moving and j <= last_driven[w]]
                    if driven:
                        self._drive_steps(driven, (j - 1) * k, k, dt)
                    else:
                        self._advance_batch(k)
                    for w in driven:
                        if j == last_driven[w] and not held[w]:
                            held[w] = True
                            final = np.asarray(drives[w].final_displacement(), float)
                            self._drive_worlds([w], final[None, :], np.zeros((1, 3)))
                    for w, p in enumerate(self._read_batch()):
                        if j < ends[w]:
                            poses[w][j] = p
                for w in list(active):
                    stop = min(i + m, ends[w])
                    bad = watches[w].check(poses[w][i - 1:stop], t_out[i:stop])
                    if bad is not None:
                        last[w], verdicts[w] = i + bad[0] + 1, bad[1]
                    if bad is not None or stop == ends[w]:
                        active.remove(w)  # failed or done: stepped on, never read again
                i += m
        effective = {"effective_timestep": dt, "steps_per_sample": ratio,
                     "batch_worlds": worlds}
        return [trajectory_from_poses(poses[w][:last[w]], t_out[:last[w]], verdicts[w],
                                      {**meta, "scenario": sc.name}, **effective)
                for w, sc in enumerate(scenarios)]

    def _drive_steps(self, worlds: list[int], step0: int, n: int, dt: float) -> None:
        """``n`` steps from step ``step0``, the bases of ``worlds`` driven (secant velocity)."""
        t = BaseDrive.grid(dt, n + 1, start=step0)
        u = np.stack([self.drives[w].displacement(t) for w in worlds], axis=1)
        v = np.diff(u, axis=0) / dt
        for j in range(n):
            self._drive_worlds(worlds, u[j], v[j])
            self._advance_batch(1)

    # ------------------------------------------------------------------ one run: world 0
    def _drive_base(self, t: float, dt: float) -> None:
        u = self.drive.displacement(np.array([t, t + dt]))
        self._drive_worlds([0], u[:1], (u[1:] - u[:1]) / dt)

    def _advance_driven(self, t0: float, n: int, dt: float) -> None:
        # the batch's own step grid and secant velocities: one run equals its world
        self._drive_steps([0], int(round(t0 / dt)), n, dt)

    def _fix_base(self) -> bool:
        final = np.asarray(self.drive.final_displacement(), float)
        self._drive_worlds([0], final[None, :], np.zeros((1, 3)))
        return True

    # ------------------------------------------------------------------ hooks
    @abstractmethod
    def _build_batch(self, scenarios: list[Scenario], settings: EngineSettings) -> float:
        """One model with a world per scenario (rule 1); return the physics step in s."""

    @abstractmethod
    def _drive_worlds(self, worlds: list[int], u: np.ndarray, v: np.ndarray) -> None:
        """Set the bases of ``worlds`` to displacement ``u`` and velocity ``v`` (each
        (len(worlds), 3)) for the next step (rule 2)."""

    @abstractmethod
    def _advance_batch(self, n: int) -> None:
        """Take ``n`` steps of every world (rule 3)."""

    @abstractmethod
    def _read_batch(self) -> list[np.ndarray]:
        """Each world's block poses (n_blocks, 7), x, y, z, qw, qx, qy, qz (rule 4)."""
