"""Audio in ROS bags as other tools write it: audio_capture's MP3 frames (with or without an
AudioInfo topic) and raw PCM without AudioInfo, in real ROS 1 and ROS 2 bags."""

from __future__ import annotations

import io
import os
from pathlib import Path

import numpy as np
import pytest

from tests.support.bagfiles import encode, mp3_stream, pieces, write_audio_bag
from touchbench.drivers.errors import DriverError
from touchbench.drivers.mp3 import ChunkStream, frame_length, looks_like_mp3
from touchbench.drivers.replay import FileReplaySource

RATE = 44100
#: Samples one MPEG-1 layer III frame decodes to.
FRAME = 1152


@pytest.fixture(scope="module")
def tones() -> np.ndarray:
    """3 s of two channels: a tone, silence, then noise (so that a variable bitrate
    varies); and a chirp from 200 to 2000 Hz, whose delay after decoding is unambiguous."""
    t = np.arange(3 * RATE) / RATE
    noise = np.random.default_rng(3).normal(0, 0.2, t.size) * (t >= 2)
    chirp = 0.3 * np.sin(2 * np.pi * (200 * t + 300 * t**2))
    return np.stack([0.5 * np.sin(2 * np.pi * 440 * t) * (t < 1) + noise, chirp])


def _frames(stream: bytes) -> int:
    """MPEG frames in ``stream``, counted header by header."""
    count, offset = 0, 0
    while offset < len(stream):
        length = frame_length(stream[offset : offset + 4])
        assert length, f"no frame header at byte {offset}"
        offset, count = offset + length, count + 1
    return count


def _read(bag: Path, **options: object) -> tuple[FileReplaySource, np.ndarray]:
    with FileReplaySource(bag, **options) as source:  # type: ignore[arg-type]
        samples = np.concatenate([block.samples for block in source.blocks()], axis=1)
    return source, samples


def _aligned_error(decoded: np.ndarray, original: np.ndarray) -> tuple[int, float]:
    """The decoder's delay (samples) by cross-correlation of the chirp, and the largest
    difference of the delayed decoded chirp and tone from the original's."""
    probe = original[1, RATE // 2 : RATE // 2 + 4096]
    scores = [probe @ decoded[1, RATE // 2 + lag : RATE // 2 + lag + 4096] for lag in range(3000)]
    lag = int(np.argmax(scores))
    shifted = decoded[:, lag : lag + original.shape[1]]
    chirp = np.abs(shifted[1, RATE // 4 : -RATE // 4] - original[1, RATE // 4 : -RATE // 4])
    tone = np.abs(shifted[0, RATE // 4 : RATE - 2000] - original[0, RATE // 4 : RATE - 2000])
    return lag, float(max(chirp.max(), tone.max()))


@pytest.mark.parametrize("variable", [False, True], ids=["cbr", "vbr"])
@pytest.mark.parametrize("suffix", [".bag", ".mcap", ".db3"])
@pytest.mark.parametrize("info", [True, False], ids=["audio_info", "no_audio_info"])
def test_mp3_frames_are_decoded_whole(
    tmp_path: Path, tones: np.ndarray, variable: bool, suffix: str, info: bool
) -> None:
    stream = mp3_stream(tones, RATE, variable=variable)
    bag = write_audio_bag(
        tmp_path / f"mic{suffix}",
        tones,
        RATE,
        coding_format="mp3",
        payloads=pieces(stream, 700),  # pieces cut across frames, as any chunking may be
        info_topic="/audio/audio_info" if info else None,
    )
    source, decoded = _read(bag)
    assert (source.samplerate, source.n_channels) == (RATE, 2)
    # Every frame decoded: libsndfile alone, given the stream's length, stops at its
    # estimate (a fifth of a variable-bitrate stream without a Xing header).
    assert decoded.shape[1] == _frames(stream) * FRAME
    lag, error = _aligned_error(decoded, tones)
    assert 0 < lag < 3000
    assert error < 0.05
    assert source.start_time == pytest.approx(0.25)
    assert bool(source.notes) is not info
    if not info:
        assert "read as MP3 (44100 Hz, 2 channel(s)" in source.notes[0]


def test_mp3_blocks_follow_each_other_in_time(tmp_path: Path, tones: np.ndarray) -> None:
    stream = mp3_stream(tones, RATE)
    bag = write_audio_bag(
        tmp_path / "mic.bag", tones, RATE, coding_format="mp3", payloads=pieces(stream, 417)
    )
    with FileReplaySource(bag) as source:
        blocks = list(source.blocks())
    assert len(blocks) > 2
    ends = [block.time + block.samples.shape[1] / RATE for block in blocks[:-1]]
    assert [block.time for block in blocks[1:]] == pytest.approx(ends)


def test_mp3_options_must_agree_with_the_frames(tmp_path: Path, tones: np.ndarray) -> None:
    bag = write_audio_bag(
        tmp_path / "mic.bag",
        tones,
        RATE,
        coding_format="mp3",
        payloads=pieces(mp3_stream(tones, RATE), 700),
        info_topic=None,
    )
    with pytest.raises(DriverError, match="its MP3 frames give samplerate 44100, but"):
        FileReplaySource(bag, samplerate=48000)
    with pytest.raises(DriverError, match="holds MP3 audio, not raw PCM of sample format S16LE"):
        FileReplaySource(bag, sample_format="S16LE", channels=2, samplerate=RATE)
    source, _ = _read(bag, samplerate=RATE, channels=2)
    assert source.n_channels == 2


@pytest.mark.parametrize("suffix", [".bag", ".mcap"])
@pytest.mark.parametrize("sample_format", ["S16LE", "S32LE", "F32LE"])
def test_pcm_without_audio_info_is_read_with_the_options(
    tmp_path: Path, tones: np.ndarray, suffix: str, sample_format: str
) -> None:
    bag = write_audio_bag(
        tmp_path / f"mic{suffix}", tones, RATE, sample_format=sample_format, info_topic=None
    )
    source, samples = _read(bag, samplerate=RATE, channels=2, sample_format=sample_format)
    dtype = {"S16LE": "<i2", "S32LE": "<i4", "F32LE": "<f4"}[sample_format]
    scale = {"S16LE": 32768.0, "S32LE": 2147483648.0, "F32LE": 1.0}[sample_format]
    expected = encode(tones, sample_format).view(dtype).reshape(-1, 2).T / scale
    assert np.array_equal(samples, expected)
    assert source.notes == []


def test_pcm_options_are_refused_naming_what_is_missing_or_differs(
    tmp_path: Path, tones: np.ndarray
) -> None:
    short = tones[:, :4096]
    no_info = write_audio_bag(tmp_path / "noinfo.bag", short, RATE, info_topic=None)
    with pytest.raises(
        DriverError, match="is not MP3, so its format is unknown: give `channels`, `sample_format`"
    ):
        FileReplaySource(no_info, samplerate=RATE)
    with pytest.raises(DriverError, match="give `samplerate` of the raw PCM"):
        FileReplaySource(no_info, channels=2, sample_format="S16LE")
    with pytest.raises(DriverError, match="4096 bytes are not whole S32LE frames of 3"):
        _read(no_info, samplerate=RATE, channels=3, sample_format="S32LE")
    with_info = write_audio_bag(tmp_path / "info.bag", short, RATE)
    with pytest.raises(DriverError, match="its AudioInfo give channels 2, but `channels` 1"):
        FileReplaySource(with_info, channels=1)
    with pytest.raises(DriverError, match="give sample_format S16LE, but `sample_format` F32LE"):
        FileReplaySource(with_info, sample_format="F32LE")
    source, _ = _read(with_info, samplerate=RATE, channels=2, sample_format="S16LE")
    assert source.n_channels == 2
    wav = tmp_path / "x.npy"
    np.save(wav, short)
    with pytest.raises(DriverError, match="`channels` applies to ROS bags only"):
        FileReplaySource(wav, samplerate=RATE, channels=2)


def test_raw_pcm_is_not_taken_for_mp3(tones: np.ndarray) -> None:
    stream = mp3_stream(tones, RATE)
    assert looks_like_mp3(stream) and looks_like_mp3(stream[:300])
    assert looks_like_mp3(b"ID3\x04" + bytes(20))
    for sample_format in ("S16LE", "S32LE", "F32LE"):
        assert not looks_like_mp3(encode(tones, sample_format).tobytes())
    # A loud PCM sample can start with an MPEG sync word; the next header is what decides.
    fake = bytearray(encode(tones, "S16LE").tobytes()[:4096])
    fake[:4] = stream[:4]
    assert not looks_like_mp3(bytes(fake))


def test_chunk_stream_reads_and_seeks_as_a_file_would() -> None:
    data = np.random.default_rng(0).integers(0, 256, 50_000, dtype=np.uint8).tobytes()
    stream = ChunkStream(lambda: iter(pieces(data, 333)), window=4096)
    reference = io.BytesIO(data)
    moves = [(0, os.SEEK_SET, 12), (0, os.SEEK_SET, 4), (413, os.SEEK_CUR, 4), (-417, 1, 5000)]
    moves += [(20_000, os.SEEK_SET, 100), (-3000, os.SEEK_CUR, 10), (100, os.SEEK_SET, 64)]
    moves += [(49_990, os.SEEK_SET, 100), (0, os.SEEK_SET, 0)]
    for offset, whence, size in moves:
        assert stream.seek(offset, whence) == reference.seek(offset, whence)
        assert stream.read(size) == reference.read(size)
        assert stream.tell() == reference.tell()
    # Seeks within the window reuse what was read (back 3000 bytes); further back (to 100,
    # and to 0) they start over.
    assert stream.restarts == 2
    position = stream.tell()
    stream.seek(0, os.SEEK_END)
    assert stream.tell() == 0 and stream.read(10) == b""
    stream.seek(position, os.SEEK_SET)
    assert stream.read(8) == data[position : position + 8]
