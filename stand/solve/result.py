"""The one result of a run, typed and frozen, and its one JSON form.

Every command that measures (``solve``, ``report``, ``measure``,
``balance``, the batch) gets a :class:`Result` from :mod:`stand.solve.pipeline`;
the CLI, the report and the summary only format it.  Inside, SI units and
complex numbers (amplitude and phase as one value); :func:`to_json` is the
only place where g, mm, deg and rpm appear, and the only place that rounds,
so the printed text, the JSON, the report and the batch summary of one run
agree to the last digit they show.
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from stand.core import Diagnostic
from stand.core.balance import Correction
from stand.core.tolerance import Criterion
from stand.errors import ModelError
from stand.measuring import Measurement
from stand.solve.keys import KeyEffect

RESULT_VERSION = 2
"""Version of the JSON form; bumped when a key changes meaning."""


JOB_LIMITS = {"serial": 64, "order": 64, "operator": 64, "note": 1000, "job_id": 64}
"""The longest text each field of a :class:`Job` takes [characters]."""


def job_field_problem(name: str, value: object) -> str | None:
    """Why ``value`` is no usable ``name`` of a job (None: it is): 1 to the field's
    :data:`JOB_LIMITS` printable characters (``str.isprintable``: no control, no format
    character such as a right-to-left override or a zero-width space), not only blanks.
    The one rule of the CLI's options, the station's form and the MES's job orders."""
    limit = JOB_LIMITS[name]
    if not isinstance(value, str):
        return f"{name}: a text of 1 to {limit} characters, got {type(value).__name__}"
    if not value.strip() or len(value) > limit or not value.isprintable():  # C0, C1, bidi,
        return f"{name}: 1 to {limit} printable characters, got {value[:80]!r}"  # zero-width
    return None


@dataclass(frozen=True)
class Job:
    """What a run was made for: the rotor's serial number, the order, who balanced it."""

    serial: str | None = None
    order: str | None = None
    operator: str | None = None
    note: str | None = None
    job_id: str | None = None
    """The MES's job order it was run under (OPC 40001-3 JobOrderID), if any."""

    def __bool__(self) -> bool:
        return any(asdict(self).values())

    def to_text(self) -> str:
        """As a run file records it (JSON)."""
        return json.dumps(asdict(self))

    @classmethod
    def from_text(cls, text: str) -> Job:
        """The job a run file records (ValueError if the attribute is not one)."""
        data = json.loads(text)
        if not isinstance(data, dict) or set(data) - set(cls.__dataclass_fields__):
            raise ValueError("not a job record")
        if not all(v is None or isinstance(v, str) for v in data.values()):
            raise ValueError("a job field is not text")
        return cls(**data)


@dataclass(frozen=True)
class Provenance:
    """Where a result came from.

    Attributes
    ----------
    software : str
        This software and its version.
    run_file : str or None
        The recording solved (None: not recorded).
    config_sha256 : str
        SHA-256 of the configuration text used (the stored or given one).
    config_source : str
        Where the configuration came from (a file, or the run file's stored one).
    start_time : str
        When the run was recorded (ISO 8601, UTC), if known.
    source : str
        What the frames came from (the bus options), if known.
    frames : int
        Frames in the recording.
    duration_s : float
        Span of the frames' host timestamps [s].
    config_toml : str
        The configuration text itself (for the report; the JSON carries its digest).
    matrix : str or None
        The stored influence matrix used in place of the stand model, if any.
    job : Job
        Serial, order, operator, note (empty when not given).
    rotor_type : str or None
        The config's ``[rotor] type``.
    stand_id : str
        The stand that recorded the run (its ``[stand] id``, else its host name).
    """

    software: str
    run_file: str | None
    config_sha256: str
    config_source: str
    start_time: str = ""
    source: str = ""
    frames: int = 0
    duration_s: float = 0.0
    config_toml: str = field(default="", repr=False)
    matrix: str | None = None
    job: Job = Job()
    rotor_type: str | None = None
    stand_id: str = ""

    @property
    def simulated(self) -> bool:
        """Whether the frames came from the simulator: a simulated scene's recording, or
        python-can's ``virtual`` bus the simulator plays on (no real stand uses it)."""
        return self.source.startswith(("simulated", "virtual:"))


@dataclass(frozen=True)
class Tolerance:
    """What a rotor may carry, in the form its customer wrote (:mod:`stand.config.tolerance`).

    Attributes
    ----------
    form : str
        ``grade`` (ISO 21940-11), ``per_plane`` (a drawing), ``static_couple`` (ISO
        21940-11's separate limits) or ``api`` (API 610/617/687).
    source : str
        Where the limit comes from, as the certificate says it.
    judged_in : str
        The planes or quantities judged, in words.
    moment : str
        ISO 21940-14's moment: ``after_balancing`` or ``later_check``.
    criteria : tuple of stand.core.tolerance.Criterion
        What is judged, each against its limit [kg m; kg m^2 for a moment].
    per_plane_kg_m : tuple of float
        Correction-plane limits: the form's own, or, for the others, limits that keep every
        criterion at any phase (the live panel's goal and the correction's skip).
    grade_m_s, max_speed_rad_s, U_per_kg_m : float or None
        The grade form's G [m/s], the maximum speed [rad/s] (grade, API), ``U_per`` [kg m].
    bearing_planes_m : tuple of float or None
        The bearing planes judged in [m from support 1], where not the supports.
    allocation : str
        The grade form's allocation and why: the lever split, or resultant and moment for
        an overhung or narrow rotor (:func:`stand.core.tolerance.rotor_shape`); empty for
        the other forms.
    """

    form: str
    source: str
    judged_in: str
    moment: str
    criteria: tuple[Criterion, ...]
    per_plane_kg_m: tuple[float, float]
    grade_m_s: float | None = None
    max_speed_rad_s: float | None = None
    U_per_kg_m: float | None = None
    bearing_planes_m: tuple[float, float] | None = None
    allocation: str = ""


@dataclass(frozen=True)
class Judgement:
    """One criterion judged by ISO 21940-14: its value, combined error and limit [kg m;
    kg m^2 for a moment] and the state (``pass``, ``fail``, ``undecided``)."""

    name: str
    plane: int | None
    value: float
    error: float
    limit: float
    state: str


@dataclass(frozen=True)
class Uncertainty:
    """How the stand's parameter tolerances spread the unbalance (95 % radii [kg m])."""

    tolerances: Any  # stand.calib.tolerance.Tolerances
    radius95_linear_kg_m: tuple[float, float]
    radius95_monte_carlo_kg_m: tuple[float, float]
    shares: dict[str, tuple[float, float]]
    draws: int


@dataclass(frozen=True)
class Check:
    """A check run against the run before the correction: ``U`` before and after [kg m]."""

    previous_run: str
    before_kg_m: tuple[complex, complex]
    after_kg_m: tuple[complex, complex]
    warnings: tuple[Diagnostic, ...] = ()
    """What reading the run before left to say (a cut line, a short log ...)."""

    @property
    def urr(self) -> tuple[float | None, float | None]:
        """Unbalance reduction ratio ``(|U_before| - |U_after|) / |U_before|`` per plane."""
        out = []
        for b, a in zip(self.before_kg_m, self.after_kg_m, strict=True):
            out.append((abs(b) - abs(a)) / abs(b) if abs(b) > 0 else None)
        return out[0], out[1]


@dataclass(frozen=True)
class LiveInfo:
    """How a live measurement ended."""

    stopped_by: str
    elapsed_s: float
    targets_kg_m: tuple[float, float]


@dataclass(frozen=True)
class IndexStop:
    """One plane's correction place brought to the operator's mark by the drive [deg]."""

    plane: int
    target_deg: float
    """The drive's angle asked for: the mark plus the place's angle from the reference mark."""
    stopped_deg: float
    """Where the drive says it came to rest."""
    seconds: float

    @property
    def error_deg(self) -> float:
        """Stopped minus target, in (-180, 180]."""
        return -((self.target_deg - self.stopped_deg + 180.0) % 360.0 - 180.0)


@dataclass(frozen=True)
class CycleInfo:
    """The stand's own cycle, when a drive ran it: each phase's time [s], the physical
    floor of the moving phases and the measurement (:func:`stand.core.motor.floors`), the
    stops at the mark, and why the cycle was aborted (None: it was not)."""

    drive: str
    runup_s: float
    settle_s: float
    measure_s: float
    brake_s: float
    index_s: float
    total_s: float
    floor_s: float
    index: tuple[IndexStop, ...] = ()
    aborted: str | None = None


@dataclass(frozen=True)
class Traces:
    """What the report plots besides the result: spectra and speed per node.

    ``spectra``: node -> (frequency [Hz], amplitude [m/s^2]) up to 4x;
    ``speeds``: node -> (time on the node's clock [s], speed [rad/s]).
    """

    spectra: dict[int, tuple[np.ndarray, np.ndarray]]
    speeds: dict[int, tuple[np.ndarray, np.ndarray]]


@dataclass(frozen=True)
class Result:
    """Everything one run says: measurement, corrections, verdict, provenance."""

    measurement: Measurement
    corrections: tuple[Correction, ...]
    correction_mode: str
    static_kg_m: complex
    couple_kg_m: complex
    tolerance: Tolerance | None
    warnings: tuple[Diagnostic, ...]
    provenance: Provenance
    uncertainty: Uncertainty | None = None
    check: Check | None = None
    live: LiveInfo | None = None
    cycle: CycleInfo | None = None
    """The drive's cycle (run-up, measure, brake, index), when a drive ran the run."""
    within_noise: tuple[bool, bool] = (False, False)
    """Per plane: the unbalance is inside its own 95 % interval (no correction prescribed)."""
    within_tolerance: tuple[bool, bool] = (False, False)
    """Per plane: no correction needed, the verdict passes this plane (or, for forms not
    judged plane by plane, the whole rotor)."""
    judgements: tuple[Judgement, ...] = ()
    """Each criterion of the tolerance, judged (:mod:`stand.solve.verdict`)."""
    keys: tuple[KeyEffect, ...] = ()
    """The rotor's keys and what their convention counts (:mod:`stand.solve.keys`)."""
    verdict: str = "none"
    """The one verdict: ``pass``, ``fail``, ``undecided`` or ``none`` (no tolerance)."""
    traces: Traces | None = field(default=None, compare=False)
    display: tuple[str, str] = ("g", "mm")
    """The units the operator sees: mass (g or oz) and length (mm or in)."""
    positions: tuple[int, float] = (0, 0.0)
    """The correction's positions: how many (0: any angle), and the angle of the first [deg]."""
    stand_name: str | None = None
    calibrated: str | None = None
    """The date of the stand's last calibration (YYYY-MM-DD), if the config says."""
    calibration_radius_kg_m: tuple[float, float] | None = None
    """Per plane: the 95 % radius the calibration's own uncertainty allows (the config's
    ``[calibration]``), beside the measurement's; None where not the rigid model's."""

    @property
    def U_kg_m(self) -> np.ndarray:
        """The unbalance of planes 1 and 2 [kg m] (the seed's ``q R e^{-i phi}``)."""
        return np.asarray(self.measurement.solution.U_kg_m)

    @property
    def omega_rad_s(self) -> float:
        """The speed the result refers to [rad/s]."""
        return self.measurement.omega_rad_s


def finite(obj: Any, where: str = "") -> Any:
    """``obj`` if every number in it is finite; else :class:`ModelError` naming the key.

    A NaN or an infinity in an answer means the inputs carry no physics (a speed
    of 1e300 rpm, NaN timestamps): it is refused, never printed.
    """
    if isinstance(obj, float) and not math.isfinite(obj):
        raise ModelError(f"the answer is not a finite number at {where or 'the top'} ({obj}): "
                         "the inputs make no physical sense")  # fmt: skip
    if isinstance(obj, dict):
        for k, v in obj.items():
            finite(v, f"{where}.{k}" if where else str(k))
    elif isinstance(obj, (list, tuple)):
        for i, v in enumerate(obj):
            finite(v, f"{where}[{i}]")
    return obj


def json_text(obj: Any, **kwargs: Any) -> str:
    """Strict JSON (no NaN or Infinity: :func:`finite` refuses them first)."""
    return json.dumps(finite(obj), allow_nan=False, **kwargs)
