"""Sources on ROS topics through a transport of the test's own (no ROS needed): the
format from AudioInfo or options, raw PCM, live MP3, taxels one sample or a block per
message."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pytest

from tests.support.bagfiles import mp3_stream, pieces
from touchbench.drivers.errors import DriverError
from touchbench.drivers.ros_source import RosAudioSource, RosTaxelSource, info_topic_of
from touchbench.drivers.ros_transport import AudioFormat, Kind, Message


class ListTransport:
    """A transport whose topic holds ``messages``; counts how many were taken."""

    def __init__(self, messages: list[bytes | np.ndarray], info: AudioFormat | None = None):
        self.messages = messages
        self.info = info
        self.taken = 0
        self.published: list[str] = []

    def audio_info(self, topic: str, *, timeout: float) -> AudioFormat | None:
        return self.info

    def subscribe(self, topic: str, kind: Kind) -> Iterator[Message]:
        for data in self.messages:
            self.taken += 1
            yield Message(data, float(self.taken))

    def advertise(self, topic: str) -> None:
        pass

    def publish(self, text: str) -> None:
        self.published.append(text)

    def stop(self) -> None:
        pass

    def close(self) -> None:
        pass


def test_pcm_described_by_audio_info_comes_in_blocks_of_its_messages() -> None:
    rng = np.random.default_rng(0)
    frames = rng.integers(-32768, 32767, size=(1000, 2), dtype=np.int16)
    messages = [frames[i : i + 300].tobytes() for i in range(0, 1000, 300)]
    info = AudioFormat(channels=2, samplerate=16000.0, sample_format="S16LE", coding="wave")
    with RosAudioSource(ListTransport(messages, info), "/a", info_topic="/i") as source:
        blocks = list(source.blocks())
    assert (source.samplerate, source.n_channels) == (16000.0, 2)
    assert [b.time for b in blocks] == [0.0, 300 / 16000, 600 / 16000, 900 / 16000]
    assert [b.arrived for b in blocks] == [1.0, 2.0, 3.0, 4.0]
    joined = np.concatenate([b.samples for b in blocks], axis=1)
    np.testing.assert_array_equal(joined, frames.T / 32768.0)
    assert "S16LE 2 channel(s) at 16000 Hz" in source.notes[0]


def test_without_audio_info_the_format_must_be_given() -> None:
    with pytest.raises(DriverError, match=r"no AudioInfo on '/i' within 0.5 s.*sample format"):
        RosAudioSource(ListTransport([]), "/a", info_topic="/i", info_timeout=0.5)
    given = RosAudioSource(
        ListTransport([np.zeros(4, "<f4").tobytes()]),
        "/a",
        info_topic="/i",
        samplerate=8000,
        channels=2,
        sample_format="F32LE",
    )
    assert [b.samples.shape for b in given.blocks()] == [(2, 2)]


def test_options_that_disagree_with_audio_info_are_refused() -> None:
    info = AudioFormat(channels=1, samplerate=16000.0, sample_format="S16LE", coding="wave")
    refused = r"AudioInfo on '/i' gives sample rate 16000 for '/a', but 44100"
    with pytest.raises(DriverError, match=refused):
        RosAudioSource(ListTransport([], info), "/a", info_topic="/i", samplerate=44100)
    flac = AudioFormat(channels=1, samplerate=16000.0, sample_format="", coding="flac")
    with pytest.raises(DriverError, match="flac-coded audio; touchbench reads raw PCM"):
        RosAudioSource(ListTransport([], flac), "/a", info_topic="/i")


def test_live_mp3_is_decoded_as_its_messages_come() -> None:
    rng = np.random.default_rng(1)
    audio = 0.2 * rng.standard_normal((1, 3 * 22050))
    messages: list[bytes | np.ndarray] = list(pieces(mp3_stream(audio, 22050), 1500))
    info = AudioFormat(channels=1, samplerate=22050.0, sample_format="", coding="mp3")
    transport = ListTransport(messages, info)
    source = RosAudioSource(transport, "/a", info_topic="/i")
    # Opening read the first frames only: a live stream is not scanned to its end.
    assert transport.taken < len(messages) // 2
    decoded = np.concatenate([b.samples for b in source.blocks()], axis=1)
    source.close()
    assert (source.samplerate, source.n_channels) == (22050.0, 1)
    assert transport.taken == len(messages)
    assert abs(decoded.shape[1] - audio.shape[1]) < 2 * 1152  # the codec's delay and padding


def test_taxels_come_one_sample_or_one_block_per_message() -> None:
    samples = np.arange(12, dtype=np.float32).reshape(4, 3)  # 4 samples of 3 taxels
    one_each: list[bytes | np.ndarray] = list(samples)
    blocked: list[bytes | np.ndarray] = [samples[:3], samples[3:]]
    for messages, times in ((one_each, [0.0, 0.01, 0.02, 0.03]), (blocked, [0.0, 0.03])):
        source = RosTaxelSource(ListTransport(messages), "/t", samplerate=100, channels=3)
        blocks = list(source.blocks())
        assert [b.time for b in blocks] == pytest.approx(times)
        joined = np.concatenate([b.samples for b in blocks], axis=1)
        np.testing.assert_array_equal(joined, samples.T)
    wrong = RosTaxelSource(ListTransport([samples[0]]), "/t", samplerate=100, channels=4)
    with pytest.raises(DriverError, match="message 1 holds 3 taxel value"):
        list(wrong.blocks())


def test_the_info_topic_is_audio_info_beside_the_audio() -> None:
    assert info_topic_of("/audio/audio") == "/audio/audio_info"
    assert info_topic_of("/audio") == "/audio_info"
    assert info_topic_of("/robot/mic/") == "/robot/audio_info"
