"""The second hostile matrix: the surfaces added after the readers' matrix
(``test_hostile_matrix.py``): drill and mill configs, the tooling store, influence
files, archive rows, Q-DAS, OPC UA, MQTT, ``health`` and ``calibrate``.

Every case ends in one of two ways: exit 2 with one line on stderr that starts
``stand: error:`` and names the key, file, row or server (``says``), or exit 0 with
a flag in what the command prints (``flags``).  No case may let a Python warning
through, end in "internal error" or a traceback, or take longer than its limit.
"""

from __future__ import annotations

import json
import shutil
import socket
import sqlite3
import threading
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import pytest
from hostile import registry

from stand.cli import main

ROOT = Path(__file__).resolve().parents[2]
CFG = (ROOT / "examples" / "demo-stand.toml").read_text()
DRILL = (ROOT / "examples" / "demo-drill.toml").read_text()
LIMIT_S = 30.0
"""No case may take longer (the slowest, a 50-drill plan, takes about 1 s)."""


@dataclass(frozen=True)
class Outcome:
    argv: list[str]
    says: str = ""
    """What the one line on stderr names (exit 2) ..."""
    flags: str = ""
    """... or what stdout must carry (exit 0)."""


Case = Callable[[Path, Path], Outcome]
"""(work dir, a good demo run) -> the command and what it must answer."""
CASES, case = registry()


def _write(d: Path, text: str, name: str = "cfg.toml") -> str:
    (d / name).write_text(text)
    return str(d / name)


def _drill(d: Path, old: str, new: str) -> str:
    assert old in DRILL, old
    return _write(d, DRILL.replace(old, new, 1))


# -- drill and mill configs: sizes and values bounded, keys that do not apply refused --

_DRILL_CASES = [
    ("10^4 drills", "[[correction.drills]]",
     "[[correction.drills]]\ndiameter_mm = 8.0\nmax_depth_mm = 20.0\n" * 10_000
     + "[[correction.drills]]", "[correction.drills]"),
    ("density 1e300", "density_kg_m3 = 7850.0", "density_kg_m3 = 1e300",
     "[correction.density_kg_m3]"),
    ("density 1e-300", "density_kg_m3 = 7850.0", "density_kg_m3 = 1e-300",
     "[correction.density_kg_m3]"),
    ("entry radius 100 m on a 90 mm plane", "entry_radius_mm = 90.0",
     "entry_radius_mm = 100000.0", "[correction.plane1.entry_radius_mm]"),
    ("entry radius 10 m on a 90 mm plane", "entry_radius_mm = 90.0",
     "entry_radius_mm = 10000.0", "[correction.plane1.entry_radius_mm]"),
    ("positions in drill mode", 'mode = "drill"', 'mode = "drill"\npositions = 6',
     "[correction.positions]"),
    ("weights_g in drill mode", 'mode = "drill"', 'mode = "drill"\nweights_g = [1.0, 2.0]',
     "[correction.weights_g]"),
    ("a [correction.mill] in drill mode", "[correction.plane1]",
     "[correction.mill]\nwidth_mm = 10.0\ndepth_mm = 5.0\n[correction.plane1]",
     "[correction.mill]"),
    ("10^4 positions_deg", "min_pitch_deg = 20.0",
     "min_pitch_deg = 20.0\npositions_deg = [" + ", ".join(["1.0"] * 10_000) + "]",
     "[correction.plane1.positions_deg]"),
    ("a sector of no arc", "min_pitch_deg = 20.0",
     "min_pitch_deg = 20.0\nsectors = [[40.0, 40.0]]", "[correction.plane1.sectors]"),
    ("a drill depth of inf", "max_depth_mm = 25.0", "max_depth_mm = inf",
     "[correction.drills.0.max_depth_mm]"),
    ("a drill diameter of nan", "diameter_mm = 20.0", "diameter_mm = nan",
     "[correction.drills.0.diameter_mm]"),
]  # fmt: skip

_MILL = DRILL.replace('mode = "drill"', 'mode = "mill"').split("[[correction.drills]]")[0] + (
    "[correction.mill]\nwidth_mm = 12.0\ndepth_mm = 4.0\n"
)

_MILL_CASES = [
    ("a slot 100 m wide", "width_mm = 12.0", "width_mm = 100000.0", "[correction.mill.width_mm]"),
    ("a slot 1 m wide on a 90 mm plane", "width_mm = 12.0", "width_mm = 1000.0",
     "[correction.mill.width_mm]"),
    ("drills in mill mode", "[correction.mill]",
     "[[correction.drills]]\ndiameter_mm = 8.0\nmax_depth_mm = 20.0\n[correction.mill]",
     "[correction.drills]"),
    ("positions_deg in mill mode", "[correction.mill]",
     "[correction.plane1]\npositions_deg = [0.0, 90.0]\n[correction.mill]",
     "[correction.plane1.positions_deg]"),
    ("max_holes in mill mode", 'mode = "mill"', 'mode = "mill"\nmax_holes = 3',
     "[correction.max_holes]"),
]  # fmt: skip

for _surface, _base, _cases in (("drill", DRILL, _DRILL_CASES), ("mill", _MILL, _MILL_CASES)):
    for _name, _old, _new, _says in _cases:
        assert _old in _base, _old

        def _config_case(
            d: Path, run: Path, text: str = _base.replace(_old, _new, 1), says: str = _says
        ) -> Outcome:
            return Outcome(["solve", str(run), "--config", _write(d, text)], says)

        case(f"{_surface}: {_name}")(_config_case)


@case("drill: a sector list covering every angle is planned")
def _full_circle(d: Path, run: Path) -> Outcome:
    cfg = _drill(d, "min_pitch_deg = 20.0", "min_pitch_deg = 20.0\nsectors = [[0.0, 360.0]]")
    return Outcome(["solve", str(run), "--config", cfg], flags="drill")


@case("drill: a drill table in remove mode is refused")
def _drills_in_remove(d: Path, run: Path) -> Outcome:
    old = "positions = 0"
    assert old in CFG
    text = CFG.replace(old, old + "\ndrills = [{diameter_mm = 8.0, max_depth_mm = 20.0}]")
    return Outcome(["solve", str(run), "--config", _write(d, text)], "[correction.drills]")


# -- archive rows: what no run of this software wrote, refused and named --


@pytest.fixture(scope="module")
def archive(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Four rotors of the production-drift scene balanced, corrected and checked: eight
    runs, sixteen plane rows, four calibration data."""
    d = tmp_path_factory.mktemp("archive")
    url = f"sqlite:///{d / 'a.sqlite'}"
    args = ["simulate", "production-drift", "--series", "4", "--out-dir", str(d / "runs")]
    assert main([*args, "--archive", url]) == 0
    return d / "a.sqlite"


ARCHIVE: dict[str, Path] = {}
"""The module's archive, set by the matrix's test for the cases that need it."""


def _tampered(d: Path, sql: str, *params: object) -> str:
    """A copy of the series' archive with one statement run on it; its URL."""
    copy = d / "a.sqlite"
    shutil.copy(ARCHIVE["series"], copy)
    with sqlite3.connect(copy) as conn:
        assert conn.execute(sql, params).rowcount >= 1, sql
    return f"sqlite:///{copy}"


_QDAS = ["export", "qdas", "--rotor-type", "auger-A", "-o"]
_ROW_CASES = [
    ("a verdict 'maybe'", "UPDATE runs SET verdict = 'maybe' WHERE id = 3", (), ["history"],
     "table runs, run 3, column verdict"),
    ("a time 'yesterday' in Q-DAS", "UPDATE runs SET start_time = 'yesterday' WHERE id = 2", (),
     _QDAS, "table runs, run 2, column start_time"),
    ("an infinite unbalance in Q-DAS", "UPDATE planes SET U_re_kg_m = 9e999 WHERE run_id = 1",
     (), _QDAS, "table planes, run 1 plane 1, column U_re_kg_m"),
    ("a radius 'NaN'", "UPDATE planes SET radius95_kg_m = 'NaN' WHERE run_id = 4 AND plane = 2",
     (), ["history"], "column radius95_kg_m"),
    ("a pass 'maybe'", "UPDATE planes SET passed = 'maybe' WHERE run_id = 2", (), ["history"],
     "column passed"),
    ("a speed 'fast' in stats", "UPDATE runs SET rpm = 'fast' WHERE id = 5", (),
     ["stats", "--rotor-type", "auger-A"], "table runs, run 5, column rpm"),
    ("a serial of 10^5 characters", "UPDATE runs SET serial = ? WHERE id = 1", ("S" * 10**5,),
     ["history"], "column serial"),
    ("a digest that is not one", "UPDATE runs SET file_sha256 = 'x' WHERE id = 6", (),
     ["history"], "column file_sha256"),
    ("a correction mode 'weld'", "UPDATE runs SET correction_mode = 'weld' WHERE id = 7", (),
     ["history"], "column correction_mode"),
    ("two serials one in Windows-1252", "UPDATE runs SET serial = CASE WHEN id < 5 "
     "THEN 'A-\u03a91' ELSE 'A-\u03a81' END", (), _QDAS, "one part ident"),
    ("an empty start time in Q-DAS", "UPDATE runs SET start_time = '' WHERE id = 2", (),
     _QDAS, ""),
    ("a calibration datum that is not JSON", "UPDATE corrections SET datum_json = 'oops' "
     "WHERE id = 2", (), ["health"], "table corrections, datum 2, column datum_json"),
    ("a calibration datum with NaN", "UPDATE corrections SET datum_json = "
     "replace(datum_json, '\"omega_rad_s\": ', '\"omega_rad_s\": NaN, \"x\": ') WHERE id = 1",
     (), ["health"], "column datum_json"),
    ("a calibration datum without A1", "UPDATE corrections SET datum_json = "
     "replace(datum_json, '\"A1\"', '\"B1\"') WHERE id = 3", (),
     ["calibrate", "--from-archive", "--config", str(ROOT / "examples/demo-stand.toml")],
     "column datum_json"),
    ("a calibration datum at -900 rpm", "UPDATE corrections SET rpm = -900 WHERE id = 4", (),
     ["health"], "table corrections, datum 4, column rpm"),
]  # fmt: skip

for _name, _sql, _params, _argv, _says in _ROW_CASES:

    def _row_case(
        d: Path, run: Path, sql: str = _sql, params: tuple = _params, argv: list = _argv,
        says: str = _says,
    ) -> Outcome:  # fmt: skip
        url = _tampered(d, sql, *params)
        tail = [str(d / "out.dfq")] if argv is _QDAS else []
        return Outcome([*argv, *tail, "--archive", url], says)

    case(f"{'qdas' if _argv is _QDAS else 'archive'}: {_name}")(_row_case)


def silent_server() -> int:
    """A TCP port on loopback that accepts connections and never says a word; its port."""
    listener = socket.create_server(("127.0.0.1", 0))
    held: list[socket.socket] = []

    def accept() -> None:
        while True:
            conn, _ = listener.accept()
            held.append(conn)

    threading.Thread(target=accept, daemon=True).start()
    return int(listener.getsockname()[1])


@case("archive: a PostgreSQL server that accepts and stays silent")
def _silent_postgres(d: Path, run: Path) -> Outcome:
    url = f"postgresql+psycopg://stand@127.0.0.1:{silent_server()}/stand"
    return Outcome(["history", "--archive", url], "did not answer within its connect timeout")


def _edited_data(d: Path, edit: Callable[[sqlite3.Connection], None]) -> str:
    """A copy of the series' archive with its calibration data edited; its URL."""
    copy = d / "a.sqlite"
    shutil.copy(ARCHIVE["series"], copy)
    with sqlite3.connect(copy) as conn:
        edit(conn)
    return f"sqlite:///{copy}"


def _scale_response(conn: sqlite3.Connection, ids: tuple[int, ...], k: float) -> None:
    """The stand's response to the correction (A1 - A0) of these data times ``k``."""
    for i in ids:
        (text,) = conn.execute("SELECT datum_json FROM corrections WHERE id = ?", (i,)).fetchone()
        datum = json.loads(text)
        datum["A1"] = [[a0 + k * (a1 - a0) for a0, a1 in zip(p0, p1, strict=True)]
                       for p0, p1 in zip(datum["A0"], datum["A1"], strict=True)]  # fmt: skip
        conn.execute("UPDATE corrections SET datum_json = ? WHERE id = ?", (json.dumps(datum), i))


def _copies(conn: sqlite3.Connection) -> None:
    """Three corrections, and the first copied 40 times under other check digests."""
    conn.execute("DELETE FROM corrections WHERE id = 4")
    cols = [r[1] for r in conn.execute("PRAGMA table_info(corrections)") if r[1] != "id"]
    row = conn.execute(f"SELECT {', '.join(cols)} FROM corrections WHERE id = 1").fetchone()
    for k in range(40):
        copy = dict(zip(cols, row, strict=True)) | {"check_sha256": f"{k:064x}"}
        marks = ", ".join("?" * len(cols))
        conn.execute(f"INSERT INTO corrections ({', '.join(cols)}) VALUES ({marks})",
                     [copy[c] for c in cols])  # fmt: skip


_DEMO = str(ROOT / "examples" / "demo-stand.toml")
_SERIES_CFG: dict[str, str] = {}


def _series_config(d: Path) -> str:
    """The calibration the series' data were made with (its first run's stored config)."""
    run = sorted((ARCHIVE["series"].parent / "runs").glob("*.h5"))[0]
    out = d / "series.toml"
    assert main(["inspect", str(run), "--config-out", str(out)]) == 0
    return str(out)


@case("health: a change a million times the model's")
def _huge_change(d: Path, run: Path) -> Outcome:
    url = _edited_data(d, lambda c: _scale_response(c, (3, 4), 1e6))
    return Outcome(["health", "--archive", url], flags="ALARM")


@case("calibrate: a change a million times the model's")
def _huge_refit(d: Path, run: Path) -> Outcome:
    url = _edited_data(d, lambda c: _scale_response(c, (3, 4), 1e6))
    cfg = _series_config(d)
    argv = ["calibrate", "--from-archive", "--config", cfg, "--archive", url]
    return Outcome(argv, "beyond any chance of the calibrated stand")


@case("health: 40 copies of one datum under other digests")
def _copied_health(d: Path, run: Path) -> Outcome:
    return Outcome(["health", "--archive", _edited_data(d, _copies)], flags="40 data left out")


@case("calibrate: three corrections and 40 copies under other digests")
def _copied_refit(d: Path, run: Path) -> Outcome:
    url, cfg = _edited_data(d, _copies), _series_config(d)
    argv = ["calibrate", "--from-archive", "--config", cfg, "--archive", url]
    return Outcome(argv, "3 data since the change: too few")


def _tooling_runs(d: Path, *second: str) -> tuple[str, str, str]:
    """A tooling config and its two index runs (the second with ``second``'s options)."""
    cfg = _write(d, CFG + f'\n[tooling]\nname = "mandrel-A"\nfolder = "{d / "toolings"}"\n')
    runs = []
    for name, extra in (("r0.h5", ()), ("r180.h5", ("--index", "180", *second))):
        runs.append(str(d / name))
        assert main(["simulate", "tooling", "--out", runs[-1], "--config", cfg, *extra]) == 0
    return cfg, runs[0], runs[1]


@case("tooling: the same run twice")
def _tooling_twice(d: Path, run: Path) -> Outcome:
    cfg, r0, _ = _tooling_runs(d)
    return Outcome(["tooling", "measure", r0, r0, "--config", cfg], "the same run given twice")


@case("tooling: a byte copy as the 180 deg run")
def _tooling_copy(d: Path, run: Path) -> Outcome:
    cfg, r0, _ = _tooling_runs(d)
    shutil.copy(r0, d / "copy.h5")
    argv = ["tooling", "measure", r0, str(d / "copy.h5"), "--config", cfg]
    return Outcome(argv, "are the same data")


@case("tooling: index runs at two speeds")
def _tooling_speeds(d: Path, run: Path) -> Outcome:
    cfg, r0, r180 = _tooling_runs(d, "--rpm", "800")
    return Outcome(["tooling", "measure", r0, r180, "--config", cfg], "differ in speed")


GOODMAN = (ROOT / "examples" / "published" / "goodman-1964.toml").read_text()
_ENTRY, _READINGS = "[[3, 0], [2, 180]]", "sensors = [[1, 0], [1, 180], [0, 0]]"
_INFLUENCE_CASES = [
    ("a matrix entry of 1e308", _ENTRY, "[[1e308, 0], [2, 180]]", "[matrix.0.0.0]"),
    ("a matrix entry of 1e300", _ENTRY, "[[1e300, 0], [2, 180]]", "[matrix.0.0.0]"),
    ("a phase of inf", _ENTRY, "[[3, inf], [2, 180]]", "[matrix.0.0.1]"),
    ("readings of 1e308", _READINGS, "sensors = [[1e308, 0], [1e308, 180], [0, 0]]",
     "[runs.0.sensors.0.0]"),
]  # fmt: skip

for _name, _old, _new, _says in _INFLUENCE_CASES:
    assert _old in GOODMAN, _old

    def _influence_case(d: Path, run: Path, text: str = GOODMAN.replace(_old, _new, 1),
                        says: str = _says) -> Outcome:  # fmt: skip
        return Outcome(["influence", _write(d, text, "runs.toml")], says)

    case(f"influence: {_name}")(_influence_case)


@case("influence: entries and readings of 1e12 (the bound) are solved")
def _influence_at_bound(d: Path, run: Path) -> Outcome:
    text = GOODMAN.replace(_ENTRY, "[[1e12, 0], [2, 180]]").replace(
        _READINGS, "sensors = [[1e12, 0], [1e12, 180], [0, 0]]"
    )
    return Outcome(["influence", _write(d, text, "runs.toml")], flags="condition number")


@case("influence: a stored matrix of 1e308")
def _stored_matrix(d: Path, run: Path) -> Outcome:
    saved = d / "m.json"
    assert main(["influence", _write(d, GOODMAN, "runs.toml"), "--save", str(saved)]) == 0
    doc = json.loads(saved.read_text())
    doc["alpha_per_kg_m"][0][0] = [1e308, 0.0]
    saved.write_text(json.dumps(doc))
    return Outcome(["solve", str(run), "--matrix", str(saved)], "[alpha_per_kg_m.0.0.0]")


def _stored_tooling(d: Path, edit: Callable[[dict], object]) -> tuple[str, str]:
    """A tooling measured from its index runs, its file then edited; (config, a run)."""
    cfg, r0, r180 = _tooling_runs(d)
    assert main(["tooling", "measure", r0, r180, "--config", cfg]) == 0
    path = d / "toolings" / "mandrel-A.json"
    doc = json.loads(path.read_text())
    edit(doc)
    path.write_text(json.dumps(doc))
    return cfg, r0


_TOOLING_FILES = [
    ("an unbalance of 1e308", lambda t: t["unbalance_kg_m"].__setitem__(0, [1e308, 0.0])),
    ("an unbalance of NaN", lambda t: t["unbalance_kg_m"].__setitem__(0, [float("nan"), 0.0])),
    ("a negative variance", lambda t: t["cov_U"][0].__setitem__(0, -1.0)),
    ("a speed of -1 rad/s", lambda t: t.__setitem__("omega_rad_s", -1.0)),
    ("a 3 x 3 covariance", lambda t: t.__setitem__("cov_U", [[1, 0, 0], [0, 1, 0], [0, 0, 1]])),
    ("two planes as one", lambda t: t["unbalance_kg_m"].pop()),
]

for _name, _edit in _TOOLING_FILES:

    def _tooling_file_case(d: Path, run: Path, edit: Callable[[dict], object] = _edit) -> Outcome:
        cfg, r0 = _stored_tooling(d, edit)
        return Outcome(["solve", r0, "--config", cfg], "mandrel-A.json: not a tooling file")

    case(f"tooling: a stored tooling with {_name}")(_tooling_file_case)


@case("tooling: a stored tooling file of 2 MiB")
def _tooling_huge(d: Path, run: Path) -> Outcome:
    cfg, r0 = _stored_tooling(d, lambda t: t.__setitem__("pad", "x" * (2 << 20)))
    return Outcome(["solve", r0, "--config", cfg], "not a tooling file (")


@case("mqtt: a port of 99999")
def _mqtt_port(d: Path, run: Path) -> Outcome:
    cfg = _write(d, CFG + '\n[plant]\nmqtt_url = "mqtt://broker:99999"\n')
    return Outcome(["solve", str(run), "--config", cfg], "[plant.mqtt_url]")


@case("mqtt: a URL with credentials")
def _mqtt_user(d: Path, run: Path) -> Outcome:
    cfg = _write(d, CFG + '\n[plant]\nmqtt_url = "mqtt://user:secret@broker"\n')
    return Outcome(["solve", str(run), "--config", cfg], "[plant.mqtt_url]")


@case("mqtt: a broker that accepts and stays silent")
def _mqtt_silent(d: Path, run: Path) -> Outcome:
    url = f"mqtt://127.0.0.1:{silent_server()}"
    cfg = _write(d, CFG + f'\n[plant]\nmqtt_url = "{url}"\n')
    argv = ["measure", "--scene", "demo", "--config", cfg, "--out", str(d / "m.h5"),
            "--archive", f"sqlite:///{d / 'a.sqlite'}", "--quiet"]  # fmt: skip
    return Outcome(argv, flags="not published over MQTT")


@case("archive: simulate --archive without --series")
def _simulate_archive(d: Path, run: Path) -> Outcome:
    argv = ["simulate", "demo", "--out", str(d / "r.h5"), "--archive", f"sqlite:///{d}/a.db"]
    return Outcome(argv, "--archive and --out-dir go with --series")


@case("opcua: an archive that is no database")
def _opcua_not_a_database(d: Path, run: Path) -> Outcome:
    (d / "notes.sqlite").write_text("these are notes, not a database\n" * 100)
    url = f"sqlite:///{d / 'notes.sqlite'}"
    return Outcome(["opcua", "--archive", url, "--port", "48999"], "not a database")


# -- the matrix --

OUTCOMES: dict[str, str] = {}


@pytest.mark.parametrize("name", list(CASES))
def test_a_hostile_surface_ends_cleanly(
    name: str,
    demo_run: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    request: pytest.FixtureRequest,
) -> None:
    if name.startswith(("archive:", "qdas:", "health:", "calibrate:")):
        ARCHIVE["series"] = request.getfixturevalue("archive")
    want = CASES[name](tmp_path, demo_run)
    capsys.readouterr()
    t0 = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        code = main(want.argv)
    took = time.perf_counter() - t0
    out, err = capsys.readouterr()
    lines = err.strip().splitlines()
    OUTCOMES[name] = "clean" if code == 2 else "flagged" if code == 0 else "wrong"
    assert not caught, [str(w.message) for w in caught]
    assert "internal error" not in err and "Traceback" not in err, err
    assert took < LIMIT_S, f"{took:.1f} s"
    if want.says:
        assert code == 2 and len(lines) == 1 and lines[0].startswith("stand: error: "), err
        assert want.says in lines[0], err
        assert len(lines[0]) < 600, f"a line of {len(lines[0])} characters"  # one line to read
    else:
        assert code == 0, err
        assert want.flags in out + err, (out, err)


def test_the_second_matrix_counts() -> None:
    """Every surface the issue names carries cases."""
    surfaces = {name.split(":")[0] for name in CASES}
    assert {
        "drill",
        "mill",
        "archive",
        "tooling",
        "health",
        "calibrate",
        "opcua",
        "influence",
    } <= surfaces
