"""The ``stand`` command line: ``main(argv) -> int``, one-line errors, exit code 2."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from reference import seed_forward
from strategies import DEMO

from stand.cli import SUBCOMMANDS, main
from stand.core import rpm_to_rad_s, unbalance_from_polar

ROOT = Path(__file__).resolve().parents[2]
CFG = str(ROOT / "examples" / "demo-stand.toml")
FWD = [
    "forward",
    "--config",
    CFG,
    "--rpm",
    "900",
    "--unbalance",
    "5000@30",
    "--unbalance",
    "3000@200",
]


def test_forward_json_is_one_object_that_agrees_with_the_seed(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main([*FWD, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["rpm"] == 900.0
    A = seed_forward(
        DEMO, float(rpm_to_rad_s(900.0)), unbalance_from_polar([5e-3, 3e-3], [30, 200])
    )
    for s, a in zip(out["supports"], A, strict=True):
        assert s["amplitude_m_s2"] == pytest.approx(abs(a), rel=1e-12)
        assert s["phase_deg"] == pytest.approx(np.degrees(np.angle(a)) % 360, rel=1e-12)
    assert [s["node"] for s in out["supports"]] == [1, 2]
    assert out["natural_frequencies_hz"] == pytest.approx([5.6468879, 7.7992808], rel=1e-7)
    assert out["warnings"] == []


def test_forward_human_output(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(FWD) == 0
    out = capsys.readouterr().out
    assert "2.39042" in out and "331.26" in out and "5.647 Hz" in out


def test_forward_warns_near_resonance(capsys: pytest.CaptureFixture[str]) -> None:
    argv = [*FWD, "--json"]
    argv[argv.index("900")] = "470"
    assert main(argv) == 0
    captured = capsys.readouterr()
    assert json.loads(captured.out)["warnings"][0]["code"] == "near_resonance"
    assert main(argv[:-1]) == 0
    assert "warning: speed 470.0 rpm" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("change", "needle"),
    [
        (("5000@30", "5000"), "G_MM@DEG"),
        (("5000@30", "x@30"), "G_MM@DEG"),
        (("5000@30", "5000@x"), "G_MM@DEG"),
        (("--unbalance", "--unbalance=-5@30"), ">= 0 g mm"),
        (("900", "0"), "speed > 0"),
        (("900", "nan"), "speed > 0"),
        ((CFG, "/nonexistent.toml"), "/nonexistent.toml: cannot read"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(
    capsys: pytest.CaptureFixture[str], change: tuple[str, str], needle: str
) -> None:
    argv = list(FWD)
    i = argv.index(change[0])
    if change[0] == "--unbalance":  # the value joins the option: --unbalance=-5@30
        argv[i : i + 2] = [change[1]]
    else:
        argv[i] = change[1]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and needle in err and "Traceback" not in err


def test_one_unbalance_only_is_refused(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(FWD[:-2]) == 2
    assert "expected --unbalance twice" in capsys.readouterr().err


def test_missing_argument_and_no_command(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["forward", "--rpm", "900"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--config" in err
    assert main([]) == 2


def test_debug_shows_the_traceback(capsys: pytest.CaptureFixture[str]) -> None:
    argv = [a if a != CFG else "/nonexistent.toml" for a in FWD]
    assert main([*argv, "--debug"]) == 2
    assert "Traceback" in capsys.readouterr().err


def test_the_installed_console_script() -> None:
    exe = shutil.which("stand", path=str(Path(sys.executable).parent))
    assert exe, "the `stand` console script is not installed next to this Python"
    ok = subprocess.run([exe, *FWD, "--json"], capture_output=True, text=True, check=False)
    assert ok.returncode == 0 and json.loads(ok.stdout)["rpm"] == 900.0
    bad = subprocess.run(
        [
            exe,
            "forward",
            "--config",
            "/nope.toml",
            "--rpm",
            "900",
            "--unbalance",
            "1@1",
            "--unbalance",
            "1@1",
        ],
        capture_output=True,
        text=True,
        check=False,
    )
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "Traceback" not in bad.stderr


@pytest.mark.parametrize("command", [None, *sorted(SUBCOMMANDS)])
def test_every_help_page_renders(command: str | None, capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["--help"] if command is None else [command, "--help"]
    with pytest.raises(SystemExit) as e:
        main(argv)
    assert e.value.code == 0 and "usage: stand" in capsys.readouterr().out


def test_each_subcommand_module_is_imported_only_when_chosen() -> None:
    """``stand --version`` and ``stand --help`` import no subcommand, numpy or scipy."""
    code = (
        "import sys; from stand.cli import main\n"
        "try:\n    main(['--help'])\nexcept SystemExit:\n    pass\n"
        "print(sorted(m for m in sys.modules if m.startswith('stand.cli.') "
        "or m in ('numpy', 'scipy', 'h5py', 'can')))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip().splitlines()[-1] == "[]"


def test_help_pages_name_every_subcommand(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        main(["--help"])
    text = capsys.readouterr().out
    assert all(name in text for name in SUBCOMMANDS)
    assert sorted(
        p.stem for p in (ROOT / "stand" / "cli").glob("*.py") if p.stem in SUBCOMMANDS
    ) == sorted(SUBCOMMANDS)


@pytest.mark.parametrize("rpm", ["1e300", "2e6"])
def test_a_meaningless_speed_is_refused_before_any_arithmetic(
    rpm: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """1e300 rpm used to overflow the model (numpy warnings, then NaN): now refused at once."""
    import warnings

    argv = ["forward", "--config", CFG, "--rpm", rpm]
    argv += ["--unbalance", "5000@30", "--unbalance", "3000@200", "--json"]
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # any overflow warning would fail the test
        assert main(argv) == 2
    out, err = capsys.readouterr()
    assert out == "" and f"--rpm: {rpm} rpm is beyond any balancing stand" in err
    argv[4] = "1e6"  # its twin: the largest speed taken gives finite numbers
    assert main(argv) == 0
    json.loads(capsys.readouterr().out, parse_constant=lambda c: pytest.fail(c))


def test_finite_names_the_first_bad_key_and_passes_good_objects() -> None:
    from stand.errors import ModelError
    from stand.solve.result import finite

    good = {"a": [1.0, {"b": 2}], "c": None, "d": "x"}
    assert finite(good) is good
    with pytest.raises(ModelError, match=r"a\[1\]\.b \(inf\)"):
        finite({"a": [1.0, {"b": float("inf")}]})


def test_an_interrupt_inside_a_finalizer_comes_again_later(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """CPython swallows an exception raised inside a weakref callback or a ``__del__``
    ("Exception ignored"): a Ctrl-C landing there would be lost and ``stand reprocess``
    would run on to its end.  The program's handler sees where it landed and delivers it
    again a moment later (SIGALRM) instead."""
    import gc
    import signal
    import sys
    import weakref

    from stand.cli import _interrupt, swallowed_there

    class Thing:
        pass

    seen: list[bool] = []
    thing = Thing()
    weakref.finalize(thing, lambda: seen.append(swallowed_there(sys._getframe())))
    del thing
    gc.collect()
    assert seen == [True]
    assert not swallowed_there(sys._getframe())
    import stand.cli

    # the timer's delay made long, so that it is still running when read, however late this
    # thread runs on a loaded machine (the shipped 5 ms would have expired: read as 0)
    monkeypatch.setattr(stand.cli, "INTERRUPT_AGAIN_S", 60.0)
    before = signal.signal(signal.SIGALRM, signal.SIG_IGN)
    try:
        with pytest.raises(KeyboardInterrupt):
            _interrupt(signal.SIGINT, sys._getframe())
        fired: list[float] = []

        def inside() -> None:  # no exception: deferred, the timer set
            _interrupt(signal.SIGINT, sys._getframe())
            fired.append(signal.getitimer(signal.ITIMER_REAL)[0])

        thing = Thing()
        weakref.finalize(thing, inside)
        del thing
        gc.collect()
        assert len(fired) == 1 and 0 < fired[0] <= 60.0
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, before)
