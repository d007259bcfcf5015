"""Safe writes: every output goes to a unique temporary name beside its target and is
published only when complete, never over an existing file without ``force``, never over
an input or a special file; a full disk is seen before the bytes are refused.

:func:`output` is the one way the software writes a whole file (reports, summaries,
configs, logs, run files made at once); :func:`publish` puts a finished temporary file
in place; :func:`ensure_room` is asked before each append to a run file being recorded.
"""

from __future__ import annotations

import errno
import json
import os
import re
import resource
import stat
import tempfile
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

from stand.errors import DiskFullError, RecordingError, UsageError, WriteError

_ABSOLUTE = re.compile(r"(?<![\w./:])(?:/[^\s/:'\"]+)+/([^\s/:'\"]+)")
"""An absolute POSIX path in a sentence: its last part is what is kept."""


def without_folders(text: str) -> str:
    """``text`` with every absolute path cut to its last part: what a plant's systems and
    its IT are shown (a file is named by its name and digest, never by the folders of the
    stand's machine).

    >>> without_folders("/srv/stand/runs/run-7.h5 (stored); a ratio 1/2, http://x/y")
    'run-7.h5 (stored); a ratio 1/2, http://x/y'
    """
    return _ABSOLUTE.sub(lambda m: m.group(1), text)


HEADROOM_BYTES = 1 << 18
"""Room kept free beyond each write's own need (HDF5's metadata, the file system's)."""


def _kind(mode: int) -> str:
    for test, name in (
        (stat.S_ISDIR, "a directory"),
        (stat.S_ISFIFO, "a FIFO"),
        (stat.S_ISCHR, "a device"),
        (stat.S_ISBLK, "a device"),
        (stat.S_ISSOCK, "a socket"),
    ):
        if test(mode):
            return name
    return "not a regular file"


def check_output(
    path: str | Path,
    *,
    force: bool = False,
    inputs: Iterable[str | Path] = (),
    exists: str = "exists already (use --force to replace it)",
) -> Path:
    """The output path, refused if it is an input, a special file or a symlink, exists
    without ``force`` (saying ``exists``: a command without ``--force`` says otherwise),
    or has no directory to go in.

    Raises
    ------
    WriteError
    """
    p = Path(path)
    for i in inputs:
        try:
            same = p.exists() and Path(i).exists() and os.path.samefile(p, i)
        except OSError:
            same = False
        if same or p.resolve() == Path(i).resolve():
            raise WriteError("is also an input: refusing to write over it", path=str(p))
    if p.is_symlink():
        raise WriteError("is a symbolic link: not replaced (name the file itself)", path=str(p))
    if p.exists():
        mode = p.stat().st_mode
        if not stat.S_ISREG(mode):
            raise WriteError(f"is {_kind(mode)}: not replaced", path=str(p))
        if not force:
            raise WriteError(exists, path=str(p))
    if not p.parent.is_dir():
        raise WriteError(f"no such directory: {p.parent}", path=str(p))
    return p


def check_input(path: str | Path) -> Path:
    """An input file that exists and is a regular file (a FIFO would block the read, a
    directory or device is no recording).

    Raises
    ------
    RecordingError
        Naming the file and what it is instead.
    """

    p = Path(path)
    try:
        mode = p.stat().st_mode
    except OSError as exc:
        if p.is_symlink():
            raise RecordingError(
                "a symbolic link that leads nowhere (or in a loop)", path=str(p)
            ) from None
        if isinstance(exc, FileNotFoundError):
            raise RecordingError("no such file", path=str(p)) from None
        raise RecordingError(f"cannot read: {exc.strerror or exc}", path=str(p)) from None
    if not stat.S_ISREG(mode):
        raise RecordingError(f"is {_kind(mode)}: not read", path=str(p))
    return p


def not_regular(path: str | Path) -> str | None:
    """What ``path`` is when it is there but no regular file ("a FIFO", "a directory",
    ...: reading a FIFO would wait for a writer forever); None for a regular file or one
    that cannot be looked at (the read that follows says why)."""
    try:
        mode = Path(path).stat().st_mode
    except OSError:
        return None
    return None if stat.S_ISREG(mode) else _kind(mode)


def check_folder(path: str | Path, what: str) -> Path:
    """A folder to keep files in (``what`` it is, for the message): refused in one line
    (UsageError) when it, or the nearest part of its path that exists, is no directory
    (a folder under a file cannot be made)."""
    p = Path(path)
    for part in (p, *p.parents):
        if part.exists() or part.is_symlink():
            if not part.is_dir():
                under = "" if part == p else f": its part {part}"
                raise UsageError(f"{what} {p}{under} is a file, not a folder")
            break
    return p


MAX_SECRET_BYTES = 4096
"""The most of a password, badge or PIN file read [bytes] (its first line is wanted)."""


def first_line(path: str | Path, what: str) -> str:
    """The first line of a small text file (a password, a badge's code), stripped
    (UsageError naming ``what`` and the file when there is none to read, or the file is
    a FIFO, a directory or a device: refused before it is opened)."""
    if (kind := not_regular(path)) is not None:
        raise UsageError(f"{path}: is {kind}, not a file holding {what}")
    try:
        with Path(path).open("rb") as f:
            head = f.read(MAX_SECRET_BYTES + 1)
        if len(head) > MAX_SECRET_BYTES and b"\n" not in head[:MAX_SECRET_BYTES]:
            raise UsageError(f"{path}: its first line is longer than {MAX_SECRET_BYTES} "
                             f"bytes: not {what}")  # fmt: skip
        line = head.split(b"\n", 1)[0].decode("utf-8", "strict")
        if not line.strip() and b"\n" not in head:
            raise IndexError  # an empty file
        return line.strip()
    except (OSError, IndexError, UnicodeDecodeError):
        raise UsageError(f"{path}: cannot read {what} from it (its first line)") from None


def strict_json(text: str) -> Any:
    """JSON as the standard has it: ``NaN``, ``Infinity`` and ``-Infinity`` (which Python's
    reader takes) are a ValueError, as any malformed text is."""
    return json.loads(text, parse_constant=_no_constant)


def _no_constant(name: str) -> Any:
    raise ValueError(f"{name} is not a number JSON allows")


def check_timestamps(t_s: np.ndarray, path: str | Path, first_frame: int = 0) -> None:
    """Refuse frames whose host timestamps are not numbers (NaN, inf), naming the first.

    ``first_frame``: the index of ``t_s[0]`` in the whole recording.

    Raises
    ------
    RecordingError
    """

    bad = np.flatnonzero(~np.isfinite(t_s))
    if len(bad):
        raise RecordingError(
            f"frame {first_frame + int(bad[0])}: its timestamp is {t_s[bad[0]]}, not a number "
            f"of seconds ({len(bad)} such frames from frame {first_frame} on)",
            path=str(path),
        )


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def temporary_beside(p: Path) -> Path:
    """A new, empty, uniquely named file beside ``p`` that keeps its extensions (the
    python-can writers choose their format by them): ``.NAME.XXXXXX.part.EXT``."""
    stem = p.name[: len(p.name) - len("".join(p.suffixes))] or p.name
    fd, tmp = tempfile.mkstemp(
        dir=p.parent, prefix=f".{stem}.", suffix=".part" + "".join(p.suffixes)
    )
    os.close(fd)
    os.chmod(tmp, 0o666 & ~_umask())  # as a plain open() would have made it
    return Path(tmp)


def publish(tmp: Path, dest: Path, *, force: bool = False) -> None:
    """Put the finished ``tmp`` at ``dest``: replaced with ``force``, else linked, so that
    of two writers of one name exactly one wins and the other is told."""
    if force:
        os.replace(tmp, dest)
        return
    try:
        os.link(tmp, dest)
    except FileExistsError:
        tmp.unlink(missing_ok=True)
        raise WriteError(
            "exists already: another program wrote it meanwhile (use --force to replace it)",
            path=str(dest),
        ) from None
    except OSError:  # no hard links here (FAT, some network shares): claim the name first
        fd = os.open(dest, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o666)
        os.close(fd)
        os.replace(tmp, dest)
        return
    tmp.unlink()


def write_error(exc: OSError, path: str | Path, what: str = "cannot write") -> WriteError:
    """One line for an OSError met while writing ``path`` (a full disk said as such)."""
    if exc.errno in (errno.ENOSPC, errno.EDQUOT, errno.EFBIG):
        return DiskFullError(
            f"{what}: {os.strerror(exc.errno)}", path=str(path), needed_bytes=0, free_bytes=0
        )
    return WriteError(f"{what}: {exc.strerror or exc}", path=str(path))


@contextmanager
def output(
    path: str | Path,
    *,
    force: bool = False,
    inputs: Iterable[str | Path] = (),
    need_bytes: int = 0,
) -> Iterator[Path]:
    """Write a whole file safely: yields a temporary path to write; on success it is
    published at ``path``; on any failure it is removed and ``path`` left as it was.

    Raises
    ------
    WriteError
        The output is refused (:func:`check_output`), or writing failed (a full disk
        is a :class:`~stand.errors.DiskFullError`).
    """
    dest = check_output(path, force=force, inputs=inputs)
    ensure_room(dest.parent, need_bytes, dest)
    try:
        tmp = temporary_beside(dest)
    except OSError as exc:
        raise write_error(exc, dest) from exc
    try:
        yield tmp
        publish(tmp, dest, force=force)
    except OSError as exc:
        tmp.unlink(missing_ok=True)
        raise write_error(exc, dest) from exc
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def ensure_room(where: Path, need_bytes: int, path: Path | None = None) -> None:
    """Refuse a write of ``need_bytes`` (plus :data:`HEADROOM_BYTES`) that the disk under
    ``where``, or the process's file-size limit for ``path``, has no room for.

    Asked before the bytes go: HDF5 does not survive a write that fails half way
    (its cache is left inconsistent, and h5py has crashed on it at exit).
    """

    need = int(need_bytes) + HEADROOM_BYTES
    target = str(path if path is not None else where)
    try:
        st = os.statvfs(where)
    except OSError:
        return  # nothing to measure with: the write itself will tell
    free = st.f_bavail * st.f_frsize
    if free < need:
        raise DiskFullError(
            f"the disk is full: {free / 1e6:.1f} MB free, the next write needs {need / 1e6:.1f} MB",
            path=target,
            needed_bytes=need,
            free_bytes=free,
        )
    limit = resource.getrlimit(resource.RLIMIT_FSIZE)[0]
    if limit != resource.RLIM_INFINITY:
        size = path.stat().st_size if path is not None and path.exists() else 0
        if size + need > limit:
            raise DiskFullError(
                f"the file-size limit (ulimit -f) is reached: {size / 1e6:.1f} of "
                f"{limit / 1e6:.1f} MB used, the next write needs {need / 1e6:.1f} MB",
                path=target,
                needed_bytes=need,
                free_bytes=max(limit - size, 0),
            )
