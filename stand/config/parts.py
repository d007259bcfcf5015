"""What the audit trail keeps of a rotor type's configuration: its tolerance and its
calibration, each as a digest of the parsed tables (a comment or a blank line changes
neither), so that ``stand audit verify --config-dir`` names which of them changed on disk
behind the journal."""

from __future__ import annotations

import hashlib
import json
import tomllib
from typing import Any

CALIBRATION_KEYS = ("M1", "M2", "C1", "C2", "H1", "H2", "reference_angle_deg",
                    "clock_tolerance_pct", "calibrated")  # fmt: skip
"""The ``[stand]`` figures a calibration sets (its name and id are the stand's)."""


def _digest(value: Any) -> str:
    text = json.dumps(value, sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.sha256(text.encode()).hexdigest()


def config_parts(text: str) -> dict[str, str | None]:
    """The digests of a configuration's ``[tolerance]`` and of its calibration (the
    ``[stand]`` figures of :data:`CALIBRATION_KEYS`, ``[sensors]`` and
    ``[calibration]``); None each where the text is not TOML."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError:
        return {"tolerance_sha256": None, "calibration_sha256": None}
    found = data.get("stand")
    stand: dict[str, Any] = found if isinstance(found, dict) else {}
    calibration = {
        "stand": {k: stand.get(k) for k in CALIBRATION_KEYS},
        "sensors": data.get("sensors"),
        "calibration": data.get("calibration"),
    }
    return {"tolerance_sha256": _digest(data.get("tolerance")),
            "calibration_sha256": _digest(calibration)}  # fmt: skip
