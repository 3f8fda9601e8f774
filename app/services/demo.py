"""The demo: simulated touch sessions -> event detection and features -> a stored data set
-> cross-validated leaderboard -> a trained model predicting a session it never saw ->
the same model recognising the touches of a fresh take replayed as a live stream.

Everything is generated (seeded) so that a newcomer sees the whole path work on a fresh
machine without data of their own.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from touchbench.app.schemas.models import TrainRequest
from touchbench.app.schemas.runs import BenchRequest
from touchbench.app.services.extraction import extract_dataset
from touchbench.app.services.live import TouchPrediction, open_live
from touchbench.app.services.models import Predictions, load_model, predict, train
from touchbench.app.services.runs import (
    create_run,
    default_classifiers,
    execute_run,
    run_leaderboard,
)
from touchbench.app.services.simulation import write_labels, write_session
from touchbench.app.store.database import Store
from touchbench.app.store.datasets import DatasetInfo, add_dataset, dataset_digest
from touchbench.app.store.runs import RunInfo
from touchbench.benchmark.evaluation.leaderboard import Leaderboard
from touchbench.benchmark.io.arff import read_arff, write_arff
from touchbench.drivers.replay import FileReplaySource


@dataclass
class DemoResult:
    dataset: DatasetInfo
    run: RunInfo
    leaderboard: Leaderboard
    model_name: str
    holdout: Path
    predictions: Predictions
    live: list[TouchPrediction]
    live_truth: list[tuple[float, float, str, str]]


def run_demo(
    folder: Path,
    store: Store,
    *,
    n_sessions: int = 4,
    touches_per_session: int = 16,
    folds: int = 5,
    jobs: int = 1,
    say: Callable[[str], None] = print,
) -> DemoResult:
    """Carry out the whole path in ``folder`` with the store ``store``."""
    folder.mkdir(parents=True, exist_ok=True)
    say(f"1. simulating {n_sessions} touch sessions (3 contact microphones, 44.1 kHz)")
    recordings, rows = [], []
    for s in range(n_sessions):
        path, touches = write_session(
            folder, f"session{s + 1}", n_touches=touches_per_session, seed=s
        )
        recordings.append(path)
        rows += [(path.name, *touch) for touch in touches]
    labels = write_labels(folder / "labels.csv", rows)

    say("2. detecting touches and extracting the UC3M audio features")
    extraction = extract_dataset(
        recordings, labels=labels, extractor="uc3m-audio", name="demo-touch"
    )
    dataset, _ = add_dataset(
        store,
        extraction.dataset,
        sha256=dataset_digest(extraction.dataset),
        name=None,
        source_name="labels.csv",
        extraction=extraction.recipe,
    )
    say(
        f"   {extraction.n_events} events found, {extraction.n_labelled} labelled -> "
        f"dataset '{dataset.name}' ({dataset.n_instances} instances x "
        f"{dataset.n_features} features, targets {', '.join(dataset.targets)})"
    )

    classifiers = default_classifiers(len(dataset.targets), "fast")
    say(f"3. cross-validating {len(classifiers)} classifiers (every fold stored as it ends)")
    request = BenchRequest(dataset=str(dataset.id), classifiers=classifiers, folds=folds)
    run = execute_run(store, create_run(store, request).id, jobs=jobs)
    board = run_leaderboard(store, run.id).board

    best = board.rows[0].classifier
    say(f"4. training {best} on every instance and predicting a session it never saw")
    model = train(store, TrainRequest(dataset=dataset.id, classifier=best))
    holdout_wav, holdout_touches = write_session(
        folder, "holdout", n_touches=touches_per_session, seed=1000
    )
    holdout_labels = write_labels(
        folder / "holdout-labels.csv", [(holdout_wav.name, *t) for t in holdout_touches]
    )
    holdout = extract_dataset(
        [holdout_wav], labels=holdout_labels, extractor="uc3m-audio", name="holdout"
    ).dataset
    holdout_arff = folder / "holdout.arff"
    write_arff(holdout, holdout_arff)
    _, trained = load_model(store, model.id)
    predictions = predict(trained, read_arff(holdout_arff), source=str(holdout_arff))

    say("5. replaying a fresh simulated take through `live`: each touch predicted as it ends")
    take, truth = write_session(folder, "live-take", n_touches=8, seed=2000)
    live: list[TouchPrediction] = []
    with FileReplaySource(take, block_length=1024) as source:
        session = open_live(
            store, model.id, samplerate=source.samplerate, n_channels=source.n_channels
        )
        for block in source.blocks():
            live += session.feed(block.samples, block.time)
        live += session.finish()
    return DemoResult(dataset, run, board, model.name, holdout_arff, predictions, live, list(truth))
