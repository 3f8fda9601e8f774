"""Commands for data sets: import, datasets, show, export, rename, delete."""

from __future__ import annotations

# Imports inside functions: start-up time. This module holds several commands and the
# one chosen loads only what it uses (the CLI imports the module when a command of it
# is chosen).
import os
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.markup import escape
from rich.progress import BarColumn, DownloadColumn, Progress, TextColumn, TimeRemainingColumn

from touchbench.app.cli.output import JsonOption, info, print_json, table
from touchbench.app.cli.state import get_state
from touchbench.app.errors import AppError
from touchbench.app.schemas.datasets import (
    AttributeDescription,
    DatasetDescription,
    ImportResult,
    RenameRequest,
)
from touchbench.app.services import datasets as service
from touchbench.app.services.datasets import ImportProgress
from touchbench.app.store.database import Store

DatasetArgument = Annotated[
    str, typer.Argument(metavar="DATASET", help="Data set name or id.", show_default=False)
]


def register(app: typer.Typer) -> None:
    app.command("import")(import_command)
    app.command("show")(show_command)
    app.command("export")(export_command)
    app.command("rename")(rename_command)
    app.command("delete")(delete_command)


def import_command(
    ctx: typer.Context,
    file: Annotated[
        Path, typer.Argument(metavar="FILE", help="ARFF or CSV file.", show_default=False)
    ],
    name: Annotated[
        str | None,
        typer.Option(
            "--name",
            metavar="NAME",
            help="Name in the store (default: the file name without its ending).",
        ),
    ] = None,
    targets: Annotated[
        str | None,
        typer.Option(
            "--targets",
            metavar="N|NAMES",
            help=(
                "Targets: N first attributes, -N last ones, or comma-separated names. "
                "Default: MEKA's '-C N' in the relation, else the last attribute (WEKA)."
            ),
        ),
    ] = None,
    file_format: Annotated[
        str | None,
        typer.Option(
            "--format", metavar="arff|csv", help="File format (default: by the file's ending)."
        ),
    ] = None,
    groups: Annotated[
        str | None,
        typer.Option(
            "--groups",
            metavar="COLUMN",
            help=(
                "The column naming each instance's group (object, subject, session): kept "
                "as the instances' groups for grouped folds, never as a feature."
            ),
        ),
    ] = None,
    ignore: Annotated[
        str | None,
        typer.Option("--ignore", metavar="COLUMNS", help="Comma-separated columns to leave out."),
    ] = None,
    as_json: JsonOption = False,
) -> None:
    """Import an ARFF or CSV file as a data set, named after the file.

    Nothing is stored from a file with an error, and known content is never stored twice.
    """
    from touchbench.app.cli.requests import build_request
    from touchbench.app.schemas.datasets import ImportRequest

    request = build_request(
        ImportRequest,
        {"file": "FILE", "format": "--format"},
        file=file,
        name=name,
        targets=targets,
        format=file_format,
        groups=groups,
        ignore=ignore,
    )
    store = get_state(ctx).store
    with _import_progress(enabled=not as_json and sys.stderr.isatty()) as progress:
        result = service.import_file(store, request, progress=progress)
    if as_json:
        print_json(result.to_json())
        return
    for note in result.notes:
        info(f"note: {note}")
    _print_summary(result)
    _print_groups(result)


@contextmanager
def _import_progress(*, enabled: bool) -> Iterator[ImportProgress | None]:
    """A byte-count progress bar on stderr (a terminal only), as an import callback."""
    if not enabled:
        yield None
        return
    bar = Progress(
        TextColumn("{task.description}"),
        BarColumn(),
        DownloadColumn(),
        TimeRemainingColumn(),
        console=Console(stderr=True),
        transient=True,
    )
    task = bar.add_task("checking", total=None)

    def update(what: str, done: int, total: int) -> None:
        bar.update(task, description=what, completed=done, total=total)

    with bar:
        yield update


def show_command(ctx: typer.Context, dataset: DatasetArgument, as_json: JsonOption = False) -> None:
    """Show a data set's schema, class distribution per target and missing values."""
    description = service.describe_dataset(get_state(ctx).store, dataset)
    if as_json:
        print_json(description.to_json())
        return
    _print_summary(description)
    _print_groups(description)
    table(
        "attributes",
        ["#", "name", "role", "type", "labels / range", "missing"],
        [
            (i + 1, a.name, a.role, a.kind, _labels_or_range(a), a.missing)
            for i, a in enumerate(description.attributes)
        ],
        justify=["right", "left", "left", "left", "left", "right"],
    )
    for target, counts in description.class_distribution.items():
        total = sum(counts.values()) or 1
        table(
            f"class distribution of {target}",
            ["label", "instances", "share"],
            [(label, n, f"{100 * n / total:.1f} %") for label, n in counts.items()],
            justify=["left", "right", "right"],
        )
    for note in description.notes:
        info(f"note: {note}")
    info(f"missing values: {description.missing_values}")


def export_command(
    ctx: typer.Context,
    dataset: DatasetArgument,
    output: Annotated[
        Path | None,
        typer.Option("-o", "--output", metavar="FILE", help="File to write (default: stdout)."),
    ] = None,
    force: Annotated[
        bool, typer.Option("--force", metavar="", help="Replace FILE if it exists.")
    ] = False,
) -> None:
    """Write a data set back as ARFF (the relation keeps MEKA's -C header for its targets).

    A file is written whole or not at all; an existing file is replaced only with --force.
    """
    store = get_state(ctx).store
    if output is None:
        _export_to_stdout(store, dataset)
        return
    count = service.export_to_file(store, dataset, output, force=force)
    info(f"wrote {count} instances to {output}")


def _export_to_stdout(store: Store, dataset: str) -> None:
    try:
        service.export_dataset(store, dataset, sys.stdout)
        sys.stdout.flush()
    except BrokenPipeError:
        # The reader went away (`export mini | head`): not an error, and nothing more to say.
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except OSError as error:
        raise AppError(f"cannot write to the standard output: {error.strerror}") from None


def rename_command(
    ctx: typer.Context,
    dataset: DatasetArgument,
    new_name: Annotated[
        str, typer.Argument(metavar="NEW", help="The new name.", show_default=False)
    ],
) -> None:
    """Give a data set another name."""
    from touchbench.app.cli.requests import build_request

    request = build_request(RenameRequest, {"name": "NEW"}, name=new_name)
    renamed = service.rename_dataset(get_state(ctx).store, dataset, request)
    info(f"renamed dataset {renamed.id} '{renamed.previous_name}' to '{renamed.name}'")


def delete_command(ctx: typer.Context, dataset: DatasetArgument) -> None:
    """Delete a data set with its instances, runs and results (not while a run uses it)."""
    gone = service.delete_dataset(get_state(ctx).store, dataset)
    info(f"deleted dataset {gone.id} '{gone.name}' ({gone.n_instances} instances)")


def _print_summary(result: ImportResult | DatasetDescription) -> None:
    table(
        None,
        ["id", "name", "instances", "features", "targets"],
        [
            (
                result.id,
                result.name,
                result.n_instances,
                result.n_features,
                ", ".join(result.targets),
            )
        ],
        justify=["right", "left", "right", "right", "left"],
    )


def _print_groups(result: ImportResult | DatasetDescription) -> None:
    """One line saying how many groups the instances fall into, and what named them."""
    groups = result.groups
    if groups is None:
        return
    named = f"column '{escape(groups.column)}'" if groups.column else "the recordings"
    info(f"groups: {groups.count}, from {named}")


def _labels_or_range(attribute: AttributeDescription) -> str:
    if attribute.values is not None:
        shown = ", ".join(attribute.values[:6])
        more = len(attribute.values) - 6
        return shown + (f", ... ({len(attribute.values)})" if more > 0 else "")
    if attribute.min is not None and attribute.max is not None:
        return f"{attribute.min:.4g} .. {attribute.max:.4g}"
    return ""
