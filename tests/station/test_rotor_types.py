"""The rotor types at the station (:mod:`stand.station.rotor_types`): a setter loads one
and sets its tooling, an engineer edits a tolerance; a change the role may not make is
refused saying why; every change keeps the file it replaces and writes one journal entry;
a hostile file is refused in one line."""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from accounts import with_accounts

from stand.actions import Actor, config_seen
from stand.archive.audit import entries, file_sha256, verify_journal
from stand.config import load_config
from stand.errors import StandError
from stand.i18n.language import ENGLISH, language
from stand.solve.pipeline import precision_targets
from stand.solve.tooling import Tooling, save_tooling
from stand.station import Station
from stand.station.rotor_types import load_rotor_type, set_tolerance, set_tooling
from stand.station.sessions import Session

ROTORS = Path(__file__).resolve().parents[2] / "stand" / "data" / "rotors"
DEMO = (ROTORS / "demo-auger.toml").read_text()


def _targets(cfg: Any, params: Any, U: Any) -> tuple[float, float]:
    return precision_targets(cfg, params, U, tolerance_share=0.10)


def _who(role: str) -> Session:
    return Session(role[:3], role, "t", None, 1e18)


@pytest.fixture
def station(tmp_path: Path) -> Station:
    folder = tmp_path / "rotors"
    folder.mkdir()
    shutil.copy(ROTORS / "demo-auger.toml", folder)
    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    with_accounts(url, *((role[:3], role, "a-long-password")
                         for role in ("operator", "setter", "engineer")))  # fmt: skip
    return Station(folder, tmp_path / "runs", url, _targets)


def _file(type_name: str = "auger-b", **swap: str) -> bytes:
    text = DEMO.replace('type = "demo-auger"', f'type = "{type_name}"')
    for old, new in swap.items():
        assert old in text, old
        text = text.replace(old, new)
    return text.encode()


def _load(station: Station, who: str, data: bytes, *, replace: bool = False,
          reason: str = "new order 4711") -> str:  # fmt: skip
    return load_rotor_type(station, _who(who), "x.toml", data, replace=replace, reason=reason,
                           _=ENGLISH)  # fmt: skip


def test_a_setter_loads_a_rotor_type_journaled_and_the_start_finds_nothing_new(
    station: Station,
) -> None:
    assert _load(station, "setter", _file()) == "auger-b"
    path = station.config_dir / "auger-b.toml"
    assert "auger-b" in station.rotor_types()
    (entry,) = entries(station.archive_url, action="config")
    assert entry["who"] == "set" and entry["reason"] == "new order 4711"
    assert entry["old_sha256"] is None and entry["new_sha256"] == file_sha256(path)
    again = config_seen(station.archive_url, Actor("set", None, "station"), path)
    assert again is None  # no second entry
    assert verify_journal(station.archive_url).problem is None


def test_roles_decide_who_may_change_what(station: Station) -> None:
    with pytest.raises(StandError, match=r"refused: ope \(operator\) may not load a rotor type"):
        _load(station, "operator", _file())
    stricter = _file("demo-auger", **{"grade_mm_s = 6.3": "grade_mm_s = 2.5"})
    with pytest.raises(StandError, match="may not change a tolerance: it takes engineer"):
        _load(station, "setter", stricter, replace=True)
    stiffer = _file(**{"C1 = 4.5e4": "C1 = 4.6e4"})  # another calibration, by a file
    with pytest.raises(StandError, match="may not change the stand's calibration"):
        _load(station, "setter", stiffer)
    assert not entries(station.archive_url, action="config")  # refused: nothing written
    _load(station, "engineer", stricter, replace=True)
    assert load_config(station.config_dir / "demo-auger.toml")[0].tolerance.grade_mm_s == 2.5
    kept = list((station.config_dir / ".history").glob("demo-auger-*.toml"))
    assert len(kept) == 1 and kept[0].read_text() == DEMO  # the file replaced, kept
    (entry,) = entries(station.archive_url, action="config")
    assert entry["old_sha256"] == file_sha256(kept[0])


def test_an_engineer_edits_a_grade_tolerance_in_place(station: Station) -> None:
    with pytest.raises(StandError, match="may not change a tolerance"):
        set_tolerance(station, _who("setter"), "demo-auger", grade_mm_s=2.5,
                      max_speed_rpm=1500, source="", reason="drawing rev B", _=ENGLISH)  # fmt: skip
    set_tolerance(station, _who("engineer"), "demo-auger", grade_mm_s=2.5, max_speed_rpm=1800,
                  source="drawing 4711 rev B", reason="drawing rev B", _=ENGLISH)  # fmt: skip
    path = station.config_dir / "demo-auger.toml"
    t = load_config(path)[0].tolerance
    assert (t.grade_mm_s, t.max_speed_rpm, t.source) == (2.5, 1800, "drawing 4711 rev B")
    assert "# kg, moving mass of support 1" in path.read_text()  # the file's comments kept
    with pytest.raises(StandError, match="grade_mm_s"):  # out of bounds: said, not written
        set_tolerance(station, _who("engineer"), "demo-auger", grade_mm_s=1e-9,
                      max_speed_rpm=1800, source="", reason="typo", _=ENGLISH)  # fmt: skip
    assert len(entries(station.archive_url, action="config")) == 1


def test_a_setter_sets_and_removes_a_tooling(station: Station, tmp_path: Path) -> None:
    where = tmp_path / "toolings"
    text = DEMO + f'\n[tooling]\nname = "none-yet"\nfolder = "{where}"\n'
    (station.config_dir / "demo-auger.toml").write_text(text)
    save_tooling(Tooling("mandrel-A", (1e-5, 2e-5), np.eye(4) * 1e-14, "2026-11-27T10:00:00Z",
                         "0" * 64, ("a.h5", "b.h5"), 94.2), where)  # fmt: skip
    with pytest.raises(StandError, match="no measured tooling mandrel-B"):
        set_tooling(station, _who("setter"), "demo-auger", "mandrel-B", reason="x", _=ENGLISH)
    set_tooling(station, _who("setter"), "demo-auger", "mandrel-A", reason="swap", _=ENGLISH)
    assert load_config(station.config_dir / "demo-auger.toml")[0].tooling.name == "mandrel-A"
    set_tooling(station, _who("setter"), "demo-auger", None, reason="off", _=ENGLISH)
    assert load_config(station.config_dir / "demo-auger.toml")[0].tooling is None
    assert [e["reason"] for e in entries(station.archive_url, action="config")] == ["swap", "off"]


@pytest.mark.parametrize(("data", "why"), [
    (b"\xff\xfe not text", "not UTF-8"),
    (b"[stand\nM1 = ", "not valid TOML"),
    (b"[stand]\nM1 = -1\n", "x.toml"),
    (_file("../../etc/x"), "cannot name a rotor type"),
    (_file("demo-auger"), "exists: tick replace"),
    (b"#" * (300 * 1024), "under 256 kiB"),
    (_file(**{'name = "demo stand"': 'name = "demo stand"\nid = "other-stand"'}),
     "names stand other-stand"),
])  # fmt: skip
def test_a_hostile_file_is_refused_in_one_line(station: Station, data: bytes, why: str) -> None:
    with pytest.raises(StandError, match=why) as caught:
        _load(station, "setter", data)
    assert "\n" not in str(caught.value)
    assert station.rotor_types() == ["demo-auger"]
    assert not entries(station.archive_url, action="config")


def test_no_reason_no_change_and_the_refusal_in_the_accounts_language(
    station: Station,
) -> None:
    with pytest.raises(StandError, match="give the reason"):
        _load(station, "setter", _file(), reason="  ")
    with pytest.raises(StandError, match="відмовлено"):
        load_rotor_type(station, _who("operator"), "x.toml", _file(), replace=False,
                        reason="r", _=language("uk"))  # fmt: skip


def test_a_lone_stand_journals_the_computers_user(tmp_path: Path) -> None:
    folder = tmp_path / "rotors"
    folder.mkdir()
    shutil.copy(ROTORS / "demo-auger.toml", folder)
    st = Station(folder, tmp_path / "runs", f"sqlite:///{tmp_path / 'a.sqlite'}", _targets)
    load_rotor_type(st, None, "x.toml", _file(), replace=False, reason="r", _=ENGLISH)
    (entry,) = entries(st.archive_url, action="config")
    assert entry["who"].startswith("os:")


def test_the_shipped_demo_rotor_types_are_never_changed(tmp_path: Path) -> None:
    st = Station(ROTORS, tmp_path / "runs", f"sqlite:///{tmp_path / 'a.sqlite'}", _targets)
    with pytest.raises(StandError, match="shipped demo rotor types: start the station with"):
        load_rotor_type(st, None, "x.toml", _file(), replace=False, reason="r", _=ENGLISH)
    assert st.rotor_types() == ["demo-auger", "demo-auger-drilled"]


@pytest.mark.parametrize(("from_rotor", "written"), [(100000, False), (1, True)])
def test_an_engineer_recalibrates_from_the_archive_when_the_change_is_significant(
    tmp_path: Path, from_rotor: int, written: bool
) -> None:
    """Twelve corrected rotors archived: on a stand as calibrated the refit keeps the
    calibration and writes nothing; on one whose support 1 is 8 % softer it writes the
    new calibration in place, journaled as a calibration (the Start finds nothing new)."""
    from stand.cli import main
    from stand.config import config_toml
    from stand.sim import load_scene
    from stand.station.rotor_types import recalibrate

    scene = tmp_path / "drift.toml"
    scene.write_text((Path(__file__).resolve().parents[2] / "stand" / "data" / "scenes"
                      / "production-drift.toml").read_text()
                     .replace("from_rotor = 100", f"from_rotor = {from_rotor}"))  # fmt: skip
    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    assert main(["simulate", str(scene), "--series", "12", "--out-dir", str(tmp_path / "runs"),
                 "--archive", url]) == 0  # fmt: skip
    folder = tmp_path / "rotors"
    folder.mkdir()
    cfg = load_scene(str(scene))[0].config()
    (folder / f"{cfg.rotor.type}.toml").write_text(config_toml(cfg))
    with_accounts(url, ("eva", "engineer", "a-long-password"), ("ana", "setter", "a-long-password"))
    st = Station(folder, tmp_path / "st-runs", url, _targets)
    with pytest.raises(StandError, match="may not change the stand's calibration"):
        recalibrate(st, _who("setter"), cfg.rotor.type, reason="drift", _=ENGLISH)
    before = (folder / f"{cfg.rotor.type}.toml").read_text()
    said = recalibrate(st, Session("eva", "engineer", "t", None, 1e18), cfg.rotor.type,
                       reason="stand health alarm", _=ENGLISH)  # fmt: skip
    path = folder / f"{cfg.rotor.type}.toml"
    if not written:
        assert said.startswith("no significant change: keep the calibration (C1 ")
        assert path.read_text() == before and not entries(url, action="calibration")
        return
    assert said.startswith("calibration written and journaled: C1 -")
    c1 = load_config(path)[0].stand.C1
    assert c1 == pytest.approx(0.92 * cfg.stand.C1, rel=0.03)  # 8 % softer, found
    (entry,) = entries(url, action="calibration")
    assert entry["who"] == "eva" and entry["new_sha256"] == file_sha256(path)
    assert config_seen(url, Actor("eva", None, "station"), path) is None


def test_a_history_folder_that_cannot_be_made_changes_nothing(station: Station) -> None:
    (station.config_dir / ".history").write_text("a file where the folder goes")
    stricter = _file("demo-auger", **{"grade_mm_s = 6.3": "grade_mm_s = 2.5"})
    with pytest.raises(StandError, match="cannot keep the file it replaces here") as caught:
        _load(station, "engineer", stricter, replace=True)
    assert "\n" not in str(caught.value)
    assert (station.config_dir / "demo-auger.toml").read_text() == DEMO
    assert not entries(station.archive_url, action="config")
