"""The documentation: README is the front door, the site builds strictly from docs/."""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
GENERATED = {"docs/reference/config.md", "docs/reference/cli.md"}
"""Pages the site's build generates (docs/hooks/reference.py): not files in docs/."""


def test_readme_is_a_front_door_of_at_most_300_lines() -> None:
    lines = (ROOT / "README.md").read_text().splitlines()
    assert len(lines) <= 300, len(lines)


def test_readme_links_lead_somewhere() -> None:
    """Every relative link of README names a file of the repository (or a page the site
    generates)."""
    text = (ROOT / "README.md").read_text()
    for target in re.findall(r"\]\(([^)#]+)\)", text):
        if "://" in target:
            continue
        assert (ROOT / target).exists() or target in GENERATED, target


def test_nothing_points_outside_the_repository() -> None:
    """The model and the protocol are the project's own pages: no README, page, module or
    example names a path above the repository (a clone holds nothing there)."""
    outside = re.compile(r"\.\./shared\b")  # the seeds' and specs' folder beside a checkout
    folders = ("docs", "stand", "drivers", "calib", "examples", "tests")
    files = [ROOT / "README.md", *(p for f in folders for p in (ROOT / f).rglob("*")
                                   if p.suffix in (".md", ".py", ".toml"))]  # fmt: skip
    found = [
        f"{f.relative_to(ROOT)}:{n}"
        for f in files if f.is_file() and f != Path(__file__)
        for n, line in enumerate(f.read_text(errors="replace").splitlines(), 1)
        if outside.search(line)
    ]  # fmt: skip
    assert found == []
    for page in ("stand-model.md", "protocol.md"):
        assert (ROOT / "docs" / page).is_file(), page


@pytest.mark.skipif(shutil.which("mkdocs", path=str(Path(sys.executable).parent)) is None,
                    reason="mkdocs is installed with the test extras")  # fmt: skip
def test_the_site_builds_strictly(tmp_path: Path) -> None:
    """`mkdocs build --strict`: a broken link, a missing page or a stale reference fails; the
    generated references hold every subcommand and every table."""
    mkdocs = Path(sys.executable).parent / "mkdocs"
    done = subprocess.run(
        [str(mkdocs), "build", "--strict", "-d", str(tmp_path / "site")],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
        env={"NO_MKDOCS_2_WARNING": "1", "PATH": "/usr/bin:/bin"},
    )
    assert done.returncode == 0, done.stderr[-3000:]
    cli = (tmp_path / "site" / "reference" / "cli" / "index.html").read_text()
    from stand.cli import SUBCOMMANDS

    for name in SUBCOMMANDS:
        assert f"stand {name}" in cli, name
    config = (tmp_path / "site" / "reference" / "config" / "index.html").read_text()
    for key in ("C_pct", "position_m", "step_pct", "mqtt_url", "grade_mm_s"):
        assert key in config, key
