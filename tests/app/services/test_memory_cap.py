"""The default memory cap of a task: derived from the machine and ``--jobs``, stored with the
run, and a task over it fails while the run goes on; ``--max-memory none`` lifts it.

The CLI runs in a subprocess that sees a machine with 1 GiB available of 4 GiB (its
``/proc/meminfo`` replaced), so that the derived cap is small; the classifiers run in the
engine's worker processes as usual.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from tests.support.cli_runner import run_cli
from tests.support.synthetic import touch_arff
from touchbench.benchmark.run.memory import MB, default_task_memory, read_meminfo

ROOT = Path(__file__).resolve().parents[3]
#: The machine the subprocess's CLI sees: 1 GiB available of 4 GiB.
SMALL_MACHINE = {"MemTotal": 4 * 2**30, "MemAvailable": 2**30}
SCRIPT = """
import sys
import touchbench.benchmark.run.memory as memory
memory.read_meminfo = lambda path='/proc/meminfo': {machine!r}
from touchbench.app.cli.main import main
sys.exit(main(sys.argv[1:]))
"""


def _cli(db: str, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-c", SCRIPT.format(machine=SMALL_MACHINE), "--db", db, *args],
        env={
            **os.environ,
            "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]),
            "TOUCHBENCH_PLUGINS": "tests.support.memory_hog",
        },
        capture_output=True,
        text=True,
        check=False,
        timeout=300,
    )


def _bench(
    capsys: pytest.CaptureFixture[str], db: str, *options: str
) -> tuple[dict[str, Any], dict[str, dict[str, Any]]]:
    """The run's stored config and its leaderboard rows by classifier."""
    ran = _cli(
        db, "bench", "touch", "--target", "gesture", "-c", "hog,nb", "-k", "2", "--json", *options
    )
    assert ran.returncode == 0, ran.stderr
    report = json.loads(ran.stdout)
    assert report["status"] == "done"
    runs = run_cli(capsys, db, "runs", "--json").json()["runs"]
    config = next(run["config"] for run in runs if run["id"] == report["run_id"])
    return config, {row["classifier"]: row for row in report["leaderboard"]}


def test_the_default_cap_fails_a_greedy_task_and_the_run_goes_on(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    db = f"sqlite:///{tmp_path / 'cap.db'}"
    imported = run_cli(
        capsys, db, "import", str(touch_arff(tmp_path / "t.arff")), "--name", "touch"
    )
    assert imported.code == 0, imported.err
    cap = default_task_memory(1, data_bytes=90 * 6 * 8, meminfo=SMALL_MACHINE)
    assert cap is not None and 256 * MB <= cap.bytes < 2**30

    config, rows = _bench(capsys, db)
    assert config["max_memory_mb"] is None
    assert config["task_memory_mb"] == cap.bytes // MB
    assert config["task_memory_from"] == "default: 1,024 MB available of 4,096 MB, 1 worker"
    assert (rows["hog"]["n_ok"], rows["hog"]["n_failed"]) == (0, 2)
    assert rows["hog"]["errors"][0].startswith(
        f"exceeded the memory limit of {cap.bytes // MB} MB per task (MemoryError"
    )
    assert (rows["nb"]["n_ok"], rows["nb"]["n_failed"]) == (2, 0)

    config, rows = _bench(capsys, db, "--max-memory", "none")
    assert config["max_memory_mb"] == 0 and config["task_memory_mb"] is None
    assert (rows["hog"]["n_ok"], rows["hog"]["n_failed"]) == (2, 0)


def test_the_cap_shrinks_with_the_jobs_and_keeps_a_reserve() -> None:
    machine = {"MemTotal": 16 * 2**30, "MemAvailable": 12 * 2**30}
    one, four = (default_task_memory(jobs, meminfo=machine) for jobs in (1, 4))
    assert one is not None and four is not None
    assert 4 * (four.bytes + 300 * MB) <= one.bytes + 300 * MB
    assert one.bytes + 300 * MB <= 12 * 2**30 - 16 * 2**30 // 10
    # a machine short of memory still leaves each task a floor, never a negative cap
    assert default_task_memory(64, meminfo=machine).bytes == 256 * MB  # type: ignore[union-attr]
    assert default_task_memory(1, meminfo={}) is not None  # sysconf on a machine without /proc
    assert read_meminfo("/nonexistent") == {}


@pytest.mark.parametrize("value", ["0.5", "-1", "lots"])
def test_a_cap_that_is_not_a_size_is_refused(value: str) -> None:
    from touchbench.app.cli.requests import build_request, describe
    from touchbench.app.errors import FieldError
    from touchbench.app.schemas.runs import BenchRequest

    with pytest.raises(FieldError) as refused:
        build_request(
            BenchRequest, {"max_memory_mb": "--max-memory"}, dataset="d", max_memory_mb=value
        )
    assert describe(refused.value).startswith("--max-memory: Input should be")
