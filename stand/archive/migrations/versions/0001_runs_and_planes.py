"""The first archive: runs and their planes.

Revision ID: 0001
Revises:
Create Date: 2026-11-22
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0001"
down_revision = None
branch_labels = None
depends_on = None


def upgrade() -> None:
    op.create_table(
        "runs",
        sa.Column("id", sa.Integer, primary_key=True, autoincrement=True),
        sa.Column("run_file", sa.Text, nullable=False),
        sa.Column("file_sha256", sa.String(64), nullable=False, unique=True),
        sa.Column("start_time", sa.String(40), nullable=False),
        sa.Column("archived_at", sa.String(40), nullable=False),
        sa.Column("serial", sa.String(64)),
        sa.Column("order_no", sa.String(64)),
        sa.Column("operator", sa.String(64)),
        sa.Column("note", sa.Text),
        sa.Column("rotor_type", sa.String(64)),
        sa.Column("rpm", sa.Float, nullable=False),
        sa.Column("config_sha256", sa.String(64), nullable=False),
        sa.Column("matrix", sa.Text),
        sa.Column("correction_mode", sa.String(8), nullable=False),
        sa.Column("verdict", sa.String(8), nullable=False),
        sa.Column("checks_run_id", sa.Integer, sa.ForeignKey("runs.id")),
        sa.Column("static_re_kg_m", sa.Float, nullable=False),
        sa.Column("static_im_kg_m", sa.Float, nullable=False),
        sa.Column("couple_re_kg_m", sa.Float, nullable=False),
        sa.Column("couple_im_kg_m", sa.Float, nullable=False),
        sa.Column("software", sa.String(64), nullable=False),
        sa.Column("result_json", sa.Text, nullable=False),
    )
    op.create_index("ix_runs_serial", "runs", ["serial"])
    op.create_index("ix_runs_rotor_type_start", "runs", ["rotor_type", "start_time"])
    op.create_index("ix_runs_order", "runs", ["order_no"])
    op.create_index("ix_runs_start", "runs", ["start_time"])
    op.create_table(
        "planes",
        sa.Column(
            "run_id",
            sa.Integer,
            sa.ForeignKey("runs.id", ondelete="CASCADE"),
            primary_key=True,
        ),
        sa.Column("plane", sa.Integer, primary_key=True),
        sa.Column("U_re_kg_m", sa.Float, nullable=False),
        sa.Column("U_im_kg_m", sa.Float, nullable=False),
        sa.Column("radius95_kg_m", sa.Float, nullable=False),
        sa.Column("permissible_kg_m", sa.Float),
        sa.Column("passed", sa.Boolean),
        sa.Column("leftover_kg_m", sa.Float, nullable=False),
        sa.Column("urr", sa.Float),
    )


def downgrade() -> None:
    op.drop_table("planes")
    op.drop_table("runs")
