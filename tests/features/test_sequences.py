"""Sequence instances: the ``sequence`` extractor, ``mfcc`` with ``frames``, resampling."""

from __future__ import annotations

import numpy as np
import pytest

from touchbench.benchmark.sequence import find_sequence
from touchbench.features.errors import FeatureError
from touchbench.features.events import Detection, Event, detect_events
from touchbench.features.extractors import make_extractor
from touchbench.features.resample import to_length


def test_to_length_averages_down_and_interpolates_up() -> None:
    x = np.arange(10.0)
    assert to_length(x, 3).tolist() == [1.0, 4.0, 7.5]  # means of 0-2, 3-5, 6-9
    assert np.array_equal(to_length(x, 10), x)
    assert np.allclose(to_length(np.array([0.0, 2.0]), 5), [0.0, 0.5, 1.0, 1.5, 2.0])
    assert np.allclose(to_length(np.array([3.0]), 4), 3.0)
    both = to_length(np.stack([x, 2 * x]), 5)
    assert both.shape == (2, 5) and np.allclose(both[1], 2 * both[0])


def test_sequence_keeps_length_samples_from_the_onset_minus_the_baseline() -> None:
    y = np.arange(100.0)[np.newaxis, :].repeat(2, axis=0)
    y[1] *= 2
    detection = Detection(events=(Event(10, 12, (0, 1)), Event(95, 100, (0,))))
    extractor = make_extractor("sequence", {"length": 20, "baseline": 3})
    instances = extractor.extract(y, samplerate=100.0, detection=detection)
    assert instances.values.shape == (1, 40)
    # onset 10, baseline mean(7, 8, 9) = 8: channel 1 is 2 ... 21, channel 2 twice that,
    # read past the event's own end (sample 12)
    assert np.allclose(instances.values[0, :20], np.arange(20) + 2)
    assert np.allclose(instances.values[0, 20:], 2 * (np.arange(20) + 2))
    assert "fewer than 20 samples" in instances.warnings[0]
    plain = make_extractor("sequence", {"length": 20})  # baseline 0: nothing subtracted
    values = plain.extract(y, samplerate=100.0, detection=detection).values
    assert np.allclose(values[0, :20], np.arange(10, 30))


def test_sequence_resamples_each_whole_event_to_length_steps() -> None:
    y = np.vstack([np.arange(1000.0), np.ones(1000)])
    detection = Detection(events=(Event(100, 500, (0,)), Event(600, 605, (1,))))
    extractor = make_extractor("sequence", {"length": 8, "resample": "true", "baseline": 2})
    instances = extractor.extract(y, samplerate=1000.0, detection=detection)
    assert instances.values.shape == (2, 16)
    long_event = instances.values[0].reshape(2, 8)
    # 400 samples in 8 bins of 50, minus the mean of samples 98 and 99
    assert np.allclose(long_event[0], np.arange(100, 500).reshape(8, 50).mean(axis=1) - 98.5)
    assert np.allclose(long_event[1], 0.0)
    short_event = instances.values[1].reshape(2, 8)  # 5 samples stretched to 8
    assert np.allclose(short_event[0], np.linspace(600, 604, 8) - 598.5)
    assert instances.spans.tolist() == [[100, 500], [600, 605]]


def test_sequence_names_give_back_the_window_shape() -> None:
    extractor = make_extractor("sequence", {"length": 32})
    names = extractor.feature_names(3)
    assert names[:2] == ["ch1[0]", "ch1[1]"] and names[32] == "ch2[0]" and len(names) == 96
    layout, note = find_sequence(names)
    assert note is None and layout is not None
    assert (layout.start, layout.channels, layout.length) == (0, ("ch1", "ch2", "ch3"), 32)


def test_mfcc_frames_keeps_the_coefficient_tracks_as_a_sequence() -> None:
    samplerate = 16000.0
    rng = np.random.default_rng(0)
    y = 0.1 * rng.standard_normal((2, int(2 * samplerate)))
    detection = detect_events("none", y, samplerate=samplerate, segment=1.0)
    summary = make_extractor("mfcc").extract(y, samplerate=samplerate, detection=detection)
    frames = np.array(summary.meta[0]["frames"])  # (98 frames, 14 coefficients x 2 channels)
    extractor = make_extractor("mfcc", {"frames": 98})
    instances = extractor.extract(y, samplerate=samplerate, detection=detection)
    names = extractor.feature_names(2)
    assert names[:2] == ["mfcc1_1[0]", "mfcc1_1[1]"] and names[98] == "mfcc2_1[0]"
    assert names[14 * 98] == "mfcc1_2[0]" and len(names) == 2 * 14 * 98
    assert instances.values.shape == (2, 2 * 14 * 98)
    tracks = instances.values[0].reshape(28, 98)
    assert np.allclose(tracks, frames.T)  # 98 frames in 1 s: kept as they are
    layout, _ = find_sequence(names)
    assert layout is not None and (layout.n_channels, layout.length) == (28, 98)
    shorter = make_extractor("mfcc", {"frames": 10}).extract(
        y, samplerate=samplerate, detection=detection
    )
    assert np.allclose(shorter.values[0].reshape(28, 10), to_length(frames.T, 10))


def test_bad_sequence_options_are_one_clear_error() -> None:
    with pytest.raises(FeatureError, match="option 'baseline' of extractor 'sequence'"):
        make_extractor("sequence", {"baseline": -1})
    with pytest.raises(FeatureError, match="option 'resample' of extractor 'sequence'"):
        make_extractor("sequence", {"resample": "maybe"})
    with pytest.raises(FeatureError, match="option 'frames' of extractor 'mfcc'"):
        make_extractor("mfcc", {"frames": 0})
