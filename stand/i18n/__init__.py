"""The plant's languages, at the ground floor beside the core: sentences the engine
writes in English and marks for the catalogues (:func:`said`, :func:`N_`), a language's
messages and its way of writing and reading numbers and dates (:class:`Language`, the
catalogues in ``stand/data/locale``), and the units a person is shown
(:class:`Display`)."""

from stand.i18n.display import Display
from stand.i18n.language import ENGLISH, LANGUAGES, Language
from stand.i18n.words import N_, said

__all__ = ["ENGLISH", "LANGUAGES", "N_", "Display", "Language", "said"]
