"""The rotor types a station measures, and the changes a setter and an engineer make to
them at the station, each asked of the account's rights and journaled.

- :func:`load_rotor_type` (a setter: right ``load``): a rotor type from a TOML file, new
  or (``replace``) in place of the type of the same name.  A file that changes that
  type's ``[tolerance]`` takes the right ``tolerance`` too (an engineer), and one whose
  ``[stand]`` (its figures), ``[sensors]`` or ``[calibration]`` differ from the
  station's calibration takes ``calibrate``: a setter cannot change either by a file.
- :func:`set_tooling` (a setter): the tooling a rotor type sits on (one measured with
  ``stand tooling measure``), or none.
- :func:`set_tolerance` (an engineer: right ``tolerance``): a grade tolerance's G, the
  maximum speed and the source.
- :func:`recalibrate` (an engineer: right ``calibrate``): the stand re-identified from
  the archive's corrected rotors, written only when the change is significant.

Every change needs a reason; it keeps the file it replaces in ``<config dir>/.history/``
(named by the time, UTC) and writes one entry in the audit trail (``config``, or
``calibration`` for a recalibration: who, the reason, the file's SHA-256 before and
after), the entry the Start screen then finds (:func:`stand.archive.audit.config_seen`).
The shipped demo rotor types are never changed.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

from stand.actions import Rights, replace_config
from stand.archive import correction_rows
from stand.config import CALIBRATION_KEYS, Config, config_from_dict, load_config, parse_toml
from stand.config.edit import updated_toml, without_table
from stand.config.paths import SHIPPED_ROTORS
from stand.config.schema import ToolingTable
from stand.core import StandParameters
from stand.errors import StandError, UsageError
from stand.health.monitor import Refit, refit
from stand.health.recalibrate import fits_text, kept_line, refitted_config, significant
from stand.i18n.language import Language
from stand.solve.tooling import folder, stored_toolings
from stand.solve.verdict import tolerance_of
from stand.station.guard import refused
from stand.station.service import Station
from stand.station.sessions import Session, actor

MAX_CONFIG_BYTES = 256 * 1024
"""A rotor type's file is a few kB; one over 256 kiB is refused unread."""
TYPE_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]{0,63}")
"""A rotor type's name, as its file is named: letters, digits, ``._-``."""


def rotor_type_rows(station: Station, _: Language) -> list[dict[str, str]]:
    """Per rotor type: its tolerance, when the stand was calibrated, its tooling (a type
    whose file does not load says why)."""
    rows = []
    for name in station.rotor_types():
        try:
            cfg, params = load_config(str(station.config_path(name)))
        except StandError as exc:
            rows.append({"type": name, "tolerance": str(exc), "calibrated": "", "tooling": ""})
            continue
        rows.append({"type": name, "tolerance": _tolerance_text(cfg, params, _),
                     "calibrated": cfg.stand.calibrated or "-",
                     "tooling": cfg.tooling.name if cfg.tooling else "-"})  # fmt: skip
    return rows


def _tolerance_text(cfg: Config, params: StandParameters, _: Language) -> str:
    """The tolerance as the table shows it: its source (:func:`stand.solve.tolerance_of`),
    with G and the speed where the grade form names its own source."""
    t, tol = cfg.tolerance, tolerance_of(cfg, params)
    if t is None or tol is None:
        return "-"
    text = _(tol.source)
    if tol.form == "grade" and t.source:
        text = (
            _("G {grade} at {rpm} rpm").format(
                grade=f"{t.grade_mm_s:g}", rpm=f"{t.max_speed_rpm:g}"
            )
            + f" ({text})"
        )
    return text


def _allow(station: Station, session: Session | None, right: str, what: str,
           _: Language) -> None:  # fmt: skip
    """UsageError (the screen shows it) unless the account may ``what`` (a lone stand
    may)."""
    if not station.sessions.required():
        return
    why = refused(session, right, what, _)
    if why is not None:
        raise UsageError(_("refused: {why}").format(why=why))


def _calibration(cfg: Config) -> tuple[Any, ...]:
    return ({k: getattr(cfg.stand, k) for k in CALIBRATION_KEYS}, cfg.sensors, cfg.calibration)


def _reason(station: Station, reason: str, _: Language) -> str:
    """The reason typed, refused when empty; and a station on the shipped demo rotor types
    is refused here too (they are the product's, not the stand's)."""
    if station.config_dir == SHIPPED_ROTORS:
        raise UsageError(_("these are the shipped demo rotor types: start the station "
                           "with --config-dir FOLDER (the stand's own) to change rotor "
                           "types"))  # fmt: skip
    reason = " ".join(reason.split())
    if not reason:
        raise UsageError(_("give the reason for the change: the audit trail keeps it"))
    return reason  # the journal refuses one of over 1000 characters, never cuts it


def load_rotor_type(station: Station, session: Session | None, file_name: str, raw: bytes,
                    *, replace: bool, reason: str, _: Language) -> str:  # fmt: skip
    """Load a rotor type from the bytes of a TOML file (named by its ``[rotor] type``);
    its name.  UsageError/ConfigError, in one line, for a file that is not a rotor type
    of this stand, a type that exists (without ``replace``) or a change the account may
    not make."""
    _allow(station, session, "load", _("load a rotor type"), _)
    reason = _reason(station, reason, _)
    if len(raw) > MAX_CONFIG_BYTES:
        raise UsageError(f"{file_name[:64]}: {len(raw)} bytes; a rotor type is under 256 kiB")
    text, data = parse_toml(raw, file_name[:64])
    cfg = config_from_dict(data, source=file_name[:64])[0]
    name = cfg.rotor.type or ""
    if not TYPE_NAME.fullmatch(name):
        raise UsageError(
            _(
                "{file}: its [rotor] type {type} cannot name a rotor type (letters, digits, . _ -)"
            ).format(file=file_name[:64], type=repr(name[:64]))
        )
    _same_stand(station, cfg, name, _)
    path = station.config_dir / f"{name}.toml"
    if path.exists() and not replace:
        raise UsageError(_("rotor type {type} exists: tick replace to load this file in its "
                           "place").format(type=name))  # fmt: skip
    others = [t for t in station.rotor_types() if t != name]
    rights = ["load"]
    if others and _calibration(cfg) != _calibration(_config(station, others[0])):
        _allow(station, session, "calibrate", _("change the stand's calibration"), _)
        rights.append("calibrate")
    if path.exists() and cfg.tolerance != _config(station, name).tolerance:
        _allow(station, session, "tolerance", _("change a tolerance"), _)
        rights.append("tolerance")
    _replace(station, path, text, session, reason, right=tuple(rights),
             what="load a rotor type")  # fmt: skip
    return name


def _config(station: Station, name: str) -> Config:
    return load_config(str(station.config_dir / f"{name}.toml"))[0]


def _same_stand(station: Station, cfg: Config, name: str, _: Language) -> None:
    """Refuse a rotor type of another stand or archive than the station's others."""
    others = [t for t in station.rotor_types() if t != name]
    if others and cfg.stand.stand_id() != station.stand_id():
        raise UsageError(_("rotor type {type} names stand {other}: this station is stand "
                           "{stand}").format(type=name, other=cfg.stand.stand_id(),
                                             stand=station.stand_id()))  # fmt: skip
    url = cfg.archive.url if cfg.archive is not None else None
    if url and str(url) != station.archive_url:
        raise UsageError(_("rotor type {type} archives elsewhere ([archive] url): this "
                           "station archives in its own").format(type=name))  # fmt: skip


def grade_of(station: Station, rotor_type: str) -> tuple[float | None, float | None, str]:
    """A rotor type's tolerance as the Tolerance panel edits it: G [mm/s], the maximum
    speed [rpm], the source (None, None, "" where it has none or its file does not load)."""
    try:
        t = load_config(str(station.config_path(rotor_type)))[0].tolerance
    except StandError:
        return None, None, ""
    if t is None:
        return None, None, ""
    return t.grade_mm_s, t.max_speed_rpm, t.source or ""


def set_tolerance(station: Station, session: Session | None, rotor_type: str, *,
                  grade_mm_s: float, max_speed_rpm: float, source: str, reason: str,
                  _: Language) -> None:  # fmt: skip
    """A grade tolerance's G [mm/s], maximum speed [rpm] and source, changed."""
    _allow(station, session, "tolerance", _("change a tolerance"), _)
    reason = _reason(station, reason, _)
    path = station.config_path(rotor_type)
    cfg, params = load_config(str(path))
    tol = tolerance_of(cfg, params)
    if cfg.tolerance is None or tol is None or tol.form != "grade":
        raise UsageError(_("rotor type {type}: only a grade tolerance is edited here; load "
                           "a file for another form").format(type=rotor_type))  # fmt: skip
    table = cfg.tolerance.model_dump(exclude_none=True) | {
        "grade_mm_s": grade_mm_s, "max_speed_rpm": max_speed_rpm}  # fmt: skip
    if source.strip():
        table["source"] = " ".join(source.split())
    new = _validated(cfg, "tolerance", table, path)
    _replace(station, path, updated_toml(path.read_text(encoding="utf-8"), new), session, reason,
             right="tolerance", what="change a tolerance")  # fmt: skip


def _validated(cfg: Config, name: str, table: dict[str, Any] | None, path: Path) -> Config:
    """``cfg`` with its table ``name`` replaced, validated as a whole (ConfigError naming
    the file where a value is out of bounds)."""
    data = cfg.model_dump(exclude_none=True)
    data[name] = table
    return config_from_dict({k: v for k, v in data.items() if v is not None},
                            source=str(path))[0]  # fmt: skip


def toolings(station: Station, rotor_type: str) -> list[str]:
    """The toolings measured in the folder of the rotor type's ``[tooling]`` (default
    folder without one)."""
    cfg = load_config(str(station.config_path(rotor_type)))[0]
    return [t.name for t in stored_toolings(folder(cfg.tooling))]


def set_tooling(station: Station, session: Session | None, rotor_type: str,
                tooling: str | None, *, reason: str, _: Language) -> None:  # fmt: skip
    """The rotor type sits on ``tooling`` (a measured one), or on none."""
    _allow(station, session, "load", _("change a rotor type's tooling"), _)
    reason = _reason(station, reason, _)
    path = station.config_path(rotor_type)
    cfg = load_config(str(path))[0]
    text = path.read_text(encoding="utf-8")
    if tooling is None:
        _replace(station, path, without_table(text, "tooling"), session, reason, right="load",
                 what="change a rotor type's tooling")  # fmt: skip
        return
    if tooling not in toolings(station, rotor_type):
        raise UsageError(_("no measured tooling {name} (stand tooling measure measures "
                           "one)").format(name=tooling))  # fmt: skip
    where = cfg.tooling.folder if cfg.tooling else None
    new = cfg.model_copy(update={"tooling": ToolingTable(name=tooling, folder=where)})
    _replace(station, path, updated_toml(text, new), session, reason, right="load",
             what="change a rotor type's tooling")  # fmt: skip


def recalibration(station: Station, rotor_type: str) -> Refit:
    """The stand re-identified from the archive's corrected rotors of this stand and
    rotor type (:func:`stand.health.monitor.refit`; UsageError when the data do not
    allow it)."""
    params = load_config(str(station.config_path(rotor_type)))[1]
    rows = correction_rows(station.archive_url, station.stand_id(), rotor_type)
    return refit(rows, params)


def recalibrate(station: Station, session: Session | None, rotor_type: str, *, reason: str,
                _: Language) -> str:  # fmt: skip
    """Write the recalibration in place when it is significant (journaled as a
    ``calibration``); what was done, in words (the kept line when it is not)."""
    _allow(station, session, "calibrate", _("change the stand's calibration"), _)
    reason = _reason(station, reason, _)
    r = recalibration(station, rotor_type)
    if not significant(r):
        return _(kept_line(r))
    path = station.config_path(rotor_type)
    cfg = load_config(str(path))[0]
    text = refitted_config(cfg, r, path.read_text(encoding="utf-8"))[1]
    _replace(station, path, text, session, reason, right="calibrate",
             what="change the stand's calibration", action="calibration")  # fmt: skip
    return _("calibration written and journaled: {fits} (95 %)").format(fits=fits_text(r))


def _replace(station: Station, path: Path, text: str, session: Session | None,
             reason: str, *, right: Rights, what: str, action: str = "config") -> int:  # fmt: skip
    """Keep the file ``path`` replaces in ``.history/``, write ``text`` in its place
    (a temporary name, then a rename), and journal it, in one transaction with the right
    checked again (:func:`stand.actions.replace_config`); the audit entry's id."""
    return replace_config(station.archive_url, actor(session), path, text, right=right,
                          what=what, reason=reason, action=action)  # fmt: skip
