"""File replay: the blocks of every format extract reads, paced or not, and bad files."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest
import soundfile

from tests.support.bagfiles import write_audio_bag
from touchbench.drivers.errors import DriverError
from touchbench.drivers.files import read_recording
from touchbench.drivers.replay import FileReplaySource


def _joined(source: FileReplaySource) -> np.ndarray:
    with source:
        return np.concatenate([block.samples for block in source.blocks()], axis=1)


@pytest.fixture
def signal() -> np.ndarray:
    return 0.4 * np.random.default_rng(0).uniform(-1, 1, size=(3, 5000))


@pytest.mark.parametrize("suffix", [".wav", ".flac", ".npy", ".csv"])
def test_replay_gives_the_samples_read_recording_gives(
    tmp_path: Path, signal: np.ndarray, suffix: str
) -> None:
    path = tmp_path / f"take{suffix}"
    if suffix == ".npy":
        np.save(path, signal)
    elif suffix == ".csv":
        path.write_text(
            "a,b,c\n" + "\n".join(",".join(f"{v:.9f}" for v in row) for row in signal.T) + "\n"
        )
    else:
        soundfile.write(path, signal.T, 8000, subtype="FLOAT" if suffix == ".wav" else "PCM_24")
    rate = 8000.0 if suffix in (".npy", ".csv") else None
    whole = read_recording(path, samplerate=rate)
    source = FileReplaySource(path, samplerate=rate, block_length=700)
    assert (source.samplerate, source.n_channels) == (8000.0, 3)
    with source:
        blocks = list(source.blocks())
    assert [b.samples.shape[1] for b in blocks] == [700] * 7 + [100]
    assert [b.time for b in blocks[:2]] == [0.0, 700 / 8000]
    assert np.array_equal(np.concatenate([b.samples for b in blocks], axis=1), whole.samples)


def test_realtime_replay_is_paced(tmp_path: Path) -> None:
    path = tmp_path / "half-second.wav"
    soundfile.write(path, np.zeros((4000, 1)), 8000)
    began = time.perf_counter()
    with FileReplaySource(path, realtime=True, block_length=1000) as source:
        blocks = list(source.blocks())
    assert time.perf_counter() - began >= 0.45
    assert all(block.arrived is not None for block in blocks)
    fast = time.perf_counter()
    _joined(FileReplaySource(path, block_length=1000))
    assert time.perf_counter() - fast < 0.45


def test_a_nan_in_a_later_block_is_found_with_its_index(tmp_path: Path) -> None:
    data = np.zeros((2, 10000))
    data[1, 7777] = np.nan
    path = tmp_path / "gap.npy"
    np.save(path, data)
    with pytest.raises(
        DriverError, match=r"gap.npy: channel 2 has a NaN .* index 7777 \(0.7777 s\)"
    ):
        _joined(FileReplaySource(path, samplerate=10000.0, block_length=1000))


@pytest.mark.parametrize(
    ("name", "content", "message"),
    [
        ("notes.xyz", b"hello, not audio", r"not a recording touchbench can read .* ROS bags"),
        ("empty.wav", b"", "has no samples"),
        ("missing.wav", None, "no such file"),
    ],
)
def test_bad_files_are_one_clear_error(
    tmp_path: Path, name: str, content: bytes | None, message: str
) -> None:
    path = tmp_path / name
    if content is not None:
        path.write_bytes(content)
    with pytest.raises(DriverError, match=message):
        FileReplaySource(path)


def test_rates_and_topics_that_do_not_apply(tmp_path: Path) -> None:
    path = tmp_path / "a.wav"
    soundfile.write(path, np.zeros((100, 1)), 8000)
    with pytest.raises(DriverError, match="sampled at 8000 Hz, but samplerate=16000"):
        FileReplaySource(path, samplerate=16000)
    with pytest.raises(DriverError, match="`topic` applies to ROS bags only"):
        FileReplaySource(path, topic="/audio")
    np.save(tmp_path / "b.npy", np.zeros(10))
    with pytest.raises(DriverError, match="no sample rate"):
        FileReplaySource(tmp_path / "b.npy")


def test_a_bag_with_several_audio_topics_asks_for_one(tmp_path: Path) -> None:
    samples = np.zeros((1, 2048))
    bag = write_audio_bag(tmp_path / "two.mcap", samples, 8000, twin_topic="/audio/twin")
    with pytest.raises(DriverError) as error:
        FileReplaySource(bag)
    assert str(error.value).endswith(
        "several audio topics (/audio/audio, /audio/twin); choose one as `topic`"
    )
    chosen = FileReplaySource(bag, topic="/audio/twin")
    try:
        assert (chosen.samplerate, chosen.n_channels) == (8000, 1)
    finally:
        chosen.close()
