"""Engine workers' start: forked from the zygote (today) against fresh interpreters (before).

Each measurement is a new Python process that imports the engine, starts ``N`` workers for
one run's context (Mini gesture's data set when ``../shared`` is there, a small synthetic
problem otherwise) and waits until every one has loaded it: the wall seconds to that point,
and the CPU seconds of the whole tree (the process, its zygote, the workers, reaped) once
they have ended.  The two sides alternate, round after round, so that a machine whose speed
drifts treats both alike.

    .venv/bin/python perf/worker_start.py [--workers 1,2,8] [--rounds 3]
"""

from __future__ import annotations

import argparse
import json
import os
import pickle
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from perf.engine_overhead import DATA as MINI  # noqa: E402 (after the path)
from perf.engine_overhead import load_problem  # noqa: E402
from touchbench.benchmark.run.engine import Problem  # noqa: E402


def measure(side: str, workers: int) -> dict[str, float]:
    """In this process: start ``workers`` workers on ``side``; their start's seconds."""
    from touchbench.benchmark.catalogue import get_spec
    from touchbench.benchmark.run import zygote
    from touchbench.benchmark.run.folds import make_folds
    from touchbench.benchmark.run.task import TaskContext
    from touchbench.benchmark.run.worker import Worker

    problem = _problem()
    folds = make_folds(problem.Y, n_folds=10)[0]
    specs = {name: get_spec(name) for name in ("nb", "rf", "xgb", "svm-rbf")}
    context = pickle.dumps(TaskContext(problem, specs, list(folds), 0))
    if side == "fresh":
        zygote.spawn = lambda *args, **kwargs: None
    start = time.perf_counter()
    pool = [Worker(context) for _ in range(workers)]
    for worker in pool:
        while not worker.ready:
            worker.receive()
    wall = time.perf_counter() - start
    for worker in pool:
        worker.close()
    zygote._close_zygote()
    times = os.times()
    return {"wall": wall, "cpu": times.children_user + times.children_system}


def _problem() -> Problem:
    if MINI.exists():
        return load_problem(MINI)
    rng = np.random.default_rng(0)
    y = np.arange(600) % 4
    X = rng.normal(size=(600, 40)) + y[:, None]
    return Problem(X=X, Y=y[:, None], n_classes=(4,), target_names=("gesture",))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--workers", default="1,2,8", help="comma-separated pool sizes")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--child", nargs=2, metavar=("SIDE", "N"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        print(json.dumps(measure(args.child[0], int(args.child[1]))))
        return
    sizes = [int(n) for n in args.workers.split(",")]
    found: dict[tuple[str, int], list[dict[str, float]]] = {}
    for round_ in range(args.rounds):
        for n in sizes:
            sides = ("zygote", "fresh") if round_ % 2 == 0 else ("fresh", "zygote")
            for side in sides:
                found.setdefault((side, n), []).append(_child(side, n))
    print(f"data: {'Mini gesture' if MINI.exists() else 'synthetic'}, rounds: {args.rounds}")
    print("| workers | fresh wall s | zygote wall s | ratio | fresh CPU s | zygote CPU s | ratio |")
    print("|---|---|---|---|---|---|---|")
    for n in sizes:
        fresh, forked = found[("fresh", n)], found[("zygote", n)]
        cells = []
        for key in ("wall", "cpu"):
            a = statistics.median(m[key] for m in fresh)
            b = statistics.median(m[key] for m in forked)
            cells += [f"{a:.2f}", f"{b:.2f}", f"{b / a:.2f}"]
        print(f"| {n} | " + " | ".join(cells) + " |")


def _child(side: str, n: int) -> dict[str, float]:
    """One measurement in a new process (so that the zygote's own start counts)."""
    environment = {**os.environ, "PYTHONPATH": str(ROOT)}
    output = subprocess.run(
        [sys.executable, __file__, "--child", side, str(n)],
        env=environment,
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    return dict(json.loads(output.strip().splitlines()[-1]))


if __name__ == "__main__":
    main()
