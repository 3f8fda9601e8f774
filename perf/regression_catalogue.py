"""The regression catalogue on a synthetic contact-localisation problem, through the engine.

No data set in ``../shared/datasets`` has numeric targets, so this script makes one: touches
at random (x, y) positions on a 40 x 30 cm plate with four contact microphones at its
corners; each touch gives per microphone a log amplitude (falling with distance, random
strength per touch), an arrival delay relative to the first microphone (distance over wave
speed, jittered) and a noisy spectral centroid that does not depend on the position.  Each
recording session has its own gain offset, so that instances of a session share something
the position does not explain.

For every regressor it prints MAE, RMSE, R^2 and the mean Euclidean error (cm) over the
engine's folds, and the fit time per fold; ``ridge`` and ``rf`` are also cross-validated by
scikit-learn's ``cross_validate`` on the same folds (the peer), with the ratio of their
MAEs (1.000: the same models) and of their wall times.  ``--groups`` runs the folds both
as shuffled k-fold and as group k-fold over sessions.

Usage::

    .venv/bin/python perf/regression_catalogue.py
    .venv/bin/python perf/regression_catalogue.py --n 800 --regressors ridge rf gp --groups
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Sequence

import numpy as np
from sklearn.base import clone
from sklearn.model_selection import cross_validate

from touchbench.benchmark.catalogue.regressors import REGRESSORS
from touchbench.benchmark.estimators import build_estimator
from touchbench.benchmark.evaluation.leaderboard import build_leaderboard
from touchbench.benchmark.problem import Problem
from touchbench.benchmark.run.engine import run_tasks
from touchbench.benchmark.run.folds import Fold, make_fold_plan

PLATE = (40.0, 30.0)
MICS = np.array([[0.0, 0.0], [40.0, 0.0], [0.0, 30.0], [40.0, 30.0]])
SPEED = 50.0  # cm per millisecond


def contact_problem(n: int, n_sessions: int, seed: int) -> Problem:
    """``n`` touches, targets (x, y) in cm, 12 features, ``n_sessions`` session groups."""
    rng = np.random.default_rng(seed)
    position = rng.uniform((0.0, 0.0), PLATE, size=(n, 2))
    session = rng.integers(0, n_sessions, size=n)
    gain = rng.normal(0.0, 0.3, size=n_sessions)[session]
    distance = np.linalg.norm(position[:, None, :] - MICS[None, :, :], axis=2) + 1.0
    strength = rng.normal(0.0, 0.2, size=n)
    amplitude = strength[:, None] + gain[:, None] - 1.5 * np.log(distance)
    amplitude += rng.normal(0.0, 0.05, size=amplitude.shape)
    arrival = distance / SPEED + rng.normal(0.0, 0.02, size=distance.shape)
    delay = arrival[:, 1:] - arrival[:, :1]
    centroid = rng.normal(2000.0, 300.0, size=(n, 4)) + 200.0 * gain[:, None]
    X = np.hstack([amplitude, delay, centroid[:, :1], centroid[:, 1:] / 1000.0, strength[:, None]])
    return Problem(
        X=X,
        Y=position,
        n_classes=(),
        target_names=("x", "y"),
        groups=session,
        task="regression",
        coordinates=(0, 1),
    )


def peer_mae(problem: Problem, regressor: str, folds: Sequence[Fold]) -> tuple[float, float]:
    """scikit-learn's ``cross_validate`` of the same pipeline on the same folds: MAE, seconds."""
    model = build_estimator(regressor, problem, random_state=0)
    splits = [(f.train, f.test) for f in folds]
    start = time.perf_counter()
    scores = cross_validate(
        clone(model), problem.X, problem.Y, cv=splits, scoring="neg_mean_absolute_error"
    )
    return float(-scores["test_score"].mean()), time.perf_counter() - start


def report(
    problem: Problem, regressors: Sequence[str], folds: int, grouped: bool, jobs: int
) -> None:
    plan = make_fold_plan(
        problem.Y, n_folds=folds, groups=problem.groups if grouped else None, regression=True
    )
    start = time.perf_counter()
    results = run_tasks(problem, regressors, plan.folds, jobs=jobs, timeout=1800)
    wall = time.perf_counter() - start
    board = build_leaderboard(results, metric="mae")
    print(
        f"\n{plan.scheme}, {len(plan.folds)} folds, {problem.n_instances} touches "
        f"({wall:.1f} s for the run, {jobs} worker(s)); marks against {board.baseline}"
    )
    print(
        f"{'#':>2} {'regressor':<12} {'':1} {'MAE cm':>14} {'RMSE cm':>14} {'R^2':>7} "
        f"{'Euclid cm':>14} {'fit s/fold':>10}"
    )
    for row in board.rows:
        if not row.n_ok:
            print(f"{row.rank:>2} {row.classifier:<12}   failed: {row.errors[:1]}")
            continue
        m = row.metrics
        print(
            f"{row.rank:>2} {row.classifier:<12} {row.mark or ' ':1} "
            f"{m['mae'][0]:7.3f} ±{m['mae'][1]:5.3f} {m['rmse'][0]:7.3f} ±{m['rmse'][1]:5.3f} "
            f"{m['r2'][0]:7.4f} {m['euclidean_error'][0]:7.3f} ±{m['euclidean_error'][1]:5.3f} "
            f"{m['fit_time'][0]:10.3f}"
        )
    engine = {row.classifier: row for row in board.rows}
    for regressor in ("ridge", "rf"):
        if regressor not in engine or not engine[regressor].n_ok:
            continue
        mae, seconds = peer_mae(problem, regressor, plan.folds)
        ours = engine[regressor].metrics["mae"][0]
        ours_time = sum(
            r.metrics["fit_time"] + r.metrics["predict_time"]
            for r in results
            if r.key.classifier == regressor and r.ok
        )
        print(
            f"peer sklearn cross_validate({regressor}): MAE {mae:.4f} (touchbench / peer "
            f"{ours / mae:.3f}); fit+predict {ours_time:.2f} s vs {seconds:.2f} s"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--n", type=int, default=1500, help="touches (default 1500)")
    parser.add_argument("--sessions", type=int, default=30)
    parser.add_argument("--folds", type=int, default=5)
    parser.add_argument("--jobs", type=int, default=1)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--regressors", nargs="+", default=[*REGRESSORS, "rc:svm-rbf", "rc:xgb"])
    parser.add_argument("--groups", action="store_true", help="also run group k-fold")
    args = parser.parse_args()
    problem = contact_problem(args.n, args.sessions, args.seed)
    report(problem, args.regressors, args.folds, False, args.jobs)
    if args.groups:
        report(problem, args.regressors, args.folds, True, args.jobs)


if __name__ == "__main__":
    main()
