from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tests.support.csvfiles import write_biotac_csv
from tests.support.processes import run_script
from touchbench.drivers.errors import DriverError
from touchbench.drivers.files import read_recording
from touchbench.drivers.replay import FileReplaySource


def _sines(n: int, rate: float = 100.0) -> np.ndarray:
    t = np.arange(n) / rate
    return np.stack([np.sin(2 * np.pi * 1.0 * t), 100 + 10 * np.cos(2 * np.pi * 0.5 * t)])


def test_a_biotac_export_is_read_with_its_names_and_resampled(tmp_path: Path) -> None:
    path = tmp_path / "slip-01.csv"
    times = write_biotac_csv(path, _sines(500), jitter=0.004)
    recording = read_recording(path)
    assert recording.channels == ("tdc", "tac")
    assert recording.n_channels == 2  # the timestamp column is no channel
    assert recording.samplerate == pytest.approx(100.0, rel=0.02)
    assert recording.n_samples == int((times[-1] - times[0]) * recording.samplerate) + 1
    (note,) = recording.notes
    assert "column 'timestamp': stamps at " in note and "resampled to" in note
    assert np.abs(recording.samples[1] - 100).max() <= 10.01


def test_a_given_rate_is_the_grid(tmp_path: Path) -> None:
    path = tmp_path / "take.csv"
    times = write_biotac_csv(path, _sines(300), jitter=0.003)
    recording = read_recording(path, samplerate=50)
    assert recording.samplerate == 50
    assert recording.n_samples == int((times[-1] - times[0]) * 50 + 1e-9) + 1
    assert "at 50 Hz" in recording.notes[0]


def test_even_stamps_are_not_resampled(tmp_path: Path) -> None:
    path = tmp_path / "even.csv"
    write_biotac_csv(path, _sines(100), jitter=0.0, start=0.0)
    recording = read_recording(path)
    assert recording.notes == () and recording.n_samples == 100
    assert recording.samplerate == pytest.approx(100.0)


def test_nanosecond_stamps_are_told_by_magnitude(tmp_path: Path) -> None:
    path = tmp_path / "ns.csv"
    write_biotac_csv(path, _sines(200), jitter=0.0, nanoseconds=True, time_name="header.stamp")
    recording = read_recording(path)
    assert recording.samplerate == pytest.approx(100.0, rel=1e-4)
    assert recording.notes == ("column 'header.stamp' holds nanoseconds",)
    assert recording.channels == ("tdc", "tac")


def test_millisecond_stamps_are_read_with_their_unit_and_noted_without(tmp_path: Path) -> None:
    """As the FabricSlide exports write them: milliseconds since the sensor started."""
    path = tmp_path / "ms.csv"
    lines = ["timestamp,c1"] + [f"{4277465 + 28 * i},{i % 7}" for i in range(200)]
    path.write_text("\n".join(lines) + "\n")
    given = read_recording(path, time_unit="ms")
    assert given.samplerate == pytest.approx(1000 / 28) and given.notes == ()
    guessed = read_recording(path)
    assert guessed.samplerate == pytest.approx(1 / 28)
    assert guessed.notes[0] == (
        "column 'timestamp' read as seconds: 28 s between samples (0.0357 Hz); if its "
        "stamps are milliseconds, give the time unit (ms)"
    )
    assert read_recording(path, time_unit="s").notes == ()  # said, so nothing to note


@pytest.mark.parametrize("name", ["time", "T", "Timestamp", "stamp", "header.stamp", "%time"])
def test_time_columns_are_found_by_name(tmp_path: Path, name: str) -> None:
    path = tmp_path / "named.csv"
    write_biotac_csv(path, _sines(50), jitter=0.0, start=0.0, time_name=name)
    assert read_recording(path).channels == ("tdc", "tac")


def test_a_time_column_can_be_given(tmp_path: Path) -> None:
    path = tmp_path / "given.csv"
    write_biotac_csv(path, _sines(50), jitter=0.0, start=0.0, time_name="clock")
    with pytest.raises(DriverError, match="no sample rate"):
        read_recording(path)
    recording = read_recording(path, time_column="CLOCK")
    assert recording.channels == ("tdc", "tac") and recording.samplerate == pytest.approx(100)
    with pytest.raises(DriverError, match=r"given.csv: has no column 'when' to read times from"):
        read_recording(path, time_column="when")


def test_channels_are_picked_by_name_or_number(tmp_path: Path) -> None:
    path = tmp_path / "pick.csv"
    samples = np.arange(4 * 20.0).reshape(4, 20)
    write_biotac_csv(path, samples, jitter=0.0, start=0.0)
    recording = read_recording(path, fields=["pac1", "TDC"])
    assert recording.channels == ("pac1", "tdc")
    assert np.allclose(recording.samples, samples[[3, 0]])
    assert read_recording(path, fields=["2"]).channels == ("tac",)
    with pytest.raises(
        DriverError, match=r"has no channel 'ele1' \(channels: tdc, tac, pdc, pac1\)"
    ):
        read_recording(path, fields=["ele1"])
    with pytest.raises(DriverError, match="has no channel 'timestamp'"):
        read_recording(path, fields=["timestamp"])


def test_many_channels_are_named_a_few_at_a_time(tmp_path: Path) -> None:
    path = tmp_path / "wide.csv"
    write_biotac_csv(path, np.zeros((25, 10)), jitter=0.0, start=0.0)
    with pytest.raises(DriverError, match=r"pac5 and 17 more\)$"):
        read_recording(path, fields=["nope"])


def test_a_trailing_comma_is_accepted_without_a_header_too(tmp_path: Path) -> None:
    path = tmp_path / "plain.csv"
    path.write_text("1,2,\n3,4,\n5,6,\n")
    recording = read_recording(path, samplerate=10)
    assert np.array_equal(recording.samples, [[1, 3, 5], [2, 4, 6]])
    assert recording.channels is None


def test_the_replay_source_carries_names_and_notes(tmp_path: Path) -> None:
    path = tmp_path / "replay.csv"
    write_biotac_csv(path, _sines(300))
    with FileReplaySource(path, fields=["tac"]) as source:
        assert source.channel_names == ("tac",) and source.n_channels == 1
        assert len(source.notes) == 1
        total = sum(block.samples.shape[1] for block in source.blocks())
    assert total > 290
    wav = tmp_path / "x.npy"
    np.save(wav, np.zeros(10))
    with pytest.raises(DriverError, match="`fields` applies to ROS bags and CSV files only"):
        FileReplaySource(wav, samplerate=10, fields=["1"])


#: Reads ``long.csv`` in a fresh interpreter and prints its peak resident memory (VmHWM,
#: KiB) before and after, and the samples read.
READ_WITH_PEAK = """
from touchbench.drivers.files import read_recording

def peak_kib():
    with open("/proc/self/status") as status:
        return next(int(line.split()[1]) for line in status if line.startswith("VmHWM:"))

before = peak_kib()
recording = read_recording("long.csv")
print(before, peak_kib(), recording.samples.shape[1])
"""


def test_reading_a_long_csv_holds_its_values_about_once(tmp_path: Path) -> None:
    """Issue 36: the rows parsed go straight into the samples' final layout, not joined
    into one table, then copied to take the time column out and to transpose it."""
    rows, channels = 300_000, 4
    table = np.column_stack(
        [np.arange(rows) / 1000.0, np.random.default_rng(0).normal(size=(rows, channels))]
    )
    header = ",".join(["time", *(f"ch{c}" for c in range(channels))])
    np.savetxt(tmp_path / "long.csv", table, fmt="%.6f", delimiter=",", header=header, comments="")
    before, after, samples = (
        int(word) for word in run_script(READ_WITH_PEAK, tmp_path).stdout.split()
    )
    assert samples == rows
    values_kib = table.nbytes / 1024  # 11.4 MiB
    # The values once, their time column's steps once more (for the median step), and a
    # few MiB of parsing: 1.4 x the values here; the table joined, the time column taken
    # out and the channels transposed made it 2.8 x.
    grown = after - before
    assert grown < 1.6 * values_kib + 4 * 1024, f"{grown / values_kib:.2f} x the values"
