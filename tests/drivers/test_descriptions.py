"""Description files (EDS, DBC) as hard as run files, the recording as the clock, and what
the data reveal about a wrong mapping: each case is one line on stderr and exit 2, or a
run solved with the description it was recorded with, saying so.

The runs are the shipped demo-canopen and demo-scan scenes made 2 s long; the configs are
``examples/canopen-stand.toml`` and ``examples/scan-stand.toml`` with one edit each, their
description file copied beside them (and edited where the case is the file's)."""

from __future__ import annotations

import json
import re
from collections.abc import Callable
from pathlib import Path

import pytest
from protocols import holds_the_demo, short_scene

from stand.cli import main
from stand.drivers.family import MAX_DESCRIPTION_BYTES

ROOT = Path(__file__).resolve().parents[2]
EDS = (ROOT / "drivers" / "canopen" / "canopen_ai.eds").read_text()
DBC = (ROOT / "drivers" / "scan" / "scan_module.dbc").read_text()
CANOPEN = (ROOT / "examples" / "canopen-stand.toml").read_text()
SCAN = (ROOT / "examples" / "scan-stand.toml").read_text()


@pytest.fixture(scope="module")
def canopen_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    d = tmp_path_factory.mktemp("canopen")
    run = d / "c.h5"
    assert main(["simulate", str(short_scene(d, "demo-canopen")), "--out", str(run)]) == 0
    return run


@pytest.fixture(scope="module")
def scan_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    d = tmp_path_factory.mktemp("scan")
    run = d / "s.h5"
    assert main(["simulate", str(short_scene(d, "demo-scan")), "--out", str(run)]) == 0
    return run


def _section_out(text: str, index: str) -> str:
    """The EDS without the sections of one object (``[1018]``, ``[1018sub1]`` ...)."""
    return re.sub(rf"(?ms)^\[{index}(sub\d+)?\]\n.*?(?=^\[|\Z)", "", text)


EDS_CASES: dict[str, tuple[Callable[[str], str], str]] = {
    "no identity 0x1018": (lambda t: _section_out(t, "1018"), "[1018]"),
    "no TPDO1 0x1800": (lambda t: _section_out(t, "1800"), "[1800]"),
    "no section headers": (lambda t: re.sub(r"(?m)^\[.*\]\n", "", t), "cannot read the EDS"),
    "a duplicated section": (
        lambda t: t + "\n[1000]\nParameterName=again\n",
        "cannot read the EDS",
    ),
    "a junk COB-ID": (
        lambda t: t.replace("DefaultValue=$NODEID+0x180", "DefaultValue=junk"),
        "[1800]",
    ),
    "a 0-bit mapping": (
        lambda t: t.replace("DefaultValue=0x71300110", "DefaultValue=0x71300100"),
        "maps no bits",
    ),
    "a mapping past 8 bytes": (
        lambda t: t.replace("DefaultValue=0x71300110", "DefaultValue=0x71300140"),
        "more than a PDO's 8 bytes",
    ),
    "a fixed COB-ID": (
        lambda t: t.replace("DefaultValue=$NODEID+0x180", "DefaultValue=0x181"),
        "both send TPDO1 on 0x181",
    ),
}


DBC_CASES: dict[str, tuple[Callable[[str], str], str]] = {
    "a syntax error": (
        lambda t: t.replace("SG_ ai1 : 16|16@1-", "SG_ ai1 : 16|16@@1-"),
        "cannot read",
    ),
    "overlapping signals": (lambda t: t.replace("ai2 : 32|16", "ai2 : 24|16"), "cannot read"),
    "a big-endian signal": (
        lambda t: t.replace("ai1 : 16|16@1-", "ai1 : 23|16@0-"),
        "little-endian",
    ),
    "a float signal": (lambda t: t + "\nSIG_VALTYPE_ 768 ai2 : 1;\n", "a float signal"),
    "a multiplexed message": (
        lambda t: t.replace(" SG_ counter : 0|16@1+", " SG_ counter M : 0|16@1+").replace(
            " SG_ ai3 : 48|16@1-", " SG_ ai3 m1 : 48|16@1-"
        ),
        "multiplexed",
    ),
    "two messages on one id": (
        lambda t: t.replace(
            'CM_ "A', 'BO_ 768 OTHER: 8 MODULE\n SG_ x : 0|8@1+ (1,0) [0|255] "" HOST\n\nCM_ "A'
        ),
        "0x300",
    ),
}


CASES = [("canopen", c) for c in EDS_CASES] + [("scan", c) for c in DBC_CASES]


@pytest.mark.parametrize(("fam", "case"), CASES)
def test_a_malformed_description_is_one_line(
    fam: str, case: str, canopen_run: Path, scan_run: Path, tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:  # fmt: skip
    """The file named in the line (a DBC's cantools message quotes it whole)."""
    name, text, base, run = (("canopen_ai.eds", EDS, CANOPEN, canopen_run) if fam == "canopen"
                             else ("scan_module.dbc", DBC, SCAN, scan_run))  # fmt: skip
    edit, says = (EDS_CASES if fam == "canopen" else DBC_CASES)[case]
    bad = edit(text)
    assert bad != text, case
    (tmp_path / name).write_text(bad)
    cfg = tmp_path / "c.toml"
    cfg.write_text(base.replace(f"../drivers/{fam}/", ""))
    capsys.readouterr()
    assert main(["solve", str(run), "--config", str(cfg)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and says in err and name in err, err
    assert "internal error" not in err


@pytest.mark.parametrize("name", ["canopen_ai.eds", "scan_module.dbc"])
def test_a_huge_description_is_refused_before_it_is_parsed(
    name: str, canopen_run: Path, scan_run: Path, tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:  # fmt: skip
    """22 MB: refused on its size (the figure is in the message, not a clock)."""
    text = EDS if name.endswith(".eds") else DBC
    filler = ";" if name.endswith(".eds") else "//"
    (tmp_path / name).write_text(text + (filler + " padding" * 20 + "\n") * 130_000)
    assert (tmp_path / name).stat().st_size > 20 * MAX_DESCRIPTION_BYTES
    cfg, run = tmp_path / "c.toml", canopen_run if name.endswith(".eds") else scan_run
    base = CANOPEN if name.endswith(".eds") else SCAN
    cfg.write_text(base.replace("../drivers/canopen/", "").replace("../drivers/scan/", ""))
    capsys.readouterr()
    assert main(["solve", str(run), "--config", str(cfg)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "more than a description file's" in err, err


CLOCKS = [
    ("canopen", "rate_hz = 2000.0", "rate_hz = 1000.0", "2000.0 Hz, the config says 1000 Hz"),
    ("canopen", "rate_hz = 2000.0", "rate_hz = 100000.0", "the config says 100000 Hz"),
    ("canopen", "rate_hz = 2000.0", "rate_hz = 2030.0", "the config says 2030 Hz"),
    ("scan", "rate_hz = 2000.0", "rate_hz = 4000.0", "2000.0 Hz, the config says 4000 Hz"),
]


@pytest.mark.parametrize(("fam", "was", "now", "says"), CLOCKS)
def test_a_clock_the_recording_contradicts_is_refused(
    fam: str, was: str, now: str, says: str, canopen_run: Path, scan_run: Path,
    tmp_path: Path, capsys: pytest.CaptureFixture[str],
) -> None:  # fmt: skip
    """1.5 % off is refused (the tolerance is 1 %), 50 % off and 50 times off too."""
    base, run = (CANOPEN, canopen_run) if fam == "canopen" else (SCAN, scan_run)
    cfg = tmp_path / "c.toml"
    text = base.replace("../drivers/", str(ROOT / "drivers") + "/")
    assert was in text
    cfg.write_text(text.replace(was, now, 1))
    capsys.readouterr()
    assert main(["solve", str(run), "--config", str(cfg)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "the recording's clock runs at" in err and says in err, err


def test_a_clock_within_one_percent_is_solved(
    canopen_run: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """0.5 % off: the configured rate is used (what the tolerance allows is documented)."""
    cfg = tmp_path / "c.toml"
    text = CANOPEN.replace("../drivers/", str(ROOT / "drivers") + "/")
    cfg.write_text(text.replace("rate_hz = 2000.0", "rate_hz = 2010.0", 1))
    capsys.readouterr()
    assert main(["solve", str(canopen_run), "--config", str(cfg)]) == 0


MAPPINGS = [
    ("canopen", ('accel = "0x7130:1"', 'accel = "0x7130:2"'), "reads a pulse train"),
    ("canopen", ('mark = "0x7130:2"', 'mark = "0x7130:1"'), "is no pulse train"),
    ("canopen", ("sync_id = 0x80", "sync_id = 0x181"), "is a frame id of node 1"),
    ("canopen", ("sync_id = 0x80", "sync_id = 0x82"), "is a frame id of node 2"),
    ("scan", ('signal = "ai3"', 'signal = "ai1"'), "is mapped twice"),
]


@pytest.mark.parametrize(("fam", "edit", "says"), MAPPINGS)
def test_a_wrong_mapping_the_data_reveal_is_refused(
    fam: str, edit: tuple[str, str], says: str, canopen_run: Path, scan_run: Path,
    tmp_path: Path, capsys: pytest.CaptureFixture[str],
) -> None:  # fmt: skip
    base, run = (CANOPEN, canopen_run) if fam == "canopen" else (SCAN, scan_run)
    text = base.replace("../drivers/", str(ROOT / "drivers") + "/")
    assert edit[0] in text
    cfg = tmp_path / "c.toml"
    cfg.write_text(text.replace(edit[0], edit[1]))
    capsys.readouterr()
    assert main(["solve", str(run), "--config", str(cfg)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and says in err, err


def test_a_scan_accelerometer_mapped_to_the_mark_input_is_refused(
    scan_run: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The mark's channel and support 1's swapped: both refusals are the data's."""
    text = SCAN.replace("../drivers/", str(ROOT / "drivers") + "/")
    text = text.replace('signal = "ai1"', 'signal = "TMP"').replace(
        'signal = "ai3"', 'signal = "ai1"'
    )
    cfg = tmp_path / "c.toml"
    cfg.write_text(text.replace('signal = "TMP"', 'signal = "ai3"'))
    capsys.readouterr()
    assert main(["solve", str(scan_run), "--config", str(cfg)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "no pulse train" in err, err


@pytest.mark.parametrize("fam", ["canopen", "scan"])
def test_a_run_keeps_its_description_and_is_solved_with_it(
    fam: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Recorded through a description beside its config; the file changed afterwards (a
    mapping that would refuse it) or removed: solved with the copy the run kept, said."""
    name, base = ("canopen_ai.eds", CANOPEN) if fam == "canopen" else ("scan_module.dbc", SCAN)
    text = EDS if fam == "canopen" else DBC
    (tmp_path / name).write_text(text)
    cfg = tmp_path / "c.toml"
    cfg.write_text(base.replace(f"../drivers/{fam}/", ""))
    scene = short_scene(tmp_path, f"demo-{fam}")
    run = tmp_path / "r.h5"
    assert main(["simulate", str(scene), "--config", str(cfg), "--out", str(run)]) == 0
    changed = (text.replace("DefaultValue=$NODEID+0x180", "DefaultValue=0x181") if fam == "canopen"
               else text.replace("ai2 : 32|16", "ai2 : 24|16"))  # fmt: skip
    for now in (changed, None):
        if now is None:
            (tmp_path / name).unlink()
        else:
            (tmp_path / name).write_text(now)
        capsys.readouterr()
        assert main(["solve", str(run), "--json"]) == 0
        out = json.loads(capsys.readouterr().out)
        holds_the_demo(out)
        said = [w for w in out["warnings"] if name in w and "the copy the run kept" in w]
        assert said, out["warnings"]


def test_a_simulated_run_through_a_config_of_another_family_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The demo-scan scene stored with a CANopen config would decode nothing."""
    cfg = tmp_path / "c.toml"
    cfg.write_text(CANOPEN.replace("../drivers/", str(ROOT / "drivers") + "/"))
    capsys.readouterr()
    argv = ["simulate", str(short_scene(tmp_path, "demo-scan")), "--config", str(cfg),
            "--out", str(tmp_path / "r.h5")]  # fmt: skip
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "sends protocol scan frames" in err, err
    assert not (tmp_path / "r.h5").exists()


def test_the_library_log_never_speaks_before_the_product(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """The canopen library's logger has a handler once a set-up runs: Python's last-resort
    handler never prints its "Transfer aborted" line."""
    import logging

    from stand.drivers.canopen.setup import quiet_library_log

    quiet_library_log()
    logging.getLogger("canopen.sdo.client").error("Transfer aborted by client with code 0x05040000")
    assert "Transfer aborted" not in capsys.readouterr().err
