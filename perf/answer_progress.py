"""What telling a learning curve's progress after every task costs, on a large request.

Run from the repository root::

    .venv/bin/python perf/answer_progress.py [--folds 10]

Imports the Maggie data set (3,572 instances x 99 features) into a temporary SQLite
store, plans a learning curve of 20 classifiers x 20 fractions, and builds the curve's
summary from fabricated results (one per task) every 200 results, timing it; the time
extrapolated to a summary after every task is what progress cost before it was told at
most once a second (:mod:`app.services.progress`).

Not a test: nothing is asserted.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

MAGGIE = Path("/work/shared/datasets/uc3m-touch/maggie/gesture_and_place.arff")
CLASSIFIERS = [
    "zeror",
    "oner",
    "part",
    "ripper",
    "stump",
    "j48",
    "cart",
    "lmt",
    "random-tree",
    "extra-tree",
    "rf",
    "rf-500",
    "extra-trees",
    "bagging",
    "adaboost",
    "hgb",
    "gbm",
    "xgb",
    "lgbm",
    "random-subspace",
]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--folds", type=int, default=10)
    args = parser.parse_args()
    from touchbench.app.schemas.datasets import ImportRequest
    from touchbench.app.schemas.learning import LearningCurveRequest
    from touchbench.app.services import learning
    from touchbench.app.services.datasets import import_file
    from touchbench.app.store.database import Store
    from touchbench.benchmark.results import TaskKey, TaskResult

    with tempfile.TemporaryDirectory() as folder:
        store = Store(f"sqlite:///{folder}/touchbench.db")
        import_file(store, ImportRequest(file=MAGGIE, name="maggie"))
        request = LearningCurveRequest(
            dataset="maggie",
            target="gesture",
            classifiers=CLASSIFIERS,
            fractions=[i / 20 for i in range(1, 21)],
            folds=args.folds,
        )
        started = time.perf_counter()
        learning.check_learning_curve(store, request)
        print(f"request accepted in {time.perf_counter() - started:.2f} s")
        plan = learning._Plan(store, request)
        fractions = list(plan.folds)
        results: dict[float, list[TaskResult]] = {}
        n, size, spent = 0, 0, 0.0
        for place, fraction in enumerate(fractions):
            for fold in range(plan.n_folds):
                for classifier in CLASSIFIERS:
                    key = TaskKey(classifier, place, fold)
                    result = TaskResult(key, "ok", None, {"f1_weighted": 0.5}, None, 10, 10)
                    results.setdefault(fraction, []).append(result)
                    n += 1
                    if n % 200 == 0:
                        started = time.perf_counter()
                        size = len(json.dumps(plan.summary(results).to_json()))
                        spent += time.perf_counter() - started
        print(
            f"{n:,} tasks; summaries every 200 results: {spent:.1f} s, so after every "
            f"result ~{spent * 200:.0f} s; a summary is {size:,} bytes of JSON"
        )
        store.dispose()


if __name__ == "__main__":
    main()
