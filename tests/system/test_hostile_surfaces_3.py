"""The third hostile matrix: the surfaces added in the month of the ball balancer and the
rocker (their bounds against the whole), reprocess, the Q-DAS time zone and the tooling
store, the machine's own tests (evaluate, residual, capability), and this month's plant
surfaces (Q-DAS evaluations and idents, the config's archive for series, imports and the
station).

Every case ends in exit 2 with one line on stderr that starts ``stand: error:`` and names
what and where (``says``).  No case may let a Python warning through, end in "internal
error" or a traceback, or take longer than :data:`LIMIT_S` (a hang guard: each takes under
a second idle).
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest
from hostile import refused_in_one_line

from stand.cli import main

ROOT = Path(__file__).resolve().parents[2]
ROCKER = (ROOT / "examples" / "grinder-rocker.toml").read_text()
LIMIT_S = 30.0
"""A hang guard, not a speed figure."""


def _rocker(tmp: Path, old: str, new: str) -> list[str]:
    assert old in ROCKER, old
    path = tmp / "rocker.toml"
    path.write_text(ROCKER.replace(old, new, 1))
    return ["autobalance", "--rocker", str(path)]


def _archive(tmp: Path) -> str:
    return f"sqlite:///{tmp / 'a.sqlite'}"


def _negative_matrix(tmp: Path) -> list[str]:
    path = tmp / "runs.toml"
    path.write_text("matrix = [[[-3.0, 0.0], [1.0, 0.0]], [[1.0, 0.0], [2.0, 0.0]]]\n\n"
                    "[[runs]]\nsensors = [[1.0, 0.0], [1.0, 0.0]]\n")  # fmt: skip
    return ["influence", str(path)]


def _stiff(tmp: Path) -> list[str]:
    from stand.sim import shipped_scenes

    text = Path(str(shipped_scenes()["demo-balls"])).read_text()
    path = tmp / "stiff.toml"
    path.write_text(text.replace("drag_n_s_m = 0.5", "drag_n_s_m = 5000.0"))
    return ["simulate", str(path), "--out", str(tmp / "s.h5")]


def _file(tmp: Path) -> str:
    path = tmp / "a-file"
    path.write_text("x")
    return str(path)


def _not_toml(tmp: Path) -> str:
    path = tmp / "bad.toml"
    path.write_text("x = [\n")
    return str(path)


def _long_serial(tmp: Path) -> list[str]:
    run = tmp / "r.h5"
    assert main(["simulate", "demo", "--out", str(run), "--serial", "S" * 41, "--config",
                 str(ROOT / "examples" / "demo-stand.toml")]) == 0  # fmt: skip
    assert main(["archive", "import", str(run), "--archive", _archive(tmp)]) == 0
    return [
        "export",
        "qdas",
        "--rotor-type",
        "demo-auger",
        "--archive",
        _archive(tmp),
        "-o",
        str(tmp / "x.dfq"),
    ]


def _two_archives(tmp: Path) -> list[str]:
    rotors = tmp / "rotors"
    rotors.mkdir()
    text = (ROOT / "stand" / "data" / "rotors" / "demo-auger.toml").read_text()
    for k in (1, 2):
        (rotors / f"type-{k}.toml").write_text(
            text + f'\n[archive]\nurl = "sqlite:///{tmp}/a{k}.sqlite"\n'
        )
    return ["station", "--config-dir", str(rotors), "--no-browser", "--port", "1"]


BALLS = ["autobalance", "--scene", "demo-balls", "--rpm", "900"]
CASES: dict[str, tuple[Callable[[Path], list[str]], str]] = {
    "ball of 1e-300 g": (lambda t: [*BALLS, "--ball-g", "1e-300"], "[autobalancer.ball_g]"),
    "race of 1e-300 mm": (lambda t: [*BALLS, "--radius-mm", "1e-300"], "[autobalancer.radius_mm]"),
    "a 5 m race on a 90 mm plane": (lambda t: [*BALLS, "--radius-mm", "5000"], "beyond 1.5 times"),
    "a 0.2 m race on a 90 mm plane": (lambda t: [*BALLS, "--radius-mm", "200"], "beyond 1.5"),
    "640 kg of balls on 60 kg": (lambda t: [*BALLS, "--ball-g", "10000"], "more than 10 %"),
    "rocker: one ball": (lambda t: _rocker(t, "balls = 2", "balls = 1"), "[rocker.balls]"),
    "rocker: hinge 1e-300": (lambda t: _rocker(t, "hinge_c_n_m = 2000.0", "hinge_c_n_m = 1e-300"),
                             "[rocker.hinge_c_n_m]"),
    "rocker: cutting angle 3.2 rad": (lambda t: _rocker(t, "gamma_rad = 1.4", "gamma_rad = 3.2"),
                                      "gamma_rad"),
    "rocker: contact geometry 10 m": (
        lambda t: _rocker(t, "disc_radius_m = 0.0625", "disc_radius_m = 10.0"), "disc_radius_m"),
    "rocker: race outside the disc": (
        lambda t: _rocker(t, "race_radius_m = 0.03", "race_radius_m = 0.07"), "outside the disc"),
    "reprocess: revision of spaces": (
        lambda t: ["reprocess", "--archive", _archive(t), "--revision", "   "], "--revision"),
    "reprocess: revision with a control character": (
        lambda t: ["reprocess", "--archive", _archive(t), "--revision", "r\x01"], "--revision"),
    "reprocess: revision of 65 characters": (
        lambda t: ["reprocess", "--archive", _archive(t), "--revision", "r" * 65], "--revision"),
    "reprocess: runs root a file": (
        lambda t: ["reprocess", "--archive", _archive(t), "--revision", "r", "--runs-root",
                   _file(t)], "a file"),
    "reprocess: runs root missing": (
        lambda t: ["reprocess", "--archive", _archive(t), "--revision", "r", "--runs-root",
                   str(t / "gone")], "not there"),
    "qdas: empty time zone": (
        lambda t: ["export", "qdas", "--rotor-type", "x", "--archive", _archive(t), "--timezone",
                   "", "-o", str(t / "x.dfq")], "no such IANA zone"),
    "qdas: a time zone of 5000 characters": (
        lambda t: ["export", "qdas", "--rotor-type", "x", "--archive", _archive(t), "--timezone",
                   "A" * 5000, "-o", str(t / "x.dfq")], "(5000 characters)"),
    "qdas: a time zone of spaces": (
        lambda t: ["export", "qdas", "--rotor-type", "x", "--archive", _archive(t), "--timezone",
                   "   ", "-o", str(t / "x.dfq")], "no such IANA zone"),
    "tooling: folder a file": (
        lambda t: ["tooling", "show", "--folder", _file(t)], "is a file"),
    "evaluate: URR claim of 0": (
        lambda t: ["evaluate", "--scene", "demo", "--urr-claim", "0"], "--urr-claim"),
    "evaluate: record into a folder that exists": (
        lambda t: ["evaluate", "--scene", "demo", "--record", str(t)], "exists already"),
    "residual: trial of 3 x": (
        lambda t: ["residual", "--scene", "demo", "--trial", "3"], "--trial"),
    "influence: a typed-in amplitude of -3": (_negative_matrix, "an amplitude is negative"),
    "simulate: a drag that stiffens the balls": (_stiff, "the balls' drag makes their equations"),
    "capability: 24 runs": (
        lambda t: ["capability", "--scene", "demo", "--count", "24"], "--count"),
    "capability: a master without its angle": (
        lambda t: ["capability", "x.h5", "--master", "1:5000"], "PLANE:G_MM@DEG"),
    "qdas: evaluations of an empty archive": (
        lambda t: ["export", "qdas", "--evaluations", "--archive", _archive(t), "-o",
                   str(t / "e.dfq")], "no archived machine evaluation"),
    "qdas: evaluations and a rotor type": (
        lambda t: ["export", "qdas", "--evaluations", "--rotor-type", "x", "-o",
                   str(t / "e.dfq")], "not allowed with"),
    "qdas: evaluations with --since": (
        lambda t: ["export", "qdas", "--evaluations", "--since", "2026-01-01", "--archive",
                   _archive(t), "-o", str(t / "e.dfq")], "--since"),
    "qdas: a serial of 41 characters": (_long_serial, "K0014 (part ident) holds at most 40"),
    "simulate --series: a config that is no TOML": (
        lambda t: ["simulate", "demo", "--series", "1", "--config", _not_toml(t), "--out-dir",
                   str(t / "d")], "not valid TOML"),
    "archive import: a config that is no TOML": (
        lambda t: ["archive", "import", "x.h5", "--config", _not_toml(t)], "not valid TOML"),
    "station: rotor types naming two archives": (_two_archives, "different archives"),
}  # fmt: skip


@pytest.mark.parametrize("name", list(CASES))
def test_a_hostile_input_is_one_line(
    name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    build, says = CASES[name]
    assert len(refused_in_one_line(build(tmp_path), says, capsys, LIMIT_S)) == 1
