"""The extract command: recordings -> touch events -> feature vectors -> a stored data set."""

from __future__ import annotations

# Imports inside functions: start-up time. This module holds several commands and the
# one chosen loads only what it uses (the CLI imports the module when a command of it
# is chosen).
import sys
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.markup import escape

from touchbench.app.cli.output import info, print_json, table, warn
from touchbench.app.cli.state import get_state
from touchbench.app.errors import AppError


def register(app: typer.Typer) -> None:
    app.command("extract")(extract_command)
    app.command("extractors")(extractors_command)


def extractors_command(
    samplerate: Annotated[
        float | None,
        typer.Option(
            "--samplerate",
            metavar="HZ",
            help="Show the defaults that depend on the sample rate, computed for HZ.",
        ),
    ] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print only JSON on stdout.")] = False,
) -> None:
    """List the extractors and event detectors with every option (-O KEY=VALUE of extract):
    its type, default and meaning.
    """
    from touchbench.app.cli.requests import build_request
    from touchbench.app.schemas.extraction import ExtractorsRequest
    from touchbench.app.services.extractors import list_extractors

    listing = list_extractors(build_request(ExtractorsRequest, samplerate=samplerate))
    if as_json:
        print_json(listing.to_json())
        return
    rate = listing.samplerate
    for kind, entries in (("--extractor", listing.extractors), ("--events", listing.events)):
        for entry in entries:
            table(
                f"{kind} {entry.name}: {entry.description}",
                ["option", "type", "default", "meaning"],
                [(o.name, o.type, _default(o, rate), o.meaning) for o in entry.options]
                or [("(none)", "", "", "")],
            )


def _default(option: Any, rate: float | None) -> str:
    """The default as the listing shows it: the value, the rule, or the value at a rate."""
    if option.at_rate is not None:
        return f"{option.at_rate} at {rate:g} Hz"
    if option.default is None:
        return option.default_text or "-"
    if isinstance(option.default, bool):
        return "true" if option.default else "false"
    if isinstance(option.default, list):
        return ",".join("-".join(f"{v:g}" for v in pair) for pair in option.default)
    return str(option.default)


def extract_command(
    ctx: typer.Context,
    recordings: Annotated[
        list[Path],
        typer.Argument(
            metavar="RECORDING...",
            help="WAV/FLAC, CSV time series, .npy files or ROS bags (.bag, .mcap, .db3).",
        ),
    ],
    labels: Annotated[
        Path | None,
        typer.Option(
            "--labels",
            help="CSV: file,start,end,TARGET... (seconds) or file,TARGET... (whole files).",
        ),
    ] = None,
    extractor: Annotated[
        str | None,
        typer.Option(
            "--extractor",
            "-e",
            help="uc3m-audio (the default), band-peaks, mfcc, taxel-dft, window or sequence.",
        ),
    ] = None,
    events: Annotated[
        str | None,
        typer.Option("--events", help="snr, dbscan or none (default: the extractor's own)."),
    ] = None,
    name: Annotated[str | None, typer.Option("--name", help="Data set name in the store.")] = None,
    samplerate: Annotated[
        float | None,
        typer.Option(
            "--samplerate",
            help=(
                "Sample rate (Hz) of CSV/.npy files without a time column and of raw PCM in "
                "bags without AudioInfo; for --fields and CSV files with uneven stamps, the "
                "even grid's rate (default: the stamps' rate)."
            ),
        ),
    ] = None,
    time_column: Annotated[
        str | None,
        typer.Option(
            "--time-column",
            metavar="NAME",
            help=(
                "The time column of CSV files, when it is not named time, t, timestamp, "
                "stamp, header.stamp, %time, ..."
            ),
        ),
    ] = None,
    time_unit: Annotated[
        str,
        typer.Option(
            "--time-unit",
            metavar="UNIT",
            help=(
                "Unit of the CSV files' time column: s, ms, us or ns; auto: seconds or "
                "nanoseconds, told apart by magnitude."
            ),
        ),
    ] = "auto",
    segment: Annotated[
        float | None,
        typer.Option("--segment", help="With --events none: cut files into segments of SECONDS."),
    ] = None,
    topic: Annotated[
        str | None,
        typer.Option(
            "--topic",
            metavar="TOPIC",
            help="Topic of ROS bags: an audio topic (if several), or any topic to read its "
            "numeric fields as channels.",
        ),
    ] = None,
    fields: Annotated[
        list[str] | None,
        typer.Option(
            "--fields",
            metavar="A,B,...",
            help="Numeric fields of --topic as channels, e.g. pdc,pac,electrodes or "
            "wrench.force (arrays give pac[0], pac[1], ...; default: its numeric fields); "
            "for CSV files, the columns (names or 1-based numbers; default: all).",
        ),
    ] = None,
    channels: Annotated[
        int | None,
        typer.Option(
            "--channels", metavar="N", help="Channels of raw PCM audio in bags without AudioInfo."
        ),
    ] = None,
    sample_format: Annotated[
        str | None,
        typer.Option(
            "--sample-format",
            metavar="FORMAT",
            help="S16LE, S32LE or F32LE: raw PCM audio in bags without AudioInfo.",
        ),
    ] = None,
    option: Annotated[
        list[str] | None,
        typer.Option(
            "--option",
            "-O",
            metavar="KEY=VALUE",
            help=(
                "KEY=VALUE option of the extractor or the event detector, e.g. threshold=12; "
                "`touchbench extractors` lists them with their defaults."
            ),
        ),
    ] = None,
    max_event: Annotated[
        float | None,
        typer.Option("--max-event", metavar="S", help="Longest event in seconds (default 60)."),
    ] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print only JSON on stdout.")] = False,
) -> None:
    """Detect touch events in recordings, extract features, and store them as a data set.

    Recordings are read block by block (memory follows the longest event, not the
    recording); ROS bags (.bag, .mcap, .db3) are read for their audio_common audio (raw PCM
    or MP3), or for the numeric fields of a --topic, put on an even grid; CSV time series
    by their time column (--fields picks columns). `touchbench extractors` lists every
    extractor's options (-O KEY=VALUE) with their type, default and meaning.
    """
    from touchbench.app.cli.requests import build_request
    from touchbench.app.schemas.extraction import ExtractRequest
    from touchbench.app.services.extraction import extract_and_store

    request = build_request(
        ExtractRequest,
        {"recordings": "RECORDING...", "options": "--option"},
        recordings=recordings,
        labels=labels,
        extractor=extractor,
        events=events,
        name=name,
        samplerate=samplerate,
        segment=segment,
        options=key_values(option or [], "--option"),
        topic=topic,
        fields=_comma_list(fields),
        channels=channels,
        sample_format=sample_format,
        max_event=max_event,
        time_column=time_column,
        time_unit=time_unit,
    )
    with _Reading() as reading:
        summary = extract_and_store(get_state(ctx).store, request, on_progress=reading.update)
    if as_json:
        print_json(summary.to_json())
        return
    for note in summary.notes:
        info(f"note: {escape(note)}")
    for warning in summary.warnings:
        warn(warning)
    if not summary.created:
        info(f"the same features are already stored as dataset {summary.id}")
    table(
        None,
        ["id", "name", "instances", "features", "targets", "events", "labelled", "dropped"],
        [
            (
                summary.id,
                summary.name,
                summary.n_instances,
                summary.n_features,
                ", ".join(summary.targets),
                summary.events_found,
                summary.events_labelled,
                summary.events_dropped,
            )
        ],
    )


def _comma_list(values: list[str] | None) -> list[str] | None:
    """``["a,b", "c"]`` (the option given once or more) as ``["a", "b", "c"]``."""
    if not values:
        return None
    return [part.strip() for value in values for part in value.split(",") if part.strip()]


def key_values(pairs: list[str], option: str, what: str = "KEY=VALUE") -> dict[str, str]:
    """``["a=1", "b=2"]`` as ``{"a": "1", "b": "2"}``; AppError naming ``option`` if not."""
    found: dict[str, str] = {}
    for pair in pairs:
        key, sep, value = pair.partition("=")
        if not sep or not key.strip() or not value.strip():
            raise AppError(f"{option} must be {what}, got '{pair}'")
        found[key.strip()] = value.strip()
    return found


class _Reading:
    """A spinner with the recording being read and its seconds so far on stderr when it is
    a terminal, else a plain line per recording."""

    def __init__(self) -> None:
        from rich.console import Console
        from rich.progress import Progress, SpinnerColumn, TextColumn, TimeElapsedColumn

        self._progress = Progress(
            SpinnerColumn(),
            TextColumn("reading {task.fields[file]}: {task.fields[seconds]:.0f} s"),
            TimeElapsedColumn(),
            console=Console(stderr=True),
            transient=True,
            disable=not sys.stderr.isatty(),
        )
        self._task = self._progress.add_task("read", file="", seconds=0.0)
        # Without a terminal (a log, CI): one plain line per recording instead.
        self._lines = not sys.stderr.isatty()
        self._file = ""

    def __enter__(self) -> _Reading:
        self._progress.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._progress.stop()

    def update(self, file: str, seconds: float) -> None:
        self._progress.update(self._task, file=file, seconds=seconds)
        if self._lines and file != self._file:
            self._file = file
            print(f"progress: reading {file}", file=sys.stderr, flush=True)
