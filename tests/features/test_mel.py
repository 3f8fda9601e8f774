from __future__ import annotations

import librosa
import numpy as np
import pytest

from tests.support.signals import sine, white_noise
from touchbench.features.errors import FeatureError
from touchbench.features.framing import frame, power_spectrogram
from touchbench.features.mel import hz_to_mel, mel_filter_bank, mel_spectrogram, mel_to_hz, mfcc

SAMPLERATE = 16000.0
FRAME, HOP = 480, 160  # 30 ms and 10 ms at 16 kHz


def test_mel_scale_is_htk() -> None:
    assert hz_to_mel(700.0) == pytest.approx(2595 * np.log10(2))
    assert hz_to_mel(1000.0) == pytest.approx(999.9855, abs=1e-3)
    assert np.allclose(mel_to_hz(hz_to_mel(np.array([0.0, 440.0, 8000.0]))), [0, 440, 8000])


def test_filter_bank_equals_librosa_htk_slaney_norm() -> None:
    ours = mel_filter_bank(samplerate=SAMPLERATE, n_fft=FRAME, n_mels=40)
    theirs = librosa.filters.mel(sr=SAMPLERATE, n_fft=FRAME, n_mels=40, htk=True)
    assert ours.shape == (40, FRAME // 2 + 1)
    assert np.allclose(ours, theirs, rtol=1e-5, atol=1e-8)


def test_unnormalised_triangles_peak_at_one() -> None:
    bank = mel_filter_bank(samplerate=SAMPLERATE, n_fft=4096, n_mels=10, normalize=False)
    assert np.all(bank.max(axis=1) > 0.95) and bank.max() <= 1.0


@pytest.mark.slow
def test_mfcc_agrees_with_librosa_under_identical_parameters() -> None:
    y = white_noise(16000, seed=4) * 0.1 + sine(440, samplerate=SAMPLERATE, n_samples=16000)
    power = power_spectrogram(frame(y, frame_length=FRAME, hop_length=HOP), window="hann")
    bank = mel_filter_bank(samplerate=SAMPLERATE, n_fft=FRAME, n_mels=40)
    ours = mfcc(mel_spectrogram(power, filter_bank=bank), n_mfcc=14)
    mel = librosa.feature.melspectrogram(
        y=y,
        sr=SAMPLERATE,
        n_fft=FRAME,
        hop_length=HOP,
        center=False,
        n_mels=40,
        htk=True,
        power=2.0,
    )
    # librosa's default top_db=80 clips the log energies; ours does not, so it is off here.
    theirs = librosa.feature.mfcc(S=librosa.power_to_db(mel, top_db=None), n_mfcc=14)
    assert ours.shape == (14, 98)  # 98 frames of 30 ms with a 10 ms hop in 1 s
    # Tolerance: the filter banks agree to float32 precision (librosa builds them in
    # float32), about 1e-4 dB on each coefficient.
    assert np.allclose(ours, theirs, atol=1e-3)


def test_mfcc_of_silence_is_the_floor_only() -> None:
    energies = np.zeros((40, 3))
    coefficients = mfcc(energies, n_mfcc=14)
    assert coefficients[0] == pytest.approx(np.full(3, -100.0 * np.sqrt(40)))
    assert np.allclose(coefficients[1:], 0)


def test_mfcc_cannot_keep_more_coefficients_than_bands() -> None:
    with pytest.raises(FeatureError, match="cannot exceed the number of mel bands"):
        mfcc(np.ones((10, 2)), n_mfcc=14)


def test_filter_bank_range_is_checked() -> None:
    with pytest.raises(FeatureError, match="mel range"):
        mel_filter_bank(samplerate=8000, n_fft=256, fmax=6000.0)
