"""The words the certificate and the screens give a correction's action and a
verdict (the units they are shown in: :mod:`stand.i18n.display`)."""

from __future__ import annotations

from typing import Any

from stand.i18n.language import ENGLISH, Language
from stand.i18n.words import N_

ACTIONS = {"remove": N_("remove"), "add": N_("add"), "drill": N_("drill"), "mill": N_("mill")}
"""A correction's action, as the certificate and its figures say it."""
PLANE_VERDICTS = {"pass": N_("PASS"), "fail": N_("FAIL"), "undecided": N_("UNDECIDED")}
"""A plane's or criterion's verdict, as the certificate's and the Check screen's tables
say it."""


def verdict_word(state: str, _: Language = ENGLISH) -> str:
    """A plane's or criterion's verdict (``pass`` ...) as the tables say it (``PASS``)."""
    return _(PLANE_VERDICTS.get(state, state.upper()))


def cycle_sentence(out: dict[str, Any], _: Language) -> str:
    """The stand's own cycle in words, when a drive ran it (``out``: the result's JSON):
    each phase's time, the floor, where each plane stopped; "" without a cycle."""
    c = out.get("cycle")
    if c is None:
        return ""
    n = _.number
    text = _("The stand's cycle ({drive}): run-up {runup} s, settling {settle} s, measuring "
             "{measure} s, braking to the mark {brake} s; {total} s in all, its physical floor "
             "{floor} s.").format(drive=c["drive"], runup=n(c["runup_s"], 2),
                                 settle=n(c["settle_s"], 2), measure=n(c["measure_s"], 2),
                                 brake=n(c["brake_s"], 2), total=n(c["total_s"], 2),
                                 floor=n(c["floor_s"], 2))  # fmt: skip
    for stop in out.get("index", []):
        text += " " + _("Plane {plane} stopped at the mark, {error}° off.").format(
            plane=stop["plane"], error=n(abs(stop["error_deg"]), 1))  # fmt: skip
    return str(text)
