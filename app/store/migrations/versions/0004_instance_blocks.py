"""Instances stored in blocks: ``instance_blocks`` holds the values and weights of
consecutive instances (about 1 MB of values a row), ``instances`` keeps only the group and
metadata of the instances that have any.  Existing data sets are moved, block by block.

Revision ID: 0004
Revises: 0003
"""

from __future__ import annotations

import numpy as np
import sqlalchemy as sa
from alembic import op

revision = "0004"
down_revision = "0003"
branch_labels = None
depends_on = None

_BLOCK_BYTES = 1 << 20
_F8 = np.dtype("<f8")

_datasets = sa.table("datasets", sa.column("id", sa.Integer), sa.column("n_attributes", sa.Integer))
_instances = sa.table(
    "instances",
    sa.column("dataset_id", sa.Integer),
    sa.column("position", sa.Integer),
    sa.column("data", sa.LargeBinary),
    sa.column("weight", sa.Float),
    sa.column("group_id", sa.Text),
    sa.column("meta", sa.JSON),
)
_blocks = sa.table(
    "instance_blocks",
    sa.column("dataset_id", sa.Integer),
    sa.column("start", sa.Integer),
    sa.column("n_rows", sa.Integer),
    sa.column("data", sa.LargeBinary),
    sa.column("weights", sa.LargeBinary),
)


def upgrade() -> None:
    op.create_table(
        "instance_blocks",
        sa.Column(
            "dataset_id",
            sa.Integer,
            sa.ForeignKey("datasets.id", ondelete="CASCADE"),
            primary_key=True,
        ),
        sa.Column("start", sa.Integer, primary_key=True),
        sa.Column("n_rows", sa.Integer, nullable=False),
        sa.Column("data", sa.LargeBinary, nullable=False),
        sa.Column("weights", sa.LargeBinary),
    )
    bind = op.get_bind()
    if bind.dialect.name == "postgresql":
        # Out of line without compression: PostgreSQL's would try (and fail) to compress
        # every megabyte of float64, which makes an import four times slower.
        op.execute(
            "ALTER TABLE instance_blocks ALTER COLUMN data SET STORAGE EXTERNAL, "
            "ALTER COLUMN weights SET STORAGE EXTERNAL"
        )
    for dataset_id, n_attributes in bind.execute(
        sa.select(_datasets.c.id, _datasets.c.n_attributes)
    ).all():
        rows = max(1, _BLOCK_BYTES // (_F8.itemsize * max(1, n_attributes)))
        result = bind.execute(
            sa.select(_instances.c.position, _instances.c.data, _instances.c.weight)
            .where(_instances.c.dataset_id == dataset_id)
            .order_by(_instances.c.position)
            .execution_options(stream_results=True, yield_per=rows)
        )
        for part in result.partitions():
            weights = None
            if any(weight is not None for _, _, weight in part):
                scale = [1.0 if weight is None else weight for _, _, weight in part]
                weights = np.array(scale, dtype=_F8).tobytes()
            bind.execute(
                _blocks.insert().values(
                    dataset_id=dataset_id,
                    start=part[0][0],
                    n_rows=len(part),
                    data=b"".join(bytes(data) for _, data, _ in part),
                    weights=weights,
                )
            )
    bind.execute(
        _instances.delete().where(_instances.c.group_id.is_(None) & _instances.c.meta.is_(None))
    )
    with op.batch_alter_table("instances") as instances:
        instances.drop_column("data")
        instances.drop_column("weight")


def downgrade() -> None:
    with op.batch_alter_table("instances") as instances:
        instances.add_column(sa.Column("data", sa.LargeBinary))
        instances.add_column(sa.Column("weight", sa.Float))
    bind = op.get_bind()
    for (dataset_id,) in bind.execute(sa.select(_datasets.c.id)).all():
        with_extras = set(
            bind.execute(
                sa.select(_instances.c.position).where(_instances.c.dataset_id == dataset_id)
            ).scalars()
        )
        blocks = bind.execute(
            sa.select(_blocks.c.start, _blocks.c.n_rows, _blocks.c.data, _blocks.c.weights)
            .where(_blocks.c.dataset_id == dataset_id)
            .order_by(_blocks.c.start)
            .execution_options(stream_results=True, yield_per=1)
        )
        for start, n_rows, data, weights in blocks:
            width = len(data) // n_rows
            scale = None if weights is None else np.frombuffer(weights, dtype=_F8).tolist()
            for i in range(n_rows):
                position = start + i
                values = {
                    "data": bytes(data[i * width : (i + 1) * width]),
                    "weight": None if scale is None else scale[i],
                }
                if position in with_extras:
                    bind.execute(
                        _instances.update()
                        .where(_instances.c.dataset_id == dataset_id)
                        .where(_instances.c.position == position)
                        .values(**values)
                    )
                else:
                    bind.execute(
                        _instances.insert().values(
                            dataset_id=dataset_id, position=position, **values
                        )
                    )
    with op.batch_alter_table("instances") as instances:
        instances.alter_column("data", existing_type=sa.LargeBinary, nullable=False)
    op.drop_table("instance_blocks")
