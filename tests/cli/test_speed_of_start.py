"""``stand --help`` and ``stand --version`` import no subcommand, and solving imports only what
it needs (their time is a benchmark: ``tests/bench/bench_start.py``)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest


def test_the_program_leaves_its_objects_out_of_the_last_collection(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """``stand`` (the console script) is ``main`` and then every object frozen, so that
    the interpreter's collection at exit does not visit them; ``main`` alone (as the
    tests call it) freezes nothing."""
    import gc

    from stand.cli import entry, main

    monkeypatch.setattr(sys, "argv", ["stand", "solve", "missing.h5", "--json"])
    assert main() == 2 and gc.get_freeze_count() == 0
    try:
        assert entry() == 2  # bad input: exit 2, as from main
        assert gc.get_freeze_count() > 0
    finally:
        gc.unfreeze()
    assert "missing.h5" in capsys.readouterr().err


LEFT_OUT = {"numpy.ma", "scipy.integrate", "matplotlib", "sqlalchemy"}
"""What solving a rigid rotor's run does without: numpy's masked arrays (which numpy's
``median`` and ``unique`` import, 8 ms: :func:`stand.core.dsp.median` is ours), the
integrators, the plots and the archive's database layer.  The bending-rotor models and the
stored matrix's schema load with the solve (about 13 ms; deferring them bought under 5 %
of the 600 s figure, so they are imported at the top like any module)."""


@pytest.mark.parametrize("suffix", [".h5", ".log"])
def test_solving_a_rigid_rotor_imports_only_what_it_needs(
    demo_run: Path, tmp_path: Path, suffix: str
) -> None:
    from stand.drivers import read_recording
    from stand.drivers.runs.logs import write_log

    argv = ["solve", str(demo_run), "--json"]
    if suffix == ".log":
        rec = read_recording(demo_run)
        write_log(rec.frames, tmp_path / "run.log")
        (tmp_path / "cfg.toml").write_text(str(rec.meta["config_toml"]))
        argv = [*argv[:1], str(tmp_path / "run.log"), "--json"]
        argv += ["--config", str(tmp_path / "cfg.toml")]
    code = (
        "import sys, io, contextlib\n"
        "from stand.cli import main\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        f"    assert main({argv!r}) == 0\n"
        "print(' '.join(sorted(sys.modules)))\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    loaded = set(done.stdout.split())
    assert "stand.measuring.measure" in loaded  # it did measure
    assert not loaded & LEFT_OUT, sorted(loaded & LEFT_OUT)


def test_balance_leaves_the_archive_and_the_report_until_it_measures() -> None:
    """``stand balance`` loads without SQLAlchemy, Alembic or matplotlib: they come on a
    thread while the physics runs (:func:`stand.process.warm_imports`), after the answer's
    own modules."""
    code = (
        "import sys; import stand.cli.balance; "
        "print(sorted(m for m in ('sqlalchemy', 'alembic', 'matplotlib') if m in sys.modules))"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "[]", done.stdout
