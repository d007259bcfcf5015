"""Safe writes: no output replaces an existing file without --force, an input, or a
special file; two writers of one name: one wins, the other is told; a full disk (or a
file-size limit) ends a command with one line and exit 2, keeping what reached the disk."""

from __future__ import annotations

import os
import resource
import shutil
import subprocess
import sys
from pathlib import Path

import h5py
import pytest

from stand.cli import main

ROOT = Path(__file__).resolve().parents[2]
CFG = str(ROOT / "examples" / "demo-stand.toml")


def _stand(*args: str, limit_bytes: int | None = None, cwd: Path | None = None) -> tuple[int, str]:
    """``stand ARGS`` in a fresh process (optionally under a file-size limit): exit, stderr."""

    def limit() -> None:
        if limit_bytes is not None:
            resource.setrlimit(resource.RLIMIT_FSIZE, (limit_bytes, limit_bytes))

    proc = subprocess.run(
        [sys.executable, "-m", "stand.cli", *args],
        capture_output=True,
        text=True,
        preexec_fn=limit,
        cwd=cwd,
        timeout=120,
        check=False,
    )
    return proc.returncode, proc.stderr


def _writers(demo_run: Path, d: Path) -> list[tuple[list[str], Path]]:
    """Every command that writes a whole file: its arguments and the file it writes."""
    return [
        (["report", str(demo_run), "-o", str(d / "r.html")], d / "r.html"),
        (["solve", str(demo_run), "--summary", str(d / "s.csv")], d / "s.csv"),
        (["simulate", "demo", "--out", str(d / "s.h5")], d / "s.h5"),
        (["convert", str(demo_run), str(d / "c.log")], d / "c.log"),
    ]


@pytest.mark.parametrize("k", range(4))
def test_an_existing_output_is_kept_unless_forced(
    demo_run: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], k: int
) -> None:
    """`report -o`, `solve --summary` ... replaced existing files silently."""
    argv, target = _writers(demo_run, tmp_path)[k]
    target.write_text("precious")
    assert main(argv) == 2
    assert "exists already (use --force to replace it)" in capsys.readouterr().err
    assert target.read_text() == "precious"
    assert main([*argv, "--force"]) == 0
    assert target.read_bytes() != b"precious"
    assert not [p for p in tmp_path.iterdir() if ".part" in p.name]  # no temporary left


def test_a_run_is_never_its_own_report(
    demo_run: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`stand report RUN.h5 -o RUN.h5` replaced the only record with HTML."""
    run = tmp_path / "run.h5"
    shutil.copy(demo_run, run)
    before = run.read_bytes()
    for force in ([], ["--force"]):
        assert main(["report", str(run), "-o", str(run), *force]) == 2
        assert "is also an input" in capsys.readouterr().err
    assert run.read_bytes() == before
    assert main(["convert", str(run), str(run), "--force"]) == 2
    assert "is also an input" in capsys.readouterr().err


@pytest.mark.parametrize("kind", ["fifo", "symlink", "directory"])
def test_a_special_file_is_never_replaced(
    demo_run: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], kind: str
) -> None:
    out = tmp_path / "out.html"
    if kind == "fifo":
        os.mkfifo(out)
    elif kind == "symlink":
        (tmp_path / "elsewhere.html").write_text("kept")
        out.symlink_to(tmp_path / "elsewhere.html")
    else:
        out.mkdir()
    assert main(["report", str(demo_run), "-o", str(out), "--force"]) == 2
    err = capsys.readouterr().err
    assert {"fifo": "is a FIFO", "symlink": "symbolic link", "directory": "a directory"}[
        kind
    ] in err
    assert out.is_fifo() if kind == "fifo" else True
    if kind == "symlink":
        assert out.is_symlink() and (tmp_path / "elsewhere.html").read_text() == "kept"


def test_two_writers_of_one_name_one_wins_the_other_is_told(tmp_path: Path) -> None:
    """Two `simulate --out same.h5` started together both said "wrote" (one .part name)."""
    out = tmp_path / "same.h5"
    argv = [sys.executable, "-m", "stand.cli", "simulate", "demo", "--out", str(out)]
    procs = [subprocess.Popen(argv, stderr=subprocess.PIPE, text=True) for _ in range(2)]
    errs = [p.communicate(timeout=60)[1] for p in procs]  # waits, reads, closes the pipe
    results = [(p.returncode, err) for p, err in zip(procs, errs, strict=True)]
    assert sorted(code for code, _ in results) == [0, 2]
    loser = next(err for code, err in results if code == 2)
    assert "exists already" in loser and "Traceback" not in loser
    with h5py.File(out) as f:
        assert f.attrs["complete"] and f.attrs["frames_committed"] == 21588
    assert [p.name for p in tmp_path.iterdir()] == ["same.h5"]


@pytest.mark.parametrize(
    "argv",
    [
        ["simulate", "demo", "--out", "{d}/a.h5"],
        ["convert", "{run}", "{d}/a.log"],
        ["convert", "{run}", "{d}/a.h5"],
        ["report", "{run}", "-o", "{d}/a.html"],
        ["balance", "--scene", "demo", "--out", "{d}/b.h5"],
        ["record", "-i", "virtual", "-c", "ulimit-test", "--out", "{d}/r.h5", "--timeout", "0.3"],
    ],
)
def test_a_file_size_limit_ends_cleanly_and_leaves_nothing_half_written(
    demo_run: Path, tmp_path: Path, argv: list[str]
) -> None:
    """Under `ulimit -f 200` (KiB): simulate and balance used to end in a segmentation
    fault and an unreadable file."""
    args = [a.format(d=tmp_path, run=demo_run) for a in argv]
    code, err = _stand(*args, limit_bytes=200 * 1024)
    lines = err.strip().splitlines()
    assert code == 2, err
    assert lines[-1].startswith("stand: error:") and "file-size limit" in lines[-1]
    assert "Traceback" not in err and "RuntimeError" not in err
    assert list(tmp_path.iterdir()) == []  # nothing half written, no temporary left


def _small_disk(tmp_path: Path, kib: int) -> Path:
    where = tmp_path / "disk"
    where.mkdir()
    done = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", f"size={kib}k", "tmpfs", str(where)],
        capture_output=True,
        check=False,
    )
    if done.returncode != 0:
        pytest.skip(f"cannot mount a small tmpfs here: {done.stderr.decode().strip()}")
    return where


@pytest.mark.realtime
def test_a_full_disk_while_recording_keeps_what_reached_it(tmp_path: Path) -> None:
    """`stand measure` onto a 1.2 MB disk: it stops with one line when the next flush has
    no room; the run file opens and holds exactly the frames it says it holds."""
    disk = _small_disk(tmp_path, 1200)
    try:
        out = disk / "m.h5"
        code, err = _stand(
            "measure", "--scene", "demo", "--out", str(out), "--target-g-mm", "0.01",
            "--max-seconds", "20", "--quiet",
        )  # fmt: skip
        assert code == 2, err
        assert "the disk is full" in err.strip().splitlines()[-1] and "Traceback" not in err
        with h5py.File(out) as f:
            n = int(f.attrs["frames_committed"])
            assert all(f["frames"][k].shape[0] >= n for k in ("t_s", "can_id", "data"))
        code, err = _stand("inspect", str(out))
        assert code in (0, 2) and "Traceback" not in err
        assert not [p for p in disk.iterdir() if ".part" in p.name]
    finally:
        subprocess.run(["umount", str(disk)], check=False)


def test_a_full_disk_for_a_whole_file_leaves_nothing(demo_run: Path, tmp_path: Path) -> None:
    disk = _small_disk(tmp_path, 300)
    try:
        for args in (["simulate", "demo", "--out", str(disk / "a.h5")],
                     ["convert", str(demo_run), str(disk / "a.blf")]):  # fmt: skip
            code, err = _stand(*args)
            assert code == 2 and "the disk is full" in err and "Traceback" not in err, err
            assert list(disk.iterdir()) == []
    finally:
        subprocess.run(["umount", str(disk)], check=False)
