"""HTML to PDF with a headless Chromium: the certificate as a document to hand over.

Chromium prints the page with its print layout (A4, ``@media print``), as a
browser would; nothing is fetched (the page embeds everything, and the
browser starts with its network features off).  The PDF is written safely
(:func:`stand.files.output`).  ``STAND_CHROMIUM`` names the browser
when it is not ``chromium`` (or ``chromium-browser``, ``google-chrome``) on
the PATH.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
from collections.abc import Iterable
from pathlib import Path

from stand.errors import UsageError, WriteError
from stand.files import output

BROWSERS = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")
FLAGS = (
    "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run", "--disable-sync",
    "--disable-background-networking", "--disable-component-update", "--disable-extensions",
    "--no-pdf-header-footer",
)  # fmt: skip
TIMEOUT_S = 120.0


def browser() -> str:
    """The Chromium to print with (UsageError naming what to install when there is none)."""
    named = os.environ.get("STAND_CHROMIUM")
    if named:
        return named
    for name in BROWSERS:
        found = shutil.which(name)
        if found:
            return found
    raise UsageError(
        "--pdf prints with Chromium, which is not installed (Debian: apt-get install "
        "chromium; or set STAND_CHROMIUM to the browser)"
    )


def write_pdf(
    html_text: str, path: str | Path, *, force: bool = False, inputs: Iterable[str] = ()
) -> None:
    """Print ``html_text`` to the PDF ``path`` (safely: complete or not at all)."""

    exe = browser()
    with (
        tempfile.TemporaryDirectory(prefix="stand-pdf-") as work,
        output(path, force=force, inputs=inputs) as tmp,
    ):
        page = Path(work) / "certificate.html"
        page.write_text(html_text, encoding="utf-8")
        cmd = [exe, *FLAGS, f"--user-data-dir={work}/profile", f"--print-to-pdf={tmp}",
               page.as_uri()]  # fmt: skip
        try:
            done = subprocess.run(cmd, capture_output=True, text=True, timeout=TIMEOUT_S)
        except (OSError, subprocess.TimeoutExpired) as exc:
            raise WriteError(f"Chromium could not print it ({exc})", path=str(path)) from exc
        ok = tmp.exists() and tmp.stat().st_size > 0 and tmp.read_bytes()[:5] == b"%PDF-"
        if done.returncode != 0 or not ok:
            why = (done.stderr.strip().splitlines() or ["no PDF written"])[-1][:200]
            raise WriteError(f"Chromium could not print it ({why})", path=str(path))
