"""Peak memory of ``extract`` on a long recording: streamed (today) against whole-array.

Run from the repository root::

    .venv/bin/python perf/extract_memory.py [--minutes 60] [--whole-minutes 5]

Writes a 3-channel 44.1 kHz 16-bit WAV of noise with a tap every 2 s (``--minutes``
long, 15 MB a minute, in a temporary folder), then measures in a fresh process each the
peak resident memory (``VmHWM``) and the time of:

* streamed: :func:`app.services.extraction.extract_dataset`, block by block (the goal:
  under 500 MB for the hour, flat as the recording grows);
* whole-array, as extraction worked before: the recording read whole, then the
  detector and the extractor on the whole array, on the first ``--whole-minutes``
  (the hour would take about 8 GB).

Not a test: nothing is asserted.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import soundfile

RATE = 44100
ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from perf.memory import PEAK_MIB  # noqa: E402 (after the path is set)

STREAMED = (
    PEAK_MIB
    + """
import sys
from pathlib import Path
from touchbench.app.services.extraction import extract_dataset
result = extract_dataset([Path(sys.argv[1])], labels=None, extractor="uc3m-audio")
print(result.n_events, peak_mib())
"""
)

WHOLE = (
    PEAK_MIB
    + """
import sys
from touchbench.drivers.files import read_recording
from touchbench.features.events import detect_events
from touchbench.features.extractors import make_extractor
recording = read_recording(sys.argv[1])
detection = detect_events("snr", recording.samples, samplerate=recording.samplerate)
instances = make_extractor("uc3m-audio").extract(
    recording.samples, samplerate=recording.samplerate, detection=detection
)
print(len(instances.values), peak_mib())
"""
)


def write_session(path: Path, minutes: float) -> None:
    rng = np.random.default_rng(0)
    tap = 0.3 * np.exp(-np.arange(2205) / 300.0) * np.sin(np.arange(2205) * 0.3)
    with soundfile.SoundFile(path, "w", RATE, 3, subtype="PCM_16") as handle:
        for _ in range(round(minutes * 30)):
            samples = 1e-3 * rng.standard_normal((2 * RATE, 3))
            samples[RATE : RATE + tap.size, 1] += tap
            handle.write(samples)


def measure(script: str, path: Path) -> tuple[int, int, float]:
    began = time.perf_counter()
    done = subprocess.run(
        [sys.executable, "-c", script, str(path)],
        capture_output=True,
        text=True,
        check=True,
        env={**os.environ, "PYTHONPATH": str(ROOT), "OMP_NUM_THREADS": "1"},
    )
    events, peak = (int(x) for x in done.stdout.split())
    return events, peak, time.perf_counter() - began


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, default=60.0)
    parser.add_argument("--whole-minutes", type=float, default=5.0)
    arguments = parser.parse_args()
    load = ", ".join(f"{value:.1f}" for value in os.getloadavg())
    print(f"Machine load average (1, 5, 15 min): {load} on {os.cpu_count()} cores")
    print(
        f"{'path':<12} {'recording':>10} {'file MB':>8} {'events':>7} {'peak MB':>8} "
        f"{'peak/file':>10} {'seconds':>8}"
    )
    with tempfile.TemporaryDirectory() as folder:
        runs = [("whole-array", arguments.whole_minutes, WHOLE)]
        runs += [
            ("streamed", minutes, STREAMED)
            for minutes in sorted({arguments.whole_minutes, arguments.minutes})
        ]
        for label, minutes, script in runs:
            path = Path(folder) / f"{minutes:g}min.wav"
            if not path.exists():
                write_session(path, minutes)
            size = path.stat().st_size / 2**20
            events, peak, seconds = measure(script, path)
            print(
                f"{label:<12} {f'{minutes:g} min':>10} {size:>8.0f} {events:>7} {peak:>8} "
                f"{peak / size:>10.2f} {seconds:>8.1f}"
            )


if __name__ == "__main__":
    main()
