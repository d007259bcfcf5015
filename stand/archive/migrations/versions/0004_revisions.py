"""Reprocessing: named revisions of archived runs, re-judged beside the originals.

Revision ID: 0004
Revises: 0003
Create Date: 2026-11-25
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0004"
down_revision = "0003"
branch_labels = None
depends_on = None


def upgrade() -> None:
    op.create_table(
        "revisions",
        sa.Column("id", sa.Integer, primary_key=True, autoincrement=True),
        sa.Column("name", sa.String(64), nullable=False, unique=True),
        sa.Column("config_sha256", sa.String(64)),
        sa.Column("config_source", sa.Text),
        sa.Column("software", sa.String(64), nullable=False),
        sa.Column("created_at", sa.String(40), nullable=False),
    )
    op.create_table(
        "revised",
        sa.Column("revision_id", sa.Integer,
                  sa.ForeignKey("revisions.id", ondelete="CASCADE"), primary_key=True),
        sa.Column("run_id", sa.Integer, sa.ForeignKey("runs.id", ondelete="CASCADE"),
                  primary_key=True),
        sa.Column("status", sa.String(12), nullable=False),
        sa.Column("reason", sa.Text),
        sa.Column("verdict", sa.String(8)),
        sa.Column("result_json", sa.Text),
        sa.Column("solved_at", sa.String(40), nullable=False),
    )  # fmt: skip
    op.create_table(
        "revised_planes",
        sa.Column("revision_id", sa.Integer, primary_key=True),
        sa.Column("run_id", sa.Integer, primary_key=True),
        sa.Column("plane", sa.Integer, primary_key=True),
        sa.Column("U_re_kg_m", sa.Float, nullable=False),
        sa.Column("U_im_kg_m", sa.Float, nullable=False),
        sa.Column("radius95_kg_m", sa.Float, nullable=False),
        sa.Column("permissible_kg_m", sa.Float),
        sa.Column("passed", sa.Boolean),
        sa.Column("leftover_kg_m", sa.Float, nullable=False),
        sa.Column("urr", sa.Float),
        sa.ForeignKeyConstraint(["revision_id", "run_id"],
                                ["revised.revision_id", "revised.run_id"], ondelete="CASCADE"),
    )  # fmt: skip


def downgrade() -> None:
    op.drop_table("revised_planes")
    op.drop_table("revised")
    op.drop_table("revisions")
