"""``touchbench serve`` pins BLAS and OpenMP to one thread per worker, unless told otherwise."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]

_PROBE = """
import numpy  # loaded before the pin, as in the serve process
from touchbench.app.cli.serve import pin_native_threads
pin_native_threads()
import sklearn.ensemble  # OpenMP loaded after it, as a worker does
from threadpoolctl import threadpool_info
print(sorted({(i["user_api"], i["num_threads"]) for i in threadpool_info()}))
"""


def _threads(**extra: str) -> str:
    environment = {
        k: v
        for k, v in os.environ.items()
        if k
        not in ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "BLIS_NUM_THREADS", "OMP_NUM_THREADS")
    }
    environment.update(extra, PYTHONPATH=str(ROOT))
    done = subprocess.run(
        [sys.executable, "-c", _PROBE], env=environment, capture_output=True, text=True, check=True
    )
    return done.stdout.strip()


def test_every_native_pool_has_one_thread() -> None:
    found = _threads()
    assert "('blas', 1)" in found and "('openmp', 1)" in found, found
    assert ", 2)" not in found, found


def test_a_thread_count_in_the_environment_is_left_alone() -> None:
    assert "('openmp', 2)" in _threads(OMP_NUM_THREADS="2")
