"""ROS bags through `touchbench extract`: real ROS 1 and ROS 2 bags written with rosbags'
own writers, read back for their audio; and the bags it must refuse."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import soundfile

from tests.support.bagfiles import (
    BIOTAC_MSG,
    BIOTAC_TYPE,
    encode,
    float_array,
    mp3_stream,
    pieces,
    write_audio_bag,
    write_fields_bag,
    write_other_audio_bag,
)
from tests.support.cli_runner import run_cli
from touchbench.app.store.database import Store
from touchbench.app.store.datasets import load_dataset
from touchbench.drivers.simulated import SimulatedTouch, simulate_session

RATE = 44100
DELAY = 0.25  # the audio starts this long after the bag's first message


@pytest.fixture(scope="module")
def session() -> np.ndarray:
    touches = [
        SimulatedTouch(0.8, 0.05, (0,), "tap", 0.3),
        SimulatedTouch(2.4, 0.6, (1, 2), "stroke", 0.2),
    ]
    return simulate_session(duration=4.0, n_channels=3, touches=touches, seed=5).recording.samples


def _labels(folder: Path, name: str) -> Path:
    # Seconds from the bag's first message: the touches' times plus the audio's delay.
    path = folder / "labels.csv"
    path.write_text(
        "file,start,end,gesture\n"
        f"{name},{0.7 + DELAY},{1.5 + DELAY},tap\n{name},{2.3 + DELAY},{3.6 + DELAY},stroke\n"
    )
    return path


@pytest.mark.parametrize(
    ("suffix", "options"),
    [
        (".bag", {}),
        (".mcap", {"stamped": True}),
        (".db3", {"with_definitions": False, "sample_format": "S32LE"}),
        (".mcap", {"sample_format": "F32LE", "message_samples": 4410}),
    ],
)
def test_extract_reads_the_audio_of_ros1_and_ros2_bags(
    capsys: pytest.CaptureFixture[str],
    store_url: str,
    tmp_path: Path,
    session: np.ndarray,
    suffix: str,
    options: dict,
) -> None:
    sample_format = options.get("sample_format", "S16LE")
    bag = write_audio_bag(tmp_path / f"robot{suffix}", session, RATE, **options)
    labels = _labels(tmp_path, bag.name)
    result = run_cli(
        capsys, store_url, "extract", str(bag), "--labels", str(labels), "--name", "bag", "--json"
    )
    assert result.code == 0, result.err
    summary = result.json()
    assert (summary["events_found"], summary["events_labelled"]) == (2, 2)

    # The same samples, as the bag carries them, from a WAV: the same features.
    dtype_samples = encode(session, sample_format).view(
        {"S16LE": "<i2", "S32LE": "<i4", "F32LE": "<f4"}[sample_format]
    )
    scale = {"S16LE": 32768.0, "S32LE": 2147483648.0, "F32LE": 1.0}[sample_format]
    wav = tmp_path / "same.wav"
    soundfile.write(wav, dtype_samples.reshape(-1, 3) / scale, RATE, subtype="DOUBLE")
    assert run_cli(capsys, store_url, "extract", str(wav), "--name", "wav").code == 0
    store = Store(store_url)
    try:
        from_bag, from_wav = load_dataset(store, "bag"), load_dataset(store, "wav")
    finally:
        store.dispose()
    assert np.array_equal(from_bag.X, from_wav.X)
    assert from_bag.meta is not None and from_wav.meta is not None
    starts = [m["start"] for m in from_bag.meta]
    assert starts == pytest.approx([m["start"] + DELAY for m in from_wav.meta])
    assert from_bag.schema.targets[0].values == ("tap", "stroke")


def test_bags_touchbench_cannot_use_exit_2_and_store_nothing(
    capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path, session: np.ndarray
) -> None:
    short = session[:, :8820]
    no_audio = write_audio_bag(tmp_path / "quiet.mcap", short, RATE, topic=None)
    not_mp3 = write_audio_bag(tmp_path / "mp3.bag", short, RATE, coding_format="mp3")
    flac = write_audio_bag(tmp_path / "flac.bag", short, RATE, coding_format="flac")
    no_info = write_audio_bag(tmp_path / "noinfo.db3", short, RATE, info_topic=None)
    good = write_audio_bag(tmp_path / "good.bag", session, RATE)
    truncated = tmp_path / "truncated.bag"
    truncated.write_bytes(good.read_bytes()[: good.stat().st_size // 2])
    other = write_other_audio_bag(tmp_path / "other.mcap")
    cases = [
        ([str(no_audio)], "no audio topic"),
        (
            [str(good), "--topic", "/mic"],
            "no topic '/mic'; its topics: /audio/audio (audio_common_msgs/msg/AudioData), ",
        ),
        (
            [str(good), "--topic", "/status"],
            "topic '/status' (std_msgs/msg/String) has no numeric field; its fields: data (string)",
        ),
        ([str(not_mp3)], "'/audio/audio': cannot decode as MP3"),
        ([str(flac)], "carries flac-coded audio; touchbench reads raw PCM (coding_format wave)"),
        (
            [str(no_info)],
            "no AudioInfo topic and the audio of '/audio/audio' is not MP3, so its format is "
            "unknown: give `samplerate`, `channels`, `sample_format` of the raw PCM",
        ),
        (
            [str(no_info), "--samplerate", "44100", "--sample-format", "s16le"],
            "format is unknown: give `channels` of the raw PCM",
        ),
        ([str(truncated)], "truncated.bag: cannot read"),
        ([str(other)], "no audio topic"),
        ([str(other), "--topic", "/audio"], "at least two are needed for a sample rate"),
    ]
    for args, expected in cases:
        result = run_cli(capsys, store_url, "extract", *args)
        assert result.code == 2, (args, result.err)
        assert len(result.err.strip().splitlines()) == 1, result.err
        assert expected in result.err, result.err
    assert run_cli(capsys, store_url, "datasets", "--json").json() == {"datasets": []}


def test_a_bag_without_audio_definitions_really_lacks_them(tmp_path: Path) -> None:
    from rosbags.rosbag2 import Reader

    folder = write_audio_bag(
        tmp_path / "old.db3", np.zeros((1, 2048)), RATE, with_definitions=False
    )
    with Reader(folder) as reader:
        formats = {c.msgtype: c.msgdef.format.name for c in reader.connections}
    assert formats["audio_common_msgs/msg/AudioData"] == "NONE"
    assert formats["std_msgs/msg/String"] != "NONE"


@pytest.fixture(scope="module")
def stereo() -> np.ndarray:
    """Two channels (MP3 holds at most two) with a tap and a stroke."""
    touches = [
        SimulatedTouch(0.8, 0.05, (0,), "tap", 0.3),
        SimulatedTouch(2.4, 0.6, (0, 1), "stroke", 0.2),
    ]
    return simulate_session(duration=4.0, n_channels=2, touches=touches, seed=7).recording.samples


@pytest.mark.parametrize(("suffix", "info_topic"), [(".bag", "/audio/audio_info"), (".mcap", None)])
def test_extract_reads_audio_captures_mp3_bags(
    capsys: pytest.CaptureFixture[str],
    store_url: str,
    tmp_path: Path,
    stereo: np.ndarray,
    suffix: str,
    info_topic: str | None,
) -> None:
    stream = mp3_stream(stereo, RATE, variable=True)
    bag = write_audio_bag(
        tmp_path / f"robot{suffix}",
        stereo,
        RATE,
        coding_format="mp3",
        payloads=pieces(stream, 1000),
        info_topic=info_topic,
    )
    labels = _labels(tmp_path, bag.name)
    result = run_cli(capsys, store_url, "extract", str(bag), "--labels", str(labels), "--json")
    assert result.code == 0, result.err
    summary = result.json()
    assert (summary["events_found"], summary["events_labelled"]) == (2, 2)
    notes = [w for w in summary["notes"] if "no AudioInfo topic" in w]
    assert len(notes) == (info_topic is None)


def test_extract_reads_raw_pcm_without_audio_info_given_its_format(
    capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path, session: np.ndarray
) -> None:
    described = write_audio_bag(tmp_path / "described.bag", session, RATE, sample_format="S32LE")
    bare = write_audio_bag(
        tmp_path / "bare.mcap", session, RATE, sample_format="S32LE", info_topic=None
    )
    assert run_cli(capsys, store_url, "extract", str(described), "--name", "described").code == 0
    options = ["--samplerate", "44100", "--channels", "3", "--sample-format", "s32le"]
    result = run_cli(capsys, store_url, "extract", str(bare), *options, "--name", "bare")
    assert result.code == 0, result.err
    store = Store(store_url)
    try:
        assert np.array_equal(load_dataset(store, "bare").X, load_dataset(store, "described").X)
    finally:
        store.dispose()


def test_extract_reads_numeric_fields_of_tactile_topics(
    capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path
) -> None:
    rng = np.random.default_rng(8)
    bags = []
    for take, offset in (("press", 1.0), ("slide", -1.0)):
        received = 0.2 + np.cumsum(rng.uniform(0.006, 0.014, 120))
        messages = [
            {
                "stamp": 1_700_000_000 * 10**9 + round(t * 1e9),
                "pdc": 2000 + round(100 * offset * t),
                "tdc": 5,
                "pac": np.zeros(22, dtype=np.int16),
                "electrodes": np.full(19, 100 + 10 * offset, dtype=np.uint16),
                "sensor": "left",
            }
            for t in received
        ]
        bags.append(
            write_fields_bag(
                tmp_path / f"{take}.bag",
                msgtype=BIOTAC_TYPE,
                definition=BIOTAC_MSG,
                messages=messages,
                received=received + 0.003,
                topic="/biotac",
            )
        )
    labels = tmp_path / "labels.csv"
    labels.write_text("file,gesture\npress.bag,press\nslide.bag,slide\n")
    result = run_cli(
        capsys,
        store_url,
        "extract",
        *map(str, bags),
        "--labels",
        str(labels),
        "--topic",
        "/biotac",
        "--fields",
        "pdc,electrodes",
        "--fields",
        "tdc",
        "-e",
        "window",
        "--events",
        "none",
        "--name",
        "biotac",
        "--json",
    )
    assert result.code == 0, result.err
    summary = result.json()
    assert summary["n_features"] == 25 * (1 + 19 + 1)
    # the fields name the channels, as a CSV header does: never ch1, ch2, ...
    store = Store(store_url)
    try:
        names = list(load_dataset(store, "biotac").schema.feature_names)
    finally:
        store.dispose()
    assert names[:3] == ["t0_pdc", "t1_pdc", "t2_pdc"]
    assert {"t0_electrodes[0]", "t24_electrodes[18]", "t24_tdc"} <= set(names)
    assert summary["events_labelled"] == 2
    jitter = [w for w in summary["notes"] if "stamps of '/biotac' are uneven" in w]
    assert [w.split(":")[0] for w in jitter] == ["press.bag", "slide.bag"]
    # Each bag's stamps have their own median rate; the second goes on the first's grid.
    grids = {w.split("resampled onto an even ")[1] for w in jitter}
    assert len(grids) == 1, jitter

    taxels = write_fields_bag(
        tmp_path / "skin.mcap",
        msgtype="std_msgs/msg/Float32MultiArray",
        messages=[float_array(rng.normal(size=16)) for _ in range(100)],
        received=np.arange(100) / 100,
        topic="/tactile",
    )
    result = run_cli(
        capsys, store_url, "extract", str(taxels), "--topic", "/tactile", "-e", "window",
        "--events", "none", "--json",
    )  # fmt: skip
    assert result.code == 0, result.err
    assert result.json()["n_features"] == 25 * 16


def test_bag_options_touchbench_refuses_exit_2(
    capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path
) -> None:
    received = np.arange(50) / 100
    bag = write_fields_bag(
        tmp_path / "skin.bag",
        msgtype="std_msgs/msg/Float32MultiArray",
        messages=[float_array(np.zeros(4)) for _ in received],
        received=received,
        topic="/tactile",
    )
    wav = tmp_path / "take.wav"
    soundfile.write(wav, np.zeros((4410, 1)), RATE)
    cases = [
        (["--fields", "data"], "--fields: needs --topic: the bag topic the fields belong to"),
        (["--sample-format", "U8"], "--sample-format: Input should be 'S16LE', 'S32LE' or"),
        (["--channels", "0"], "--channels: Input should be greater than or equal to 1"),
        (["--topic", "/skin"], "no topic '/skin'; its topics: /status (std_msgs/msg/String), "),
        (["--topic", "/tactile", "--fields", "layout.dim"], "field 'layout.dim' is an array of"),
        (["--topic", "/tactile", "--fields", "size"], "has no field 'size' (in 'size'); its"),
    ]
    for options, expected in cases:
        result = run_cli(capsys, store_url, "extract", str(bag), *options)
        assert result.code == 2, (options, result.err)
        assert len(result.err.strip().splitlines()) == 1, result.err
        assert expected in result.err, result.err
    result = run_cli(capsys, store_url, "extract", str(wav), "--channels", "1")
    assert result.code == 2 and "`channels` applies to ROS bags only" in result.err
    assert run_cli(capsys, store_url, "datasets", "--json").json() == {"datasets": []}
