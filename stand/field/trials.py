"""The field method (influence coefficients) on the stand: trial runs in, one Result out.

Trial runs are recorded as any run; :mod:`stand.calib.influence` turns their
support phasors into the influence matrix, and the initial run is solved
through it by the one pipeline (:func:`stand.solve.recordings.solve_recording`), so
corrections, tolerance and check are those of every other run.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from stand.calib.influence import InfluenceRun, initial_covariance
from stand.core import StandParameters
from stand.measuring import Measurement, with_unbalance_covariance
from stand.solve import Result, SolveOptions, load_config_text, measure_recording, solve_recording


def influence_runs(
    entries: Sequence[tuple[str | None, Any, Any, bool]], config: str | None
) -> tuple[list[Any], Any, StandParameters | None, str, float | None]:
    """The runs of the field method: ``(file or None, typed readings, Trial, left_on)`` each.

    Recorded runs are measured (support phasors and their covariance); typed
    readings (:func:`stand.calib.influence.phasors`) are taken as they are.  A
    trial without a radius is at its plane's correction radius (1 m, i.e.
    masses "at the trial radius", without a config).  Returns the
    :class:`~stand.calib.influence.InfluenceRun` list, the config and
    parameters (None without any), the config text, and the first run's speed
    [rad/s] (None when typed in).
    """

    cfg = params = None
    text = ""
    omega = None
    if config:
        cfg, params, text = load_config_text(config)
    measured: list[tuple[Any, Any, Any, bool]] = []
    for path, typed, trial, left_on in entries:
        if path is None:
            measured.append((np.asarray(typed), None, trial, left_on))
            continue
        m, run_cfg, run_params, run_text = measure_recording(path, config)
        if cfg is None:  # the first recorded run's own config serves them all
            cfg, params, text = run_cfg, run_params, run_text
        omega = m.omega_rad_s if omega is None else omega
        A = np.array([ph.A_m_s2 for ph in m.supports])
        measured.append((A, m.cov_A_m2_s4, trial, left_on))
    runs = []
    for A, cov, trial, left_on in measured:
        if trial is not None and trial.radius_m is None:
            R = 1.0 if params is None else (params.R1, params.R2)[trial.plane - 1]
            trial = replace(trial, radius_m=R)
        runs.append(InfluenceRun(A, trial, left_on, cov))
    return runs, cfg, params, text, omega


def solve_initial_run(path: str, config: str | None, runs: list[Any], matrix: Any) -> Result:
    """The initial run of trial runs solved through the matrix they measured: its interval
    holds the run's noise and the matrix's, taken together (they share the initial run)."""

    def joint(m: Measurement) -> Measurement:
        cov = initial_covariance(runs, matrix.imap.alpha, m.solution.U_kg_m)
        return m if cov is None else with_unbalance_covariance(m, cov)

    return solve_recording(path, config, SolveOptions(matrix=matrix), adjust=joint)
