"""The certificate in the customer's language (``stand report --lang``): its own words
all in that language, the figures as they are, and the release block too."""

from __future__ import annotations

from pathlib import Path

import pytest

from stand.cli import main

ENGLISH_WORDS = ("Balancing certificate", "Unbalance per correction plane", "Correction",
                 "Calibration used", "Measurement", "Run and parameters", "Release")  # fmt: skip


@pytest.mark.parametrize(("code", "words"), [
    ("de", ("Wuchtprotokoll", "Unwucht je Ausgleichsebene", "Verwendete Kalibrierung",
            "Freigabe", "freigegeben von")),
    ("uk", ("Сертифікат балансування", "Дисбаланс у площинах корекції",
            "Використане калібрування", "Випуск", "випустив")),
])  # fmt: skip
def test_a_certificate_in_the_customers_language(tmp_path: Path, code: str,
                                                 words: tuple[str, ...]) -> None:  # fmt: skip
    run, page = tmp_path / "r.h5", tmp_path / "c.html"
    assert main(["simulate", "demo", "--out", str(run), "--serial", "L-1"]) == 0
    assert main(["report", str(run), "-o", str(page), "--lang", code, "--release",
                 "--archive", f"sqlite:///{tmp_path / 'a.sqlite'}"]) == 0  # fmt: skip
    text = page.read_text()
    assert f'<html lang="{code}">' in text
    for w in words:
        assert w in text, w
    for w in ENGLISH_WORDS:
        assert f">{w}<" not in text, w  # no heading left in English
    assert "L-1" in text  # the job's own values as they are


def test_an_unknown_language_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]
                                        ) -> None:  # fmt: skip
    assert main(["report", "r.h5", "-o", str(tmp_path / "c.html"), "--lang", "xx"]) == 2
    assert "--lang" in capsys.readouterr().err
