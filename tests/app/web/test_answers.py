"""The web page's run view with a paper's imported results beside the run, and a
classifier's per-class scores and calibration, from a real service."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.support.cli_runner import run_cli
from tests.support.service import Server
from tests.support.synthetic import touch_arff


def test_the_page_shows_the_paper_beside_us_and_how_sure(
    capsys: pytest.CaptureFixture[str], sqlite_server: Server, tmp_path: Path
) -> None:
    db, api = sqlite_server.database_url, sqlite_server.client
    data = touch_arff(tmp_path / "touch.arff", n=60, with_place=False)
    assert run_cli(capsys, db, "import", str(data)).code == 0
    ours = run_cli(capsys, db, "bench", "touch", "-c", "j48,nb", "--folds", "3", "--json")
    run_id = ours.json()["run_id"]
    results = tmp_path / "results.arff"
    results.write_text(run_cli(capsys, db, "leaderboard", str(run_id), "-f", "arff").out)
    paper = run_cli(
        capsys, db, "import-results", str(results), "--dataset", "touch", "--json"
    ).json()["id"]

    board = api.get(f"/fragments/runs/{run_id}/leaderboard", params={"beside": paper})
    assert board.status_code == 200
    html = board.text
    assert '<td class="run">' in html and ">NaiveBayes<" in html
    assert "folds paired by number" in html
    assert f'name="beside" value="{paper}"' in html  # the pickers keep the runs beside

    classifier = api.get(f"/fragments/runs/{run_id}/classifiers/nb")
    assert classifier.status_code == 200
    page = classifier.text
    assert "How sure: per class and calibration" in page
    assert 'data-table="classes"' in page and "Expected calibration error" in page
    assert page.count("<figure") >= 3  # confusion, folds, reliability


def test_the_data_set_view_shows_its_newest_learning_curve(
    capsys: pytest.CaptureFixture[str], sqlite_server: Server, tmp_path: Path
) -> None:
    db, api = sqlite_server.database_url, sqlite_server.client
    data = touch_arff(tmp_path / "touch.arff", n=60, with_place=False)
    assert run_cli(capsys, db, "import", str(data)).code == 0
    before = api.get("/fragments/datasets/touch")
    assert before.status_code == 200 and "How many touches" not in before.text
    curve = run_cli(
        capsys, db, "learning-curve", "touch", "-c", "nb", "--fractions", "0.5", "--folds", "3"
    )
    assert curve.code == 0, curve.err
    after = api.get("/fragments/datasets/touch").text
    assert "How many touches" in after and 'data-table="learning"' in after
    assert ">nb<" in after and after.count("<figure") == 2  # classes, learning curve
    assert "Not drawn" not in after
