"""The stand's own evaluations (ISO 21940-21's machine tests, the capability study), each
with its date, verdict and the next one's due date.

Revision ID: 0007
Revises: 0006
Create Date: 2026-11-27
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0007"
down_revision = "0006"
branch_labels = None
depends_on = None


def upgrade() -> None:
    op.create_table(
        "evaluations",
        sa.Column("id", sa.Integer, primary_key=True, autoincrement=True),
        sa.Column("stand_id", sa.String(64)),
        sa.Column("kind", sa.String(16), nullable=False),
        sa.Column("performed_at", sa.String(40), nullable=False),
        sa.Column("verdict", sa.String(12), nullable=False),
        sa.Column("due", sa.String(10)),
        sa.Column("simulated", sa.Boolean, nullable=False),
        sa.Column("software", sa.String(64), nullable=False),
        sa.Column("result_json", sa.Text, nullable=False),
    )
    op.create_index("ix_evaluations_stand", "evaluations", ["stand_id", "kind", "performed_at"])


def downgrade() -> None:
    op.drop_index("ix_evaluations_stand", table_name="evaluations")
    op.drop_table("evaluations")
