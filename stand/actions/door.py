"""The one door every change goes through: who (:class:`Actor`), with what right, the
change made and journaled in one database transaction (:func:`door`).

A change opens the door with the right it takes; inside, in one transaction of the
archive, the actor's right is checked against the accounts as they are now (a disabled
or demoted account is refused at once), the change is made (rows written in the same
transaction, files through :meth:`Passage.write`, undone if the transaction does not
commit) and journaled (:meth:`Passage.journal`, signed).  A refusal changes nothing and
is journaled itself, in a transaction of its own.  After the commit the journal's head
is kept in the anchor beside the stand's key.

A stand whose archive has no account is a lone stand: the operating system's user (by
the process's effective uid, never the environment) may do everything, journaled as
``os:NAME``.  Once an archive has accounts, every change names its account.
"""

from __future__ import annotations

import os
import pwd
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from stand.archive import Archive
from stand.archive.accounts import ROLES, account_in, may
from stand.archive.audit import Change, anchor, append, archive_id
from stand.archive.keys import StandKey, stand_key
from stand.archive.schema import accounts
from stand.errors import RefusedError
from stand.files import output


@dataclass(frozen=True)
class Actor:
    """Who makes a change, and from where.

    Parameters
    ----------
    name
        The account's name, or ``os:NAME`` for the operating system's user of a lone stand.
    role
        The account's role as it logged in (None: the operating system's user).  The
        door checks the role the account has *now*.
    source
        Where the change came from: ``cli``, ``station``, ``opcua`` or ``mqtt``.
    """

    name: str
    role: str | None
    source: str

    @property
    def is_account(self) -> bool:
        return self.role is not None


def os_user() -> str:
    """The operating system's user of this process, by its effective uid (``os:NAME``;
    ``os:uid-N`` where the user database has no name for it)."""
    uid = os.geteuid()
    try:
        return f"os:{pwd.getpwuid(uid).pw_name}"
    except KeyError:
        return f"os:uid-{uid}"


def os_actor(source: str = "cli") -> Actor:
    """The operating system's user of this process as an :class:`Actor`."""
    return Actor(os_user(), None, source)


@dataclass
class Passage:
    """A change under way inside the door: its open transaction (``conn``), who makes it,
    and what it journaled and wrote so far."""

    conn: Any
    actor: Actor
    key: StandKey
    url: str
    journaled: list[dict[str, Any]] = field(default_factory=list)
    unchanged: bool = False
    """Set by a body that found nothing to change (a run archived already)."""
    _undo: list[tuple[Path, bytes | None]] = field(default_factory=list)

    def journal(self, change: Change) -> int:
        """One signed entry for ``change``, in this transaction; its id."""
        entry = append(self.conn, change, who=self.actor.name, source=self.actor.source,
                       key=self.key)  # fmt: skip
        self.journaled.append(entry)
        return int(entry["id"])

    def write(self, path: str | Path, data: bytes, *, force: bool = False,
              inputs: tuple[str | Path, ...] = ()) -> None:  # fmt: skip
        """Write ``data`` to ``path`` (a temporary name, then a rename; never over a file
        without ``force``); put back as it was if the transaction does not commit."""
        p = Path(path)
        before = p.read_bytes() if p.is_file() else None
        with output(p, force=force, inputs=inputs, need_bytes=len(data)) as tmp:
            tmp.write_bytes(data)
        self._undo.append((p, before))

    def track(self, path: str | Path) -> None:
        """A file the change writes by other means (a PDF printed): put back as it was if
        the transaction does not commit."""
        p = Path(path)
        self._undo.append((p, p.read_bytes() if p.is_file() else None))

    def undo(self) -> None:
        """Put back every file written, newest first (the transaction did not commit)."""
        for path, before in reversed(self._undo):
            try:
                if before is None:
                    path.unlink(missing_ok=True)
                else:
                    with output(path, force=True) as tmp:
                        tmp.write_bytes(before)
            except OSError:
                continue


Rights = str | tuple[str, ...] | None
"""What a change takes: a right, several (all of them), or None: an observation anyone
makes (a run archived, a file found changed), attributed to whoever made it."""


def refusal(conn: Any, actor: Actor, right: Rights, what: str) -> str | None:
    """Why ``actor`` may not ``what`` (taking ``right``) in the archive of ``conn`` as it
    is now; None if it may."""
    import sqlalchemy as sa

    if right is None:
        return None

    has_accounts = conn.execute(sa.select(accounts.c.name).limit(1)).first() is not None
    if not has_accounts:
        if actor.is_account:
            return f"no account {actor.name} in this archive"
        return None  # a lone stand: its operating system's user
    if not actor.is_account:
        return (f"this archive has accounts: to {what}, name yours "
                "(stand ... --as NAME; at the station, log in)")  # fmt: skip
    found = account_in(conn, actor.name)
    if found is None or not found["active"]:
        return f"account {actor.name} is disabled or gone"
    for one in (right,) if isinstance(right, str) else right:
        if not may(found["role"], one):
            roles = " or ".join(r for r in ROLES if may(r, one))
            return f"{actor.name} ({found['role']}) may not {what}: it takes {roles}"
    return None


@contextmanager
def door(url: str, actor: Actor, right: Rights, what: str) -> Iterator[Passage]:
    """The one way a change is made: yields a :class:`Passage` inside one transaction of
    the archive ``url`` once ``actor`` is found to have ``right``; the body makes the
    change and journals it; all of it commits together, or none of it does.

    Raises
    ------
    RefusedError
        ``actor`` may not (the refusal is journaled).
    """
    key = stand_key()
    with Archive(url) as archive:
        passage: Passage | None = None
        why = None
        try:
            with archive.transaction() as conn:
                why = refusal(conn, actor, right, what)
                if why is None:
                    passage = Passage(conn, actor, key, url)
                    yield passage
                    if not passage.journaled and not passage.unchanged:
                        raise RuntimeError(f"{what}: a change through the door journals itself")
                    aid = archive_id(conn)
        except RefusedError as exc:  # the change's own rule refused it: nothing changed
            if passage is not None:
                passage.undo()
            _journal_refusal(archive, actor, key, exc.right, what, str(exc))
            raise
        except BaseException:
            if passage is not None:
                passage.undo()
            raise
        if why is not None:
            named = right if isinstance(right, str) else "+".join(right or ())
            _journal_refusal(archive, actor, key, named, what, why)
            raise RefusedError(f"refused: {why}", who=actor.name, right=named)
        assert passage is not None
        if passage.journaled:
            anchor(aid, passage.journaled[-1])


def _journal_refusal(archive: Archive, actor: Actor, key: StandKey, right: str, what: str,
                     why: str) -> None:  # fmt: skip
    """Journal a refusal, in a transaction of its own."""
    with archive.transaction() as conn:
        entry = append(conn, Change("refused", what, None, None, why[:1000],
                                    detail={"right": right}),
                       who=actor.name, source=actor.source, key=key)  # fmt: skip
        aid = archive_id(conn)
    anchor(aid, entry)
