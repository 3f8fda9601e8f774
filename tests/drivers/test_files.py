from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import soundfile

from touchbench.drivers.errors import DriverError
from touchbench.drivers.files import read_recording


@pytest.mark.parametrize(("suffix", "subtype"), [(".wav", "PCM_16"), (".flac", "PCM_24")])
def test_audio_keeps_every_channel_and_the_file_rate(
    tmp_path: Path, suffix: str, subtype: str
) -> None:
    samples = 0.5 * np.random.default_rng(0).uniform(-1, 1, (4, 1000))
    path = tmp_path / f"take{suffix}"
    soundfile.write(path, samples.T, 44100, subtype=subtype)
    recording = read_recording(path)
    assert recording.samples.shape == (4, 1000) and recording.samples.dtype == np.float64
    assert recording.samplerate == 44100.0 and recording.path == str(path)
    assert np.allclose(recording.samples, samples, atol=2.0**-15)
    assert recording.duration == pytest.approx(1000 / 44100)


def test_audio_rate_must_agree_with_a_given_rate(tmp_path: Path) -> None:
    path = tmp_path / "take.wav"
    soundfile.write(path, np.zeros(100), 16000)
    with pytest.raises(DriverError, match="sampled at 16000 Hz, but samplerate=44100"):
        read_recording(path, samplerate=44100)


def test_csv_with_a_time_column_gives_the_rate(tmp_path: Path) -> None:
    path = tmp_path / "taxels.csv"
    rows = ["t,a,b"] + [f"{i / 800:.6f},{i},{-i}" for i in range(10)]
    path.write_text("\n".join(rows) + "\n")
    recording = read_recording(path)
    assert recording.samplerate == pytest.approx(800.0)
    assert np.array_equal(recording.samples, [np.arange(10.0), -np.arange(10.0)])


def test_csv_without_time_needs_a_samplerate(tmp_path: Path) -> None:
    path = tmp_path / "plain.csv"
    path.write_text("1,2\n3,4\n5,6\n")
    with pytest.raises(DriverError, match="no sample rate: give `samplerate` for a file"):
        read_recording(path)
    recording = read_recording(path, samplerate=100)
    assert np.array_equal(recording.samples, [[1, 3, 5], [2, 4, 6]])


def test_csv_errors_name_the_line_and_column(tmp_path: Path) -> None:
    path = tmp_path / "bad.csv"
    path.write_text("time,x\n0.0,1\n0.1,oops\n")
    with pytest.raises(DriverError, match=r"bad.csv:3: column 'x': 'oops' is not a number"):
        read_recording(path)
    path.write_text("time,x\n0.0,1\n0.1,\n")
    with pytest.raises(DriverError, match=r"bad.csv:3: column 'x' is empty"):
        read_recording(path)
    path.write_text("time,x\n0.0,1\n0.1,2,3\n")
    with pytest.raises(DriverError, match=r"bad.csv:3: has 3 fields, expected 2"):
        read_recording(path)
    path.write_text("time,x\n0.0,1\n0.1,2\n0.1,3\n")
    with pytest.raises(DriverError, match=r"bad.csv:4: column 'time': the time does not rise"):
        read_recording(path)


def test_csv_rows_logged_twice_are_left_out_with_a_note(tmp_path: Path) -> None:
    path = tmp_path / "twice.csv"
    rows = ["timestamp,x"] + [f"{1000 + 28 * i},{i}" for i in range(6)]
    path.write_text("\n".join([*rows, rows[-1], ""]))  # the last sample written again
    recording = read_recording(path, time_unit="ms")
    assert np.array_equal(recording.samples, [np.arange(6.0)])
    assert recording.samplerate == pytest.approx(1000 / 28)
    assert any(
        "1 row(s) repeat the row before" in note and "line 8" in note for note in recording.notes
    )
    assert not recording.resampled  # even stamps: nothing was put on a new grid
    path.write_text("\n".join([*rows, rows[-1].replace(",5", ",6"), ""]))
    with pytest.raises(DriverError, match=r"twice.csv:8: column 'timestamp': the time does not"):
        read_recording(path, time_unit="ms")


def test_npy_one_or_two_dimensional(tmp_path: Path) -> None:
    path = tmp_path / "signal.npy"
    np.save(path, np.arange(6.0))
    assert read_recording(path, samplerate=10).samples.shape == (1, 6)
    np.save(path, np.ones((3, 6), dtype=np.float32))
    assert read_recording(path, samplerate=10).samples.shape == (3, 6)
    with pytest.raises(DriverError, match="no sample rate"):
        read_recording(path)
    np.save(path, np.ones((2, 3, 4)))
    with pytest.raises(DriverError, match="must be 1-D"):
        read_recording(path, samplerate=10)


def test_nan_samples_are_reported_with_channel_and_time(tmp_path: Path) -> None:
    path = tmp_path / "gap.npy"
    data = np.zeros((2, 100))
    data[1, 50] = np.nan
    np.save(path, data)
    with pytest.raises(DriverError, match=r"channel 2 has a NaN or infinite sample at index 50"):
        read_recording(path, samplerate=100)


def test_missing_empty_and_unreadable_files(tmp_path: Path) -> None:
    with pytest.raises(DriverError, match="no such file"):
        read_recording(tmp_path / "absent.wav")
    empty = tmp_path / "empty.wav"
    soundfile.write(empty, np.zeros((0, 2)), 44100)
    with pytest.raises(DriverError, match="has no samples"):
        read_recording(empty)
    garbage = tmp_path / "noise.wav"
    garbage.write_bytes(b"this is not a wave file")
    with pytest.raises(DriverError, match=r"noise\.wav: cannot read as audio"):
        read_recording(garbage)
    with pytest.raises(DriverError, match="is a folder"):
        read_recording(tmp_path)


def test_a_bad_given_samplerate_is_rejected(tmp_path: Path) -> None:
    path = tmp_path / "signal.npy"
    np.save(path, np.zeros(10))
    for rate in (0, -5, float("nan")):
        with pytest.raises(DriverError, match="positive number of Hz"):
            read_recording(path, samplerate=rate)
