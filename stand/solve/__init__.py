"""One run to one frozen :class:`Result`: a run file, a CAN log or live streams, with a
configuration, measured (:mod:`stand.measuring`), corrected (:mod:`stand.solve.correct`:
weights, holes or a slot), judged against the tolerance and, for a check run, against the
run before (:mod:`stand.solve.check`).  :mod:`stand.solve.pipeline` builds the Result,
:mod:`stand.solve.recordings` reads recorded runs into it, :mod:`stand.solve.result_json`
is its one JSON form; the tooling's unbalance is subtracted here
(:mod:`stand.solve.tooling`) and measured from two index runs
(:mod:`stand.solve.index_runs`).  Everything above only formats a Result.
"""

from stand.solve.check import solve_check, with_check
from stand.solve.pipeline import (
    ConfigText,
    SolveOptions,
    build_result,
    load_config_text,
    measure_streams,
)
from stand.solve.recordings import measure_recording, solve_recording, stored_streams
from stand.solve.result import JOB_LIMITS, Job, Provenance, Result, job_field_problem, json_text
from stand.solve.result_json import to_json

__all__ = [
    "JOB_LIMITS",
    "ConfigText",
    "Job",
    "Provenance",
    "Result",
    "SolveOptions",
    "build_result",
    "job_field_problem",
    "json_text",
    "load_config_text",
    "measure_recording",
    "measure_streams",
    "solve_check",
    "solve_recording",
    "stored_streams",
    "to_json",
    "with_check",
]
