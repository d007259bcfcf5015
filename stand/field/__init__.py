"""The field method and bending rotors: influence coefficients from trial runs
(:mod:`stand.field.trials`: the initial run solved through the matrix they measured),
N correction planes from readings (:mod:`stand.field.planes`) or from recorded runs
(:mod:`stand.field.runs`), and one correction across several speeds through the beam
model (:mod:`stand.field.speeds`).
"""

from stand.field.runs import field_from_runs
from stand.field.speeds import balance_speeds, speeds_json
from stand.field.trials import influence_runs, solve_initial_run

__all__ = [
    "balance_speeds",
    "field_from_runs",
    "influence_runs",
    "solve_initial_run",
    "speeds_json",
]
