"""The application layer's recording path: a run file or a CAN log and a config to a Result.

:func:`solve_recording` reads a recording, takes its stored configuration
(or the one given) and its stored influence matrix, measures it through
:func:`stand.solve.pipeline.measure_streams` and builds the one
:class:`~stand.solve.result.Result` with :func:`stand.solve.pipeline.build_result`; a
batch (:func:`solve_many`), a measurement alone (:func:`measure_recording`),
the masses a correction puts on (:func:`correction_masses`) and the summary
of a recording (:func:`recording_summary`) are its neighbours.  The live path
is :mod:`stand.live.loop`.
"""

from __future__ import annotations

import copy
import math
import multiprocessing
import os
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from contextlib import contextmanager
from dataclasses import dataclass, replace
from typing import Any

from stand.config import Config, parse_matrix
from stand.core import StandParameters
from stand.drivers.family import FrameBuilder
from stand.drivers.runs.recording import (
    JOB_ATTR,
    MATRIX_ATTR,
    STAND_ATTR,
    Recording,
    config_digest,
    read_streams,
)
from stand.drivers.streams import RunStreams
from stand.errors import MeasurementError, NoStatusError, RecordingError, StandError
from stand.measuring import Measurement
from stand.measuring.measure import measure
from stand.solve.acquisition import acquisition_of, default_acquisition, stored_descriptions
from stand.solve.correct import removed_masses
from stand.solve.pipeline import (
    SOFTWARE,
    ConfigText,
    SolveOptions,
    build_result,
    check_matrix,
    load_config_text,
    measure_streams,
    stored_config,
)
from stand.solve.result import Job, Provenance, Result


def job_of(meta: dict[str, Any], path: str) -> Job:
    """The job a run file records (an empty one if none; RecordingError if damaged)."""

    text = meta.get(JOB_ATTR)
    if not text:
        return Job()
    try:
        return Job.from_text(str(text))
    except (ValueError, TypeError) as exc:
        raise RecordingError(
            f"the attribute {JOB_ATTR!r} is not a job ({exc})", path=path
        ) from None


def solve_recording(
    path: str,
    config: str | ConfigText | None = None,
    options: SolveOptions = SolveOptions(),
    *,
    adjust: Callable[[Measurement], Measurement] | None = None,
) -> Result:
    """Solve one recorded run (a run file or a python-can log).

    Parameters
    ----------
    path
        The recording.
    config
        A configuration file (or its text, :class:`~stand.solve.pipeline.ConfigText`);
        None: the one the run file carries.
    options
        How to solve.  Without a matrix, a run measured with an influence
        matrix is solved with the one it stores.
    adjust
        A last step on the measurement before the result is built (the
        initial run of trial runs: its joint covariance with the matrix).

    Raises
    ------
    StandError
        Bad input, naming the file and what is wrong.
    """

    return solve_read(read_run(path, config), options, adjust=adjust)


def solve_read(
    run: RunRead,
    options: SolveOptions = SolveOptions(),
    *,
    adjust: Callable[[Measurement], Measurement] | None = None,
) -> Result:
    """:func:`solve_recording` of a run already read (:func:`read_run`): a command that
    needs the run's streams too reads it once."""
    path = run.rec.path
    rec, cfg, params, text, source, streams = (run.rec, run.cfg, run.params, run.text,
                                               run.source, run.streams)  # fmt: skip
    stored = rec.meta.get(MATRIX_ATTR)
    if options.matrix is None and stored:  # measured with a matrix: reprocessed with it
        options = replace(options, matrix=parse_matrix(str(stored), f"{path} (stored matrix)"))
    check_matrix(options, cfg, live=True)
    with named_errors(path):
        m = measure_streams(streams, cfg, params, options)
    if adjust is not None:
        m = adjust(m)
    prov = Provenance(
        software=SOFTWARE,
        run_file=path,
        config_sha256=config_digest(text),
        config_source=source,
        start_time=str(rec.meta.get("start_time", "")),
        source=str(rec.meta.get("source", "")),
        frames=streams.frames,
        duration_s=streams.duration_s,
        config_toml=text,
        matrix=None if options.matrix is None else options.matrix.path,
        job=job_of(rec.meta, path),
        rotor_type=cfg.rotor.type,
        stand_id=str(rec.meta.get(STAND_ATTR) or cfg.stand.stand_id()),
    )
    return build_result(
        m, cfg, params, stream_warnings=(*rec.warnings, *streams.warnings), provenance=prov,
        options=options, streams=streams,
    )  # fmt: skip


@dataclass(frozen=True)
class RunRead:
    """A recording read once and decoded once: its attributes, the config it is solved
    with (given, or the one it carries), and its streams as that config's family reads
    them."""

    rec: Recording
    cfg: Config
    params: StandParameters
    text: str
    source: str
    streams: RunStreams


def read_run(path: str, config: str | ConfigText | None, *, strict_status: bool = True,
             fallback: ConfigText | None = None) -> RunRead:  # fmt: skip
    """Read ``path`` once: its attributes first, then the config (``config``, else the
    run's own, else ``fallback``) chooses the family
    (:func:`stand.solve.acquisition.acquisition_of`, with the description files the run
    kept), whose builder decodes the frames block by block."""
    chosen: list[tuple[Config, StandParameters, str, str]] = []

    def choose(meta: dict[str, Any]) -> FrameBuilder:
        if config is None and fallback is not None and not meta.get("config_toml"):
            cfg, params, text = fallback.load()
            source = fallback.source
        elif isinstance(config, ConfigText):
            cfg, params, text = config.load()
            source = config.source
        elif config:
            cfg, params, text = load_config_text(config)
            source = config
        else:
            cfg, params, text = stored_config(meta, path)
            source = f"{path} (stored)"
        chosen[:] = [(cfg, params, text, source)]
        own = source.endswith(" (stored)")  # its own config: the description files it kept
        acq = acquisition_of(cfg, source, stored=stored_descriptions(meta, path, own=own))
        return acq.builder()

    with named_errors(path):
        rec, streams = read_streams(path, choose, strict_status=strict_status)
    cfg, params, text, source = chosen[0]
    return RunRead(rec, cfg, params, text, source, streams)


def stored_streams(rec: Recording) -> RunStreams:
    """The streams of a recording read whole (its frames in memory), as the configuration
    it carries reads them (protocol v1's when it carries none)."""
    if rec.meta.get("config_toml"):
        cfg, _, _ = stored_config(rec.meta, rec.path)
        acq = acquisition_of(cfg, f"{rec.path} (stored)",
                             stored=stored_descriptions(rec.meta, rec.path))  # fmt: skip
    else:
        acq = default_acquisition()
    return acq.streams(rec.frames, strict_status=False)


def _solve_or_error(path: str, config: str | None, options: SolveOptions) -> Result | StandError:
    """One run of a batch: its result, or the error that refused it (never raises bad input)."""
    try:
        return solve_recording(path, config, options)
    except StandError as exc:
        return exc


def solve_many(
    paths: Sequence[str],
    config: str | None,
    options: SolveOptions,
    jobs: int = 1,
    progress: Callable[[], None] | None = None,
) -> Iterator[tuple[str, Result | StandError]]:
    """Solve several runs (in ``jobs`` processes), yielding each as it is done."""
    if jobs == 1:
        for path in paths:
            yield path, _solve_or_error(path, config, options)
            if progress:
                progress()
        return

    # fresh interpreters with one BLAS thread each: N processes, not N x cores threads
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(var, "1")
    context = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(max_workers=jobs, mp_context=context) as pool:
        futures = {pool.submit(_solve_or_error, p, config, options): p for p in paths}
        for f in as_completed(futures):
            yield futures[f], f.result()
            if progress:
                progress()


def measure_recording(
    path: str, config: str | None = None, *, raw_sensors: bool = False, compensate: bool = True
) -> tuple[Measurement, Any, StandParameters, str]:
    """One run's measurement alone, for identification and influence coefficients.

    ``raw_sensors``: the nodes' phasors as they read, without the config's
    ``[sensors]`` gains and delays (what a calibration identifies); ``compensate`` False:
    without the ``[tooling]`` compensation (the tooling's own runs).  Returns the
    measurement, the config, its parameters and its text.
    """

    run = read_run(path, config)
    streams, cfg, params, text = run.streams, run.cfg, run.params, run.text
    with named_errors(path):
        if raw_sensors:
            m = measure(streams, params, reference_angle_deg=cfg.stand.reference_angle_deg)
        else:
            m = measure_streams(streams, cfg, params, SolveOptions(compensate=compensate))
    return m, cfg, params, text


def correction_masses(run: str, config: str | None = None) -> list[tuple[int, float, float, float]]:
    """The masses an operator puts on (grams > 0) or takes off (< 0) to apply the correction
    that ``run``'s result prescribes, with its config's mode, positions and weights:
    ``(plane, grams, angle_deg, radius_m)`` each, the angle from the reference mark
    against the direction of rotation; a drilled hole or a slot as the metal it removes
    at its centre of mass's radius (not at the radius the drill enters).
    """
    return result_masses(solve_recording(run, config))


def result_masses(result: Result) -> list[tuple[int, float, float, float]]:
    """:func:`correction_masses` of a result already solved."""
    return [
        (i + 1, grams, angle, radius)
        for i, corr in enumerate(result.corrections)
        for grams, angle, radius in removed_masses(corr, result.measurement.radius_m[i])
    ]


@contextmanager
def named_errors(path: str) -> Iterator[None]:
    """Measuring errors of a recorded run name its file (its node and figure they name)."""
    try:
        yield
    except (MeasurementError, NoStatusError) as exc:
        named = copy.copy(exc)
        named.args = (f"{path}: {exc}",)
        raise named from exc


def _number(x: float | None) -> float | int | None:
    if x is None or not math.isfinite(x):
        return None
    return int(x) if float(x).is_integer() else x


def recording_summary(rec: Any, streams: Any) -> dict[str, Any]:
    """The inspect object of a recording and its rebuilt streams (JSON-ready)."""
    nodes = []
    for n, s in sorted(streams.nodes.items()):
        rpm = s.rpm()
        nodes.append(
            {
                "node": n,
                "frames": s.frames,
                "samples": s.samples,
                "valid_samples": len(s.index),
                "lost_frames": s.lost_frames,
                "invalid_samples": s.invalid_samples,
                "duplicate_frames": s.duplicate_frames,
                "marks": s.marks,
                "lost_marks": s.lost_marks,
                "segments": s.segments,
                "status_frames": s.status_frames,
                "rate_hz": _number(s.rate_hz),
                "scale_um_s2": _number(s.scale_um_s2),
                "flags": list(s.flags),
                "rpm": None if rpm is None else round(rpm, 4),
            }
        )
    meta = {
        k: rec.meta[k]
        for k in ("software", "start_time", "end_time", "source", "complete")
        if k in rec.meta
    }
    return {
        "file": rec.path,
        "frames": streams.frames,
        "nodes": nodes,
        "unknown_frames": streams.unknown_frames,
        "bad_frames": streams.bad_frames,
        "error_frames": streams.error_frames,
        "duration_s": round(streams.duration_s, 6),
        "run": meta,
        "warnings": [w.message for w in (*rec.warnings, *streams.warnings)],
    }
