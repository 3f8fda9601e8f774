"""Read ARFF files with liac-arff, with pandas' C parser and with touchbench, side by side.

For every ARFF file of the reference datasets (and, with ``--rows N``, a generated
Maggie-like file of N rows), in this one process:

- ``liac-arff``: ``arff.load``, the usual Python reader;
- ``pandas block``: ``pandas.read_csv`` on the data section alone (the lines after
  ``@data``, no header, no checks): the floor a C parser sets;
- ``touchbench``: ``read_arff``, the whole file, every check, same values bit for bit
  (plain blocks by Arrow's CSV reader, the rest by the exact reader);
- ``tokenizer``: ``read_arff(parser="tokenizer")``, WEKA's tokenizer on every row (the
  exact reference the fast paths are tested against);

each the best of ``--repeat`` reads, with the ratios liac-arff / touchbench (higher is
better) and touchbench / pandas (lower is better).  The values liac-arff reads are
compared with touchbench's, and a disagreement is reported.

Usage::

    .venv/bin/python perf/arff_read.py [DATASETS_FOLDER] [--repeat N] [--rows N]
"""

from __future__ import annotations

import argparse
import io
import math
import sys
import tempfile
import time
from collections.abc import Callable
from functools import partial
from pathlib import Path
from typing import Any

import arff  # liac-arff
import numpy as np
import pandas as pd
from generated import write_maggie_like

from touchbench.benchmark.dataset import Dataset
from touchbench.benchmark.errors import DataFormatError
from touchbench.benchmark.io.arff import read_arff
from touchbench.benchmark.io.dates import DateFormat

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


def read_data_block_with_pandas(block: bytes, n_columns: int) -> pd.DataFrame:
    """The data section alone, as pandas reads a headerless CSV (quotes as ARFF's ')."""
    return pd.read_csv(
        io.BytesIO(block),
        header=None,
        names=list(range(n_columns)),
        quotechar="'",
        na_values=["?"],
        keep_default_na=False,
        engine="c",
        low_memory=False,
    )


def data_block(path: Path) -> bytes:
    content = path.read_bytes()
    marker = content.lower().find(b"@data")
    return content[content.index(b"\n", marker) + 1 :]


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


def attempt(read: Callable[[], Any], repeat: int) -> tuple[float, Any, str]:
    """(best seconds, result, '') or (nan, None, why it failed)."""
    try:
        seconds, result = best_time(read, repeat)
    except DataFormatError as error:
        return math.nan, None, f"line {error.line}: {error.message}"
    except Exception as error:  # the peers raise many kinds; each is reported
        return math.nan, None, shorten(f"{type(error).__name__}: {error}", 70)
    return seconds, result, ""


def table_row(path: Path, name: str, repeat: int, *, liac: bool = True) -> str:
    """One line of the table: every reader's best time, the ratios and the check."""
    ours_s, ours, ours_failure = attempt(partial(read_arff, path), repeat)
    exact_s, exact, _ = attempt(partial(read_arff, path, parser="tokenizer"), max(1, repeat // 3))
    liac_s, theirs, liac_failure = (
        attempt(partial(read_with_liac, path), repeat) if liac else (math.nan, None, "skipped")
    )
    n_columns = 0 if ours is None else ours.schema.n_attributes
    block = data_block(path)
    pandas_s, _, pandas_failure = attempt(
        partial(read_data_block_with_pandas, block, n_columns), repeat
    )
    shape = "-" if ours is None else f"{ours.values.shape[0]} x {ours.values.shape[1]}"

    def seconds(value: float) -> str:
        return f"{'-':>9}" if math.isnan(value) else f"{value:9.4f}"

    def ratio(top: float, bottom: float) -> str:
        return f"{'-':>6}" if math.isnan(top) or math.isnan(bottom) else f"{top / bottom:5.1f}x"

    checks = []
    if ours is not None and exact is not None:
        same = ours.values.tobytes() == exact.values.tobytes() and ours.schema == exact.schema
        checks.append("= tokenizer" if same else "DIFFERS FROM THE TOKENIZER")
    if ours is not None and theirs is not None:
        checks.append(disagreement(ours, theirs) or "= liac-arff")
    for who, why in (("touchbench", ours_failure), ("liac-arff", liac_failure)):
        if why and why != "skipped":
            checks.append(f"{who} fails: {why}")
    if pandas_failure:
        checks.append("pandas fails")
    return (
        f"{shorten(name, 40):<40} {shape:>13} {seconds(liac_s)} {seconds(pandas_s)} "
        f"{seconds(ours_s)} {seconds(exact_s)} {ratio(liac_s, ours_s)} "
        f"{ratio(ours_s, pandas_s)}  {'; '.join(checks)}"
    )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", nargs="?", type=Path, default=DEFAULT_FOLDER)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument(
        "--rows", type=int, default=0, help="also a generated Maggie-like file of N rows"
    )
    options = parser.parse_args()
    folder: Path = options.folder
    files = sorted(folder.rglob("*.arff")) if folder.is_dir() else []
    if not files and not options.rows:
        print(
            f"no .arff files under {folder}: pass the folder of the reference datasets "
            "(../shared/datasets beside the repository), or --rows N",
            file=sys.stderr,
        )
        return 2
    import pyarrow

    print(
        f"best of {options.repeat} reads per file and reader (tokenizer: fewer); "
        f"pandas {pd.__version__}, pyarrow {pyarrow.__version__}, liac-arff {arff.__version__}\n"
    )
    print(
        f"{'file':<40} {'rows x attr':>13} {'liac-arff':>9} {'pandas':>9} {'touchb.':>9} "
        f"{'tokenizer':>9} {'liac/':>6} {'touchb/':>6}"
    )
    print(
        f"{'':<40} {'':>13} {'s':>9} {'block s':>9} {'s':>9} {'s':>9} {'touchb':>6} {'pandas':>6}"
    )
    np.seterr(all="ignore")
    read_arff(files[0]) if files else None  # pyarrow imported before anything is timed
    for path in files:
        print(table_row(path, str(path.relative_to(folder)), options.repeat), flush=True)
    if options.rows:
        with tempfile.TemporaryDirectory() as scratch:
            path = write_maggie_like(Path(scratch) / "generated.arff", options.rows)
            size = path.stat().st_size / 1e6
            name = f"generated, {size:.0f} MB"
            print(table_row(path, name, max(1, options.repeat // 3), liac=False), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
