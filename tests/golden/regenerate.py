"""Regenerate the golden texts on purpose: ``python tests/golden/regenerate.py``.

Run it only when a change to the operator's output is intended; review the
diff of tests/golden/ before committing it.  ``balance-demo.json`` is a
balance result recorded once (a live run is not repeatable to the digit);
the test pushes it through the same formatter the command uses.
"""

from __future__ import annotations

import contextlib
import io
import json
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
CASES = {
    "solve-demo.txt": ["solve", "{run}"],
    "solve-demo-taper-uncertainty.txt": ["solve", "{run}", "--taper", "--uncertainty"],
}


def solve_texts(run: Path) -> dict[str, str]:
    """The text of each solve case on ``run`` (stdout only)."""
    from stand.cli import main

    out = {}
    for name, argv in CASES.items():
        buf = io.StringIO()
        with contextlib.redirect_stdout(buf), contextlib.redirect_stderr(io.StringIO()):
            assert main([a.format(run=run) for a in argv]) == 0
        out[name] = buf.getvalue()
    return out


def balance_text(obj: dict) -> str:  # type: ignore[type-arg]
    """The text ``stand balance`` prints for a result object."""
    from stand.cli.format import print_result

    buf = io.StringIO()
    with contextlib.redirect_stdout(buf), contextlib.redirect_stderr(io.StringIO()):
        print_result(obj)
    return buf.getvalue()


def main() -> int:
    from stand.cli import main as stand

    with tempfile.TemporaryDirectory() as tmp:
        run = Path(tmp) / "demo.h5"
        assert stand(["simulate", "demo", "--out", str(run)]) == 0
        for name, text in solve_texts(run).items():
            (HERE / name).write_text(text)
        if "--balance" in sys.argv:  # record a new balance result (a live run, about 4 s)
            buf = io.StringIO()
            with contextlib.redirect_stdout(buf):
                argv = ["balance", "--scene", "demo", "--out", str(Path(tmp) / "b.h5"), "--json"]
                assert stand([*argv, "--quiet"]) == 0
            obj = json.loads(buf.getvalue())
            obj["run_file"] = obj["provenance"]["run_file"] = "run-20261122-100000.h5"
            obj["report"] = "run-20261122-100000.html"
            (HERE / "balance-demo.json").write_text(json.dumps(obj, indent=1) + "\n")
    obj = json.loads((HERE / "balance-demo.json").read_text())
    (HERE / "balance-demo.txt").write_text(balance_text(obj))
    print(f"wrote {len(CASES) + 1} golden texts in {HERE}")
    return 0


if __name__ == "__main__":
    sys.path.insert(0, str(HERE.parent / "helpers"))
    raise SystemExit(main())
