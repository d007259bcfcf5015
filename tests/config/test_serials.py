"""A rotor type's rule for generated serials (:mod:`stand.config.serials`)."""

from __future__ import annotations

import datetime as dt

import pytest
from hypothesis import given
from hypothesis import strategies as st
from pydantic import TypeAdapter, ValidationError

from stand.config.serials import SerialRule, next_serial, rule_prefix

DAY = dt.date(2026, 11, 27)
RULE = TypeAdapter(SerialRule)


def test_the_day_and_the_running_number() -> None:
    rule = RULE.validate_python("AUG-{date}-{n:04}")
    assert rule_prefix(rule, DAY) == "AUG-20261127-"
    assert next_serial(rule, DAY, []) == "AUG-20261127-0001"
    taken = ["AUG-20261127-0001", "AUG-20261127-0007", "AUG-20261126-0042", "AUG-20261127-x"]
    assert next_serial(rule, DAY, taken) == "AUG-20261127-0008"
    assert next_serial(RULE.validate_python("R{n}/{date}"), DAY, ["R9/20261127"]) == "R10/20261127"


@pytest.mark.parametrize("bad", ["AUG-{date}", "{n}{n}", "A B-{n}", "{x}-{n}", "{n:4}",
                                 "A" * 40 + "{n}", "{n:00}", "Ä-{n}"])  # fmt: skip
def test_a_rule_that_cannot_make_a_serial_is_refused(bad: str) -> None:
    with pytest.raises(ValidationError, match="serial_rule"):
        RULE.validate_python(bad)


@given(st.lists(st.integers(1, 10**6), max_size=20))
def test_the_next_is_one_more_than_the_highest_taken(numbers: list[int]) -> None:
    rule = "X-{date}-{n:05}"
    taken = [f"X-20261127-{k:05d}" for k in numbers]
    got = next_serial(rule, DAY, taken)
    assert got not in taken and int(got.rsplit("-", 1)[1]) == max(numbers, default=0) + 1
