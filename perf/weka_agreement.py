"""touchbench's WEKA-named entries beside WEKA itself: mean accuracy over repeated 10-fold CV.

For every catalogue entry that states a WEKA command line, and every data file, runs
Debian's WEKA (``java weka.classifiers... -t FILE -x 10 -s SEED``, seeds 1..R) and
touchbench's engine (stratified 10-fold CV repeated R times) and prints both means and
their difference; a difference above ``--tolerance`` points is flagged.  The folds differ
(WEKA draws its own), so the means, not single folds, are compared.  With
``--candidates``, entries built on other libraries are set beside the WEKA command they
would be named after, to show why they carry no WEKA name.

Data: WEKA's own example files (``/usr/share/doc/weka/examples``; the package ships
``segment-challenge.arff`` as its segment data) and the UC3M touch data
(``../shared/datasets``, one file per target, the other target removed).

    nice .venv/bin/python perf/weka_agreement.py [--repeats 10] [--files iris,vote]
        [--entries j48,nb] [--candidates] [--jobs 2] [--tolerance 2]
"""

from __future__ import annotations

import argparse
import functools
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

from touchbench.benchmark.catalogue import CATALOGUE
from touchbench.benchmark.io.arff import read_arff, write_arff
from touchbench.benchmark.problem import problem_from_dataset, restrict_targets
from touchbench.benchmark.run.engine import run_tasks
from touchbench.benchmark.run.folds import make_folds
from touchbench.benchmark.weka.reference import WEKA_DATA, cross_validated_accuracy, weka_jar

UC3M = Path(__file__).resolve().parents[2] / "shared/datasets/uc3m-touch"
WEKA_FILES = (
    "breast-cancer",
    "vote",
    "credit-g",
    "soybean",
    "labor",
    "diabetes",
    "iris",
    "segment-challenge",
)
UC3M_FILES = ("mini/gesture", "mini/place")

#: Entries on other libraries, and the WEKA command each would be named after.
CANDIDATES = {
    "rf": "weka.classifiers.trees.RandomForest -I 100 -K 0 -S 1",
    "svm-linear-smo": "weka.classifiers.functions.SMO",
    "logistic-mle": "weka.classifiers.functions.Logistic -R 1.0E-8 -M -1",
    "bagging-j48": "weka.classifiers.meta.Bagging -P 100 -S 1 -I 10 -W weka.classifiers.trees.J48",
    "stump": "weka.classifiers.trees.DecisionStump",
    "oner": "weka.classifiers.rules.OneR -B 6",
}


def data_files(names: list[str], folder: Path) -> dict[str, tuple[Path, str]]:
    """ARFF file per data set name and WEKA's class option (``last`` or ``first``)."""
    out: dict[str, tuple[Path, str]] = {}
    for name in names:
        if "/" not in name:
            out[name] = (WEKA_DATA / f"{name}.arff", "last")
            continue
        robot, target = name.split("/")
        source = UC3M / robot / "gesture_and_place.arff"
        if not source.is_file():
            print(f"skipped {name}: {source} not found", file=sys.stderr)
            continue
        dataset = restrict_targets(read_arff(source), [target])
        path = folder / f"{robot}-{target}.arff"
        with path.open("w") as stream:
            write_arff(dataset, stream)
        out[name] = (path, "first" if dataset.schema.target_indices == (0,) else "last")
    return out


def touchbench_accuracy(path: Path, ids: list[str], repeats: int, jobs: int) -> dict[str, float]:
    """Accuracy (percent) of each id, pooled over the folds of each repetition as WEKA
    reports it, then averaged over ``repeats`` x stratified 10-fold CV."""
    # WEKA's files: the last attribute is the class; ours: the MEKA header names it
    problem, _ = problem_from_dataset(read_arff(path))
    folds, _ = make_folds(problem.Y, n_folds=10, n_repeats=repeats)
    results = run_tasks(problem, ids, folds, jobs=jobs, timeout=None)
    out = {}
    for classifier in ids:
        mine = [r for r in results if r.key.classifier == classifier]
        if not mine or not all(r.ok for r in mine):
            out[classifier] = np.nan
            continue
        correct = sum(r.metrics["accuracy"] * r.n_test for r in mine)
        out[classifier] = 100.0 * correct / sum(r.n_test for r in mine)
    return out


def weka_accuracy(command: str, path: Path, class_index: str, repeats: int) -> float:
    """Mean of WEKA's stratified 10-fold CV accuracy over seeds 1..repeats."""
    return float(
        np.mean(
            [
                cross_validated_accuracy(command, path, seed=seed, class_index=class_index)
                for seed in range(1, repeats + 1)
            ]
        )
    )


def compare(
    files: dict[str, tuple[Path, str]],
    commands: dict[str, str],
    repeats: int,
    jobs: int,
    tolerance: float,
) -> list[tuple[str, str, float, float]]:
    rows = []
    for name, (path, class_index) in files.items():
        start = time.perf_counter()
        ours = touchbench_accuracy(path, list(commands), repeats, jobs)
        with ThreadPoolExecutor(max_workers=jobs) as pool:
            theirs = dict(
                zip(
                    commands,
                    pool.map(
                        functools.partial(
                            weka_accuracy, path=path, class_index=class_index, repeats=repeats
                        ),
                        commands.values(),
                    ),
                    strict=True,
                )
            )
        for classifier in commands:
            diff = ours[classifier] - theirs[classifier]
            flag = "  <-- differs" if not abs(diff) <= tolerance else ""
            print(
                f"{name:18s} {classifier:16s} WEKA {theirs[classifier]:6.2f}  "
                f"touchbench {ours[classifier]:6.2f}  diff {diff:+6.2f}{flag}",
                flush=True,
            )
            rows.append((name, classifier, theirs[classifier], ours[classifier]))
        print(f"  ({name}: {time.perf_counter() - start:.0f} s)", flush=True)
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--files", default=",".join(WEKA_FILES + UC3M_FILES))
    parser.add_argument("--entries", default="", help="ids (default: every WEKA-named entry)")
    parser.add_argument("--repeats", type=int, default=10)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--tolerance", type=float, default=2.0)
    parser.add_argument("--candidates", action="store_true")
    args = parser.parse_args()
    if weka_jar() is None:
        sys.exit("WEKA is not installed: apt-get install weka default-jre-headless")
    ids = (
        args.entries.split(",")
        if args.entries
        else [spec.id for spec in CATALOGUE.values() if spec.weka_command]
    )
    commands = {i: CATALOGUE[i].weka_command or "" for i in ids}
    if args.candidates:
        commands = dict(CANDIDATES)
    with tempfile.TemporaryDirectory() as folder:
        files = data_files(args.files.split(","), Path(folder))
        print(
            f"{len(commands)} entries x {len(files)} files, {args.repeats} x 10-fold CV "
            f"(accuracy %, WEKA {weka_jar()})",
            flush=True,
        )
        rows = compare(files, commands, args.repeats, args.jobs, args.tolerance)
    worst = max(rows, key=lambda r: abs(r[3] - r[2]), default=None)
    differing = [r for r in rows if not abs(r[3] - r[2]) <= args.tolerance]
    print(f"{len(rows)} comparisons; {len(differing)} beyond {args.tolerance} points", end="")
    print(f"; largest: {worst[0]} {worst[1]} {worst[3] - worst[2]:+.2f}" if worst else "")


if __name__ == "__main__":
    main()
