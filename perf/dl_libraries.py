"""PyTorch against Keras 3 on JAX for the neural entries: install, epoch time, memory.

The deep-learning library behind ``bilstm``, ``cnn1d``, ``resnet1d`` and
``inception-time`` was to be chosen by measurement.  This script measures both
candidates on the same windows, side by side in one run:

1. Install.  Each into a fresh virtual environment holding NumPy already, pip's cache
   left out as on a fresh machine: ``torch==2.13.0 safetensors`` (the CPU wheel this
   machine keeps on disk; any newer torch pulls a CUDA build of several GB) and
   ``keras jax jaxlib`` (from PyPI).  Printed: seconds and megabytes added.
2. Training.  The same BiLSTM (64 units a direction, dropout 0.2, one dense output;
   Adam at 1e-3, batches of 32, cross-entropy; channels standardised on the training
   part) on the same windows: the oscillating link's MFCC frames as ``perf/neural.py``
   makes them, and the first of its 5 folds (by trial, stratified) to train and test.
   PyTorch is our own estimator
   (:class:`benchmark.catalogue.neural.NeuralSequenceClassifier`, one network, no early
   stopping); Keras runs in the venv of step 1 with
   ``KERAS_BACKEND=jax``.  Each in a fresh process pinned to one core with one thread
   (``OMP_NUM_THREADS``, XLA's flags), the two alternating for ``--rounds`` rounds (this
   machine's speed drifts).  Printed per round: the first epoch (JAX compiles there),
   the first epoch of a second network in the same process (every fold, refit and
   network of an ensemble is one: JAX compiles each anew), seconds per later epoch,
   peak resident memory, test accuracy, and the latency of one row's class
   probabilities (p50 and p99 of 200, after 100 to warm up).  The same for ``cnn1d``
   (three convolution blocks, global pooling, a dense layer) on the same windows.

    .venv/bin/python perf/dl_libraries.py [--trials 1200] [--epochs 6] [--rounds 2]
                                          [--networks bilstm cnn1d]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # perf.neural, run as a script

from perf.neural import install, link_data
from touchbench.app.services.simulation import write_link_trials
from touchbench.benchmark.problem import problem_from_dataset
from touchbench.benchmark.run.folds import make_folds
from touchbench.benchmark.sequence import panel

ROOT = Path(__file__).resolve().parents[1]

#: Our estimator: a first fit of one epoch (PyTorch's first call sets up its kernels and
#: threads), then one of one epoch and one of ``epochs``: their difference is the later
#: epochs' time.
TORCH = """
import json, resource, sys, time
import numpy as np
import torch  # imported before the clock starts, as Keras and JAX are
from touchbench.benchmark.catalogue.neural import NeuralSequenceClassifier
data = np.load(sys.argv[1])
X, y, train, test = data["X"], data["y"], data["train"], data["test"]
n, channels, length = X.shape
seconds = []  # a cold fit of one epoch, then warm ones of one and of all epochs
for epochs in (1, 1, int(sys.argv[2])):
    model = NeuralSequenceClassifier(
        network=sys.argv[3], hidden=64, filters=32, kernel=5, max_epochs=epochs,
        validation_fraction=0.0, refit=False, sequence=(0, channels, length), random_state=0,
    )
    began = time.perf_counter()
    model.fit(X[train].reshape(len(train), -1), y[train])
    seconds.append(time.perf_counter() - began)
accuracy = float((model.predict(X[test].reshape(len(test), -1)) == y[test]).mean())
latency = []
for i in range(300):  # the test rows, again from the first if there are fewer
    row = X[test[i % len(test)]].reshape(1, channels * length)
    began = time.perf_counter()
    model.predict_proba(row)
    latency.append(1000 * (time.perf_counter() - began))
print(json.dumps({
    "row": list(np.percentile(latency[100:], [50, 99])),
    "first": seconds[0], "again": seconds[1],
    "later": (seconds[2] - seconds[1]) / (int(sys.argv[2]) - 1),
    "peak": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, "accuracy": accuracy,
}))
"""

#: The same network in Keras 3; the first epoch and the later ones timed by a callback.
KERAS = """
import json, resource, sys, time
import numpy as np
import keras
data = np.load(sys.argv[1])
X, y, train, test = data["X"], data["y"], data["train"], data["test"]
mean = X[train].mean(axis=(0, 2), keepdims=True)
scale = X[train].std(axis=(0, 2), keepdims=True)
X = np.moveaxis(((X - mean) / np.where(scale > 0, scale, 1)).astype("float32"), 1, 2)
layers = keras.layers
def build(seed):
    keras.utils.set_random_seed(seed)
    if sys.argv[3] == "bilstm":
        body = [layers.Bidirectional(layers.LSTM(64)), layers.Dropout(0.2)]
    else:  # cnn1d: three convolution blocks, pooling while 4 steps or more are left
        body, length = [], X.shape[1]
        for filters in (32, 64, 64):
            body += [layers.Conv1D(filters, 5, padding="same", activation="relu")]
            if length >= 4:
                body.append(layers.MaxPooling1D(2))
                length //= 2
        body += [layers.GlobalAveragePooling1D(), layers.Dense(64, activation="relu"),
                 layers.Dropout(0.2)]
    model = keras.Sequential([keras.Input(X.shape[1:]), *body, layers.Dense(int(y.max()) + 1)])
    model.compile(
        optimizer=keras.optimizers.Adam(1e-3),
        loss=keras.losses.SparseCategoricalCrossentropy(from_logits=True),
    )
    return model
model = build(0)
class Clock(keras.callbacks.Callback):
    def on_epoch_begin(self, epoch, logs=None):
        self.began = time.perf_counter()
    def on_epoch_end(self, epoch, logs=None):
        seconds.append(time.perf_counter() - self.began)
seconds = []
model.fit(X[train], y[train], batch_size=32, epochs=int(sys.argv[2]), verbose=0,
          callbacks=[Clock()])
accuracy = float((model.predict(X[test], verbose=0).argmax(axis=1) == y[test]).mean())
latency = []
for i in range(300):  # the test rows, again from the first if there are fewer
    row = X[test[i % len(test)]][None]
    began = time.perf_counter()
    keras.ops.softmax(model.predict_on_batch(row))
    latency.append(1000 * (time.perf_counter() - began))
began = time.perf_counter()  # a new network (the next fold, the refit): compiled again
build(1).fit(X[train], y[train], batch_size=32, epochs=1, verbose=0)
print(json.dumps({
    "row": list(np.percentile(latency[100:], [50, 99])),
    "again": time.perf_counter() - began, "first": seconds[0], "later": float(np.mean(seconds[1:])),
    "peak": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, "accuracy": accuracy,
}))
"""

#: perf/neural.py's recipe: 30 MFCCs x 8 frames a channel.
MFCC = {"n_mfcc": "30", "frames": "8"}

ONE_THREAD = {
    "OMP_NUM_THREADS": "1",
    "OPENBLAS_NUM_THREADS": "1",
    "MKL_NUM_THREADS": "1",
    "XLA_FLAGS": "--xla_cpu_multi_thread_eigen=false intra_op_parallelism_threads=1",
}


def windows(folder: Path, trials: int) -> Path:
    """The link's windows (n, channels, length), labels and a split by trial, saved."""
    data = link_data(write_link_trials(folder, trials=trials, seed=1), "mfcc", MFCC)
    problem, _ = problem_from_dataset(data)
    assert problem.sequence is not None and problem.groups is not None
    X, _ = panel(problem.X, problem.sequence.shape)
    # the first of perf/neural.py's folds: by trial, stratified (the classes take turns
    # across trials, so every fifth trial would be one class)
    folds, _ = make_folds(problem.Y, n_folds=5, groups=problem.groups, seed=0)
    train, test = folds[0].train, folds[0].test
    path = folder / "windows.npz"
    np.savez(path, X=X, y=problem.Y[:, 0].astype(np.int64), train=train, test=test)
    print(f"  windows: {len(train)} to train, {len(test)} to test, {X.shape[1]} x {X.shape[2]}")
    return path


def train(
    python: Path, code: str, windows_path: Path, epochs: int, backend: str, network: str
) -> dict:
    """One training of ``network`` in a fresh process pinned to the first core; what it
    printed."""
    core = str(min(os.sched_getaffinity(0)))
    environment = {**os.environ, **ONE_THREAD, "PYTHONPATH": str(ROOT), "KERAS_BACKEND": backend}
    done = subprocess.run(
        ["taskset", "-c", core, str(python), "-c", code, str(windows_path), str(epochs), network],
        capture_output=True,
        text=True,
        env=environment,
        check=True,
    )
    return dict(json.loads(done.stdout.strip().splitlines()[-1]))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=1200, help="link trials of 3 s")
    parser.add_argument("--epochs", type=int, default=6, help="epochs a training")
    parser.add_argument("--rounds", type=int, default=2, help="alternating rounds")
    parser.add_argument(
        "--networks", nargs="+", default=["bilstm", "cnn1d"], choices=["bilstm", "cnn1d"]
    )
    arguments = parser.parse_args()
    load = ", ".join(f"{value:.1f}" for value in os.getloadavg())
    print(f"Machine load average (1, 5, 15 min): {load} on {os.cpu_count()} cores")
    with tempfile.TemporaryDirectory() as name:
        folder = Path(name)
        print("1. Install (a fresh venv with NumPy, no pip cache)")
        install(folder, ("torch==2.13.0", "safetensors"), base=("numpy",))
        keras_venv = install(folder, ("keras", "jax", "jaxlib"), base=("numpy",))
        print(f"2. Training, {arguments.epochs} epochs, and one row, one thread on one core")
        path = windows(folder, arguments.trials)
        sides = (
            ("PyTorch (ours)", Path(sys.executable), TORCH, "torch"),
            ("Keras 3 on JAX", keras_venv / "bin/python", KERAS, "jax"),
        )
        print(
            f"  {'':24s} {'first epoch':>12s} {'next network':>13s} {'later epochs':>13s} "
            f"{'peak':>8s} {'accuracy':>9s} {'one row p50 / p99':>18s}"
        )
        for network in arguments.networks:
            for round_ in range(arguments.rounds):
                for label, python, code, backend in sides if round_ % 2 == 0 else sides[::-1]:
                    got = train(python, code, path, arguments.epochs, backend, network)
                    print(
                        f"  {f'{network}, {label}':24s} {got['first']:10.2f} s "
                        f"{got['again']:11.2f} s {got['later']:10.2f} s/e "
                        f"{got['peak']:5.0f} MB {got['accuracy']:9.3f} "
                        f"{got['row'][0]:8.2f} / {got['row'][1]:5.2f} ms"
                    )


if __name__ == "__main__":
    main()
