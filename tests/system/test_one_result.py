"""One run, one result: the text, the JSON, the report and the batch summary agree."""

from __future__ import annotations

import csv
import json
import re
import shutil
from pathlib import Path

import pytest

from stand.cli import main

OPTIONS = {
    "plain": [],
    "taper": ["--taper"],
    "no gate": ["--no-gate"],
    "uncertainty": ["--uncertainty", "--draws", "50"],
    "all": ["--taper", "--no-gate", "--uncertainty", "--draws", "50"],
}


def _run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> str:
    assert main(argv) == 0
    return capsys.readouterr().out


@pytest.mark.parametrize("name", OPTIONS)
def test_text_json_report_and_summary_agree(
    name: str, demo_run: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    opts = OPTIONS[name]
    run = str(demo_run)
    obj = json.loads(_run(["solve", run, "--json", *opts], capsys))
    text = _run(["solve", run, *opts], capsys)
    for p in obj["planes"]:  # the text shows what the JSON holds, rounded as shown
        row = (
            f"  {p['plane']}  {p['unbalance_g_mm']:16.1f} {p['uncertainty_g_mm']:10.1f} "
            f"{p['angle_deg']:13.2f}"
        )
        assert row in text
    report = tmp_path / "r.html"
    _run(["report", run, "-o", str(report), *opts], capsys)
    html = report.read_text()
    for p in obj["planes"]:
        assert f"{p['unbalance_g_mm']:.1f} ± {p['uncertainty_g_mm']:.1f}" in html
    if "--uncertainty" in opts:
        for p in obj["parameter_uncertainty"]["planes"]:
            assert f"±{p['radius95_monte_carlo_g_mm']:.1f}" in html
    # the batch: two copies of the run, a JSON and a CSV summary
    copy = tmp_path / "copy.h5"
    shutil.copy(demo_run, copy)
    summary = tmp_path / "s.json"
    assert main(["solve", run, str(copy), "--summary", str(summary), *opts]) == 0
    capsys.readouterr()
    batch = json.loads(summary.read_text())
    assert batch[run] == obj  # every key, every digit
    rows = tmp_path / "s.csv"
    assert main(["solve", run, "--summary", str(rows), *opts]) == 0
    capsys.readouterr()
    (row,) = list(csv.DictReader(rows.open()))
    assert float(row["plane1_g_mm"]) == obj["planes"][0]["unbalance_g_mm"]
    assert float(row["plane2_uncertainty_g_mm"]) == obj["planes"][1]["uncertainty_g_mm"]


def test_the_batch_runs_in_worker_processes_with_the_same_answer(
    demo_run: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    copies = []
    for k in range(3):
        copies.append(tmp_path / f"r{k}.h5")
        shutil.copy(demo_run, copies[-1])
    bad = tmp_path / "bad.log"
    bad.write_text("not a candump line\n")
    summary = tmp_path / "s.json"
    args = ["solve", *map(str, copies), str(bad), "--jobs", "2", "--summary", str(summary)]
    assert main([*args, "--uncertainty", "--draws", "50"]) == 2  # one bad run: exit 2
    capsys.readouterr()
    batch = json.loads(summary.read_text())
    one = json.loads(
        _run(["solve", str(copies[0]), "--json", "--uncertainty", "--draws", "50"], capsys)
    )
    for c in copies:
        got = batch[str(c)]
        assert (
            got["planes"] == one["planes"]
            and got["parameter_uncertainty"] == one["parameter_uncertainty"]
        )
    assert re.search(r"bad\.log", batch[str(bad)]["error"])


def test_the_result_names_its_provenance(
    demo_run: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    import hashlib

    import h5py

    obj = json.loads(_run(["solve", str(demo_run), "--json"], capsys))
    p = obj["provenance"]
    with h5py.File(demo_run, "r") as f:
        text = f.attrs["config_toml"]
    assert p["config_sha256"] == hashlib.sha256(text.encode()).hexdigest()
    assert p["run_file"] == str(demo_run) and p["software"].startswith("stand ")
    assert p["frames"] > 10000
