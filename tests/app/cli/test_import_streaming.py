"""Importing and exporting stream: a ~50 MB file goes through the CLI in bounded memory,
and an import interrupted midway (Ctrl-C, ``kill -9``) leaves nothing in the store.

Each command runs in its own process, which reports its own peak resident set (VmHWM
from ``/proc``; ``ru_maxrss`` would include the memory of the test process it was forked
from).  The bound is generous, a test of streaming rather than a measurement
(``perf/store_load.py`` measures): reading the file whole into rows would take about
ten times its size.
"""

from __future__ import annotations

import os
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from sqlalchemy import func, select

from tests.support.memory import CLI_WITH_PEAK, REPOSITORY
from touchbench.app.store.database import Store
from touchbench.app.store.listing import list_datasets
from touchbench.app.store.tables import InstanceBlockRow, InstanceRow

PEAK_BOUND_MB = 400

# A shell that runs a command in the background starts it with Ctrl-C ignored, which
# Python then keeps ignoring: the CLI is started as a terminal would start it.
_CLI_WITH_CTRL_C = """
import signal, sys
signal.signal(signal.SIGINT, signal.default_int_handler)
from touchbench.app.cli.main import main
sys.exit(main(sys.argv[1:]))
"""

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="needs Linux's /proc"),
]


def cli_peak_mb(*args: str) -> tuple[int, float, str]:
    """``touchbench ARGS`` in its own process: exit status, peak RSS in MB, stderr."""
    done = subprocess.run(
        [sys.executable, "-c", CLI_WITH_PEAK, *args],
        env={**os.environ, "PYTHONPATH": str(REPOSITORY)},
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        check=False,
        timeout=600,
    )
    peak = int(done.stderr.rsplit("peak-rss-kb ", 1)[1]) / 1024
    return done.returncode, peak, done.stderr


def write_large_arff(path: Path, megabytes: int) -> int:
    """A Maggie-like file of about ``megabytes`` MB (one block of rows, repeated)."""
    rng = np.random.default_rng(3)
    header = ["@relation 'big: -C 2'", "@attribute g {'tap','slap'}", "@attribute p {a,b}"]
    header += [f"@attribute f{i} numeric" for i in range(99)]
    values = np.round(rng.lognormal(3, 2, size=(2000, 99)), 5)
    block = "".join(
        f"'{'tap' if i % 2 else 'slap'}',{'ab'[i % 3 % 2]},{','.join(map(repr, row))}\n"
        for i, row in enumerate(values.tolist())
    ).encode()
    repeats = max(1, megabytes * 1_000_000 // len(block))
    with open(path, "wb") as stream:
        stream.write(("\n".join(header) + "\n@data\n").encode())
        for _ in range(repeats):
            stream.write(block)
    return repeats * 2000


def test_a_50_mb_import_and_its_export_stay_in_bounded_memory(tmp_path: Path) -> None:
    source = tmp_path / "big.arff"
    rows = write_large_arff(source, 50)
    assert source.stat().st_size > 45_000_000
    db = f"sqlite:///{tmp_path / 'store.db'}"
    code, peak, err = cli_peak_mb("--db", db, "import", str(source), "--json")
    assert code == 0, err
    assert peak < PEAK_BOUND_MB, f"import peaked at {peak:.0f} MB"
    exported = tmp_path / "out.arff"
    code, peak, err = cli_peak_mb("--db", db, "export", "big", "-o", str(exported))
    assert code == 0, err
    assert peak < PEAK_BOUND_MB, f"export peaked at {peak:.0f} MB"
    with open(exported, "rb") as stream:
        lines = sum(block.count(b"\n") for block in iter(lambda: stream.read(1 << 20), b""))
    assert lines == 101 + 4 + rows  # header, blank lines, @relation, @data, rows


@pytest.mark.parametrize("signal_number", [signal.SIGINT, signal.SIGKILL])
def test_an_import_interrupted_midway_leaves_nothing_behind(
    tmp_path: Path, signal_number: int
) -> None:
    source = tmp_path / "big.arff"
    write_large_arff(source, 40)
    store_path = tmp_path / "store.db"
    db = f"sqlite:///{store_path}"
    Store(db).dispose()  # migrated before the import starts
    process = subprocess.Popen(
        [sys.executable, "-c", _CLI_WITH_CTRL_C, "--db", db, "import", str(source)],
        env={**os.environ, "PYTHONPATH": str(REPOSITORY)},
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    probe = sqlite3.connect(store_path, timeout=0, isolation_level=None)

    def importing() -> bool:
        """Whether a write transaction (the import's) holds the store."""
        try:
            probe.execute("BEGIN IMMEDIATE")
        except sqlite3.OperationalError:
            return True
        probe.execute("ROLLBACK")
        return False

    deadline = time.monotonic() + 120
    while not importing():
        assert process.poll() is None, "the import ended before it could be interrupted"
        assert time.monotonic() < deadline
        time.sleep(0.01)
    # Frozen the moment its transaction is seen (the 40 MB it still has to write take far
    # longer than this look), the import cannot finish before the signal, however fast the
    # machine: a stopped process keeps SIGINT pending until SIGCONT, and SIGKILL ends it.
    process.send_signal(signal.SIGSTOP)
    assert importing(), "the import ended before it could be interrupted"
    process.send_signal(signal_number)
    process.send_signal(signal.SIGCONT)
    _, err = process.communicate(timeout=120)
    if signal_number == signal.SIGINT:
        assert process.returncode == 130
        assert err.strip().splitlines() == ["touchbench: interrupted"]
    else:
        assert process.returncode == -signal.SIGKILL
    probe.close()
    store = Store(db)
    assert list_datasets(store) == []
    with store.session() as session:
        assert session.scalar(select(func.count()).select_from(InstanceRow)) == 0
        assert session.scalar(select(func.count()).select_from(InstanceBlockRow)) == 0
    store.dispose()
