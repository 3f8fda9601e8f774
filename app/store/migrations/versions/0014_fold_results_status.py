"""An index of fold results by run and status, ``ix_fold_results_run_status``: the progress
a run's page polls every second counts the run's results and its failures
(:func:`~app.store.run_progress.run_progress`, :func:`~app.store.runs.results_version`),
which the index answers by itself, without reading a row of the table (each row holds its
metrics and confusion matrix: a run of 30,000 fold results reads megabytes otherwise).

Revision ID: 0014
Revises: 0013
"""

from __future__ import annotations

from alembic import op

revision = "0014"
down_revision = "0013"
branch_labels = None
depends_on = None


def upgrade() -> None:
    op.create_index("ix_fold_results_run_status", "fold_results", ["run_id", "status"])


def downgrade() -> None:
    op.drop_index("ix_fold_results_run_status", "fold_results")
