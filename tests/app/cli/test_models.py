"""`touchbench train / models / predict`, on SQLite and PostgreSQL."""

from __future__ import annotations

from pathlib import Path

import pytest
from sqlalchemy import create_engine, text

from tests.support.cli_runner import run_cli
from tests.support.synthetic import touch_arff


@pytest.fixture
def trained(capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path) -> Path:
    path = touch_arff(tmp_path / "touch.arff", n=120)
    assert run_cli(capsys, store_url, "import", str(path)).code == 0
    result = run_cli(
        capsys,
        store_url,
        "train",
        "touch",
        "--classifier",
        "nb",
        "--target",
        "gesture",
        "--json",
    )
    assert result.code == 0, result.err
    model = result.json()
    assert (model["name"], model["classifier"], model["targets"]) == ("touch-nb", "nb", ["gesture"])
    assert len(model["sha256"]) == 64 and model["size_bytes"] > 0
    return path


def test_models_lists_the_trained_model(
    capsys: pytest.CaptureFixture[str], store_url: str, trained: Path
) -> None:
    listing = run_cli(capsys, store_url, "models", "--json").json()["models"]
    assert [(m["name"], m["dataset"]) for m in listing] == [("touch-nb", "touch")]


def test_predict_gives_labels_probabilities_and_accuracy(
    capsys: pytest.CaptureFixture[str], store_url: str, trained: Path
) -> None:
    result = run_cli(capsys, store_url, "predict", "touch-nb", str(trained), "--json")
    assert result.code == 0, result.err
    report = result.json()
    rows = report["predictions"]
    assert len(rows) == 120
    first = rows[0]
    assert first["gesture"] in {"tap", "slap", "stroke"}
    assert set(first["probabilities"]["gesture"]) == {"tap", "slap", "stroke"}
    assert sum(first["probabilities"]["gesture"].values()) == pytest.approx(1.0)
    assert report["accuracy"]["gesture"] > 0.85


def test_attributes_are_matched_by_name_and_labels_by_text(
    capsys: pytest.CaptureFixture[str], store_url: str, trained: Path, tmp_path: Path
) -> None:
    lines = trained.read_text(encoding="utf-8").splitlines()
    header = [line for line in lines if line.startswith("@")]
    data = [line for line in lines if line and not line.startswith("@")]
    # The same instances with the attributes in another order and nominal labels reordered.
    order = [6, 2, 3, 4, 5, 0]  # mic, f0..f3, gesture (place left out)
    attributes = [line for line in header if line.startswith("@attribute")]
    attributes[0] = "@attribute gesture {stroke, tap, slap}"
    attributes[6] = "@attribute mic {both, right, left}"
    shuffled = ["@relation moved", *[attributes[i] for i in order], "@data"]
    shuffled += [",".join(row.split(",")[i] for i in order) for row in data]
    moved = tmp_path / "moved.arff"
    moved.write_text("\n".join(shuffled) + "\n", encoding="utf-8")
    original = run_cli(capsys, store_url, "predict", "touch-nb", str(trained), "--json").json()
    again = run_cli(capsys, store_url, "predict", "touch-nb", str(moved), "--json")
    assert again.code == 0, again.err
    assert [r["gesture"] for r in again.json()["predictions"]] == [
        r["gesture"] for r in original["predictions"]
    ]


def test_a_file_without_the_models_attributes_exits_2(
    capsys: pytest.CaptureFixture[str], store_url: str, trained: Path, tmp_path: Path
) -> None:
    lacking = tmp_path / "lacking.arff"
    lacking.write_text(
        "@relation x\n@attribute f0 numeric\n@attribute gesture {tap}\n@data\n1,tap\n",
        encoding="utf-8",
    )
    result = run_cli(capsys, store_url, "predict", "touch-nb", str(lacking))
    assert result.code == 2
    assert "lacking.arff" in result.err and "f1" in result.err and "mic" in result.err
    unknown = run_cli(capsys, store_url, "predict", "no-such-model", str(trained))
    assert unknown.code == 2 and "no model 'no-such-model'" in unknown.err


def test_a_tampered_artifact_is_refused_before_loading(
    capsys: pytest.CaptureFixture[str], store_url: str, trained: Path
) -> None:
    engine = create_engine(store_url.replace("postgresql://", "postgresql+psycopg://", 1))
    with engine.begin() as connection:
        blob = bytes(connection.execute(text("SELECT artifact FROM model_artifacts")).scalar_one())
        tampered = blob[:-1] + bytes([blob[-1] ^ 0xFF])
        connection.execute(text("UPDATE model_artifacts SET artifact = :a"), {"a": tampered})
    engine.dispose()
    result = run_cli(capsys, store_url, "predict", "touch-nb", str(trained))
    assert result.code == 2
    assert "sha256" in result.err


def test_training_is_refused_naming_the_option(
    capsys: pytest.CaptureFixture[str], store_url: str, trained: Path, tmp_path: Path
) -> None:
    half = tmp_path / "half.arff"
    rows = "".join(f"{'tap' if i % 2 else 'slap'},?,{i % 2 + 0.1 * i}\n" for i in range(20))
    half.write_text(
        "@relation 'half: -C 2'\n@attribute gesture {tap, slap}\n@attribute place {head, arm}\n"
        "@attribute f0 numeric\n@data\n" + rows,
        encoding="utf-8",
    )
    assert run_cli(capsys, store_url, "import", str(half)).code == 0
    cases = [
        (
            ["touch", "-c", "nb", "--name", "touch-nb@2"],
            "--name: a model name cannot hold '@' (NAME@VERSION and NAME@ALIAS name a version",
        ),
        (
            ["half", "-c", "nb", "--target", "place"],
            "--target: no instance has a known value of the target ('place'): nothing to train on",
        ),
        (
            ["half", "-c", "cc:nb"],
            "DATASET: no instance has a known value of every target ('gesture', 'place'): "
            "nothing to train on",
        ),
        (["touch", "-c", "nb", "--target", "nope"], "--target: the data set has no attribute"),
        (["touch", "-c", "nb", "--seed", "-1"], "--seed: Input should be greater than or equal"),
        (["touch", "-c", "nope"], "--classifier: unknown classifier 'nope'"),
    ]
    for args, expected in cases:
        result = run_cli(capsys, store_url, "train", *args)
        assert result.code == 2, (args, result.err)
        assert result.err.strip().splitlines() == [result.err.strip()], result.err
        assert result.err.startswith(f"touchbench: error: {expected}"), result.err
    listing = run_cli(capsys, store_url, "models", "--json").json()["models"]
    assert [model["name"] for model in listing] == ["touch-nb"]


def test_a_deleted_version_never_comes_back_under_its_number(
    capsys: pytest.CaptureFixture[str], store_url: str, trained: Path
) -> None:
    """Issue 36: delete ``pin@2`` (the newest), train ``pin`` again with another classifier:
    it becomes ``pin@3`` with an id never given before, and ``rollback pin`` refuses rather
    than move ``@champion`` onto a model nobody promoted."""

    def train(classifier: str) -> dict[str, object]:
        done = run_cli(
            capsys, store_url, "train", "touch", "-c", classifier, "--target", "gesture",
            "--name", "pin", "--json",
        )  # fmt: skip
        assert done.code == 0, done.err
        model: dict[str, object] = done.json()
        return model

    assert [train("nb")["version"], train("j48")["version"]] == [1, 2]
    for version in ("pin@2", "pin@1"):
        assert run_cli(capsys, store_url, "promote", version).code == 0
    listing = run_cli(capsys, store_url, "models", "--json").json()["models"]
    deleted_id = next(m["id"] for m in listing if m["name"] == "pin" and m["version"] == 2)
    gone = run_cli(capsys, store_url, "delete-model", "pin")
    assert gone.code == 0 and f"deleted model {deleted_id} 'pin@2'" in gone.err
    again = train("ibk")
    assert again["version"] == 3 and isinstance(again["id"], int) and again["id"] > deleted_id
    refused = run_cli(capsys, store_url, "rollback", "pin")
    assert refused.code == 2 and "nothing to roll back to" in refused.err, refused.err
    missing = run_cli(capsys, store_url, "predict", "pin@2", str(trained))
    assert missing.code == 2 and "model 'pin' has no version 2 (versions: 1, 3)" in missing.err
    listing = run_cli(capsys, store_url, "models", "--json").json()["models"]
    pins = [(m["id"], m["version"], m["classifier"], m["aliases"]) for m in listing[1:]]
    assert pins == [
        (pins[0][0], 1, "nb", ["champion"]),
        (again["id"], 3, "ibk", []),
    ]
