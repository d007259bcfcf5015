"""The operator's text, pinned: ``stand solve`` and ``stand balance`` print exactly this.

A change of wording or layout fails here; when it is meant, regenerate with
``python tests/golden/regenerate.py`` and review the diff.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from golden.regenerate import CASES, HERE, balance_text, solve_texts


def test_solve_prints_exactly_the_golden_text(demo_run: Path) -> None:
    texts = solve_texts(demo_run)
    for name in CASES:
        assert texts[name] == (HERE / name).read_text(), f"{name} changed: regenerate on purpose"


def test_balance_prints_exactly_the_golden_text() -> None:
    obj = json.loads((HERE / "balance-demo.json").read_text())
    assert balance_text(obj) == (HERE / "balance-demo.txt").read_text()


def test_golden_texts_speak_to_the_operator() -> None:
    for path in HERE.glob("*.txt"):
        text = path.read_text()
        assert "seed" not in text, f"{path.name} speaks of the seed"
        assert "against the direction of rotation" in text


@pytest.mark.parametrize("name", sorted(CASES))
def test_golden_files_exist(name: str) -> None:
    assert (HERE / name).stat().st_size > 200
