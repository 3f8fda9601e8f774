"""Which microphone can go (`bench --ablate-groups`) and how many touches are enough
(`learning-curve`), each kept as a job with its progress; importance as a job, as the API's
workers carry it out.  SQLite only: each starts the engine's worker processes several times."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.support.cli_runner import run_cli
from tests.support.synthetic import mics_arff, touch_arff
from touchbench.app.schemas.importance import ImportanceRequest
from touchbench.app.services.answers import latest_ablation
from touchbench.app.services.jobs import execute_job, submit_answer
from touchbench.app.store.database import Store
from touchbench.app.store.jobs import list_jobs


@pytest.fixture
def db(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> str:
    url = f"sqlite:///{tmp_path / 'touchbench.db'}"
    assert run_cli(capsys, url, "import", str(mics_arff(tmp_path / "mics.arff"))).code == 0
    return url


def test_ablating_the_deciding_microphone_is_significant_and_the_noise_not(
    capsys: pytest.CaptureFixture[str], db: str, tmp_path: Path
) -> None:
    result = run_cli(
        capsys, db, "bench", "mics", "-c", "nb", "--folds", "5", "--ablate-groups", "channel",
        "--json",
    )  # fmt: skip
    assert result.code == 0, result.err
    found = result.json()
    ablation = found["ablation"]
    assert found["run_id"] == ablation["run_id"] and ablation["complete"]
    assert [g["name"] for g in ablation["groups"]] == ["channel 1", "channel 2"]
    entries = {e["group"]: e for e in ablation["entries"]}
    decisive, noise = entries["channel 1"], entries["channel 2"]
    assert decisive["significant"] and decisive["verdict"] == "needed"
    assert decisive["change"] < -0.4 and decisive["n_folds"] == 5
    assert not noise["significant"] and noise["verdict"] == "can go"
    assert abs(noise["change"]) < 0.05 and noise["p"] > 0.05
    # kept: the API's GET /api/runs/{id}/ablation and the pages read it back
    store = Store(db)
    kept = latest_ablation(store, found["run_id"])
    assert kept.entries[0].change == pytest.approx(decisive["change"])
    (job,) = list_jobs(store)
    assert (job.kind, job.status, job.params["grouping"]) == ("ablation", "done", "channel")
    # importance as the API's workers carry it out: a queued job, its folds kept as they end
    queued = submit_answer(store, ImportanceRequest(run=found["run_id"], classifier="nb"))
    assert queued.status == "queued" and queued.kind == "importance"
    done = execute_job(store, queued.id)
    assert done is not None and done.status == "done", done
    assert done.result is not None and done.result["complete"]
    assert done.result["done"] == done.result["total"] == 5
    assert done.result["groups"]["channel"][0]["name"] == "channel 1"
    # the HTML report shows both
    page = tmp_path / "report.html"
    report = run_cli(capsys, db, "report", str(found["run_id"]), "-o", str(page))
    assert report.code == 0, report.err
    html = page.read_text()
    assert "Which sensor and which features" in html
    assert 'data-table="ablation"' in html and 'data-table="importance"' in html


def test_bad_ablations_are_one_line_exit_2(
    capsys: pytest.CaptureFixture[str], db: str, tmp_path: Path
) -> None:
    bad = run_cli(capsys, db, "bench", "mics", "-c", "nb", "--ablate-groups", "mic")
    assert bad.code == 2 and bad.err.startswith("touchbench: error: --ablate-groups:")
    assert bad.err.count("\n") == 1
    plain = tmp_path / "plain.arff"
    plain.write_text("@relation plain\n@attribute a numeric\n@attribute c {x,y}\n@data\n1,x\n")
    assert run_cli(capsys, db, "import", str(plain)).code == 0
    none = run_cli(capsys, db, "bench", "plain", "-c", "nb", "--ablate-groups", "channel")
    assert none.code == 2 and "--ablate-groups: the features of data set 'plain' fall into no" in (
        none.err
    )
    assert run_cli(capsys, db, "runs", "--json").json()["runs"] == []  # refused before a run


def test_learning_curve_finds_where_a_classifier_has_enough(
    capsys: pytest.CaptureFixture[str], db: str, tmp_path: Path
) -> None:
    plot = tmp_path / "curve.svg"
    result = run_cli(
        capsys, db, "learning-curve", "mics", "-c", "nb,j48", "--fractions", "0.2,0.5",
        "--folds", "3", "-o", str(plot), "--json",
    )  # fmt: skip
    assert result.code == 0, result.err
    found = result.json()
    assert found["fractions"] == [0.2, 0.5, 1.0] and found["complete"]
    assert found["done"] == found["total"] == 2 * 3 * 3
    for curve in found["curves"]:
        assert [p["n_folds"] for p in curve["points"]] == [3, 3, 3]
        sizes = [p["n_train"] for p in curve["points"]]
        assert sizes == sorted(sizes) and sizes[-1] == 60
        assert curve["enough"] in found["fractions"]
    assert "<svg" in plot.read_text() and "learning curves" in plot.read_text()
    # the HTML report of a run on the data set shows the data set's newest curve
    run = run_cli(capsys, db, "bench", "mics", "-c", "nb", "--folds", "3", "--json").json()
    page = tmp_path / "report.html"
    assert run_cli(capsys, db, "report", str(run["run_id"]), "-o", str(page)).code == 0
    html = page.read_text()
    assert "How many touches" in html and 'data-table="learning"' in html
    assert html.count("Score by share of each training fold") == 1 and "Not drawn" not in html
    bad = run_cli(capsys, db, "learning-curve", "mics", "-c", "nb", "--fractions", "0,0.5")
    assert bad.code == 2 and bad.err.startswith("touchbench: error: --fractions")
    unknown = run_cli(capsys, db, "learning-curve", "mics", "-c", "nope")
    assert unknown.code == 2 and "--classifiers" in unknown.err


def test_a_multi_target_run_is_calibrated_per_target(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    db = f"sqlite:///{tmp_path / 'touchbench.db'}"
    data = touch_arff(tmp_path / "touch.arff", n=60)
    assert run_cli(capsys, db, "import", str(data)).code == 0
    run = run_cli(capsys, db, "bench", "touch", "-c", "cc:nb", "--folds", "3", "--json")
    assert run.code == 0, run.err
    found = run_cli(capsys, db, "classes", str(run.json()["run_id"]), "--json").json()
    (entry,) = found["classifiers"]
    assert entry["calibration"] is None and entry["calibration_note"] == "per target"
    for target in entry["targets"]:
        assert target["calibration"]["n_instances"] == 60, target["target"]
        assert 0 <= target["calibration"]["ece"] <= 1
    plot = tmp_path / "reliability.svg"
    drawn = run_cli(capsys, db, "calibration", str(run.json()["run_id"]), "-o", str(plot))
    assert drawn.code == 0, drawn.err
    assert "cc:nb on gesture" in plot.read_text() and "cc:nb on place" in plot.read_text()
    assert "per target" in drawn.out
