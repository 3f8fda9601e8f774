"""Printing: JSON on stdout for ``--json``, rich tables for people, messages on stderr."""

from __future__ import annotations

import json
import math
import re
import sys
from collections.abc import Collection, Iterable, Sequence
from typing import TYPE_CHECKING, Annotated, Any

import typer
from rich.console import Console
from rich.markup import escape
from rich.table import Table

# Defined where app.cli.main finds them without rich's tables; commands take them from here.
from touchbench.app.cli.exits import EXIT_FAILED as EXIT_FAILED
from touchbench.app.cli.exits import EXIT_INTERRUPTED as EXIT_INTERRUPTED
from touchbench.app.cli.exits import ExitWith as ExitWith
from touchbench.app.schemas.base import finite

if TYPE_CHECKING:
    from touchbench.app.reports.run_tables import RunTable

#: The ``--json`` flag of every listing and result command.
JsonOption = Annotated[bool, typer.Option("--json", help="Print only JSON on stdout.")]

#: Pipes and files get a wide page: nobody wants a leaderboard wrapped at 80 columns.
console = Console(highlight=False, soft_wrap=False, width=None if sys.stdout.isatty() else 160)
#: Messages are never wrapped: a command quoted in a message must stay pasteable.
err_console = Console(stderr=True, highlight=False, soft_wrap=True)
#: Longest text shown in a table cell; the rest is elided (``--json`` has it whole).
MAX_CELL = 60
_CONTROL = re.compile(r"[\x00-\x1f\x7f-\x9f]")


def print_json(data: Any) -> None:
    """Only JSON on stdout: NaN and infinities become ``null``."""
    sys.stdout.write(json.dumps(finite(data), indent=2, default=str) + "\n")
    sys.stdout.flush()


def info(message: str) -> None:
    """A note for people, on stderr so that stdout stays clean for pipes."""
    err_console.print(message)


def warn(message: str) -> None:
    """Something changed or left out that the user should know of, on stderr."""
    err_console.print(f"[yellow]warning:[/yellow] {escape(message)}")


def run_table(shown: RunTable) -> None:
    """A titled table of text cells (:mod:`app.reports.run_tables`), numbers on the right."""
    table(
        shown.title,
        list(shown.header),
        shown.rows,
        justify=["right" if numeric else "left" for numeric in shown.numeric],
    )


def table(
    title: str | None,
    columns: Sequence[str],
    rows: Iterable[Sequence[Any]],
    *,
    justify: Sequence[str] | None = None,
    whole: Collection[str] = (),
) -> None:
    """Print a table; the first two columns and those named in ``whole`` are never wrapped
    nor cut."""
    cells = [[format_cell(value) for value in row] for row in rows]
    out = Table(title=title, title_justify="left", header_style="bold")
    for i, column in enumerate(columns):
        out.add_column(
            column,
            justify=(justify[i] if justify else "left"),  # type: ignore[arg-type]
            no_wrap=i < 2 or column in whole,
            min_width=max([len(column), *(len(row[i]) for row in cells)])
            if column in whole
            else None,
        )
    for row in cells:
        out.add_row(*row)
    console.print(out)


def format_cell(value: Any) -> str:
    """A value as a table shows it: numbers to 4 decimals, text made safe and short."""
    if value is None:
        return "-"
    if isinstance(value, float):
        if math.isnan(value):
            return "-"
        return f"{value:.4f}" if abs(value) < 1e5 else f"{value:.4g}"
    return escape(printable(str(value)))


def printable(text: str, limit: int = MAX_CELL) -> str:
    """``text`` with control characters shown as ``?`` and cut to ``limit`` characters."""
    text = _CONTROL.sub("?", text)
    return text if len(text) <= limit else text[: limit - 1] + "…"


#: ``--engine``: what runs a model's predictions (``predict``, ``live``, ``ros``).
EngineOption = Annotated[
    str | None,
    typer.Option(
        "--engine",
        metavar="ENGINE",
        help="What runs the predictions: onnx (the model's ONNX twin, written by "
        "`touchbench export-model`), native (the model itself), auto (the twin where the "
        "model has one).",
        show_default="auto",
    ),
]


#: ``--aggregate`` of a finished run's views (``leaderboard``, ``plot``, ``report``,
#: ``classes``, ``calibration``): its stored test-fold predictions scored again, nothing fitted.
RescoreOption = Annotated[
    str | None,
    typer.Option(
        "--aggregate",
        metavar="window|recording",
        help=(
            "Score each recording's windows as one prediction (recording) or each "
            "window (window), from the run's stored test-fold predictions: nothing is "
            "fitted again. Default: as the run was scored. recording needs a data set "
            "extracted from recordings, one label per recording, and a run that stored "
            "its predictions (not an imported one)."
        ),
        show_default=False,
    ),
]
