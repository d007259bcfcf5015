"""Clients of other implementations, run by the tests: the Node.js programs in
``tests/js`` (Ajv; their npm packages installed by ``npm ci --prefix tests/js``, as
``.ci/run`` does).  Where Node.js or the package is missing, the test is skipped with the
reason naming what to install (the run's end lists it)."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path
from typing import Any

import pytest

JS = Path(__file__).resolve().parents[1] / "js"


def node_with(package: str) -> str:
    """The ``node`` program, where it and ``tests/js``'s ``package`` are installed; else
    the test is skipped naming them."""
    node = shutil.which("node")
    if node is None or not (JS / "node_modules" / package).is_dir():
        pytest.skip(f"Node.js and the npm package {package} are not installed (apt-get install "
                    "nodejs npm; npm ci --prefix tests/js)")  # fmt: skip
    return node


def ajv(schema: Path, documents: list[Any], folder: Path) -> dict[str, Any]:
    """Ajv in strict mode on ``schema``: whether it compiles and, for each document,
    whether it is valid and why not."""
    node = node_with("ajv")
    files = []
    for k, doc in enumerate(documents):
        files.append(folder / f"ajv-{k}.json")
        files[-1].write_text(json.dumps(doc))
    done = subprocess.run([node, str(JS / "ajv_check.js"), str(schema), *map(str, files)],
                          capture_output=True, text=True, timeout=60)  # fmt: skip
    assert done.returncode == 0, done.stderr
    out: dict[str, Any] = json.loads(done.stdout)
    return out
