"""Peak memory of the ONNX export's check (the graph against the model on every training
instance), whole against in chunks of :data:`benchmark.export.check.CHECK_ROWS` rows.

Run from the repository root::

    .venv/bin/python perf/onnx_check_memory.py [--repeat 1 10] [--classifiers rf cc:rf]

Fits each classifier on the Maggie data set (3,572 instances x 99 features, two targets;
one target, gesture, for a single-target classifier), stores the model in a temporary
file, then in a fresh process per case loads it, converts it, and measures the peak
resident memory (``VmHWM``) before and after :func:`check_twin` on the training
instances repeated ``--repeat`` times (a training set that many times larger), with the
check whole (one ONNX Runtime call) and in chunks.

Not a test: nothing is asserted.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from perf.memory import PEAK_MIB  # noqa: E402 (after the path is set)

MAGGIE = Path("/work/shared/datasets/uc3m-touch/maggie/gesture_and_place.arff")

CHECK = (
    PEAK_MIB
    + """
import sys, time
import numpy as np
from touchbench.benchmark.export import check, onnx as export
from touchbench.benchmark.model import loads_model, model_digest
data = open(sys.argv[1], "rb").read()
model = loads_model(data, sha256=model_digest(data))
X = np.tile(np.load(sys.argv[2]), (int(sys.argv[3]), 1))
check.CHECK_ROWS = int(sys.argv[4])
graph = export.convert(model).SerializeToString()
before = peak_mib()
start = time.perf_counter()
export.check_twin(model, graph, X)
print(len(X), before, peak_mib(), round(time.perf_counter() - start, 2))
"""
)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, nargs="+", default=[1, 10])
    parser.add_argument("--classifiers", nargs="+", default=["rf", "cc:rf"])
    args = parser.parse_args()
    from touchbench.app.services.datasets import read_data_file
    from touchbench.benchmark.model import dumps_model, fit_model
    from touchbench.benchmark.problem import restrict_targets

    full = read_data_file(MAGGIE)
    with tempfile.TemporaryDirectory() as folder:
        for classifier in args.classifiers:
            data = full if ":" in classifier else restrict_targets(full, ["gesture"])
            model = fit_model(data, classifier)
            path = Path(folder) / "model.bin"
            path.write_bytes(dumps_model(model))
            np.save(Path(folder) / "X.npy", data.X)
            for repeat in args.repeat:
                for rows, how in ((10**9, "whole"), (0, "chunked")):
                    from touchbench.benchmark.export.check import CHECK_ROWS

                    chunk = rows or CHECK_ROWS
                    started = time.perf_counter()
                    out = subprocess.run(
                        [
                            sys.executable,
                            "-c",
                            CHECK,
                            str(path),
                            str(Path(folder) / "X.npy"),
                            str(repeat),
                            str(chunk),
                        ],
                        capture_output=True,
                        text=True,
                        check=True,
                        cwd=ROOT,
                    ).stdout.split()
                    n, before, after, seconds = out
                    print(
                        f"{classifier:8} {int(n):>7,} rows {how:8} peak before check "
                        f"{before:>5} MiB, after {after:>5} MiB (+{int(after) - int(before)}), "
                        f"check {seconds} s, process {time.perf_counter() - started:.1f} s"
                    )


if __name__ == "__main__":
    main()
