from __future__ import annotations

from itertools import pairwise

import numpy as np
import pytest

from touchbench.drivers.errors import DriverError
from touchbench.drivers.simulated import SimulatedTouch, simulate_session
from touchbench.drivers.source import RecordingSource


def test_sessions_are_reproducible_from_the_seed() -> None:
    first = simulate_session(duration=5.0, seed=7)
    again = simulate_session(duration=5.0, seed=7)
    other = simulate_session(duration=5.0, seed=8)
    assert first.touches == again.touches
    assert np.array_equal(first.recording.samples, again.recording.samples)
    assert not np.array_equal(first.recording.samples, other.recording.samples)


def test_random_touches_are_separated_and_inside_the_session() -> None:
    session = simulate_session(duration=20.0, n_touches=8, min_gap=1.0, seed=1, n_channels=2)
    touches = session.touches
    assert len(touches) >= 5
    assert all(t.onset >= 0.5 and t.end < 20.0 for t in touches)
    assert all(later.onset - earlier.end >= 1.0 for earlier, later in pairwise(touches))
    assert all(set(t.channels) <= {0, 1} for t in touches)


def test_touches_are_heard_only_on_their_channels_and_only_when_they_happen() -> None:
    touch = SimulatedTouch(onset=1.0, duration=0.2, channels=(1,), kind="stroke", amplitude=0.4)
    session = simulate_session(
        duration=2.0, samplerate=8000.0, n_channels=2, touches=[touch], noise_level=0.0
    )
    samples = session.recording.samples
    assert not samples[0].any()
    assert not samples[1, :8000].any() and not samples[1, 9600:].any()
    assert 0.1 < np.abs(samples[1, 8000:9600]).max() <= 0.4


def test_bad_touches_and_sessions_are_rejected() -> None:
    with pytest.raises(DriverError, match="names channels"):
        simulate_session(duration=2.0, n_channels=2, touches=[SimulatedTouch(1.0, 0.1, (2,))])
    with pytest.raises(DriverError, match="does not fit"):
        simulate_session(duration=2.0, touches=[SimulatedTouch(3.0, 0.1, (0,))])
    with pytest.raises(DriverError, match="positive duration"):
        simulate_session(duration=0.0)


def test_recording_source_replays_blocks_that_cover_the_recording() -> None:
    recording = simulate_session(duration=1.0, samplerate=1000.0, n_touches=0).recording
    with RecordingSource(recording, block_length=300) as source:
        blocks = list(source.blocks())
    assert [block.samples.shape for block in blocks] == [(3, 300)] * 3 + [(3, 100)]
    assert [block.time for block in blocks] == [0.0, 0.3, 0.6, 0.9]
    assert np.array_equal(np.concatenate([b.samples for b in blocks], axis=1), recording.samples)
    assert source.samplerate == 1000.0 and source.n_channels == 3
    with pytest.raises(DriverError, match="block_length"):
        RecordingSource(recording, block_length=0)
