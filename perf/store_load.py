"""Import, load and export of a large data set, end to end, on SQLite and PostgreSQL.

1. ``touchbench import`` of a generated Maggie-like ARFF file (``--rows``; 235 000 rows
   make the 200 MB file of issue 14), and ``touchbench export`` of it to ``/dev/null``,
   each in its own process: wall time and peak memory (the process's maximum resident
   set, from ``wait4``).  Both are streamed, so memory does not grow with the file: the
   same is measured on a file of a quarter the rows (``small``) to show it.
2. ``load_dataset`` of the stored data set into numpy, best of three, side by side with
   ``numpy.load`` of the same matrix from a ``.npy`` file on the same disk (the floor any
   store is measured against; ratio = store seconds / numpy seconds).

Usage::

    .venv/bin/python perf/store_load.py [--rows 235000] [--postgres URL]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
import uuid
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np
from generated import write_maggie_like
from sqlalchemy import create_engine, text
from sqlalchemy.engine import make_url

from touchbench.app.store.database import Store
from touchbench.app.store.datasets import load_dataset

REPOSITORY = Path(__file__).resolve().parents[1]
REPEATS = 3  # load times are the best of this many


#: Runs the CLI and then prints the process's own peak resident set (VmHWM: unlike
#: ru_maxrss, it does not include the memory of the parent it was forked from).
_CLI_WITH_PEAK = """
import sys
from touchbench.app.cli.main import main
code = main(sys.argv[1:])
with open("/proc/self/status") as status:
    peak = next(line.split()[1] for line in status if line.startswith("VmHWM:"))
print(f"peak-rss-kb {peak}", file=sys.stderr)
sys.exit(code)
"""


def run_cli(*args: str) -> tuple[float, float, float]:
    """``touchbench ARGS`` in its own process: (wall seconds, CPU seconds, peak RSS in MB).

    CPU time (user + system) is the figure to trust on a busy machine; on an idle one with
    two cores, an import's wall time is below it (reading and storing overlap).
    """
    environment = {**os.environ, "PYTHONPATH": str(REPOSITORY)}
    start = time.perf_counter()
    process = subprocess.Popen(
        [sys.executable, "-c", _CLI_WITH_PEAK, *args],
        env=environment,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    assert process.stderr is not None
    errors = process.stderr.read()
    _, status, usage = os.wait4(process.pid, 0)
    seconds = time.perf_counter() - start
    if os.waitstatus_to_exitcode(status) != 0:
        raise SystemExit(f"touchbench {' '.join(args)} failed: {errors}")
    peak = int(errors.rsplit("peak-rss-kb ", 1)[1]) / 1024
    return seconds, usage.ru_utime + usage.ru_stime, peak


def measure(url: str, folder: Path, files: dict[str, Path]) -> list[str]:
    """Import and export of each file, then the load of the largest; table lines."""
    lines = []
    for label, path in files.items():
        name = f"{label}-{uuid.uuid4().hex[:6]}"
        size = path.stat().st_size / 1e6
        for command in (
            ("import", str(path), "--name", name),
            ("export", name, "-o", "/dev/null"),
        ):
            wall, cpu, peak = run_cli("--db", url, *command)
            lines.append(
                f"  {command[0]} {label:<6} {size:5.0f} MB  {wall:6.2f} s wall  {cpu:6.2f} s CPU"
                f"  {peak:5.0f} MB peak"
            )
    store = Store(url)
    loading = float("inf")
    for _ in range(REPEATS):
        start = time.perf_counter()
        loaded = load_dataset(store, name)
        loading = min(loading, time.perf_counter() - start)
    store.dispose()
    floor = numpy_floor(folder, loaded.values)
    lines.append(
        f"  load_dataset {loaded.values.shape[0]} x {loaded.values.shape[1]}: {loading:.3f} s "
        f"(numpy.load {floor:.3f} s, ratio {loading / floor:.1f})"
    )
    return lines


def numpy_floor(folder: Path, values: np.ndarray) -> float:
    path = folder / "floor.npy"
    np.save(path, values)
    best = float("inf")
    for _ in range(REPEATS):
        start = time.perf_counter()
        np.load(path)
        best = min(best, time.perf_counter() - start)
    path.unlink()
    return best


@contextmanager
def postgres_database(server: str) -> Iterator[str | None]:
    """A fresh database on ``server`` for this run (``None`` if there is no server)."""
    admin = create_engine(server, isolation_level="AUTOCOMMIT")
    name = f"touchbench_perf_{uuid.uuid4().hex[:8]}"
    try:
        with admin.connect() as connection:
            connection.execute(text(f'CREATE DATABASE "{name}"'))
    except Exception as error:
        print(f"postgresql: skipped ({str(error).splitlines()[0]})")
        yield None
        return
    try:
        yield make_url(server).set(database=name).render_as_string(hide_password=False)
    finally:
        with admin.connect() as connection:
            connection.execute(text(f'DROP DATABASE "{name}" WITH (FORCE)'))
        admin.dispose()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=int, default=235_000)
    parser.add_argument(
        "--postgres", default="postgresql+psycopg://postgres:postgres@127.0.0.1:5432/test"
    )
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(scratch)
        files = {
            "small": write_maggie_like(folder / "small.arff", args.rows // 4),
            "large": write_maggie_like(folder / "large.arff", args.rows),
        }
        print(f"generated Maggie-like files: {args.rows // 4} and {args.rows} rows x 101\n")
        print("sqlite")
        for line in measure(f"sqlite:///{folder}/perf.db", folder, files):
            print(line, flush=True)
        with postgres_database(args.postgres) as url:
            if url is not None:
                print("postgresql")
                for line in measure(url, folder, files):
                    print(line, flush=True)


if __name__ == "__main__":
    main()
