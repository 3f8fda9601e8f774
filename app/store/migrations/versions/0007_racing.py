"""Raced runs: which entries stopped early and why, ``entry_drops``.

Revision ID: 0007
Revises: 0006
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
        "entry_drops",
        sa.Column(
            "run_id", sa.Integer, sa.ForeignKey("runs.id", ondelete="CASCADE"), primary_key=True
        ),
        sa.Column("classifier", sa.String(100), primary_key=True),
        sa.Column("reason", sa.String(20), nullable=False),
        sa.Column("after_fold", sa.Integer, nullable=False),
        sa.Column("p_value", sa.Float, nullable=True),
        sa.Column("leader", sa.String(100), nullable=True),
        sa.Column("mean", sa.Float, nullable=True),
    )


def downgrade() -> None:
    op.drop_table("entry_drops")
