"""The archive's tables: the one home of its schema (SQLAlchemy Core).

One row per run (its job, its file and digest, its verdict, the run it
checks), one row per plane (the unbalance as a complex number in kg m, its
95 % radius, the tolerance and the URR when it was a check), and one row
per confirmed correction with its check (the calibration datum of
:mod:`stand.health.monitor`).  SI units and
complex parts in columns; the whole result as JSON beside them, so that a
report can be made again without the run file.  Changes go through a
migration in ``migrations/versions`` (Alembic), never by editing a table
here alone.
"""

from __future__ import annotations

from sqlalchemy import (
    Boolean,
    Column,
    Float,
    ForeignKey,
    Index,
    Integer,
    MetaData,
    String,
    Table,
    Text,
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
    Column("verdict", String(8), nullable=False),  # pass, fail, none (no tolerance)
    Column("checks_run_id", Integer, ForeignKey("runs.id")),
    Column("static_re_kg_m", Float, nullable=False),
    Column("static_im_kg_m", Float, nullable=False),
    Column("couple_re_kg_m", Float, nullable=False),
    Column("couple_im_kg_m", Float, nullable=False),
    Column("software", String(64), nullable=False),
    Column("result_json", Text, nullable=False),
    Column("stand_id", String(64)),  # the stand that recorded it (revision 0002)
)
Index("ix_runs_serial", runs.c.serial)
Index("ix_runs_rotor_type_start", runs.c.rotor_type, runs.c.start_time)
Index("ix_runs_order", runs.c.order_no)
Index("ix_runs_start", runs.c.start_time)
Index("ix_runs_stand", runs.c.stand_id, runs.c.start_time)

planes = Table(
    "planes",
    metadata,
    Column("run_id", Integer, ForeignKey("runs.id", ondelete="CASCADE"), primary_key=True),
    Column("plane", Integer, primary_key=True),
    Column("U_re_kg_m", Float, nullable=False),
    Column("U_im_kg_m", Float, nullable=False),
    Column("radius95_kg_m", Float, nullable=False),
    Column("permissible_kg_m", Float),
    Column("passed", Boolean),
    Column("leftover_kg_m", Float, nullable=False),  # what rounding the correction leaves
    Column("urr", Float),  # when the run checks another
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
