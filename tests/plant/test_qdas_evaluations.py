"""The stand's machine evaluations (ISO 21940-21) in Q-DAS, "like a run": each archived
evaluation one value line of the part ``ISO 21940-21``, read back by aqdefreader and by
the key-table reader, equal to what ``stand evaluate --json`` said."""

from __future__ import annotations

import contextlib
import io
import json
import re
from pathlib import Path
from typing import Any

import pytest

from stand.cli import main

pytest.importorskip("aqdefreader", reason="aqdefreader (the test extra) is not installed")


def _json(argv: list[str]) -> dict[str, Any]:
    out = io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()):
        main(argv)
    got: dict[str, Any] = json.loads(out.getvalue())
    return got


@pytest.fixture(scope="module")
def evaluated(tmp_path_factory: pytest.TempPathFactory) -> tuple[str, list[dict[str, Any]], Path]:
    """Three evaluations archived from one recorded set of proving runs: as recorded, with
    a claim of 99.5 % (the URR test fails), and without the URR runs (not judged)."""
    tmp = tmp_path_factory.mktemp("evaluations")
    rec = tmp / "rec"
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        assert main(["evaluate", "--scene", "demo", "--record", str(rec)]) == 0
    text = (rec / "runs.toml").read_text()
    blocks = text.split("[[runs]]")
    (rec / "no-urr.toml").write_text("[[runs]]".join(b for b in blocks if '"urr"' not in b))
    url = f"sqlite:///{tmp / 'a.sqlite'}"
    said = [
        _json(["evaluate", str(rec / "runs.toml"), "--archive", url, "--json"]),
        _json(["evaluate", str(rec / "runs.toml"), "--archive", url, "--json",
               "--urr-claim", "99.5"]),
        _json(["evaluate", str(rec / "no-urr.toml"), "--archive", url, "--json"]),
    ]  # fmt: skip
    out = tmp / "ev.dfq"
    with contextlib.redirect_stdout(io.StringIO()):
        assert main(["export", "qdas", "--evaluations", "--archive", url, "-o", str(out)]) == 0
    return url, said, out


def test_each_evaluation_is_a_value_line_read_by_aqdefreader(
    evaluated: tuple[str, list[dict[str, Any]], Path],
) -> None:
    """aqdefreader's nine characteristics hold each evaluation's figures in order (to their
    decimals); the URR test not judged is no value (255), never a 0; the limits are the
    latest evaluation's (the spread's 12 %, the claim's 95 %)."""
    from aqdefreader.file import DfqFile

    _, said, out = evaluated
    assert [s["verdict"] for s in said] == ["pass", "fail", "not judged"]
    with contextlib.redirect_stdout(io.StringIO()):
        part = DfqFile(out.read_bytes().decode("cp1252").splitlines()).get_part(0)

    def lowest(s: dict[str, Any], i: int) -> float | None:
        got = [r["urr_pct"][i] for r in s["urr_test"]["runs"] if r["urr_pct"][i] is not None]
        return min(got) if got else None

    rows = []
    for s in said:
        u = s["u_mar_test"]["planes"]
        rows.append([u[0]["mean_g_mm"], u[0]["spread_pct"], u[1]["mean_g_mm"],
                     u[1]["spread_pct"], lowest(s, 0), lowest(s, 1), *s["cross_effect_pct"],
                     s["u_mar_test"]["e_mar_g_mm_per_kg"]])  # fmt: skip
    for k in range(9):
        got = [m.value for m in part.get_characteristic_by_index(k + 1).get_measurements()]
        want = [row[k] for row in rows if row[k] is not None]
        decimals = 3 if k == 8 else 2
        assert got == pytest.approx(want, abs=0.5 * 10**-decimals + 1e-9), k
    assert len(part.get_characteristic_by_index(5).get_measurements()) == 2  # 1 not judged
    text = out.read_bytes().decode("cp1252")
    assert re.search(r"K2110/5 95\.00\r\n", text) and re.search(r"K2111/2 12\.00\r\n", text)
    assert text.count("K0054/0 ") == 3 and "K0054/0 not judged" in text


def test_the_file_keeps_the_key_table_and_one_stand(
    evaluated: tuple[str, list[dict[str, Any]], Path], tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:  # fmt: skip
    """Every key and field within AQDEF's types and lengths; an archive without evaluations,
    or `--runs` with `--evaluations`, is one line and nothing written."""
    from test_qdas_foreign import check_key_table

    url, _, out = evaluated
    assert check_key_table(out.read_bytes()) > 3 * 9 * 3
    x = tmp_path / "x.dfq"
    empty = f"sqlite:///{tmp_path / 'e.sqlite'}"
    assert main(["export", "qdas", "--evaluations", "--archive", empty, "-o", str(x)]) == 2
    assert "no archived machine evaluation" in capsys.readouterr().err
    assert main(["export", "qdas", "--evaluations", "--runs", "--archive", url, "-o", str(x)]) == 2
    assert capsys.readouterr().err.count("\n") == 1 and not x.exists()
