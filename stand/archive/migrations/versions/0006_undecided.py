"""The verdict ``undecided`` (ISO 21940-14: the residual's interval straddles the limit):
the verdict columns widen from 8 to 12 characters.

Revision ID: 0006
Revises: 0005
Create Date: 2026-11-27
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0006"
down_revision = "0005"
branch_labels = None
depends_on = None


def upgrade() -> None:
    for table in ("runs", "revised"):
        with op.batch_alter_table(table) as batch:  # SQLite alters a table by copying it
            batch.alter_column("verdict", type_=sa.String(12), existing_type=sa.String(8))


def downgrade() -> None:
    for table in ("runs", "revised"):
        with op.batch_alter_table(table) as batch:
            batch.alter_column("verdict", type_=sa.String(8), existing_type=sa.String(12))
