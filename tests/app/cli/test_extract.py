"""`touchbench extract`: simulated recordings -> a stored data set, and its bad input."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.support.cli_runner import run_cli
from touchbench.app.services.simulation import write_labels, write_session


@pytest.fixture
def session(tmp_path: Path) -> tuple[Path, Path, int]:
    wav, touches = write_session(tmp_path, "s1", n_touches=6, seed=3)
    labels = write_labels(tmp_path / "labels.csv", [(wav.name, *t) for t in touches])
    return wav, labels, len(touches)


def test_extract_stores_a_labelled_dataset_with_uc3m_features(
    capsys: pytest.CaptureFixture[str], store_url: str, session: tuple[Path, Path, int]
) -> None:
    wav, labels, n_touches = session
    result = run_cli(
        capsys,
        store_url,
        "extract",
        str(wav),
        "--labels",
        str(labels),
        "--extractor",
        "uc3m-audio",
        "--name",
        "sim",
        "--json",
    )
    assert result.code == 0, result.err
    summary = result.json()
    assert summary["events_found"] == n_touches
    assert summary["events_labelled"] == n_touches and summary["events_dropped"] == 0
    assert (summary["name"], summary["n_instances"], summary["n_features"]) == ("sim", 6, 99)
    assert summary["targets"] == ["gesture", "place"]
    shown = run_cli(capsys, store_url, "show", "sim", "--json").json()
    names = [a["name"] for a in shown["attributes"]]
    assert names[:4] == ["gesture", "place", "pitchFFT_1", "pitchFFTMin_1"]
    assert names[-1] == "duration_3"
    exported = run_cli(capsys, store_url, "export", "sim")
    assert exported.out.startswith("@relation") and "-C 2" in exported.out.splitlines()[0]


def test_extract_bad_input_exits_2_and_stores_nothing(
    capsys: pytest.CaptureFixture[str],
    store_url: str,
    session: tuple[Path, Path, int],
    tmp_path: Path,
) -> None:
    wav, labels, _ = session
    bad_labels = tmp_path / "bad.csv"
    bad_labels.write_text("file,start,end,gesture\nmissing.wav,0,1,tap\n", encoding="utf-8")
    cases = [
        (["extract", str(wav), "--labels", str(bad_labels)], "missing.wav"),
        (["extract", str(wav), "--labels", str(labels), "--extractor", "nope"], "nope"),
        (["extract", str(tmp_path / "absent.wav"), "--labels", str(labels)], "absent.wav"),
    ]
    empty = tmp_path / "empty.wav"
    empty.write_bytes(b"")
    cases.append((["extract", str(empty)], "empty.wav"))
    for args, expected in cases:
        result = run_cli(capsys, store_url, *args)
        assert result.code == 2, (args, result.err)
        assert len(result.err.strip().splitlines()) == 1, result.err
        assert expected in result.err
    assert run_cli(capsys, store_url, "datasets", "--json").json() == {"datasets": []}


def test_the_request_is_refused_before_any_recording_is_read(
    capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path
) -> None:
    absent = str(tmp_path / "absent.wav")  # never opened: the request is refused first
    cases = [
        (["--events", "nope"], "--events: unknown event detection 'nope' (known: "),
        (["-e", "nope"], "--extractor: unknown extractor 'nope' (known: uc3m-audio, "),
        (["--segment", "2"], "--segment: only applies to --events 'none', not 'snr'"),
        (["-O", "bands=1"], "--option: unknown option 'bands' for extractor 'uc3m-audio'"),
        (["--max-event", "1e300"], "--max-event: Input should be less than or equal to 86400"),
        (["--name", "12"], "--name: a dataset name cannot be a number"),
    ]
    for args, expected in cases:
        result = run_cli(capsys, store_url, "extract", absent, *args)
        assert result.code == 2, (args, result.err)
        assert result.err.strip().splitlines() == [result.err.strip()], result.err
        assert result.err.startswith(f"touchbench: error: {expected}"), result.err
    assert run_cli(capsys, store_url, "datasets", "--json").json() == {"datasets": []}
