"""The archive's tables: the one home of its schema (SQLAlchemy Core).

One row per run (its job, its file and digest, its verdict, the run it
checks, its kind: production or a tooling's index run), one row per plane
(the unbalance as a complex number in kg m, its 95 % radius, the tolerance
and the URR when it was a check), and one row per confirmed correction with
its check (the calibration datum of :mod:`stand.health.monitor`); and the
revisions ``stand reprocess`` makes: a named re-judgement (its config's
digest, the software), a row per run it re-solved (its status, verdict and
JSON) and one per plane, beside the originals, which are never changed; and
the stand's own evaluations (ISO 21940-21's machine tests, the capability
study) with their verdicts and due dates; and the job orders a line's MES sends, with
their states; the audit trail and the accounts.  SI
units and complex parts in columns; the whole result as JSON beside them, so
that a report can be made again without the run file.  Changes go through a
migration in ``migrations/versions`` (Alembic), never by editing a table
here alone.
"""

from __future__ import annotations

from typing import Any

from sqlalchemy import (
    Boolean,
    Column,
    Float,
    ForeignKey,
    ForeignKeyConstraint,
    Index,
    Integer,
    MetaData,
    String,
    Table,
    Text,
    UniqueConstraint,
)

metadata = MetaData()

runs = Table(
    "runs",
    metadata,
    Column("id", Integer, primary_key=True, autoincrement=True),
    Column("run_file", Text, nullable=False),
    Column("file_sha256", String(64), nullable=False, unique=True),
    Column("start_time", String(40), nullable=False),
    Column("archived_at", String(40), nullable=False),
    Column("serial", String(64)),
    Column("order_no", String(64)),
    Column("operator", String(64)),
    Column("note", Text),
    Column("rotor_type", String(64)),
    Column("rpm", Float, nullable=False),
    Column("config_sha256", String(64), nullable=False),
    Column("matrix", Text),
    Column("correction_mode", String(8), nullable=False),
    Column("verdict", String(12), nullable=False),  # pass, fail, undecided, none
    Column("checks_run_id", Integer, ForeignKey("runs.id")),
    Column("static_re_kg_m", Float, nullable=False),
    Column("static_im_kg_m", Float, nullable=False),
    Column("couple_re_kg_m", Float, nullable=False),
    Column("couple_im_kg_m", Float, nullable=False),
    Column("software", String(64), nullable=False),
    Column("result_json", Text, nullable=False),
    Column("stand_id", String(64)),  # the stand that recorded it (revision 0002)
    # production, or tooling: an index run of the tooling (revision 0005)
    Column("kind", String(12), nullable=False, server_default="production"),
    Column("job_id", String(64)),  # the MES's job order it ran under (revision 0008)
)
Index("ix_runs_serial", runs.c.serial)
Index("ix_runs_rotor_type_start", runs.c.rotor_type, runs.c.start_time)
Index("ix_runs_order", runs.c.order_no)
Index("ix_runs_start", runs.c.start_time)
Index("ix_runs_stand", runs.c.stand_id, runs.c.start_time)
Index("ix_runs_job", runs.c.stand_id, runs.c.job_id)


def plane_values() -> list[Column[Any]]:
    """A plane's columns (new objects each call): the archive's planes and a revision's."""
    return [
        Column("U_re_kg_m", Float, nullable=False),
        Column("U_im_kg_m", Float, nullable=False),
        Column("radius95_kg_m", Float, nullable=False),
        Column("permissible_kg_m", Float),
        Column("passed", Boolean),
        Column("leftover_kg_m", Float, nullable=False),  # what rounding the correction leaves
        Column("urr", Float),  # when the run checks another (a revision: not recomputed)
    ]


planes = Table(
    "planes",
    metadata,
    Column("run_id", Integer, ForeignKey("runs.id", ondelete="CASCADE"), primary_key=True),
    Column("plane", Integer, primary_key=True),
    *plane_values(),
)

corrections = Table(
    "corrections",
    metadata,
    Column("id", Integer, primary_key=True, autoincrement=True),
    Column("initial_sha256", String(64), nullable=False),  # the run before the correction
    Column("check_sha256", String(64), nullable=False, unique=True),  # the check after it
    Column("stand_id", String(64)),
    Column("rotor_type", String(64)),
    Column("rpm", Float, nullable=False),
    Column("config_sha256", String(64), nullable=False),  # the calibration it was made with
    Column("confirmed_by", String(64)),  # the operator who confirmed it applied
    Column("applied", String(16), nullable=False),  # "as shown" or "typed" (what was put on)
    Column("start_time", String(40), nullable=False),  # the check run's
    Column("archived_at", String(40), nullable=False),
    Column("datum_json", Text, nullable=False),  # phasors, covariances, correction, config
)  # revision 0003: each confirmed correction and its check (stand.health.monitor)
Index("ix_corrections_group", corrections.c.stand_id, corrections.c.rotor_type,
      corrections.c.start_time)  # fmt: skip

revisions = Table(
    "revisions",
    metadata,
    Column("id", Integer, primary_key=True, autoincrement=True),
    Column("name", String(64), nullable=False, unique=True),
    Column("config_sha256", String(64)),  # None: each run re-solved with its own stored config
    Column("config_source", Text),  # the file it was given as
    Column("software", String(64), nullable=False),
    Column("created_at", String(40), nullable=False),
)  # revision 0004: the runs re-judged by stand reprocess, beside the originals

revised = Table(
    "revised",
    metadata,
    Column("revision_id", Integer, ForeignKey("revisions.id", ondelete="CASCADE"),
           primary_key=True),
    Column("run_id", Integer, ForeignKey("runs.id", ondelete="CASCADE"), primary_key=True),
    Column("status", String(12), nullable=False),  # ok, missing, altered, unreadable, refused
    Column("reason", Text),  # why not ok, in one line
    Column("verdict", String(12)),  # pass, fail, undecided, none; None unless ok
    Column("result_json", Text),  # the re-solved result's JSON form; None unless ok
    Column("solved_at", String(40), nullable=False),
)  # fmt: skip

revised_planes = Table(
    "revised_planes",
    metadata,
    Column("revision_id", Integer, primary_key=True),
    Column("run_id", Integer, primary_key=True),
    Column("plane", Integer, primary_key=True),
    *plane_values(),
    ForeignKeyConstraint(["revision_id", "run_id"], ["revised.revision_id", "revised.run_id"],
                         ondelete="CASCADE"),
)  # fmt: skip

evaluations = Table(
    "evaluations",
    metadata,
    Column("id", Integer, primary_key=True, autoincrement=True),
    Column("stand_id", String(64)),
    Column("kind", String(16), nullable=False),  # machine (ISO 21940-21), capability
    Column("performed_at", String(40), nullable=False),  # ISO 8601, UTC
    Column("verdict", String(12), nullable=False),  # pass, fail, not judged; capable, ...
    Column("due", String(10)),  # YYYY-MM-DD: the next one's (machine tests)
    Column("simulated", Boolean, nullable=False),  # its runs came from the simulator
    Column("software", String(64), nullable=False),
    Column("result_json", Text, nullable=False),  # the evaluation's JSON form
)  # revision 0007: the stand's own evaluations, kept with their due dates
Index("ix_evaluations_stand", evaluations.c.stand_id, evaluations.c.kind,
      evaluations.c.performed_at)  # fmt: skip

jobs = Table(
    "jobs",
    metadata,
    Column("id", Integer, primary_key=True, autoincrement=True),
    Column("stand_id", String(64), nullable=False),
    Column("job_order_id", String(64), nullable=False),  # the MES's JobOrderID
    Column("rotor_type", String(64), nullable=False),
    Column("serial", String(64), nullable=False),
    Column("order_no", String(64)),
    Column("operator", String(64)),
    Column("description", Text),
    Column("state", String(16), nullable=False),  # AllowedToStart, Running, Ended, Aborted
    Column("start_requested", Boolean, nullable=False),  # StoreAndStart or Start was called
    Column("stored_at", String(40), nullable=False),  # ISO 8601, UTC
    Column("started_at", String(40)),
    Column("ended_at", String(40)),
    Column("run_id", Integer, ForeignKey("runs.id")),  # the latest run under it
    Column("verdict", String(12)),  # that run's
    UniqueConstraint("stand_id", "job_order_id", name="uq_jobs_stand_job"),
)  # revision 0008: the job orders the MES sends (OPC 40001-3), and where they are

audit = Table(
    "audit",
    metadata,
    Column("id", Integer, primary_key=True, autoincrement=False),  # 1, 2, 3 ... no gaps
    Column("at_utc", String(40), nullable=False),  # ISO 8601, UTC
    Column("zone", String(64), nullable=False),  # the local zone then: "CET +01:00"
    Column("who", String(64), nullable=False),  # an account, or os:USER
    Column("action", String(16), nullable=False),  # config, calibration, matrix, ...
    Column("subject", Text, nullable=False),  # what changed, in words
    Column("old_sha256", String(64)),  # before (None: it did not exist)
    Column("new_sha256", String(64)),  # after (None: removed)
    Column("reason", Text),  # as typed (None: none given)
    Column("previous_sha256", String(64), nullable=False),  # the entry before's hash
    Column("entry_sha256", String(64), nullable=False),  # this entry's (stand.archive.audit)
    Column("source", String(16)),  # cli, station, opcua, ... (revision 0010)
    Column("key_id", String(16)),  # the stand key that signed it (stand.archive.keys)
    Column("signature", String(128)),  # Ed25519 of entry_sha256, hex
    Column("detail", Text),  # the state the change left, JSON (no secrets)
)  # revision 0009: the audit trail, append-only and hash-chained; 0010: signed

accounts = Table(
    "accounts",
    metadata,
    Column("name", String(64), primary_key=True),
    Column("role", String(16), nullable=False),  # operator, setter, engineer, administrator
    Column("password_hash", Text, nullable=False),  # argon2id
    Column("badge_sha256", String(64)),  # before 0011: a badge's plain SHA-256 (no log-in)
    Column("badge_hmac", String(64)),  # HMAC-SHA256, its key outside the archive (0011)
    Column("pin_hash", Text),  # argon2id of the badge's PIN (0011)
    Column("active", Boolean, nullable=False),
    Column("language", String(8)),  # the screens' language (None: the station's)
    Column("created_at", String(40), nullable=False),
    Column("changed_at", String(40), nullable=False),
    UniqueConstraint("badge_hmac", name="uq_accounts_badge_hmac"),  # one badge, one person
)  # revision 0009: the people who work the stand (stand.archive.accounts); 0011: badges
