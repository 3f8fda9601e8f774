"""Compiles the numba kernels of aeon's MiniRocket and MultiRocket (the ``minirocket`` and
``multirocket`` classifiers) and of librosa (the test suite's reference features) once, so
that numba's on-disk cache (``cache=True``, beside each module) holds them.

Without it, every process that first meets a kernel compiles it: a run of ``multirocket``
on two engine workers compiles the same kernels in both, and the test suite's workers do the
same. ``scripts/install.sh`` runs this beside pip's install of the rest; it is safe to run
again (it then loads the cached kernels). The calls go through touchbench's own classifier
so that the kernels compiled are those of the types touchbench passes (float32, one or
several channels); librosa's are compiled when its modules load.
"""

from __future__ import annotations

import argparse
import functools
import signal
import subprocess
import sys
import time
from collections.abc import Callable

import numpy as np


def compile_rocket(variant: str) -> None:
    """Fit and predict ``variant`` on one and on two channels."""
    from touchbench.benchmark.catalogue.time_series import RocketClassifier

    rng = np.random.default_rng(0)
    length = 32
    for n_channels in (1, 2):
        X = rng.normal(size=(8, n_channels * length))
        y = np.arange(8) % 2
        model = RocketClassifier(
            variant, n_kernels=84, sequence=(0, n_channels, length), random_state=0
        )
        model.fit(X, y).predict(X)


def compile_librosa() -> None:
    """Load librosa's modules with kernels (their ``guvectorize`` kernels compile on load)."""
    import librosa

    y = np.random.default_rng(0).normal(size=4096)
    librosa.feature.zero_crossing_rate(y)
    librosa.feature.spectral_centroid(y=y, sr=22050)
    librosa.feature.mfcc(y=y, sr=22050, n_mfcc=13)


#: Each in a process of its own: the rockets' kernels are the long pole, one core each.
STEPS: dict[str, Callable[[], None]] = {
    "minirocket": functools.partial(compile_rocket, "minirocket"),
    "multirocket": functools.partial(compile_rocket, "multirocket"),
    "librosa": compile_librosa,
}


def main(arguments: list[str]) -> int:
    """Each step in a process of its own, at once (one step when named)."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("step", nargs="?", choices=sorted(STEPS), help="only this step")
    name = parser.parse_args(arguments).step
    if name is None:
        return _run_steps()
    start = time.monotonic()
    try:
        STEPS[name]()
    except ImportError as error:  # an environment without that extra: nothing to compile
        print(f"{name}: not installed ({error}); nothing compiled", file=sys.stderr)
        return 0
    print(f"{name}: kernels compiled in {time.monotonic() - start:.0f} s", file=sys.stderr)
    return 0


def _run_steps() -> int:
    """Every step at once; a SIGTERM (install.sh's, when pip fails or is interrupted) ends
    them too, rather than leaving them compiling on their own."""
    signal.signal(signal.SIGTERM, lambda number, frame: sys.exit(128 + number))
    steps = [subprocess.Popen([sys.executable, __file__, step]) for step in STEPS]
    try:
        return max(step.wait() for step in steps)
    finally:
        for step in steps:
            step.terminate()
            step.wait()


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
