"""kill -9 of `touchbench bench` while a network trains, then `--resume`: the same scores."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from tests.support.gate import CNN1D_PARAMS, SMALL, Gate
from tests.support.sequences import sequence_dataset, shapes
from touchbench.app.store.database import Store
from touchbench.app.store.datasets import add_dataset, dataset_digest
from touchbench.benchmark.catalogue import get_spec
from touchbench.benchmark.estimators import build_estimator
from touchbench.benchmark.problem import problem_from_dataset
from touchbench.benchmark.run.folds import make_fold_plan

FOLDS = 3


def _stored(url: str) -> dict[int, float]:
    """Accuracy of each fold of run 1 stored so far, by fold."""
    store = Store(url)
    try:
        with store.engine.connect() as connection:
            rows = connection.exec_driver_sql(
                "SELECT fold, metrics FROM fold_results WHERE run_id = 1"
            ).all()
    finally:
        store.dispose()
    return {fold: json.loads(metrics)["accuracy"] for fold, metrics in rows}


def test_a_network_run_killed_mid_training_resumes_to_the_same_scores(tmp_path: Path) -> None:
    assert get_spec("cnn1d").params == CNN1D_PARAMS  # gate-cnn1d is cnn1d behind a gate
    data = sequence_dataset(*shapes(36))
    url = f"sqlite:///{tmp_path / 'runs.db'}"
    store = Store(url)
    add_dataset(store, data, sha256=dataset_digest(data))
    store.dispose()
    gate = Gate(tmp_path / "gate")
    gate.open()  # every fit goes through; its started-* file says its training began
    environment = {**os.environ, **gate.environment()}
    bench = [sys.executable, "-m", "touchbench.app.cli.main", "--db", url, "bench"]
    child = subprocess.Popen(
        [*bench, "shapes", "-c", "gate-cnn1d", "--folds", str(FOLDS), "--jobs", "1"],
        env=environment,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )
    deadline = time.monotonic() + 300
    try:
        while gate.started() < 2:  # the first fold is trained: the second is training now
            assert child.poll() is None, child.stderr.read().decode() if child.stderr else ""
            assert time.monotonic() < deadline, "the first fold did not train in 5 minutes"
            time.sleep(0.02)
    finally:
        os.kill(child.pid, signal.SIGKILL)
        child.wait()
    before = _stored(url)
    assert len(before) < FOLDS, "the run ended before it was killed"

    resumed = subprocess.run(
        [*bench, "--resume", "1", "--json"], env=environment, capture_output=True, timeout=300
    )
    assert resumed.returncode == 0, resumed.stderr.decode()
    after = _stored(url)
    assert sorted(after) == list(range(FOLDS))
    assert {fold: after[fold] for fold in before} == before  # kept, not trained again

    # The same folds trained here, uninterrupted: the scores of the killed and resumed run.
    problem, _ = problem_from_dataset(data)
    plan = make_fold_plan(problem.Y, n_folds=FOLDS, seed=0, target_names=problem.target_names)
    for fold in plan.folds:
        model = build_estimator("cnn1d", problem, random_state=0)
        model.set_params(**{f"classifier__{key}": value for key, value in SMALL.items()})
        y = problem.Y[:, 0]
        model.fit(problem.X[fold.train], y[fold.train])
        accuracy = float(np.mean(model.predict(problem.X[fold.test]) == y[fold.test]))
        assert after[fold.fold] == pytest.approx(accuracy, abs=1e-12), fold.fold
