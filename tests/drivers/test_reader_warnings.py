"""What a reader reads around (a cut line, lines that are not frames, a short file) reaches
every command's output and the Result: solve (text and JSON) and a check against such a run."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from stand.cli import main

ROOT = Path(__file__).resolve().parents[2]
CFG = str(ROOT / "examples" / "demo-stand.toml")


@pytest.fixture(scope="module")
def demo_h5(tmp_path_factory: pytest.TempPathFactory) -> Path:
    run = tmp_path_factory.mktemp("warn") / "demo.h5"
    assert main(["simulate", "demo", "--out", str(run)]) == 0
    return run


def _converted(demo_h5: Path, folder: Path, suffix: str) -> Path:
    out = folder / f"run{suffix}"
    assert main(["convert", str(demo_h5), str(out)]) == 0
    return out


def _cut(p: Path) -> Path:
    p.write_bytes(p.read_bytes()[:-8])  # a killed candump: its last line cut mid-way
    return p


def _every_tenth_garbage(p: Path) -> Path:
    lines = p.read_text().splitlines(keepends=True)
    p.write_text("".join("garbage, not a frame\n" if k % 10 == 9 and k > 10 else line
                         for k, line in enumerate(lines)))  # fmt: skip
    return p


def _one_byte_short(p: Path) -> Path:
    p.write_bytes(p.read_bytes()[:-1])
    return p


@pytest.mark.parametrize(
    ("suffix", "damage", "says"),
    [(".log", _cut, "cut short"), (".asc", _every_tenth_garbage, "not frames were left out"),
     (".trc", _every_tenth_garbage, "not frames were left out"),
     (".blf", _one_byte_short, "the BLF header says")],
)  # fmt: skip
def test_a_reader_warning_reaches_solve(
    demo_h5: Path, tmp_path: Path, suffix: str, damage, says: str,  # type: ignore[no-untyped-def]
    capsys: pytest.CaptureFixture[str],
) -> None:  # fmt: skip
    run = damage(_converted(demo_h5, tmp_path, suffix))
    capsys.readouterr()
    assert main(["solve", str(run), "--config", CFG, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert any(says in w and run.name in w for w in out["warnings"]), out["warnings"]
    assert main(["solve", str(run), "--config", CFG]) == 0
    assert says in capsys.readouterr().err


@pytest.mark.realtime
def test_a_reader_warning_of_the_run_before_reaches_the_check(
    demo_h5: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    before = _cut(_converted(demo_h5, tmp_path, ".log"))
    capsys.readouterr()
    argv = ["balance", "--scene", "demo", "--config", CFG, "--check", str(before), "--no-archive",
            "--out", str(tmp_path / "after.h5"), "--json"]  # fmt: skip
    assert main(argv) == 0
    out = json.loads(capsys.readouterr().out)
    assert any("the run before" in w and "cut short" in w for w in out["warnings"]), out


@pytest.mark.parametrize(
    "args",
    [["--rpm", "1e300", "--unbalance", "100@0", "--unbalance", "100@0"],
     ["--rpm", "999999", "--unbalance", "1e300@0", "--unbalance", "100@0"],
     ["--rpm", "1e300", "--unbalance", "100@0", "--unbalance", "100@0", "--json"]],
)  # fmt: skip
def test_forward_beyond_any_stand_is_one_line_and_no_numpy_warning(args: list[str]) -> None:
    """Refused before any arithmetic: nothing of numpy's (RuntimeWarning: overflow) is
    printed, not even by a fresh interpreter (the warnings filter of the tests is not
    the user's)."""
    import subprocess
    import sys

    r = subprocess.run([sys.executable, "-m", "stand.cli", "forward", "--config", CFG, *args],
                       capture_output=True, text=True, timeout=60)  # fmt: skip
    assert r.returncode == 2 and r.stdout == ""
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "beyond any" in lines[0], r.stderr
