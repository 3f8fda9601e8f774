"""Data sets and their instances.

Revision ID: 0001
Revises:
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0001"
down_revision = None
branch_labels = None
depends_on = None


def upgrade() -> None:
    op.create_table(
        "datasets",
        sa.Column("id", sa.Integer, primary_key=True),
        sa.Column("name", sa.String(200), nullable=False, unique=True),
        sa.Column("relation", sa.Text, nullable=False),
        sa.Column("schema", sa.JSON, nullable=False),
        sa.Column("target_names", sa.JSON, nullable=False),
        sa.Column("n_instances", sa.Integer, nullable=False),
        sa.Column("n_attributes", sa.Integer, nullable=False),
        sa.Column("sparse", sa.Boolean, nullable=False),
        sa.Column("source_name", sa.Text),
        sa.Column("sha256", sa.String(64), nullable=False),
        sa.Column("created_at", sa.DateTime(timezone=True), nullable=False),
    )
    op.create_index("ix_datasets_sha256", "datasets", ["sha256"])
    op.create_table(
        "instances",
        sa.Column(
            "dataset_id",
            sa.Integer,
            sa.ForeignKey("datasets.id", ondelete="CASCADE"),
            primary_key=True,
        ),
        sa.Column("position", sa.Integer, primary_key=True),
        sa.Column("data", sa.LargeBinary, nullable=False),
        sa.Column("weight", sa.Float),
        sa.Column("group_id", sa.Text),
        sa.Column("meta", sa.JSON),
    )


def downgrade() -> None:
    op.drop_table("instances")
    op.drop_index("ix_datasets_sha256", "datasets")
    op.drop_table("datasets")
