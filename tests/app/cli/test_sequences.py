"""Sequence data sets through the command line: extract, export, import, train, predict,
and a sequence classifier refused on flat features (exit 2, one line)."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.support.cli_runner import run_cli
from touchbench.app.services.runs import default_classifiers


@pytest.fixture
def link(capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path) -> Path:
    """Six simulated oscillating-link trials (3 s each) in ``tmp_path / "link"``."""
    result = run_cli(
        capsys, store_url, "simulate", "oscillating-link", "--out", str(tmp_path / "link"),
        "--trials", "6", "--seed", "2",
    )  # fmt: skip
    assert result.code == 0, result.err
    return tmp_path / "link"


def _extract(
    capsys: pytest.CaptureFixture[str], url: str, link: Path, name: str, *args: str
) -> dict:
    recordings = sorted(str(path) for path in link.glob("*.wav"))
    result = run_cli(
        capsys, url, "extract", *recordings, "--labels", str(link / "labels.csv"),
        "--name", name, "--json", *args,
    )  # fmt: skip
    assert result.code == 0, result.err
    return result.json()


@pytest.mark.slow
def test_a_sequence_data_set_exports_imports_trains_and_predicts(
    capsys: pytest.CaptureFixture[str], store_url: str, link: Path, tmp_path: Path
) -> None:
    summary = _extract(
        capsys, store_url, link, "windows", "-e", "sequence", "--events", "none",
        "--segment", "1", "-O", "length=64", "-O", "resample=true",
    )  # fmt: skip
    assert summary["n_instances"] == 18 and summary["n_features"] == 3 * 64
    exported = tmp_path / "windows.arff"
    assert run_cli(capsys, store_url, "export", "windows", "-o", str(exported)).code == 0
    text = exported.read_text()
    assert "@attribute ch1[0] numeric" in text and "@attribute ch3[63] numeric" in text
    assert run_cli(capsys, store_url, "import", str(exported), "--name", "again").code == 0
    twice = tmp_path / "again.arff"
    assert run_cli(capsys, store_url, "export", "again", "-o", str(twice)).code == 0
    assert twice.read_text().split("@data", 1)[1] == text.split("@data", 1)[1]

    trained = run_cli(capsys, store_url, "train", "again", "--classifier", "minirocket", "--json")
    assert trained.code == 0, trained.err
    assert trained.json()["classifier"] == "minirocket"
    predicted = run_cli(capsys, store_url, "predict", "again-minirocket", str(exported), "--json")
    assert predicted.code == 0, predicted.err
    report = predicted.json()
    assert len(report["predictions"]) == 18
    assert report["accuracy"]["contact"] == 1.0  # its own training windows


def test_sequence_classifiers_on_a_flat_data_set_exit_2_with_one_line(
    capsys: pytest.CaptureFixture[str], store_url: str, link: Path
) -> None:
    _extract(capsys, store_url, link, "peaks", "-e", "band-peaks")
    for args in (
        ("train", "peaks", "--classifier", "minirocket"),
        ("bench", "peaks", "--classifiers", "rf,multirocket", "--folds", "2"),
        ("bench", "peaks", "--classifiers", "interval-forest", "--folds", "2"),
    ):
        result = run_cli(capsys, store_url, *args)
        assert result.code == 2, (args, result.err)
        lines = result.err.strip().splitlines()
        assert len(lines) == 1 and "needs a sequence data set" in lines[0], result.err
        assert "Traceback" not in result.err
    runs = run_cli(capsys, store_url, "runs", "--json").json()
    assert runs["runs"] == []  # nothing half-written


def test_suites_hold_sequence_classifiers_only_for_sequence_data_sets() -> None:
    sequence_ids = {"minirocket", "multirocket", "interval-forest"}
    flat = default_classifiers(1, "default")
    assert "rf" in flat and not sequence_ids & set(flat)
    assert sequence_ids <= set(default_classifiers(1, "default", sequences=True))
    assert not sequence_ids & set(default_classifiers(1, "all"))
    assert "rf" in default_classifiers(1, "all", sequences=True)
