"""Printing: JSON on stdout for ``--json``, rich tables for people, messages on stderr."""

from __future__ import annotations

import json
import math
import sys
from collections.abc import Iterable, Sequence
from typing import Any

from rich.console import Console
from rich.table import Table

#: Pipes and files get a wide page: nobody wants a leaderboard wrapped at 80 columns.
console = Console(highlight=False, soft_wrap=False, width=None if sys.stdout.isatty() else 160)
err_console = Console(stderr=True, highlight=False)


def print_json(data: Any) -> None:
    """Only JSON on stdout: NaN and infinities become ``null``."""
    sys.stdout.write(json.dumps(_finite(data), indent=2, default=str) + "\n")
    sys.stdout.flush()


def info(message: str) -> None:
    """A note for people, on stderr so that stdout stays clean for pipes."""
    err_console.print(message)


def table(
    title: str | None,
    columns: Sequence[str],
    rows: Iterable[Sequence[Any]],
    *,
    justify: Sequence[str] | None = None,
) -> None:
    out = Table(title=title, title_justify="left", header_style="bold")
    for i, column in enumerate(columns):
        out.add_column(column, justify=(justify[i] if justify else "left"), no_wrap=i < 2)  # type: ignore[arg-type]
    for row in rows:
        out.add_row(*(format_cell(value) for value in row))
    console.print(out)


def format_cell(value: Any) -> str:
    if value is None:
        return "-"
    if isinstance(value, float):
        if math.isnan(value):
            return "-"
        return f"{value:.4f}" if abs(value) < 1e5 else f"{value:.4g}"
    return str(value)


def _finite(data: Any) -> Any:
    if isinstance(data, float) and not math.isfinite(data):
        return None
    if isinstance(data, dict):
        return {key: _finite(value) for key, value in data.items()}
    if isinstance(data, list | tuple):
        return [_finite(value) for value in data]
    return data
