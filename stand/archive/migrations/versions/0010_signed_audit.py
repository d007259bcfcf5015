"""A signed journal: each audit entry's source, the key that signed it, its signature and
the state it left (:mod:`stand.archive.keys`); on PostgreSQL the journal's rows can no
longer be updated or deleted (a trigger refuses it, and the privileges are revoked).

Revision ID: 0010
Revises: 0009
Create Date: 2026-11-28
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0010"
down_revision = "0009"
branch_labels = None
depends_on = None

REFUSE = """
CREATE OR REPLACE FUNCTION stand_audit_append_only() RETURNS trigger AS $$
BEGIN
  RAISE EXCEPTION 'the audit trail is append-only: % refused', TG_OP;
END;
$$ LANGUAGE plpgsql
"""


def upgrade() -> None:
    with op.batch_alter_table("audit") as batch:
        batch.add_column(sa.Column("source", sa.String(16)))  # cli, station, opcua, ...
        batch.add_column(sa.Column("key_id", sa.String(16)))  # the signing key's id
        batch.add_column(sa.Column("signature", sa.String(128)))  # Ed25519, hex
        batch.add_column(sa.Column("detail", sa.Text))  # the state it left, JSON
    if op.get_bind().dialect.name == "postgresql":
        op.execute(REFUSE)
        op.execute(
            "CREATE TRIGGER audit_append_only BEFORE UPDATE OR DELETE OR TRUNCATE "
            "ON audit FOR EACH STATEMENT EXECUTE FUNCTION stand_audit_append_only()"
        )
        op.execute("REVOKE UPDATE, DELETE, TRUNCATE ON audit FROM PUBLIC, CURRENT_USER")


def downgrade() -> None:
    if op.get_bind().dialect.name == "postgresql":
        op.execute("DROP TRIGGER audit_append_only ON audit")
        op.execute("DROP FUNCTION stand_audit_append_only()")
    with op.batch_alter_table("audit") as batch:
        for name in ("detail", "signature", "key_id", "source"):
            batch.drop_column(name)
