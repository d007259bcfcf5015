"""The stand keeps itself honest: each confirmed correction and its check, as a datum.

Revision ID: 0003
Revises: 0002
Create Date: 2026-11-24
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0003"
down_revision = "0002"
branch_labels = None
depends_on = None


def upgrade() -> None:
    op.create_table(
        "corrections",
        sa.Column("id", sa.Integer, primary_key=True, autoincrement=True),
        sa.Column("initial_sha256", sa.String(64), nullable=False),
        sa.Column("check_sha256", sa.String(64), nullable=False, unique=True),
        sa.Column("stand_id", sa.String(64)),
        sa.Column("rotor_type", sa.String(64)),
        sa.Column("rpm", sa.Float, nullable=False),
        sa.Column("config_sha256", sa.String(64), nullable=False),
        sa.Column("confirmed_by", sa.String(64)),
        sa.Column("applied", sa.String(16), nullable=False),
        sa.Column("start_time", sa.String(40), nullable=False),
        sa.Column("archived_at", sa.String(40), nullable=False),
        sa.Column("datum_json", sa.Text, nullable=False),
    )
    op.create_index("ix_corrections_group", "corrections", ["stand_id", "rotor_type", "start_time"])


def downgrade() -> None:
    op.drop_index("ix_corrections_group", "corrections")
    op.drop_table("corrections")
