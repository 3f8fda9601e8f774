"""``touchbench datasets``: the store's data sets, one line each.

Apart from :mod:`app.cli.datasets` (import, show, export, ...), whose file readers and
NumPy this command does not need: listing the store is the command people type most.
"""

from __future__ import annotations

import typer

from touchbench.app.cli.output import JsonOption, info, print_json, table
from touchbench.app.cli.state import get_state
from touchbench.app.schemas.datasets import DatasetList
from touchbench.app.services.listing import list_datasets


def register(app: typer.Typer) -> None:
    app.command("datasets")(datasets_command)


def datasets_command(ctx: typer.Context, as_json: JsonOption = False) -> None:
    """List the data sets in the store."""
    rows = list_datasets(get_state(ctx).reader)
    if as_json:
        print_json(DatasetList(datasets=rows).to_json())
        return
    if not rows:
        info("no datasets yet: `touchbench import FILE` adds one")
        return
    table(
        None,
        ["id", "name", "instances", "features", "targets", "source", "imported"],
        [
            (
                row.id,
                row.name,
                row.n_instances,
                row.n_features,
                ", ".join(row.targets),
                row.source,
                row.created_at.strftime("%Y-%m-%d %H:%M"),
            )
            for row in rows
        ],
        justify=["right", "left", "right", "right", "left", "left", "left"],
    )
