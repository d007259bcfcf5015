"""The hostile-input matrix: crafted and corrupted run files, logs, configs and
degenerate measurements, each fed to the command that reads it.

Every case must end either in exit 2 with one line on stderr naming the file (a
clean refusal) or, where the input is still usable (a candump log cut mid-line, a
stray frame), in exit 0 with a warning.  Never an internal error, never a crash.
`test_the_matrix_counts` prints the counts that README gives.
"""

from __future__ import annotations

import functools
import os
import shutil
from collections.abc import Callable
from pathlib import Path

import h5py
import numpy as np
import pytest
from hostile import registry

from stand.cli import main
from stand.drivers import read_recording
from stand.drivers.frames import Frames
from stand.drivers.runs.logs import write_log
from stand.drivers.runs.seal import USERBLOCK_BYTES
from stand.drivers.v1.protocol import MARK_BASE, SAMPLES_BASE, STATUS_BASE

ROOT = Path(__file__).resolve().parents[2]
CFG = (ROOT / "examples" / "demo-stand.toml").read_text()

Case = Callable[[Path, Path], tuple[list[str], str]]
"""(work dir, a good demo run) -> (stand's arguments, what the one line must say; "" = ok)."""
CASES, case = registry()


@functools.cache
def _frames(run: str) -> Frames:
    return read_recording(run).frames


def _cfg(d: Path, text: str = CFG) -> str:
    (d / "cfg.toml").write_text(text)
    return str(d / "cfg.toml")


def _run_copy(d: Path, run: Path, edit: Callable[[h5py.File], None], *, unseal: bool = True) -> str:
    """The run edited by HDF5; by default its seal wiped too, as a file written or edited
    by another program carries none: the checks behind the seal are what catch it then."""
    out = d / "run.h5"
    shutil.copy(run, out)
    with h5py.File(out, "a") as f:
        edit(f)
    if unseal:
        with out.open("r+b") as f:
            f.write(bytes(USERBLOCK_BYTES))
    return str(out)


@case("run file: sealed, then one attribute changed by another program")
def _resealed(d: Path, run: Path) -> tuple[list[str], str]:
    edit = lambda f: f.attrs.__setitem__("software", "edited")  # noqa: E731
    return ["solve", _run_copy(d, run, edit, unseal=False)], "SHA-256 sealed"


def _log(d: Path, text: str | bytes, name: str = "run.log") -> str:
    p = d / name
    p.write_bytes(text.encode() if isinstance(text, str) else text)
    return str(p)


def _good_log_text(run: Path) -> str:
    f = _frames(str(run))
    return "".join(
        f"({t:.6f}) vcan0 {cid:03X}#{bytes(row[:dlc]).hex().upper()}\n"
        for t, cid, dlc, row in zip(
            f.t_s[:4000], f.can_id[:4000], f.dlc[:4000], f.data[:4000], strict=True
        )
    )


def _frames_log(d: Path, run: Path, change: Callable[[Frames], Frames]) -> list[str]:
    p = d / "run.log"
    write_log(change(_frames(str(run)).take(np.arange(len(_frames(str(run)))))), p)
    return ["solve", str(p), "--config", _cfg(d)]


# --- run files: attributes and datasets of the wrong kind -------------------------------
for _name, _edit, _says in [
    ("format attribute an int", lambda f: f.attrs.__setitem__("format", 7), "not a run file"),
    ("format_version a word", lambda f: f.attrs.__setitem__("format_version", "x"), "format_version"),
    ("format_version huge", lambda f: f.attrs.__setitem__("format_version", 99), "newer"),
    ("frames_committed a word", lambda f: f.attrs.__setitem__("frames_committed", "x"), "frames_committed"),
    ("frames_committed negative", lambda f: f.attrs.__setitem__("frames_committed", -5), "frames_committed"),
    ("frames_committed an array", lambda f: f.attrs.__setitem__("frames_committed", [1, 2]), "frames_committed"),
    ("config_toml not TOML", lambda f: (f.attrs.__setitem__("config_toml", "[[["), f.attrs.__delitem__("config_sha256")), "config"),
    ("config_toml bytes", lambda f: (f.attrs.__setitem__("config_toml", np.void(b"\x00\xff")), f.attrs.__delitem__("config_sha256")), "config"),
    ("config_sha256 an int", lambda f: f.attrs.__setitem__("config_sha256", 5), "config_sha256"),
    ("no /frames/t_s", lambda f: f["frames"].__delitem__("t_s"), "t_s"),
    ("/frames/data 1-D", lambda f: (f["frames"].__delitem__("data"), f["frames"].create_dataset("data", data=np.zeros(10, np.uint8))), "data"),
    ("/frames/can_id floats", lambda f: (f["frames"].__delitem__("can_id"), f["frames"].create_dataset("can_id", data=np.full(21588, 0.5))), "can_id"),
    ("/frames a dataset", lambda f: (f.__delitem__("frames"), f.create_dataset("frames", data=[1])), "frames"),
    ("/warnings missing", lambda f: f.__delitem__("warnings"), "warnings"),
    ("/warnings/code numbers", lambda f: (f["warnings"].__delitem__("code"), f["warnings"].create_dataset("code", data=[1.0])), "warnings"),
    ("soft link loop", lambda f: (f.__delitem__("frames"), f.__setitem__("frames", h5py.SoftLink("/frames"))), "frames"),
    ("external link", lambda f: (f["frames"].__delitem__("t_s"), f["frames"].__setitem__("t_s", h5py.ExternalLink("/etc/hostname", "/x"))), "external"),
    ("declares 2e8 rows", lambda f: f.attrs.__setitem__("frames_committed", 200_000_000) or [f["frames"][k].resize((200_000_000, *f["frames"][k].shape[1:])) for k in f["frames"]], "declares"),
]:  # fmt: skip

    def _h5_case(d: Path, run: Path, edit=_edit, says=_says) -> tuple[list[str], str]:  # type: ignore[no-untyped-def]
        return ["solve", _run_copy(d, run, edit)], says

    case(f"run file: {_name}")(_h5_case)


@case("run file: frames_committed beyond its rows (cut short)")
def _beyond(d: Path, run: Path) -> tuple[list[str], str]:
    return [
        "inspect",
        _run_copy(d, run, lambda f: f.attrs.__setitem__("frames_committed", 10**6)),
    ], ""


@case("run file: timestamps not numbers")
def _nan_stamps(d: Path, run: Path) -> tuple[list[str], str]:
    def edit(f: h5py.File) -> None:
        t = f["frames/t_s"][:]
        t[3] = np.nan
        f["frames/t_s"][:] = t

    return ["solve", _run_copy(d, run, edit)], "frame 3: its timestamp is nan"


@case("run file: payload width 0")
def _width0(d: Path, run: Path) -> tuple[list[str], str]:
    def edit(f: h5py.File) -> None:
        del f["frames/data"]
        f["frames"].create_dataset("data", shape=(21588, 0), dtype=np.uint8)

    return ["solve", _run_copy(d, run, edit)], "data must be"


@case("bus: a file that allows URL channels for itself")
def _allow(d: Path, run: Path) -> tuple[list[str], str]:
    i = CFG.index("[bus]")
    text = CFG[:i] + '[bus]\ninterface = "slcan"\nchannel = "loop://"\nallow_url_channel = true\n'
    return ["record", "--config", _cfg(d, text), "--out", str(d / "r.h5")], "a file cannot allow"


@case("log: trc with its header only")
def _trc_header(d: Path, run: Path) -> tuple[list[str], str]:
    return ["inspect", _log(d, b";$FILEVERSION=2.1\n;$STARTTIME=0\n", "run.trc")], "run.trc"


@case("run file: external storage of another file's bytes")
def _external(d: Path, run: Path) -> tuple[list[str], str]:
    secret = d / "secret.bin"
    secret.write_bytes(b"secret" * 1000)

    def edit(f: h5py.File) -> None:
        del f["frames/t_s"]
        f["frames"].create_dataset(
            "t_s", shape=(750,), dtype="<f8", external=[(str(secret), 0, 6000)]
        )

    return ["convert", _run_copy(d, run, edit), str(d / "out.log")], "external"


@case("run file: empty")
def _empty(d: Path, run: Path) -> tuple[list[str], str]:
    return ["solve", _log(d, b"", "run.h5")], "not a readable run file"


@case("run file: random bytes")
def _random(d: Path, run: Path) -> tuple[list[str], str]:
    return ["inspect", _log(d, np.random.default_rng(1).bytes(5000), "run.h5")], "run file"


@case("run file: a directory")
def _directory(d: Path, run: Path) -> tuple[list[str], str]:
    (d / "dir.h5").mkdir()
    return ["solve", str(d / "dir.h5")], "is a directory"


@case("run file: a FIFO")
def _fifo(d: Path, run: Path) -> tuple[list[str], str]:
    os.mkfifo(d / "fifo.log")
    return ["solve", str(d / "fifo.log"), "--config", _cfg(d)], "is a FIFO"


@case("run file: a symlink loop")
def _loop(d: Path, run: Path) -> tuple[list[str], str]:
    (d / "a.h5").symlink_to(d / "b.h5")
    (d / "b.h5").symlink_to(d / "a.h5")
    return ["solve", str(d / "a.h5")], "symbolic link"


# --- candump logs ------------------------------------------------------------------------
for _name, _text, _says in [
    ("remote frame of DLC 300", "(0.000000) vcan0 141#R300\n", "run.log:1"),
    ("300 data bytes", "(0.000000) vcan0 141#" + "00" * 300 + "\n", "run.log:1"),
    ("a data field of 5 MB", "(0.000000) vcan0 141#" + "0" * 5_000_000 + "\n", "run.log:1"),
    ("no timestamp", "vcan0 141#A00F640000010000\n", "run.log:1"),
    ("timestamp inf", "(inf) vcan0 141#A00F640000010000\n", "run.log:1"),
    ("id of 40 bits", "(0.000000) vcan0 FFFFFFFFFF#00\n", "run.log:1"),
    ("data not hex", "(0.000000) vcan0 141#ZZ\n", "run.log:1"),
    ("binary garbage", "\x00\x01\x02\xff garbage\n", "run.log:1"),
    ("only comments", "# nothing\n# at all\n", "run.log:1"),
]:  # fmt: skip

    def _log_case(d: Path, run: Path, text=_text, says=_says) -> tuple[list[str], str]:  # type: ignore[no-untyped-def]
        return ["solve", _log(d, text), "--config", _cfg(d)], says

    case(f"candump: {_name}")(_log_case)


@case("candump: cut mid-line (as a killed candump leaves it)")
def _cut(d: Path, run: Path) -> tuple[list[str], str]:
    text = _good_log_text(run)
    return ["inspect", _log(d, text[: len(text) - 7])], ""


@case("candump: cut inside the last timestamp")
def _cut_stamp(d: Path, run: Path) -> tuple[list[str], str]:
    text = _good_log_text(run)
    last = text.rstrip("\n").rfind("\n") + 1
    return ["inspect", _log(d, text[: last + 4])], ""


@case("candump: CRLF line ends")
def _crlf(d: Path, run: Path) -> tuple[list[str], str]:
    return ["inspect", _log(d, _good_log_text(run).replace("\n", "\r\n"))], ""


@case("candump: a 1 MB line with no end")
def _long_line(d: Path, run: Path) -> tuple[list[str], str]:
    return ["inspect", _log(d, "(0.0) vcan0 141#" + "A" * 1_000_000)], "run.log:1"


# --- other python-can logs ---------------------------------------------------------------
for _name, _ext, _bytes, _says in [
    ("asc garbage", ".asc", b"date Sat Nov 22\nbase hex timestamps absolute\nthis is not a frame\n", "run.asc"),
    ("trc garbage", ".trc", b";$FILEVERSION=2.1\nnot a frame at all\n", "run.trc"),
    ("csv malformed", ".csv", b"timestamp,arbitration_id\nx,y\n", "run.csv"),
    ("blf random bytes", ".blf", np.random.default_rng(2).bytes(3000), "run.blf"),
]:  # fmt: skip

    def _other(d: Path, run: Path, ext=_ext, data=_bytes, says=_says) -> tuple[list[str], str]:  # type: ignore[no-untyped-def]
        return ["solve", _log(d, data, "run" + ext), "--config", _cfg(d)], says

    case(f"log: {_name}")(_other)


@case("log: blf one byte short, every frame readable")
def _blf_short(d: Path, run: Path) -> tuple[list[str], str]:
    p = d / "run.blf"
    write_log(_frames(str(run)), p)
    p.write_bytes(p.read_bytes()[:-1])
    return ["inspect", str(p)], ""


# --- inputs too large for this machine: refused before anything is allocated ------------
@case("huge: a sparse 40 GB candump log")
def _sparse(d: Path, run: Path) -> tuple[list[str], str]:
    p = d / "run.log"
    with p.open("wb") as f:
        f.truncate(40 * 10**9)  # sparse: no disk used
    return ["solve", str(p), "--config", _cfg(d)], "GB of memory"


for _name, _old, _new in [
    ("a scene of 1e6 s", "seconds = 8.0", "seconds = 1e6"),
    ("a scene at 1e9 rpm", "rpm = 900.0", "rpm = 1e9"),
]:  # fmt: skip

    def _huge_scene(d: Path, run: Path, old=_old, new=_new) -> tuple[list[str], str]:  # type: ignore[no-untyped-def]
        text = (ROOT / "stand" / "data" / "scenes" / "demo.toml").read_text()
        (d / "scene.toml").write_text(text.replace(old, new))
        return ["simulate", str(d / "scene.toml"), "--out", str(d / "x.h5")], "GB of memory"

    case(f"huge: {_name}")(_huge_scene)


# --- configs -----------------------------------------------------------------------------
for _name, _text, _says in [
    ("TOML nested 5000 deep", "a = " + "[" * 5000 + "]" * 5000 + "\n", "cfg.toml"),
    ("tolerance speed 5e-324", CFG.replace("max_speed_rpm = 1500.0", "max_speed_rpm = 5e-324"), "max_speed_rpm"),
    ("reference angle 1e20", CFG.replace("reference_angle_deg = 0.0", "reference_angle_deg = 1e20"), "reference_angle_deg"),
    ("no [stand]", CFG[CFG.index("[rotor]"):], "[stand]"),
    ("binary", "\x00\xff\xfe", "cfg.toml"),
    ("sensor delay 1e300", CFG + "\n[sensors]\ndelay_s = [1e300, 0]\n", "delay_s"),
    ("a mass of 1e300 kg", CFG.replace("M3 = 60.0", "M3 = 1e300"), "M3"),
]:  # fmt: skip

    def _cfg_case(d: Path, run: Path, text=_text, says=_says) -> tuple[list[str], str]:  # type: ignore[no-untyped-def]
        return ["solve", str(run), "--config", _cfg(d, text)], says

    case(f"config: {_name}")(_cfg_case)


@case("config: a directory")
def _cfg_dir(d: Path, run: Path) -> tuple[list[str], str]:
    (d / "cfg").mkdir()
    return ["solve", str(run), "--config", str(d / "cfg")], "cfg"


@case("bus: kvaser without its driver")
def _kvaser(d: Path, run: Path) -> tuple[list[str], str]:
    return [
        "record",
        "-i",
        "kvaser",
        "-c",
        "0",
        "--out",
        str(d / "r.h5"),
        "--timeout",
        "0.2",
    ], "kvaser"


# --- degenerate measurements -------------------------------------------------------------
def _set(
    rows: Callable[[Frames], np.ndarray], cols: slice, value: int
) -> Callable[[Frames], Frames]:
    def change(f: Frames) -> Frames:
        f.data[rows(f), cols] = value
        return f

    return change


for _name, _change, _says in [
    ("every sequence counter 0", _set(lambda f: f.can_id & 0x7C0 == SAMPLES_BASE, slice(0, 2), 0), "node 1"),
    ("every revolution counter 0", _set(lambda f: f.can_id & 0x7C0 == MARK_BASE, slice(5, 7), 0), "node 1"),
    ("every MARK at one sample", _set(lambda f: f.can_id & 0x7C0 == MARK_BASE, slice(0, 5), 0), "node 1"),
    ("STATUS rate 0", _set(lambda f: f.can_id & 0x7C0 == STATUS_BASE, slice(0, 2), 0), "node 1"),
    ("STATUS version 9", _set(lambda f: f.can_id & 0x7C0 == STATUS_BASE, slice(5, 6), 9), "node 1"),
    ("only error frames", lambda f: Frames(f.t_s, f.can_id, f.dlc, f.data, f.flags | 4), "node 1 sent nothing"),
    ("node ids 0", lambda f: Frames(f.t_s, f.can_id & 0x7F0, f.dlc, f.data, f.flags), "node 1 sent nothing"),
]:  # fmt: skip

    def _degenerate(d: Path, run: Path, change=_change, says=_says) -> tuple[list[str], str]:  # type: ignore[no-untyped-def]
        return _frames_log(d, run, change), says

    case(f"measurement: {_name}")(_degenerate)


for _rpm in (120_000.0, 240_000.0):

    @case(f"measurement: {4000 * 60 / _rpm:g} samples a revolution")
    def _fast(d: Path, run: Path, rpm: float = _rpm) -> tuple[list[str], str]:
        scene = (
            (ROOT / "stand/data/scenes/demo.toml")
            .read_text()
            .replace("rpm = 900.0", f"rpm = {rpm}")
        )
        (d / "fast.toml").write_text(scene.replace("seconds = 8.0", "seconds = 1.0"))
        assert main(["simulate", str(d / "fast.toml"), "--out", str(d / "fast.h5")]) == 0
        return ["solve", str(d / "fast.h5")], "node 1"


OUTCOMES: dict[str, str] = {}


@pytest.mark.parametrize("name", list(CASES))
def test_a_hostile_input_ends_cleanly(
    name: str, demo_run: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv, says = CASES[name](tmp_path, demo_run)
    capsys.readouterr()
    code = main(argv)
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    outcome = (
        "ok"
        if code == 0
        else "clean"
        if code == 2 and err.startswith("stand: error:")
        else "internal"
    )
    OUTCOMES[name] = outcome
    assert "internal error" not in err and "Traceback" not in err, err
    if says:
        assert code == 2 and len(lines) == 1 and lines[0].startswith("stand: error: "), err
        assert says in lines[0], err
    else:
        assert code == 0, err


def test_the_matrix_counts(capsys: pytest.CaptureFixture[str]) -> None:
    """README's count: at least 60 cases (the outcomes are asserted case by case)."""
    assert len(CASES) >= 60, len(CASES)
