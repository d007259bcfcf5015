"""Many stands, one archive: each run carries the id of the stand that recorded it.

Revision ID: 0002
Revises: 0001
Create Date: 2026-11-24
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0002"
down_revision = "0001"
branch_labels = None
depends_on = None


def upgrade() -> None:
    with op.batch_alter_table("runs") as batch:  # SQLite alters a table by copying it
        batch.add_column(sa.Column("stand_id", sa.String(64)))
    op.create_index("ix_runs_stand", "runs", ["stand_id", "start_time"])


def downgrade() -> None:
    op.drop_index("ix_runs_stand", "runs")
    with op.batch_alter_table("runs") as batch:
        batch.drop_column("stand_id")
