"""What tuning costs: tuned twins against their defaults, and halving against a full grid.

For each chosen catalogue entry, on the same outer folds of the UC3M Mini gesture data
(``../shared/datasets``), three things are fitted on each outer training fold and scored
(weighted F1) on its test fold, all in this one process:

- the default entry (what ``bench`` runs);
- its tuned twin (``ID+tuned``: scikit-learn's successive halving inside the training
  fold, at the default ``--budget`` unless ``--budget`` is given);
- a full ``GridSearchCV`` of the same space with the same inner folds and scorer.

It prints, per entry, the mean score and seconds per fold of each, the tuned twin's cost
as a multiple of the default (the goal: under 10x at the default budget), the candidates
of its first round and the rows of its last (fewer than the training fold's when the
budget cannot pay for 3 candidates on all of them), and the grid's cost as a multiple of
the halving search; and the machine's load average before and after.

    .venv/bin/python perf/tuning.py [--classifiers svm-rbf,logistic,ibk5-std] [--folds 5]
        [--budget MINUTES] [--robot mini] [--grid-max 100]

Everything runs single-threaded (as the engine's workers do); grids larger than
``--grid-max`` settings are not searched in full (their columns print ``nan``).
"""

from __future__ import annotations

import argparse
import os
import time
import warnings
from pathlib import Path

import numpy as np
from sklearn.base import clone
from sklearn.metrics import f1_score
from sklearn.model_selection import GridSearchCV, ParameterGrid, StratifiedKFold
from threadpoolctl import threadpool_limits

from touchbench.benchmark.catalogue import build_pipeline, get_spec
from touchbench.benchmark.catalogue.inner import inner_folds
from touchbench.benchmark.catalogue.tuning import (
    CLASSIFIER_STEP,
    TunedClassifier,
    as_grid,
    tuned_spec,
)
from touchbench.benchmark.io.arff import read_arff

DATASETS = Path(__file__).resolve().parents[2] / "shared/datasets/uc3m-touch"


def load(robot: str) -> tuple[np.ndarray, np.ndarray]:
    """Features and gesture codes (rows with a missing gesture dropped)."""
    data = read_arff(DATASETS / robot / "gesture_and_place.arff")
    targets = set(data.schema.target_indices)
    features = [i for i in range(data.schema.n_attributes) if i not in targets]
    gesture = data.values[:, data.schema.target_indices[data.schema.target_names.index("gesture")]]
    keep = ~np.isnan(gesture)
    return data.values[keep][:, features], gesture[keep].astype(np.int64)


def timed_fold(model: object, X: np.ndarray, y: np.ndarray, train: np.ndarray, test: np.ndarray):
    """(weighted F1 on the test rows, seconds to fit and predict)."""
    started = time.perf_counter()
    model.fit(X[train], y[train])  # type: ignore[attr-defined]
    predicted = model.predict(X[test])  # type: ignore[attr-defined]
    seconds = time.perf_counter() - started
    return float(f1_score(y[test], predicted, average="weighted")), seconds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--classifiers", default="svm-rbf,logistic,ibk5-std")
    parser.add_argument("--folds", type=int, default=5)
    parser.add_argument("--budget", type=float, default=None, help="minutes (default: bench's)")
    parser.add_argument("--robot", default="mini")
    parser.add_argument(
        "--grid-max", type=int, default=100, help="skip full grids larger than this"
    )
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    with threadpool_limits(limits=1):  # single-threaded, as the engine's workers run
        compare(args)


def compare(args: argparse.Namespace) -> None:
    """Print the table for ``args.classifiers``."""
    X, y = load(args.robot)
    outer = list(StratifiedKFold(args.folds, shuffle=True, random_state=0).split(X, y))
    print(f"{args.robot} gesture: {len(y)} instances, {args.folds} outer folds, inner 3-fold")
    print(f"load average before: {' '.join(f'{v:.2f}' for v in os.getloadavg())}")
    header = (
        f"{'entry':<10} {'grid':>5} | {'default F1':>10} {'s/fold':>7} | {'halving F1':>10} "
        f"{'s/fold':>7} {'x default':>9} {'cands':>5} {'rows':>5} | {'grid F1':>8} {'s/fold':>7} "
        f"{'x halving':>9}"
    )
    print(header)
    print("-" * len(header))
    for classifier in args.classifiers.split(","):
        spec = get_spec(classifier)
        assert spec.search_space is not None, f"{classifier} has no search space"
        grid = as_grid(spec.search_space, f"{CLASSIFIER_STEP}__")
        size = len(ParameterGrid(grid))
        default = build_pipeline(spec, n_features=X.shape[1], random_state=0)
        tuned = build_pipeline(tuned_spec(spec, args.budget), n_features=X.shape[1], random_state=0)
        rows: dict[str, list[tuple[float, float]]] = {"default": [], "halving": [], "grid": []}
        candidates, rows_used = [], []
        for train, test in outer:
            rows["default"].append(timed_fold(clone(default), X, y, train, test))
            halving = clone(tuned)
            rows["halving"].append(timed_fold(halving, X, y, train, test))
            tuner = halving[-1]
            assert isinstance(tuner, TunedClassifier)
            candidates.append(tuner.n_candidates_)
            rows_used.append(tuner.n_resources_ / len(train))
            if size > args.grid_max:
                continue
            search = GridSearchCV(
                clone(default),
                grid,
                scoring="f1_weighted",
                cv=inner_folds(y[train], tuner.cv, tuner.random_state),
                error_score=np.nan,
            )
            rows["grid"].append(timed_fold(search, X, y, train, test))
        mean = {
            name: np.mean(values, axis=0) if values else np.full(2, np.nan)
            for name, values in rows.items()
        }
        print(
            f"{classifier:<10} {size:>5} | {mean['default'][0]:>10.4f} {mean['default'][1]:>7.2f} "
            f"| {mean['halving'][0]:>10.4f} {mean['halving'][1]:>7.2f} "
            f"{mean['halving'][1] / mean['default'][1]:>9.1f} {np.mean(candidates):>5.0f} "
            f"{np.mean(rows_used):>5.2f} "
            f"| {mean['grid'][0]:>8.4f} {mean['grid'][1]:>7.2f} "
            f"{mean['grid'][1] / mean['halving'][1]:>9.1f}",
            flush=True,
        )
    print(f"load average after: {' '.join(f'{v:.2f}' for v in os.getloadavg())}")


if __name__ == "__main__":
    main()
