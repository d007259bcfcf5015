"""What a balancer test's starts must be before they are judged: runs of this rotor with
this balancer, each its own.

A start recorded with another rotor (its stored ``[rotor]``), without balls, or with
another balancer (plane, count, ball mass, race radius) than the config's is refused, as
are two starts that are one file, or one recording (their 1x alike beyond any chance of
noise, :func:`stand.solve.index_runs.same_data`: a copy).  Each refusal is one line naming
the start and what differs.
"""

from __future__ import annotations

import itertools
import tomllib
from pathlib import Path
from typing import Any

from stand.config import Config
from stand.errors import ConfigError, UsageError
from stand.solve.index_runs import same_data

BALANCER_KEYS = ("plane", "balls", "ball_g", "radius_mm")
"""What makes a balancer another one."""


def check_recorded(path: str, meta: dict[str, Any], cfg: Config) -> None:
    """Refuse a start whose stored configuration names another rotor or balancer than
    ``cfg`` (a run without a stored configuration is taken as the config says)."""
    text = str(meta.get("config_toml", "") or "")
    if not text:
        return
    try:
        stored = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"its stored configuration is not TOML ({exc})", source=path) from exc
    ball = stored.get("autobalancer")
    if not isinstance(ball, dict):
        raise UsageError(f"{path}: recorded on a rotor without a ball balancer: not a start of "
                         "this test")  # fmt: skip
    mine = cfg.autobalancer
    assert mine is not None
    for key in BALANCER_KEYS:
        got, want_ = ball.get(key), getattr(mine, key)
        if got != want_:
            raise UsageError(f"{path}: recorded with [autobalancer] {key} = {got!r}, the "
                             f"config has {want_!r}: another balancer")  # fmt: skip
    rotor = stored.get("rotor")
    want = cfg.rotor.model_dump(exclude_none=True, exclude={"keys", "planes"})
    if isinstance(rotor, dict):
        for key, value in want.items():
            got = rotor.get(key)
            if isinstance(value, (int, float)) and isinstance(got, (int, float)):
                same = abs(float(got) - float(value)) <= 1e-9 * max(1.0, abs(float(value)))
            else:
                same = got == value
            if not same and key != "shaft":
                raise UsageError(f"{path}: recorded with [rotor] {key} = {got!r}, the config "
                                 f"has {value!r}: another rotor")  # fmt: skip


def check_distinct(paths: list[str], results: list[Any]) -> None:
    """Refuse two starts that are one file or one recording."""
    for (i, a), (j, b) in itertools.combinations(enumerate(paths), 2):
        if Path(a).resolve() == Path(b).resolve():
            raise UsageError(f"start {j + 1} is start {i + 1} again ({a}): one run per start")
        if same_data(results[i].measurement, results[j].measurement):
            raise UsageError(f"starts {i + 1} and {j + 1} ({a}, {b}) are one recording (their "
                             "1x alike beyond any chance of noise): one run per start")  # fmt: skip
