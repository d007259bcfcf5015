"""Alembic's environment for the archive: migrations run on the connection the archive
opened (``config.attributes["connection"]``), inside its transaction."""

from __future__ import annotations

from alembic import context

from stand.archive.schema import metadata

connection = context.config.attributes["connection"]
context.configure(connection=connection, target_metadata=metadata, render_as_batch=True)
with context.begin_transaction():
    context.run_migrations()
