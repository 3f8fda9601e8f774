"""Live prediction: latency per touch, and whether the capture path keeps up.

Run from the repository root::

    .venv/bin/python perf/live_latency.py [--sessions 8] [--capture-seconds 60]

1. Latency.  A 100-tree random forest (``rf``) is trained on the ``uc3m-audio``
   features of simulated 3-microphone sessions (44.1 kHz), then fresh sessions are
   replayed through :class:`app.services.live.LiveSession` in blocks of 512 samples
   (11.6 ms, what ``touchbench live`` asks of the sound card) and of 1024 (23 ms, another
   usual period), one table row each.  For each touch it prints percentiles of: the latency
   ``live`` reports (from the end of the event, after the hangover, to the prediction:
   the wait for the block holding the end plus the computing), the computing alone
   (extraction of the event and prediction), and the two predictions alone
   (``predict`` and ``predict_proba`` of the forest on one instance).  Goal: p50 under
   20 ms, p99 under 50 ms.  Then the neural entries ``cnn1d`` and ``bilstm`` on MFCC
   frames (``mfcc`` with ``frames=32``) of the same sessions, one thread: the computing
   per touch and the prediction alone, the latter also with the preprocessor's columns
   selected by lists of indices (how it was before: scikit-learn checks a list of 1,344
   indices item by item on every call), alternating with the array selection.  Goal: p99
   under 20 ms on one core.  ``--networks-only`` runs only this part.
2. Capture.  The same model runs on PortAudio capture of 3 channels at 44.1 kHz through
   ALSA's file plugin (a ``replay`` device in a temporary HOME, as the tests do), pinned
   to one core.  That device is not paced (it delivers as fast as it can), so the
   figure is how many times real time the whole capture path (callback, queue,
   detection, extraction, prediction) runs: above 1 with margin, a paced sound card
   never fills the queue.  Blocks dropped from a full queue and PortAudio's own input
   overflows (xruns: the unpaced device outrunning its callback thread) are printed.
3. Engines.  ``rf``, ``xgb``, ``logistic`` and ``svm-rbf`` trained on the same features,
   exported as ONNX (``export-model``'s service), and one row predicted by the model
   itself (``native``) and by its ONNX twin in ONNX Runtime (``onnx``), alternately, row
   after row of the training features: per-row latency p50/p99 and the ratio native/ONNX
   (what ``--engine auto`` was chosen by).  ``--engines-only`` runs this part alone.

Not a test: nothing is asserted.
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse
import copy
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import soundfile

if TYPE_CHECKING:
    from touchbench.app.store.database import Store

ROOT = Path(__file__).resolve().parents[1]

CAPTURE = """
import os, sys, time
os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})
from touchbench.app.services.live import open_live
from touchbench.app.store.database import Store
from touchbench.drivers.sound import SoundDeviceSource
seconds, queue = float(sys.argv[2]), float(sys.argv[3])
source = SoundDeviceSource("replay", samplerate=44100, channels=3, seconds=seconds,
                           queue_seconds=queue, block_length=int(sys.argv[4]))
session = open_live(Store(sys.argv[1]), "touch-rf", samplerate=44100, n_channels=3)
began, touches = time.perf_counter(), 0
with source:
    for block in source.blocks():
        touches += len(session.feed(block.samples, block.time, arrived=block.arrived))
    touches += len(session.finish())
print(seconds / (time.perf_counter() - began), touches, source.dropped, source.xruns)
"""


def percentiles(values: list[float]) -> str:
    p50, p90, p99 = np.percentile(values, [50, 90, 99])
    return f"{p50:8.1f} {p90:8.1f} {p99:8.1f} {max(values):8.1f}"


def with_listed_columns(model: Any) -> Any:
    """A copy of ``model`` whose column transformer selects its columns by lists of
    indices, as it did before: scikit-learn checks a list item by item on each call."""
    twin = copy.deepcopy(model)
    transformer = twin.estimator[0]
    transformer.transformers_ = [
        (name, step, list(columns) if isinstance(columns, np.ndarray) else columns)
        for name, step, columns in transformer.transformers_
    ]
    return twin


def networks(store: Store, here: Path, recordings: list[Path], labels: Path, sessions: int) -> None:
    """Per-touch latency of the neural entries (``cnn1d``, ``bilstm``) on MFCC frames."""
    from touchbench.app.schemas.extraction import ExtractRequest
    from touchbench.app.schemas.models import TrainRequest
    from touchbench.app.services.extraction import extract_and_store
    from touchbench.app.services.live import open_live
    from touchbench.app.services.loading import load_model
    from touchbench.app.services.models import train
    from touchbench.app.services.simulation import write_session
    from touchbench.drivers.replay import FileReplaySource
    from touchbench.drivers.source import LIVE_BLOCK

    frames = ExtractRequest(
        recordings=recordings, labels=labels, name="frames", extractor="mfcc", events="snr",
        options={"frames": "32"},
    )  # fmt: skip
    extract_and_store(store, frames)
    print(
        f"\n1b. Neural networks on MFCC frames (mfcc frames=32), {LIVE_BLOCK}-sample blocks, "
        f"one thread, ms per touch"
    )
    print(f"{'':<46} {'p50':>8} {'p90':>8} {'p99':>8} {'max':>8}")
    for classifier in ("cnn1d", "bilstm"):
        began = time.perf_counter()
        train(store, TrainRequest(dataset="frames", classifier=classifier, target="gesture"))
        fitted = time.perf_counter() - began
        _, model = load_model(store, f"frames-{classifier}")
        computing = []
        for seed in range(sessions):
            wav, _ = write_session(here, f"fresh{seed}", n_touches=16, seed=1000 + seed)
            with FileReplaySource(wav, block_length=LIVE_BLOCK) as source:
                session = open_live(store, f"frames-{classifier}", samplerate=44100.0, n_channels=3)
                for block in source.blocks():
                    start = time.perf_counter()
                    if session.feed(block.samples, block.time, arrived=start):
                        computing.append(1000 * (time.perf_counter() - start))
        X = np.zeros((1, len(model.schema.features)))
        listed = with_listed_columns(model)
        alone: dict[str, list[float]] = {"arrays": [], "lists": []}
        cpu: dict[str, list[float]] = {"arrays": [], "lists": []}
        for twin in (model, listed):
            twin.predict_with_proba(X)  # the network is rebuilt from its weights once
        for _ in range(200):  # alternating: the machine's speed drifts
            for name, twin in (("arrays", model), ("lists", listed)):
                start, start_cpu = time.perf_counter(), time.process_time()
                twin.predict_with_proba(X)
                alone[name].append(1000 * (time.perf_counter() - start))
                cpu[name].append(1000 * (time.process_time() - start_cpu))
        print(f"{f'computing (extract + predict), {classifier}':<46} {percentiles(computing)}")
        print(f"{f'predict_with_proba alone, {classifier}':<46} {percentiles(alone['arrays'])}")
        print(f"{'  same, columns as lists (before)':<46} {percentiles(alone['lists'])}")
        # CPU time: what a loaded machine's waits do not inflate
        print(f"{'  CPU ms of predict_with_proba alone':<46} {percentiles(cpu['arrays'])}")
        print(f"{'  same, columns as lists (before)':<46} {percentiles(cpu['lists'])}")
        print(f"  ({classifier} trained in {fitted:.1f} s on {len(recordings) * 16} touches)")


def engines(store: Store, repeats: int) -> None:
    """Per-row latency of each entry's own estimator and of its ONNX twin, alternately."""
    from touchbench.app.schemas.models import ExportRequest, TrainRequest
    from touchbench.app.services.export import export_model
    from touchbench.app.services.loading import load_predictor
    from touchbench.app.services.models import train
    from touchbench.app.store.datasets import load_dataset

    X = load_dataset(store, "touch").X
    print(f"\n3. One row, native vs ONNX Runtime ({repeats} rows each, alternating), ms")
    header = f"{'':<12} {'native p50':>10} {'p99':>8} {'onnx p50':>10} {'p99':>8} {'p50 ratio':>10}"
    print(header)
    for classifier in ("rf", "xgb", "logistic", "svm-rbf"):
        name = f"touch-{classifier}"
        if classifier != "rf":
            train(store, TrainRequest(dataset="touch", classifier=classifier, target="gesture"))
        export_model(store, ExportRequest(model=name))
        predictors = {
            engine: load_predictor(store, name, engine)[1] for engine in ("native", "onnx")
        }
        times: dict[str, list[float]] = {"native": [], "onnx": []}
        for i in range(repeats):
            row = X[i % len(X) : i % len(X) + 1]
            for engine in ("native", "onnx") if i % 2 else ("onnx", "native"):
                began = time.perf_counter()
                predictors[engine].predict_with_proba(row)
                times[engine].append(1000 * (time.perf_counter() - began))
        native, onnx = (np.percentile(times[e][10:], [50, 99]) for e in ("native", "onnx"))
        print(
            f"{classifier:<12} {native[0]:>10.3f} {native[1]:>8.3f} {onnx[0]:>10.3f} "
            f"{onnx[1]:>8.3f} {native[0] / onnx[0]:>9.1f}x"
        )


def main() -> None:
    from touchbench.app.schemas.extraction import ExtractRequest
    from touchbench.app.schemas.models import TrainRequest
    from touchbench.app.services.extraction import extract_and_store
    from touchbench.app.services.live import open_live
    from touchbench.app.services.loading import load_model
    from touchbench.app.services.models import train
    from touchbench.app.services.simulation import write_labels, write_session
    from touchbench.app.store.database import Store
    from touchbench.drivers.replay import FileReplaySource
    from touchbench.drivers.source import LIVE_BLOCK

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sessions", type=int, default=8, help="fresh sessions replayed")
    parser.add_argument("--capture-seconds", type=float, default=60.0)
    parser.add_argument("--engines-only", action="store_true", help="only part 3")
    parser.add_argument("--rows", type=int, default=400, help="rows per engine in part 3")
    parser.add_argument(
        "--networks-only", action="store_true", help="only the neural entries' latency (1b)"
    )
    arguments = parser.parse_args()
    load = ", ".join(f"{value:.1f}" for value in os.getloadavg())
    print(f"Machine load average (1, 5, 15 min): {load} on {os.cpu_count()} cores")
    with tempfile.TemporaryDirectory() as folder:
        here = Path(folder)
        db = f"sqlite:///{here / 'live.db'}"
        store = Store(db)
        recordings, rows = [], []
        for seed in range(4):
            wav, touches = write_session(here, f"train{seed}", n_touches=16, seed=seed)
            recordings.append(wav)
            rows += [(wav.name, *touch) for touch in touches]
        labels = write_labels(here / "labels.csv", rows)
        if arguments.networks_only:
            networks(store, here, recordings, labels, arguments.sessions)
            return
        extract_and_store(store, ExtractRequest(recordings=recordings, labels=labels, name="touch"))
        train(store, TrainRequest(dataset="touch", classifier="rf", target="gesture"))
        _, model = load_model(store, "touch-rf")
        if arguments.engines_only:
            engines(store, arguments.rows)
            return

        rows = []
        for block_length in sorted({LIVE_BLOCK, 1024}):
            reported, computing = [], []
            for seed in range(arguments.sessions):
                wav, _ = write_session(here, f"fresh{seed}", n_touches=16, seed=1000 + seed)
                with FileReplaySource(wav, block_length=block_length) as source:
                    session = open_live(store, "touch-rf", samplerate=44100.0, n_channels=3)
                    for block in source.blocks():
                        began = time.perf_counter()
                        touches = session.feed(block.samples, block.time, arrived=began)
                        if touches:
                            computing.append(1000 * (time.perf_counter() - began))
                            reported += [t.latency_ms for t in touches]
            rows.append((f"reported by live, {block_length}-sample blocks", reported))
            rows.append((f"computing (extract + predict), {block_length}", computing))
        predicting, one_pass = [], []
        X = np.zeros((1, len(model.schema.features)))
        for _ in range(50):
            began = time.perf_counter()
            model.predict(X)
            model.predict_proba(X)
            predicting.append(1000 * (time.perf_counter() - began))
            began = time.perf_counter()
            model.predict_with_proba(X)
            one_pass.append(1000 * (time.perf_counter() - began))
        rows.append(("predict + predict_proba, 100-tree forest", predicting))
        rows.append(("predict_with_proba (one pass, what live does)", one_pass))
        print(f"\n1. Latency per touch, ms ({len(reported)} touches per block length)")
        print(f"{'':<46} {'p50':>8} {'p90':>8} {'p99':>8} {'max':>8}")
        for label, values in rows:
            print(f"{label:<46} {percentiles(values)}")

        networks(store, here, recordings, labels, arguments.sessions)

        print(
            f"\n2. Capture path, 3 ch x 44.1 kHz in {LIVE_BLOCK}-sample blocks through "
            "PortAudio/ALSA, one core"
        )
        home = here / "home"
        home.mkdir()
        raw = here / "capture.s16"
        parts = []
        for seed in range(int(np.ceil(arguments.capture_seconds / 25))):
            wav, _ = write_session(here, f"capture{seed}", n_touches=12, seed=2000 + seed)
            samples, _ = soundfile.read(wav, always_2d=True)
            parts.append(samples)
        audio = np.concatenate(parts)[: round(arguments.capture_seconds * 44100) + 44100]
        np.clip(np.round(audio * 32768), -32768, 32767).astype("<i2").tofile(raw)
        (home / ".asoundrc").write_text(
            f'pcm.replay {{\n type file\n slave.pcm "nullcap"\n file "/dev/null"\n'
            f' infile "{raw}"\n format "raw"\n}}\npcm.nullcap {{ type null }}\n'
        )
        env = {**os.environ, "HOME": str(home), "PYTHONPATH": str(ROOT)}
        print(f"{'queue':<28} {'x real time':>12} {'touches':>8} {'dropped':>8} {'xruns':>8}")
        for queue in (arguments.capture_seconds * 2, 5.0):
            done = subprocess.run(
                [
                    sys.executable,
                    "-c",
                    CAPTURE,
                    db,
                    str(arguments.capture_seconds),
                    str(queue),
                    str(LIVE_BLOCK),
                ],
                capture_output=True,
                text=True,
                env=env,
                check=True,
            )
            factor, touches, dropped, xruns = done.stdout.split()
            label = f"{queue:g} s" + (" (default)" if queue == 5.0 else " (holds it all)")
            print(f"{label:<28} {float(factor):>12.1f} {touches:>8} {dropped:>8} {xruns:>8}")
        engines(store, arguments.rows)  # last: it gives touch-rf its twin, which live takes


if __name__ == "__main__":
    main()
