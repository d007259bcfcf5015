"""A calibration renewed from production data (:func:`stand.health.monitor.refit`): whether
the change is significant, the sentence that keeps the calibration when it is not, and
the configuration that carries the refitted values.  ``stand calibrate --from-archive``
and the station's Setup screen both use it."""

from __future__ import annotations

import datetime as dt
from typing import Any

from stand.config import Config
from stand.config.edit import updated_toml
from stand.health.monitor import Refit
from stand.i18n.words import said


def significant(r: Refit) -> bool:
    """Whether a fitted change lies outside its own 95 % interval."""
    return any(abs(f.change) > f.interval95 for f in r.fits)


def fits_text(r: Refit) -> str:
    """``C1 -0.71 +- 2.69 %; C2 ...``: each fitted change and its 95 % interval."""
    return "; ".join(f"{f.name} {100 * f.change:+.2f} +- {100 * f.interval95:.2f} %"
                     for f in r.fits)  # fmt: skip


def kept_line(r: Refit) -> str:
    """``no significant change: keep the calibration (C1 -0.71 +- 2.69 %, ...)``."""
    fits = fits_text(r)
    n = len(r.group.rows) - r.start
    return said("no significant change: keep the calibration ({fits}, 95 %: each change "
                "inside its interval, from {n} corrected rotors)", fits=fits, n=n)  # fmt: skip


def refitted_config(cfg: Config, r: Refit, original: str) -> tuple[list[str], str]:
    """The config with the refitted values (stiffnesses, masses, gains; today's date): its
    header of comments with the fits, and its text (``original``'s comments kept)."""
    stand = cfg.stand.model_copy(
        update={n: getattr(r.after, n) for n in ("C1", "C2", "M1", "M2")}
        | {"calibrated": dt.date.today().isoformat()}
    )
    gain = list(cfg.sensors.gain)
    for f in r.fits:
        if f.name.startswith("gain"):
            gain[int(f.name[-1]) - 1] *= 1 + f.change
    new = cfg.model_copy(
        update={"stand": stand, "sensors": cfg.sensors.model_copy(update={"gain": gain})}
    )
    header = [
        f"# recalibrated from {len(r.group.rows) - r.start} corrected rotors (from datum "
        f"{r.start + 1} of {len(r.group.rows)}):",
        *(f"#   {f.name} {100 * f.change:+.3f} +- {100 * f.interval95:.3f} % (95 %)"
          for f in r.fits),
    ]  # fmt: skip
    return header, "\n".join(header) + "\n" + updated_toml(original, new)


def fits_json(r: Refit) -> list[dict[str, Any]]:
    """Each fitted parameter's change and its 95 % interval [%]."""
    return [{"parameter": f.name, "change_pct": round(100 * f.change, 4),
             "interval95_pct": round(100 * f.interval95, 4)} for f in r.fits]  # fmt: skip
