"""Numeric targets end to end: `bench` (regressors, --position), `leaderboard`, `train`,
`predict` print numbers; what does not fit a regression is refused in one line."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.support.cli_runner import CliResult, run_cli
from tests.support.synthetic import position_arff, touch_arff
from touchbench.app.services.models import predict_records
from touchbench.app.store.database import Store


@pytest.fixture
def db(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> str:
    url = f"sqlite:///{tmp_path}/t.db"
    for path in (position_arff(tmp_path / "contact.arff"), touch_arff(tmp_path / "touch.arff")):
        assert run_cli(capsys, url, "import", str(path), "--json").code == 0
    return url


def refused(result: CliResult, message: str) -> None:
    assert result.code == 2, result.err
    assert message in result.err and "Traceback" not in result.err
    assert len(result.err.strip().splitlines()) == 1, result.err


def test_bench_leaderboard_train_predict_on_numeric_targets(
    capsys: pytest.CaptureFixture[str], db: str, tmp_path: Path
) -> None:
    bench = run_cli(
        capsys, db, "bench", "contact", "-c", "zeror,ridge", "-k", "3", "--position", "x,y",
        "--json",
    )  # fmt: skip
    assert bench.code == 0, bench.err
    report = bench.json()
    assert report["kind"] == "regression" and report["targets"] == ["x", "y"]
    assert report["metric"] == "mae" and report["lower_is_better"] is True
    assert report["folds"] == "k-fold"
    rows = {row["classifier"]: row for row in report["leaderboard"]}
    assert report["leaderboard"][-1]["classifier"] == "zeror"
    assert rows["zeror"]["mark"] == "*"  # a larger error than the best: significantly worse
    ridge = rows["ridge"]["metrics"]
    assert ridge["mae"]["mean"] < rows["zeror"]["metrics"]["mae"]["mean"]
    assert ridge["r2"]["mean"] > 0.5 and ridge["euclidean_error"]["mean"] > ridge["mae"]["mean"]
    assert set(ridge["per_target"]) == {"x", "y"}

    table = run_cli(capsys, db, "leaderboard", "1", "--metric", "rmse")
    assert table.code == 0, table.err
    assert "(k-fold), ranked by rmse (lower is better)" in " ".join(table.out.split())

    train = run_cli(capsys, db, "train", "contact", "-c", "ridge", "--json")
    assert train.code == 0, train.err
    predict = run_cli(
        capsys, db, "predict", "contact-ridge", str(tmp_path / "contact.arff"), "--json"
    )
    assert predict.code == 0, predict.err
    answer = predict.json()
    first = answer["predictions"][0]
    assert isinstance(first["x"], float) and isinstance(first["y"], float)
    assert set(answer["mae"]) == {"x", "y"} and answer["mae"]["x"] < 1.0
    shown = run_cli(capsys, db, "predict", "contact-ridge", str(tmp_path / "contact.arff"))
    assert "mean absolute error on x" in shown.err
    served = predict_records(  # what POST /api/models/{id}/predict answers
        Store(db), "contact-ridge", [{"f0": 1.0, "f1": 0.0, "f2": 0.0, "mic": "left"}]
    ).to_json()
    assert served["predictions"][0]["x"] == pytest.approx(10.0, abs=1.0)
    assert isinstance(served["predictions"][0]["y"], float) and served["mae"] == {}


def test_classification_leaderboards_name_their_folds_and_refuse_regression_metrics(
    capsys: pytest.CaptureFixture[str], db: str
) -> None:
    bench = run_cli(
        capsys, db, "bench", "touch", "--target", "gesture", "-c", "zeror", "-k", "3", "--json"
    )
    assert bench.code == 0, bench.err
    assert bench.json()["folds"] == "stratified k-fold"
    assert bench.json()["lower_is_better"] is False
    refused(
        run_cli(capsys, db, "leaderboard", "1", "--metric", "mae"),
        "'mae' is a regression metric and run 1 classifies nominal targets",
    )


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (("-c", "ridge", "--metric", "f1_weighted"), "'f1_weighted' is not a regression metric"),
        (("-c", "j48"), "classifier 'j48' has no regressor: the targets are numeric"),
        (("-c", "ridge", "--position", "x,mic"), "--position: 'mic' is not a target"),
        (("-c", "ridge", "--metric", "euclidean_error"), "'euclidean_error' needs coordinates"),
        (("--independent",), "a regression benchmarks its targets together"),
        (("-c", "rf", "--tune"), "--tune: works on classification runs"),
        (("-c", "rf,ridge", "--stack", "2"), "--stack: works on classification runs"),
        (("--weka", "J48"), "--weka: works on classification runs"),
    ],
)
def test_what_does_not_fit_a_regression_is_refused_in_one_line(
    capsys: pytest.CaptureFixture[str], db: str, args: tuple[str, ...], message: str
) -> None:
    refused(run_cli(capsys, db, "bench", "contact", *args), message)
    assert run_cli(capsys, db, "runs", "--json").json() == {"runs": []}


def test_regression_metric_and_position_on_a_classification_bench(
    capsys: pytest.CaptureFixture[str], db: str
) -> None:
    refused(
        run_cli(capsys, db, "bench", "touch", "-c", "bcc:nb", "--metric", "rmse"),
        "'rmse' is a regression metric",
    )
    refused(
        run_cli(capsys, db, "bench", "touch", "-c", "bcc:nb", "--position", "gesture,place"),
        "--position: 'gesture' is a nominal target",
    )
