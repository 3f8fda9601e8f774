"""``POST /api/runs`` takes the run's request (BenchRequest) as its body, on a real service on
SQLite and PostgreSQL: what a run cannot honour is answered 422 with the field's place in the
body and a message without any command-line word, before a run row exists."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import pytest

from tests.support.cli_runner import CLI_WORDS, run_cli
from tests.support.rows import count_rows
from tests.support.service import Server, finished
from tests.support.synthetic import position_arff, touch_arff

BASE = {"dataset": "touch", "classifiers": ["zeror", "nb"], "folds": 3}


REFUSALS: list[tuple[dict[str, Any], str, str]] = [
    # what a benchmark of each target on its own cannot honour
    ({"independent": True, "target": "gesture"}, "target", "is not used with `independent`"),
    ({"independent": True, "weka": ["J48"]}, "weka", "is not used with `independent`"),
    ({"independent": True, "position": ["f0", "f1"]}, "position", "is not used with"),
    ({"independent": True, "tune": True}, "tune", "is not used with `independent`"),
    ({"independent": True, "budget": 5}, "budget", "is not used with `independent`"),
    ({"independent": True, "stack": 2}, "stack", "is not used with `independent`"),
    ({"independent": True, "metric": "accuracy"}, "metric", "is not used with `independent`"),
    ({"independent": True, "baseline": "nb"}, "baseline", "is not used with `independent`"),
    ({"independent": True}, "independent", "queue a run per `target`"),
    # bounds the OS and the engine can honour
    ({"max_memory_mb": 1e308}, "max_memory_mb", "less than or equal to 1048576"),
    ({"max_memory_mb": 1e15}, "max_memory_mb", "less than or equal to 1048576"),
    ({"timeout": -1}, "timeout", "greater than or equal to 0"),
    ({"folds": 1}, "folds", "greater than or equal to 2"),
    ({"folds": "lobo"}, "folds", "must be a number of folds or logo"),
    ({"folds": "logo", "target": "gesture"}, "folds", "needs groups, and the data set has none"),
    ({"folds": "logo", "repeats": 2}, "repeats", "must be 1 with `folds` logo"),
    ({"budget": 2000, "tune": True}, "budget", "less than or equal to 1440"),
    ({"stack": 21}, "stack", "less than or equal to 20"),
    # rules across fields, and those that need the data set
    ({"budget": 1}, "budget", "is only meaningful with `tune`"),
    ({"suite": "fast"}, "suite", "is not used with `classifiers`"),
    ({"target": "gesture", "stack": 3}, "stack", "needs at least 3 classifiers"),
    ({"stack": 1}, "stack", "stacks multi-class classifiers: pick one `target`"),
    ({"target": "gesture", "tune": True}, "tune", "no classifier of this run declares"),
    ({"target": "gesture", "baseline": "rf"}, "baseline", "'rf' is not a classifier"),
    ({"target": "gesture", "metric": "mae"}, "metric", "'mae' is a regression metric"),
    ({"classifiers": ["nbx"], "target": "gesture"}, "classifiers", "unknown classifier 'nbx'"),
    ({"target": "nope"}, "target", "no attribute named 'nope'"),
    ({"dataset": "contact", "classifiers": ["ridge"], "stack": 1}, "stack", "numeric"),
    ({"dataset": "contact", "classifiers": ["ridge"], "tune": True}, "tune", "numeric"),
    ({"dataset": "contact", "weka": ["J48"], "classifiers": None}, "weka", "numeric"),
    ({"target": "gesture", "position": ["x", "y"]}, "position", "'x' is not a target"),
    (
        {"dataset": "contact", "classifiers": ["ridge"], "position": ["x", "mic"]},
        "position",
        "'mic' is not a target",
    ),
    ({"dataset": "contact", "classifiers": ["ridge"], "position": ["x"]}, "position", "at least 2"),
    ({"dataset": "mixed", "position": ["x", "y"]}, "position", "include nominal ones (mic)"),
    ({"dataset": "flat", "position": ["x", "y"]}, "position", "'x' has a single value (1)"),
    # racing and the total budget
    ({"race": True, "folds": 2}, "race", "needs at least 3 folds"),
    ({"race": True, "race_alpha": 0}, "race_alpha", "greater than 0"),
    ({"race": True, "race_alpha": 0.5}, "race_alpha", "less than 0.5"),
    ({"race_alpha": 0.05}, "race_alpha", "is only meaningful with `race`"),
    ({"budget_total": -1}, "budget_total", "greater than 0"),
    ({"independent": True, "race": True}, "race", "is not used with `independent`"),
    # ensemble selection
    ({"ensemble": 0}, "ensemble", "greater than or equal to 1"),
    ({"ensemble": 101}, "ensemble", "less than or equal to 100"),
    ({"ensemble": 2}, "ensemble", "selects among multi-class classifiers: pick one nominal"),
    ({"dataset": "contact", "classifiers": ["ridge"], "ensemble": 2}, "ensemble", "numeric"),
    ({"independent": True, "ensemble": 2}, "ensemble", "is not used with `independent`"),
]


@pytest.mark.slow
def test_every_refusal_names_its_field_and_leaves_no_run(
    capsys: pytest.CaptureFixture[str], server: Server, tmp_path: Path
) -> None:
    contact = position_arff(tmp_path / "contact.arff").read_text(encoding="utf-8")
    (tmp_path / "mixed.arff").write_text(contact.replace("-C -2", "-C -3"), encoding="utf-8")
    flat = [re.sub(r",[^,]+,([^,]+)$", r",1.0,\1", line) for line in contact.splitlines()]
    (tmp_path / "flat.arff").write_text("\n".join(flat) + "\n", encoding="utf-8")  # x is 1.0
    for path, name in (
        (touch_arff(tmp_path / "touch.arff", n=60), "touch"),
        (position_arff(tmp_path / "contact.arff"), "contact"),
        (tmp_path / "mixed.arff", "mixed"),
        (tmp_path / "flat.arff", "flat"),
    ):
        assert run_cli(capsys, server.database_url, "import", str(path), "--name", name).code == 0
    api = server.client
    for change, field, words in REFUSALS:
        body = {key: value for key, value in {**BASE, **change}.items() if value is not None}
        answer = api.post("/api/runs", json=body)
        assert answer.status_code == 422, (change, answer.text)
        error = answer.json()["error"]
        assert error["where"] == f"body.{field}", (change, error)
        assert words in error["message"], (change, error)
        assert not CLI_WORDS.search(error["message"]), (change, error)
    assert count_rows(server.database_url, "runs") == 0
    assert api.get("/api/runs").json() == {"runs": []}

    # what is taken is stored: 0 means no time limit, the metric ranks the leaderboard
    started = api.post(
        "/api/runs",
        json={**BASE, "dataset": 1, "target": "gesture", "timeout": 0, "metric": "accuracy"},
    )
    assert started.status_code == 202, started.text
    run = server.wait_for(f"/api/runs/{started.json()['id']}", finished)
    assert run["status"] == "done" and run["config"]["timeout"] is None
    board = api.get(f"/api/runs/{run['id']}/leaderboard")
    assert board.json()["metric"] == "accuracy"
    cli_board = run_cli(capsys, server.database_url, "leaderboard", str(run["id"]), "--json")
    assert board.json() == cli_board.json()
    wrong = api.get(f"/api/runs/{run['id']}/leaderboard", params={"metric": "euclidean_error"})
    assert wrong.status_code == 400 and not CLI_WORDS.search(wrong.json()["error"]["message"])

    # a raced run: its drop in the API's leaderboard and on the web page
    raced = api.post(
        "/api/runs",
        json={**BASE, "dataset": 1, "target": "gesture", "classifiers": ["zeror", "nb", "j48"],
              "folds": 5, "race": True},
    )  # fmt: skip
    assert raced.status_code == 202, raced.text
    run = server.wait_for(f"/api/runs/{raced.json()['id']}", finished)
    assert run["status"] == "done" and run["config"]["race"] == {"alpha": 0.01}
    board = api.get(f"/api/runs/{run['id']}/leaderboard").json()
    assert board["race"]["dropped"] == 1
    zeror = next(row for row in board["leaderboard"] if row["classifier"] == "zeror")
    assert zeror["dropped"]["reason"] == "race" and zeror["n_ok"] == zeror["dropped"]["after_fold"]
    page = api.get(f"/fragments/runs/{run['id']}/leaderboard").text
    assert zeror["dropped"]["note"] in page and board["race"]["note"] in page
    assert 'class="dropped"' in page

    # an ensemble selection and a vote from fold predictions: their origin in the API's
    # leaderboard and on the web page, the selection's weights per fold
    selecting = api.post(
        "/api/runs",
        json={**BASE, "dataset": 1, "target": "gesture", "classifiers": ["nb", "voting-hard"],
              "ensemble": 2},
    )  # fmt: skip
    assert selecting.status_code == 202, selecting.text
    run = server.wait_for(f"/api/runs/{selecting.json()['id']}", finished)
    assert run["status"] == "done" and run["config"]["ensemble"] == 2
    assert run["config"]["helpers"] == ["logistic", "rf", "svm-rbf"]
    assert run["classifiers"] == ["nb", "voting-hard", "ensemble-2"]
    board = api.get(f"/api/runs/{run['id']}/leaderboard").json()
    rows = {row["classifier"]: row for row in board["leaderboard"]}
    assert rows["ensemble-2"]["origin"]["note"] == "from fold predictions of nb, voting-hard"
    assert rows["rf"]["origin"]["note"] == "helper of voting-hard"
    assert rows["nb"]["origin"] is None and rows["ensemble-2"]["n_ok"] == 3
    assert {choice["classifier"] for choice in board["choices"]} == {"ensemble-2"}
    page = api.get(f"/fragments/runs/{run['id']}/leaderboard").text
    assert "from fold predictions of nb, voting-hard" in page and "helper of voting-hard" in page
