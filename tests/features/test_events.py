from __future__ import annotations

import numpy as np
import pytest

from tests.support.signals import click_train
from touchbench.drivers.simulated import SimulatedTouch, simulate_session
from touchbench.features.errors import FeatureError
from touchbench.features.events import (
    EVENT_KINDS,
    detect_dbscan,
    detect_events,
    detect_none,
    detect_snr,
)
from touchbench.features.snr import snr_track

SAMPLERATE = 44100.0
WINDOW_SECONDS = 256 / SAMPLERATE


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_snr_events_match_simulated_onsets_within_one_window(seed: int) -> None:
    session = simulate_session(duration=15.0, n_touches=7, seed=seed)
    detection = detect_snr(session.recording.samples, samplerate=SAMPLERATE)
    assert len(detection.events) == len(session.touches)
    for event, touch in zip(detection.events, session.touches, strict=True):
        start, end = event.seconds(SAMPLERATE)
        assert abs(start - touch.onset) <= WINDOW_SECONDS
        # The event ends a 500 ms hangover after the touch falls below the threshold,
        # which a decaying tap does before its nominal end.
        assert touch.onset + 0.5 <= end <= touch.end + 0.5 + 2 * WINDOW_SECONDS
        assert set(event.channels) <= set(touch.channels)
        assert event.n_contacts == 1


def test_touches_on_several_channels_form_one_event_from_first_onset_to_last_end() -> None:
    touches = [
        SimulatedTouch(1.0, 0.05, (0,), "tap", 0.3),
        SimulatedTouch(1.3, 0.05, (2,), "tap", 0.3),
        SimulatedTouch(3.0, 0.05, (1,), "tap", 0.3),
    ]
    session = simulate_session(duration=5.0, touches=touches, seed=4)
    events = detect_snr(session.recording.samples, samplerate=SAMPLERATE).events
    assert len(events) == 2
    first, second = events
    assert first.channels == (0, 2) and second.channels == (1,)
    assert abs(first.onset / SAMPLERATE - 1.0) <= WINDOW_SECONDS
    # Ends with channel 2's touch (1.3 s + up to 50 ms + 500 ms hangover), not channel 0's.
    assert 1.8 <= first.offset / SAMPLERATE <= 1.85 + 2 * WINDOW_SECONDS
    assert first.n_contacts == 2


@pytest.mark.parametrize(("rate", "duration"), [(4.0, 2.0), (8.0, 1.5)])
def test_a_click_train_gives_its_number_of_contacts(rate: float, duration: float) -> None:
    y, n_clicks = click_train(rate, duration=duration + 1.5, samplerate=SAMPLERATE)
    y[int((0.5 + duration) * SAMPLERATE) :] = y[-1000:].std() * 0  # clicks stop
    y += 1e-3 * np.random.default_rng(3).standard_normal(y.size)
    expected = int(np.ceil(duration * rate))
    events = detect_snr(y[np.newaxis, :], samplerate=SAMPLERATE).events
    assert len(events) == 1
    assert events[0].n_contacts == expected
    assert n_clicks > expected  # the train was cut, so the count is not trivially all clicks


def test_silence_and_steady_noise_give_no_event() -> None:
    assert detect_snr(np.zeros((2, 44100)), samplerate=SAMPLERATE).events == ()
    noise = 1e-3 * np.random.default_rng(0).standard_normal((2, 44100 * 3))
    assert detect_snr(noise, samplerate=SAMPLERATE).events == ()


def test_noise_floor_is_frozen_during_a_touch_and_follows_quiet_windows() -> None:
    session = simulate_session(
        duration=4.0,
        touches=[SimulatedTouch(1.0, 1.0, (0,), "stroke", 0.3)],
        seed=2,
        n_channels=1,
    )
    track = snr_track(session.recording.samples, samplerate=SAMPLERATE)
    (touch,) = track.touches
    floor = track.noise[0]
    assert np.all(floor[touch.first_window : touch.last_window + 1] == floor[touch.first_window])
    assert np.all(np.diff(floor[: touch.first_window]) != 0)  # updated while quiet
    assert np.all(track.snr[0, track.active[0]] > 10.0)
    assert touch.last_window - touch.first_window + 1 >= int(0.5 * SAMPLERATE / 256)


def test_snr_is_a_linear_amplitude_ratio() -> None:
    y = 1e-3 * np.random.default_rng(1).standard_normal((1, 44100))
    y[0, 22050:22306] = 0.05 * np.sign(np.sin(np.arange(256)))
    track = snr_track(y, samplerate=SAMPLERATE)
    window = 22050 // 256
    level = track.level[0, window]
    assert track.snr[0, window] == pytest.approx(level / track.noise[0, window])
    assert 20 < track.snr[0, window] < 60  # about 0.05 / 1e-3 in amplitude, not in dB


def test_dbscan_merges_jittery_detections_of_a_contact_into_one_event() -> None:
    samplerate = 100.0
    rng = np.random.default_rng(0)
    y = 0.01 * rng.standard_normal((2, 3000)) + 2.0  # a baseline offset is no event
    onsets = [500, 1500, 2400]
    ring = 0.5 * np.cos(np.pi * 0.8 * np.arange(30)) * np.exp(-np.arange(30) / 15)
    for onset in onsets:
        y[0, onset:] += 1.0  # pressure rises and stays: a staircase of contacts
        y[0, onset : onset + 30] += ring  # the vibration crosses the threshold on and off
        y[1, onset + 2 :] += 0.5
    detection = detect_dbscan(y, samplerate=samplerate)
    assert [event.onset for event in detection.events] == onsets
    assert all(event.channels == (0, 1) for event in detection.events)
    assert all(event.n_contacts == 1 for event in detection.events)


def test_dbscan_rejects_a_cutoff_above_nyquist() -> None:
    with pytest.raises(FeatureError, match="cutoff"):
        detect_dbscan(np.zeros((1, 1000)), samplerate=100.0, cutoff=60.0)


def test_none_gives_the_whole_file_or_whole_segments() -> None:
    y = np.zeros((3, 2500))
    (whole,) = detect_none(y, samplerate=1000.0).events
    assert (whole.onset, whole.offset, whole.channels) == (0, 2500, (0, 1, 2))
    detection = detect_none(y, samplerate=1000.0, segment=1.0)
    assert [(e.onset, e.offset) for e in detection.events] == [(0, 1000), (1000, 2000)]
    assert "last 0.5 s" in detection.warnings[0]
    with pytest.raises(FeatureError, match="shorter than one segment"):
        detect_none(y, samplerate=1000.0, segment=3.0)


def test_detect_events_validates_kind_options_and_segment() -> None:
    y = np.zeros((1, 44100))
    assert set(EVENT_KINDS) == {"snr", "dbscan", "none"}
    with pytest.raises(FeatureError, match="unknown event detection 'energy'"):
        detect_events("energy", y, samplerate=SAMPLERATE)
    with pytest.raises(FeatureError, match="unknown option 'eps' for events 'snr'"):
        detect_events("snr", y, samplerate=SAMPLERATE, options={"eps": 1})
    with pytest.raises(FeatureError, match="option 'threshold' of events 'snr'"):
        detect_events("snr", y, samplerate=SAMPLERATE, options={"threshold": "loud"})
    with pytest.raises(FeatureError, match="only applies to events 'none'"):
        detect_events("snr", y, samplerate=SAMPLERATE, segment=1.0)


def test_options_given_as_text_are_parsed() -> None:
    session = simulate_session(duration=4.0, n_touches=2, seed=5)
    strict = detect_events(
        "snr",
        session.recording.samples,
        samplerate=SAMPLERATE,
        options={"threshold": "1e6", "hangover": "0.2"},
    )
    assert strict.events == ()


def test_detectors_reject_nan_samples() -> None:
    y = np.zeros((1, 44100))
    y[0, 100] = np.nan
    for kind in ("snr", "dbscan"):
        with pytest.raises(FeatureError, match="NaN"):
            detect_events(kind, y, samplerate=SAMPLERATE)
