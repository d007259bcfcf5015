"""Measure live until the unbalance is precise enough (or a time limit), recording the run."""

from __future__ import annotations

import argparse

from stand.cli import live_args


def add_arguments(p: argparse.ArgumentParser) -> None:
    live_args.add_arguments(p, default_target=f"{live_args.DEFAULT_TARGET_PCT:g}")


def run(args: argparse.Namespace) -> int:
    from stand.cli.common import solve_options
    from stand.cli.format import show
    from stand.result import to_json

    result, _, _ = live_args.measure_live(
        args, "measure", live_args.targets_from(args), solve_options(args)
    )
    show(to_json(result), args.json)
    return 0
