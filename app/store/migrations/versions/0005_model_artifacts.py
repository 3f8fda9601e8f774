"""Model artifacts in a table of their own: ``model_artifacts`` holds the bytes, ``models``
keeps the small columns.

SQLite reads a row's columns in order and reaches any column stored after a large value by
walking that value's overflow pages: with the artifact inside ``models``, reading a model's
sha256 (every served prediction checks it) or listing the models read every artifact's pages
(2 ms for a 100-tree forest).

Revision ID: 0005
Revises: 0004
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0005"
down_revision = "0004"
branch_labels = None
depends_on = None

_models = sa.table("models", sa.column("id", sa.Integer), sa.column("artifact", sa.LargeBinary))
_artifacts = sa.table(
    "model_artifacts", sa.column("model_id", sa.Integer), sa.column("artifact", sa.LargeBinary)
)


def upgrade() -> None:
    op.create_table(
        "model_artifacts",
        sa.Column(
            "model_id",
            sa.Integer,
            sa.ForeignKey("models.id", ondelete="CASCADE"),
            primary_key=True,
        ),
        sa.Column("artifact", sa.LargeBinary, nullable=False),
    )
    op.execute(
        _artifacts.insert().from_select(
            ["model_id", "artifact"], sa.select(_models.c.id, _models.c.artifact)
        )
    )
    # Not batch mode: SQLite would rebuild ``models``, and dropping the old table deletes
    # the artifacts just copied (ON DELETE CASCADE); SQLite drops a column in place.
    op.drop_column("models", "artifact")


def downgrade() -> None:
    with op.batch_alter_table("models") as models:
        models.add_column(sa.Column("artifact", sa.LargeBinary))
    bind = op.get_bind()
    for model_id, artifact in bind.execute(sa.select(_artifacts.c.model_id, _artifacts.c.artifact)):
        bind.execute(_models.update().where(_models.c.id == model_id).values(artifact=artifact))
    with op.batch_alter_table("models") as models:
        models.alter_column("artifact", existing_type=sa.LargeBinary, nullable=False)
    op.drop_table("model_artifacts")
