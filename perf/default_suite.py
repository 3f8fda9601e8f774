"""The default suite on the reference data: leaderboards, timing, and LazyPredict beside it.

Runs a suite (``default`` unless told otherwise) under 10-fold cross-validation on Mini
(and, with ``--robots mini,maggie``, Maggie) for each requested target, prints the top of
each leaderboard with WEKA's significance marks, the wall time and the classifiers
cross-validated per minute.  With ``--lazypredict PYTHON`` (an interpreter of a separate
virtual environment where ``pip install lazypredict`` worked), LazyPredict's
``LazyClassifier(cv=K)`` runs on the same data in the same run, for classifiers per minute
side by side.  LazyPredict fits each model on a 90 % training split, cross-validates it on
that split and scores it on the remaining 10 %.

    .venv/bin/python perf/default_suite.py [--robots mini,maggie] [--targets gesture,place]
        [--suite default] [--jobs 2] [--top 15] [--lazypredict /path/to/venv/bin/python]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

from touchbench.benchmark.catalogue import suite
from touchbench.benchmark.estimators import reads_sequences
from touchbench.benchmark.evaluation.leaderboard import build_leaderboard
from touchbench.benchmark.io.arff import read_arff
from touchbench.benchmark.run.engine import Problem, run_tasks
from touchbench.benchmark.run.folds import make_folds

DATASETS = Path(__file__).resolve().parents[2] / "shared/datasets/uc3m-touch"

LAZYPREDICT_SCRIPT = """
import json, sys, time, warnings
import numpy as np
from lazypredict.Supervised import LazyClassifier
from sklearn.model_selection import train_test_split
warnings.simplefilter("ignore")
data = np.load(sys.argv[1])
X, y, folds, jobs = data["X"], data["y"], int(sys.argv[2]), int(sys.argv[3])
X_train, X_test, y_train, y_test = train_test_split(
    X, y, test_size=0.1, stratify=y, random_state=0
)
start = time.perf_counter()
models = LazyClassifier(cv=folds, n_jobs=jobs, random_state=0, ignore_warnings=True)
scores = models.fit(X_train, X_test, y_train, y_test)
scores = scores[0] if isinstance(scores, tuple) else scores
elapsed = time.perf_counter() - start
cv_f1 = [c for c in scores.columns if "F1" in c and "CV" in c and "Std" not in c]
column = cv_f1[0] if cv_f1 else "F1 Score"
best = scores[column].astype(float).idxmax()
print(json.dumps({
    "models": int(len(scores)), "seconds": elapsed, "column": column,
    "best": str(best), "best_f1": float(scores.loc[best, column]),
}))
"""


def load(robot: str, target: str) -> Problem:
    data = read_arff(DATASETS / robot / "gesture_and_place.arff")
    names = data.schema.target_names
    index = names.index(target)
    other = set(data.schema.target_indices)
    features = [i for i in range(data.schema.n_attributes) if i not in other]
    return Problem(
        X=data.values[:, features],
        Y=data.values[:, [data.schema.target_indices[index]]].astype(np.int64),
        n_classes=(len(data.schema.targets[index].values),),
        target_names=(target,),
    )


def run_suite(problem: Problem, ids: list[str], n_folds: int, jobs: int, top: int) -> float:
    folds, notes = make_folds(problem.Y, n_folds=n_folds)
    for note in notes:
        print(f"  note: {note}")
    start = time.perf_counter()
    results = run_tasks(problem, ids, folds, jobs=jobs, timeout=600.0)
    elapsed = time.perf_counter() - start
    board = build_leaderboard(results)
    fit = {
        row.classifier: row.metrics["fit_time"][0] if "fit_time" in row.metrics else float("nan")
        for row in board.rows
    }
    print(f"  {'rank':>4} {'classifier':24s}   f1_weighted        accuracy  fit s/fold")
    for row in board.rows[:top]:
        mean, std = row.metrics["f1_weighted"]
        print(
            f"  {row.rank:4d} {row.classifier:24s} {row.mark:1s} {mean:.4f} ± {std:.4f}  "
            f"{row.metrics['accuracy'][0]:.4f}  {fit[row.classifier]:8.2f}"
        )
    failed = [row for row in board.rows if row.n_failed]
    for row in failed:
        print(f"  failed: {row.classifier}: {row.n_failed} task(s): {row.errors[0]}")
    v, same, worse = board.summary
    print(
        f"  (v/ /*) = ({v}/{same}/{worse}) against {board.baseline}; "
        f"{len(results)} tasks, {len(failed)} classifier(s) with failures"
    )
    print(
        f"  wall {elapsed:.1f} s = {elapsed / 60:.2f} min; "
        f"{len(ids) / (elapsed / 60):.1f} classifiers cross-validated per minute"
    )
    # CPU seconds of the fits and predictions themselves: on a shared machine the wall
    # time says as much about the neighbours as about the suite
    cpu = sum(
        r.metrics.get("fit_cpu_time", 0.0) + r.metrics.get("predict_cpu_time", 0.0) for r in results
    )
    print(
        f"  CPU in fits and predictions {cpu:.0f} s = {cpu / jobs / 60:.2f} min over {jobs} "
        f"jobs; load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores"
    )
    slowest = sorted(board.rows, key=lambda row: -row.metrics.get("fit_time", (0.0,))[0])[:5]
    print(
        "  slowest fits (s/fold): "
        + ", ".join(f"{row.classifier} {row.metrics['fit_time'][0]:.1f}" for row in slowest)
    )
    return elapsed


def run_lazypredict(python: str, problem: Problem, n_folds: int, jobs: int) -> None:
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "data.npz"
        np.savez(path, X=problem.X, y=problem.Y[:, 0])
        completed = subprocess.run(
            [python, "-c", LAZYPREDICT_SCRIPT, str(path), str(n_folds), str(jobs)],
            capture_output=True,
            text=True,
            check=False,
        )
    if completed.returncode != 0:
        print(f"  LazyPredict failed: {completed.stderr.strip().splitlines()[-1:]}")
        return
    report = json.loads(completed.stdout.strip().splitlines()[-1])
    rate = report["models"] / (report["seconds"] / 60)
    print(
        f"  LazyPredict: {report['models']} models in {report['seconds']:.1f} s = "
        f"{rate:.1f} classifiers per minute; best {report['best']} "
        f"{report['column']} {report['best_f1']:.4f}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--robots", default="mini")
    parser.add_argument("--targets", default="gesture")
    parser.add_argument("--suite", default="default")
    parser.add_argument("--folds", type=int, default=10)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--top", type=int, default=15)
    parser.add_argument("--lazypredict", metavar="PYTHON", default=None)
    args = parser.parse_args()
    for robot in args.robots.split(","):
        for target in args.targets.split(","):
            problem = load(robot, target)
            # sequence classifiers refuse these flat feature files, as `bench` leaves them out
            ids = [i for i in suite(args.suite) if problem.sequence or not reads_sequences(i)]
            print(
                f"{robot} {target}: {problem.n_instances} instances, suite '{args.suite}' "
                f"({len(ids)} classifiers), {args.folds} folds, {args.jobs} jobs"
            )
            run_suite(problem, ids, args.folds, args.jobs, args.top)
            if args.lazypredict:
                run_lazypredict(args.lazypredict, problem, args.folds, args.jobs)


if __name__ == "__main__":
    main()
