"""Peak memory of ``extract`` on a long recording: streamed (today) against whole-array;
and of reading a CSV recording near the values limit, this checkout against another.

Run from the repository root::

    .venv/bin/python perf/extract_memory.py [--minutes 60] [--whole-minutes 5]
    .venv/bin/python perf/extract_memory.py --csv-against DIR [--channels 4] [--rounds 3]

Writes a 3-channel 44.1 kHz 16-bit WAV of noise with a tap every 2 s (``--minutes``
long, 15 MB a minute, in a temporary folder), then measures in a fresh process each the
peak resident memory (``VmHWM``) and the time of:

* streamed: :func:`app.services.extraction.extract_dataset`, block by block (the goal:
  under 500 MB for the hour, flat as the recording grows);
* whole-array, as extraction worked before: the recording read whole, then the
  detector and the extractor on the whole array, on the first ``--whole-minutes``
  (the hour would take about 8 GB).

With ``--csv-against DIR`` (another checkout, e.g. a ``git worktree`` of an older
commit), it writes instead a CSV of a time column and ``--channels`` channels holding 95 %
of the values a recording may hold (:data:`drivers.limits.CELLS`), and reads it
(:func:`drivers.files.read_recording`, what replay, extraction and prediction from a file
call) in a fresh process per read, that checkout and this one alternating for
``--rounds`` rounds: the peak resident memory (``VmHWM``) over the process's own at the
start, as a multiple of the values' bytes (rows x columns x 8), and the ratio of the two.

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


READ_CSV = (
    PEAK_MIB
    + """
import sys, time
from touchbench.drivers.files import read_recording
start, began = peak_mib(), time.perf_counter()
recording = read_recording(sys.argv[1])
print(start, peak_mib(), recording.samples.shape[1], time.perf_counter() - began)
"""
)


def write_csv(path: Path, rows: int, channels: int) -> None:
    """``rows`` of a time column at 1 kHz and ``channels`` of noise, 6 decimals."""
    rng = np.random.default_rng(0)
    with path.open("w") as handle:
        handle.write(",".join(["time", *(f"ch{c}" for c in range(channels))]) + "\n")
        for start in range(0, rows, 100_000):
            stop = min(start + 100_000, rows)
            block = np.column_stack(
                [np.arange(start, stop) / 1000.0, rng.normal(size=(stop - start, channels))]
            )
            np.savetxt(handle, block, fmt="%.6f", delimiter=",")


def measure_csv(code: Path, path: Path) -> tuple[int, int, int, float]:
    """Read ``path`` with the checkout ``code``: MiB at the start, peak MiB, samples, seconds."""
    done = subprocess.run(
        [sys.executable, "-c", READ_CSV, str(path)],
        capture_output=True,
        text=True,
        check=True,
        cwd=code,
        env={**os.environ, "PYTHONPATH": str(code), "OMP_NUM_THREADS": "1"},
    )
    start, peak, samples, seconds = done.stdout.split()
    return int(start), int(peak), int(samples), float(seconds)


def csv_main(against: Path, channels: int, rounds: int) -> None:
    from touchbench.drivers.limits import CELLS

    rows = int(0.95 * CELLS) // (channels + 1)
    values = rows * (channels + 1) * 8 / 2**20
    codes = {"before": against.resolve(), "now": ROOT}
    print(f"CSV: time + {channels} channels, {rows:,} rows: {values:.0f} MiB of values")
    print(f"before: {codes['before']}\nnow: {codes['now']}")
    print(
        f"{'round':>5} {'code':>6} {'start MiB':>9} {'peak MiB':>8} {'over start':>10} "
        f"{'x values':>8} {'seconds':>8}"
    )
    grown: dict[str, list[float]] = {"before": [], "now": []}
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "near-limit.csv"
        write_csv(path, rows, channels)
        print(f"file: {path.stat().st_size / 2**20:.0f} MiB")
        for round_ in range(1, rounds + 1):
            for label, code in codes.items():
                start, peak, samples, seconds = measure_csv(code, path)
                assert samples == rows, (samples, rows)
                grown[label].append(peak - start)
                print(
                    f"{round_:>5} {label:>6} {start:>9} {peak:>8} {peak - start:>10} "
                    f"{(peak - start) / values:>8.2f} {seconds:>8.1f}"
                )
    before, now = min(grown["before"]), min(grown["now"])
    print(
        f"least growth over the start: before {before:.0f} MiB ({before / values:.2f} x values), "
        f"now {now:.0f} MiB ({now / values:.2f} x values); before / now {before / now:.2f}"
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
    parser.add_argument("--csv-against", type=Path, help="checkout to compare CSV reading with")
    parser.add_argument("--channels", type=int, default=4, help="CSV channels (--csv-against)")
    parser.add_argument("--rounds", type=int, default=3, help="CSV rounds (--csv-against)")
    arguments = parser.parse_args()
    load = ", ".join(f"{value:.1f}" for value in os.getloadavg())
    print(f"Machine load average (1, 5, 15 min): {load} on {os.cpu_count()} cores")
    if arguments.csv_against is not None:
        csv_main(arguments.csv_against, arguments.channels, arguments.rounds)
        return
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
