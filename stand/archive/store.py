"""The archive's database: open (and migrate), write one result, read back.

SQLAlchemy Core over SQLite (the default: one file in the user's data
directory, WAL mode, writers queued by ``BEGIN IMMEDIATE`` and a busy
timeout) or PostgreSQL (a plant-wide archive, by URL).  Each run is written
in one transaction: a crash leaves the run in the archive whole or not at
all.  The schema is :mod:`stand.archive.schema`; every change to it is an
Alembic migration, applied when an archive is opened.
"""

from __future__ import annotations

import datetime as dt
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from stand.archive.schema import corrections, planes, runs
from stand.archive.validate import correction_row
from stand.config import data_folder
from stand.errors import ArchiveError

BUSY_TIMEOUT_S = 60.0
"""A writer waits this long for another to finish before giving up [s]."""
CONNECT_TIMEOUT_S = 10
"""A database server must answer a new connection within this [s] (libpq's
``connect_timeout``; a URL's own ``?connect_timeout=`` wins)."""
MIGRATIONS = Path(__file__).resolve().parent / "migrations"
MIGRATING = threading.Lock()
"""Alembic's ``context`` is one module-wide proxy: two threads of one process (the station's
and the OPC UA server's, a test's) migrating at once mix their options ("KeyError:
'script'", seen in the test suite).  One at a time."""


SCHEMA_HEAD = "0011"
"""The newest migration of ``stand/archive/migrations`` (a test holds it to alembic's)."""
BACKENDS = ("sqlite", "postgresql")
"""The databases an archive is kept in (the migrations and the tests know these two)."""


def default_url() -> str:
    """``sqlite:///`` the file ``archive.sqlite`` in the user's data directory."""
    return f"sqlite:///{data_folder() / 'archive.sqlite'}"


def _safe(url: str) -> str:
    """The URL as errors show it: without a password."""
    from sqlalchemy.engine import make_url

    try:
        return make_url(url).render_as_string(hide_password=True)
    except Exception:
        return url


class Archive:
    """One archive, opened (and migrated to the latest schema).

    Use as a context manager; :meth:`close` is idempotent.

    Raises
    ------
    ArchiveError
        The URL is not a database this software can use, or it cannot be reached.
    """

    def __init__(self, url: str | None = None):
        import sqlalchemy as sa
        from sqlalchemy.exc import ArgumentError, NoSuchModuleError, SQLAlchemyError

        self.url = url or default_url()
        self.shown = _safe(self.url)
        try:
            u = sa.engine.make_url(self.url)
            if u.get_backend_name() not in BACKENDS:
                raise ArchiveError(f"a {u.get_backend_name()} database is not one the stand "
                                   f"keeps its archive in: {' or '.join(BACKENDS)} "
                                   "(sqlite:///FILE, postgresql+psycopg://user@host/db)",
                                   url=self.shown)  # fmt: skip
            self.sqlite = u.get_backend_name() == "sqlite"
            if self.sqlite and u.database and u.database != ":memory:":
                _sqlite_file_or_none(Path(u.database), self.shown)
                Path(u.database).parent.mkdir(parents=True, exist_ok=True)
                share = network_filesystem(Path(u.database).parent)
                if share is not None:
                    raise ArchiveError(
                        f"an SQLite archive on a network share ({share}) is not safe: its file "
                        "locks do not hold there, so two stands can corrupt it. Use "
                        "PostgreSQL for an archive that several stands share "
                        "(postgresql+psycopg://user@host/db)",
                        url=self.shown,
                    )
            connect = {}
            if u.get_driver_name() in ("psycopg", "psycopg2") and "connect_timeout" not in u.query:
                connect["connect_timeout"] = CONNECT_TIMEOUT_S
            self.engine = sa.create_engine(self.url, future=True, connect_args=connect)
        except ArchiveError:
            raise
        except (ArgumentError, NoSuchModuleError, ImportError, ValueError, OSError) as exc:
            raise ArchiveError(f"not a usable database URL ({exc})", url=self.shown) from exc
        if self.sqlite:
            _sqlite_pragmas(self.engine)
        self._closed = False
        try:
            self._migrate()
        except SQLAlchemyError as exc:
            self.close()
            raise ArchiveError(_reason(exc), url=self.shown) from exc
        except ArchiveError:
            self.close()
            raise

    def _migrate(self) -> None:
        """Bring the archive to :data:`SCHEMA_HEAD` with alembic, unless it is there already
        (one query: alembic's scripts take 20 ms to load at every open)."""
        from alembic import command
        from alembic.config import Config
        from alembic.util.exc import CommandError
        from sqlalchemy.exc import SQLAlchemyError

        with self.engine.connect() as conn:  # a server that does not answer: raised here, once
            try:
                now = conn.exec_driver_sql("SELECT version_num FROM alembic_version").scalar()
            except SQLAlchemyError:  # a new archive: no version table yet
                now = None
        if now == SCHEMA_HEAD:
            return

        cfg = Config()
        cfg.set_main_option("script_location", str(MIGRATIONS))
        with MIGRATING, self.engine.begin() as conn:
            if not self.sqlite:  # one migrating process at a time on a shared server
                conn.exec_driver_sql("SELECT pg_advisory_xact_lock(727274)")
            cfg.attributes["connection"] = conn
            try:
                command.upgrade(cfg, "head")
            except CommandError as exc:  # a revision this software does not know
                raise ArchiveError(
                    f"its schema is not one this software knows ({exc}): a newer version "
                    "of stand made it",
                    url=self.shown,
                ) from exc

    @contextmanager
    def transaction(self) -> Iterator[Any]:
        """One transaction (``BEGIN IMMEDIATE`` on SQLite); ArchiveError if it fails."""
        from sqlalchemy.exc import SQLAlchemyError

        try:
            with self.engine.begin() as conn:
                yield conn
        except SQLAlchemyError as exc:
            raise ArchiveError(_reason(exc), url=self.shown) from exc

    def _insert_once(
        self,
        table: Any,
        key: str,
        row: dict[str, Any],
        what: str,
        then: Callable[[Any, int], None] | None = None,
    ) -> int:
        """Insert ``row`` into ``table`` in one transaction (``then(conn, id)`` in it too),
        unless a row with the same ``key`` is there already (also when another writer put it
        there meanwhile: the unique key's violation); the row's id."""
        import sqlalchemy as sa
        from sqlalchemy.exc import IntegrityError

        def existing(conn: Any) -> Any:
            return conn.execute(sa.select(table.c.id).where(table.c[key] == row[key])).scalar()

        try:
            with self.engine.begin() as conn:
                found = existing(conn)
                if found is not None:
                    return int(found)
                stamp = dt.datetime.now(dt.UTC).isoformat(timespec="seconds")
                new = conn.execute(table.insert().values(**row, archived_at=stamp))
                new_id = int(new.inserted_primary_key[0])  # type: ignore[index]
                if then is not None:
                    then(conn, new_id)
                return new_id
        except IntegrityError:  # another stand wrote the same one meanwhile
            with self.transaction() as conn:
                found = existing(conn)
            if found is None:
                raise ArchiveError(f"the {what} could not be written", url=self.shown) from None
            return int(found)
        except sa.exc.SQLAlchemyError as exc:
            raise ArchiveError(_reason(exc), url=self.shown) from exc

    def add(self, row: dict[str, Any], plane_rows: list[dict[str, Any]]) -> int:
        """Write one run and its planes in one transaction; the run's id.  A run already
        archived (the same file digest) is not written again: its id is returned."""

        def with_planes(conn: Any, run_id: int) -> None:
            conn.execute(planes.insert(), [{**p, "run_id": run_id} for p in plane_rows])

        return self._insert_once(runs, "file_sha256", row, "run", with_planes)

    def add_correction(self, row: dict[str, Any]) -> int:
        """Write one correction datum (:mod:`stand.health.monitor`); a check already stored (the
        same digest) is not written again: its id is returned."""

        return self._insert_once(corrections, "check_sha256", row, "calibration datum")

    def correction_rows(self, stand: str | None = None, rotor_type: str | None = None) -> list[Any]:
        """The correction data, oldest first, of a stand and a rotor type (None: any), each
        checked (:func:`stand.archive.validate.correction_row`): the row's columns, and its
        datum parsed once under ``datum``."""
        import sqlalchemy as sa

        q = sa.select(corrections).order_by(corrections.c.start_time, corrections.c.id)
        if stand is not None:
            q = q.where(corrections.c.stand_id == stand)
        if rotor_type is not None:
            q = q.where(corrections.c.rotor_type == rotor_type)
        with self.transaction() as conn:
            found = list(conn.execute(q).mappings())
        return [{**row, "datum": correction_row(row, self.shown)} for row in found]

    def mark_tooling(self, file_sha256s: list[str]) -> list[int]:
        """:func:`mark_tooling_runs` in a transaction of its own."""
        with self.transaction() as conn:
            return mark_tooling_runs(conn, file_sha256s)

    def run_id(self, file_sha256: str) -> int | None:
        """The id of the run with this file digest, if archived."""
        import sqlalchemy as sa

        with self.transaction() as conn:
            found = conn.execute(
                sa.select(runs.c.id).where(runs.c.file_sha256 == file_sha256)
            ).scalar()
        return None if found is None else int(found)

    def close(self) -> None:
        if not self._closed:
            self._closed = True
            self.engine.dispose()

    def __enter__(self) -> Archive:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def mark_tooling_runs(conn: Any, file_sha256s: list[str]) -> list[int]:
    """Mark the archived runs with these file digests as a tooling's index runs (kind
    ``tooling``: out of production statistics and exports), in the open transaction
    ``conn``; their ids, oldest first (none when they were never archived)."""
    import sqlalchemy as sa

    ids = sorted(conn.execute(
        sa.select(runs.c.id).where(runs.c.file_sha256.in_(file_sha256s))).scalars())  # fmt: skip
    if ids:
        conn.execute(runs.update().where(runs.c.id.in_(ids)).values(kind="tooling"))
    return [int(i) for i in ids]


NETWORK_FILESYSTEMS = frozenset({
    "nfs", "nfs4", "cifs", "smb3", "smbfs", "9p", "ceph", "glusterfs", "fuse.glusterfs",
    "fuse.sshfs", "sshfs", "afs", "lustre", "gpfs", "ncpfs", "davfs", "fuse.s3fs", "fuse.rclone",
})  # fmt: skip
"""File systems whose locks SQLite cannot trust (its documentation: not over a network)."""
MOUNTS = Path("/proc/self/mounts")


SQLITE_SMALLEST = 512
"""The smallest SQLite database file [bytes]: one page of the smallest size."""


def _sqlite_file_or_none(path: Path, shown: str) -> None:
    """Refuse (ArchiveError) a file there that cannot be an SQLite database, being shorter
    than its smallest page but not empty: SQLite would take it for an empty database and
    write over it.  (A longer file that is no database SQLite refuses itself; one that
    another process is creating grows a whole page at a time, from empty.)"""
    if not path.exists():
        return
    if not path.is_file():
        raise ArchiveError("is not a file (a folder or a device): no archive", url=shown)
    try:
        size = path.stat().st_size
    except OSError as exc:
        raise ArchiveError(f"cannot be read ({exc.strerror or exc})", url=shown) from exc
    if 0 < size < SQLITE_SMALLEST:
        raise ArchiveError("file is not a database (not SQLite's): not opened, never written "
                           "over", url=shown)  # fmt: skip


def network_filesystem(folder: Path) -> str | None:
    """``nfs4 at /mnt/share`` when ``folder`` lies on a network file system, else None
    (also when the mounts cannot be read: not Linux)."""
    try:
        lines = MOUNTS.read_text().splitlines()
    except OSError:
        return None
    target = str(folder.resolve())
    best: tuple[int, str, str] | None = None
    for line in lines:
        parts = line.split()
        if len(parts) < 3:
            continue
        point = parts[1].replace("\\040", " ")
        inside = target == point or target.startswith(point.rstrip("/") + "/")
        if inside and (best is None or len(point) > best[0]):
            best = (len(point), point, parts[2])
    if best is not None and best[2] in NETWORK_FILESYSTEMS:
        return f"{best[2]} at {best[1]}"
    return None


def _sqlite_pragmas(engine: Any) -> None:
    """WAL (readers never block the writer), foreign keys, a busy timeout, and
    ``BEGIN IMMEDIATE`` so that two writers queue instead of deadlocking."""
    from sqlalchemy import event

    @event.listens_for(engine, "connect")
    def _on_connect(dbapi_conn: Any, _record: Any) -> None:
        dbapi_conn.isolation_level = None  # SQLAlchemy emits BEGIN itself, below
        cur = dbapi_conn.cursor()
        cur.execute(f"PRAGMA busy_timeout = {int(BUSY_TIMEOUT_S * 1000)}")
        cur.execute("PRAGMA journal_mode = WAL")
        cur.execute("PRAGMA synchronous = NORMAL")
        cur.execute("PRAGMA foreign_keys = ON")
        cur.close()

    @event.listens_for(engine, "begin")
    def _on_begin(conn: Any) -> None:
        conn.exec_driver_sql("BEGIN IMMEDIATE")


def _reason(exc: Exception) -> str:
    """The database's own words, on one line."""
    orig = getattr(exc, "orig", None) or exc
    words = " ".join(str(orig).split())[:300]
    if "timeout expired" in words:
        return f"the server did not answer within its connect timeout ({words})"
    return words
