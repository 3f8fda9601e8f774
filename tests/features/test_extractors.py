from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tests.support.signals import sine
from touchbench.drivers.simulated import SimulatedTouch, simulate_session
from touchbench.features.errors import FeatureError
from touchbench.features.events import EVENT_KINDS, Detection, Event, detect_events, detect_snr
from touchbench.features.extractors import EXTRACTORS, make_extractor, uc3m_feature_names
from touchbench.features.extractors.uc3m_audio import CHANNEL_FEATURES

SAMPLERATE = 44100.0
WINDOW_MS = 1000 * 256 / SAMPLERATE


def _arff_attribute_names(path: Path) -> list[str]:
    names = []
    for line in path.read_text().splitlines():
        if line.lower().startswith("@data"):
            break
        if line.lower().startswith("@attribute"):
            rest = line.split(None, 1)[1]
            name = rest[1 : rest.index("'", 1)] if rest.startswith("'") else rest.split()[0]
            names.append(name)
    return names


@pytest.mark.shared
@pytest.mark.parametrize("robot", ["mini", "maggie"])
def test_uc3m_names_equal_the_published_arff_header(shared_datasets: Path, robot: str) -> None:
    header = _arff_attribute_names(
        shared_datasets / "uc3m-touch" / robot / "gesture_and_place.arff"
    )
    assert header[:2] == ["gesture", "place"]
    assert uc3m_feature_names(3) == header[2:]
    assert make_extractor("uc3m-audio").feature_names(3) == header[2:]


def test_uc3m_names_generalise_to_any_channel_count() -> None:
    assert len(CHANNEL_FEATURES) == 33
    names = uc3m_feature_names(5)
    assert len(names) == 165 and names[0] == "pitchFFT_1" and names[-1] == "duration_5"
    assert names[33 * 4 + 30] == "ZCRmax - ZCRmin_5"


def _single_tap(frequency: float, channels: tuple[int, ...]) -> np.ndarray:
    """3 channels of faint noise with a tone burst of 6 whole windows on ``channels``."""
    rng = np.random.default_rng(0)
    y = 1e-5 * rng.standard_normal((3, int(3 * SAMPLERATE)))
    start = 172 * 256  # a window boundary near 1 s
    burst = sine(frequency, samplerate=SAMPLERATE, n_samples=6 * 256, amplitude=0.2)
    for channel in channels:
        y[channel, start : start + burst.size] += burst
    return y


def test_uc3m_values_follow_the_published_units() -> None:
    frequency = 8 * SAMPLERATE / 256  # 1378.1 Hz, a bin centre
    y = _single_tap(frequency, channels=(0, 1))
    extractor = make_extractor("uc3m-audio")
    instances = extractor.extract(
        y, samplerate=SAMPLERATE, detection=detect_snr(y, samplerate=SAMPLERATE)
    )
    assert instances.values.shape == (1, 99)
    row = dict(zip(extractor.feature_names(3), instances.values[0], strict=True))
    for channel in (1, 2):
        assert row[f"pitchFFT_{channel}"] == pytest.approx(frequency)
        assert row[f"pitchFFTDif_{channel}"] == 0.0
        # 22050 Hz / lag 16 = 1378.1 Hz: the autocorrelation finds the same tone.
        assert row[f"pitchAutocorrelation_{channel}"] == pytest.approx(22050 / 16)
        assert row[f"centroide_{channel}"] == pytest.approx(frequency, rel=0.01)
        assert row[f"rollOff_{channel}"] == pytest.approx(frequency + SAMPLERATE / 256)
        assert row[f"SNR_{channel}"] >= 10 and row[f"SNRMax_{channel}"] >= row[f"SNR_{channel}"]
        assert row[f"ganancia_{channel}"] == pytest.approx(0.2 / np.sqrt(2), rel=1e-3)
        assert 0 <= row[f"fluxMin_{channel}"] <= row[f"fluxMax_{channel}"] <= np.sqrt(2)
        # Two zero crossings per period: 2 * 1378 Hz * 256 / 44100 = 16 per window, the
        # one at a window's first sample (sin 0) counted in no window.
        assert 15 <= row[f"ZCRmin_{channel}"] <= row[f"ZCRmax_{channel}"] <= 16
        assert row[f"pitchWavelet_{channel}"] == 0.0
        assert row[f"numWordsMinute_{channel}"] == 0.0
        # Whole windows in ms: the burst's 6 windows plus an 86-window hangover.
        assert row[f"duration_{channel}"] == pytest.approx(92 * WINDOW_MS)
    # The third microphone heard nothing: 33 zeros.
    assert all(row[name] == 0.0 for name in uc3m_feature_names(3)[66:])
    assert instances.meta[0]["channels"] == [0, 1]


def test_uc3m_shortest_touch_lasts_87_windows_as_in_the_mini_data() -> None:
    y = 1e-3 * np.random.default_rng(1).standard_normal((1, int(2 * SAMPLERATE)))
    y[0, 44100 : 44100 + 100] += 0.3  # shorter than a window, inside one window
    extractor = make_extractor("uc3m-audio")
    instances = extractor.extract(
        y, samplerate=SAMPLERATE, detection=detect_snr(y, samplerate=SAMPLERATE)
    )
    duration = dict(zip(extractor.feature_names(1), instances.values[0], strict=True))["duration_1"]
    assert duration == pytest.approx(87 * WINDOW_MS)  # 505.034 ms, the Mini minimum


def test_uc3m_wavelet_pitch_option_fills_the_wavelet_columns() -> None:
    y = _single_tap(1000.0, channels=(0,))
    detection = detect_snr(y, samplerate=SAMPLERATE)
    extractor = make_extractor("uc3m-audio", {"wavelet_pitch": "true"})
    row = dict(
        zip(
            extractor.feature_names(3),
            extractor.extract(y, samplerate=SAMPLERATE, detection=detection).values[0],
            strict=True,
        )
    )
    assert row["pitchWavelet_1"] == pytest.approx(1000.0, rel=0.05)


def test_uc3m_works_with_events_from_another_detector() -> None:
    y = _single_tap(1000.0, channels=(2,))
    detection = detect_events("none", y, samplerate=SAMPLERATE)
    extractor = make_extractor("uc3m-audio")
    values = extractor.extract(y, samplerate=SAMPLERATE, detection=detection).values
    assert values.shape == (1, 99)
    assert not values[0, :66].any() and values[0, 66] > 0


def test_uc3m_rejects_other_sample_rates() -> None:
    with pytest.raises(FeatureError, match="needs a sample rate of 44100 Hz, got 48000 Hz"):
        make_extractor("uc3m-audio").check_input(samplerate=48000.0, n_channels=3)


def test_band_peaks_finds_theta_and_the_peaks_in_each_band() -> None:
    samplerate = 3200.0
    n = int(3 * samplerate)
    t = np.arange(n) / samplerate
    vertical = 1.0 * np.sin(2 * np.pi * 60 * t) + 0.5 * np.sin(2 * np.pi * 520 * t)
    vertical += 0.3 * np.sin(2 * np.pi * 900 * t)
    horizontal = 1.0 * np.sin(2 * np.pi * 30 * t)
    y = np.stack([horizontal, np.zeros(n), vertical])
    extractor = make_extractor("band-peaks")
    extractor.check_input(samplerate=samplerate, n_channels=3)
    detection = detect_events("none", y, samplerate=samplerate, segment=1.0)
    instances = extractor.extract(y, samplerate=samplerate, detection=detection)
    names = extractor.feature_names(3)
    assert names == [
        "theta",
        "peakFrequency_0_120",
        "peakProminence_0_120",
        "peakFrequency_500_550",
        "peakProminence_500_550",
        "peakFrequency_825_925",
        "peakProminence_825_925",
    ]
    assert instances.values.shape == (3, 7)
    expected_theta = np.arctan(np.sqrt(0.5 + 0.125 + 0.045) / np.sqrt(0.5))
    assert np.allclose(instances.values[:, 0], expected_theta, rtol=1e-3)
    assert np.allclose(instances.values[:, [1, 3, 5]], [60.0, 520.0, 900.0])
    # Amplitude spectrum: a bin-centred sinusoid of amplitude A has a peak of A.
    assert np.allclose(instances.values[:, [2, 4, 6]], [1.0, 0.5, 0.3], atol=0.02)


def test_band_peaks_needs_a_rate_that_covers_its_bands_and_two_channels() -> None:
    extractor = make_extractor("band-peaks")
    with pytest.raises(FeatureError, match="at least 1850 Hz"):
        extractor.check_input(samplerate=1000.0, n_channels=3)
    with pytest.raises(FeatureError, match="at least 2 channels"):
        extractor.check_input(samplerate=3200.0, n_channels=1)
    custom = make_extractor("band-peaks", {"bands": "10-20,30-40", "vertical": "1"})
    assert custom.feature_names(2)[1:3] == ["peakFrequency_10_20", "peakProminence_10_20"]
    with pytest.raises(FeatureError, match="option 'bands'"):
        make_extractor("band-peaks", {"bands": "20-10"})


def test_mfcc_summarises_98_frames_per_second_and_keeps_the_sequence() -> None:
    samplerate = 16000.0
    rng = np.random.default_rng(0)
    y = 0.1 * rng.standard_normal((2, int(2 * samplerate)))
    extractor = make_extractor("mfcc")
    detection = detect_events("none", y, samplerate=samplerate, segment=1.0)
    instances = extractor.extract(y, samplerate=samplerate, detection=detection)
    names = extractor.feature_names(2)
    assert len(names) == 56 and names[:2] == ["mfcc1_mean_1", "mfcc2_mean_1"]
    assert names[14] == "mfcc1_std_1" and names[28] == "mfcc1_mean_2"
    assert instances.values.shape == (2, 56)
    frames = np.array(instances.meta[0]["frames"])
    assert frames.shape == (98, 28)
    assert np.allclose(instances.values[0, :14], frames[:, :14].mean(axis=0))
    assert np.allclose(instances.values[0, 14:28], frames[:, :14].std(axis=0))
    assert np.allclose(instances.values[0, 28:42], frames[:, 14:].mean(axis=0))


def test_taxel_dft_gives_one_instance_per_window_with_real_parts_of_bins_4_to_31() -> None:
    rng = np.random.default_rng(0)
    y = rng.standard_normal((2, 200))
    extractor = make_extractor("taxel-dft", samplerate=1000.0)
    instances = extractor.extract(
        y, samplerate=1000.0, detection=detect_events("none", y, samplerate=1000.0)
    )
    assert extractor.feature_names(2)[:2] == ["dft4_1", "dft5_1"]
    assert extractor.feature_names(2)[27:29] == ["dft31_1", "dft4_2"]
    n_windows = 1 + (200 - 64) // 8
    assert instances.values.shape == (n_windows, 56)
    third = np.fft.fft(y[:, 16:80], axis=1).real[:, 4:32]
    assert np.allclose(instances.values[2], third.reshape(-1))
    assert list(instances.spans[2]) == [16, 80]


def test_window_subtracts_the_mean_of_the_samples_before_the_onset() -> None:
    y = np.arange(100.0)[np.newaxis, :].repeat(2, axis=0)
    y[1] *= 2
    detection = Detection(events=(Event(10, 40, (0, 1)), Event(0, 30, (0,)), Event(90, 100, (0,))))
    extractor = make_extractor("window")
    instances = extractor.extract(y, samplerate=100.0, detection=detection)
    assert instances.values.shape == (2, 50)
    # Onset 10: baseline mean(7, 8, 9) = 8, so channel 1 gives 2, 3, ...; channel 2 twice.
    assert np.allclose(instances.values[0, :25], np.arange(25) + 2)
    assert np.allclose(instances.values[0, 25:], 2 * (np.arange(25) + 2))
    # Onset 0 has no samples before it: it is its own baseline.
    assert np.allclose(instances.values[1, :25], np.arange(25))
    assert "fewer than 25 samples" in instances.warnings[0]


def test_registry_describes_every_extractor() -> None:
    assert set(EXTRACTORS) == {
        "uc3m-audio",
        "band-peaks",
        "mfcc",
        "taxel-dft",
        "window",
        "sequence",
    }
    for name, extractor_class in EXTRACTORS.items():
        extractor = make_extractor(name, samplerate=44100.0)
        assert extractor.name == name and extractor_class.description
        assert extractor.default_events in EVENT_KINDS
        assert len(extractor.feature_names(2)) == len(set(extractor.feature_names(2)))
        assert extractor.min_samples(44100.0) >= 1


def test_unknown_extractor_or_option_is_a_clear_error() -> None:
    with pytest.raises(FeatureError, match="unknown extractor 'mfc' \\(known: uc3m-audio"):
        make_extractor("mfc")
    with pytest.raises(FeatureError, match="unknown option 'n' for extractor 'window'"):
        make_extractor("window", {"n": 3})


@pytest.mark.parametrize("name", sorted(EXTRACTORS))
def test_every_extractor_makes_named_finite_rows_from_a_simulated_session(name: str) -> None:
    extractor = make_extractor(name, samplerate=44100.0)
    session = simulate_session(
        duration=3.0,
        samplerate=44100.0,
        n_channels=3,
        seed=3,
        touches=[SimulatedTouch(1.0, 0.3, (0, 2), "stroke", 0.3)],
    )
    y = session.recording.samples
    samplerate = 44100.0
    segment = extractor.default_segment if extractor.default_events == "none" else None
    detection = detect_events(extractor.default_events, y, samplerate=samplerate, segment=segment)
    instances = extractor.extract(y, samplerate=samplerate, detection=detection)
    assert instances.values.shape[1] == len(extractor.feature_names(3))
    assert instances.values.shape[0] >= 1 and np.isfinite(instances.values).all()
    assert instances.spans.shape == (instances.values.shape[0], 2)
    assert len(instances.meta) == instances.values.shape[0]
