"""Start-up time of the ``touchbench`` command and the job process, beside typer and rich.

Every command, every job process a service starts and every test subprocess pays the
start-up, so it is measured on its own: wall-clock time of a fresh process for

- ``python -c "import typer, rich"``: the baseline, the libraries every command needs;
- ``touchbench --version`` and ``touchbench --help``;
- ``touchbench datasets`` on an empty SQLite store (created, and migrated, before timing);
- ``python -m app.jobs.process --help``: the worker process a service starts per run or job,

each ``--rounds`` times (default 10).  The commands take turns within each round, so that
the machine's speed drifting over the minutes spreads over all of them alike.  Prints each
command's median wall-clock time, its spread (lowest and highest) and its ratio to the
baseline, then its median CPU time (user and system) and that ratio: the CPU time depends
less on what else the machine is running.

The processes run as an installed touchbench does: with the compiled modules cached (in a
temporary folder, ``PYTHONPYCACHEPREFIX``, so that the working tree stays clean; a first
round, not counted, fills it).  ``--tree`` measures another checkout, e.g. the main branch's
for a before and after.

Usage::

    .venv/bin/python perf/startup.py [--rounds N] [--tree CHECKOUT]
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def commands(store_url: str) -> dict[str, list[str]]:
    """The command lines to time, by the name printed; the first is the baseline."""
    python = sys.executable
    touchbench = str(Path(python).with_name("touchbench"))
    return {
        'python -c "import typer, rich"': [python, "-c", "import typer, rich"],
        "touchbench --version": [touchbench, "--version"],
        "touchbench --help": [touchbench, "--help"],
        "touchbench datasets (empty SQLite)": [touchbench, "--db", store_url, "datasets"],
        "python -m app.jobs.process --help": [
            python,
            "-m",
            "touchbench.app.jobs.process",
            "--help",
        ],
    }


def children_cpu() -> float:
    """CPU seconds (user and system) of the finished child processes so far."""
    used = resource.getrusage(resource.RUSAGE_CHILDREN)
    return used.ru_utime + used.ru_stime


def elapsed(argv: list[str], env: dict[str, str], cwd: Path) -> tuple[float, float]:
    """Wall-clock and CPU seconds of ``argv``, from its start to its exit; a failure stops
    the measurement."""
    cpu = children_cpu()
    start = time.perf_counter()
    done = subprocess.run(argv, env=env, cwd=cwd, capture_output=True, check=False)
    seconds = time.perf_counter() - start
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(argv)} exited {done.returncode}: {done.stderr.decode()}")
    return seconds, children_cpu() - cpu


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=10, help="Runs of each command.")
    parser.add_argument(
        "--tree", type=Path, default=ROOT, help="The checkout to measure (default: this one)."
    )
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="touchbench-startup-") as folder:
        env = dict(os.environ)
        env["PYTHONPATH"] = str(args.tree.resolve())
        env["PYTHONPYCACHEPREFIX"] = str(Path(folder) / "pycache")
        env.pop("PYTHONDONTWRITEBYTECODE", None)
        env.pop("TOUCHBENCH_DATABASE_URL", None)
        lines = commands(f"sqlite:///{Path(folder) / 'empty.db'}")
        for argv in lines.values():  # compile and cache; create and migrate the store
            elapsed(argv, env, args.tree)
        times: dict[str, list[float]] = {name: [] for name in lines}
        cpu: dict[str, list[float]] = {name: [] for name in lines}
        for _ in range(args.rounds):
            for name, argv in lines.items():
                wall, used = elapsed(argv, env, args.tree)
                times[name].append(wall)
                cpu[name].append(used)
    baseline = statistics.median(next(iter(times.values())))
    cpu_baseline = statistics.median(next(iter(cpu.values())))
    print(f"{args.rounds} runs each, alternating; seconds per process")
    print(
        f"{'command':<36} {'wall':>6} {'lowest':>7} {'highest':>7} {'x base':>7} "
        f"{'CPU':>6} {'x base':>7}"
    )
    for name, seconds in times.items():
        median = statistics.median(seconds)
        used = statistics.median(cpu[name])
        print(
            f"{name:<36} {median:6.3f} {min(seconds):7.3f} {max(seconds):7.3f} "
            f"{median / baseline:7.2f} {used:6.3f} {used / cpu_baseline:7.2f}"
        )


if __name__ == "__main__":
    main()
