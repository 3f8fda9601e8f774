"""Multi-target data through the CLI: bench, --independent, train/predict, bad input."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.support.cli_runner import run_cli
from tests.support.synthetic import touch_arff


@pytest.fixture
def two_targets(capsys: pytest.CaptureFixture[str], sqlite_store_url: str, tmp_path: Path) -> Path:
    path = touch_arff(tmp_path / "touch.arff", n=120)
    assert run_cli(capsys, sqlite_store_url, "import", str(path)).code == 0
    return path


def test_classifiers_lists_meta_base_configurations(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    listing = run_cli(
        capsys, f"sqlite:///{tmp_path}/t.db", "classifiers", "--multi-target", "--json"
    ).json()["classifiers"]
    ids = {entry["id"] for entry in listing}
    metas = {entry["meta"] for entry in listing if not entry["binary_only"]}
    bases = {entry["base"] for entry in listing if entry["base"]}
    assert {"bcc:rf", "cc:svm-rbf", "lc:xgb"} <= ids
    assert len(metas) >= 10 and len(bases) >= 8 and len(ids) >= 40
    bcc = next(e for e in listing if e["id"] == "bcc:rf")
    assert bcc["follows"].startswith("meka.")


def test_bench_on_two_targets_reports_meka_metrics(
    capsys: pytest.CaptureFixture[str], sqlite_store_url: str, two_targets: Path
) -> None:
    result = run_cli(
        capsys,
        sqlite_store_url,
        "bench",
        "touch",
        "-c",
        "cr:nb,bcc:j48,lc:j48",
        "-k",
        "3",
        "--json",
    )
    assert result.code == 0, result.err
    report = result.json()
    assert report["kind"] == "multitarget" and report["metric"] == "hamming_score"
    for row in report["leaderboard"]:
        metrics = row["metrics"]
        assert {"hamming_score", "exact_match", "hamming_loss", "zero_one_loss"} <= set(metrics)
        assert set(metrics["per_target"]) == {"gesture", "place"}
        assert metrics["hamming_score"]["mean"] == pytest.approx(
            1 - metrics["hamming_loss"]["mean"]
        )
        assert metrics["exact_match"]["mean"] <= metrics["hamming_score"]["mean"]
    assert report["leaderboard"][0]["metrics"]["hamming_score"]["mean"] > 0.8


def test_independent_runs_each_target_and_multiplies(
    capsys: pytest.CaptureFixture[str], sqlite_store_url: str, two_targets: Path
) -> None:
    result = run_cli(
        capsys,
        sqlite_store_url,
        "bench",
        "touch",
        "--independent",
        "-c",
        "zeror,nb",
        "-k",
        "3",
        "--json",
    )
    assert result.code == 0, result.err
    report = result.json()
    best = report["best"]
    assert set(best) == {"gesture", "place"}
    product = (
        best["gesture"]["metrics"]["accuracy"]["mean"]
        * (best["place"]["metrics"]["accuracy"]["mean"])
    )
    assert report["product"]["accuracy"] == pytest.approx(product)
    runs = run_cli(capsys, sqlite_store_url, "runs", "--json").json()["runs"]
    assert sorted(r["targets"][0] for r in runs) == ["gesture", "place"]


def test_train_and_predict_a_multi_target_model(
    capsys: pytest.CaptureFixture[str], sqlite_store_url: str, two_targets: Path
) -> None:
    trained = run_cli(capsys, sqlite_store_url, "train", "touch", "-c", "bcc:j48", "--json")
    assert trained.code == 0, trained.err
    assert trained.json()["targets"] == ["gesture", "place"]
    predicted = run_cli(
        capsys, sqlite_store_url, "predict", "touch-bcc:j48", str(two_targets), "--json"
    )
    assert predicted.code == 0, predicted.err
    first = predicted.json()["predictions"][0]
    assert first["gesture"] in {"tap", "slap", "stroke"} and first["place"] in {"head", "arm"}
    assert set(first["probabilities"]) == {"gesture", "place"}
    assert set(first["probabilities"]["place"]) == {"head", "arm"}
    assert predicted.json()["accuracy"]["place"] > 0.8


def test_multi_target_bad_input_exits_2(
    capsys: pytest.CaptureFixture[str], sqlite_store_url: str, tmp_path: Path, two_targets: Path
) -> None:
    single = touch_arff(tmp_path / "single.arff", with_place=False, seed=5)
    assert run_cli(capsys, sqlite_store_url, "import", str(single), "--name", "single").code == 0
    numeric = tmp_path / "n.arff"
    numeric.write_text(
        "@relation 'n: -C 2'\n@attribute a numeric\n@attribute b numeric\n"
        "@attribute x numeric\n@data\n1,2,3\n2,3,4\n",
        encoding="utf-8",
    )
    assert run_cli(capsys, sqlite_store_url, "import", str(numeric)).code == 0
    cases = [
        (["bench", "single", "-c", "bcc:rf"], "multi-target method"),
        (["bench", "touch", "-c", "bcc:rff"], "did you mean 'rf'"),
        (["bench", "touch", "-c", "bogus:rf"], "unknown multi-target method 'bogus'"),
        (["bench", "touch", "-c", "rf"], "multi-class classifier"),
        (["bench", "n", "-c", "j48"], "the targets are numeric"),
        (["bench", "touch", "--independent", "--target", "place"], "--independent"),
    ]
    for args, expected in cases:
        result = run_cli(capsys, sqlite_store_url, *args)
        assert result.code == 2, (args, result.err)
        assert len(result.err.strip().splitlines()) == 1, result.err
        assert expected in result.err, (args, result.err)
    assert run_cli(capsys, sqlite_store_url, "runs", "--json").json() == {"runs": []}
