"""The service under pressure: kill -9 in the middle of a run and a restart; twenty clients
at once on one SQLite file."""

from __future__ import annotations

import signal
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import httpx
import pytest

from tests.support.cli_runner import run_cli
from tests.support.service import Server, finished
from tests.support.synthetic import touch_arff

#: Metrics that measure time or size, which differ between two runs of the same protocol.
COSTS = {"fit_time", "predict_time", "fit_cpu_time", "predict_cpu_time", "model_size"}


def _scores(board: dict[str, Any]) -> list[tuple[Any, ...]]:
    return [
        (
            row["rank"],
            row["classifier"],
            row["mark"],
            {name: value for name, value in row["metrics"].items() if name not in COSTS},
        )
        for row in board["leaderboard"]
    ]


@pytest.mark.slow
def test_kill_9_restart_and_resume_give_the_uninterrupted_leaderboard(
    capsys: pytest.CaptureFixture[str], make_server: Callable[..., Server], tmp_path: Path
) -> None:
    server = make_server(job_workers="1")
    run_cli(capsys, server.database_url, "import", str(touch_arff(tmp_path / "touch.arff", n=120)))
    request = {
        "dataset": "touch",
        "target": "gesture",
        "classifiers": ["mlp", "gate", "j48", "zeror"],
        "folds": 5,  # a kill mid-run and a resume need a few folds, not ten
        "seed": 3,
    }
    # tasks run classifier-major: mlp's 5 folds, then gate's; its fits wait for the test,
    # so the service dies after exactly 8 tasks, mid-gate
    gate = server.gate
    assert gate is not None
    run_id = server.client.post("/api/runs", json=request).json()["id"]
    gate.let_through(3)
    server.wait_for(f"/api/runs/{run_id}", lambda body: body["tasks_done"] >= 8)
    gate.wait_started(4)
    server.stop(signal.SIGKILL)

    restarted = make_server(job_workers="1")
    run = restarted.client.get(f"/api/runs/{run_id}").json()
    assert run["status"] in {"interrupted", "running"} and run["tasks_done"] == 8
    gate.open()
    deadline = time.monotonic() + 60
    while (resumed := restarted.client.post(f"/api/runs/{run_id}/resume")).status_code == 409:
        assert time.monotonic() < deadline, resumed.text  # the old worker is still dying
        time.sleep(0.5)
    assert resumed.status_code == 202, resumed.text
    run = restarted.wait_for(f"/api/runs/{run_id}", finished, timeout=900)
    assert (run["status"], run["tasks_done"]) == ("done", 20)

    fresh_id = restarted.client.post("/api/runs", json=request).json()["id"]
    restarted.wait_for(f"/api/runs/{fresh_id}", finished, timeout=900)
    interrupted = restarted.client.get(f"/api/runs/{run_id}/leaderboard").json()
    uninterrupted = restarted.client.get(f"/api/runs/{fresh_id}/leaderboard").json()
    assert _scores(interrupted) == _scores(uninterrupted)


@pytest.mark.slow
def test_twenty_clients_at_once_lose_and_duplicate_nothing(
    capsys: pytest.CaptureFixture[str],
    make_sqlite_server: Callable[..., Server],
    tmp_path: Path,
) -> None:
    server = make_sqlite_server(job_workers="2")
    base = touch_arff(tmp_path / "touch.arff", n=60)
    run_cli(capsys, server.database_url, "import", str(base))
    trained = run_cli(
        capsys, server.database_url, "train", "touch", "-c", "nb", "--target", "gesture"
    )
    assert trained.code == 0, trained.err
    # every client goes round at least once, and on for 5 s of all twenty at once
    stop_at = time.monotonic() + 5
    outcomes: dict[str, list[int]] = {"upload": [], "run": [], "predict": []}
    errors: list[str] = []
    runs: list[int] = []
    lock = threading.Lock()

    def client(number: int) -> None:
        path = touch_arff(tmp_path / f"c{number}.arff", n=30, seed=number + 1)
        with httpx.Client(base_url=server.url, timeout=120) as api:
            # a run is created among the uploads; each costs a job process, so a quarter
            # of the clients start one, and they all race the others' writes
            started = number % 4 != 0
            rounds = 0
            while rounds == 0 or time.monotonic() < stop_at:
                rounds += 1
                with path.open("rb") as handle:
                    answer = api.post(
                        "/api/datasets",
                        files={"file": (path.name, handle)},
                        data={"name": f"client-{number}"},
                    )
                record("upload", answer)
                if not started and answer.status_code == 201:
                    run = api.post(
                        "/api/runs",
                        json={
                            "dataset": f"client-{number}",
                            "target": "gesture",
                            "classifiers": ["zeror", "nb"],
                            "folds": 2,
                        },
                    )
                    record("run", run)
                    if run.status_code == 202:
                        with lock:
                            runs.append(run.json()["id"])
                    started = True
                predicted = api.post(
                    "/api/models/touch-nb/predict",
                    json={"instances": [{"f0": 1.0, "f1": 0.5, "f2": 0, "f3": 0, "mic": "left"}]},
                )
                record("predict", predicted)

    def record(kind: str, answer: httpx.Response) -> None:
        with lock:
            outcomes[kind].append(answer.status_code)
            if answer.status_code >= 500 or "locked" in answer.text:
                errors.append(f"{kind}: {answer.status_code} {answer.text[:200]}")

    threads = [threading.Thread(target=client, args=(n,)) for n in range(20)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert not errors, errors[:5]
    assert set(outcomes["predict"]) == {200}
    # the first upload of each client creates its data set; later ones are the same content
    assert outcomes["upload"].count(201) == 20 and set(outcomes["upload"]) <= {200, 201}
    assert len(runs) == 5 and set(outcomes["run"]) == {202}
    for run_id in runs:
        run = server.wait_for(f"/api/runs/{run_id}", finished, timeout=900)
        assert (run["status"], run["tasks_done"], run["tasks"]) == ("done", 4, 4), run
    listed = server.client.get("/api/datasets").json()["datasets"]
    assert sorted(d["name"] for d in listed) == sorted(
        ["touch", *(f"client-{n}" for n in range(20))]
    )
    all_runs = server.client.get("/api/runs").json()["runs"]
    assert len(all_runs) == 5 and sum(r["tasks_done"] for r in all_runs) == 20
    assert sorted(r["dataset"] for r in all_runs) == sorted(f"client-{n}" for n in range(0, 20, 4))
