"""The operator's CLI text in the plant's language (``--lang``), and the engine's sentences
(:func:`stand.i18n.words.said`) found again and translated wherever they are shown."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
from messages import SENTENCE, used

from stand.cli import main
from stand.i18n.language import catalogue_path, language
from stand.i18n.words import said


def _text(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[str, str]:
    assert main(argv) == 0
    got = capsys.readouterr()
    return got.out, got.err


@pytest.mark.parametrize("code", ["de", "uk"])
def test_every_line_of_the_answer_is_in_the_language(
    demo_run: Path, code: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """``stand solve RUN --lang`` and the same in English: no line with words is the same
    in both (each heading, instruction, verdict and rule is translated), and the figures
    carry the language's decimal comma."""
    english, _ = _text(["solve", str(demo_run)], capsys)
    other, _ = _text(["solve", str(demo_run), "--lang", code], capsys)
    assert len(english.splitlines()) == len(other.splitlines())
    same = [line for line in other.splitlines() if line in english.splitlines()]
    assert not same, same
    assert re.search(r"\d,\d", other) and not re.search(r"\d\.\d", other)
    if code == "de":
        for words in ("Drehzahl", "Ebene 1:", "Bewertung: N.I.O.", "Ausgleich (Material"):
            assert words in other, words


def test_the_json_stays_english_whatever_the_language(
    demo_run: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out, _ = _text(["solve", str(demo_run), "--json", "--lang", "de"], capsys)
    obj = json.loads(out)
    assert obj["tolerance"]["rule"].startswith("ISO 21940-14, directly after balancing")
    assert obj["tolerance"]["criteria"][0]["name"] == "plane 1"


def test_an_engine_sentence_reads_in_the_language_nested_and_with_commas() -> None:
    inner = said("node {node}: only {n} steady, settled revolutions (want {want} or more): "
                 "measure longer", node=1, n=12, want=30)  # fmt: skip
    outer = said("the run before ({run}): {message}", run="A-1.h5", message=inner)
    assert outer.startswith("the run before (A-1.h5): node 1: only 12 steady")  # English
    de = language("de")
    assert de(outer) == (
        "der Lauf davor (A-1.h5): Knoten 1: nur 12 gleichmäßige, "
        "eingeschwungene Umdrehungen (gefordert 30 oder mehr): länger messen"
    )
    figures = said("supports settled after {n} revolutions", n="12.5")
    assert language("uk")(figures) == "опори усталилися після 12,5 обертів"
    assert de("a sentence no catalogue has: 3.5") == "a sentence no catalogue has: 3.5"
    assert language("en")(outer) == outer


@pytest.mark.parametrize("code", ["de", "uk"])
def test_every_engine_sentence_is_found_again_by_its_words(code: str) -> None:
    """Each message the engine writes, with placeholder values filled in, reads back as
    its own translation (never as another message's: the longest is tried first)."""
    from babel.messages.pofile import read_po

    with catalogue_path(code).open("rb") as f:
        catalog = {str(m.id): m for m in read_po(f, locale=code) if m.id}
    words = language(code)
    sentences = [m for m in used(("said",)) if "{" in m]
    assert len(sentences) > 40
    for msgid in sentences:
        assert SENTENCE in catalog[msgid].auto_comments, msgid
        names = re.findall(r"\{(\w+)\}", msgid)
        values = {n: f"v{i}x" for i, n in enumerate(dict.fromkeys(names))}
        assert words(msgid.format(**values)) == str(catalog[msgid].string).format(**values), msgid
