from __future__ import annotations

import librosa
import numpy as np
import pytest
from scipy.signal import find_peaks, peak_prominences

from tests.support.signals import sine, white_noise
from touchbench.features.errors import FeatureError
from touchbench.features.framing import fft_frequencies, frame, stft
from touchbench.features.spectral import (
    band_peak,
    spectral_centroid,
    spectral_flux,
    spectral_rolloff,
)

SAMPLERATE = 44100.0
N_FFT = 256
FREQUENCIES = fft_frequencies(samplerate=SAMPLERATE, n_fft=N_FFT)


def magnitude(y: np.ndarray, *, hop: int = 256, window: str = "hann") -> np.ndarray:
    return np.abs(stft(frame(y, frame_length=N_FFT, hop_length=hop), window=window))  # type: ignore[arg-type]


def test_centroid_of_a_sine_at_a_bin_centre_is_its_frequency() -> None:
    # Hann leakage is symmetric (bins k-1, k, k+1), so the centroid stays on bin k.
    frequency = 12 * SAMPLERATE / N_FFT
    S = magnitude(sine(frequency, samplerate=SAMPLERATE, n_samples=4096))
    assert np.allclose(spectral_centroid(S, frequencies=FREQUENCIES), frequency)


def test_centroid_of_white_noise_is_near_a_quarter_of_the_rate() -> None:
    S = magnitude(white_noise(44100 * 2, seed=5))
    centroid = spectral_centroid(S, frequencies=FREQUENCIES).mean()
    assert centroid == pytest.approx(SAMPLERATE / 4, rel=0.02)


def test_centroid_rolloff_and_flux_of_silence_are_zero() -> None:
    S = magnitude(np.zeros(1024))
    assert np.array_equal(spectral_centroid(S, frequencies=FREQUENCIES), np.zeros(4))
    assert np.array_equal(spectral_rolloff(S, frequencies=FREQUENCIES), np.zeros(4))
    assert np.array_equal(spectral_flux(S), np.zeros(4))


def test_rolloff_of_a_sine_is_the_bin_where_95_percent_of_energy_is_reached() -> None:
    frequency = 20 * SAMPLERATE / N_FFT
    S = magnitude(sine(frequency, samplerate=SAMPLERATE, n_samples=2048)) ** 2
    # Hann power in bins 19, 20, 21 is 1/16, 1/4, 1/16 of ... (1/6, 2/3, 1/6 of the total):
    # 83 % is reached at bin 20, 100 % at bin 21.
    assert np.allclose(spectral_rolloff(S, frequencies=FREQUENCIES), 21 * SAMPLERATE / N_FFT)
    assert np.allclose(spectral_rolloff(S, frequencies=FREQUENCIES, roll_percent=0.8), frequency)


def test_centroid_and_rolloff_agree_with_librosa_on_the_same_frames() -> None:
    y = white_noise(22050, seed=7) + sine(3000, samplerate=SAMPLERATE, n_samples=22050)
    S = magnitude(y, hop=128)
    expected_centroid = librosa.feature.spectral_centroid(
        y=y, sr=SAMPLERATE, n_fft=N_FFT, hop_length=128, center=False
    )[0]
    # librosa's roll-off on the power spectrogram, 95 %: the same definition.
    expected_rolloff = librosa.feature.spectral_rolloff(
        S=S**2, sr=SAMPLERATE, n_fft=N_FFT, roll_percent=0.95
    )[0]
    assert np.allclose(spectral_centroid(S, frequencies=FREQUENCIES), expected_centroid, rtol=1e-9)
    assert np.array_equal(
        spectral_rolloff(S**2, frequencies=FREQUENCIES, roll_percent=0.95), expected_rolloff
    )


def test_flux_is_zero_for_a_steady_spectrum_and_root_two_for_disjoint_ones() -> None:
    steady = np.ones((5, 4))
    assert np.allclose(spectral_flux(steady)[1:], 0)
    assert spectral_flux(steady)[0] == pytest.approx(1.0)  # against silence before
    disjoint = np.array([[1.0, 0.0], [0.0, 3.0]])
    assert spectral_flux(disjoint)[1] == pytest.approx(np.sqrt(2))
    assert np.allclose(spectral_flux(disjoint, previous=disjoint), 0)


def test_flux_rejects_a_previous_spectrum_of_another_shape() -> None:
    with pytest.raises(FeatureError, match="previous has shape"):
        spectral_flux(np.ones((5, 4)), previous=np.ones((5, 3)))


def test_band_peak_matches_scipy_peak_prominences() -> None:
    frequencies = np.arange(0.0, 1601.0)
    rng = np.random.default_rng(0)
    spectrum = np.abs(rng.standard_normal((3, frequencies.size))) * 0.1
    spectrum[:, 60] += [5.0, 2.0, 1.0]
    spectrum[:, 530] += 3.0
    frequency, prominence = band_peak(spectrum, frequencies=frequencies, band=(0.0, 120.0))
    assert np.array_equal(frequency, [60.0, 60.0, 60.0])
    for row, value in zip(spectrum, prominence, strict=True):
        assert value == pytest.approx(peak_prominences(row, [60])[0][0])
    frequency, _ = band_peak(spectrum, frequencies=frequencies, band=(500.0, 550.0))
    assert np.array_equal(frequency, [530.0, 530.0, 530.0])


def test_band_peak_picks_the_highest_local_maximum_in_the_band() -> None:
    frequencies = np.arange(10.0)
    spectrum = np.array([0.0, 1.0, 0.0, 4.0, 0.0, 2.0, 0.0, 9.0, 8.0, 9.5])
    peaks, _ = find_peaks(spectrum)
    assert list(peaks) == [1, 3, 5, 7]
    frequency, prominence = band_peak(spectrum, frequencies=frequencies, band=(0.0, 6.0))
    assert frequency == 3.0 and prominence == pytest.approx(4.0)


def test_band_without_a_local_maximum_gives_its_largest_bin_and_zero_prominence() -> None:
    frequencies = np.arange(10.0)
    spectrum = np.arange(10.0)
    frequency, prominence = band_peak(spectrum, frequencies=frequencies, band=(2.0, 5.0))
    assert (frequency, prominence) == (5.0, 0.0)


def test_band_outside_the_spectrum_is_an_error() -> None:
    with pytest.raises(FeatureError, match=r"band \[2000, 3000\] Hz holds no frequency bin"):
        band_peak(np.ones(11), frequencies=np.arange(11.0) * 100, band=(2000.0, 3000.0))


def test_frequencies_must_match_the_bins() -> None:
    with pytest.raises(FeatureError, match="frequencies must have shape"):
        spectral_centroid(np.ones((5, 3)), frequencies=np.arange(4.0))
