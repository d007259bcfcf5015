"""Write the balancing certificate of a run: a self-contained HTML file, and/or a PDF."""

from __future__ import annotations

import argparse
from pathlib import Path

from stand.actions import release_certificate, signature_path
from stand.archive import file_digest, url_for
from stand.cli.common import (
    actor_of,
    add_across_speeds_arguments,
    add_actor_arguments,
    add_archive_argument,
    add_force_argument,
    add_measure_arguments,
    add_reason_argument,
    add_uncertainty_arguments,
    solve_options,
    write_text_output,
)
from stand.config import load_config
from stand.errors import UsageError
from stand.field import balance_speeds, speeds_json
from stand.files import check_output
from stand.i18n.language import LANGUAGES, language
from stand.report import render, render_speeds, write_pdf
from stand.solve import solve_check, solve_recording


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "run",
        nargs="+",
        metavar="RUN",
        help="run file (.h5) or python-can log; several with --across-speeds",
    )
    p.add_argument("-o", "--out", metavar="REPORT.html", help="the HTML certificate to write")
    p.add_argument("--pdf", metavar="REPORT.pdf", help="the PDF to write (printed by Chromium)")
    p.add_argument(
        "--config",
        metavar="CFG",
        help="stand configuration (default: the one stored in the run file)",
    )
    p.add_argument(
        "--check",
        metavar="PREVIOUS_RUN",
        help="RUN is a check run: show the unbalance before the correction and the URR",
    )
    p.add_argument(
        "--check-any",
        action="store_true",
        help="--check against a run of another rotor, stand or speed anyway",
    )
    add_across_speeds_arguments(p)
    add_measure_arguments(p)
    add_uncertainty_arguments(p)
    add_force_argument(p, "the outputs")
    p.add_argument(
        "--lang",
        choices=tuple(LANGUAGES),
        default="en",
        help="the certificate's language: the customer's (default: en)",
    )
    g = p.add_argument_group("releasing the certificate (an electronic signature)")
    g.add_argument(
        "--release",
        action="store_true",
        help="release it (--as NAME once the archive has accounts: a setter or above): its "
        "signature block names who, when, the run file's SHA-256 and the stand key; the "
        "file kept (the PDF if one is written) is signed (FILE.sig beside it) and its "
        "SHA-256 journaled (stand audit check FILE)",
    )
    add_archive_argument(g)
    add_reason_argument(g)
    add_actor_arguments(g)


def run(args: argparse.Namespace) -> int:

    if not args.out and not args.pdf:
        raise UsageError("stand report: give -o REPORT.html, --pdf REPORT.pdf, or both")
    if len(args.run) > 1 and not args.across_speeds:
        raise UsageError("stand report: one run, or several with --across-speeds")
    inputs = [i for i in (*args.run, args.config, args.check) if i]
    for out in (args.out, args.pdf):
        if out:
            check_output(out, force=args.force, inputs=inputs)  # before the work
    if args.across_speeds:
        if args.check:
            raise UsageError("stand report: --check is for one run, not --across-speeds")
        speeds = balance_speeds(
            args.run,
            args.config,
            method=args.method,
            max_mass_g=args.max_mass_g,
            slow_roll=args.slow_roll,
        )
        return _write(args, render_speeds(speeds_json(speeds)), inputs)
    options = solve_options(args, traces=True)
    run = args.run[0]
    if args.check:
        result = solve_check(run, args.check, args.config, options, strict=not args.check_any)
    else:
        result = solve_recording(run, args.config, options)
    words = language(args.lang)
    page = render(result, words)
    if not args.release:
        return _write(args, page, inputs)
    cfg = load_config(args.config)[0] if args.config else None
    url = url_for(args.archive, cfg)
    actor = actor_of(args, url)
    targets = [Path(p) for p in (args.out, args.pdf) if p]  # the customer keeps the last
    kept, entry = release_certificate(url, actor, page, file_digest(run),
                          f"certificate of {Path(run).name} ({targets[-1].name})", targets,
                          lambda text: _write(args, text, inputs), words=words,
                          reason=args.reason)  # fmt: skip
    print(f"released by {actor.name}: audit entry {entry}; its signature {signature_path(kept)}")
    return 0


def _write(args: argparse.Namespace, page: str, inputs: list[str]) -> int:
    """The page as HTML (-o) and as PDF (--pdf)."""
    if args.out:
        write_text_output(args.out, page, force=args.force, inputs=inputs)
        print(f"wrote {args.out}")
    if args.pdf:
        write_pdf(page, args.pdf, force=args.force, inputs=inputs)
        print(f"wrote {args.pdf}")
    return 0
