"""The engineer's own records: a folder of record files, or a manifest that lists them.

Wherever a record set's name is accepted, a path to one's own set is too
(``rockbench records --set PATH``, ``rockbench fragility --record-set PATH``,
``set = "PATH"`` in a scenario file, relative to that file):

* a folder: every ``.AT2`` file (PEER NGA, accelerations in g) and ``.csv`` file (two
  columns ``t, acc``, in m/s²) in it is one record, named by the file's stem;
* a TOML manifest (a ``.toml`` file, or a folder holding :data:`MANIFEST`), for units,
  scales and metadata:

  .. code-block:: toml

      description = "roof motions of building A, from its 2016 records"
      [[records]]
      file = "roof-ew.csv"      # relative to the manifest
      units = "g"               # "g" or "m/s2"; default g for AT2, m/s2 for CSV
      scale = 1.0               # a factor on the accelerations
      name = "roof-ew"          # default: the file's stem
      event = "Central Italy"   # optional metadata: event, year, station, component
      year = 2016

      [[records]]               # a three-component recording: a file per axis
      name = "AMT"              # the motion's name; its records are AMT-x, AMT-y, AMT-z
      x = "AMT.HNE.AT2"         # x, y horizontal, z vertical; any one may be left out
      y = "AMT.HNN.AT2"
      z = "AMT.HNZ.AT2"

:func:`read_user_set` reads the listing (:class:`UserSet`); the records themselves are
read by :meth:`rockbench.scenarios.excitation.Record.from_file`, and
:mod:`rockbench.scenarios.record_sets` serves them as any other set. A set's
:attr:`UserSet.digest` covers every file's bytes, so a changed file is a changed set.
"""

from __future__ import annotations

import dataclasses
import hashlib
from dataclasses import dataclass
from pathlib import Path

from rockbench import checks
from rockbench.errors import ScenarioError
from rockbench.tomlfile import read_toml

__all__ = ["MANIFEST", "RECORD_SUFFIXES", "UserRecord", "UserSet", "is_path", "read_user_set"]

#: The manifest a folder may hold.
MANIFEST = "records.toml"
#: Record files a folder without a manifest contributes.
RECORD_SUFFIXES = (".at2", ".csv")

_TOP = {"description", "records"}
_ENTRY = {"file", "units", "scale", "name", "event", "year", "station", "component",
          "x", "y", "z"}


@dataclass(frozen=True)
class UserRecord:
    """One record file of a user's set.

    Attributes
    ----------
    name : str
        Record name within the set.
    path : Path
        The file.
    units : str or None
        ``"g"`` or ``"m/s2"``; None: the file type's default.
    scale : float
        Factor on the accelerations.
    event, station, component : str
        Metadata ("" when not given).
    year : int
        Year of the event (0 when not given).
    axis : str
        Its axis in a three-component motion (``"x"``, ``"y"``, ``"z"``; "" alone).
    motion : str
        The name of that motion ("" alone).
    """

    name: str
    path: Path
    units: str | None
    scale: float
    event: str = ""
    station: str = ""
    component: str = ""
    year: int = 0
    axis: str = ""
    motion: str = ""


@dataclass(frozen=True)
class UserSet:
    """A user's record set: its location, description and records.

    Attributes
    ----------
    name : str
        The set's name: its resolved path.
    description : str
        From the manifest, or what the folder holds.
    records : tuple of UserRecord
        The records, in the manifest's order or by file name.
    digest : str
        SHA-256 of the manifest and every record file (16 hex digits).
    """

    name: str
    description: str
    records: tuple[UserRecord, ...]
    digest: str


def is_path(spec: str, base: Path | None = None) -> bool:
    """Whether a set name ``spec`` refers to files (a folder or a ``.toml`` manifest)."""
    return ("/" in spec or "\\" in spec or spec.lower().endswith(".toml")
            or _resolve(spec, base).exists())


def _resolve(spec: str, base: Path | None) -> Path:
    path = Path(spec).expanduser()
    return (base / path if base is not None and not path.is_absolute() else path).resolve()


def _entry(raw: object, i: int, root: Path) -> list[UserRecord]:
    """The record of a ``[[records]]`` table, or the components of a three-component one."""
    where = f"[[records]] #{i}"
    data = checks.table(raw, where)
    checks.no_unknown(data, _ENTRY, where)
    axes = [a for a in "xyz" if a in data]
    if ("file" in data) == bool(axes):
        raise ScenarioError(f"{where} needs either 'file' (one record) or 'x', 'y', 'z' "
                            f"(a file per component of one recording)")
    units = data.get("units")
    if units is not None and units not in ("g", "m/s2"):
        raise ScenarioError(f"{where} units must be 'g' or 'm/s2', got {checks.describe(units)}")
    files = {a: (root / checks.text(data[a], f"{where} {a}")).resolve() for a in axes}
    if "file" in data:
        files = {"": (root / checks.text(data["file"], f"{where} file")).resolve()}
    if axes and "x" not in axes:
        raise ScenarioError(f"{where} has {', '.join(axes)} but no 'x': the first horizontal "
                            f"component is the one a planar study runs")
    name = checks.text(data.get("name", next(iter(files.values())).stem), f"{where} name")
    one = UserRecord(
        name=name, path=next(iter(files.values())), units=units,
        scale=checks.number(data.get("scale", 1.0), f"{where} scale"),
        event=checks.text(data.get("event", ""), f"{where} event"),
        station=checks.text(data.get("station", ""), f"{where} station"),
        component=checks.text(data.get("component", ""), f"{where} component"),
        year=int(checks.integer(data.get("year", 0), f"{where} year", low=0)))
    if "file" in data:
        return [one]
    return [dataclasses.replace(one, name=f"{name}-{a}", path=path, component=a, axis=a,
                                motion=name) for a, path in files.items()]


def read_user_set(spec: str, base: Path | None = None) -> UserSet:
    """The set at ``spec``: a folder of record files, a folder with a manifest, or a manifest.

    Parameters
    ----------
    spec : str
        The path, absolute or relative to ``base`` (default: the working folder).
    base : Path, optional
        The folder relative paths start from (a scenario file's folder).

    Raises
    ------
    ScenarioError
        No such folder or file, a malformed manifest, no record, two records of one
        name, or a listed file that does not exist; the message names the file.
    """
    path = _resolve(spec, base)
    if path.is_dir() and (path / MANIFEST).is_file():
        path = path / MANIFEST
    h = hashlib.sha256()
    if path.is_dir():
        files = sorted(p for p in path.iterdir()
                       if p.is_file() and p.suffix.lower() in RECORD_SUFFIXES)
        records = tuple(UserRecord(p.stem, p, None, 1.0) for p in files)
        description = f"record files of {path}"
    elif path.is_file():
        data = read_toml(path, ScenarioError, "record set manifest")
        try:
            checks.no_unknown(data, _TOP, "the manifest")
            entries = data.get("records", [])
            if not isinstance(entries, list):
                raise ScenarioError(f"records must be an array of tables [[records]], got "
                                    f"{checks.describe(entries)}")
            records = tuple(r for i, raw in enumerate(entries, 1)
                            for r in _entry(raw, i, path.parent))
            description = checks.text(data.get("description", f"records listed in {path}"),
                                      "description")
        except ScenarioError as exc:
            raise ScenarioError(f"{path}: {exc}") from None
        h.update(path.read_bytes())
    else:
        raise ScenarioError(f"record set {spec!r}: no such folder or manifest ({path})")
    if not records:
        raise ScenarioError(f"record set {path}: no record (a folder needs .AT2 or .csv "
                            f"files; a manifest [[records]] tables)")
    names = [r.name for r in records]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise ScenarioError(f"record set {path}: two records are named {twice[0]!r}; name "
                            f"them apart (name = ...)")
    for r in records:
        try:
            h.update(r.path.read_bytes())
        except OSError as exc:
            raise ScenarioError(f"record set {path}: cannot read record file {r.path}: "
                                f"{exc.strerror or exc}") from None
    return UserSet(str(path), description, records, h.hexdigest()[:16])
