"""The extract command: recordings -> touch events -> feature vectors -> a stored data set."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from app.cli.output import info, print_json, table
from app.cli.state import get_state


def register(app: typer.Typer) -> None:
    app.command("extract")(extract_command)


def extract_command(
    ctx: typer.Context,
    recordings: Annotated[
        list[Path],
        typer.Argument(metavar="RECORDING...", help="WAV/FLAC, CSV time series or .npy files."),
    ],
    labels: Annotated[
        Path | None,
        typer.Option(
            "--labels",
            help="CSV: file,start,end,TARGET... (seconds) or file,TARGET... (whole files).",
        ),
    ] = None,
    extractor: Annotated[
        str,
        typer.Option(
            "--extractor", "-e", help="uc3m-audio, band-peaks, mfcc, taxel-dft or window."
        ),
    ] = "uc3m-audio",
    events: Annotated[
        str | None,
        typer.Option("--events", help="snr, dbscan or none (default: the extractor's own)."),
    ] = None,
    name: Annotated[str | None, typer.Option("--name", help="Data set name in the store.")] = None,
    samplerate: Annotated[
        float | None,
        typer.Option(
            "--samplerate", help="Sample rate (Hz) of CSV/.npy files without a time column."
        ),
    ] = None,
    segment: Annotated[
        float | None,
        typer.Option("--segment", help="With --events none: cut files into segments of SECONDS."),
    ] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print only JSON on stdout.")] = False,
) -> None:
    """Detect touch events in recordings, extract features, and store them as a data set."""
    from app.services.extraction import extract_dataset
    from app.store.datasets import add_dataset, dataset_digest

    result = extract_dataset(
        recordings,
        labels=labels,
        extractor=extractor,
        events=events,
        name=name,
        samplerate=samplerate,
        segment=segment,
    )
    data = result.dataset
    dataset_info, created = add_dataset(
        get_state(ctx).store,
        data,
        sha256=dataset_digest(data),
        name=name,
        source_name=", ".join(p.name for p in recordings[:3])
        + (f" (+{len(recordings) - 3})" if len(recordings) > 3 else ""),
    )
    summary = {
        "id": dataset_info.id,
        "name": dataset_info.name,
        "n_instances": dataset_info.n_instances,
        "n_features": dataset_info.n_features,
        "targets": dataset_info.targets,
        "events_found": result.n_events,
        "events_labelled": result.n_labelled,
        "events_dropped": result.n_dropped,
        "warnings": result.warnings,
        "created": created,
    }
    if as_json:
        print_json(summary)
        return
    for warning in result.warnings:
        info(f"[yellow]warning:[/yellow] {warning}")
    if not created:
        info(f"the same features are already stored as dataset {dataset_info.id}")
    table(
        None,
        ["id", "name", "instances", "features", "targets", "events", "labelled", "dropped"],
        [
            (
                dataset_info.id,
                dataset_info.name,
                dataset_info.n_instances,
                dataset_info.n_features,
                ", ".join(dataset_info.targets),
                result.n_events,
                result.n_labelled,
                result.n_dropped,
            )
        ],
    )
