from __future__ import annotations

import numpy as np
import pytest

from tests.support.signals import sine
from touchbench.features.errors import FeatureError
from touchbench.features.framing import fft_frequencies, frame, frame_count, power_spectrogram, stft


def test_frame_is_a_strided_view_in_librosa_layout() -> None:
    y = np.arange(20.0).reshape(2, 10)
    frames = frame(y, frame_length=4, hop_length=3)
    assert frames.shape == (2, 4, 3)
    assert np.shares_memory(frames, y)
    for t in range(3):
        assert np.array_equal(frames[:, :, t], y[:, 3 * t : 3 * t + 4])
    assert frame_count(10, frame_length=4, hop_length=3) == 3


def test_frame_rejects_a_signal_shorter_than_one_frame() -> None:
    with pytest.raises(FeatureError, match="shorter than one window of 8"):
        frame(np.zeros(7), frame_length=8, hop_length=8)


def test_frame_rejects_nan_samples_with_their_index() -> None:
    y = np.zeros((2, 16))
    y[1, 5] = np.nan
    with pytest.raises(FeatureError, match=r"NaN or infinite sample at index \(1, 5\)"):
        frame(y, frame_length=4, hop_length=4)


def test_frame_rejects_bad_lengths() -> None:
    with pytest.raises(FeatureError, match="hop_length must be at least 1"):
        frame(np.zeros(16), frame_length=4, hop_length=0)


def test_stft_of_a_sine_at_a_bin_centre_peaks_at_that_bin() -> None:
    samplerate, n_fft = 8000.0, 256
    y = sine(10 * samplerate / n_fft, samplerate=samplerate, n_samples=2048)
    power = power_spectrogram(frame(y, frame_length=n_fft, hop_length=128), window="rectangular")
    assert power.shape == (n_fft // 2 + 1, 15)
    assert np.all(np.argmax(power, axis=0) == 10)
    # Rectangular window, whole periods: all the energy in bin 10, |X| = N / 2.
    assert np.allclose(power[10], (n_fft / 2) ** 2)
    assert np.allclose(np.delete(power, 10, axis=0), 0, atol=1e-12 * n_fft**2)


def test_stft_zero_pads_to_n_fft_and_checks_the_window() -> None:
    frames = frame(np.ones(64), frame_length=16, hop_length=16)
    assert stft(frames, n_fft=32).shape == (17, 4)
    with pytest.raises(FeatureError, match="window has shape"):
        stft(frames, window=np.ones(8))
    with pytest.raises(FeatureError, match="n_fft"):
        stft(frames, n_fft=8)


def test_fft_frequencies_are_bin_centres() -> None:
    frequencies = fft_frequencies(samplerate=44100, n_fft=256)
    assert frequencies.shape == (129,)
    assert frequencies[1] == pytest.approx(172.265625)
    assert frequencies[-1] == pytest.approx(22050)
    with pytest.raises(FeatureError, match="samplerate"):
        fft_frequencies(samplerate=0, n_fft=256)
