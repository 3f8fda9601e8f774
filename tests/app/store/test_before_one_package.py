"""A store written before touchbench became one import name opens, lists and predicts."""

from __future__ import annotations

import gzip
import json
import shutil
from pathlib import Path

import pytest

from tests.support.cli_runner import run_cli
from tests.support.predictions import assert_same_predictions

BEFORE = Path(__file__).parent / "data" / "before-one-package"


@pytest.fixture
def old_store(tmp_path: Path) -> str:
    database = tmp_path / "touchbench.db"
    with gzip.open(BEFORE / "store.db.gz") as packed, database.open("wb") as unpacked:
        shutil.copyfileobj(packed, unpacked)
    return f"sqlite:///{database}"


@pytest.mark.parametrize("model", ["old-j48", "old-cc"])
def test_a_model_stored_before_the_move_predicts_as_it_did(
    capsys: pytest.CaptureFixture[str], old_store: str, tmp_path: Path, model: str
) -> None:
    data = tmp_path / "robot.arff"
    assert run_cli(capsys, old_store, "export", "robot", "-o", str(data)).code == 0
    predicted = run_cli(capsys, old_store, "predict", model, str(data), "--json")
    assert predicted.code == 0, predicted.err
    expected = json.loads((BEFORE / f"predictions-{model}.json").read_text())
    assert_same_predictions(predicted.json()["predictions"], expected)


def test_the_old_store_lists_its_models(capsys: pytest.CaptureFixture[str], old_store: str) -> None:
    listed = run_cli(capsys, old_store, "models", "--json")
    assert listed.code == 0, listed.err
    assert sorted(row["name"] for row in listed.json()["models"]) == ["old-cc", "old-j48"]
