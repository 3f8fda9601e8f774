"""`touchbench extract` on CSV time series as real tactile exports write them: ROS stamps,
jitter, trailing commas, named channels; and the label leak a time column would open."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tests.support.cli_runner import run_cli
from tests.support.csvfiles import write_biotac_csv

RATE = 100.0


@pytest.fixture
def sqlite_url(tmp_path: Path) -> str:
    return f"sqlite:///{tmp_path / 'touchbench.db'}"


def _time_blocks(folder: Path, *, time_name: str) -> Path:
    """Two classes of the same noise, each recorded in its own hour: only the recording
    time tells them apart.  Returns the labels file."""
    folder.mkdir()
    rng = np.random.default_rng(7)
    rows = ["file,slip"]
    for label, hour in (("left", 0), ("right", 1)):
        for take in range(6):
            name = f"{label}-{take}.csv"
            start = 1.7e9 + 3600 * hour + 20 * take
            write_biotac_csv(
                folder / name,
                rng.standard_normal((3, 1000)),
                start=start,
                rate=RATE,
                seed=take,
                time_name=time_name,
            )
            rows.append(f"{name},{label}")
    labels = folder / "labels.csv"
    labels.write_text("\n".join(rows) + "\n")
    return labels


def _rf_accuracy(
    capsys: pytest.CaptureFixture[str], url: str, labels: Path, name: str, *extra: str
) -> float:
    recordings = sorted(str(p) for p in labels.parent.glob("*-*.csv"))
    extracted = run_cli(
        capsys,
        url,
        "extract",
        *recordings,
        "--labels",
        str(labels),
        "--extractor",
        "sequence",
        "--events",
        "none",
        "--segment",
        "1",
        "-O",
        "length=100",
        "--name",
        name,
        *extra,
        "--json",
    )
    assert extracted.code == 0, extracted.err
    run = run_cli(capsys, url, "bench", name, "--classifiers", "rf", "--folds", "3", "--json")
    assert run.code == 0, run.err
    (row,) = run.json()["leaderboard"]
    return float(row["metrics"]["accuracy"]["mean"])


def test_a_time_column_never_reaches_the_features(
    capsys: pytest.CaptureFixture[str], sqlite_url: str, tmp_path: Path
) -> None:
    labels = _time_blocks(tmp_path / "stamped", time_name="timestamp")
    accuracy = _rf_accuracy(capsys, sqlite_url, labels, "stamped")
    shown = run_cli(capsys, sqlite_url, "show", "stamped", "--json").json()
    names = [attribute["name"] for attribute in shown["attributes"]]
    assert names[:3] == ["slip", "tdc[0]", "tdc[1]"]
    assert not any(name.startswith("timestamp") for name in names)
    # 120 one-second windows of noise, folds grouped by recording: chance is 0.5.
    assert 0.3 < accuracy < 0.7, accuracy
    # The same files with a time column nobody recognises (read as a channel, as before
    # this was fixed): the recording time gives the label away, which this test sees.
    leaky = _time_blocks(tmp_path / "unnamed", time_name="clock")
    assert _rf_accuracy(capsys, sqlite_url, leaky, "leaky", "--samplerate", "100") > 0.95
    # ...and the column given by name is a time column again.
    given = _rf_accuracy(capsys, sqlite_url, leaky, "given", "--time-column", "clock")
    assert 0.3 < given < 0.7, given


def test_a_biotac_export_keeps_its_names_and_says_it_resampled(
    capsys: pytest.CaptureFixture[str], sqlite_url: str, tmp_path: Path
) -> None:
    path = tmp_path / "slip-01.csv"
    write_biotac_csv(path, np.random.default_rng(0).standard_normal((5, 600)), jitter=0.0045)
    result = run_cli(
        capsys,
        sqlite_url,
        "extract",
        str(path),
        "--extractor",
        "window",
        "--events",
        "none",
        "--segment",
        "1",
        "-O",
        "length=10",
        "--fields",
        "pac1,pac2",
        "--name",
        "biotac",
    )
    assert result.code == 0, result.err
    assert "note: slip-01.csv: column 'timestamp': stamps at " in result.err
    shown = run_cli(capsys, sqlite_url, "show", "biotac", "--json").json()
    names = [attribute["name"] for attribute in shown["attributes"]]
    assert names[:2] == ["t0_pac1", "t1_pac1"] and names[-1] == "t9_pac2" and len(names) == 20


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--fields", "ele1"], "slip.csv: has no channel 'ele1' (channels: tdc, tac)"),
        (["--time-column", "when"], "slip.csv: has no column 'when' to read times from"),
        (["--time-column", ""], "--time-column:"),
        (["--time-unit", "min"], "--time-unit: Input should be 'auto', 's', 'ms', 'us' or 'ns'"),
        (["--fields", "x" * 300], "--fields: String should have at most 200 characters"),
    ],
)
def test_bad_series_options_exit_2_in_one_line(
    capsys: pytest.CaptureFixture[str],
    sqlite_url: str,
    tmp_path: Path,
    args: list[str],
    message: str,
) -> None:
    path = tmp_path / "slip.csv"
    write_biotac_csv(path, np.zeros((2, 300)))
    result = run_cli(capsys, sqlite_url, "extract", str(path), "-e", "window", *args)
    assert result.code == 2, result.err
    assert len(result.err.strip().splitlines()) == 1 and message in result.err, result.err
