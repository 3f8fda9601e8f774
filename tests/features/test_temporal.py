from __future__ import annotations

import librosa
import numpy as np
import pytest

from tests.support.signals import sine, white_noise
from touchbench.features.framing import frame
from touchbench.features.temporal import peak_level, rms, zero_crossing_rate, zero_crossings

SAMPLERATE = 44100.0


def test_rms_of_a_sine_over_whole_periods_is_amplitude_over_root_two() -> None:
    y = sine(SAMPLERATE / 64, samplerate=SAMPLERATE, n_samples=1024, amplitude=0.5)
    assert np.allclose(rms(frame(y, frame_length=256, hop_length=256)), 0.5 / np.sqrt(2))


def test_rms_and_peak_of_silence_are_zero() -> None:
    frames = frame(np.zeros((2, 512)), frame_length=256, hop_length=128)
    assert np.array_equal(rms(frames), np.zeros((2, 3)))
    assert np.array_equal(peak_level(frames), np.zeros((2, 3)))
    assert np.array_equal(zero_crossings(frames), np.zeros((2, 3)))


def test_peak_level_is_the_largest_absolute_sample() -> None:
    y = np.zeros(8)
    y[2], y[6] = -0.7, 0.4
    assert np.array_equal(peak_level(frame(y, frame_length=4, hop_length=4)), [0.7, 0.4])


def test_zero_crossings_of_a_sine_count_two_per_period() -> None:
    # 10 periods in 2560 samples, phase shifted so that no sample is exactly 0.
    n = np.arange(2560)
    y = np.sin(2 * np.pi * 10 * n / 2560 + 0.1)
    assert zero_crossings(frame(y, frame_length=2560, hop_length=2560))[0] == 20


def test_rms_and_zcr_agree_with_librosa_on_white_noise() -> None:
    y = white_noise(44100, seed=3)
    frames = frame(y, frame_length=256, hop_length=128)
    expected_rms = librosa.feature.rms(y=y, frame_length=256, hop_length=128, center=False)[0]
    expected_zcr = librosa.feature.zero_crossing_rate(
        y, frame_length=256, hop_length=128, center=False
    )[0]
    # librosa returns float32: agreement to float32 precision.
    assert expected_rms.dtype == np.float32
    assert np.allclose(rms(frames), expected_rms, rtol=1e-6, atol=0)
    # Same definition (sign changes / frame length); librosa's 1e-10 threshold never
    # applies to these samples.
    assert np.array_equal(zero_crossing_rate(frames), expected_zcr)


@pytest.mark.parametrize("channels", [1, 3])
def test_features_keep_the_channel_axis_first(channels: int) -> None:
    y = np.stack([white_noise(1000, seed=s) for s in range(channels)])
    frames = frame(y, frame_length=100, hop_length=50)
    assert rms(frames).shape == (channels, 19)
    assert zero_crossing_rate(frames).shape == (channels, 19)
