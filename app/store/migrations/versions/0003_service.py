"""What the service needs: run ownership and heartbeats (who is executing a run, and is it
still alive), cancellation, the reason a run failed; jobs (extraction, training) queued for
worker processes; the extraction recipe of a data set and of the models trained on it;
the format of model artifacts. Runs that finished under the old name 'finished' are 'done'.

Revision ID: 0003
Revises: 0002
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0003"
down_revision = "0002"
branch_labels = None
depends_on = None


def upgrade() -> None:
    with op.batch_alter_table("runs") as runs:
        runs.add_column(sa.Column("owner", sa.String(200)))
        runs.add_column(sa.Column("heartbeat_at", sa.DateTime(timezone=True)))
        runs.add_column(sa.Column("started_at", sa.DateTime(timezone=True)))
        runs.add_column(sa.Column("error", sa.Text))
        runs.add_column(
            sa.Column("cancel_requested", sa.Boolean, nullable=False, server_default=sa.false())
        )
    op.execute("UPDATE runs SET status = 'done' WHERE status = 'finished'")
    with op.batch_alter_table("datasets") as datasets:
        datasets.add_column(sa.Column("extraction", sa.JSON))
    with op.batch_alter_table("models") as models:
        models.add_column(sa.Column("extraction", sa.JSON))
        models.add_column(
            sa.Column("format", sa.String(20), nullable=False, server_default="pickle")
        )
    op.create_table(
        "jobs",
        sa.Column("id", sa.Integer, primary_key=True),
        sa.Column("kind", sa.String(20), nullable=False),
        sa.Column("status", sa.String(20), nullable=False),
        sa.Column("params", sa.JSON, nullable=False),
        sa.Column("result", sa.JSON),
        sa.Column("error", sa.Text),
        sa.Column("owner", sa.String(200)),
        sa.Column("heartbeat_at", sa.DateTime(timezone=True)),
        sa.Column("created_at", sa.DateTime(timezone=True), nullable=False),
        sa.Column("started_at", sa.DateTime(timezone=True)),
        sa.Column("finished_at", sa.DateTime(timezone=True)),
    )
    op.create_index("ix_jobs_status", "jobs", ["status"])


def downgrade() -> None:
    op.drop_index("ix_jobs_status", "jobs")
    op.drop_table("jobs")
    with op.batch_alter_table("models") as models:
        models.drop_column("format")
        models.drop_column("extraction")
    with op.batch_alter_table("datasets") as datasets:
        datasets.drop_column("extraction")
    op.execute("UPDATE runs SET status = 'finished' WHERE status = 'done'")
    with op.batch_alter_table("runs") as runs:
        for column in ("cancel_requested", "error", "started_at", "heartbeat_at", "owner"):
            runs.drop_column(column)
