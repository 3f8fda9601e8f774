"""Time-series classifiers on whole event windows against flat features, same folds.

The issue's reference: on whole event windows of a real tactile array, MiniRocket reached
about 0.79 accuracy in 5-fold cross-validation where a random forest on hand-made
features reached 0.47-0.49.  This script measures the same comparison on the data there
is here, in one run:

* the simulated oscillating link (``touchbench simulate oscillating-link``: 3-axis
  accelerometer at 3200 Hz, 6 contact classes, one instance per second of a trial):
  ``band-peaks`` and MFCC summaries under a random forest, against the raw 3 x 3200
  windows (``sequence``) and the MFCC frames (``mfcc`` with ``frames=98``) under
  MiniRocket, MultiRocket and the interval forest;
* simulated contact-microphone sessions (``touchbench simulate contact-mic``, gesture
  and place): ``uc3m-audio`` under a random forest against MFCC frames under MiniRocket;
* the reference recordings in ``../shared/datasets``, when they hold raw windows (the
  UC3M files hold only the published features: the script says so).

Folds are group-aware (a trial or session stays on one side) and stratified, as
``touchbench bench`` makes them; every comparison uses the same folds.  Then the cost of
a sequence model's input: MiniRocket's transform per 1000 windows against the flat
extractor (``band-peaks``) on the same windows, both single-threaded.

    .venv/bin/python perf/sequences.py [--trials 60] [--sessions 8] [--folds 5] [--jobs 2]
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

from touchbench.app.services.extraction import extract_dataset
from touchbench.app.services.simulation import write_contact_mic_sessions, write_link_trials
from touchbench.benchmark.dataset import Dataset
from touchbench.benchmark.evaluation.leaderboard import build_leaderboard
from touchbench.benchmark.io.arff import read_arff
from touchbench.benchmark.problem import problem_from_dataset, restrict_targets
from touchbench.benchmark.run.engine import run_tasks
from touchbench.benchmark.run.folds import make_folds
from touchbench.benchmark.sequence import find_sequence, panel
from touchbench.features.events import Detection, Event
from touchbench.features.extractors import make_extractor

SHARED = Path(__file__).resolve().parents[2] / "shared/datasets"
FLAT = ("rf",)
SEQUENCE = ("minirocket", "multirocket", "interval-forest")


def cross_validate(
    recordings: Sequence[Path],
    labels: Path,
    extractor: str,
    classifiers: Sequence[str],
    *,
    target: str,
    folds: int,
    jobs: int,
    events: str | None = None,
    segment: float | None = None,
    options: dict[str, str] | None = None,
) -> dict[str, tuple[float, float, float]]:
    """Accuracy (mean, std over folds) and fit seconds per fold of each classifier."""
    extracted = extract_dataset(
        recordings,
        labels=labels,
        extractor=extractor,
        events=events,
        segment=segment,
        options=options,
    )
    data = restrict_targets(extracted.dataset, [target])
    return cross_validate_data(
        data, classifiers, folds=folds, jobs=jobs, label=f"{extractor} {options or ''}: "
    )


def cross_validate_data(
    data: Dataset, classifiers: Sequence[str], *, folds: int, jobs: int, label: str = ""
) -> dict[str, tuple[float, float, float]]:
    """Accuracy (mean, std over folds) and fit seconds per fold of each classifier on
    ``data``, folds grouped as the data set groups its instances; printed as they come."""
    problem, _ = problem_from_dataset(data)
    splits, _ = make_folds(problem.Y, n_folds=folds, groups=problem.groups, seed=0)
    results = run_tasks(problem, classifiers, splits, jobs=jobs, timeout=3600)
    board = build_leaderboard(results)
    shape = problem.sequence.describe() if problem.sequence else f"{problem.n_features} features"
    print(f"    {label}{problem.n_instances} instances, {shape}")
    scores = {}
    for row in board.rows:
        if row.n_failed:
            print(f"      {row.classifier}: failed: {row.errors[0]}")
            continue
        mean, std = row.metrics["accuracy"]
        fit = row.metrics["fit_time"][0]
        scores[row.classifier] = (mean, std, fit)
        print(f"      {row.classifier:16s} accuracy {mean:.3f} ± {std:.3f}   fit {fit:7.2f} s/fold")
    return scores


def link(folder: Path, trials: int, folds: int, jobs: int) -> None:
    recordings, labels = write_link_trials(folder, trials=trials, seed=1)
    print(f"  oscillating link: {trials} trials of 3 s, 6 contact classes, {folds}-fold by trial")
    common = {"target": "contact", "folds": folds, "jobs": jobs, "events": "none", "segment": 1.0}
    flat = cross_validate(recordings, labels, "band-peaks", FLAT, **common)
    summary = cross_validate(recordings, labels, "mfcc", FLAT, **common)
    raw = cross_validate(
        recordings, labels, "sequence", (*SEQUENCE, *FLAT), options={"length": "3200"}, **common
    )
    frames = cross_validate(
        recordings, labels, "mfcc", ("minirocket",), options={"frames": "98"}, **common
    )
    best_flat = max(flat["rf"][0], summary["rf"][0])
    best_sequence = max(raw.get("minirocket", (0.0,))[0], frames.get("minirocket", (0.0,))[0])
    print(
        f"  => link: MiniRocket {best_sequence:.3f} vs random forest on hand-made features "
        f"{best_flat:.3f} (margin {best_sequence - best_flat:+.3f})"
    )


def contact_mic(folder: Path, sessions: int, folds: int, jobs: int) -> None:
    recordings, labels = write_contact_mic_sessions(folder, trials=sessions, seed=1)
    print(f"  contact microphones: {sessions} sessions of 16 touches, {folds}-fold by session")
    for target in ("gesture", "place"):
        common = {"target": target, "folds": folds, "jobs": jobs, "events": "snr"}
        flat = cross_validate(recordings, labels, "uc3m-audio", FLAT, **common)
        frames = cross_validate(
            recordings, labels, "mfcc", ("minirocket", "interval-forest"),
            options={"frames": "32"}, **common,
        )  # fmt: skip
        print(
            f"  => {target}: MiniRocket on MFCC frames {frames.get('minirocket', (0.0,))[0]:.3f}"
            f" vs random forest on uc3m-audio {flat['rf'][0]:.3f}"
        )


def shared_data() -> None:
    files = sorted(SHARED.glob("**/*.arff")) if SHARED.is_dir() else []
    if not files:
        print(f"  reference data: {SHARED} is absent; nothing to measure there")
        return
    with_windows = []
    for path in files:
        if path.name.startswith("weka_results"):
            continue
        layout, _ = find_sequence(read_arff(path).schema.feature_names)
        if layout is not None:
            with_windows.append(path)
    if not with_windows:
        print(
            f"  reference data: the {len(files)} ARFF files under {SHARED} hold published "
            "features only, no raw windows (no CHANNEL[T] attributes, no recordings): the "
            "sequence path cannot be measured on them"
        )


def transform_cost(folder: Path, n_windows: int) -> None:
    """MiniRocket's transform against band-peaks' extraction, per 1000 1-s link windows."""
    recordings, labels = write_link_trials(folder, trials=max(1, n_windows // 3), seed=7)
    extracted = extract_dataset(
        recordings,
        labels=labels,
        extractor="sequence",
        events="none",
        segment=1.0,
        options={"length": "3200"},
    )
    problem, _ = problem_from_dataset(extracted.dataset)
    assert problem.sequence is not None
    windows = panel(problem.X, problem.sequence.shape)[0]
    from aeon.transformations.collection.convolution_based import MiniRocket

    with threadpool_limits(limits=1):
        rocket = MiniRocket(n_kernels=10_000, n_jobs=1, random_state=0)
        rocket.fit(windows[:8].astype(np.float32))
        rocket.transform(windows[:2].astype(np.float32))  # compiled before the clock starts
        start = time.perf_counter()
        rocket.transform(np.ascontiguousarray(windows, dtype=np.float32))
        rocket_seconds = time.perf_counter() - start
        flat = make_extractor("band-peaks")
        whole = Detection(events=(Event(0, windows.shape[2], (0, 1, 2)),))
        start = time.perf_counter()
        for window in windows:
            flat.extract(window, samplerate=3200.0, detection=whole)
        flat_seconds = time.perf_counter() - start
    per = 1000 / len(windows)
    print(
        f"  per 1000 windows of 3 x 3200 ({len(windows)} measured, one thread): MiniRocket "
        f"transform {rocket_seconds * per:.2f} s, band-peaks extraction {flat_seconds * per:.2f} s"
        f" (ratio {rocket_seconds / flat_seconds:.1f}x)"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--trials", type=int, default=60, help="oscillating-link trials")
    parser.add_argument("--sessions", type=int, default=8, help="contact-mic sessions")
    parser.add_argument("--folds", type=int, default=5)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--windows", type=int, default=300, help="windows timed")
    args = parser.parse_args()
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(scratch)
        shared_data()
        link(folder / "link", args.trials, args.folds, args.jobs)
        contact_mic(folder / "mic", args.sessions, args.folds, args.jobs)
        transform_cost(folder / "timing", args.windows)


if __name__ == "__main__":
    main()
