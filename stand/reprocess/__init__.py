"""Reprocessing: archived runs re-judged from their files with a corrected calibration (or
a new software's rules), into a named revision beside the originals.

Which runs (:mod:`stand.reprocess.selection`), what a worker does with each
(:mod:`stand.reprocess.work`), where they are solved: this machine's processes or a Dask
cluster (:mod:`stand.reprocess.engine`), and what changed: per run, per rotor, the recall
list (:mod:`stand.reprocess.rejudge`).  Only the client writes the archive.
"""

from stand.reprocess.engine import DaskEngine, LocalEngine, default_jobs
from stand.reprocess.rejudge import Request, reprocess, summary
from stand.reprocess.selection import KINDS, Selection

__all__ = [
    "KINDS",
    "DaskEngine",
    "LocalEngine",
    "Request",
    "Selection",
    "default_jobs",
    "reprocess",
    "summary",
]
