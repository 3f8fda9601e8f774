"""Read every ARFF file of the reference datasets with liac-arff and with touchbench.

Each file is read several times by each library in this one run; the table shows the
best time of each and the speed ratio (liac-arff time / touchbench time).  The values
both libraries read are compared, and a disagreement is reported.

Usage::

    .venv/bin/python perf/arff_read.py [DATASETS_FOLDER] [--repeat N]
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from collections.abc import Callable
from functools import partial
from pathlib import Path
from typing import Any

import arff  # liac-arff

from benchmark.dataset import Dataset
from benchmark.errors import DataFormatError
from benchmark.io.arff import read_arff
from benchmark.io.dates import DateFormat

DEFAULT_FOLDER = Path(__file__).resolve().parents[1].parent / "shared" / "datasets"


def best_time(read: Callable[[], Any], repeat: int) -> tuple[float, Any]:
    """The shortest of ``repeat`` timed calls of ``read``, and its last result."""
    best = math.inf
    result = None
    for _ in range(repeat):
        start = time.perf_counter()
        result = read()
        best = min(best, time.perf_counter() - start)
    return best, result


def shorten(text: str, width: int) -> str:
    return text if len(text) <= width else text[: width - 3] + "..."


def read_with_liac(path: Path) -> dict[str, Any]:
    with open(path, encoding="utf-8") as stream:
        return arff.load(stream)


def disagreement(ours: Dataset, theirs: dict[str, Any]) -> str | None:
    """Where liac-arff's reading differs from ours, ``None`` if nowhere."""
    attributes = ours.schema.attributes
    if [name for name, _ in theirs["attributes"]] != [a.name for a in attributes]:
        return "attribute names differ"
    if len(theirs["data"]) != ours.n_instances:
        return f"{len(theirs['data'])} rows against {ours.n_instances}"
    for j, attribute in enumerate(attributes):
        column = ours.values[:, j]
        if attribute.kind in ("nominal", "string"):
            mine: list[Any] = [attribute.label(value) for value in column]
        elif attribute.kind == "date":
            date_format = DateFormat(attribute.date_format)
            mine = [None if math.isnan(v) else date_format.format(v) for v in column]
        else:
            mine = [None if math.isnan(v) else float(v) for v in column]
        their_column = [row[j] for row in theirs["data"]]
        if attribute.kind == "date":
            their_column = [
                None if t is None else date_format.format(date_format.parse(t))
                for t in their_column
            ]
        if mine != their_column:
            return f"values of attribute '{attribute.name}' differ"
    return None


def table_row(path: Path, folder: Path, repeat: int) -> str:
    """One line of the table: both libraries' best times, their ratio and the check."""
    ours: Dataset | None = None
    theirs: dict[str, Any] | None = None
    ours_failure = liac_failure = ""
    ours_seconds = liac_seconds = math.nan
    try:
        ours_seconds, ours = best_time(partial(read_arff, path), repeat)
    except DataFormatError as error:
        ours_failure = f"line {error.line}: {error.message}"
    try:
        liac_seconds, theirs = best_time(partial(read_with_liac, path), repeat)
    except Exception as error:  # liac-arff raises many kinds; each is reported
        liac_failure = shorten(f"{type(error).__name__}: {error}", 90)

    shape = "-" if ours is None else f"{ours.values.shape[0]} x {ours.values.shape[1]}"
    liac_text = f"{'fails':>12}" if liac_failure else f"{liac_seconds:12.4f}"
    ours_text = f"{'fails':>13}" if ours_failure else f"{ours_seconds:13.4f}"
    ratio = f"{'-':>7}" if liac_failure or ours_failure else f"{liac_seconds / ours_seconds:6.1f}x"
    if ours is not None and theirs is not None:
        check = disagreement(ours, theirs) or "values agree"
    else:
        failures = (("liac-arff", liac_failure), ("touchbench", ours_failure))
        check = "; ".join(f"{who} fails: {why}" for who, why in failures if why)
    name = str(path.relative_to(folder))
    return f"{name:<44} {shape:>17} {liac_text} {ours_text} {ratio}  {check}"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", nargs="?", type=Path, default=DEFAULT_FOLDER)
    parser.add_argument("--repeat", type=int, default=5)
    options = parser.parse_args()
    folder: Path = options.folder
    if not folder.is_dir():
        print(
            f"no datasets folder at {folder}: pass the folder of the reference datasets "
            "(../shared/datasets beside the repository)",
            file=sys.stderr,
        )
        return 2
    files = sorted(folder.rglob("*.arff"))
    if not files:
        print(f"no .arff files under {folder}", file=sys.stderr)
        return 2

    print(f"best of {options.repeat} reads per file and library\n")
    print(
        f"{'file':<44} {'rows x attributes':>17} {'liac-arff s':>12} {'touchbench s':>13} "
        f"{'ratio':>7}  check"
    )
    for path in files:
        print(table_row(path, folder, options.repeat))
    return 0


if __name__ == "__main__":
    sys.exit(main())
