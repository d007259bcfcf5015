"""`stand report`: one self-contained HTML file an operator can read."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from configs import with_type

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
    assert "[tolerance]" not in html  # the parameters a customer needs, not the config file
    assert "<th class=l>tolerance</th><td class=l>ISO 21940-11, G 6.3" in html
    assert "<th class=l>plane 1: correction radius</th><td class=l>90 mm</td>" in html


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
                str(Path(__file__).resolve().parents[2] / "examples" / "demo-stand.toml"),
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


def _check_pair(tmp_path: Path) -> tuple[Path, Path, Path]:
    """A rotor type's config with a stand name and calibration date; a run before the
    correction and a check run after it (the simulated rotor with the correction on)."""
    text = (Path(__file__).resolve().parents[2] / "examples" / "demo-stand.toml").read_text()
    text = with_type(text, "auger-A")
    text = text.replace("[stand]\n", '[stand]\nname = "stand 2"\ncalibrated = "2026-11-02"\n', 1)
    cfg = tmp_path / "typed.toml"
    cfg.write_text(text)
    before, after = tmp_path / "before.h5", tmp_path / "after.h5"
    job = ["--serial", "A-9", "--order", "O-3", "--operator", "kim", "--config", str(cfg)]
    assert main(["simulate", "demo", *job, "--out", str(before)]) == 0
    argv = ["simulate", "demo", *job, "--apply", str(before), "--seed", "5"]
    assert main([*argv, "--out", str(after)]) == 0
    return cfg, before, after


def test_the_certificate_carries_job_basis_before_after_calibration_and_signatures(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    _, before, after = _check_pair(tmp_path)
    out = tmp_path / "cert.html"
    assert main(["report", str(after), "--check", str(before), "-o", str(out)]) == 0
    html = out.read_text()
    expected = ("auger-A", "A-9", "O-3", "kim", "stand 2", "calibrated on 2026-11-02",
                "Tolerance:", "G 6.3", "Rule:", "ISO 21940-14", "before [g mm]", "URR",
                "balanced by kim", "inspected by", "IN TOLERANCE",
                "no correction needed")  # fmt: skip
    for text in expected:
        assert text in html, text
    urr = [float(x) for x in re.findall(r"<td>(\d+\.\d) %</td>", html)]
    assert len(urr) == 2 and min(urr) >= 95.0
    assert "the seed" not in html  # operator text never speaks of the seed
    # a customer's paper: no path of the stand's disk, no configuration dump (the archive
    # keeps it whole under its digest), the configuration named in words
    assert str(tmp_path) not in html and "<pre>" not in html and "[bus]" not in html
    assert "Calibration used:</b> the configuration stored with the run" in html
    assert main(["report", str(after)]) == 2
    assert "give -o REPORT.html, --pdf REPORT.pdf, or both" in capsys.readouterr().err


def test_the_certificate_prints_to_a_pdf_of_two_a4_pages(tmp_path: Path) -> None:
    """Chromium prints it with its print layout: page 1 the certificate, then the
    measurement (pdftoppm renders them, as README's pictures were made), two pages in
    every language: a check's German and Ukrainian certificates ran onto a third page
    holding the appendix's last line."""
    import shutil
    import subprocess

    from stand.report.printing import BROWSERS

    if not any(shutil.which(b) for b in BROWSERS):
        pytest.skip("Chromium is not installed (Debian: apt-get install chromium)")
    _, before, after = _check_pair(tmp_path)
    pdf = tmp_path / "cert.pdf"
    assert main(["report", str(after), "--check", str(before), "--pdf", str(pdf)]) == 0
    data = pdf.read_bytes()
    assert data.startswith(b"%PDF-") and not list(tmp_path.glob("*.part"))
    if shutil.which("pdftoppm") is None:
        pytest.skip("pdftoppm is not installed (Debian: apt-get install poppler-utils)")
    subprocess.run(["pdftoppm", "-r", "30", "-png", str(pdf), str(tmp_path / "p")], check=True)
    pages = sorted(tmp_path.glob("p-*.png"))
    assert len(pages) == 2
    for lang in ("de", "uk"):
        other = tmp_path / f"cert-{lang}.pdf"
        args = ["report", str(after), "--check", str(before), "--lang", lang]
        assert main([*args, "--pdf", str(other)]) == 0
        subprocess.run(["pdftoppm", "-r", "10", "-png", str(other), str(tmp_path / lang)],
                       check=True)  # fmt: skip
        assert len(list(tmp_path.glob(f"{lang}-*.png"))) == 2, lang
    from matplotlib.image import imread

    h, w = imread(pages[0]).shape[:2]
    assert abs(h / w - 297 / 210) < 0.02  # A4 portrait
    assert main(["report", str(after), "--pdf", str(pdf)]) == 2  # never overwritten


def test_a_missing_browser_is_one_line(tmp_path: Path, capsys, monkeypatch) -> None:
    monkeypatch.setenv("PATH", str(tmp_path))
    monkeypatch.delenv("STAND_CHROMIUM", raising=False)
    run = tmp_path / "r.h5"
    assert main(["simulate", "demo", "--out", str(run)]) == 0
    capsys.readouterr()
    assert main(["report", str(run), "--pdf", str(tmp_path / "r.pdf")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "apt-get install chromium" in err
    assert not (tmp_path / "r.pdf").exists()


def test_the_check_s_polar_plot_draws_the_before_point_it_names(tmp_path: Path) -> None:
    """The check certificate's legend names "before": the picture shows it, a grey square
    at the run before's unbalance (there are pixels of its colour only with a check)."""
    import base64
    import io

    import matplotlib.image as mpimg
    import numpy as np

    from stand.report.plots import polar
    from stand.solve import solve_check, solve_recording, to_json

    _, before, after = _check_pair(tmp_path)
    pictures = []
    for out in (
        to_json(solve_recording(str(after))),
        to_json(solve_check(str(after), str(before))),
    ):
        data = base64.b64decode(polar(out).split(",", 1)[1])
        pictures.append(mpimg.imread(io.BytesIO(data), format="png")[..., :3])
    grey = [int((np.abs(p - 0.45) < 0.02).all(axis=-1).sum()) for p in pictures]
    assert grey[1] >= grey[0] + 2 * 40, grey  # two squares of at least 40 pixels each
    out = to_json(solve_check(str(after), str(before)))
    assert all(0 <= p["before_angle_deg"] < 360 for p in out["check"]["planes"])
