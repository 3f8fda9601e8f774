"""Public tactile recordings that other people's tools wrote, read by touchbench and scored
beside a plain aeon / scikit-learn script on the same arrays and folds.

Two public data sets (neither is in this repository; give a checkout's path, or the script
clones it into ``/tmp/touchbench-real-data``):

* ``biotac``: https://github.com/dexrob/BioTac_slide_20_50 -- a BioTac sliding over 20
  materials, 50 slides each: ``raw_data/matX/matX_N_bio.csv``, exported from ROS bags
  (a ``timestamp`` column of ROS stamps in seconds with jitter, 44 named channels tdc,
  tac, pdc, pac1..22, ele1..19, a trailing comma on every row).  Read as whole slides of
  400 samples at 100 Hz (the authors' own length).
* ``fabric``: https://github.com/wngfra/FabricSlide -- a finger-shaped capacitive sensor
  (2 proximity and 16 taxel channels, about 35 Hz, a ``timestamp`` column in
  milliseconds) sliding over 7 fabrics at several forces and speeds:
  ``data/fabric/NAME_Fforce_V-speed_rep.csv``.  Read as the first 512 samples of each slide.

For each, the script prints what touchbench read (recordings, channels, rate, notes) and
the accuracy of ``minirocket``, ``interval-forest`` and ``rf`` through touchbench's engine
beside aeon's ``MiniRocketClassifier``, aeon's ``RandomIntervalClassifier`` (extra trees,
as touchbench's entry) and scikit-learn's ``RandomForestClassifier`` fitted by hand on the
same windows and the same stratified folds (one slide = one instance).  The goal is
agreement within 2 points.

    .venv/bin/python perf/real_data.py [--biotac PATH] [--fabric PATH] [--per-class 10]
        [--folds 5] [--jobs 1]
"""

from __future__ import annotations

import argparse
import math
import re
import subprocess
import tempfile
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from app.services.extraction import extract_dataset
from benchmark.evaluation.leaderboard import build_leaderboard
from benchmark.problem import problem_from_dataset
from benchmark.run.engine import run_tasks
from benchmark.run.folds import Fold, make_folds
from benchmark.sequence import panel

CLASSIFIERS = ("minirocket", "interval-forest", "rf")
CLONES = Path("/tmp/touchbench-real-data")


@dataclass(frozen=True)
class Source:
    """A public data set: where it lives, which files are recordings, and their labels."""

    name: str
    url: str
    pattern: str
    label: Callable[[Path], str]
    order: Callable[[Path], tuple[Any, ...]]
    extraction: dict[str, Any]


def _trial(path: Path) -> tuple[Any, ...]:
    """Files in the order of their numbers (``mat3_12_bio`` after ``mat3_2_bio``)."""
    return tuple(int(part) if part.isdigit() else part for part in re.split(r"(\d+)", path.name))


SOURCES = {
    "biotac": Source(
        "biotac",
        "https://github.com/dexrob/BioTac_slide_20_50",
        "raw_data/mat*/mat*_*_bio.csv",
        label=lambda path: path.parent.name,
        order=_trial,
        extraction={"samplerate": 100.0, "options": {"length": "400"}},
    ),
    "fabric": Source(
        "fabric",
        "https://github.com/wngfra/FabricSlide",
        "data/fabric/*.csv",
        label=lambda path: path.name.split("_")[0],
        order=_trial,
        extraction={"time_unit": "ms", "options": {"length": "512"}},
    ),
}


def checkout(source: Source, given: Path | None) -> Path | None:
    """The data set's folder: the given one, else a shallow clone under /tmp."""
    if given is not None:
        return given
    target = CLONES / source.name
    if not target.is_dir():
        CLONES.mkdir(parents=True, exist_ok=True)
        cloned = subprocess.run(
            ["git", "clone", "--depth", "1", source.url, str(target)],
            capture_output=True,
            text=True,
            check=False,
        )
        if cloned.returncode != 0:
            print(f"  {source.name}: cannot clone {source.url}: {cloned.stderr.strip()[-200:]}")
            return None
    return target


def pick(source: Source, folder: Path, per_class: int) -> dict[Path, str]:
    """The first ``per_class`` recordings of every class, with their labels."""
    by_class: dict[str, list[Path]] = {}
    for path in sorted(folder.glob(source.pattern), key=source.order):
        by_class.setdefault(source.label(path), []).append(path)
    return {path: label for label, paths in sorted(by_class.items()) for path in paths[:per_class]}


def plain_scores(
    windows: np.ndarray, flat: np.ndarray, y: np.ndarray, folds: Sequence[Fold]
) -> dict[str, float]:
    """Mean accuracy over ``folds`` of aeon's and scikit-learn's own classifiers."""
    from aeon.classification.convolution_based import MiniRocketClassifier
    from aeon.classification.interval_based import RandomIntervalClassifier
    from sklearn.ensemble import ExtraTreesClassifier, RandomForestClassifier

    n_channels, length = windows.shape[1:]
    intervals = 4 + int(math.sqrt(length * n_channels))  # touchbench's default count
    makers: dict[str, Callable[[], Any]] = {
        "minirocket": lambda: MiniRocketClassifier(n_kernels=10_000, random_state=0),
        "interval-forest": lambda: RandomIntervalClassifier(
            n_intervals=intervals,
            estimator=ExtraTreesClassifier(n_estimators=300, criterion="entropy", random_state=0),
            random_state=0,
        ),
        "rf": lambda: RandomForestClassifier(n_estimators=100, random_state=0),
    }
    scores = {}
    for name, make in makers.items():
        data = flat if name == "rf" else windows
        accuracy = []
        for fold in folds:
            model = make().fit(data[fold.train], y[fold.train])
            accuracy.append(float(np.mean(model.predict(data[fold.test]) == y[fold.test])))
        scores[name] = float(np.mean(accuracy))
    return scores


def measure(source: Source, folder: Path, per_class: int, n_folds: int, jobs: int) -> None:
    chosen = pick(source, folder, per_class)
    if not chosen:
        print(f"  {source.name}: no recordings match {source.pattern} under {folder}")
        return
    with tempfile.TemporaryDirectory() as scratch:
        labels = Path(scratch) / f"{source.name}.csv"
        labels.write_text(
            "file,label\n" + "".join(f"{path.name},{label}\n" for path, label in chosen.items())
        )
        start = time.perf_counter()
        extracted = extract_dataset(
            list(chosen), labels=labels, extractor="sequence", events="none", **source.extraction
        )
        seconds = time.perf_counter() - start
    problem, _ = problem_from_dataset(extracted.dataset)
    assert problem.sequence is not None
    names = extracted.dataset.schema.feature_names
    channels = list(dict.fromkeys(name.split("[")[0] for name in names))
    classes = sorted(set(chosen.values()))
    print(
        f"  {source.name} ({source.url}): {len(chosen)} recordings, {len(classes)} classes, "
        f"read in {seconds:.1f} s"
    )
    print(f"    {problem.sequence.describe()}; channels: {', '.join(channels[:8])}, ...")
    for note in [*extracted.notes, *extracted.warnings][:4]:
        print(f"    note: {note[:160]}")
    folds, _ = make_folds(problem.Y, n_folds=n_folds, groups=problem.groups, seed=0)
    start = time.perf_counter()
    results = run_tasks(problem, CLASSIFIERS, folds, jobs=jobs, timeout=3600)
    ours_seconds = time.perf_counter() - start
    board = build_leaderboard(results)
    ours = {
        row.classifier: float(row.metrics["accuracy"][0]) for row in board.rows if not row.n_failed
    }
    for row in board.rows:
        if row.n_failed:
            print(f"    {row.classifier}: failed: {row.errors[0][:160]}")
    windows = panel(problem.X, problem.sequence.shape)[0]
    y = problem.Y[:, 0]
    start = time.perf_counter()
    plain = plain_scores(np.ascontiguousarray(windows, dtype=np.float32), problem.X, y, folds)
    plain_seconds = time.perf_counter() - start
    print(f"    {len(folds)}-fold accuracy   touchbench   aeon/scikit-learn   difference")
    for name in CLASSIFIERS:
        mine, theirs = ours.get(name, float("nan")), plain[name]
        gap = 100 * (mine - theirs)
        print(f"    {name:17s}    {mine:10.3f}   {theirs:17.3f}   {gap:+8.1f} pt")
    print(f"    wall: touchbench {ours_seconds:.0f} s, plain script {plain_seconds:.0f} s")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    for source in SOURCES.values():
        parser.add_argument(
            f"--{source.name}", type=Path, metavar="PATH", help=f"a checkout of {source.url}"
        )
    parser.add_argument("--only", choices=sorted(SOURCES), help="measure one data set")
    parser.add_argument("--per-class", type=int, default=10, help="recordings per class")
    parser.add_argument("--folds", type=int, default=5)
    parser.add_argument("--jobs", type=int, default=1)
    args = parser.parse_args()
    print("public recordings read by touchbench, scored beside aeon / scikit-learn")
    for source in SOURCES.values():
        if args.only and source.name != args.only:
            continue
        folder = checkout(source, getattr(args, source.name))
        if folder is not None:
            measure(source, folder, args.per_class, args.folds, args.jobs)


if __name__ == "__main__":
    main()
