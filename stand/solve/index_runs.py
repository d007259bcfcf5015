"""The tooling's unbalance measured from two index runs: the rotor on its tooling as usual,
then turned 180 deg on it (:func:`stand.core.balance.index_split` separates them).

A use case above the recording path: both runs are measured as any run, neither
compensated; what it finds is kept by :func:`stand.solve.tooling.save_tooling`.
"""

from __future__ import annotations

from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np

from stand.config import SAME_SPEED
from stand.core import rad_s_to_rpm
from stand.core.balance import index_split
from stand.core.same import is_same_data
from stand.drivers.runs.recording import config_digest
from stand.errors import ConfigError, UsageError
from stand.solve.recordings import measure_recording
from stand.solve.tooling import TOOLING_NAME, Tooling


def same_data(m_a: Any, m_b: Any) -> bool:
    """Whether two measurements are one recording: their support phasors alike beyond what
    noise can make (:mod:`stand.core.same`; a byte copy, a run kept twice).  False where a
    measurement carries no covariance to judge by."""
    if m_a.cov_A_m2_s4 is None or m_b.cov_A_m2_s4 is None:
        return False
    a = np.array([(p.A_m_s2.real, p.A_m_s2.imag) for p in m_a.supports]).ravel()
    b = np.array([(p.A_m_s2.real, p.A_m_s2.imag) for p in m_b.supports]).ravel()
    return is_same_data(b - a, np.asarray(m_a.cov_A_m2_s4) + np.asarray(m_b.cov_A_m2_s4))


def _two_runs(m0: Any, m180: Any, run_0: str, run_180: str) -> None:
    """Refuse two index runs that are one (:func:`same_data`)."""
    if same_data(m0, m180):
        raise UsageError(
            f"{run_0} and {run_180} are the same data (their 1x alike beyond any chance of "
            f"noise): the 180 deg run must be the rotor turned half a revolution on its tooling"
        )


def measure_tooling(run_0: str, run_180: str, config: str | None, name: str | None) -> Any:
    """The tooling's unbalance from its two index runs (the rotor at 0 deg, then turned
    180 deg on the tooling), neither compensated; returns ``(Tooling, rotor U, rotor
    covariance, config)``.  The name is ``name`` or the config's ``[tooling] name``."""
    if Path(run_0).resolve() == Path(run_180).resolve():
        raise UsageError(f"the same run given twice ({run_0}): give the 0 and the 180 deg runs")
    m0, cfg, _, text = measure_recording(run_0, config, compensate=False)
    m180, _, _, text180 = measure_recording(run_180, config, compensate=False)
    if config_digest(text) != config_digest(text180):
        raise ConfigError(
            "the two index runs were measured with different configurations", source=run_180
        )
    if abs(m180.omega_rad_s / m0.omega_rad_s - 1) > SAME_SPEED:
        raise ConfigError(
            f"the two index runs differ in speed by more than {100 * SAME_SPEED:g} % "
            f"({rad_s_to_rpm(m0.omega_rad_s):.0f} and {rad_s_to_rpm(m180.omega_rad_s):.0f} rpm)",
            source=run_180,
        )
    _two_runs(m0, m180, run_0, run_180)
    name = name or (cfg.tooling.name if cfg.tooling else None)
    if not name:
        raise ConfigError("name the tooling: --name NAME, or [tooling] name in the config")
    if not TOOLING_NAME.fullmatch(name):
        raise ConfigError(
            f"a tooling's name is 1 to 64 letters, digits, '.', '_' or '-' (it names a file), "
            f"got {name!r}",
            key="tooling.name",
        )
    U_t, cov_t, U_r, cov_r = index_split(
        m0.solution.U_kg_m,
        np.asarray(m0.solution.cov_U).real,
        m180.solution.U_kg_m,
        np.asarray(m180.solution.cov_U).real,
    )
    when = datetime.now(UTC).isoformat(timespec="seconds")
    tooling = Tooling(
        name, (complex(U_t[0]), complex(U_t[1])), cov_t, when, config_digest(text),
        (str(Path(run_0).resolve()), str(Path(run_180).resolve())), m0.omega_rad_s,
    )  # fmt: skip
    return tooling, U_r, cov_r, cfg
