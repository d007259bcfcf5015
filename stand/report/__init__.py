"""What a person reads: the run's certificate as one HTML page (:mod:`stand.report.certificate`),
the pages of corrections across speeds and of production statistics
(:mod:`stand.report.pages`), a re-judgement's (:mod:`stand.report.reprocess_page`),
their plots (:mod:`stand.report.plots`), PDFs printed by
headless Chromium (:mod:`stand.report.printing`) and the words for actions and verdicts
(:mod:`stand.report.units`; the units shown are :mod:`stand.i18n.display`'s).  Formatting
only: nothing here measures.
"""

from stand.report.certificate import render
from stand.report.pages import render_production, render_speeds
from stand.report.printing import write_pdf
from stand.report.release import Release, released
from stand.report.reprocess_page import render_reprocess

__all__ = [
    "Release",
    "released",
    "render",
    "render_production",
    "render_reprocess",
    "render_speeds",
    "write_pdf",
]
