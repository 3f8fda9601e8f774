"""The model registry tied by foreign keys, as MLflow's: ``registered_models`` holds a row per
model name with the number its newest version ever took (``last_version``, which only
grows); ``models`` (one row per version), ``model_aliases`` and ``model_alias_history``
refer to it by ``registered_model_id`` instead of repeating the name, so that renaming is one
UPDATE and deleting one DELETE; an alias refers to its version by a foreign key and goes
with it.  Ids are AUTOINCREMENT on SQLite (a sequence already on PostgreSQL): an id, like a
version, is never given twice.

Every name found in ``models`` or in the aliases' history gets its parent row, with the
highest version either holds, so that a version deleted before this migration but still
named in the history is not given again.

SQLite cannot add a foreign key or AUTOINCREMENT to a table in place: ``models`` is
rebuilt, and dropping the old one deletes, by cascade, the rows that refer to it
(``model_artifacts``, ``model_exports``), so those are kept aside and put back, as in 0008.
The aliases and their history are small and referred to by nothing: on both stores they are
kept aside, created anew and filled again.

Revision ID: 0013
Revises: 0012
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import sqlalchemy as sa
from alembic import op

revision = "0013"
down_revision = "0012"
branch_labels = None
depends_on = None

_OLD_KEY = "uq_models_name_version"
_KEY = "uq_models_registered_model_version"
#: Tables whose rows refer to ``models`` with ON DELETE CASCADE, kept aside on SQLite.
_REFERRING = ("model_artifacts", "model_exports")
#: The columns of ``models`` other than its id, name (or parent) and version, in order.
_MODEL_COLUMNS = (
    "dataset_id",
    "run_id",
    "classifier",
    "params",
    "schema",
    "targets",
    "sha256",
    "size_bytes",
    "created_at",
    "extraction",
    "format",
)


def upgrade() -> None:
    op.create_table(
        "registered_models",
        sa.Column("id", sa.Integer, primary_key=True),
        sa.Column("name", sa.String(200), nullable=False, unique=True),
        sa.Column("last_version", sa.Integer, nullable=False),
        sa.Column("created_at", sa.DateTime(timezone=True), nullable=False),
        sqlite_autoincrement=True,
    )
    op.execute(
        "INSERT INTO registered_models (name, last_version, created_at) "
        "SELECT name, MAX(version), MIN(created_at) FROM ("
        " SELECT name, version, created_at FROM models"
        " UNION ALL SELECT name, version, set_at FROM model_alias_history"
        " UNION ALL SELECT name, version, set_at FROM model_aliases"
        ") AS named GROUP BY name ORDER BY MIN(created_at), name"
    )
    _keep_aside(
        "model_aliases",
        "SELECT r.id AS registered_model_id, a.alias, a.version, a.set_at FROM model_aliases a"
        " JOIN registered_models r ON r.name = a.name"
        " JOIN models m ON m.name = a.name AND m.version = a.version",
    )
    _keep_aside(
        "model_alias_history",
        "SELECT h.id, r.id AS registered_model_id, h.alias, h.version, h.set_at, h.undone"
        " FROM model_alias_history h JOIN registered_models r ON r.name = h.name",
    )
    op.drop_table("model_aliases")
    op.drop_index("ix_model_alias_history_name", "model_alias_history")
    op.drop_table("model_alias_history")
    if op.get_bind().dialect.name == "sqlite":
        _rebuild_models(upgraded=True)
    else:
        op.add_column("models", sa.Column("registered_model_id", sa.Integer))
        op.execute(
            "UPDATE models SET registered_model_id = "
            "(SELECT r.id FROM registered_models r WHERE r.name = models.name)"
        )
        op.alter_column("models", "registered_model_id", nullable=False)
        op.alter_column("models", "version", server_default=None)
        op.create_foreign_key(
            None, "models", "registered_models", ["registered_model_id"], ["id"], ondelete="CASCADE"
        )
        op.drop_constraint(_OLD_KEY, "models", type_="unique")
        op.create_unique_constraint(_KEY, "models", ["registered_model_id", "version"])
        op.drop_column("models", "name")
    _create_aliases(_parent_column)
    _put_back("model_aliases")
    _put_back("model_alias_history")


def downgrade() -> None:
    _keep_aside(
        "model_aliases",
        "SELECT r.name, a.alias, a.version, a.set_at FROM model_aliases a"
        " JOIN registered_models r ON r.id = a.registered_model_id",
    )
    _keep_aside(
        "model_alias_history",
        "SELECT h.id, r.name, h.alias, h.version, h.set_at, h.undone FROM model_alias_history h"
        " JOIN registered_models r ON r.id = h.registered_model_id",
    )
    op.drop_index("ix_model_alias_history_alias", "model_alias_history")
    op.drop_table("model_alias_history")
    op.drop_table("model_aliases")
    if op.get_bind().dialect.name == "sqlite":
        _rebuild_models(upgraded=False)
    else:
        op.add_column("models", sa.Column("name", sa.String(200)))
        op.execute(
            "UPDATE models SET name = "
            "(SELECT r.name FROM registered_models r WHERE r.id = models.registered_model_id)"
        )
        op.alter_column("models", "name", nullable=False)
        op.alter_column("models", "version", server_default="1")
        op.drop_constraint(_KEY, "models", type_="unique")
        op.drop_constraint("models_registered_model_id_fkey", "models", type_="foreignkey")
        op.drop_column("models", "registered_model_id")
        op.create_unique_constraint(_OLD_KEY, "models", ["name", "version"])
    _create_aliases(_name_column)
    _put_back("model_aliases")
    _put_back("model_alias_history")
    op.drop_table("registered_models")


def _parent_column(primary_key: bool) -> sa.Column[Any]:
    return sa.Column(
        "registered_model_id",
        sa.Integer,
        sa.ForeignKey("registered_models.id", ondelete="CASCADE"),
        primary_key=primary_key,
        nullable=False,
    )


def _name_column(primary_key: bool) -> sa.Column[Any]:
    return sa.Column("name", sa.String(200), primary_key=primary_key, nullable=False)


def _create_aliases(owner: Callable[[bool], sa.Column[Any]]) -> None:
    """``model_aliases`` and ``model_alias_history`` with ``owner`` naming their model (the
    parent's id after this revision, the name before it)."""
    upgraded = owner is _parent_column
    op.create_table(
        "model_aliases",
        owner(True),
        sa.Column("alias", sa.String(100), primary_key=True),
        sa.Column("version", sa.Integer, nullable=False),
        sa.Column("set_at", sa.DateTime(timezone=True), nullable=False),
        *(
            [
                sa.ForeignKeyConstraint(
                    ["registered_model_id", "version"],
                    ["models.registered_model_id", "models.version"],
                    ondelete="CASCADE",
                    name="fk_model_aliases_version",
                )
            ]
            if upgraded
            else []
        ),
    )
    op.create_table(
        "model_alias_history",
        sa.Column("id", sa.Integer, primary_key=True),
        owner(False),
        sa.Column("alias", sa.String(100), nullable=False),
        sa.Column("version", sa.Integer, nullable=False),
        sa.Column("set_at", sa.DateTime(timezone=True), nullable=False),
        sa.Column("undone", sa.Boolean, nullable=False, server_default=sa.false()),
        sqlite_autoincrement=upgraded,
    )
    if upgraded:
        op.create_index(
            "ix_model_alias_history_alias",
            "model_alias_history",
            ["registered_model_id", "alias", "id"],
        )
    else:
        op.create_index("ix_model_alias_history_name", "model_alias_history", ["name"])


def _keep_aside(table: str, select: str) -> None:
    op.execute(f"CREATE TEMPORARY TABLE _kept_{table} AS {select}")


def _put_back(table: str) -> None:
    op.execute(f"INSERT INTO {table} SELECT * FROM _kept_{table}")
    op.execute(f"DROP TABLE _kept_{table}")
    if table == "model_alias_history" and op.get_bind().dialect.name == "postgresql":
        # the ids were copied: the new table's sequence starts after them
        op.execute(
            "SELECT setval(pg_get_serial_sequence('model_alias_history', 'id'), "
            "COALESCE(MAX(id), 0) + 1, false) FROM model_alias_history"
        )


def _model_columns() -> list[sa.Column[Any]]:
    return [
        sa.Column("dataset_id", sa.Integer, sa.ForeignKey("datasets.id", ondelete="SET NULL")),
        sa.Column("run_id", sa.Integer, sa.ForeignKey("runs.id", ondelete="SET NULL")),
        sa.Column("classifier", sa.String(100), nullable=False),
        sa.Column("params", sa.JSON, nullable=False),
        sa.Column("schema", sa.JSON, nullable=False),
        sa.Column("targets", sa.JSON, nullable=False),
        sa.Column("sha256", sa.String(64), nullable=False),
        sa.Column("size_bytes", sa.Integer, nullable=False),
        sa.Column("created_at", sa.DateTime(timezone=True), nullable=False),
        sa.Column("extraction", sa.JSON),
        sa.Column("format", sa.String(20), nullable=False, server_default="pickle"),
    ]


def _registered_models_table(name: str) -> None:
    op.create_table(
        name,
        sa.Column("id", sa.Integer, primary_key=True),
        _parent_column(False),
        sa.Column("version", sa.Integer, nullable=False),
        *_model_columns(),
        sa.UniqueConstraint("registered_model_id", "version", name=_KEY),
        sqlite_autoincrement=True,
    )


def _named_models_table(name: str) -> None:
    op.create_table(
        name,
        sa.Column("id", sa.Integer, primary_key=True),
        sa.Column("name", sa.String(200), nullable=False),
        *_model_columns(),
        sa.Column("version", sa.Integer, nullable=False, server_default="1"),
        sa.UniqueConstraint("name", "version", name=_OLD_KEY),
    )


def _copy_models(new: str, *, owner: str, value: str, join: str) -> str:
    """The statement that fills ``new`` from ``models``, naming each version's model by
    the column ``owner``, whose ``value`` comes from ``registered_models r`` joined ``join``."""
    columns = ", ".join(_MODEL_COLUMNS)
    picked = ", ".join(f"m.{column}" for column in _MODEL_COLUMNS)
    return (
        f"INSERT INTO {new} (id, {owner}, version, {columns}) "
        f"SELECT m.id, {value}, m.version, {picked} FROM models m "
        f"JOIN registered_models r ON {join}"
    )


def _rebuild_models(*, upgraded: bool) -> None:
    """SQLite: ``models`` made anew with its versions under their registered model
    (``upgraded``) or their name, with the rows that refer to it kept aside meanwhile."""
    for table in _REFERRING:
        _keep_aside(table, f"SELECT * FROM {table}")
    if upgraded:
        _registered_models_table("_models_new")
        op.execute(
            _copy_models(
                "_models_new", owner="registered_model_id", value="r.id", join="r.name = m.name"
            )
        )
    else:
        _named_models_table("_models_new")
        op.execute(
            _copy_models(
                "_models_new", owner="name", value="r.name", join="r.id = m.registered_model_id"
            )
        )
    op.drop_table("models")
    op.rename_table("_models_new", "models")
    for table in _REFERRING:
        # emptied by the cascade when foreign keys are enforced (the store's connections),
        # untouched otherwise
        op.execute(f"DELETE FROM {table}")
        _put_back(table)
