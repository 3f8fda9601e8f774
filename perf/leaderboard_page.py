"""The web page's leaderboard beside the JSON leaderboard, server-side, for a large run.

Builds a run of 88 catalogue configurations x 10 folds in a fresh store (SQLite by
default), writing the 880 fold results through the store's own ``record_result`` as the
engine does (realistic metrics and confusion matrices, no model trained), then times, in
one process and alternately, what the service does for

- ``GET /api/runs/{id}/leaderboard`` (the JSON endpoint), and
- ``GET /fragments/runs/{id}/leaderboard`` (the HTML the run page shows), ranked by the
  default metric, and by kappa against another baseline (a click on the page),

through the ASGI application in-process (no socket: the server's work alone).  The goal
is under 300 ms for the page's leaderboard.  Prints median and best times and the ratios;
nothing is asserted.

``--first-rankings K`` times instead, in CPU seconds (``time.process_time``: the machine may
be busy), what a service process spends on the first ranking of a new version of a run's
results (:func:`~app.services.runs.ranked_run` with nothing kept), K times, and the progress
a page polls every second; ``--results-file N`` makes the run by importing a results file
of N classifiers x 10 folds instead (an imported paper's run, as ``perf/hostile.py --only
pages`` does with 3,000).  To compare two versions of the code, run this file from a copy
of each tree in turn against the same store (``--db URL --run ID``), alternately.

    .venv/bin/python perf/leaderboard_page.py [--classifiers 88] [--folds 10]
        [--requests 30] [--db URL] [--results-file N] [--first-rankings K] [--run ID]
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from fastapi.testclient import TestClient  # noqa: E402

from tests.support.hostile_inputs import results_arff  # noqa: E402
from tests.support.synthetic import touch_arff  # noqa: E402
from touchbench.app.main import create_app  # noqa: E402
from touchbench.app.schemas.datasets import ImportRequest  # noqa: E402
from touchbench.app.schemas.imported import ImportResultsRequest  # noqa: E402
from touchbench.app.services.datasets import import_file  # noqa: E402
from touchbench.app.services.imported import import_results  # noqa: E402
from touchbench.app.services.lifecycle import run_progress  # noqa: E402
from touchbench.app.services.runs import leaderboard, ranked_run  # noqa: E402
from touchbench.app.settings import Settings  # noqa: E402
from touchbench.app.store.database import Store  # noqa: E402
from touchbench.app.store.runs import create_run, finish_run, record_result  # noqa: E402
from touchbench.benchmark.catalogue import CATALOGUE  # noqa: E402
from touchbench.benchmark.results import TaskKey, TaskResult  # noqa: E402

#: Every score a multi-class fold records, with its direction (True: higher is better).
SCORES = (
    "accuracy",
    "balanced_accuracy",
    "f1_macro",
    "f1_weighted",
    "kappa",
    "mcc",
    "precision_weighted",
    "recall_weighted",
    "roc_auc",
)
COSTS = ("fit_time", "predict_time", "fit_cpu_time", "predict_cpu_time", "log_loss")


def build_run(store: Store, folder: Path, n_classifiers: int, n_folds: int) -> int:
    """A data set and a finished run of ``n_classifiers`` x ``n_folds`` recorded results."""
    data = touch_arff(folder / "touch.arff", n=300, with_place=False)
    dataset = import_file(store, ImportRequest(file=data, name="perf"))
    ids = list(CATALOGUE)[:n_classifiers]
    if len(ids) < n_classifiers:
        raise SystemExit(f"the catalogue has {len(ids)} configurations, fewer than asked")
    run = create_run(
        store,
        dataset_id=dataset.id,
        kind="multiclass",
        targets=["gesture"],
        classifiers=ids,
        config={
            "folds": n_folds,
            "folds_requested": n_folds,
            "repeats": 1,
            "seed": 0,
            "timeout": 600.0,
            "max_memory_mb": None,
            "targets_given": ["gesture"],
            "suite": None,
            "weka": {},
            "n_tasks": n_classifiers * n_folds,
            "n_instances": 300,
            "grouped": False,
        },
    )
    rng = np.random.default_rng(0)
    for classifier in ids:
        skill = rng.uniform(0.4, 0.95)
        for fold in range(n_folds):
            score = float(np.clip(skill + rng.normal(0, 0.03), 0, 1))
            metrics = {name: float(np.clip(score + rng.normal(0, 0.01), 0, 1)) for name in SCORES}
            metrics.update({name: float(rng.uniform(0.001, 2.0)) for name in COSTS})
            metrics["model_size"] = float(rng.integers(1_000, 3_000_000))
            hits = round(30 * score)
            confusion = [[hits // 3, 0, 10 - hits // 3], [0, 10, 0], [0, 0, 10]]
            record_result(
                store,
                run.id,
                TaskResult(
                    key=TaskKey(classifier, 0, fold),
                    status="ok",
                    error=None,
                    metrics=metrics,
                    confusion=confusion,
                    n_train=270,
                    n_test=30,
                ),
            )
    finish_run(store, run.id, "done")
    return run.id


def imported_run(store: Store, folder: Path, n_classifiers: int) -> int:
    """A run imported from a results file of ``n_classifiers`` x 10 folds."""
    data = touch_arff(folder / "paper.arff", n=90, with_place=False)
    import_file(store, ImportRequest(file=data, name="paper"))
    results = results_arff(folder / "results.arff", n_classifiers=n_classifiers)
    return import_results(store, ImportResultsRequest(file=results, dataset="paper")).id


def first_rankings(store: Store, run_id: int, times: int) -> None:
    """CPU seconds of the first ranking of the run, ``times`` times, and of its progress."""
    ranked_run(store, run_id)  # warm up: imports, statements compiled
    seconds = []
    for _ in range(times):
        leaderboard._KEPT._kept.clear()  # nothing kept: each is a first ranking
        start = time.process_time()
        ranked_run(store, run_id)
        seconds.append(time.process_time() - start)
    polls = []
    for _ in range(20 * times):
        start = time.process_time()
        run_progress(store, run_id)
        polls.append(time.process_time() - start)
    print(
        f"first ranking (CPU s): median {statistics.median(seconds):.3f}, "
        f"best {min(seconds):.3f}, each {' '.join(f'{s:.3f}' for s in seconds)}"
    )
    print(
        f"progress poll (CPU ms): median {1000 * statistics.median(polls):.2f}, "
        f"best {1000 * min(polls):.2f}"
    )


def timed(get: Callable[[], int], requests: int) -> list[float]:
    """Milliseconds of ``requests`` calls (each must answer 200)."""
    times = []
    for _ in range(requests):
        start = time.perf_counter()
        status = get()
        times.append((time.perf_counter() - start) * 1000.0)
        if status != 200:
            raise SystemExit(f"answered {status}")
    return times


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--classifiers", type=int, default=88)
    parser.add_argument("--folds", type=int, default=10)
    parser.add_argument("--requests", type=int, default=30)
    parser.add_argument("--db", help="store URL (default: a new SQLite file)")
    parser.add_argument("--results-file", type=int, metavar="N", help="import N classifiers")
    parser.add_argument("--first-rankings", type=int, metavar="K", help="time K first rankings")
    parser.add_argument("--run", type=int, help="a run already in the store --db names")
    options = parser.parse_args()

    with tempfile.TemporaryDirectory() as name:
        folder = Path(name)
        url = options.db or f"sqlite:///{folder / 'perf.db'}"
        store = Store(url)
        started = time.perf_counter()
        if options.run is not None:
            run_id = options.run
        elif options.results_file:
            run_id = imported_run(store, folder, options.results_file)
        else:
            run_id = build_run(store, folder, options.classifiers, options.folds)
        print(f"run {run_id} ready in {time.perf_counter() - started:.1f} s ({url.split(':')[0]})")
        if options.first_rankings:
            first_rankings(store, run_id, options.first_rankings)
            return
        store.dispose()
        settings = Settings(database_url=url, work_dir=folder / "work")
        with TestClient(create_app(settings), base_url="http://localhost") as client:
            second = list(CATALOGUE)[1]
            paths = {
                "JSON /api/runs/{id}/leaderboard": f"/api/runs/{run_id}/leaderboard",
                "page /fragments/runs/{id}/leaderboard": f"/fragments/runs/{run_id}/leaderboard",
                "JSON, kappa against a baseline": (
                    f"/api/runs/{run_id}/leaderboard?metric=kappa&baseline={second}"
                ),
                "page, kappa against a baseline": (
                    f"/fragments/runs/{run_id}/leaderboard?metric=kappa&baseline={second}"
                ),
            }
            for path in paths.values():  # warm up: imports, caches, compiled templates
                timed(lambda path=path: client.get(path).status_code, 3)
            results: dict[str, list[float]] = {label: [] for label in paths}
            for _ in range(options.requests):  # alternate, so that load affects all alike
                for label, path in paths.items():
                    results[label] += timed(lambda path=path: client.get(path).status_code, 1)
            rows = len(client.get(paths["page /fragments/runs/{id}/leaderboard"]).text)
    load = ", ".join(f"{value:.1f}" for value in os.getloadavg())
    print(f"\n{options.requests} requests each, in-process (ms), load average {load}")
    print(f"  {'':<38} {'median':>8} {'best':>8} {'p90':>8}")
    for label, times in results.items():
        p90 = float(np.percentile(times, 90))
        print(f"  {label:<38} {statistics.median(times):8.1f} {min(times):8.1f} {p90:8.1f}")
    labels = list(results)
    for json_label, page_label in ((labels[0], labels[1]), (labels[2], labels[3])):
        ratio = statistics.median(results[page_label]) / statistics.median(results[json_label])
        print(f"  ratio page / JSON ({page_label.split(', ')[-1]}): {ratio:.2f}")
    verdict = "under" if statistics.median(results[labels[1]]) < 300 else "OVER"
    print(f"  page's leaderboard median is {verdict} the 300 ms goal ({rows} bytes of HTML)")


if __name__ == "__main__":
    main()
