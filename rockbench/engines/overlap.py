"""Run-time check that an assembly's bodies do not pass through contacts an engine lacks.

An engine that lays its contacts once, on the joints that exist at rest (OpenSees'
interface springs), has nothing between two bodies that were apart at rest: if a
mechanism brings them together they pass through each other and the run would
still look physical. Such an engine names those pairs
(:meth:`rockbench.engines.base.Engine.unmodelled_pairs`) and the watchdog checks
them along the run: any overlap beyond rounding is a contact the model missed.

Bodies are numbered as in the limit analysis: blocks ``0 … n − 1``, then the
supports, then the base (the half-plane z ≤ 0).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from rockbench.engines.drive import BaseDrive
from rockbench.geometry.polygon import penetration, rotate
from rockbench.scenarios import Scenario

__all__ = ["OverlapWatch"]

#: Overlap that counts, as a fraction of the smaller body's least size: far below any
#: real penetration a missed contact reaches, far above the rounding of poses at rest.
OVERLAP_FRACTION = 1e-3
#: Seconds between two checked samples (a body crossing a 0.1 m block at 1 m/s is
#: inside it for 0.1 s).
CHECK_INTERVAL = 0.02


class OverlapWatch:
    """Overlaps of the named body pairs of a geometry, sample by sample.

    Parameters
    ----------
    scenario : Scenario
        What runs.
    drive : BaseDrive
        Its base motion (the supports move with it).
    pairs : sequence of (int, int)
        Body pairs (limit-analysis numbering, module docstring) that the engine
        builds no contact between.
    """

    def __init__(self, scenario: Scenario, drive: BaseDrive,
                 pairs: Sequence[tuple[int, int]]) -> None:
        asm = scenario.geometry
        self.n = scenario.n_blocks
        self.profiles = [b.profile() for b in asm.bodies]
        self.supports = [s.array for s in asm.supports]
        self.ground = self.n + len(self.supports)
        self.radius = np.array([float(np.hypot(*p.T).max()) for p in self.profiles])
        least = [float(min(np.ptp(p, axis=0))) for p in self.profiles]
        least += [float(min(np.ptp(s, axis=0))) for s in self.supports] + [np.inf]
        self.pairs = [(a, b, OVERLAP_FRACTION * min(least[a], least[b])) for a, b in pairs]
        self.drive = drive
        self.every = max(1, round(CHECK_INTERVAL * scenario.output_rate))

    def first(self, poses: np.ndarray, t: np.ndarray) -> tuple[int, str] | None:
        """First checked sample with an overlap beyond the tolerance, and what overlaps.

        Parameters
        ----------
        poses : ndarray, shape (m, n_blocks, 7)
            Poses (x, y, z, w, qx, qy, qz) of the chunk's samples.
        t : ndarray, shape (m,)
            Their times (s).
        """
        if not self.pairs:
            return None
        for j in range(0, len(t), self.every):
            found = self._overlap(poses[j], float(t[j]))
            if found is not None:
                return j, found
        return None

    def _overlap(self, pose: np.ndarray, t: float) -> str | None:
        x, z = pose[:, 0], pose[:, 2]
        w, qx, qy, qz = pose[:, 3], pose[:, 4], pose[:, 5], pose[:, 6]
        theta = np.arctan2(qx * qz + w * qy, 0.5 - (qx * qx + qy * qy))
        u = float(self.drive.displacement(t)[0]) if self.drive.moving else 0.0
        polys: dict[int, np.ndarray] = {}
        for a, b, tol in self.pairs:
            if b < self.n and np.hypot(x[a] - x[b], z[a] - z[b]) > \
                    self.radius[a] + self.radius[b]:
                continue  # bounding circles apart
            for k in (a, b):
                if k < self.n and k not in polys:
                    polys[k] = np.array([x[k], z[k]]) + rotate(self.profiles[k], theta[k])
            pa = polys[a]
            if b == self.ground:
                depth = -float(pa[:, 1].min())
            else:
                pb = polys[b] if b < self.n else self.supports[b - self.n] + np.array([u, 0.0])
                depth = penetration(pa, pb)
            if depth > tol:
                other = ("the base" if b == self.ground else f"block {b + 1}" if b < self.n
                         else f"support {b - self.n + 1}")
                return (f"interpenetration: block {a + 1} and {other} overlap by {depth:.3g} m, "
                        f"a contact the engine does not model")
        return None
