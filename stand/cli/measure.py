"""Measure live until the unbalance is precise enough (or a time limit), recording the run."""

from __future__ import annotations

import argparse

from stand.cli.common import (
    DEFAULT_TARGET_PCT,
    add_live_measure_arguments,
    solve_options,
    targets_from,
)
from stand.cli.format import show
from stand.cli.panel import archive_live, measure_live_from_args
from stand.i18n.language import language
from stand.solve import to_json


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_live_measure_arguments(p, default_target=f"{DEFAULT_TARGET_PCT:g}")


def run(args: argparse.Namespace) -> int:

    result, cfg, _ = measure_live_from_args(
        args, "measure", targets_from(args), solve_options(args)
    )
    show(to_json(result), args.json, language(args.lang))
    archive_live(args, result, cfg)
    return 0
