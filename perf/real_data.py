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
beside a peer fitted by hand on the same windows and the same stratified folds (one slide
= one instance): aeon's ``MiniRocketClassifier``; for the interval forest, aeon's own
``RandomIntervals`` set to touchbench's seven statistics over the same three
representations and counts, with the same extra trees (:class:`AeonIntervalForest`), and
as references aeon's ``RandomIntervalClassifier`` (its own statistics, the series only)
and ``TimeSeriesForestClassifier``; scikit-learn's ``RandomForestClassifier`` on the flat
columns.  Beside each: the accuracy of every fold, and recording by recording how many
predictions differ and which side alone is right (a sign test), since on a few hundred
slides one point is a few recordings; ``--seeds N`` refits both sides under N seeds.  The
goal is agreement within 2 points.

    .venv/bin/python perf/real_data.py [--biotac PATH] [--fabric PATH] [--per-class 10]
        [--folds 5] [--jobs 1] [--seeds 1]
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
from aeon.classification.convolution_based import MiniRocketClassifier
from aeon.classification.interval_based import RandomIntervalClassifier, TimeSeriesForestClassifier
from aeon.transformations.collection.interval_based import RandomIntervals
from aeon.utils.numba import stats
from scipy.stats import binomtest
from sklearn.ensemble import ExtraTreesClassifier, RandomForestClassifier

from touchbench.app.errors import USER_ERRORS
from touchbench.app.services.extraction import extract_dataset
from touchbench.benchmark.estimators import build_estimator
from touchbench.benchmark.evaluation.leaderboard import build_leaderboard
from touchbench.benchmark.problem import Problem, problem_from_dataset
from touchbench.benchmark.results import TaskKey
from touchbench.benchmark.run.engine import run_tasks
from touchbench.benchmark.run.folds import Fold, make_folds
from touchbench.benchmark.sequence import panel

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


#: aeon's numba statistics in the order of touchbench's seven (mean, std, slope, median,
#: iqr, min, max), for the like-for-like interval peer.
AEON_STATISTICS = (
    "row_mean",
    "row_std",
    "row_slope",
    "row_median",
    "row_iqr",
    "row_numba_min",
    "row_numba_max",
)


class AeonIntervalForest:
    """The interval peer configured like touchbench's ``interval-forest``: aeon's own
    ``RandomIntervals`` (its draw, its numba statistics, set to touchbench's seven) over
    the series, its first difference and its amplitude spectrum, ``n_intervals`` each,
    then 300 entropy extra trees.  Fits sequences of shape (n, n_channels, length)."""

    def __init__(self, n_intervals: int, random_state: int) -> None:
        self.n_intervals = n_intervals
        self.random_state = random_state

    @staticmethod
    def _representations(X: np.ndarray) -> list[np.ndarray]:
        return [X, np.diff(X, axis=-1), np.abs(np.fft.rfft(X, axis=-1))]

    def fit(self, X: np.ndarray, y: np.ndarray) -> AeonIntervalForest:
        features = [getattr(stats, name) for name in AEON_STATISTICS]
        self.transforms_ = [
            RandomIntervals(
                n_intervals=self.n_intervals, features=features, random_state=self.random_state + i
            )
            for i in range(3)
        ]
        self.forest_ = ExtraTreesClassifier(
            n_estimators=300, criterion="entropy", random_state=self.random_state
        ).fit(self._features(X, fit=True), y)
        return self

    def _features(self, X: np.ndarray, fit: bool = False) -> np.ndarray:
        pairs = zip(self.transforms_, self._representations(X), strict=True)
        return np.hstack([t.fit_transform(r) if fit else t.transform(r) for t, r in pairs])

    def predict(self, X: np.ndarray) -> np.ndarray:
        return np.asarray(self.forest_.predict(self._features(X)))


@dataclass(frozen=True)
class Peer:
    """A plain aeon / scikit-learn classifier: what it is, how to make one with a seed, and
    what it reads: ``windows`` (n, n_channels, length) as touchbench has them, ``float32``
    windows (aeon's rockets compute in float32) or the ``flat`` columns (n, n_columns)."""

    label: str
    make: Callable[[int], Any]
    reads: str = "windows"


def peers(n_channels: int, length: int) -> dict[str, list[Peer]]:
    """Per touchbench classifier, its like-for-like peer first, then other references."""
    count = 4 + int(math.sqrt(length * n_channels))  # touchbench's default count
    return {
        "minirocket": [
            Peer(
                "aeon MiniRocketClassifier, 10,000 kernels",
                lambda seed: MiniRocketClassifier(n_kernels=10_000, random_state=seed),
                reads="float32",
            )
        ],
        "interval-forest": [
            Peer(
                f"aeon RandomIntervals, touchbench's 7 statistics, {count} intervals of each of "
                "series, difference, spectrum; 300 extra trees",
                lambda seed: AeonIntervalForest(count, seed),
            ),
            Peer(
                f"aeon RandomIntervalClassifier, its 7 statistics, {count} intervals of the "
                "series only; 300 extra trees",
                lambda seed: RandomIntervalClassifier(
                    n_intervals=count,
                    estimator=ExtraTreesClassifier(
                        n_estimators=300, criterion="entropy", random_state=seed
                    ),
                    random_state=seed,
                ),
            ),
            Peer(
                "aeon TimeSeriesForestClassifier, mean/std/slope, intervals per tree, 200 trees",
                lambda seed: TimeSeriesForestClassifier(n_estimators=200, random_state=seed),
            ),
        ],
        "rf": [
            Peer(
                "scikit-learn RandomForestClassifier, 100 trees, flat columns",
                lambda seed: RandomForestClassifier(n_estimators=100, random_state=seed),
                reads="flat",
            )
        ],
    }


def cross_predict(
    fit_predict: Callable[[np.ndarray, np.ndarray], np.ndarray], n: int, folds: Sequence[Fold]
) -> np.ndarray:
    """Out-of-fold predictions of shape (n,) (each fold's test part predicted once)."""
    predicted = np.empty(n, dtype=object)
    for fold in folds:
        predicted[fold.test] = fit_predict(fold.train, fold.test)
    return predicted


def fold_scores(predicted: np.ndarray, y: np.ndarray, folds: Sequence[Fold]) -> list[float]:
    """Accuracy of each fold's test part."""
    return [float(np.mean(predicted[fold.test] == y[fold.test])) for fold in folds]


def paired(ours: np.ndarray, theirs: np.ndarray, y: np.ndarray) -> str:
    """How two sets of predictions of the same recordings differ, with a sign test."""
    only_ours = int(np.sum((ours == y) & (theirs != y)))
    only_theirs = int(np.sum((ours != y) & (theirs == y)))
    p = binomtest(only_ours, only_ours + only_theirs).pvalue if only_ours + only_theirs else 1.0
    return (
        f"predictions differ on {int(np.sum(ours != theirs))} of {y.size} recordings; right "
        f"only in touchbench {only_ours}, only in the peer {only_theirs} (sign test p={p:.2f})"
    )


def _folds(scores: Sequence[float]) -> str:
    return " ".join(f"{score:.3f}" for score in scores)


def measure(
    source: Source, folder: Path, per_class: int, n_folds: int, jobs: int, seeds: int
) -> None:
    chosen = pick(source, folder, per_class)
    if not chosen:
        print(f"  {source.name}: no recordings match {source.pattern} under {folder}")
        return
    with tempfile.TemporaryDirectory() as scratch:
        labels = Path(scratch) / f"{source.name}.csv"
        labels.write_text(
            "file,label\n" + "".join(f"{path.name},{label}\n" for path, label in chosen.items())
        )
        start, options = time.perf_counter(), source.extraction
        try:
            extracted = extract_dataset(
                list(chosen), labels=labels, extractor="sequence", events="none", **options
            )
        except USER_ERRORS as error:
            print(f"  {source.name}: touchbench cannot read it: {error}")
            return
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
    notes = [*extracted.notes, *extracted.warnings]
    # one resampling note per recording: the first, then the other kinds of note
    resampled = [note for note in notes if "resampled to" in note]
    for note in [*resampled[:1], *[note for note in notes if note not in resampled][:5]]:
        print(f"    note: {note[:160]}")
    if len(resampled) > 1:
        print(f"    note: and {len(resampled) - 1} more recordings resampled from jittered stamps")
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
    engine_folds = {
        name: [
            result.metrics["accuracy"]
            for fold in folds
            for result in results
            if result.key == TaskKey(name, fold.repeat, fold.fold) and result.status == "ok"
        ]
        for name in CLASSIFIERS
    }
    windows = np.ascontiguousarray(panel(problem.X, problem.sequence.shape)[0])
    n_channels, length = windows.shape[1:]
    start = time.perf_counter()
    table = []
    for name, (peer, *references) in peers(n_channels, length).items():
        table.append(compare(name, peer, references, problem, windows, folds, seeds, engine_folds))
    plain_seconds = time.perf_counter() - start
    print(f"    {len(folds)}-fold accuracy   touchbench   aeon/scikit-learn   difference")
    for name, theirs in table:
        mine = ours.get(name, float("nan"))
        print(f"    {name:17s}    {mine:10.3f}   {theirs:17.3f}   {100 * (mine - theirs):+8.1f} pt")
    print(f"    wall: touchbench's engine {ours_seconds:.0f} s, by hand {plain_seconds:.0f} s")


def compare(
    name: str,
    peer: Peer,
    references: Sequence[Peer],
    problem: Problem,
    windows: np.ndarray,
    folds: Sequence[Fold],
    seeds: int,
    engine_folds: dict[str, list[float]],
) -> tuple[str, float]:
    """Print touchbench's classifier against its peer fold by fold and recording by
    recording; return the peer's mean accuracy (seed 0)."""
    y = problem.Y[:, 0]

    def ours_predict(seed: int) -> np.ndarray:
        def fit_predict(train: np.ndarray, test: np.ndarray) -> np.ndarray:
            model = build_estimator(name, problem, random_state=seed)
            return np.asarray(model.fit(problem.X[train], y[train]).predict(problem.X[test]))

        return cross_predict(fit_predict, y.size, folds)

    def peer_predict(p: Peer, seed: int) -> np.ndarray:
        X = {"windows": windows, "float32": windows.astype(np.float32), "flat": problem.X}[p.reads]

        def fit_predict(train: np.ndarray, test: np.ndarray) -> np.ndarray:
            return np.asarray(p.make(seed).fit(X[train], y[train]).predict(X[test]))

        return cross_predict(fit_predict, y.size, folds)

    mine, theirs = ours_predict(0), peer_predict(peer, 0)
    mine_folds, their_folds = fold_scores(mine, y, folds), fold_scores(theirs, y, folds)
    same = np.allclose(mine_folds, engine_folds[name])
    print(f"    {name} against {peer.label}")
    print(
        f"      per fold: touchbench {_folds(mine_folds)} | peer {_folds(their_folds)}"
        + ("" if same else f" (the engine's folds: {_folds(engine_folds[name])})")
    )
    print(f"      {paired(mine, theirs, y)}")
    for reference in references:
        other = peer_predict(reference, 0)
        print(
            f"      reference {reference.label}: {np.mean(fold_scores(other, y, folds)):.3f}; "
            + paired(mine, other, y)
        )
    if seeds > 1:
        spread = {
            "touchbench": [np.mean(mine_folds)]
            + [np.mean(fold_scores(ours_predict(s), y, folds)) for s in range(1, seeds)],
            "peer": [np.mean(their_folds)]
            + [np.mean(fold_scores(peer_predict(peer, s), y, folds)) for s in range(1, seeds)],
        }
        print(
            f"      seeds 0-{seeds - 1}: "
            + "; ".join(
                f"{side} mean {np.mean(values):.3f}, {min(values):.3f}-{max(values):.3f}"
                for side, values in spread.items()
            )
        )
    return name, float(np.mean(their_folds))


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
    parser.add_argument(
        "--seeds", type=int, default=1, help="refit both sides under this many seeds"
    )
    args = parser.parse_args()
    print("public recordings read by touchbench, scored beside aeon / scikit-learn")
    for source in SOURCES.values():
        if args.only and source.name != args.only:
            continue
        folder = checkout(source, getattr(args, source.name))
        if folder is not None:
            measure(source, folder, args.per_class, args.folds, args.jobs, args.seeds)


if __name__ == "__main__":
    main()
