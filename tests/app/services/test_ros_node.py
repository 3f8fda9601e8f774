"""``touchbench ros`` on a real ROS 1 graph: a rosmaster of the test's own on a free port,
a peer node publishing a simulated contact-mic session as audio_common AudioData, and the
node under test as a subprocess; the touches it publishes are those ``live --replay``
prints for the same audio, with the model itself or with its ONNX twin."""

from __future__ import annotations

import json
import shutil
import signal
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
import soundfile

from tests.support.cli_runner import run_cli
from tests.support.ros_peer import Peer, rosmaster
from touchbench.app.schemas.extraction import ExtractRequest
from touchbench.app.schemas.models import ExportRequest, TrainRequest
from touchbench.app.services.export import export_model
from touchbench.app.services.extraction import extract_and_store
from touchbench.app.services.live import open_live
from touchbench.app.services.models import train
from touchbench.app.services.simulation import write_contact_mic_sessions, write_session
from touchbench.app.store.database import Store
from touchbench.drivers.ros1 import DEBIAN_PACKAGES

ROS_MISSING = shutil.which("rosmaster") is None or not Path(DEBIAN_PACKAGES, "rospy").is_dir()
pytestmark = pytest.mark.skipif(
    ROS_MISSING,
    reason="ROS 1 is not installed (Debian's ros-core, python3-rospy, python3-genpy: "
    "scripts/install.sh installs them)",
)

#: Seconds a step may take before the test gives up (not a timing assertion; a loaded
#: machine starts a Python process with scikit-learn slowly).
PATIENCE = 180.0


@pytest.fixture(scope="module")
def ros_env(tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict[str, str]]:
    """The environment of nodes on a rosmaster started for these tests."""
    with rosmaster(str(tmp_path_factory.mktemp("ros")), patience=PATIENCE) as env:
        yield env


@pytest.fixture(scope="module")
def trained(tmp_path_factory: pytest.TempPathFactory) -> tuple[str, str, Path]:
    """A store URL, a model trained on simulated sessions (with its ONNX twin), and a
    session it never saw."""
    folder = tmp_path_factory.mktemp("sessions")
    url = f"sqlite:///{folder / 'touchbench.db'}"
    store = Store(url)
    try:
        recordings, labels = write_contact_mic_sessions(folder, trials=2, n_touches=8)
        extract_and_store(store, ExtractRequest(recordings=recordings, labels=labels, name="touch"))
        model = train(store, TrainRequest(dataset="touch", classifier="cc:rf"))
        export_model(store, ExportRequest(model=model.name))
    finally:
        store.dispose()
    unseen, _ = write_session(folder, "unseen", n_touches=5, seed=99)
    return url, model.name, unseen


def start_node(env: dict[str, str], url: str, *args: str) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "touchbench.app.cli.main", "--db", url, "ros", *args],
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def stop(process: subprocess.Popen[str]) -> tuple[int, str, str]:
    process.send_signal(signal.SIGINT)
    out, err = process.communicate(timeout=PATIENCE)
    return process.returncode, out, err


@pytest.mark.parametrize(("kind", "engine"), [("audio", "native"), ("taxels", "onnx")])
def test_the_node_publishes_the_touches_live_replay_prints(
    kind: str,
    engine: str,
    ros_env: dict[str, str],
    trained: tuple[str, str, Path],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """The session cut short in the middle of its last touch, so that touch is still open
    when the stream stops: ``live`` prints it at the end of the file, the node when
    interrupted.  As taxels, the same samples as Float32MultiArray blocks, predicted by the
    model's ONNX twin: its labels are the model's, its probabilities within 1e-5."""
    url, model, unseen = trained
    samples, rate = soundfile.read(unseen, dtype="float32", always_2d=True)
    native = ("--engine", "native")
    whole = run_cli(
        capsys, url, "live", "--model", model, "--replay", str(unseen), "--json", *native
    )
    assert whole.code == 0, whole.err
    last = json.loads(whole.out.splitlines()[-1])
    samples = samples[: int((last["start"] + last["end"]) / 2 * rate)]
    cut = tmp_path / "cut.wav"
    soundfile.write(cut, samples, int(rate), subtype="FLOAT")
    replay = run_cli(capsys, url, "live", "--model", model, "--replay", str(cut), "--json", *native)
    expected = [json.loads(line) for line in replay.out.splitlines()]
    store = Store(url)
    try:  # the touches that come out while the stream flows: all but the last
        session = open_live(store, model, samplerate=rate, n_channels=3, engine="native")
        blocks = [samples[i : i + 512].T.astype(np.float64) for i in range(0, len(samples), 512)]
        while_streaming = sum(len(session.feed(block)) for block in blocks)
    finally:
        store.dispose()
    assert len(expected) == 5 and while_streaming == 4, (len(expected), while_streaming)
    np.save(tmp_path / "audio.npy", samples.T)

    topic = ("--audio-topic" if kind == "audio" else "--taxel-topic", "/mic/signal")
    node = start_node(ros_env, url, "--model", model, *topic, "--engine", engine)
    peer_options = ("--info", "/mic/audio_info") if kind == "audio" else ("--taxels",)
    peer = Peer(
        ros_env,
        str(tmp_path / "audio.npy"),
        *("--topic", "/mic/signal", *peer_options),
        patience=PATIENCE,
    )
    try:
        peer.until(lambda: bool(peer.sent) and len(peer.touches) >= while_streaming)
        code, _, err = stop(node)
        peer.until(lambda: len(peer.touches) >= len(expected))
    finally:
        if node.poll() is None:
            node.kill()
        peer.close()
    assert code == 130, err
    assert err.strip().splitlines()[-1] == "touchbench: interrupted"
    assert "Traceback" not in err
    got = [line["touch"] for line in peer.touches]
    for touch, wanted in zip(got, expected, strict=True):
        assert touch["predictions"].keys() == wanted["predictions"].keys()
        for target, answer in touch["predictions"].items():
            assert answer["value"] == wanted["predictions"][target]["value"]
            probability = wanted["predictions"][target]["probability"]
            assert answer["probability"] == pytest.approx(probability, abs=1e-5)
    assert [(t["start"], t["end"]) for t in got] == [(t["start"], t["end"]) for t in expected]
    assert all(t["latency_ms"] >= 0 for t in got)
