"""Badges kept as an HMAC under a key outside the archive, each bound to a PIN: the
accounts gain ``badge_hmac`` (unique: one badge, one person) and ``pin_hash`` (argon2id).
A badge stored before (``badge_sha256``, a plain SHA-256 that an offline search of every
short code recovers) is left as it was, so that the journal's digests of the accounts
still hold, but no longer logs in: the administrator issues it again
(``stand users set NAME --badge-file F --pin-file P``).

Revision ID: 0011
Revises: 0010
Create Date: 2026-11-28
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0011"
down_revision = "0010"
branch_labels = None
depends_on = None


def upgrade() -> None:
    with op.batch_alter_table("accounts") as batch:
        batch.add_column(sa.Column("badge_hmac", sa.String(64)))
        batch.add_column(sa.Column("pin_hash", sa.Text))
        batch.create_unique_constraint("uq_accounts_badge_hmac", ["badge_hmac"])


def downgrade() -> None:
    with op.batch_alter_table("accounts") as batch:
        batch.drop_constraint("uq_accounts_badge_hmac", type_="unique")
        batch.drop_column("pin_hash")
        batch.drop_column("badge_hmac")
