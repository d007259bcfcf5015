"""Editing a config's text in tests: one rotor type line, whatever the text had."""

from __future__ import annotations

import re


def with_type(text: str, rotor_type: str) -> str:
    """``text`` whose ``[rotor]`` table names ``rotor_type`` (its own ``type`` replaced,
    or one added at the table's top)."""
    head, sep, rest = text.partition("[rotor]\n")
    assert sep, "no [rotor] table"
    rest = re.sub(r'(?m)^type = "[^"]*"[^\n]*\n', "", rest, count=1)
    return f'{head}[rotor]\ntype = "{rotor_type}"\n{rest}'
