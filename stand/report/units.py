"""The words the certificate and the screens give a correction's action and a
verdict (the units they are shown in: :mod:`stand.i18n.display`)."""

from __future__ import annotations

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
