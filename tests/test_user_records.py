"""One's own records: a folder or a manifest is a record set wherever a set's name is."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rockbench.cli import main
from rockbench.errors import ScenarioError
from rockbench.scenarios import load_scenario
from rockbench.scenarios.excitation import STANDARD_GRAVITY
from rockbench.scenarios.record_sets import get_record_set, load_record
from rockbench.studies.fragility import set_records

T = np.arange(0.0, 4.0, 0.01)
ACC = 2.0 * np.sin(2 * np.pi * 1.5 * T) * np.exp(-0.5 * T)  # m/s²


def _csv(path: Path, acc: np.ndarray) -> Path:
    np.savetxt(path, np.c_[T, acc], delimiter=",", header="t,acc", comments="")
    return path


@pytest.fixture
def folder(tmp_path: Path) -> Path:
    d = tmp_path / "myrecs"
    d.mkdir()
    _csv(d / "site-a.csv", ACC)
    _csv(d / "site-b.csv", 0.5 * ACC)
    (d / "notes.txt").write_text("not a record")
    return d


def test_a_folder_is_a_set_of_its_record_files(folder: Path) -> None:
    rset = get_record_set(str(folder))
    assert [r.name for r in rset.records] == ["site-a", "site-b"]
    # the listed PGA is that of the baseline-corrected motion: within the correction of
    # the raw peak (a constant of ∫a dt / T_end)
    corr = abs(np.trapezoid(ACC, T)) / T[-1]
    assert abs(rset.records[0].pga - np.max(np.abs(ACC))) <= corr + 1e-12
    assert rset.records[1].pga == pytest.approx(0.5 * rset.records[0].pga, rel=1e-12)
    rec = load_record(str(folder), "site-b", scale=2.0)
    np.testing.assert_allclose(rec.acceleration(T), load_record(str(folder), "site-a")
                               .acceleration(T), rtol=0, atol=1e-12)


def test_a_manifest_gives_units_scales_names_and_metadata(folder: Path) -> None:
    _csv(folder / "roof.csv", ACC / STANDARD_GRAVITY)  # the same motion, in g
    (folder / "records.toml").write_text(
        'description = "roof of building A"\n'
        '[[records]]\nfile = "roof.csv"\nunits = "g"\nname = "roof-ew"\nevent = "test"\n'
        'year = 2016\n'
        '[[records]]\nfile = "site-a.csv"\nscale = 0.5\n')
    rset = get_record_set(str(folder))  # the folder's manifest wins over its listing
    assert rset.description == "roof of building A"
    assert [(r.name, r.event, r.year) for r in rset.records] == [("roof-ew", "test", 2016),
                                                                   ("site-a", "", 0)]
    roof, half = (load_record(str(folder), n) for n in ("roof-ew", "site-a"))
    np.testing.assert_allclose(roof.acceleration(T), 2.0 * half.acceleration(T), atol=1e-12)


def test_a_changed_file_is_a_changed_set(folder: Path) -> None:
    before = get_record_set(str(folder))
    _csv(folder / "site-a.csv", 3.0 * ACC)
    after = get_record_set(str(folder))
    assert after.version != before.version
    assert after.records[0].pga == pytest.approx(3.0 * before.records[0].pga, rel=1e-12)


def test_a_scenario_file_names_a_set_relative_to_itself(folder: Path) -> None:
    path = folder.parent / "roof.toml"
    path.write_text('name = "roof"\nduration = 4.0\n'
                    'blocks = [ { width = 0.25, depth = 0.25, height = 1.25, mass = 1.0 } ]\n'
                    '[excitation]\ntype = "record"\nset = "myrecs"\nrecord = "site-a"\n'
                    'scale = 1.5\n')
    sc = load_scenario(path)
    ref = load_record(str(folder), "site-a", scale=1.5)
    np.testing.assert_array_equal(sc.excitation.acceleration(T), ref.acceleration(T))


def test_the_fragility_study_takes_a_folder(folder: Path) -> None:
    recs = set_records(str(folder))
    assert [r.name for r in recs] == ["site-a", "site-b"]


@pytest.mark.parametrize("content, match", [
    ('[[records]]\nfile = "missing.csv"\n', r"cannot read record file .*missing\.csv"),
    ('[[records]]\nfile = "site-a.csv"\nunits = "mm"\n', r"units must be 'g' or 'm/s2'"),
    ('[[records]]\nfile = "site-a.csv"\n[[records]]\nfile = "site-a.csv"\n',
     r"two records are named 'site-a'"),
    ('[[records]]\nname = "x"\n', r"\[\[records\]\] #1 needs either 'file' \(one record\) or 'x'"),
    ('colour = "red"\n', r"unknown key 'colour'"),
])
def test_bad_manifests_name_the_file_and_the_field(folder: Path, content: str,
                                                   match: str) -> None:
    (folder / "set.toml").write_text(content)
    with pytest.raises(ScenarioError, match=match):
        get_record_set(str(folder / "set.toml"))


def test_an_empty_folder_or_a_wrong_path_is_refused(tmp_path: Path) -> None:
    with pytest.raises(ScenarioError, match="no record"):
        get_record_set(str(tmp_path))
    with pytest.raises(ScenarioError, match="no such folder or manifest"):
        get_record_set(str(tmp_path / "nothing" / "here"))


def test_records_lists_a_folder(folder: Path, capsys) -> None:
    assert main(["records", "--set", str(folder), "--json"]) == 0
    out = capsys.readouterr().out
    assert '"name": "site-a"' in out and '"distribution": "local files"' in out
