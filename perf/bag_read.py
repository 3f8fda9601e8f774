"""Reading audio from ROS bags: seconds of audio per second, against the same samples in a WAV.

Run from the repository root::

    .venv/bin/python perf/bag_read.py [--minutes 10] [--message-samples 1024]

Writes ``--minutes`` of 3-channel 44.1 kHz S16LE audio as a ROS 1 ``.bag``, a ROS 2
``.mcap`` and a ROS 2 ``.db3`` (``audio_common_msgs/AudioData``, one message per
``--message-samples`` frames, as audio_capture sends them) and as a 16-bit WAV, then
reads each back block by block through :class:`drivers.replay.FileReplaySource` (what
``extract`` does), checks that every reader gives the same samples, and prints the
seconds of audio read per second and the WAV's speed over the bag's.  Best of three.
Not a test: nothing is asserted.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import soundfile

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from tests.support.bagfiles import write_audio_bag
from touchbench.drivers.replay import FileReplaySource

RATE = 44100


def read_all(path: Path) -> tuple[float, np.ndarray]:
    best, total = np.inf, np.zeros(3)
    for _ in range(3):
        began = time.perf_counter()
        with FileReplaySource(path) as source:
            total = np.zeros(3)
            for block in source.blocks():
                total += block.samples.sum(axis=1)
        best = min(best, time.perf_counter() - began)
    return best, total


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, default=10.0)
    parser.add_argument("--message-samples", type=int, default=1024)
    arguments = parser.parse_args()
    load = ", ".join(f"{value:.1f}" for value in os.getloadavg())
    print(f"Machine load average (1, 5, 15 min): {load} on {os.cpu_count()} cores")
    seconds = arguments.minutes * 60
    rng = np.random.default_rng(0)
    samples = np.round(rng.uniform(-0.5, 0.5, (3, round(seconds * RATE))) * 32768) / 32768
    with tempfile.TemporaryDirectory() as folder:
        here = Path(folder)
        wav = here / "audio.wav"
        soundfile.write(wav, samples.T, RATE, subtype="PCM_16")
        paths = {"WAV (PCM_16)": wav}
        for suffix, label in (
            (".bag", "ROS 1 .bag"),
            (".mcap", "ROS 2 .mcap"),
            (".db3", "ROS 2 .db3"),
        ):
            paths[label] = write_audio_bag(
                here / f"audio-{suffix[1:]}{suffix}",
                samples,
                RATE,
                message_samples=arguments.message_samples,
            )
        wav_time, reference = read_all(wav)
        print(
            f"{arguments.minutes:g} min of 3 x 44.1 kHz S16LE, "
            f"{arguments.message_samples}-frame messages"
        )
        print(f"{'format':<14} {'audio s / s':>12} {'WAV speed / this':>17}")
        for label, path in paths.items():
            elapsed, total = (wav_time, reference) if path == wav else read_all(path)
            if not np.allclose(total, reference):
                raise SystemExit(f"{label}: not the samples of the WAV")
            print(f"{label:<14} {seconds / elapsed:>12.0f} {elapsed / wav_time:>17.1f}")


if __name__ == "__main__":
    main()
