"""The stand configuration: one TOML file, validated by pydantic.

Tables (SI units, the seed's symbols)::

    [stand]   M1 M2 C1 C2 [H1 H2 reference_angle_deg]
    [rotor]   M3 J3 a b c d R1 R2 [type bending_hz]
    [rotor.shaft] (optional) the shaft M3, J3, a..d and bending_hz follow from
    [[rotor.planes]] (optional) correction planes for balancing across speeds
                  (the rotor's tables: :mod:`stand.config.rotor`)
    [bus]     (optional) passed as is to ``can.Bus(**bus)``: interface,
              channel, bitrate and any option of the python-can interface
    [tolerance]   (optional) one form: grade, per plane, static + couple, API; the
                  acceptance moment (ISO 21940-11/-14, :mod:`stand.config.tolerance`)
    [correction]  (optional) mode, positions, position0_deg, weights_g, weight_step_g;
                  drilling and milling (:mod:`stand.config.correction`)
    [sensors]     (optional) gain, delay_s per node (from stand calibrate)
    [display]     (optional) mass = "g" | "oz", length = "mm" | "in" (what the operator sees)
    [archive]     (optional) url: the database runs are archived in
    [tooling], [plant], [calibration] (optional): the tooling, the plant's systems,
                  how well the calibration is known
    [drive]       (optional) the stand's drive, its shaft and the cycle's limits
                  (:mod:`stand.config.drive`)

Unknown keys and tables are refused (``extra="forbid"``); numbers must be
TOML numbers (a quoted ``"8.0"`` is refused, not guessed at).  The physical
checks are :meth:`stand.core.model.StandParameters.check`; their errors are
reported here with the file and the key.
"""

from __future__ import annotations

import json
import socket
import tomllib
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import BaseModel, Field, FiniteFloat, PositiveFloat, field_validator
from pydantic_core import PydanticCustomError

from stand.config.autobalancer import AutobalancerTable, check_autobalancer
from stand.config.bus import bus_choice
from stand.config.correction import CorrectionTable as CorrectionTable  # re-exported
from stand.config.correction import check_correction
from stand.config.drive import DriveTable, drive_choice
from stand.config.plant import PlantTable as PlantTable  # re-exported
from stand.config.rotor import SHAFT_AGREE
from stand.config.rotor import RotorTable as RotorTable  # re-exported
from stand.config.tables import STRICT as STRICT  # re-exported: every table's model config
from stand.config.tables import Angle, Mass, Name, Stiffness
from stand.config.tolerance import ToleranceTable as ToleranceTable  # re-exported
from stand.config.tolerance import check_keys, check_tolerance
from stand.config.validation import BUS_VALUE, shown
from stand.config.validation import validate as validate  # re-exported
from stand.core.model import STAND_KEYS, StandParameters
from stand.core.shaft import shaft_rotor
from stand.drivers.family import FAMILIES
from stand.errors import ConfigError, ModelError, ParameterError
from stand.files import not_regular


def default_stand_id() -> str:
    """The stand id without ``[stand] id``: this computer's host name (at most 64
    characters), the same for the CLI, the station, the archive, OPC UA, MQTT and Q-DAS."""
    return socket.gethostname()[:64] or "stand"


class StandTable(BaseModel):
    """``[stand]``: the supports (kg, N/m, N s/m) and the reference sensor (deg)."""

    model_config = STRICT

    M1: Mass
    M2: Mass
    C1: Stiffness
    C2: Stiffness
    H1: Stiffness = 0.0
    H2: Stiffness = 0.0
    reference_angle_deg: Angle = 0.0
    evaluation_interval_days: Annotated[int, Field(ge=1, le=3650)] = 30
    """How often ISO 21940-21's machine tests (stand evaluate) are due [days]: monthly for a
    stand in daily use."""
    clock_tolerance_pct: PositiveFloat = 0.1
    """How far the speeds two nodes measure of one shaft may differ [%]."""
    name: Name | None = None
    """The stand's name, as certificates show it (e.g. "stand 2, hall B")."""
    id: Name | None = None
    """The stand's id in a plant's shared archive (default: this computer's host name)."""

    def stand_id(self) -> str:
        """``id``, else this computer's host name."""

        return self.id or default_stand_id()

    calibrated: Annotated[str, Field(pattern=r"^\d{4}-\d{2}-\d{2}$")] | None = None
    """The date of its last calibration (YYYY-MM-DD; stand calibrate writes it)."""


class DisplayTable(BaseModel):
    """``[display]``: units shown to the operator (SI inside; the JSON keeps g and mm)."""

    model_config = STRICT

    mass: Literal["g", "oz"] = "g"
    length: Literal["mm", "in"] = "mm"


class ToolingTable(BaseModel):
    """``[tooling]``: the adapter, mandrel or coupling the rotor sits on; its unbalance,
    measured once by ``stand tooling measure``, is subtracted from every run."""

    model_config = STRICT

    name: Annotated[str, Field(pattern=r"^[A-Za-z0-9][A-Za-z0-9._-]{0,63}$")]
    """Letters, digits, ``. _ -`` (it names a file in the tooling folder; the same rule as
    :data:`stand.solve.tooling.TOOLING_NAME`)."""
    folder: Annotated[str, Field(min_length=1, max_length=4000)] | None = None
    """Where the tooling's measurement is kept (default: ``tooling/`` in the user's data
    folder, beside the archive)."""


class CalibrationTable(BaseModel):
    """``[calibration]``: how well the stand's calibration is known (half-widths of uniform
    bands, seed 003): every result's ``calibration_interval_g_mm`` follows from them."""

    model_config = STRICT

    C_pct: Annotated[FiniteFloat, Field(ge=0.0, le=100.0)] = 5.0
    """C1, C2 [%]."""
    M_pct: Annotated[FiniteFloat, Field(ge=0.0, le=100.0)] = 2.0
    """M1, M2, M3, J3 [%]."""
    length_mm: Annotated[FiniteFloat, Field(ge=0.0, le=1e3)] = 1.0
    """a, b, c, d [mm]."""
    gain_pct: Annotated[FiniteFloat, Field(ge=0.0, le=100.0)] = 1.0
    """Each sensor's gain [%]."""


class ArchiveTable(BaseModel):
    """``[archive]``: where runs are archived (a database URL; default: the user's own)."""

    model_config = STRICT

    url: Annotated[str, Field(min_length=1, max_length=2000)]
    """``sqlite:///path/archive.sqlite`` or ``postgresql+psycopg://user@host/db``."""


class SensorsTable(BaseModel):
    """``[sensors]``: each node's calibrated sensitivity (1 = as STATUS says) and delay [s]."""

    model_config = STRICT

    gain: Annotated[
        list[Annotated[FiniteFloat, Field(ge=0.1, le=10.0)]], Field(min_length=2, max_length=2)
    ] = [1.0, 1.0]
    """Within 0.1 to 10: a sensor ten times off its data sheet is a wrong sensor."""
    delay_s: Annotated[
        list[Annotated[FiniteFloat, Field(ge=-0.05, le=0.05)]], Field(min_length=2, max_length=2)
    ] = [0.0, 0.0]
    """Within +-50 ms: a sensor's and node's filters delay by microseconds to milliseconds."""


class Config(BaseModel):
    """A whole configuration file."""

    model_config = STRICT

    stand: StandTable
    rotor: RotorTable
    bus: dict[str, str | int | float | bool | list[Any] | dict[str, Any]] | None = None
    """Passed to ``can.Bus`` as given (lists for options such as ``can_filters``), but for
    ``protocol`` and the family's own table, the product's (:mod:`stand.config.bus`)."""

    @field_validator("bus", mode="before")
    @classmethod
    def _plain_values(cls, bus: Any) -> Any:
        """A table inside ``[bus]`` only as a family's own (``[bus.scan]``, ...): can.Bus
        takes plain values."""
        for key, value in bus.items() if isinstance(bus, dict) else ():
            if isinstance(value, dict) and key not in FAMILIES:
                raise PydanticCustomError("bus_value", BUS_VALUE, {"key": key, "got": shown(value)})
        return bus

    tolerance: ToleranceTable | None = None
    correction: CorrectionTable = CorrectionTable()
    sensors: SensorsTable = SensorsTable()
    display: DisplayTable = DisplayTable()
    archive: ArchiveTable | None = None
    tooling: ToolingTable | None = None
    plant: PlantTable | None = None
    calibration: CalibrationTable = CalibrationTable()
    autobalancer: AutobalancerTable | None = None
    drive: DriveTable | None = None

    def measure_options(self) -> dict[str, Any]:
        """What :func:`stand.measuring.measure.measure` needs from the configuration."""
        return {
            "reference_angle_deg": self.stand.reference_angle_deg,
            "clock_tolerance": self.stand.clock_tolerance_pct / 100,
            "sensor_gain": tuple(self.sensors.gain),
            "sensor_delay_s": tuple(self.sensors.delay_s),
        }

    def parameters(self) -> StandParameters:
        """The core's parameter object (raises :class:`ParameterError`)."""
        values = {**self.stand.model_dump(), **self.rotor.model_dump()}
        for key in ("reference_angle_deg", "clock_tolerance_pct", "type", "name", "calibrated",
                    "evaluation_interval_days",
                    "id", "bending_hz", "shaft", "planes", "keys", "serial_rule"):  # fmt: skip
            del values[key]
        return StandParameters(**values)


def parameters_of(cfg: Config, source: str) -> StandParameters:
    """The core parameters of a validated configuration (physical checks as ConfigError)."""
    try:
        return cfg.parameters()
    except ParameterError as exc:
        table = "stand" if exc.key in STAND_KEYS else "rotor"
        raise ConfigError(
            str(exc).split(": ", 1)[1], source=source, key=f"{table}.{exc.key}"
        ) from None


def config_from_dict(
    data: dict[str, Any], source: str = "<config>"
) -> tuple[Config, StandParameters]:
    """Validate a parsed configuration; return it and the core parameters.

    Raises
    ------
    ConfigError
        Naming ``source``, the first bad key and what is wrong with it.
    """
    cfg = with_shaft(validate(Config, data, source), source)
    check_correction(cfg.correction, cfg.rotor, source)
    if cfg.bus is not None:  # the family and its table, checked now
        bus_choice(cfg.bus, source)
    if cfg.drive is not None:  # the family and its table, checked now
        drive_choice(cfg.drive, source)
    params = parameters_of(cfg, source)
    check_tolerance(cfg.tolerance, params, source)
    check_keys(cfg.rotor.keys, params, source)
    check_autobalancer(cfg.autobalancer, params, source)
    return cfg, params


def with_shaft(cfg: Config, source: str) -> Config:
    """The config with ``M3, J3, a, b, c, d`` (and ``bending_hz``) from its ``[rotor.shaft]``
    table; values given as well must agree within :data:`SHAFT_AGREE`.  Without a shaft
    table, every one of them must be given."""
    r = cfg.rotor
    keys = ("M3", "J3", "a", "b", "c", "d")
    if r.shaft is None:
        missing = [k for k in keys if getattr(r, k) is None]
        if missing:
            raise ConfigError(
                "missing (give it, or describe the shaft in a [rotor.shaft] table)",
                source=source,
                key=f"rotor.{missing[0]}",
            )
        return cfg

    s = r.shaft
    try:
        got = shaft_rotor(*s.core_args())
    except ModelError as exc:
        raise ConfigError(str(exc), source=source, key="rotor.shaft") from None
    span = abs(s.support_positions_m[1] - s.support_positions_m[0])
    derived = {k: getattr(got, k) for k in keys} | {"bending_hz": got.bending_hz}
    for k, value in derived.items():
        given = getattr(r, k)
        scale = span if k in ("a", "b", "c", "d") else abs(value)
        if given is not None and abs(given - value) > SHAFT_AGREE * scale:
            raise ConfigError(
                f"{given:g} given, the shaft gives {value:.6g}: they differ by more than "
                f"{100 * SHAFT_AGREE:g} %",
                source=source,
                key=f"rotor.{k}",
            )
    update = {k: v for k, v in derived.items() if getattr(r, k) is None}
    return cfg.model_copy(update={"rotor": r.model_copy(update=update)})


def to_toml(tables: dict[str, dict[str, Any]]) -> str:
    """TOML text of flat tables of numbers, booleans and strings (what a config holds).

    >>> print(to_toml({"run": {"rpm": 900.0, "name": "x"}}), end="")
    [run]
    rpm = 900.0
    name = "x"
    """
    lines: list[str] = []
    for name, table in tables.items():
        lines.append(f"[{name}]")
        for key, value in table.items():
            lines.append(f"{key} = {_toml_value(value)}")
        lines.append("")
    return "\n".join(lines).rstrip("\n") + "\n"


def _toml_value(value: Any) -> str:
    """One TOML value: a boolean, string, number, array or inline table."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{k} = {_toml_value(v)}" for k, v in value.items()) + " }"
    return repr(value)


def config_toml(cfg: Config) -> str:
    """The configuration as TOML text (stored in run files)."""
    return to_toml({k: v for k, v in cfg.model_dump(exclude_none=True).items()})


def read_toml(path: str | Path) -> tuple[str, dict[str, Any]]:
    """The text of a TOML file and its parsed content (:class:`ConfigError` if unreadable)."""
    path = Path(path)
    try:
        if (kind := not_regular(path)) is not None:  # a FIFO would wait forever
            raise ConfigError(f"is {kind}, not a configuration file", source=str(path))
        raw = path.read_bytes()
    except OSError as exc:
        raise ConfigError(
            f"cannot read the configuration: {exc.strerror}", source=str(path)
        ) from None
    return parse_toml(raw, str(path))


def parse_toml(raw: bytes, source: str) -> tuple[str, dict[str, Any]]:
    """The text of a configuration's bytes and its parsed content (:class:`ConfigError`,
    naming ``source``, if they are not UTF-8 TOML)."""
    try:
        text = raw.decode("utf-8")
        return text, tomllib.loads(text)
    except UnicodeDecodeError as exc:
        raise ConfigError(
            f"not UTF-8 text ({exc.reason} at byte {exc.start})", source=source
        ) from None
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"not valid TOML: {exc}", source=source) from None
    except RecursionError:
        raise ConfigError("nested too deep to be a configuration", source=source) from None


def load_config(path: str | Path) -> tuple[Config, StandParameters]:
    """Read, parse and validate a configuration file.

    Examples
    --------
    >>> import tempfile, os
    >>> text = '''[stand]
    ... M1 = 8.0
    ... M2 = 9.0
    ... C1 = 4.5e4
    ... C2 = 5.2e4
    ... [rotor]
    ... M3 = 60.0
    ... J3 = 21.0
    ... a = 0.15
    ... b = 0.85
    ... c = 0.70
    ... d = 0.20
    ... R1 = 0.09
    ... R2 = "0.08"
    ... '''
    >>> with tempfile.NamedTemporaryFile("w", suffix=".toml", delete=False) as f:
    ...     _ = f.write(text)
    >>> try:
    ...     load_config(f.name)
    ... except ConfigError as e:
    ...     print(str(e).replace(f.name, "stand.toml"))
    stand.toml: [rotor.R2]: Input should be a valid number, got '0.08'
    >>> os.unlink(f.name)
    """
    _, data = read_toml(path)
    return config_from_dict(data, source=str(path))
