"""The sound-card path for real: PortAudio capturing through ALSA's file plugin.

This machine has no sound card, so each test writes an ``.asoundrc`` in a temporary
HOME that defines a capture device ``replay``: ALSA's ``file`` plugin reading a raw
S16_LE file (``infile``) over a ``null`` device.  PortAudio lists it and captures the
file's samples, so ``devices``, ``record`` and ``live --device`` run as they would on a
robot, in real processes (PortAudio reads the ALSA configuration once per process).
Only the test of a missing PortAudio library hides the library from ``sounddevice``.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import soundfile

from tests.support.cli_runner import run_cli
from touchbench.app.services.simulation import write_labels, write_session

ROOT = Path(__file__).resolve().parents[3]
RATE = 44100


def _asoundrc(home: Path, raw: Path) -> None:
    home.mkdir(parents=True, exist_ok=True)
    (home / ".asoundrc").write_text(
        'pcm.replay {\n  type file\n  slave.pcm "nullcap"\n  file "/dev/null"\n'
        f'  infile "{raw}"\n  format "raw"\n}}\npcm.nullcap {{ type null }}\n'
    )


def _write_raw(path: Path, samples: np.ndarray) -> np.ndarray:
    """(channels, n) samples as interleaved S16_LE; returns what capture will read back."""
    quantised = np.clip(np.round(samples * 32768), -32768, 32767).astype("<i2")
    quantised.T.tofile(path)
    return quantised / 32768.0


def _touchbench(
    home: Path, db: str, *args: str, timeout: float = 120
) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "touchbench.app.cli.main", "--db", db, *args],
        capture_output=True,
        text=True,
        timeout=timeout,
        env={**os.environ, "HOME": str(home), "PYTHONPATH": str(ROOT)},
        check=False,
    )


@pytest.fixture
def device(tmp_path: Path) -> tuple[Path, np.ndarray]:
    """HOME with a ``replay`` device capturing a 3-channel simulated touch session."""
    wav, _ = write_session(tmp_path, "heard", n_touches=3, seed=11)
    samples, _ = soundfile.read(wav, always_2d=True)
    home = tmp_path / "home"
    raw = tmp_path / "heard.s16"
    _asoundrc(home, raw)
    return home, _write_raw(raw, samples.T)


def test_devices_lists_the_alsa_replay_device(
    device: tuple[Path, np.ndarray], tmp_path: Path
) -> None:
    home, _ = device
    result = _touchbench(home, f"sqlite:///{tmp_path / 'x.db'}", "devices", "--json")
    assert result.returncode == 0, result.stderr
    devices = {d["name"]: d for d in json.loads(result.stdout)["devices"]}
    assert devices["replay"]["input_channels"] >= 3
    assert devices["replay"]["default_samplerate"] > 0


def test_capture_returns_the_raw_file_samples(device: tuple[Path, np.ndarray]) -> None:
    home, expected = device
    script = (
        "import numpy as np\n"
        "from touchbench.drivers.sound import SoundDeviceSource\n"
        "with SoundDeviceSource('replay', samplerate=44100, channels=3, seconds=2.0) as s:\n"
        "    blocks = list(s.blocks())\n"
        "x = np.concatenate([b.samples for b in blocks], axis=1)\n"
        "print(x.shape[1], s.overflows, all(b.arrived is not None for b in blocks))\n"
        "np.save('captured.npy', x)\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", script],
        capture_output=True,
        text=True,
        cwd=home,
        env={**os.environ, "HOME": str(home), "PYTHONPATH": str(ROOT)},
        timeout=60,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    count, overflows, stamped = result.stdout.split()
    assert (int(count), overflows, stamped) == (2 * RATE, "0", "True")
    captured = np.load(home / "captured.npy")
    assert np.array_equal(captured, expected[:, : 2 * RATE])


def test_record_writes_labelled_takes_that_extract_reads(
    capsys: pytest.CaptureFixture[str], device: tuple[Path, np.ndarray], tmp_path: Path
) -> None:
    home, expected = device
    db = f"sqlite:///{tmp_path / 'rec.db'}"
    out = tmp_path / "session"
    # The null device under the file plugin is not paced: it delivers as fast as it can,
    # so a take longer than the queue (5 s) could lose blocks when the consumer lags.
    seconds = 4.0
    for gesture in ("tap", "stroke"):
        result = _touchbench(
            home,
            db,
            "record",
            "--device",
            "replay",
            "--channels",
            "3",
            "--samplerate",
            "44100",
            "--seconds",
            f"{seconds:.2f}",
            "--out",
            str(out),
            "--label",
            f"gesture={gesture}",
            "--label",
            "robot=mini",
        )
        assert result.returncode == 0, result.stderr
        assert "touch" in result.stderr and "labelled in" in result.stderr
    assert (out / "labels.csv").read_text() == (
        "file,gesture,robot\ntake-001.wav,tap,mini\ntake-002.wav,stroke,mini\n"
    )
    take, rate = soundfile.read(out / "take-001.wav", always_2d=True)
    assert rate == RATE and np.array_equal(take.T, expected[:, : take.shape[0]])
    assert take.shape[0] == round(seconds * RATE)
    reference = tmp_path / "reference.wav"
    soundfile.write(reference, take, RATE, subtype="FLOAT")
    alone = run_cli(capsys, db, "extract", str(reference), "--json").json()
    summary = run_cli(
        capsys,
        db,
        "extract",
        str(out / "take-001.wav"),
        str(out / "take-002.wav"),
        "--labels",
        str(out / "labels.csv"),
        "--json",
    ).json()
    assert alone["events_found"] >= 1
    assert summary["events_found"] == 2 * alone["events_found"]
    assert summary["targets"] == ["gesture", "robot"]
    clash = _touchbench(
        home,
        db,
        "record",
        "--device",
        "replay",
        "--seconds",
        "0.1",
        "--out",
        str(out),
        "--label",
        "place=head",
    )
    assert clash.returncode == 2 and "labels takes with gesture,robot" in clash.stderr


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--device", "no-such-card"], "no capture device 'no-such-card'"),
        (["--device", "replay", "--samplerate", "100"], "refuses 3 channel(s) at 100 Hz"),
        (["--device", "replay", "--channels", "500"], "refuses 500 channel(s)"),
    ],
)
def test_devices_and_settings_that_do_not_exist_are_one_line(
    device: tuple[Path, np.ndarray], tmp_path: Path, args: list[str], message: str
) -> None:
    home, _ = device
    extra = ["--channels", "3"] if "--channels" not in args else []
    result = _touchbench(
        home,
        f"sqlite:///{tmp_path / 'x.db'}",
        "record",
        *args,
        *extra,
        "--seconds",
        "1",
        "--out",
        str(tmp_path / "never"),
    )
    assert result.returncode == 2
    assert result.stderr.strip().count("\n") == 0, result.stderr
    assert message in result.stderr
    assert not (tmp_path / "never").exists()


def test_ctrl_c_keeps_the_take_so_far_and_a_valid_labels_file(
    device: tuple[Path, np.ndarray], tmp_path: Path
) -> None:
    home, _ = device
    out = tmp_path / "session"
    process = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "touchbench.app.cli.main",
            "--db",
            f"sqlite:///{tmp_path / 'x.db'}",
            "record",
            "--device",
            "replay",
            "--channels",
            "3",
            "--seconds",
            "100000",
            "--out",
            str(out),
            "--label",
            "gesture=tap",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        # faulthandler: a process that does not stop prints every thread's stack at SIGABRT
        env={**os.environ, "HOME": str(home), "PYTHONPATH": str(ROOT), "PYTHONFAULTHANDLER": "1"},
        # A job started in the background inherits SIGINT ignored; a terminal's is not.
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    part = out / "take-001.wav.part"
    deadline = time.monotonic() + 60
    while not (part.exists() and part.stat().st_size > 100_000) and time.monotonic() < deadline:
        time.sleep(0.05)
    process.send_signal(signal.SIGINT)
    try:
        _, err = process.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        process.send_signal(signal.SIGABRT)
        _, stacks = process.communicate(timeout=30)
        pytest.fail(f"record did not stop within 60 s of Ctrl-C; its threads:\n{stacks}")
    assert process.returncode == 2, err
    # Touches heard before the Ctrl-C are shown as they end; the outcome is one line.
    errors = [line for line in err.splitlines() if not line.startswith("touch ")]
    assert len(errors) == 1 and "interrupted by Ctrl-C; the take so far is kept" in errors[0]
    take, rate = soundfile.read(out / "take-001.wav", always_2d=True)
    assert rate == RATE and take.shape[1] == 3 and take.shape[0] > 0
    assert (out / "labels.csv").read_text() == "file,gesture\ntake-001.wav,tap\n"
    assert not part.exists()


def test_live_on_the_device_predicts_what_live_on_the_file_predicts(
    capsys: pytest.CaptureFixture[str], device: tuple[Path, np.ndarray], tmp_path: Path
) -> None:
    home, expected = device
    db = f"sqlite:///{tmp_path / 'live.db'}"
    recordings, rows = [], []
    for seed in range(3):
        wav, touches = write_session(tmp_path, f"train{seed}", n_touches=12, seed=seed)
        recordings.append(str(wav))
        rows += [(wav.name, *touch) for touch in touches]
    labels = write_labels(tmp_path / "labels.csv", rows)
    assert (
        run_cli(capsys, db, "extract", *recordings, "--labels", str(labels), "--name", "touch").code
        == 0
    )
    assert (
        run_cli(capsys, db, "train", "touch", "--classifier", "j48", "--target", "gesture").code
        == 0
    )
    same = tmp_path / "same.wav"  # 4.5 s: within the capture queue (see the record test)
    soundfile.write(same, expected[:, : round(4.5 * RATE)].T, RATE, subtype="PCM_16")
    seconds = "4.5"
    from_device = _touchbench(
        home,
        db,
        "live",
        "--model",
        "touch-j48",
        "--device",
        "replay",
        "--seconds",
        seconds,
        "--json",
    )
    assert from_device.returncode == 0, from_device.stderr
    from_file = run_cli(capsys, db, "live", "--model", "touch-j48", "--replay", str(same), "--json")
    assert from_file.code == 0, from_file.err

    def touches(text: str) -> list[tuple[float, float, str]]:
        lines = [json.loads(line) for line in text.splitlines()]
        return [(t["start"], t["end"], t["predictions"]["gesture"]["value"]) for t in lines]

    assert len(touches(from_file.out)) >= 2
    assert touches(from_device.stdout) == touches(from_file.out)


def test_a_missing_portaudio_is_one_line_that_names_the_package(tmp_path: Path) -> None:
    script = (
        "import ctypes.util, sys\n"
        "ctypes.util.find_library = lambda name: None  # as on a machine without it\n"
        "from touchbench.app.cli.main import main\n"
        f"sys.exit(main(['--db', 'sqlite:///{tmp_path / 'x.db'}', 'devices']))\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", script],
        capture_output=True,
        text=True,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        timeout=60,
        check=False,
    )
    assert result.returncode == 2
    assert result.stderr.strip().count("\n") == 0
    assert "PortAudio is not installed" in result.stderr and "libportaudio2" in result.stderr
