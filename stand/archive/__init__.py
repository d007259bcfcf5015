"""The archive: every run, its job, its result per plane and its links, in a database.

The run files stay the raw record; the archive keeps their path and SHA-256
digest (``stand archive verify`` finds files missing or altered since), the
job (serial, order, operator, note, rotor type), the verdict, each plane's
unbalance, interval, tolerance and leftover, and for a check run the run it
checks and the URR.  ``balance`` and ``measure`` archive every run;
``stand archive import`` adds runs recorded before.

Where: ``--archive URL``, else the config's ``[archive] url``, else one
SQLite file in the user's data directory (:func:`default_url`).
"""

from stand.archive.results import (
    correction_rows,
    drift_rows,
    file_digest,
    file_status,
    insert_result,
    result_of,
    rows,
    run_id_in,
    url_for,
    verdict,
    verify,
)
from stand.archive.store import Archive, default_url

__all__ = [
    "Archive",
    "correction_rows",
    "default_url",
    "drift_rows",
    "file_digest",
    "file_status",
    "insert_result",
    "result_of",
    "rows",
    "run_id_in",
    "url_for",
    "verdict",
    "verify",
]
