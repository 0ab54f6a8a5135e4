"""Speed benchmarks of rockbench (issue 7); not part of the test run.

Run ``python -m benchmarks [--quick] [--only overhead,analytic,scaling,paper]``;
it regenerates ``benchmarks/RESULTS.md`` and ``benchmarks/accuracy_speed.png``.

Timing rules (the machine may be shared): every comparison is taken side by
side in one process run, the variants are interleaved (A B A B ...), each is
repeated and the *minimum* is kept, and both wall time and CPU time of this
process (``time.process_time``) are recorded. On a loaded machine the CPU time
is the better estimate of the wall time an idle machine would give; goals are
checked on it. The load average is written next to every table.
"""

from __future__ import annotations

import gc
import math
import os
import platform
import statistics
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

__all__ = ["ENGINES", "ENGINES_3D", "Timing", "best_of", "interleaved", "paired_ratio",
           "engine_status",
           "load", "machine_info", "fmt_time", "warm"]

#: Every engine the project has or is adding, in table order.
ENGINES = ("mujoco", "bullet", "dart", "pymunk", "drake", "dem2d")
#: The 3D engines (stack scaling).
ENGINES_3D = ("mujoco", "bullet", "dart", "drake")


@dataclass
class Timing:
    """Best (minimum) wall and CPU time over repeats, in s, every CPU time, the last result."""

    wall: float = math.inf
    cpu: float = math.inf
    result: Any = None
    cpus: list[float] = field(default_factory=list)

    @property
    def n(self) -> int:
        """Number of timed runs."""
        return len(self.cpus)

    def add(self, wall: float, cpu: float, result: Any) -> None:
        self.wall = min(self.wall, wall)
        self.cpu = min(self.cpu, cpu)
        self.result = result
        self.cpus.append(cpu)


def paired_ratio(a: Timing, b: Timing) -> float:
    """Median over rounds of a's CPU time over b's, from :func:`interleaved` timings.

    The two runs of a round are a fraction of a second apart, so a machine
    whose speed drifts over seconds (a shared host) slows both alike: the
    ratio of each pair is steadier than the ratio of the two minima.
    """
    return float(statistics.median(x / y for x, y in zip(a.cpus, b.cpus, strict=True)))


def _timed(fn: Callable[[], Any]) -> tuple[float, float, Any]:
    c0, w0 = time.process_time(), time.perf_counter()
    out = fn()
    w1, c1 = time.perf_counter(), time.process_time()
    return w1 - w0, c1 - c0, out


class _NoGc:
    """The cyclic garbage collector off while timing, run between rounds instead.

    A full collection walks every object of the process (~50 ms with the
    engines' libraries loaded) and leaves the caches cold: collecting before
    each call would cap a short case at a few dozen rounds and time every one
    of them cold. Rounds are still separated by a collection every second.
    """

    def __enter__(self) -> _NoGc:
        gc.collect()
        gc.disable()
        self._last = time.perf_counter()
        return self

    def between_rounds(self) -> None:
        if time.perf_counter() - self._last > 1.0:
            gc.collect()
            self._last = time.perf_counter()

    def __exit__(self, *exc: object) -> None:
        gc.enable()


def best_of(fn: Callable[[], Any], repeat: int) -> Timing:
    """Minimum wall/CPU time of ``repeat`` calls of ``fn``."""
    t = Timing()
    with _NoGc() as nogc:
        for _ in range(max(1, repeat)):
            t.add(*_timed(fn))
            nogc.between_rounds()
    return t


def interleaved(fns: dict[str, Callable[[], Any]], repeat: int,
                min_time: float = 0.0) -> dict[str, Timing]:
    """Time several variants side by side: A B C, C B A, A B C ..., minima kept.

    The order alternates from round to round so that neither variant always
    runs right after the other (whose cache or allocator state it would inherit).

    At least ``repeat`` rounds, and more until the rounds have taken about
    ``min_time`` seconds: the minimum of a few-millisecond run needs hundreds
    of samples on a shared machine, that of a one-second run a handful.
    """
    out = {k: Timing() for k in fns}
    rounds = max(1, repeat)
    done = 0
    with _NoGc() as nogc:
        start = time.perf_counter()
        order = list(fns.items())
        while done < rounds:
            for k, fn in order if done % 2 == 0 else order[::-1]:
                out[k].add(*_timed(fn))
            done += 1
            if done == 1 and min_time > 0:
                per_round = time.perf_counter() - start
                rounds = max(rounds, math.ceil(min_time / max(per_round, 1e-6)))
            nogc.between_rounds()
    return out


def engine_status(name: str) -> tuple[bool, str]:
    """(available, version or reason) from the registry; never raises."""
    from rockbench.engines import engine_info

    try:
        info = engine_info(name)
    except Exception as exc:  # unknown (not registered yet) or broken plugin
        msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        return False, f"not registered ({msg[:60]})"
    if not info.available:
        return False, f"unavailable ({info.reason[:60]})"
    return True, info.version


_WARM: set[str] = set()


def warm(name: str) -> None:
    """Run engine ``name`` once on a tiny scenario (imports, JIT caches) before timing it."""
    if name in _WARM:
        return
    _WARM.add(name)
    from rockbench.engines import get_engine
    from rockbench.scenarios import get_scenario

    for sc in (get_scenario("free-b1-0.5").replace(duration=0.02),
               get_scenario("stack-pulse-5.0hz-4mm").replace(duration=0.02)):
        try:
            get_engine(name).simulate(sc, "fast")
        except Exception:  # reported by the benchmark itself
            pass


def load() -> str:
    """The 1/5/15-minute load averages and the core count, as text."""
    try:
        la = os.getloadavg()
    except OSError:  # pragma: no cover - not on Unix
        return "load n/a"
    return f"load {la[0]:.1f}/{la[1]:.1f}/{la[2]:.1f} on {os.cpu_count()} cores"


def machine_info() -> list[tuple[str, str]]:
    """Machine and library versions for the results header."""
    import numpy
    import scipy

    import rockbench

    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as fh:
            for line in fh:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    rows = [("CPU", f"{cpu}, {os.cpu_count()} logical cores"),
            ("OS", platform.platform()),
            ("Python", platform.python_version()),
            ("rockbench", rockbench.__version__),
            ("NumPy / SciPy", f"{numpy.__version__} / {scipy.__version__}")]
    for name in ENGINES:
        ok, what = engine_status(name)
        rows.append((name, what))
    return rows


def fmt_time(s: float) -> str:
    """Seconds as ms below 1 s, else s."""
    if not math.isfinite(s):
        return "–"
    if s < 1.0:
        return f"{s * 1e3:.1f} ms"
    return f"{s:.2f} s"
