"""An archived run as OPC 40001-101's ``ResultDataType``: its meta data (ResultId, times,
part, job, evaluation) and, as its content, the stand's ``BalancingResultDataType`` (per
plane the initial and residual unbalance and angle, the 95 % radius, the permissible, the
pass and a check's URR).

The ResultId is the archive's run id as text: the same id the MQTT payload carries as
``result_id`` and ``stand history --json`` as ``id``.  The stand's machine evaluations
(ISO 21940-21) are results too, ``E`` and the evaluation's archive id (``E12``), their
content the stand's ``MachineEvaluationDataType``.  The data types must have been
loaded into asyncua (:mod:`stand.plant.opcua.model`, ``load_data_type_definitions``).
"""

from __future__ import annotations

import datetime as dt
from typing import Any

from stand.plant.opcua.model import EVALUATIONS
from stand.plant.qdas.evaluations import FIGURES, PART

RESULT_STATE_COMPLETED = 1
"""ResultMetaDataType.ResultState: processing was carried out completely."""
EVALUATION = {"pass": EVALUATIONS.index("OK"), "fail": EVALUATIONS.index("NotOK"),
              "undecided": EVALUATIONS.index("NotDecidable"),
              "none": EVALUATIONS.index("Undefined")}  # fmt: skip
"""The archive's verdict as ResultEvaluationEnum (``undecided``: ISO 21940-14's interval
straddles the limit; ``none``: no tolerance to judge by)."""
MACHINE_EVALUATION = {"pass": EVALUATIONS.index("OK"), "fail": EVALUATIONS.index("NotOK"),
                      "not judged": EVALUATIONS.index("NotDecidable")}  # fmt: skip
"""A machine evaluation's verdict as ResultEvaluationEnum (not judged: a test short of its
runs could not be decided)."""
EVALUATION_PREFIX = "E"
"""ResultIds of machine evaluations: ``E`` and the evaluation's archive id."""


def _time(iso: str | None) -> dt.datetime | None:
    """An archived ISO 8601 time as an aware UTC datetime (None for none)."""
    if not iso:
        return None
    when = dt.datetime.fromisoformat(iso)
    return (when if when.tzinfo else when.replace(tzinfo=dt.UTC)).astimezone(dt.UTC)


def _plane(ua: Any, p: dict[str, Any], before: dict[str, Any]) -> Any:
    return ua.BalancingPlaneDataType(
        Plane=int(p["plane"]),
        InitialUnbalance_g_mm=float(before["unbalance_g_mm"]),
        InitialAngle_deg=float(before["angle_deg"]),
        ResidualUnbalance_g_mm=float(p["unbalance_g_mm"]),
        ResidualAngle_deg=float(p["angle_deg"]),
        Uncertainty95_g_mm=float(p["uncertainty_g_mm"]),
        Permissible_g_mm=None if p["permissible_g_mm"] is None else float(p["permissible_g_mm"]),
        Pass=None if p["pass"] is None else bool(p["pass"]),
        Urr=None if p["urr"] is None else float(p["urr"]),
    )


def result_data(run: dict[str, Any]) -> Any:
    """The ``ResultDataType`` of an archived run as :func:`stand.archive.query.latest`
    gives it."""
    from asyncua import ua

    prov = run["result"].get("provenance", {})
    start = _time(run["start_time"])
    duration = prov.get("duration_s")
    times = None
    if start is not None and isinstance(duration, (int, float)):
        times = ua.ProcessingTimesDataType(
            StartTime=start, EndTime=start + dt.timedelta(seconds=float(duration)),
            AcquisitionDuration=float(duration) * 1e3,
        )  # fmt: skip
    simulated = prov.get("simulated")
    meta = ua.ResultMetaDataType(
        ResultId=str(run["id"]),
        IsSimulated=simulated if isinstance(simulated, bool) else None,
        ResultState=RESULT_STATE_COMPLETED,
        PartId=run["serial"] or None,
        ProductId=run["rotor_type"] or None,
        JobId=run.get("job") or run["order"] or None,  # the MES's job order, else the order
        CreationTime=start,
        ProcessingTimes=times,
        ResultEvaluation=ua.ResultEvaluationEnum(EVALUATION[run["verdict"]]),
        ResultEvaluationDetails=ua.LocalizedText(f"verdict {run['verdict']}"),
    )
    content = ua.BalancingResultDataType(
        RotorType=run["rotor_type"] or "",
        Verdict=run["verdict"],
        RunFileSha256=run["file_sha256"],
        ChecksResultId=None if run["checks_run"] is None else str(run["checks_run"]),
        Planes=[_plane(ua, p, q) for p, q in zip(run["planes"], run["initial"], strict=True)],
    )
    return ua.ResultDataType(
        ResultMetaData=meta,
        ResultContent=[ua.Variant(content, ua.VariantType.ExtensionObject)],
    )


def evaluation_data(e: dict[str, Any]) -> Any:
    """The ``ResultDataType`` of an archived machine evaluation as
    :func:`stand.archive.evaluations.evaluation_by_id` gives it."""
    from asyncua import ua

    when = _time(e["performed_at"])
    figures = {f.field: f.value(e["result"]) for f in FIGURES}
    meta = ua.ResultMetaDataType(
        ResultId=f"{EVALUATION_PREFIX}{e['id']}",
        IsSimulated=bool(e["simulated"]),
        ResultState=RESULT_STATE_COMPLETED,
        ProductId=PART,
        CreationTime=when,
        ResultEvaluation=ua.ResultEvaluationEnum(MACHINE_EVALUATION[e["verdict"]]),
        ResultEvaluationDetails=ua.LocalizedText(
            "; ".join([f"machine evaluation {e['verdict']}",
                       *(e["result"].get("not_judged_because") or [])])),
    )  # fmt: skip
    content = ua.MachineEvaluationDataType(
        Standard=PART, Verdict=e["verdict"], Due=e["due"],
        **{k: None if v is None else float(v) for k, v in figures.items()},
    )  # fmt: skip
    return ua.ResultDataType(
        ResultMetaData=meta,
        ResultContent=[ua.Variant(content, ua.VariantType.ExtensionObject)],
    )
