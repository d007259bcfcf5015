"""What the operator sees: units from the config's [display] table, the live panel."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from stand.cli import main
from stand.i18n.display import G_PER_OZ, MM_PER_IN, Display

ROOT = Path(__file__).resolve().parents[2]


def _config(tmp_path: Path, mass: str, length: str) -> Path:
    text = (ROOT / "examples" / "demo-stand.toml").read_text()
    text += f'\n[display]\nmass = "{mass}"\nlength = "{length}"\n'
    path = tmp_path / f"{mass}-{length}.toml"
    path.write_text(text)
    return path


@given(st.floats(1e-3, 1e7), st.sampled_from(["g", "oz"]), st.sampled_from(["mm", "in"]))
def test_an_unbalance_converts_back_to_g_mm_within_its_shown_digits(
    g_mm: float, mass: str, length: str
) -> None:
    """The shown number, times the unit's size, is the g mm value to within half its last
    shown digit (and 0.05 g mm in g mm): rounding only, no factor lost."""
    d = Display(mass, length)
    shown = d.number(g_mm)
    factor = (G_PER_OZ if mass == "oz" else 1.0) * (MM_PER_IN if length == "in" else 1.0)
    digits = len(shown.split(".")[1]) if "." in shown else 0
    assert abs(float(shown) * factor - g_mm) <= 0.5 * 10.0**-digits * factor * (1 + 1e-12)
    assert d.unbalance(g_mm).endswith(f" {mass} {length}")


@pytest.mark.parametrize(("mass", "length"), [("oz", "in"), ("g", "in"), ("oz", "mm")])
def test_solve_speaks_the_config_s_units_and_the_json_keeps_g_and_mm(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], mass: str, length: str
) -> None:
    run = str(tmp_path / "r.h5")
    assert main(["simulate", "demo", "--out", run]) == 0
    cfg = str(_config(tmp_path, mass, length))
    capsys.readouterr()
    assert main(["solve", run, "--config", cfg]) == 0
    text = capsys.readouterr().out
    unit = f"{mass} {length}"
    assert (
        f"unbalance [{unit}]" in text and f"U_per {Display(mass, length).unbalance(2406.4)}" in text
    )
    assert f"mass [{mass}] at radius [{length}]" in text
    assert " g mm" not in text.replace(f"[{unit}]", "") or unit == "g mm"
    assert main(["solve", run, "--config", cfg, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["display"] == {"mass": mass, "length": length}
    assert out["planes"][0]["unbalance_g_mm"] == pytest.approx(5000, rel=1e-3)  # SI-ish inside


def test_the_report_speaks_the_config_s_units(tmp_path: Path) -> None:
    run = str(tmp_path / "r.h5")
    assert main(["simulate", "demo", "--out", run]) == 0
    report = tmp_path / "r.html"
    cfg = str(_config(tmp_path, "oz", "in"))
    assert main(["report", run, "--config", cfg, "-o", str(report)]) == 0
    html = report.read_text()
    assert "unbalance [oz in] (95 %)" in html and "1.959 oz at 30.0°" in html
    assert "g mm" not in html


def test_a_bad_display_unit_is_refused_naming_the_key(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    cfg = _config(tmp_path, "lb", "mm")
    assert main(["advise", "--config", str(cfg)]) == 2
    err = capsys.readouterr().err
    assert "[display.mass]" in err and err.count("\n") == 1, err


def test_the_live_panel_shows_each_plane_against_its_goal_and_tolerance() -> None:
    """The panel as a terminal shows it (rendered to text), from a real measurement."""
    from rich.console import Console

    from stand.cli.panel import panel
    from stand.drivers.v1.build import rebuild
    from stand.live import Progress
    from stand.sim import load_scene, simulate
    from stand.solve import SolveOptions, measure_streams

    sc, p, _ = load_scene("demo")
    m = measure_streams(rebuild(simulate(sc, p).frames), sc.config(), p, SolveOptions())
    progress = Progress(4.2, m, (2e-6, 1e-3))  # plane 1 not yet precise, plane 2 precise
    console = Console(record=True, width=130)
    console.print(
        panel("virtual:x", "run.h5", progress, tolerance_kg_m=(1098.1e-6, 1e-2), units=Display())
    )
    text = console.export_text()
    assert "[g mm]" in text and "[deg]" in text and "900.0 rpm" in text
    rows = [ln.split("│")[1] for ln in text.splitlines() if ln.startswith("│")]
    k1 = next(k for k, r in enumerate(rows) if r.strip().startswith("1 "))
    k2 = next(k for k, r in enumerate(rows) if r.strip().startswith("2 "))
    one, two = " ".join(rows[k1 : k1 + 2]), " ".join(rows[k2 : k2 + 2])
    assert "4999" in one and "30.0" in one and "measuring" in one and "over tolerance" in one
    assert "± 2.0" in one and "1098.1" in one
    assert "within tolerance" in two  # 3000 g mm against 10,000
    assert "against the direction of" in text and "recording into run.h5" in text
    waiting = Console(record=True, width=130)
    waiting.print(panel("virtual:x", "run.h5", None, tolerance_kg_m=None, units=Display(),
                        waiting="too few reference edges yet", elapsed_s=0.5))  # fmt: skip
    assert "waiting: too few reference edges yet" in waiting.export_text()
