"""The quality engineer's first-pass figures, as the issue defines them: a rotor passes
first time only when its first run passed; the correction's first-check rate is a figure
of its own; counts in words with their plurals."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import pytest

from stand.archive.stats import _rotors, first_pass
from stand.cli import main
from stand.solve.words import counted, first_pass_text


def _run(i: int, serial: str | None, verdict: str, checks: int | None = None) -> SimpleNamespace:
    return SimpleNamespace(id=i, serial=serial, verdict=verdict, checks_run_id=checks)


def test_three_rotors_that_failed_their_first_run_are_no_first_pass() -> None:
    """Three rotors, each failed at its first run and passed at its check: first-pass yield
    0 % (it said 100 %), first check 100 %, three rotors."""
    rows = [_run(1, "A", "fail"), _run(2, "B", "fail"), _run(3, "C", "fail"),
            _run(4, "A", "pass", 1), _run(5, "B", "pass", 2), _run(6, "C", "pass", 3)]  # fmt: skip
    rotors = _rotors(rows)
    got = first_pass(rows, rotors)
    assert len(rotors) == 3
    assert (got["first_pass_yield"], got["first_check_pass_rate"]) == (0.0, 1.0)
    text = first_pass_text(got)
    assert text.startswith("first-pass yield 0.0 % (0 of 3 rotors within tolerance at their")
    assert "first check 100.0 % (3 of 3 rotors corrected" in text


def test_the_figures_count_apart_what_they_cannot_judge() -> None:
    """A rotor within tolerance at once, one failed and not checked, one failed twice, one
    never judged (no tolerance): yield 1 of 3 judged, first check 0 of 1, the rest apart."""
    rows = [_run(1, "A", "pass"), _run(2, "B", "fail"), _run(3, "C", "fail"),
            _run(4, "C", "fail", 3), _run(5, "D", "none")]  # fmt: skip
    got = first_pass(rows, _rotors(rows))
    assert (got["first_pass_yield"], got["first_check_pass_rate"]) == (0.3333, 0.0)
    assert (got["not_checked_yet"], got["not_judged_first_run"]) == (1, 1)
    assert first_pass_text(got).endswith(
        "; 1 rotor failed, not checked yet; 1 rotor not judged at the first run"
    )
    assert first_pass([], [])["first_pass_yield"] is None  # nothing judged: no figure


@pytest.mark.parametrize(("n", "words"), [(0, "0 rotors"), (1, "1 rotor"), (2, "2 rotors")])
def test_plurals(n: int, words: str) -> None:
    assert counted(n, "rotor") == words


def test_stats_of_one_rotor_say_one_rotor(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    run = tmp_path / "r.h5"
    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    cfg = Path(__file__).parents[2] / "examples" / "demo-stand.toml"  # rotor type demo-auger
    assert main(["simulate", "demo", "--out", str(run), "--serial", "P-1", "--config",
                 str(cfg)]) == 0  # fmt: skip
    assert main(["archive", "import", str(run), "--archive", url]) == 0
    capsys.readouterr()
    assert main(["stats", "--rotor-type", "demo-auger", "--archive", url]) == 0
    out = capsys.readouterr().out
    assert "demo-auger: 1 rotor (1 run)" in out and "1 rotors" not in out
    assert "first-pass yield 0.0 % (0 of 1 rotor within tolerance" in out
