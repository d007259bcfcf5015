"""Numbers in words the operator and the quality engineer read: one home for plurals and
for the production's first-pass line.

>>> counted(1, "rotor"), counted(3, "rotor"), counted(0, "run")
('1 rotor', '3 rotors', '0 runs')
>>> counted(2, "check", "checks of a run")
'2 checks of a run'
"""

from __future__ import annotations

from typing import Any


def counted(n: int, noun: str, plural: str | None = None) -> str:
    """``n`` and the noun, singular for exactly one (``plural`` default: noun + s)."""
    return f"{n} {noun if n == 1 else (plural or noun + 's')}"


def first_pass_text(out: dict[str, Any]) -> str:
    """The first-pass figures (:func:`stand.archive.stats.first_pass`) in one line."""

    def pct(x: float | None) -> str:
        return "-" if x is None else f"{100 * x:.1f} %"

    judged = out["passed_first_run"] + out["failed_first_run"]
    checked = out["passed_first_check"] + out["failed_first_check"]
    text = (
        f"first-pass yield {pct(out['first_pass_yield'])} ({out['passed_first_run']} of "
        f"{counted(judged, 'rotor')} within tolerance at their first run); first check "
        f"{pct(out['first_check_pass_rate'])} ({out['passed_first_check']} of "
        f"{counted(checked, 'rotor')} corrected within tolerance at the first check)"
    )
    apart = [counted(out["not_checked_yet"], "rotor") + " failed, not checked yet"
             if out["not_checked_yet"] else "",
             counted(out["not_judged_first_run"], "rotor") + " not judged at the first run"
             if out["not_judged_first_run"] else ""]  # fmt: skip
    return text + "".join(f"; {a}" for a in apart if a)
