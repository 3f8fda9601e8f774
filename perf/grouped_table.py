"""A table from another lab, grouped by object: how much of a k-fold score is the objects.

The BioTac SP grasp stability set (BTS3, Zapata-Impata, Gil and Torres, IROS 2018
workshop RoboTac; https://github.com/yayaneath/biotac-sp-images) has one CSV row per grasp:
the object grasped (41 household objects), ``slipped`` (0/1) and 72 BioTac SP electrode
values.  It is not shipped with touchbench; get it with

    git clone https://github.com/yayaneath/biotac-sp-images

This script imports ``biotac-palmdown-grasps.csv`` (or the file given) twice through the
import service, once as it stands (the object's name a feature, as before ``groups``) and
once with ``groups="object"``, then cross-validates a few catalogue classifiers under
stratified 10-fold on the plain import, and under group 10-fold and leave-one-object-out on
the grouped one, and prints the mean accuracy of each: the gap between the first and the
last is what memorising the objects was worth.

    .venv/bin/python perf/grouped_table.py [--csv PATH] [--classifiers rf,j48,nb]
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np

from touchbench.app.schemas.datasets import ImportRequest
from touchbench.app.services.datasets import import_file
from touchbench.app.store.database import Store
from touchbench.app.store.datasets import load_dataset
from touchbench.benchmark.problem import problem_from_dataset
from touchbench.benchmark.run.engine import Problem, run_tasks
from touchbench.benchmark.run.folds import FoldPlan, make_fold_plan

CSV = Path("biotac-sp-images/biotac-palmdown-grasps.csv")


def imported(store: Store, path: Path, **columns: str) -> str:
    """The stored data set's name."""
    request = ImportRequest(
        file=path, targets=["slipped"], name="grouped" if columns else "plain", **columns
    )
    return import_file(store, request).name


def accuracies(problem: Problem, plans: dict[str, FoldPlan], classifiers: list[str]) -> None:
    """One line per fold plan: its folds and each classifier's mean accuracy."""
    for label, plan in plans.items():
        results = run_tasks(problem, classifiers, plan.folds, jobs=2, timeout=None)
        means = {
            c: np.mean([r.metrics["accuracy"] for r in results if r.key.classifier == c])
            for c in classifiers
        }
        shown = "  ".join(f"{c} {means[c]:.3f}" for c in classifiers)
        print(f"  {label:34s} {len(plan.folds):3d} folds  {shown}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--csv", type=Path, default=CSV)
    parser.add_argument("--classifiers", default="rf,j48,nb")
    args = parser.parse_args()
    if not args.csv.is_file():
        raise SystemExit(f"{args.csv}: no such file (see this script's docstring for the data)")
    classifiers = args.classifiers.split(",")
    with tempfile.TemporaryDirectory() as folder:
        store = Store(f"sqlite:///{folder}/touchbench.db")
        plain = imported(store, args.csv)
        grouped = imported(store, args.csv, groups="object")
        plain_problem, _ = problem_from_dataset(load_dataset(store, plain))
        grouped_problem, _ = problem_from_dataset(load_dataset(store, grouped))
        groups = grouped_problem.groups
        assert groups is not None
        print(
            f"{args.csv.name}: {grouped_problem.n_instances} grasps of "
            f"{np.unique(groups).size} objects, {grouped_problem.n_features} features "
            f"({plain_problem.n_features} with the object's name)"
        )
        accuracies(
            plain_problem,
            {"stratified 10-fold, object a feature": make_fold_plan(plain_problem.Y, n_folds=10)},
            classifiers,
        )
        accuracies(
            grouped_problem,
            {
                "group 10-fold": make_fold_plan(grouped_problem.Y, n_folds=10, groups=groups),
                "leave-one-object-out": make_fold_plan(
                    grouped_problem.Y, groups=groups, split="leave-one-group-out"
                ),
            },
            classifiers,
        )
        store.dispose()


if __name__ == "__main__":
    main()
