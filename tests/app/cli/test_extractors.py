"""`touchbench extractors` (options as data) and the defaults extraction computes from
the recordings: taxel-dft at 100 Hz, sequences of whole recordings."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tests.support.cli_runner import run_cli
from tests.support.csvfiles import write_biotac_csv


@pytest.fixture
def sqlite_url(tmp_path: Path) -> str:
    return f"sqlite:///{tmp_path / 'touchbench.db'}"


def test_extractors_lists_every_option_and_extract_help_points_to_it(
    capsys: pytest.CaptureFixture[str], sqlite_url: str
) -> None:
    listed = run_cli(capsys, sqlite_url, "extractors", "--json")
    assert listed.code == 0, listed.err
    body = listed.json()
    assert [e["name"] for e in body["extractors"]] == [
        "uc3m-audio",
        "band-peaks",
        "mfcc",
        "taxel-dft",
        "window",
        "sequence",
    ]
    window = next(e for e in body["extractors"] if e["name"] == "window")
    assert window["options"][0] == {
        "name": "length",
        "type": "integer >= 1",
        "default": 25,
        "default_text": None,
        "meaning": "samples from the onset",
        "at_rate": None,
    }
    snr = next(e for e in body["events"] if e["name"] == "snr")
    assert "threshold" in [o["name"] for o in snr["options"]]
    table = run_cli(capsys, sqlite_url, "extractors", "--samplerate", "100")
    assert table.code == 0 and "1 at 100 Hz" in table.out and "--extractor taxel-dft" in table.out
    assert "4 from 400 Hz up" in run_cli(capsys, sqlite_url, "extractors").out
    refused = run_cli(capsys, sqlite_url, "extractors", "--samplerate", "0")
    assert refused.code == 2 and refused.err.count("\n") == 1 and "--samplerate" in refused.err
    helped = run_cli(capsys, sqlite_url, "extract", "--help")
    assert "touchbench extractors" in " ".join(helped.out.split())


def test_taxel_dft_at_100_hz_says_which_bins_it_dropped(
    capsys: pytest.CaptureFixture[str], sqlite_url: str, tmp_path: Path
) -> None:
    path = tmp_path / "slip.csv"
    write_biotac_csv(path, np.random.default_rng(0).standard_normal((2, 400)), jitter=0.0)
    result = run_cli(capsys, sqlite_url, "extract", str(path), "-e", "taxel-dft", "--json")
    assert result.code == 0, result.err
    summary = result.json()
    assert summary["notes"] == [
        "extractor 'taxel-dft': drop=1 at 100 Hz (4 from 400 Hz up (as published), else 1 "
        "(DC only))"
    ]
    assert summary["n_features"] == 2 * 31
    kept = run_cli(
        capsys, sqlite_url, "extract", str(path), "-e", "taxel-dft", "-O", "drop=0", "--json"
    ).json()
    assert kept["n_features"] == 2 * 32 and kept["notes"] == []
    names = [
        a["name"]
        for a in run_cli(capsys, sqlite_url, "show", kept["name"], "--json").json()["attributes"]
    ]
    assert names[:2] == ["dft0_tdc", "dft1_tdc"]


def test_sequences_of_whole_recordings_take_the_longest_one(
    capsys: pytest.CaptureFixture[str], sqlite_url: str, tmp_path: Path
) -> None:
    rng = np.random.default_rng(2)
    paths = []
    for name, n in (("a.csv", 800), ("b.csv", 500), ("c.csv", 120)):
        paths.append(tmp_path / name)
        write_biotac_csv(paths[-1], rng.standard_normal((2, n)), jitter=0.0, start=0.0)
    result = run_cli(
        capsys,
        sqlite_url,
        "extract",
        *map(str, paths),
        "-e",
        "sequence",
        "--events",
        "none",
        "--name",
        "whole",
        "--json",
    )
    assert result.code == 0, result.err
    summary = result.json()
    assert (summary["n_instances"], summary["n_features"]) == (3, 2 * 800)
    assert summary["notes"] == [
        "extractor 'sequence': length=800 samples (8 s), the longest recording; shorter ones "
        "are padded with their last sample"
    ]
    assert summary["warnings"] == []
    cut = run_cli(
        capsys,
        sqlite_url,
        "extract",
        *map(str, paths),
        "-e",
        "sequence",
        "--events",
        "none",
        "-O",
        "length=200",
        "--json",
    ).json()
    assert cut["n_features"] == 2 * 200 and cut["n_instances"] == 3
    assert "cut or padded to length=200" in cut["notes"][0]
