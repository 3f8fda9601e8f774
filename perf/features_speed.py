"""Speed of the extractors (real-time factor) and of our spectral features against librosa.

Run from the repository root::

    .venv/bin/python perf/features_speed.py [--seconds 60] [--repeats 5]

Everything runs on one core (BLAS/OpenMP threads pinned to 1 before numpy loads).  Part
1 times each extractor's whole path from samples to instances (event detection
included) on a synthetic session shaped like its sensor, on one array and streamed
block by block (what ``extract`` and ``live`` do), and prints the real-time factor,
seconds of signal per second of computing (goal for ``uc3m-audio`` on 3-channel 44.1 kHz
audio: at least 1000).  Part 2 computes the same spectral features on the same
frames with touchbench and with librosa in the same run, checks that they agree, and
prints librosa's time over ours (above 1: touchbench is faster).  Best of ``repeats``
runs each.  Not a test: nothing is asserted.
"""

from __future__ import annotations

import os

for _variable in (
    "OMP_NUM_THREADS",
    "OPENBLAS_NUM_THREADS",
    "MKL_NUM_THREADS",
    "NUMBA_NUM_THREADS",
):
    os.environ[_variable] = "1"

import argparse  # noqa: E402
import time  # noqa: E402
from collections.abc import Callable  # noqa: E402
from importlib.metadata import version  # noqa: E402
from typing import Any  # noqa: E402

import librosa  # noqa: E402
import numpy as np  # noqa: E402

from touchbench.drivers.simulated import simulate_session  # noqa: E402
from touchbench.features.events import detect_events  # noqa: E402
from touchbench.features.extractors import make_extractor  # noqa: E402
from touchbench.features.framing import fft_frequencies, frame, power_spectrogram, stft  # noqa: E402
from touchbench.features.mel import mel_filter_bank, mel_spectrogram, mfcc  # noqa: E402
from touchbench.features.recipe import Recipe  # noqa: E402
from touchbench.features.spectral import spectral_centroid, spectral_rolloff  # noqa: E402
from touchbench.features.temporal import rms, zero_crossing_rate  # noqa: E402

#: extractor -> (channels, sample rate, touches per minute, segment seconds for "none")
SENSORS: dict[str, tuple[int, float, int, float | None]] = {
    "uc3m-audio": (3, 44100.0, 24, None),
    "band-peaks": (3, 3200.0, 0, 1.0),
    "mfcc": (1, 16000.0, 0, 1.0),
    "taxel-dft": (16, 1000.0, 0, None),
    "window": (4, 100.0, 20, None),
}


def best_time(function: Callable[[], Any], repeats: int) -> float:
    function()  # warm-up (imports, caches, numba compilation in librosa)
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return min(times)


def extractor_speed(name: str, seconds: float, repeats: int) -> tuple[float, float, int]:
    n_channels, samplerate, touches_per_minute, segment = SENSORS[name]
    session = simulate_session(
        duration=seconds,
        samplerate=samplerate,
        n_channels=n_channels,
        n_touches=int(touches_per_minute * seconds / 60),
        min_gap=1.0,
        seed=0,
    )
    y = session.recording.samples
    extractor = make_extractor(name, samplerate=samplerate)
    kind = extractor.default_events

    def run() -> int:
        detection = detect_events(kind, y, samplerate=samplerate, segment=segment)
        return extractor.extract(y, samplerate=samplerate, detection=detection).values.shape[0]

    recipe = Recipe.resolve(name, segment=segment)

    def streamed() -> int:
        stream = recipe.open(samplerate=samplerate, n_channels=n_channels)
        count = 0
        for start in range(0, y.shape[1], 65536):
            count += stream.feed(y[:, start : start + 65536]).values.shape[0]
        return count + stream.finish().values.shape[0]

    whole, flowing = best_time(run, repeats), best_time(streamed, repeats)
    count = run()
    if streamed() != count:
        raise SystemExit(f"{name}: streaming found another number of instances")
    return seconds / whole, seconds / flowing, count


def spectral_comparison(seconds: float, repeats: int) -> list[tuple[str, float, float]]:
    samplerate, n_fft = 44100.0, 256
    y = simulate_session(duration=seconds, samplerate=samplerate, n_channels=3, seed=1)
    y_samples = y.recording.samples
    frequencies = fft_frequencies(samplerate=samplerate, n_fft=n_fft)

    def ours() -> dict[str, np.ndarray]:
        frames = frame(y_samples, frame_length=n_fft, hop_length=n_fft)
        magnitude = np.abs(stft(frames, window="hann"))
        return {
            "centroid": spectral_centroid(magnitude, frequencies=frequencies),
            "rolloff": spectral_rolloff(magnitude**2, frequencies=frequencies),
            "rms": rms(frames),
            "zcr": zero_crossing_rate(frames),
        }

    def theirs() -> dict[str, np.ndarray]:
        magnitude = np.abs(
            librosa.stft(y_samples, n_fft=n_fft, hop_length=n_fft, center=False, window="hann")
        )
        return {
            "centroid": librosa.feature.spectral_centroid(S=magnitude, sr=samplerate)[:, 0],
            "rolloff": librosa.feature.spectral_rolloff(
                S=magnitude**2, sr=samplerate, roll_percent=0.95
            )[:, 0],
            "rms": librosa.feature.rms(
                y=y_samples, frame_length=n_fft, hop_length=n_fft, center=False
            )[:, 0],
            "zcr": librosa.feature.zero_crossing_rate(
                y_samples, frame_length=n_fft, hop_length=n_fft, center=False
            )[:, 0],
        }

    mine, reference = ours(), theirs()
    for key in mine:
        # librosa computes in float32 here; agreement to float32 precision.
        if not np.allclose(mine[key], reference[key], rtol=1e-4, atol=1e-6):
            raise SystemExit(f"{key}: touchbench and librosa disagree")
    rows = [
        (
            "centroid+rolloff+rms+zcr, 3 x 44.1 kHz, 256/256",
            best_time(ours, repeats),
            best_time(theirs, repeats),
        )
    ]

    speech = simulate_session(duration=seconds, samplerate=16000.0, n_channels=1, seed=2)
    x = speech.recording.samples[0]
    bank = mel_filter_bank(samplerate=16000.0, n_fft=480, n_mels=40)

    def our_mfcc() -> np.ndarray:
        power = power_spectrogram(frame(x, frame_length=480, hop_length=160), window="hann")
        return mfcc(mel_spectrogram(power, filter_bank=bank), n_mfcc=14)

    def their_mfcc() -> np.ndarray:
        mel = librosa.feature.melspectrogram(
            y=x, sr=16000, n_fft=480, hop_length=160, center=False, n_mels=40, htk=True
        )
        return librosa.feature.mfcc(S=librosa.power_to_db(mel, top_db=None), n_mfcc=14)

    if not np.allclose(our_mfcc(), their_mfcc(), atol=1e-2):
        raise SystemExit("mfcc: touchbench and librosa disagree")
    rows.append(
        (
            "mfcc 14/40, 1 x 16 kHz, 30 ms/10 ms",
            best_time(our_mfcc, repeats),
            best_time(their_mfcc, repeats),
        )
    )
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=60.0, help="signal length")
    parser.add_argument("--repeats", type=int, default=5, help="timed runs (best is kept)")
    arguments = parser.parse_args()
    load = ", ".join(f"{value:.1f}" for value in os.getloadavg())
    print(f"Machine load average (1, 5, 15 min): {load} on {os.cpu_count()} cores")
    print(f"Real-time factor, one core, {arguments.seconds:g} s synthetic sessions")
    print("(whole: one array, as before; streamed: 65536-sample blocks through the engine)")
    header = f"{'extractor':<12} {'sensor':<22} {'instances':>9} {'whole x rt':>11}"
    print(f"{header} {'streamed x rt':>14}")
    for name, (channels, rate, _, _) in SENSORS.items():
        whole, flowing, count = extractor_speed(name, arguments.seconds, arguments.repeats)
        sensor = f"{channels} ch x {rate:g} Hz"
        print(f"{name:<12} {sensor:<22} {count:>9} {whole:>11.0f} {flowing:>14.0f}")
    print()
    print(f"Same features, same frames: touchbench vs librosa {version('librosa')}")
    print(f"{'features':<46} {'ours (ms)':>10} {'librosa (ms)':>13} {'librosa/ours':>13}")
    for label, ours, theirs in spectral_comparison(arguments.seconds, arguments.repeats):
        print(f"{label:<46} {1000 * ours:>10.1f} {1000 * theirs:>13.1f} {theirs / ours:>13.2f}")


if __name__ == "__main__":
    main()
