"""`stand report`: one self-contained HTML file an operator can read."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from stand.cli import main


def test_report_is_self_contained_and_says_what_to_do(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    run = tmp_path / "demo.h5"
    assert main(["simulate", "demo", "--out", str(run)]) == 0
    out = tmp_path / "report.html"
    assert main(["report", str(run), "-o", str(out)]) == 0
    html = out.read_text()
    assert "OUT OF TOLERANCE" in html
    assert re.search(r"remove 55\.5\d g at 30\.0°", html)
    assert re.search(r"remove 37\.\d\d g at (199\.9|200\.0)°", html)
    assert "against the direction of rotation" in html
    assert html.count('src="data:image/png;base64,') == 3  # polar, spectrum, speed
    assert not re.search(r'(src|href)="(https?:|//)', html)  # nothing fetched from outside
    assert "[tolerance]" in html and "grade_mm_s = 6.3" in html


def test_report_of_a_bad_run_writes_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "bad.log").write_text("garbage\n")
    out = tmp_path / "report.html"
    assert (
        main(
            [
                "report",
                str(tmp_path / "bad.log"),
                "-o",
                str(out),
                "--config",
                str(Path(__file__).resolve().parents[1] / "examples" / "demo-stand.toml"),
            ]
        )
        == 2
    )
    assert not out.exists() and not (tmp_path / "report.html.part").exists()


@pytest.mark.realtime
def test_balance_writes_its_report_beside_the_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    run = tmp_path / "r.h5"
    assert main(["balance", "--scene", "demo", "--out", str(run), "--quiet"]) == 0
    assert f"report: {tmp_path / 'r.html'}" in capsys.readouterr().out
    assert (tmp_path / "r.html").read_text().startswith("<!doctype html>")
