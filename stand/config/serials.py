"""A rotor type's rule for generated serial numbers (``[rotor] serial_rule``), for rotors
that come to the stand without one: ``"AUG-{date}-{n:04}"`` gives ``AUG-20261127-0001``,
``AUG-20261127-0002``, ... (``{date}``: the local day as YYYYMMDD; ``{n}``: the day's
running number, ``{n:04}`` zero-padded to 4 digits).  Pure text: the serials already
taken come from the caller (the archive)."""

from __future__ import annotations

import datetime as dt
import re
from typing import Annotated

from pydantic import AfterValidator

PART = re.compile(r"\{date\}|\{n(?::0([1-9]))?\}|[A-Za-z0-9._/-]")
"""What a rule is made of: the placeholders and the characters a serial may hold."""


def _checked(rule: str) -> str:
    pos = 0
    while pos < len(rule):
        m = PART.match(rule, pos)
        if m is None:
            raise ValueError(
                f"serial_rule {rule!r}: at {rule[pos : pos + 10]!r}: only letters, "
                "digits, . _ / - and the placeholders {date} and {n} (or {n:04})"
            )
        pos = m.end()
    if len(re.findall(r"\{n(?::0[1-9])?\}", rule)) != 1:
        raise ValueError(f"serial_rule {rule!r}: needs {{n}} (the day's running number) once")
    if len(rule) > 40:
        raise ValueError(f"serial_rule {rule!r}: at most 40 characters")
    return rule


SerialRule = Annotated[str, AfterValidator(_checked)]
"""A checked ``serial_rule``."""


def _split(rule: str, day: dt.date) -> tuple[str, str, int]:
    """The text before the running number, after it, and its width (0: as it comes)."""
    m = re.search(r"\{n(?::0([1-9]))?\}", rule)
    assert m is not None
    head = rule[: m.start()].replace("{date}", day.strftime("%Y%m%d"))
    tail = rule[m.end() :].replace("{date}", day.strftime("%Y%m%d"))
    return head, tail, int(m.group(1) or 0)


def rule_prefix(rule: str, day: dt.date) -> str:
    """What every serial the rule makes on ``day`` starts with (to find those taken)."""
    return _split(rule, day)[0]


def next_serial(rule: str, day: dt.date, taken: list[str]) -> str:
    """The next serial the rule makes on ``day``: one more than the highest running
    number among ``taken`` that the rule made that day (1 when none)."""
    head, tail, width = _split(rule, day)
    pattern = re.compile(re.escape(head) + r"(\d+)" + re.escape(tail))
    used = [int(m.group(1)) for s in taken if (m := pattern.fullmatch(s))]
    return f"{head}{max(used, default=0) + 1:0{width}d}{tail}"
