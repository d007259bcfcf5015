"""The job orders a line's MES sends (OPC 40001-3, Machinery Job Management) with their
states, and each run's job order.

Revision ID: 0008
Revises: 0007
Create Date: 2026-11-27
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0008"
down_revision = "0007"
branch_labels = None
depends_on = None


def upgrade() -> None:
    op.create_table(
        "jobs",
        sa.Column("id", sa.Integer, primary_key=True, autoincrement=True),
        sa.Column("stand_id", sa.String(64), nullable=False),
        sa.Column("job_order_id", sa.String(64), nullable=False),
        sa.Column("rotor_type", sa.String(64), nullable=False),
        sa.Column("serial", sa.String(64), nullable=False),
        sa.Column("order_no", sa.String(64)),
        sa.Column("operator", sa.String(64)),
        sa.Column("description", sa.Text),
        sa.Column("state", sa.String(16), nullable=False),
        sa.Column("start_requested", sa.Boolean, nullable=False),
        sa.Column("stored_at", sa.String(40), nullable=False),
        sa.Column("started_at", sa.String(40)),
        sa.Column("ended_at", sa.String(40)),
        sa.Column("run_id", sa.Integer, sa.ForeignKey("runs.id")),
        sa.Column("verdict", sa.String(12)),
        sa.UniqueConstraint("stand_id", "job_order_id", name="uq_jobs_stand_job"),
    )
    with op.batch_alter_table("runs") as batch:
        batch.add_column(sa.Column("job_id", sa.String(64)))
    op.create_index("ix_runs_job", "runs", ["stand_id", "job_id"])


def downgrade() -> None:
    op.drop_index("ix_runs_job", table_name="runs")
    with op.batch_alter_table("runs") as batch:
        batch.drop_column("job_id")
    op.drop_table("jobs")
