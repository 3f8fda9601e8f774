"""Commands that answer questions after the leaderboard: the paper's published results
imported beside ours (``import-results``)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from app.cli.output import JsonOption, info, print_json, table
from app.cli.state import get_state


def register(app: typer.Typer) -> None:
    app.command("import-results")(import_results_command)


def import_results_command(
    ctx: typer.Context,
    file: Annotated[
        Path,
        typer.Argument(metavar="FILE", help="WEKA Experimenter results ARFF.", show_default=False),
    ],
    name: Annotated[
        str | None,
        typer.Option("--name", metavar="NAME", help="The run's name (default: WEKA FILE)."),
    ] = None,
    dataset: Annotated[
        str | None,
        typer.Option(
            "--dataset",
            metavar="DATASET",
            help=(
                "The stored data set the results are of (default: the one whose relation "
                "the file's Key_Dataset names)."
            ),
        ),
    ] = None,
    target: Annotated[
        str | None,
        typer.Option(
            "--target",
            metavar="NAME",
            help=(
                "The target the schemes predicted (default: the data set's only target, or "
                "the one WEKA's Remove filter in Key_Dataset left)."
            ),
        ),
    ] = None,
    as_json: JsonOption = False,
) -> None:
    """Import a WEKA Experimenter results file (InstanceResultListener ARFF) as a finished
    run, so that leaderboards and reports rank the paper's classifiers beside ours."""
    # start-up time: the ARFF reader and the store load with the command that uses them
    from app.cli.requests import build_request
    from app.schemas.imported import ImportResultsRequest
    from app.services.imported import import_results

    request = build_request(
        ImportResultsRequest,
        {"file": "FILE"},
        file=file,
        name=name,
        dataset=dataset,
        target=target,
    )
    run = import_results(get_state(ctx).store, request)
    if as_json:
        print_json(run.to_json())
        return
    schemes = run.config.get("schemes", [])
    table(
        f"run {run.id}: {run.config.get('name')} on {run.dataset_name} "
        f"({', '.join(run.targets)}), {run.config.get('folds')} folds x "
        f"{run.config.get('repeats')} runs, {run.n_results} results",
        ["classifier", "WEKA scheme", "options"],
        [(s["classifier"], s["scheme"], s["options"]) for s in schemes],
    )
    info(
        f"`touchbench leaderboard RUN --beside {run.id}` ranks these beside a run of yours "
        f"on {run.dataset_name}"
    )
