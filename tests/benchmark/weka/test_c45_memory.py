"""J48's memory is linear in the data, not times the classes (issue 22: 9,480 windows x
1,232 features x 20 classes allocated 1.74 GiB per array and met the OOM killer).

The fit runs in a fresh interpreter, whose peak resident memory (``VmHWM`` in
``/proc/self/status``) is read before and after it: the split search used to hold about
ten arrays of (rows, features, classes): 105 MB more than its data here, now 12 MB.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]
SCRIPT = """
import numpy as np
from touchbench.benchmark.weka.c45 import C45Classifier

def peak():
    with open("/proc/self/status") as status:
        line = next(line for line in status if line.startswith("VmHWM:"))
    return int(line.split()[1]) * 1024

n, width, classes = 150, 1000, 20
rng = np.random.default_rng(0)
y = np.arange(n) % classes
X = rng.normal(size=(n, width))
X[:, :classes] += 3.0 * (y[:, None] == np.arange(classes))
before = peak()
tree = C45Classifier().fit(X, y)
print(peak() - before, X.nbytes, tree.n_leaves_)
"""


def test_j48_on_a_wide_twenty_class_set_grows_by_little_more_than_its_data() -> None:
    ran = subprocess.run(
        [sys.executable, "-c", SCRIPT],
        env={**os.environ, "PYTHONPATH": str(ROOT), "OPENBLAS_NUM_THREADS": "1"},
        capture_output=True,
        text=True,
        check=False,
        timeout=300,
    )
    assert ran.returncode == 0, ran.stderr
    grown, data, leaves = (int(word) for word in ran.stdout.split())
    assert leaves >= 20  # a real tree, one leaf per class at least
    # n x features x classes x 8 bytes is 24 MB here, and the old search held ~10 of them
    assert grown < 40 * 2**20 + 10 * data, f"the fit grew the peak by {grown / 2**20:.0f} MB"
