"""The Python API's overhead: ``touchbench.bench`` against ``touchbench bench`` on the same
run, and against a plain scikit-learn ``cross_validate`` loop over the same classifiers and
folds.

Mini's gestures (``../shared/datasets``), the fast suite, 10-fold CV, one worker process
(``--jobs``).  The three ways run side by side, alternating (API, CLI, plain; then again),
each in this process: the API and the CLI against the same SQLite store, into which the
data set is imported once, before the first round; every round adds one run to it.  The
plain loop computes scikit-learn's scorers in this process (no worker processes, no
store), as perf/engine_overhead.py does.  Printed: each round's wall seconds, then the
medians and their ratios API / CLI (goal: about 1) and API / plain loop (the engine's own
overhead and the store's writes; the issue's goal: within 5 %).

    .venv/bin/python perf/python_api.py [--rounds 3] [--folds 10] [--jobs 1] [--quick]

``--quick``: one round, 5 folds, four classifiers (zeror, nb, j48, lda): for a busy machine.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import statistics
import sys
import tempfile
import time
from pathlib import Path

from engine_overhead import DATA, load_problem, plain_loop  # perf/, beside this script

import touchbench
from touchbench.app.cli.main import main as cli
from touchbench.benchmark.catalogue import suite
from touchbench.benchmark.run.folds import make_folds

QUICK = ["zeror", "nb", "j48", "lda"]


def through_api(url: str, name: str, classifiers: list[str], folds: int, jobs: int) -> float:
    start = time.perf_counter()
    touchbench.bench(name, target="gesture", classifiers=classifiers, folds=folds, jobs=jobs,
                     store=url, progress=False)  # fmt: skip
    return time.perf_counter() - start


def through_cli(url: str, name: str, classifiers: list[str], folds: int, jobs: int) -> float:
    args = ["--db", url, "bench", name, "--target", "gesture", "-c", ",".join(classifiers),
            "-k", str(folds), "--jobs", str(jobs), "--json"]  # fmt: skip
    start = time.perf_counter()
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        code = cli(args)
    seconds = time.perf_counter() - start
    if code != 0:
        sys.exit(f"touchbench bench exited {code}")
    return seconds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--folds", type=int, default=10)
    parser.add_argument("--jobs", type=int, default=1)
    parser.add_argument("--quick", action="store_true")
    options = parser.parse_args()
    if not DATA.exists():
        sys.exit(f"needs {DATA}")
    classifiers = suite("fast")
    if options.quick:
        options.rounds, options.folds, classifiers = 1, 5, QUICK
    folder = tempfile.mkdtemp(prefix="touchbench-perf-")
    url = f"sqlite:///{folder}/perf.db"
    imported = io.StringIO()
    with contextlib.redirect_stdout(imported), contextlib.redirect_stderr(io.StringIO()):
        cli(["--db", url, "import", str(DATA), "--name", "mini", "--json"])
    problem = load_problem(DATA)
    folds, _ = make_folds(problem.Y, n_folds=options.folds, seed=0)
    print(
        f"Mini gesture: {problem.X.shape[0]} instances x {problem.X.shape[1]} features; "
        f"{len(classifiers)} classifiers ({','.join(classifiers)}), {options.folds} folds, "
        f"{options.jobs} job(s)"
    )
    times: dict[str, list[float]] = {"api": [], "cli": [], "plain": []}
    for round_ in range(options.rounds):
        # alternate which goes first, so that a machine getting busier does not favour one
        order = ["api", "cli", "plain"] if round_ % 2 == 0 else ["plain", "cli", "api"]
        for way in order:
            if way == "api":
                seconds = through_api(url, "mini", classifiers, options.folds, options.jobs)
            elif way == "cli":
                seconds = through_cli(url, "mini", classifiers, options.folds, options.jobs)
            else:
                seconds = plain_loop(problem, classifiers, folds, options.jobs)
            times[way].append(seconds)
        print(
            f"round {round_ + 1}: api {times['api'][-1]:.1f} s, cli {times['cli'][-1]:.1f} s, "
            f"plain cross_validate {times['plain'][-1]:.1f} s"
        )
    api, cli_, plain = (statistics.median(times[w]) for w in ("api", "cli", "plain"))
    print(f"medians: api {api:.1f} s, cli {cli_:.1f} s, plain {plain:.1f} s")
    print(f"api / cli   = {api / cli_:.3f}")
    print(f"api / plain = {api / plain:.3f}")
    print(f"cli / plain = {cli_ / plain:.3f}")
    print(f"(store kept at {Path(folder) / 'perf.db'})")


if __name__ == "__main__":
    main()
