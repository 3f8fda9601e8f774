"""A model trained on extracted recordings predicts a raw recording (`predict MODEL
take.csv`) and a replay at a given rate (`live --replay FILE --samplerate HZ`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tests.support.cli_runner import run_cli
from tests.support.recordings import RATE, write_take


@pytest.fixture
def model(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> tuple[str, Path]:
    url = f"sqlite:///{tmp_path / 'touchbench.db'}"
    folder = tmp_path / "session"
    folder.mkdir()
    rows = ["file,state"]
    for take in range(8):
        kind = "slip" if take % 2 else "still"
        write_take(folder / f"take-{take}.csv", kind, seed=take)
        rows.append(f"take-{take}.csv,{kind}")
    labels = folder / "labels.csv"
    labels.write_text("\n".join(rows) + "\n")
    takes = sorted(str(p) for p in folder.glob("take-*.csv"))
    extracted = run_cli(
        capsys,
        url,
        "extract",
        *takes,
        "--labels",
        str(labels),
        "-e",
        "taxel-dft",
        "--samplerate",  # the sensor's nominal rate: the grid of the jittered stamps
        "100",
        "--name",
        "slips",
    )
    assert extracted.code == 0, extracted.err
    trained = run_cli(capsys, url, "train", "slips", "--classifier", "rf", "--json")
    assert trained.code == 0, trained.err
    return trained.json()["name"], tmp_path


def test_predict_extracts_a_raw_recording_with_the_models_recipe(
    capsys: pytest.CaptureFixture[str], model: tuple[str, Path]
) -> None:
    name, folder = model
    url = f"sqlite:///{folder / 'touchbench.db'}"
    unseen = folder / "unseen.csv"
    write_take(unseen, "slip", seed=42)
    result = run_cli(capsys, url, "predict", name, str(unseen), "--json")
    assert result.code == 0, result.err
    report = result.json()
    labels = [row["state"] for row in report["predictions"]]
    # 6 s resampled onto the model's grid (100 Hz), 64-sample windows every 8: about 67.
    assert 62 <= len(labels) <= 72
    assert labels.count("slip") > 0.9 * len(labels)
    assert any("unseen.csv: column 'timestamp'" in warning for warning in report["warnings"])
    # The same as extracting the recording as a data set on that grid and predicting its
    # export.
    (listed,) = run_cli(capsys, url, "models", "--json").json()["models"]
    rate = str(listed["extraction"]["samplerate"])
    extracted = run_cli(
        capsys, url, "extract", str(unseen), "-e", "taxel-dft", "--samplerate", rate, "--name", "u"
    )
    assert extracted.code == 0, extracted.err
    exported = folder / "u.arff"
    exported.write_text(run_cli(capsys, url, "export", "u").out)
    offline = run_cli(capsys, url, "predict", name, str(exported), "--json").json()
    assert [row["state"] for row in offline["predictions"]] == labels


def test_live_replay_takes_the_given_rate(
    capsys: pytest.CaptureFixture[str], model: tuple[str, Path]
) -> None:
    name, folder = model
    url = f"sqlite:///{folder / 'touchbench.db'}"
    raw = folder / "raw.npy"
    rng = np.random.default_rng(5)
    np.save(
        raw, np.sin(2 * np.pi * 12 * np.arange(600) / RATE) + 0.1 * rng.standard_normal((3, 600))
    )
    refused = run_cli(capsys, url, "live", "--model", name, "--replay", str(raw))
    assert refused.code == 2 and "raw.npy: no sample rate" in refused.err, refused.err
    replayed = run_cli(
        capsys, url, "live", "--model", name, "--replay", str(raw), "--samplerate", "100", "--json"
    )
    assert replayed.code == 0, replayed.err
    lines = replayed.out.strip().splitlines()
    assert len(lines) == 1 + (600 - 64) // 8
