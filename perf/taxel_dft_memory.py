"""Peak memory of ``extract -e taxel-dft`` on a long tactile recording, against the size
of the features it makes.

Run from the repository root (``--code`` to measure another checkout, e.g. the one
before a change)::

    .venv/bin/python perf/taxel_dft_memory.py [--minutes 30] [--channels 44] [--code DIR]

Writes a BioTac-like recording (``--channels`` channels of noise at 100 Hz, ``--minutes``
long) as a ``.npy`` file, as a plain CSV (an even ``time`` column) and as a real export
(a ``timestamp`` column of jittered ROS stamps, a comma at the end of every row, which
versions before issue 22 refuse), then measures in a fresh process for each the
peak resident memory (``VmHWM``) of
:func:`app.services.extraction.extract_dataset` with ``taxel-dft`` (64-sample windows,
step 8, ``drop=4``, the values every version accepts), beside the bytes of the feature
matrix it returns.  Not a test: nothing is asserted.
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

RATE = 100.0
ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from perf.memory import PEAK_MIB  # noqa: E402 (after the path is set)

EXTRACT = (
    PEAK_MIB
    + """
import sys
from pathlib import Path
from touchbench.app.services.extraction import extract_dataset
rate = None if sys.argv[1].endswith(".csv") else 100.0
result = extract_dataset(
    [Path(sys.argv[1])], labels=None, extractor="taxel-dft", samplerate=rate,
    options={"drop": 4},
)
peak = peak_mib()
print(result.dataset.values.shape[0], result.dataset.values.nbytes // 2**20, peak)
"""
)


def write_recordings(folder: Path, minutes: float, channels: int) -> list[Path]:
    n = round(minutes * 60 * RATE)
    rng = np.random.default_rng(0)
    samples = rng.standard_normal((channels, n))
    npy = folder / "long.npy"
    np.save(npy, samples)
    even = np.arange(n) / RATE
    jittered = 1.7e9 + even + rng.uniform(-0.004, 0.004, n)
    plain = _write_csv(folder / "plain.csv", "time", even, samples, "\n")
    export = _write_csv(folder / "export.csv", "timestamp", jittered, samples, ",\n")
    return [npy, plain, export]


def _write_csv(path: Path, time: str, times: np.ndarray, samples: np.ndarray, end: str) -> Path:
    with path.open("w") as handle:
        handle.write(",".join([time, *(f"ch{c}" for c in range(samples.shape[0]))]) + end)
        for start in range(0, times.size, 10000):
            stop = min(start + 10000, times.size)
            block = np.column_stack([times[start:stop], samples[:, start:stop].T])
            np.savetxt(handle, block, fmt="%.6f", delimiter=",", newline=end)
    return path


def measure(path: Path, code: Path) -> tuple[int, int, int, float] | str:
    """Windows, feature MB, peak MB and seconds; or the error, if the version refuses."""
    began = time.perf_counter()
    done = subprocess.run(
        [sys.executable, "-c", EXTRACT, str(path)],
        capture_output=True,
        text=True,
        check=False,
        env={**os.environ, "PYTHONPATH": str(code), "OMP_NUM_THREADS": "1"},
        cwd=code,
    )
    if done.returncode != 0:
        return done.stderr.strip().splitlines()[-1]
    windows, features, peak = (int(x) for x in done.stdout.split())
    return windows, features, peak, time.perf_counter() - began


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, default=30.0)
    parser.add_argument("--channels", type=int, default=44)
    parser.add_argument("--code", type=Path, default=ROOT, help="checkout to measure")
    arguments = parser.parse_args()
    load = ", ".join(f"{value:.1f}" for value in os.getloadavg())
    print(f"Machine load average (1, 5, 15 min): {load} on {os.cpu_count()} cores")
    print(f"code: {arguments.code}")
    print(
        f"{'input':<6} {'file MB':>8} {'windows':>8} {'features MB':>12} {'peak MB':>8} "
        f"{'peak/features':>14} {'seconds':>8}"
    )
    with tempfile.TemporaryDirectory() as folder:
        for path in write_recordings(Path(folder), arguments.minutes, arguments.channels):
            size = path.stat().st_size / 2**20
            measured = measure(path, arguments.code)
            if isinstance(measured, str):
                print(f"{path.stem:<6} {size:>8.0f} refused: {measured[:80]}")
                continue
            windows, features, peak, seconds = measured
            print(
                f"{path.stem:<6} {size:>8.0f} {windows:>8} {features:>12} {peak:>8} "
                f"{peak / max(features, 1):>14.2f} {seconds:>8.1f}"
            )


if __name__ == "__main__":
    main()
