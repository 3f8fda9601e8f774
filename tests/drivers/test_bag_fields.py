"""Numeric fields of bag topics as channels: a BioTac-like message of our own with a header,
std_msgs/Float32MultiArray taxels, stamps that jitter; and the fields that must be refused."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from tests.support.bagfiles import BIOTAC_MSG, BIOTAC_TYPE, float_array, write_fields_bag
from touchbench.drivers.bag_reader import topic_listing
from touchbench.drivers.errors import DriverError
from touchbench.drivers.replay import FileReplaySource

START = 1_700_000_000 * 10**9  # the bag's first message, in ns
N = 400


def _jittered(seed: int, n: int = N) -> np.ndarray:
    """Seconds after the bag's start, a 100 Hz sensor's: steps of 3 to 17 ms."""
    return 0.5 + np.cumsum(np.random.default_rng(seed).uniform(0.003, 0.017, n))


def _biotac(times: np.ndarray) -> list[dict]:
    """Messages stamped at ``times`` whose values are straight lines in time, so that
    linear interpolation onto any grid gives them exactly."""
    return [
        {
            "stamp": START + round(t * 1e9),
            "pdc": round(1000 + 100 * t),  # uint16: whole numbers, checked loosely
            "tdc": 7,
            "pac": (np.arange(22) + 1000 * t).astype(np.int16),
            "electrodes": np.full(19, 3, dtype=np.uint16),
            "sensor": "left",
        }
        for t in times
    ]


def _biotac_bag(path: Path, messages: list[dict], received: np.ndarray) -> Path:
    """A bag of BioTac-like ``messages`` on ``/biotac``, received at ``received``."""
    return write_fields_bag(
        path,
        msgtype=BIOTAC_TYPE,
        definition=BIOTAC_MSG,
        messages=messages,
        received=received,
        topic="/biotac",
    )


def _read(bag: Path, **options: object) -> tuple[FileReplaySource, np.ndarray, np.ndarray]:
    """The source, its samples and each sample's time."""
    with FileReplaySource(bag, **options) as source:  # type: ignore[arg-type]
        blocks = list(source.blocks())
    samples = np.concatenate([block.samples for block in blocks], axis=1)
    times = np.concatenate(
        [block.time + np.arange(block.samples.shape[1]) / source.samplerate for block in blocks]
    )
    return source, samples, times


@pytest.mark.parametrize("suffix", [".bag", ".mcap", ".db3"])
def test_a_custom_message_is_read_at_its_header_stamps_on_an_even_grid(
    tmp_path: Path, suffix: str
) -> None:
    stamps = _jittered(1)
    received = stamps + 0.004  # the bag receives each message 4 ms after its stamp
    bag = _biotac_bag(tmp_path / f"finger{suffix}", _biotac(stamps), received)
    source, samples, times = _read(bag, topic="/biotac", fields=["pdc", "pac"])
    inner = source._inner
    assert inner is not None
    assert inner.channel_names == ["pdc", *(f"pac[{i}]" for i in range(22))]  # type: ignore[attr-defined]
    steps = np.diff(stamps)
    assert source.samplerate == pytest.approx(1 / np.median(steps)) and source.resampled
    assert source.start_time == pytest.approx(stamps[0], abs=1e-9)
    assert times[0] == pytest.approx(stamps[0], abs=1e-9)
    assert times[-1] <= stamps[-1] < times[-1] + 1 / source.samplerate
    # Straight lines in time stay straight lines on the grid (pac[k] = k + 1000 t, int16).
    expected = np.arange(22)[:, np.newaxis] + 1000 * times
    assert np.abs(samples[1:] - expected).max() < 1.0  # int16 rounding at the stamps
    assert np.abs(samples[0] - (1000 + 100 * times)).max() < 1.0
    assert len(source.notes) == 1
    assert source.notes[0].startswith("stamps of '/biotac' are uneven (steps 3")
    assert "resampled onto an even" in source.notes[0]


def test_default_fields_and_a_given_rate(tmp_path: Path) -> None:
    stamps = _jittered(2)
    bag = _biotac_bag(tmp_path / "finger.bag", _biotac(stamps), stamps)
    source, samples, times = _read(bag, topic="/biotac", samplerate=50)
    names = source._inner.channel_names  # type: ignore[union-attr]
    assert names[:3] == ["pdc", "tdc", "pac[0]"] and names[-1] == "electrodes[18]"
    assert samples.shape[0] == 1 + 1 + 22 + 19
    assert source.samplerate == 50.0 and not source.resampled
    assert np.allclose(np.diff(times), 1 / 50)
    assert np.all(samples[1] == 7) and np.all(samples[-1] == 3)


@pytest.mark.parametrize("suffix", [".bag", ".mcap"])
def test_float32_multiarray_taxels_at_the_bags_receive_times(tmp_path: Path, suffix: str) -> None:
    received = _jittered(3)
    rng = np.random.default_rng(4)
    taxels = rng.normal(size=(N, 16)).astype(np.float32)
    bag = write_fields_bag(
        tmp_path / f"skin{suffix}",
        msgtype="std_msgs/msg/Float32MultiArray",
        messages=[float_array(row) for row in taxels],
        received=received,
        topic="/tactile",
    )
    rate = 1 / np.median(np.diff(received))
    source, samples, times = _read(bag, topic="/tactile")
    assert source._inner.channel_names == [f"data[{i}]" for i in range(16)]  # type: ignore[union-attr]
    assert source.samplerate == pytest.approx(rate)
    expected = np.stack([np.interp(times, received, taxels[:, i]) for i in range(16)])
    assert np.allclose(samples, expected, atol=1e-6)
    # Even stamps are no news; only the jitter is.
    assert source.notes and "stamps of '/tactile' are uneven" in source.notes[0]


def test_even_stamps_unset_headers_and_stamps_that_go_back(tmp_path: Path) -> None:
    received = 0.5 + np.arange(200) / 100
    messages = _biotac(received)
    for message in messages:
        message["stamp"] = 0  # a driver that leaves its header unset
    bag = _biotac_bag(tmp_path / "unset.bag", messages, received)
    source, samples, _ = _read(bag, topic="/biotac", fields=["tdc"])
    assert source.samplerate == pytest.approx(100)
    assert samples.shape == (1, 200)
    assert source.notes == [
        "'/biotac' read at the times the bag received it: its header stamps are not set"
    ]

    stamps = 0.5 + np.arange(200) / 100
    stamps[[50, 120]] = stamps[[49, 100]]  # a repeated stamp, and one that goes back
    bag = _biotac_bag(tmp_path / "back.bag", _biotac(stamps), 0.5 + np.arange(200) / 100)
    source, samples, _ = _read(bag, topic="/biotac", fields=["tdc"], samplerate=100)
    assert "2 message(s) of '/biotac' whose stamp did not rise past the one before" in " ".join(
        source.notes
    )
    assert samples.shape == (1, 200)


def test_fields_touchbench_cannot_read_are_refused_in_one_line(tmp_path: Path) -> None:
    stamps = _jittered(5, 50)
    bag = _biotac_bag(tmp_path / "finger.bag", _biotac(stamps), stamps)
    cases = [
        ({"topic": "/tactile"}, "no topic '/tactile'; its topics: /biotac ("),
        ({"topic": "/biotac", "fields": ["pressure"]}, "has no field 'pressure' (in 'pressure')"),
        ({"topic": "/biotac", "fields": ["sensor"]}, "field 'sensor' is string, not a number"),
        ({"topic": "/biotac", "fields": ["pac[30]"]}, "message 1 on '/biotac': "),
        ({"topic": "/biotac", "fields": ["pdc[0]"]}, "field 'pdc' (in 'pdc[0]') is not an array"),
        ({"topic": "/biotac", "fields": ["pdc.x"]}, "a number has no field 'x' (in 'pdc.x')"),
        ({"topic": "/biotac", "fields": ["pac-1"]}, "field 'pac-1' is not a field path"),
        ({"topic": "/status"}, "(std_msgs/msg/String) has no numeric field; its fields: data"),
        ({"fields": ["pdc"]}, "`fields` needs the `topic` they belong to"),
        ({"topic": "/biotac", "channels": 2}, "`channels` applies to audio, and topic '/biotac'"),
        ({}, "no audio topic (audio_common_msgs"),
    ]
    for options, expected in cases:
        with pytest.raises(DriverError) as caught:
            _read(bag, **options)
        assert expected in str(caught.value), (options, str(caught.value))
        assert "\n" not in str(caught.value)

    taxels = [float_array(np.zeros(16 if i < 10 else 12)) for i in range(20)]
    bag = write_fields_bag(
        tmp_path / "skin.bag",
        msgtype="std_msgs/msg/Float32MultiArray",
        messages=taxels,
        received=np.arange(20) / 100,
        topic="/tactile",
    )
    with pytest.raises(DriverError, match="message 11 on '/tactile' has 12 values, the first 16"):
        _read(bag, topic="/tactile")


def test_a_bag_of_many_topics_is_listed_in_a_few() -> None:
    connections = [
        SimpleNamespace(topic=f"/sensor{i}", msgtype="std_msgs/msg/Float32") for i in range(9)
    ]
    listing = topic_listing(connections)
    assert listing.startswith("/sensor0 (std_msgs/msg/Float32), /sensor1 (")
    assert listing.endswith("/sensor5 (std_msgs/msg/Float32) and 3 more")
    assert topic_listing([]) == "none"
