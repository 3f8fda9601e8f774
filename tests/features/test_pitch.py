from __future__ import annotations

import numpy as np
import pytest

from tests.support.signals import sine, white_noise
from touchbench.features.errors import FeatureError
from touchbench.features.framing import fft_frequencies, frame, stft
from touchbench.features.pitch import pitch_autocorrelation, pitch_fft, pitch_wavelet

SAMPLERATE = 44100.0


def test_fft_pitch_of_a_sine_at_a_bin_centre_is_that_bin() -> None:
    frequency = 4 * SAMPLERATE / 256
    S = np.abs(
        stft(
            frame(
                sine(frequency, samplerate=SAMPLERATE, n_samples=2560),
                frame_length=256,
                hop_length=256,
            )
        )
    )
    frequencies = fft_frequencies(samplerate=SAMPLERATE, n_fft=256)
    assert np.array_equal(pitch_fft(S, frequencies=frequencies), np.full(10, frequency))


def test_fft_pitch_respects_the_search_range() -> None:
    S = np.zeros((5, 1))
    S[0], S[3] = 10.0, 1.0
    assert pitch_fft(S, frequencies=np.arange(5.0))[0] == 0.0
    assert pitch_fft(S, frequencies=np.arange(5.0), fmin=1.0)[0] == 3.0
    with pytest.raises(FeatureError, match="no frequency bin"):
        pitch_fft(S, frequencies=np.arange(5.0), fmin=10.0)


def test_autocorrelation_pitch_of_a_whole_lag_period_is_exact() -> None:
    rate = 22050.0
    frames = frame(
        sine(rate / 21, samplerate=rate, n_samples=1280), frame_length=128, hop_length=128
    )
    pitch = pitch_autocorrelation(frames, samplerate=rate, fmin=rate / 31, fmax=rate / 2)
    assert np.allclose(pitch, rate / 21)


def test_autocorrelation_pitch_below_the_range_is_fmin_and_silence_is_zero() -> None:
    rate = 22050.0
    low = frame(sine(200.0, samplerate=rate, n_samples=1280), frame_length=128, hop_length=128)
    silent = frame(np.zeros(256), frame_length=128, hop_length=128)
    kwargs = {"samplerate": rate, "fmin": rate / 31, "fmax": rate / 2}
    assert np.allclose(pitch_autocorrelation(low, **kwargs), rate / 31)
    assert np.array_equal(pitch_autocorrelation(silent, **kwargs), [0.0, 0.0])


def test_autocorrelation_range_must_fit_in_a_frame() -> None:
    frames = frame(np.ones(64), frame_length=32, hop_length=32)
    with pytest.raises(FeatureError, match="lags"):
        pitch_autocorrelation(frames, samplerate=22050, fmin=100.0, fmax=5000.0)


@pytest.mark.parametrize("frequency", [150.0, 440.0, 1000.0, 2500.0])
def test_wavelet_pitch_of_a_harmonic_tone_is_within_one_percent(frequency: float) -> None:
    n = 8192
    y = sine(frequency, samplerate=SAMPLERATE, n_samples=n) + 0.3 * sine(
        2 * frequency, samplerate=SAMPLERATE, n_samples=n
    )
    pitch = pitch_wavelet(frame(y, frame_length=2048, hop_length=2048), samplerate=SAMPLERATE)
    assert pitch.shape == (4,)
    assert np.allclose(pitch, frequency, rtol=0.01)


def test_wavelet_pitch_of_silence_is_zero() -> None:
    frames = frame(np.zeros((2, 4096)), frame_length=1024, hop_length=1024)
    assert np.array_equal(pitch_wavelet(frames, samplerate=SAMPLERATE), np.zeros((2, 4)))


def test_wavelet_pitch_never_exceeds_fmax() -> None:
    frames = frame(white_noise(16384, seed=2), frame_length=1024, hop_length=1024)
    assert np.all(pitch_wavelet(frames, samplerate=SAMPLERATE, fmax=3000.0) <= 3000.0)


def test_wavelet_pitch_checks_its_parameters() -> None:
    frames = frame(np.ones(64), frame_length=32, hop_length=32)
    with pytest.raises(FeatureError, match="fmax"):
        pitch_wavelet(frames, samplerate=8000, fmax=5000.0)
    with pytest.raises(FeatureError, match="threshold_ratio"):
        pitch_wavelet(frames, samplerate=8000, threshold_ratio=0.0)
