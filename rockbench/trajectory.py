"""The :class:`Trajectory` result type returned by engines and analytic references.

A trajectory holds sampled time histories per block (bottom to top) and the
outcome of the run. It is deliberately neutral: the analytic package and the
engine plugins both build it, and the report only ever reads it.

Files: ``save("run.npz")`` writes the arrays plus a JSON sidecar ``run.json``
with the metadata; ``save("run.csv")`` writes one column per quantity
(``t, theta_1, x_1, z_1, wobble_1, theta_2, ...``) plus the same sidecar.
"""

from __future__ import annotations

import json
import os
import zipfile
from dataclasses import dataclass, field
from enum import Enum
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["Status", "Trajectory", "QUANTITIES", "QUANTITIES_3D", "write_npz", "Orientation",
           "orientation_from_quaternions", "angles_from_quaternions"]

#: Per-block quantities stored in a trajectory, in column order.
QUANTITIES = ("theta", "x", "z", "wobble")
#: Per-block quantities of motion out of the x–z plane, stored where any is not zero.
QUANTITIES_3D = ("y", "roll", "twist")


class Status(str, Enum):
    """Outcome of a run. Stability is a result: every status is reportable."""

    OK = "ok"
    OVERTURNED = "overturned"
    UNSTABLE = "unstable"  # NaN, explosion or energy gain
    CRASHED = "crashed"  # exception or dead process
    TIMEOUT = "timeout"
    UNSUPPORTED = "unsupported"

    def __str__(self) -> str:  # print "ok", not "Status.OK"
        return self.value

    @property
    def completed(self) -> bool:
        """True if the physics ran to a physical outcome (ok or overturned)."""
        return self in (Status.OK, Status.OVERTURNED)


def _as_2d(a: Any, n: int, name: str) -> np.ndarray:
    arr = np.asarray(a, dtype=float)
    if arr.ndim == 1:
        arr = arr[:, None]
    if arr.ndim != 2 or arr.shape[0] != n:
        raise ValueError(f"{name} must have shape (len(t), n_blocks), got {arr.shape}")
    return arr


@dataclass(init=False)
class Trajectory:
    """Sampled response of a block or stack.

    Parameters
    ----------
    t : ndarray, shape (n,)
        Sample times in s.
    theta : ndarray, shape (n, n_blocks)
        Absolute rocking angle of each block about +y (rad), bottom block first.
        Positive when the block's top moves toward +x.
    x, z : ndarray, shape (n, n_blocks), optional
        Centroid position in the ground frame (m); NaN where unknown.
    wobble : ndarray, shape (n, n_blocks), optional
        Out-of-plane rotation (rad): angle between the block's y axis and the
        world y axis; 0 for planar methods.
    y : ndarray, shape (n, n_blocks), optional
        Centroid position across the plane (m); 0 for planar methods.
    roll : ndarray, shape (n, n_blocks), optional
        Rotation about +x (rad), atan2(−R₁₂, R₂₂): positive when the top moves toward −y
        (θ's twin for rocking about x); 0 for planar methods.
    twist : ndarray, shape (n, n_blocks), optional
        Rotation of the block about its own vertical axis (rad, the twist of the swing–twist
        decomposition about z, in (−π, π]); 0 for planar methods.
    status : Status
        Outcome of the run.
    message : str
        Reason for a non-ok status, or a note.
    wall_time : float
        Wall-clock time of the simulation in s.
    cpu_time : float
        CPU time of the process during the simulation in s (0 where unmeasured).
    engine, engine_version : str
        Who produced it.
    settings : dict
        The engine settings used (plain JSON-able values).
    scenario : str
        Name of the scenario.
    impacts : ndarray, optional
        Impact times (s) where the method knows them (analytic references).
    extra : dict
        Free-form JSON-able metadata (e.g. motion patterns of the analytic model).
    """

    t: np.ndarray
    theta: np.ndarray
    x: np.ndarray
    z: np.ndarray
    wobble: np.ndarray
    y: np.ndarray
    roll: np.ndarray
    twist: np.ndarray
    status: Status = Status.OK
    message: str = ""
    wall_time: float = 0.0
    cpu_time: float = 0.0
    engine: str = ""
    engine_version: str = ""
    settings: dict[str, Any] = field(default_factory=dict)
    scenario: str = ""
    impacts: np.ndarray | None = None
    extra: dict[str, Any] = field(default_factory=dict)

    # written out rather than generated: x, z, wobble and the 3D quantities may be left out
    # (None) but are always arrays once built, and the arrays may be given as any array-like
    def __init__(self, t: ArrayLike, theta: ArrayLike, x: ArrayLike | None = None,
                 z: ArrayLike | None = None, wobble: ArrayLike | None = None,
                 status: Status | str = Status.OK, message: str = "", wall_time: float = 0.0,
                 cpu_time: float = 0.0, engine: str = "", engine_version: str = "",
                 settings: dict[str, Any] | None = None, scenario: str = "",
                 impacts: ArrayLike | None = None, extra: dict[str, Any] | None = None,
                 y: ArrayLike | None = None, roll: ArrayLike | None = None,
                 twist: ArrayLike | None = None) -> None:
        self.t = np.asarray(t, dtype=float).reshape(-1)
        n = self.t.size
        self.theta = _as_2d(theta, n, "theta")
        nb = self.theta.shape[1]
        self.x = _as_2d(np.full((n, nb), np.nan) if x is None else x, n, "x")
        self.z = _as_2d(np.full((n, nb), np.nan) if z is None else z, n, "z")
        self.wobble = _as_2d(np.zeros((n, nb)) if wobble is None else wobble, n, "wobble")
        self.y = _as_2d(np.zeros((n, nb)) if y is None else y, n, "y")
        self.roll = _as_2d(np.zeros((n, nb)) if roll is None else roll, n, "roll")
        self.twist = _as_2d(np.zeros((n, nb)) if twist is None else twist, n, "twist")
        self.status = Status(status)
        self.message = message
        self.wall_time = wall_time
        self.cpu_time = cpu_time
        self.engine = engine
        self.engine_version = engine_version
        self.settings = {} if settings is None else settings
        self.scenario = scenario
        self.impacts = None if impacts is None else np.asarray(impacts, float)
        self.extra = {} if extra is None else extra

    @property
    def n_blocks(self) -> int:
        """Number of blocks."""
        return self.theta.shape[1]

    @property
    def planar(self) -> bool:
        """True when nothing left the x–z plane (every 3D quantity is exactly 0)."""
        return not any(np.any(getattr(self, q) != 0.0) for q in QUANTITIES_3D)

    @property
    def tilt(self) -> np.ndarray:
        """Angle between each block's z axis and the world's (rad, ≥ 0), from θ and the
        roll: tan² tilt = tan² θ + tan² roll (the block's z axis ∝ (tan θ, −tan roll, 1))."""
        return np.arctan(np.hypot(np.tan(self.theta), np.tan(self.roll)))

    @property
    def azimuth(self) -> np.ndarray:
        """Direction in which each block's top leans (rad, from +x toward +y)."""
        return np.arctan2(-np.tan(self.roll), np.tan(self.theta))

    def quantities(self) -> tuple[str, ...]:
        """The per-block quantities this trajectory stores: :data:`QUANTITIES`, and
        :data:`QUANTITIES_3D` when it is not :attr:`planar`."""
        return QUANTITIES if self.planar else QUANTITIES + QUANTITIES_3D

    def arrays(self) -> dict[str, np.ndarray]:
        """``t`` and each stored per-block quantity (:meth:`quantities`), by name."""
        return {"t": self.t, **{q: getattr(self, q) for q in self.quantities()}}

    @classmethod
    def failed(
        cls, status: Status | str, message: str, *, n_blocks: int = 1, **meta: Any
    ) -> Trajectory:
        """An empty trajectory that records why a run produced no samples."""
        return cls(
            t=np.zeros(0), theta=np.zeros((0, n_blocks)), status=Status(status),
            message=message, **meta,
        )

    def metadata(self) -> dict[str, Any]:
        """JSON-able metadata (everything except the arrays)."""
        return {
            "scenario": self.scenario,
            "engine": self.engine,
            "engine_version": self.engine_version,
            "settings": self.settings,
            "status": self.status.value,
            "message": self.message,
            "wall_time": self.wall_time,
            "cpu_time": self.cpu_time,
            "n_blocks": self.n_blocks,
            "impacts": None if self.impacts is None else self.impacts.tolist(),
            "extra": self.extra,
        }

    def columns(self) -> dict[str, np.ndarray]:
        """Flat columns ``t, theta_1, x_1, z_1, wobble_1, theta_2, ...`` (blocks 1-based;
        ``y_1, roll_1, twist_1`` after each block's where the motion left the plane)."""
        cols = {"t": self.t}
        quantities = self.quantities()
        for i in range(self.n_blocks):
            for q in quantities:
                cols[f"{q}_{i + 1}"] = getattr(self, q)[:, i]
        return cols

    def save(self, path: str | Path, *, scenario: dict[str, Any] | None = None) -> Path:
        """Write the arrays (``.npz`` or ``.csv``) and a JSON sidecar (``.json``).

        Parameters
        ----------
        path : str or Path
            Target file; its suffix selects the format.
        scenario : dict, optional
            The scenario description to store in the sidecar.

        Returns
        -------
        Path
            The sidecar path.
        """
        path = Path(path)
        if path.suffix not in (".npz", ".csv"):
            raise ValueError(f"unsupported trajectory format {path.suffix!r}: use .npz or .csv")
        path.parent.mkdir(parents=True, exist_ok=True)
        cols = self.columns()
        meta = self.metadata()
        if scenario is not None:
            meta["scenario_definition"] = scenario
        side = path.with_suffix(".json")
        # write then rename, sidecar last: an interrupted save leaves the old files
        # or a data file without its sidecar, never a torn file under the final name
        tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
        try:
            with tmp.open("wb") as fh:
                if path.suffix == ".npz":
                    write_npz(fh, cols)
                else:
                    data = (np.column_stack(list(cols.values())) if self.t.size
                            else np.zeros((0, len(cols))))
                    np.savetxt(fh, data, delimiter=",", header=",".join(cols), comments="",
                               fmt="%.10g")
            os.replace(tmp, path)
            tmp_side = side.with_name(f".{side.name}.{os.getpid()}.tmp")
            tmp_side.write_text(json.dumps(meta, indent=2, default=_json_default))
            os.replace(tmp_side, side)
        finally:
            tmp.unlink(missing_ok=True)
        return side

    @classmethod
    def load(cls, path: str | Path) -> Trajectory:
        """Read a trajectory written by :meth:`save`."""
        path = Path(path)
        meta = json.loads(path.with_suffix(".json").read_text())
        if path.suffix == ".npz":
            with np.load(path) as f:
                cols = {k: f[k] for k in f.files}
        else:
            data = np.genfromtxt(path, delimiter=",", names=True, ndmin=1)
            names = data.dtype.names or ()
            cols = {k: np.atleast_1d(data[k]).astype(float) for k in names}
        nb = int(meta["n_blocks"])
        arrays = {
            q: np.column_stack([cols[f"{q}_{i + 1}"] for i in range(nb)]).reshape(-1, nb)
            for q in QUANTITIES + QUANTITIES_3D if f"{q}_1" in cols or q in QUANTITIES
        }
        return cls(
            t=cols["t"], **arrays, status=Status(meta["status"]), message=meta["message"],
            wall_time=meta["wall_time"], cpu_time=meta.get("cpu_time", 0.0),
            engine=meta["engine"],
            engine_version=meta["engine_version"], settings=meta["settings"],
            scenario=meta["scenario"], impacts=meta.get("impacts"), extra=meta.get("extra", {}),
        )


def write_npz(fh: Any, arrays: dict[str, np.ndarray]) -> None:
    """Write ``arrays`` to the binary file ``fh`` as an ``.npz`` that ``np.load`` reads.

    Deflate at level 1 rather than ``np.savez_compressed``'s 6: trajectories
    compress to the same size (measured: 450 kB either way for 20 s of one
    block) in half the CPU, which the study's parent process would otherwise
    take from the workers for every run it saves.
    """
    with zipfile.ZipFile(fh, "w", zipfile.ZIP_DEFLATED, compresslevel=1) as zf:
        for name, value in arrays.items():
            with zf.open(f"{name}.npy", "w", force_zip64=True) as member:
                np.lib.format.write_array(member, np.asanyarray(value), allow_pickle=False)


def _json_default(obj: Any) -> Any:
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, Enum):
        return obj.value
    raise TypeError(f"not JSON serialisable: {type(obj).__name__}")


class Orientation(NamedTuple):
    """The angles a :class:`Trajectory` reports of each sampled orientation (rad)."""

    theta: np.ndarray
    wobble: np.ndarray
    roll: np.ndarray
    twist: np.ndarray


def orientation_from_quaternions(q: np.ndarray) -> Orientation:
    """θ, wobble, roll and twist from unit quaternions (w, x, y, z), shape (..., 4).

    θ = atan2(R₀₂, R₂₂) and the roll atan2(−R₁₂, R₂₂) are the lean of the body's z axis
    toward +x and toward −y (rotations about +y and +x); the twist is the rotation about
    the body's own z axis, 2 atan2(q_z, q_w) (the swing–twist decomposition), wrapped to
    (−π, π]; the wobble is the angle between the body's y axis and the world's.
    """
    theta, wobble = angles_from_quaternions(q)
    w, x, y, z = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    r12 = 2.0 * (y * z - w * x)
    r22 = 1.0 - 2.0 * (x * x + y * y)
    twist = 2.0 * np.arctan2(z, w)
    twist = np.where(twist > np.pi, twist - 2.0 * np.pi, twist)
    twist = np.where(twist <= -np.pi, twist + 2.0 * np.pi, twist)
    return Orientation(theta, wobble, np.arctan2(-r12, r22), twist)


def angles_from_quaternions(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rocking angle about +y and out-of-plane wobble from unit quaternions (w, x, y, z).

    θ = atan2(R02, R22) (the body z axis tilting toward +x is positive) and the
    wobble is the angle between the body y axis and the world y axis.
    """
    w, x, y, z = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    r02 = 2.0 * (x * z + w * y)
    r22 = 1.0 - 2.0 * (x * x + y * y)
    r11 = 1.0 - 2.0 * (x * x + z * z)
    return np.arctan2(r02, r22), np.arccos(np.clip(r11, -1.0, 1.0))
