"""Live prediction: the model's own recipe on a stream gives the training features."""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
import soundfile

from tests.support.cli_runner import run_cli
from tests.support.recordings import extract_sessions
from touchbench.app.errors import AppError
from touchbench.app.schemas.extraction import ExtractRequest
from touchbench.app.schemas.models import TrainRequest
from touchbench.app.services.extraction import extract_and_store, extract_dataset
from touchbench.app.services.live import LiveSession, open_live
from touchbench.app.services.loading import load_model
from touchbench.app.services.models import predict, train
from touchbench.app.services.simulation import write_labels, write_session
from touchbench.app.store.database import Store
from touchbench.drivers.replay import FileReplaySource


@pytest.fixture(scope="module")
def trained(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[Store, str, Path]]:
    """A store (SQLite) with a model trained on extracted sessions, the model's name, and a
    session it never saw; made once for the module's tests, which only read them."""
    folder = tmp_path_factory.mktemp("live")
    store = Store(f"sqlite:///{folder / 'touchbench.db'}")
    extract_sessions(store, folder, sessions=3, touches=10)
    model = train(store, TrainRequest(dataset="touch", classifier="cc:rf"))
    unseen, _ = write_session(folder, "unseen", n_touches=6, seed=99)
    yield store, model.name, unseen
    store.dispose()


def test_live_predicts_what_predict_says_of_the_extracted_instances(
    trained: tuple[Store, str, Path],
) -> None:
    sqlite_store, name, unseen = trained
    offline = extract_dataset([unseen], labels=None, extractor="uc3m-audio").dataset
    _, model = load_model(sqlite_store, name)
    expected = predict(model, offline)
    with FileReplaySource(unseen, block_length=512) as source:
        session = open_live(sqlite_store, name, samplerate=source.samplerate, n_channels=3)
        touches = [t for b in source.blocks() for t in session.feed(b.samples, b.time)]
        touches += session.finish()
    assert len(touches) == offline.n_instances == 6
    assert offline.meta is not None
    assert [t.start for t in touches] == pytest.approx([m["start"] for m in offline.meta])
    for target in ("gesture", "place"):
        assert [t.predictions[target][0] for t in touches] == expected.labels[target]
    assert all(0 < t.predictions["gesture"][1] <= 1 for t in touches)  # type: ignore[operator]
    line = touches[0].to_json()
    assert set(line) == {"start", "end", "predictions", "latency_ms", "model"}
    assert line["model"] == f"{name}@1"
    assert set(line["predictions"]["place"]) == {"value", "probability"}
    assert line["latency_ms"] >= 0 and json.dumps(line)


def test_the_recipe_travels_with_the_data_set_to_the_model(
    trained: tuple[Store, str, Path],
) -> None:
    sqlite_store, name, _ = trained
    info, _ = load_model(sqlite_store, name)
    recipe = info.extraction
    assert recipe is not None
    assert (recipe["extractor"], recipe["events"], recipe["n_channels"]) == ("uc3m-audio", "snr", 3)
    assert recipe["samplerate"] == 44100.0 and recipe["event_options"]["hangover"] == 0.5


def test_a_stream_unlike_the_training_recordings_is_refused(
    trained: tuple[Store, str, Path],
) -> None:
    sqlite_store, name, _ = trained
    with pytest.raises(AppError, match=r"trained on 3-channel recordings .* source has 2"):
        open_live(sqlite_store, name, samplerate=44100.0, n_channels=2)
    with pytest.raises(AppError, match=r"recordings at 44100 Hz, but the source runs at 48000"):
        open_live(sqlite_store, name, samplerate=48000.0, n_channels=3)


def test_a_model_of_an_imported_arff_refuses_live(
    capsys: pytest.CaptureFixture[str], sqlite_store_url: str, tmp_path: Path
) -> None:
    arff = tmp_path / "mini.arff"
    rows = "\n".join(f"{'tap' if i % 2 else 'slap'},{i * 0.1:.1f},{i % 3}" for i in range(20))
    arff.write_text(
        "@relation mini\n@attribute gesture {tap,slap}\n@attribute a numeric\n"
        f"@attribute b numeric\n@data\n{rows}\n"
    )
    wav, _ = write_session(tmp_path, "take", n_touches=2, seed=1)
    assert run_cli(capsys, sqlite_store_url, "import", str(arff), "--targets", "gesture").code == 0
    assert run_cli(capsys, sqlite_store_url, "train", "mini", "--classifier", "j48").code == 0
    result = run_cli(capsys, sqlite_store_url, "live", "--model", "mini-j48", "--replay", str(wav))
    assert result.code == 2 and result.err.count("\n") == 1
    assert "imported from a file, not extracted from recordings" in result.err


@pytest.fixture(scope="module")
def j48_of_one_session(tmp_path_factory: pytest.TempPathFactory) -> tuple[str, Path]:
    """The URL of a store (SQLite) with ``touch-j48`` (gesture) trained on one extracted
    session of six touches, and that session's recording; made once for the module's
    tests, which only read them."""
    folder = tmp_path_factory.mktemp("j48")
    url = f"sqlite:///{folder / 'touchbench.db'}"
    store = Store(url)
    try:
        wav, touches = write_session(folder, "s", n_touches=6, seed=4)
        labels = write_labels(folder / "l.csv", [(wav.name, *t) for t in touches])
        extract_and_store(store, ExtractRequest(recordings=[wav], labels=labels, name="touch"))
        train(store, TrainRequest(dataset="touch", classifier="j48", target="gesture"))
    finally:
        store.dispose()
    return url, wav


def test_live_bad_input_is_one_line(
    capsys: pytest.CaptureFixture[str], j48_of_one_session: tuple[str, Path], tmp_path: Path
) -> None:
    sqlite_store_url, wav = j48_of_one_session
    mono = tmp_path / "mono.wav"
    soundfile.write(mono, np.zeros(44100), 44100)
    odd = tmp_path / "take.xyz"
    odd.write_text("not audio")
    cases = [
        (["--replay", str(mono)], "trained on 3-channel recordings"),
        (["--replay", str(odd)], "not a recording touchbench can read"),
        (["--replay", str(wav), "--device", "0"], "exactly one of --device DEV or --replay"),
        (["--replay", str(wav), "--model", "nope"], "nope"),
        (["--replay", str(wav), "--block", "8"], "--block"),
    ]
    for args, message in cases:
        model = [] if "--model" in args else ["--model", "touch-j48"]
        result = run_cli(capsys, sqlite_store_url, "live", *model, *args)
        assert result.code == 2, (args, result.err)
        assert result.err.count("\n") == 1 and message in result.err, result.err


def test_the_block_length_changes_when_touches_are_told_not_what_they_are(
    capsys: pytest.CaptureFixture[str], j48_of_one_session: tuple[str, Path]
) -> None:
    sqlite_store_url, wav = j48_of_one_session
    seen = []
    for block in ("256", "512", "4096"):
        result = run_cli(
            capsys, sqlite_store_url, "live", "--model", "touch-j48", "--replay", str(wav),
            "--block", block, "--json",
        )  # fmt: skip
        assert result.code == 0, result.err
        lines = [json.loads(line) for line in result.out.splitlines()]
        seen.append([(t["start"], t["end"], t["predictions"]["gesture"]["value"]) for t in lines])
    assert len(seen[0]) == 6 and seen[0] == seen[1] == seen[2]


def test_live_session_takes_a_recipe_given_explicitly(
    trained: tuple[Store, str, Path],
) -> None:
    sqlite_store, name, unseen = trained
    info, model = load_model(sqlite_store, name)
    session = LiveSession(info, model, samplerate=44100.0, n_channels=3, extraction=info.extraction)
    samples, _ = soundfile.read(unseen, always_2d=True)
    touches = session.feed(samples.T, 10.0) + session.finish()
    assert len(touches) == 6 and touches[0].start > 10.0


def test_a_network_predicts_live_what_predict_says(tmp_path: Path) -> None:
    store = Store(f"sqlite:///{tmp_path / 'net.db'}")  # one store kind: the model is the point
    recordings, rows = [], []
    for seed in range(2):
        wav, touches = write_session(tmp_path, f"s{seed}", n_touches=8, seed=seed)
        recordings.append(wav)
        rows += [(wav.name, *touch) for touch in touches]
    frames = {"extractor": "mfcc", "events": "snr", "options": {"frames": "8"}}
    labels = write_labels(tmp_path / "labels.csv", rows)
    request = ExtractRequest(recordings=recordings, labels=labels, name="frames", **frames)
    extract_and_store(store, request)
    model = train(store, TrainRequest(dataset="frames", classifier="cnn1d", target="gesture"))
    unseen, _ = write_session(tmp_path, "unseen", n_touches=4, seed=99)
    offline = extract_dataset([unseen], labels=None, **frames).dataset  # type: ignore[arg-type]
    _, network = load_model(store, model.name)
    expected = predict(network, offline)
    with FileReplaySource(unseen, block_length=512) as source:
        session = open_live(store, model.name, samplerate=source.samplerate, n_channels=3)
        touches = [t for b in source.blocks() for t in session.feed(b.samples, b.time)]
        touches += session.finish()
    assert len(touches) == offline.n_instances == 4
    assert [t.predictions["gesture"][0] for t in touches] == expected.labels["gesture"]
    store.dispose()
