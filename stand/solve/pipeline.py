"""The application layer: from a recording (or live streams) and a config to one :class:`Result`.

Data flows one way::

    CAN frames -> per-node streams (stand.drivers.streams)
               -> 1x phasor per support, unbalance per plane (stand.measuring.measure)
               -> corrections, tolerance, parameter spread, check (here)
               -> Result (stand.solve.result) -> text, JSON, report, summary

Every command that measures goes through
:func:`stand.solve.recordings.solve_recording` (a file) or :func:`build_result`
(streams it already has, e.g. a live session); both through
:func:`measure_streams`.  The CLI modules parse arguments and format; none
of them repeats a step here.
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from stand import __version__
from stand.calib.tolerance import Tolerances, parameter_uncertainty
from stand.config import Config, config_from_dict, read_toml
from stand.core import Diagnostic, StandParameters, natural_frequencies, rad_s_to_rpm
from stand.core.balance import static_couple
from stand.core.flexible import RIGID_TOLERANCE, rigid_error_range, rigid_limit_rpm
from stand.core.inverse import RESONANCE_BAND
from stand.errors import ConfigError
from stand.i18n.words import said
from stand.measuring import Measurement
from stand.measuring.live_fit import remeasure
from stand.measuring.measure import measure
from stand.solve.autobalance import balls_note, balls_stand
from stand.solve.correct import corrections as plane_corrections
from stand.solve.keys import key_effects, with_keys
from stand.solve.result import (
    Check,
    LiveInfo,
    Provenance,
    Result,
    Traces,
    Uncertainty,
)
from stand.solve.tooling import compensate, folder, load_tooling, tooling_file
from stand.solve.verdict import combined_error, judged, plane_passes, tolerance_of

SOFTWARE = f"stand {__version__}"
SPECTRUM_MAX_SAMPLES = 1 << 18
"""The report's spectrum uses at most this many samples per node (the run's last ones)."""


@dataclass(frozen=True)
class SolveOptions:
    """How to solve a run.

    Attributes
    ----------
    taper : bool
        Hann taper against a neighbour close to 1x.
    gate : bool
        Use only the steady, settled part of the run.
    tolerances : stand.calib.tolerance.Tolerances or None
        Parameter tolerances to propagate (None: no parameter spread).
    draws : int
        Monte Carlo draws for the parameter spread.
    traces : bool
        Also compute the spectra and speed traces the report plots.
    matrix : stand.config.matrix.LoadedMatrix or None
        A stored influence matrix to use in place of the stand model.
    compensate : bool
        Subtract the config's ``[tooling]`` unbalance (:mod:`stand.solve.tooling`); off for
        the tooling's own index runs.
    acceptance : str or None
        ISO 21940-14's moment, ``after_balancing`` or ``later_check`` (None: the config's).
    """

    taper: bool = False
    gate: bool = True
    tolerances: Any = None
    draws: int = 1000
    traces: bool = False
    matrix: Any = None
    compensate: bool = True
    acceptance: str | None = None


def stored_config(meta: dict[str, Any], path: str) -> tuple[Any, StandParameters, str]:
    """The configuration a run file carries: (config, parameters, text)."""

    text = str(meta.get("config_toml", ""))
    if not text:
        raise ConfigError("carries no configuration: give --config CFG", source=path)
    source = f"{path} (stored config)"
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"the stored configuration is not TOML ({exc})", source=path) from exc
    cfg, params = config_from_dict(data, source=source)
    return cfg, params, text


def load_config_text(path: str) -> tuple[Any, StandParameters, str]:
    """A configuration file: (config, parameters, text)."""

    text, data = read_toml(path)
    cfg, params = config_from_dict(data, source=path)
    return cfg, params, text


@dataclass(frozen=True)
class ConfigText:
    """A configuration given by its text, not its path: what a worker on another machine,
    which cannot read the client's file, solves with (``source`` names it in errors and in
    the result's provenance)."""

    text: str
    source: str

    def load(self) -> tuple[Any, StandParameters, str]:
        """(config, parameters, text), as :func:`load_config_text` gives them."""
        try:
            data = tomllib.loads(self.text)
        except tomllib.TOMLDecodeError as exc:
            raise ConfigError(f"not TOML ({exc})", source=self.source) from exc
        cfg, params = config_from_dict(data, source=self.source)
        return cfg, params, self.text


def precision_targets(
    cfg: Config,
    params: StandParameters,
    U_kg_m: Sequence[complex],
    *,
    pct: float | None = None,
    abs_kg_m: float | None = None,
    tolerance_share: float | None = None,
    default_pct: float = 5.0,
) -> tuple[float, float]:
    """The 95 % radius each plane must reach [kg m].

    An absolute target, else a percentage of each plane's unbalance, else
    ``tolerance_share`` of each plane's ISO tolerance (when the config has
    one), else ``default_pct`` of the unbalance.
    """
    if abs_kg_m is not None:
        return abs_kg_m, abs_kg_m
    if pct is None and tolerance_share is not None:
        tol = tolerance_of(cfg, params)
        if tol is not None:
            return tuple(tolerance_share * u for u in tol.per_plane_kg_m)  # type: ignore[return-value]
    share = (default_pct if pct is None else pct) / 100
    return share * abs(U_kg_m[0]), share * abs(U_kg_m[1])


def _uncertainty(m: Measurement, params: StandParameters, options: SolveOptions) -> Uncertainty:

    A = np.array([ph.A_m_s2 for ph in m.supports])
    r = parameter_uncertainty(params, m.omega_rad_s, A, options.tolerances, draws=options.draws)
    lin, mc = r.radius95_linear, r.radius95_monte_carlo
    return Uncertainty(
        options.tolerances,
        (float(lin[0]), float(lin[1])),
        (float(mc[0]), float(mc[1])),
        r.shares,
        r.draws,
    )


def calibration_radius(
    m: Measurement,
    cfg: Config,
    params: StandParameters,
    options: SolveOptions,
    drifted: dict[str, float] | None = None,
) -> tuple[float, float] | None:
    """Each plane's 95 % radius [kg m] from what the calibration is known to (the config's
    ``[calibration]`` bands, linearised, :mod:`stand.calib.tolerance`): what the stand's
    knowledge allows, beside what the data allow.  ``drifted``: relative changes the
    stand's health found (``{"C1": 0.2, ...}``, :func:`stand.health.monitor.drift_bands`); each
    widens its class's band to at least that.  None where the answer is not the rigid
    model's (an influence matrix, a bending shaft)."""

    if options.matrix is not None or cfg.rotor.shaft is not None:
        return None
    c, d = cfg.calibration, drifted or {}
    tol = Tolerances(
        max(c.C_pct / 100, d.get("C1", 0.0), d.get("C2", 0.0)),
        max(c.M_pct / 100, d.get("M1", 0.0), d.get("M2", 0.0)),
        c.length_mm * 1e-3,
        max(c.gain_pct / 100, d.get("gain1", 0.0), d.get("gain2", 0.0)),
    )
    A = np.array([ph.A_m_s2 for ph in m.supports])
    r = parameter_uncertainty(params, m.omega_rad_s, A, tol, draws=0)
    return float(r.radius95_linear[0]), float(r.radius95_linear[1])


def traces_of(streams: Any, omega_rad_s: float) -> Traces:
    """Spectra (up to 4x) and speed over the run, per node, for the report."""
    spectra: dict[int, tuple[np.ndarray, np.ndarray]] = {}
    speeds: dict[int, tuple[np.ndarray, np.ndarray]] = {}
    f1 = omega_rad_s / (2 * np.pi)
    for n, s in sorted(streams.nodes.items()):
        if s.rate_hz is None or s.rate_hz <= 0:
            continue
        if s.accel_m_s2 is not None and len(s.index) >= 64:
            seg = np.flatnonzero(s.segment == 0)[-SPECTRUM_MAX_SAMPLES:]
            idx = s.index[seg]
            a = np.zeros(int(idx[-1] - idx[0]) + 1)
            a[idx - idx[0]] = s.accel_m_s2[seg]  # lost samples as zeros: a spectrum is a view
            win = np.hanning(len(a))
            spec = 2 * np.abs(np.fft.rfft(a * win)) / np.sum(win)
            f = np.fft.rfftfreq(len(a), 1 / s.rate_hz)
            band = f <= 4 * f1
            spectra[n] = (f[band], spec[band])
        m = s.mark_segment == 0
        pos, rev = s.mark_position[m], s.mark_rev[m]
        if len(pos) >= 2:
            t = (pos[1:] + pos[:-1]) / 2 / s.rate_hz
            speeds[n] = (t, 2 * np.pi * s.rate_hz * np.diff(rev) / np.diff(pos))
    return Traces(spectra, speeds)


def _floor_notes(m: Measurement, noise: Sequence[bool], provenance: Provenance) -> list[Diagnostic]:
    """Planes inside their own interval (no correction prescribed), and a tooling measured
    with another configuration."""
    floor = [
        Diagnostic(
            "within_noise",
            said(
                "plane {plane}: {u} g mm is inside its own 95 % interval (+-{r} g mm): its angle "
                "is undefined, so no correction is prescribed",
                plane=i + 1,
                u=f"{abs(U) * 1e6:.1f}",
                r=f"{m.radius95_kg_m[i] * 1e6:.1f}",
            ),
            float(abs(U) / m.radius95_kg_m[i]),
        )
        for i, U in enumerate(m.solution.U_kg_m)
        if noise[i]
    ]
    if m.tooling is not None and m.tooling.config_sha256 != provenance.config_sha256:
        floor.append(
            Diagnostic(
                "tooling_config",
                said(
                    "the tooling {name} was measured with another configuration (on "
                    "{date}): if the stand was calibrated since, measure the tooling again "
                    "(stand tooling measure)",
                    name=repr(m.tooling.name),
                    date=m.tooling.measured[:10],
                ),
            )
        )
    return floor


def build_result(
    m: Measurement,
    cfg: Config,
    params: StandParameters,
    *,
    stream_warnings: Sequence[Any] = (),
    provenance: Provenance,
    options: SolveOptions = SolveOptions(),
    streams: Any = None,
    check: Check | None = None,
    live: LiveInfo | None = None,
) -> Result:
    """Corrections, static and couple parts, tolerance and spread for a measurement."""
    c = cfg.correction
    noise = [abs(U) <= m.radius95_kg_m[i] for i, U in enumerate(m.solution.U_kg_m)]
    tolerance = tolerance_of(cfg, params, options.acceptance, m.omega_rad_s)
    cal = calibration_radius(m, cfg, params, options)
    judgements, verdict = (
        ((), "none")
        if tolerance is None
        else judged(tolerance, m.solution.U_kg_m, combined_error(m.radius95_kg_m, cal))
    )
    fine = plane_passes(tolerance, judgements, verdict)  # nothing to do in this plane
    corrections = plane_corrections(
        m.solution.U_kg_m,
        m.radius_m,
        c,
        skip=[a or b for a, b in zip(noise, fine, strict=True)],
        permissible_kg_m=None if tolerance is None else tolerance.per_plane_kg_m,
    )
    floor = _floor_notes(m, noise, provenance)
    static, couple = static_couple(params, m.solution.U_kg_m)
    return Result(
        measurement=m,
        corrections=corrections,
        correction_mode=c.mode,
        static_kg_m=static,
        couple_kg_m=couple,
        tolerance=tolerance,
        warnings=(*stream_warnings, *m.warnings, *floor),
        within_noise=(bool(noise[0]), bool(noise[1])),
        within_tolerance=fine,
        judgements=judgements,
        verdict=verdict,
        provenance=provenance,
        uncertainty=_uncertainty(m, params, options) if options.tolerances is not None else None,
        check=check,
        live=live,
        traces=traces_of(streams, m.omega_rad_s) if options.traces and streams else None,
        display=(cfg.display.mass, cfg.display.length),
        positions=(c.positions, c.position0_deg),
        stand_name=cfg.stand.name,
        calibrated=cfg.stand.calibrated,
        calibration_radius_kg_m=cal,
        keys=key_effects(cfg.rotor.keys, params),
    )


def measure_streams(
    streams: Any, cfg: Config, params: StandParameters, options: SolveOptions
) -> Any:
    """The measurement of a run's streams with the config's sensor calibration (and the
    options' influence matrix in place of the model, if any)."""
    m = measure(
        streams, balls_stand(params, cfg.autobalancer), **cfg.measure_options(),
        taper=options.taper, gate=options.gate,
        influence=None if options.matrix is None else options.matrix.imap,
        beam=cfg.rotor.beam(),
    )  # fmt: skip
    return _finish(m, cfg, params, options)


def remeasure_streams(
    prev: Any, tails: Any, cfg: Config, params: StandParameters, options: SolveOptions
) -> Any:
    """:func:`measure_streams` of a live run from its last measurement ``prev`` and the
    streams of its last frames (:func:`stand.measuring.live_fit.remeasure`); None when a full pass
    is due."""

    m = remeasure(
        prev, tails, balls_stand(params, cfg.autobalancer), **cfg.measure_options(),
        influence=None if options.matrix is None else options.matrix.imap,
        beam=cfg.rotor.beam(),
    )  # fmt: skip
    return None if m is None else _finish(m, cfg, params, options)


def _finish(m: Any, cfg: Config, params: StandParameters, options: SolveOptions) -> Any:
    """The config's notes on a measurement, and its tooling taken out."""
    flexible = cfg.rotor.shaft is not None and options.matrix is None
    notes = [None if flexible else rigid_note(cfg, params, m.omega_rad_s)]
    notes.append(balls_note(cfg, params, m))
    if options.matrix is not None:
        notes.append(options.matrix.speed_note(m.omega_rad_s))
    if any(notes):
        m = replace(m, warnings=[*m.warnings, *(n for n in notes if n is not None)])
    if cfg.tooling is not None and options.compensate:
        where = folder(cfg.tooling)
        if tooling_file(cfg.tooling.name, where).exists():
            m = compensate(m, load_tooling(cfg.tooling.name, where))
        else:  # its own index runs come first: measured, and said loudly
            note = Diagnostic(
                "tooling_not_measured",
                said(
                    "the tooling {name} has not been measured: its unbalance is NOT "
                    "subtracted from this answer (measure it: stand tooling measure RUN_0 "
                    "RUN_180)",
                    name=repr(cfg.tooling.name),
                ),
            )
            m = replace(m, warnings=[*m.warnings, note])
    if options.compensate:  # the tooling's own index runs measure the tooling, not the part
        m = with_keys(m, key_effects(cfg.rotor.keys, params))
    return m


def rigid_note(cfg: Config, params: StandParameters, omega_rad_s: float) -> Diagnostic | None:
    """A warning when a rotor bending at ``[rotor] bending_hz`` would put the rigid model's
    answer more than 1 % off at this speed (:mod:`stand.core.flexible`)."""

    f_ff = cfg.rotor.bending_hz
    if f_ff is None:
        return None
    f = omega_rad_s / (2 * math.pi)
    lo, hi = rigid_error_range(f, f_ff)
    if hi <= RIGID_TOLERANCE:
        return None
    limit = rigid_limit_rpm(f_ff)
    floor = float(rad_s_to_rpm(natural_frequencies(params).max())) * RESONANCE_BAND
    cure = (said("balance at {rpm} rpm or below for 1 %", rpm=f"{limit:.0f}") if limit > floor
            else said("within 1 % it needs {rpm} rpm or less, below this stand's natural "
                      "frequencies ({floor} rpm with their margin): the rotor needs a flexible "
                      "model, or a stiffer stand",
                      rpm=f"{limit:.0f}", floor=f"{floor:.0f}"))  # fmt: skip
    return Diagnostic("flexible_rotor", said(
        "the rotor bends: at {rpm} rpm, {pct} % of its first bending frequency ({hz} Hz), the "
        "rigid model's answer may be off by {lo} to {hi} % (mostly in the static part); {cure}",
        rpm=f"{60 * f:.0f}", pct=f"{100 * f / f_ff:.1f}", hz=f"{f_ff:g}", lo=f"{100 * lo:.1f}",
        hi=f"{100 * hi:.1f}", cure=cure), hi)  # fmt: skip


def check_matrix(options: SolveOptions, cfg: Config, *, live: bool) -> None:
    """Refuse the options' influence matrix for another rotor type (or typed-in readings
    on the stand) before anything is measured."""
    if options.matrix is not None:
        options.matrix.check(cfg.rotor.type, live=live)
