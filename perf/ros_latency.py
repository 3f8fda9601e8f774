"""The ROS node's latency per touch: from the end of a touch's audio message to its
published prediction.

Run from the repository root (ROS 1 installed, as scripts/install.sh does)::

    .venv/bin/python perf/ros_latency.py [--touches 40] [--block 512] [--core 0]
                                         [--engines native,onnx] [--rounds 2]

A random forest (``cc:rf``, 100 trees per target) is trained on the ``uc3m-audio``
features of simulated 3-microphone sessions (44.1 kHz).  A rosmaster of its own is
started on a free port, ``touchbench ros`` runs pinned to one core (``taskset``), and a
peer node (tests/support/ros_peer.py, on the other cores) publishes a fresh session as
``AudioData`` messages of ``--block`` samples (F32LE, described by a latched
``AudioInfo``), paced in real time as a microphone would, and listens to ``/touch``.

Which message completes each touch is known beforehand: the same session fed in the same
blocks through :class:`app.services.live.LiveSession` in this process says after which
block each touch comes out (touches only the end of the stream closes are left out).
The latency of a touch is then the peer's clock when the prediction arrived minus its
clock when the publish of that message returned (``time.perf_counter``, one monotonic
clock for every process of the machine): the whole path, ROS both ways included.  Beside
it, the computing alone in this process (``LiveSession.feed`` of that block: detection,
extraction, prediction), so the difference is what ROS and the node's loop add.
Goal: p99 under 20 ms on one core.  Each engine (``--engine`` of ``touchbench ros``: the
model itself, or its ONNX twin written by ``export-model``) is measured in turn, the
engines alternating for ``--rounds`` rounds, since this machine's speed drifts.

Not a test: nothing is asserted.
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np
import soundfile

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from tests.support.ros_peer import Peer
from tests.support.ros_peer import rosmaster
from touchbench.app.schemas.extraction import ExtractRequest
from touchbench.app.schemas.models import Engine, ExportRequest, TrainRequest
from touchbench.app.services.export import export_model
from touchbench.app.services.extraction import extract_and_store
from touchbench.app.services.live import open_live
from touchbench.app.services.models import train
from touchbench.app.services.simulation import write_contact_mic_sessions, write_session
from touchbench.app.store.database import Store

PATIENCE = 300.0


def percentiles(values: list[float]) -> str:
    p50, p99 = np.percentile(values, [50, 99])
    return f"p50 {p50:7.2f} ms   p99 {p99:7.2f} ms   max {max(values):7.2f} ms   (n={len(values)})"


def measure(
    url: str, model: str, engine: Engine, samples: np.ndarray, rate: float, folder: Path, args: Any
) -> dict[str, list[float]]:
    """One round of one engine: the computing alone in this process, then the node."""
    store = Store(url)
    try:  # after which message each touch comes out, and the computing alone
        live = open_live(store, model, samplerate=rate, n_channels=samples.shape[1], engine=engine)
        trigger, computing = [], []
        for index, begin in enumerate(range(0, len(samples), args.block)):
            block = samples[begin : begin + args.block].T.astype(np.float64)
            start = time.perf_counter()
            touches = live.feed(block)
            elapsed = 1000 * (time.perf_counter() - start)
            for _ in touches:
                trigger.append(index)
                computing.append(elapsed)
    finally:
        store.dispose()

    with rosmaster(str(folder / f"ros-{engine}"), patience=PATIENCE) as env:
        cores = sorted(os.sched_getaffinity(0))
        others = [c for c in cores if c != args.core] or cores
        node = subprocess.Popen(
            [
                *("taskset", "-c", str(args.core)),
                *(sys.executable, "-m", "touchbench.app.cli.main", "--db", url, "ros"),
                *("--model", model, "--audio-topic", "/mic/audio", "--engine", engine),
            ],
            env=env,
            stderr=subprocess.PIPE,
            text=True,
        )
        peer = Peer(
            {**env, "OMP_NUM_THREADS": "1"},
            str(folder / "audio.npy"),
            *("--topic", "/mic/audio", "--info", "/mic/audio_info", "--pace"),
            *("--chunk", str(args.block)),
            patience=PATIENCE,
        )
        os.sched_setaffinity(peer.process.pid, others)
        try:
            peer.until(lambda: bool(peer.sent) and len(peer.touches) >= len(trigger))
        finally:
            node.send_signal(signal.SIGINT)
            node.communicate(timeout=PATIENCE)
            peer.close()
    heard = peer.touches[: len(trigger)]
    return {
        "ros": [1000 * (t["received"] - peer.sent[i]) for t, i in zip(heard, trigger, strict=True)],
        "computing": computing,
        "reported": [t["touch"]["latency_ms"] for t in heard],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--touches", type=int, default=40, help="Touches of the session.")
    parser.add_argument("--block", type=int, default=512, help="Samples per message.")
    parser.add_argument("--core", type=int, default=0, help="The node's core.")
    parser.add_argument("--engines", default="native,onnx", help="Engines, comma-separated.")
    parser.add_argument("--rounds", type=int, default=2, help="Rounds of every engine.")
    args = parser.parse_args()
    engines: list[Engine] = args.engines.split(",")
    if shutil.which("rosmaster") is None:
        sys.exit("ROS 1 is not installed: bash scripts/install.sh")
    load = ", ".join(f"{value:.1f}" for value in os.getloadavg())
    print(f"Machine load average (1, 5, 15 min): {load} on {os.cpu_count()} cores")
    figures: dict[str, dict[str, list[float]]] = {
        engine: {"ros": [], "computing": [], "reported": []} for engine in engines
    }
    with tempfile.TemporaryDirectory() as folder_name:
        folder = Path(folder_name)
        url = f"sqlite:///{folder / 'touchbench.db'}"
        store = Store(url)
        try:
            recordings, labels = write_contact_mic_sessions(folder, trials=3, n_touches=10)
            extract_and_store(store, ExtractRequest(recordings=recordings, labels=labels, name="t"))
            model = train(store, TrainRequest(dataset="t", classifier="cc:rf")).name
            if "onnx" in engines:
                export_model(store, ExportRequest(model=model))
        finally:
            store.dispose()
        session_path, _ = write_session(folder, "fresh", n_touches=args.touches, seed=1234)
        samples, rate = soundfile.read(session_path, dtype="float32", always_2d=True)
        np.save(folder / "audio.npy", samples.T)
        for _ in range(args.rounds):
            for engine in engines:
                for key, values in measure(url, model, engine, samples, rate, folder, args).items():
                    figures[engine][key] += values
    load = ", ".join(f"{value:.1f}" for value in os.getloadavg())
    print(f"Machine load average at the end: {load}")
    print(
        f"touchbench ros, cc:rf on uc3m-audio, {args.touches} touches a round, {args.rounds} "
        f"round(s), messages of {args.block} samples ({1000 * args.block / rate:.1f} ms), "
        f"node on core {args.core}"
    )
    for engine in engines:
        measured = figures[engine]
        print(f"engine {engine}:")
        rows = (
            ("end of the touch's message -> prediction heard (ROS both ways)", "ros"),
            ("computing alone (LiveSession.feed of that block, in-process)", "computing"),
            ("latency_ms the node reports (from the event's last sample)", "reported"),
        )
        for title, key in rows:
            print(f"  {title:64s} {percentiles(measured[key])}")
        overhead = np.percentile(measured["ros"], 50) - np.percentile(measured["computing"], 50)
        print(f"  what ROS and the node's loop add at p50: {overhead:.2f} ms")


if __name__ == "__main__":
    main()
