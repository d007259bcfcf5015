"""Clients of other implementations, run by the tests: the Node.js programs in
``tests/js`` (Ajv, node-opcua; their npm packages installed by the suite itself with
``npm ci --prefix tests/js`` where npm is there: ``tests/conftest.py``).  Where Node.js or
a package is missing, the test is skipped with the reason (the run's end lists it)."""

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
    import os

    node = shutil.which("node")
    if node is None:
        pytest.skip("Node.js is not installed (apt-get install nodejs npm): the suite then "
                    "installs its clients itself (npm ci --prefix tests/js)")  # fmt: skip
    if not (JS / "node_modules" / package).is_dir():
        why = os.environ.get("STAND_TESTS_NODE_CLIENTS") or "npm ci --prefix tests/js not run"
        pytest.skip(f"the npm package {package} is not installed: {why}")
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


class NodeUaClient:
    """A node-opcua client of ``tests/js`` (``script``: ``ua_client.js``, ``ua_jobs.js``)
    running against an endpoint with its arguments ``args``: its JSON lines
    read as they come (node-opcua's own log lines, which it writes to stdout too, skipped).

    ``prefix`` runs it inside something else (``ip netns exec NS``)."""

    def __init__(self, endpoint: str, *args: object, prefix: tuple[str, ...] = (),
                 script: str = "ua_client.js") -> None:  # fmt: skip
        import queue
        import threading

        node = node_with("node-opcua-client")
        self.proc = subprocess.Popen(
            [*prefix, node, str(JS / script), endpoint, *map(str, args)],
            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
        )  # fmt: skip
        self.lines: queue.Queue[dict[str, Any]] = queue.Queue()

        def read() -> None:
            assert self.proc.stdout is not None
            for line in self.proc.stdout:
                if line.startswith("{"):
                    self.lines.put(json.loads(line))
            self.lines.put({"error": f"ua_client.js ended ({self.proc.wait()})"})

        threading.Thread(target=read, daemon=True).start()

    def next(self, timeout_s: float = 60.0) -> dict[str, Any]:
        """Its next JSON line (a hang guard of ``timeout_s``, not a speed requirement)."""
        got = self.lines.get(timeout=timeout_s)
        assert "error" not in got, got["error"]
        return got

    def close(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
        self.proc.wait(10)
