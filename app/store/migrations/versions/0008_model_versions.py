"""Model versions and aliases: training again under a name makes its next version.

``models.name`` is no longer unique; ``(name, version)`` is, and every model stored before
is version 1 of its name.  ``model_aliases`` holds ``NAME@ALIAS -> version`` and
``model_alias_history`` each version an alias was set to (``rollback`` steps back).

SQLite cannot drop the unique constraint of a column in place: the table is rebuilt, and
dropping the old one deletes, by cascade, the rows that refer to it (``model_artifacts``),
so those are kept aside and put back (``PRAGMA foreign_keys`` cannot be turned off inside
the migration's transaction).

Revision ID: 0008
Revises: 0007
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0008"
down_revision = "0007"
branch_labels = None
depends_on = None

_KEY = "uq_models_name_version"
#: Tables whose rows refer to ``models`` with ON DELETE CASCADE, kept aside on SQLite.
_REFERRING = ("model_artifacts",)


def upgrade() -> None:
    sqlite = op.get_bind().dialect.name == "sqlite"
    if sqlite:
        _keep_referring()
        with op.batch_alter_table(
            "models",
            recreate="always",
            naming_convention={"uq": "uq_%(table_name)s_%(column_0_name)s"},
        ) as models:
            models.drop_constraint("uq_models_name", type_="unique")
            models.add_column(sa.Column("version", sa.Integer, nullable=False, server_default="1"))
            models.create_unique_constraint(_KEY, ["name", "version"])
        _put_back_referring()
    else:
        op.drop_constraint("models_name_key", "models", type_="unique")
        op.add_column(
            "models", sa.Column("version", sa.Integer, nullable=False, server_default="1")
        )
        op.create_unique_constraint(_KEY, "models", ["name", "version"])
    op.create_table(
        "model_aliases",
        sa.Column("name", sa.String(200), primary_key=True),
        sa.Column("alias", sa.String(100), primary_key=True),
        sa.Column("version", sa.Integer, nullable=False),
        sa.Column("set_at", sa.DateTime(timezone=True), nullable=False),
    )
    op.create_table(
        "model_alias_history",
        sa.Column("id", sa.Integer, primary_key=True),
        sa.Column("name", sa.String(200), nullable=False),
        sa.Column("alias", sa.String(100), nullable=False),
        sa.Column("version", sa.Integer, nullable=False),
        sa.Column("set_at", sa.DateTime(timezone=True), nullable=False),
        sa.Column("undone", sa.Boolean, nullable=False, server_default=sa.false()),
    )
    op.create_index("ix_model_alias_history_name", "model_alias_history", ["name"])


def downgrade() -> None:
    op.drop_index("ix_model_alias_history_name", "model_alias_history")
    op.drop_table("model_alias_history")
    op.drop_table("model_aliases")
    # Only version 1 of each name can keep its name under a unique constraint again.
    op.execute("DELETE FROM models WHERE version > 1")
    if op.get_bind().dialect.name == "sqlite":
        _keep_referring()
        with op.batch_alter_table("models", recreate="always") as models:
            models.drop_constraint(_KEY, type_="unique")
            models.drop_column("version")
            models.create_unique_constraint("uq_models_name", ["name"])
        _put_back_referring()
    else:
        op.drop_constraint(_KEY, "models", type_="unique")
        op.drop_column("models", "version")
        op.create_unique_constraint("models_name_key", "models", ["name"])


def _keep_referring() -> None:
    for table in _REFERRING:
        op.execute(f"CREATE TEMPORARY TABLE _kept_{table} AS SELECT * FROM {table}")


def _put_back_referring() -> None:
    for table in _REFERRING:
        # emptied by the cascade when foreign keys are enforced (the store's connections),
        # untouched otherwise
        op.execute(f"DELETE FROM {table}")
        op.execute(f"INSERT INTO {table} SELECT * FROM _kept_{table}")
        op.execute(f"DROP TABLE _kept_{table}")
