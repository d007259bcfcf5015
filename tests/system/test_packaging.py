"""The package installs as it is laid out: drivers/ and calib/ as stand.drivers and
stand.calib (setuptools' package-dir, no symbolic link), every package named in
pyproject.toml, nothing else at site-packages' top."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PROBE = (
    "import importlib.util as u, stand.drivers.family as p, stand.calib.identify as c; "
    "print(p.__file__); print(c.__file__); print(u.find_spec('drivers'), u.find_spec('calib'))"
)


def _probe(cwd: Path, env: dict[str, str] | None = None) -> list[str]:
    done = subprocess.run(
        [sys.executable, "-c", PROBE], capture_output=True, text=True, check=True, cwd=cwd, env=env
    )
    return done.stdout.splitlines()


def test_every_package_is_named_in_pyproject() -> None:
    setup = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    dirs = setup["package-dir"]
    found = {
        ".".join(p.parent.relative_to(ROOT).parts) for p in (ROOT / "stand").rglob("__init__.py")
    } | set(dirs)
    for folder, package in dirs.items():  # drivers/ and calib/ with their wings
        found |= {
            ".".join((folder, *p.parent.relative_to(ROOT / package).parts))
            for p in (ROOT / package).rglob("*/__init__.py")
        }
    assert sorted(setup["packages"]) == sorted(found)
    assert dirs == {"stand.drivers": "drivers", "stand.calib": "calib"}


def test_the_tree_holds_no_symbolic_link() -> None:
    files = subprocess.run(
        ["git", "ls-files", "-s"], capture_output=True, text=True, check=True, cwd=ROOT
    ).stdout
    assert [line for line in files.splitlines() if line.startswith("120000")] == []


def test_the_installed_package_maps_the_folders(tmp_path: Path) -> None:
    """The install in use (README's is editable) reads drivers/ and calib/ as
    stand.drivers and stand.calib, and has no top-level drivers or calib."""
    drivers, calib, specs = _probe(tmp_path)
    assert Path(drivers).parent.name == "drivers" and Path(calib).parent.name == "calib"
    assert specs == "None None"


def test_a_regular_install_maps_them_too(tmp_path: Path) -> None:
    """A regular install (a wheel, as pip builds it) lays the folders out inside stand/."""
    site, src = tmp_path / "site", tmp_path / "src"  # a copy: no build/ left in the tree
    src.mkdir()
    for name in ("pyproject.toml", "README.md"):
        shutil.copy(ROOT / name, src / name)
    for name in ("stand", "drivers", "calib"):
        shutil.copytree(ROOT / name, src / name, ignore=shutil.ignore_patterns("__pycache__"))
    subprocess.run(
        [sys.executable, "-m", "pip", "install", "--quiet", "--no-deps", "--no-compile",
         "--target", str(site), str(src)],
        capture_output=True, check=True,
    )  # fmt: skip
    env = {**os.environ, "PYTHONPATH": str(site)}
    drivers, calib, specs = _probe(tmp_path, env)
    assert Path(drivers).is_relative_to(site / "stand" / "drivers")
    assert Path(calib).is_relative_to(site / "stand" / "calib")
    assert (site / "stand" / "drivers" / "v1" / "sensor_node_v1.dbc").is_file()
    assert (site / "stand" / "drivers" / "scan" / "scan_module.dbc").is_file()
    assert (site / "stand" / "drivers" / "canopen" / "canopen_ai.eds").is_file()
    assert specs == "None None"
