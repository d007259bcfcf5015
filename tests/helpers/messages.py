"""The messages the product marks for the catalogues, found by Python's own parser.

``python tests/helpers/messages.py`` lists, per shipped language, the messages its
catalogue lacks (to translate) and those no code uses (to remove); a message the engine
writes with :func:`stand.i18n.words.said` and placeholders goes in with the comment
``#. engine sentence`` (:data:`stand.i18n.language.SENTENCE`).
"""

from __future__ import annotations

import ast
from pathlib import Path

from stand.i18n.language import SENTENCE

ROOT = Path(__file__).resolve().parents[2]
TRANSLATED = sorted(p for d in ("stand", "drivers", "calib") for p in (ROOT / d).rglob("*.py"))
"""Every module of the product: a message is marked where it is written."""


def marked(path: Path, names: tuple[str, ...] = ("_", "N_", "said")) -> set[str]:
    """The messages a module marks: ``_("...")`` (``self._("...")`` too), ``N_("...")``
    and ``said("...", ...)`` with a literal text (Python's own parser: Babel's extractor
    skips an f-string's inside before Python 3.12)."""

    def name(f: ast.expr) -> str | None:
        return f.id if isinstance(f, ast.Name) else f.attr if isinstance(f, ast.Attribute) else None

    found = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if (isinstance(node, ast.Call) and name(node.func) in names and node.args
                and isinstance(node.args[0], ast.Constant)
                and isinstance(node.args[0].value, str)):  # fmt: skip
            found.add(node.args[0].value)
    return found


def used(names: tuple[str, ...] = ("_", "N_", "said")) -> set[str]:
    """Every message the product marks (with ``names``)."""
    return set().union(*(marked(p, names) for p in TRANSLATED))


def main() -> None:
    """Print what each catalogue lacks and what it holds that no code uses."""
    from babel.messages.pofile import read_po

    from stand.i18n.language import LANGUAGES, catalogue_path

    need, sentences = used(), used(("said",))
    for code in (c for c in LANGUAGES if c != "en"):
        with catalogue_path(code).open("rb") as f:
            have = {str(m.id) for m in read_po(f, locale=code) if m.id}
        for m in sorted(need - have):
            mark = f"#. {SENTENCE}\n" if m in sentences and "{" in m else ""
            print(f"{code}: lacks: {mark}msgid {m!r}")
        for m in sorted(have - need):
            print(f"{code}: unused: {m!r}")


if __name__ == "__main__":
    main()
