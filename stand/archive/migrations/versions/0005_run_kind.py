"""A run's kind: production (a rotor measured for itself) or tooling (an index run of the
tooling, measured to find the tooling's unbalance: out of production statistics and
exports).

Revision ID: 0005
Revises: 0004
Create Date: 2026-11-26
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0005"
down_revision = "0004"
branch_labels = None
depends_on = None


def upgrade() -> None:
    with op.batch_alter_table("runs") as batch:  # SQLite alters a table by copying it
        batch.add_column(
            sa.Column("kind", sa.String(12), nullable=False, server_default="production")
        )


def downgrade() -> None:
    with op.batch_alter_table("runs") as batch:
        batch.drop_column("kind")
