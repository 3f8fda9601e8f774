"""Engine overhead: touchbench's engine vs. a plain scikit-learn ``cross_validate`` loop.

Both sides run the same catalogue pipelines on the same folds of Mini's gestures (10-fold
CV) and compute the same multi-class metrics (scikit-learn scorers on one side, the engine's
metrics plus model sizes on the other).  Both run single-threaded BLAS/OpenMP, as the
engine's workers do (a multi-threaded BLAS on a shared 2-core machine makes the plain loop
many times slower, which would flatter the engine).  Printed: wall seconds, the ratio
engine / plain loop (goal <= 1.10), and the speed-up of 2 jobs over 1 (goal >= 1.7x).

    .venv/bin/python perf/engine_overhead.py [--classifiers rf,logistic,...] [--rounds 2]
"""

from __future__ import annotations

import argparse
import os
import time
import warnings
from collections.abc import Callable
from pathlib import Path

import numpy as np
from sklearn.metrics import cohen_kappa_score, make_scorer
from sklearn.model_selection import cross_validate
from threadpoolctl import threadpool_limits

from touchbench.benchmark.catalogue import build_pipeline, get_spec
from touchbench.benchmark.io.arff import read_arff
from touchbench.benchmark.run.engine import Problem, run_tasks
from touchbench.benchmark.run.folds import Fold, make_folds

DATA = (
    Path(__file__).resolve().parents[2] / "shared/datasets/uc3m-touch/mini/gesture_and_place.arff"
)
CLASSIFIERS = "zeror,nb,j48,ibk,lda,logistic,svm-rbf,rf,extra-trees,mlp,xgb"


def load_problem(path: Path) -> Problem:
    data = read_arff(path)
    return Problem(
        X=data.values[:, 2:],
        Y=data.values[:, [0]].astype(np.int64),
        n_classes=(len(data.schema.attributes[0].values),),
        target_names=("gesture",),
    )


def scorers(classifier: str) -> dict[str, object]:
    scoring: dict[str, object] = {
        "accuracy": "accuracy",
        "balanced_accuracy": "balanced_accuracy",
        "f1_weighted": "f1_weighted",
        "f1_macro": "f1_macro",
        "precision_weighted": "precision_weighted",
        "recall_weighted": "recall_weighted",
        "kappa": make_scorer(cohen_kappa_score),
        "mcc": "matthews_corrcoef",
    }
    if get_spec(classifier).probabilities:
        scoring["roc_auc"] = "roc_auc_ovr_weighted"
        scoring["log_loss"] = "neg_log_loss"
    return scoring


def plain_loop(problem: Problem, classifiers: list[str], folds: list[Fold], n_jobs: int) -> float:
    """Wall seconds of ``cross_validate`` over every classifier, in this process."""
    cv = [(f.train, f.test) for f in folds]
    y = problem.Y[:, 0]
    start = time.perf_counter()
    with threadpool_limits(limits=1), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for classifier in classifiers:
            pipeline = build_pipeline(classifier, n_features=problem.n_features)
            cross_validate(
                pipeline, problem.X, y, cv=cv, scoring=scorers(classifier), n_jobs=n_jobs
            )
    return time.perf_counter() - start


def engine(problem: Problem, classifiers: list[str], folds: list[Fold], jobs: int) -> float:
    """Wall seconds of the engine over every classifier, worker start-up included.

    Also prints how many tasks were in progress on average (the sum of the tasks' own
    fit and predict seconds over the wall time): with 2 jobs, 2.0 would mean both
    workers always had a core; less means the cores were busy with other processes.
    """
    start = time.perf_counter()
    results = run_tasks(problem, classifiers, folds, jobs=jobs, timeout=None)
    elapsed = time.perf_counter() - start
    failed = [r for r in results if r.status != "ok"]
    if failed:
        raise SystemExit(f"{len(failed)} task(s) failed, e.g. {failed[0].key}: {failed[0].error}")
    busy = sum(r.metrics["fit_time"] + r.metrics["predict_time"] for r in results)
    cpu = sum(r.metrics["fit_cpu_time"] + r.metrics["predict_cpu_time"] for r in results)
    print(
        f"    engine, {jobs} job(s): {elapsed:.1f} s wall, tasks in progress on average "
        f"{busy / elapsed:.2f}, CPU seconds per task second {cpu / busy:.2f}"
    )
    return elapsed


def best_of(rounds: int, measure: Callable[[], float]) -> float:
    return min(measure() for _ in range(rounds))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, default=DATA)
    parser.add_argument("--classifiers", default=CLASSIFIERS)
    parser.add_argument("--folds", type=int, default=10)
    parser.add_argument("--rounds", type=int, default=1, help="best of this many runs each")
    args = parser.parse_args()
    problem = load_problem(args.data)
    classifiers = args.classifiers.split(",")
    folds, _ = make_folds(problem.Y, n_folds=args.folds)
    print(f"load average before: {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")
    print(
        f"{args.data.parent.name} gesture: {problem.n_instances} instances, {problem.n_features} "
        f"features, {len(classifiers)} classifiers x {len(folds)} folds = "
        f"{len(classifiers) * len(folds)} tasks"
    )
    times = {
        "plain, 1 job": best_of(args.rounds, lambda: plain_loop(problem, classifiers, folds, 1)),
        "engine, 1 job": best_of(args.rounds, lambda: engine(problem, classifiers, folds, 1)),
        "plain, 2 jobs": best_of(args.rounds, lambda: plain_loop(problem, classifiers, folds, 2)),
        "engine, 2 jobs": best_of(args.rounds, lambda: engine(problem, classifiers, folds, 2)),
    }
    print(f"load average after: {os.getloadavg()[0]:.2f}")
    for name, seconds in times.items():
        print(f"  {name:16s} {seconds:8.1f} s")
    print(
        f"engine / plain loop, 1 job:  {times['engine, 1 job'] / times['plain, 1 job']:.3f}"
        "  (goal <= 1.10)"
    )
    print(f"engine / plain loop, 2 jobs: {times['engine, 2 jobs'] / times['plain, 2 jobs']:.3f}")
    print(
        f"engine speed-up 2 jobs over 1: {times['engine, 1 job'] / times['engine, 2 jobs']:.2f}x"
        "  (goal >= 1.7x)"
    )
    print(
        f"plain loop speed-up n_jobs=2 over 1: "
        f"{times['plain, 1 job'] / times['plain, 2 jobs']:.2f}x"
    )


if __name__ == "__main__":
    main()
