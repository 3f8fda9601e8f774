"""`export-model`, the example program, and the engine of `predict`, `live` and the
service: a model's ONNX twin answers what the model answers."""

from __future__ import annotations

import contextlib
import hashlib
import json
import sqlite3
import subprocess
import sys
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import onnxruntime
import pytest
from sqlalchemy import create_engine, text

from tests.support.cli_runner import CLI_WORDS, run_cli
from tests.support.live import pcm_blocks, stream, ws_url
from tests.support.recordings import extract_sessions
from tests.support.rows import count_rows
from tests.support.service import Server, finished, servers
from touchbench.app.schemas.models import TrainRequest
from touchbench.app.services.datasets import read_data_file
from touchbench.app.services.models import train
from touchbench.app.services.simulation import write_session
from touchbench.app.store.database import Store

ROOT = Path(__file__).resolve().parents[3]
EXAMPLE = ROOT / "examples" / "predict_onnx.py"


@pytest.fixture(scope="module")
def trained(tmp_path_factory: pytest.TempPathFactory) -> tuple[str, Path, Path]:
    """A store with `touch-rf` (live-capable, one target) and `touch-j48`, the session
    recordings, and an unseen session."""
    folder = tmp_path_factory.mktemp("onnx")
    url = f"sqlite:///{folder / 'touchbench.db'}"
    store = Store(url)
    extract_sessions(store, folder, sessions=2, touches=8)
    for classifier in ("rf", "j48"):
        train(store, TrainRequest(dataset="touch", classifier=classifier, target="gesture"))
    store.dispose()
    unseen, _ = write_session(folder, "unseen", n_touches=4, seed=99)
    return url, folder, unseen


def test_export_the_example_program_and_predict_agree(
    capsys: pytest.CaptureFixture[str], trained: tuple[str, Path, Path], tmp_path: Path
) -> None:
    url, _, _ = trained
    graph = tmp_path / "model.onnx"
    done = run_cli(capsys, url, "export-model", "touch-rf", "-o", str(graph), "--json")
    assert done.code == 0, done.err
    exported = done.json()
    assert exported["checked_instances"] == 16 and len(exported["sha256"]) == 64
    assert onnxruntime.InferenceSession(str(graph)).get_inputs()[0].name == "features"
    again = run_cli(capsys, url, "export-model", "touch-rf", "-o", str(graph))
    assert again.code == 2 and "--force" in again.err

    arff = tmp_path / "touch.arff"
    assert run_cli(capsys, url, "export", "touch", "-o", str(arff)).code == 0
    native = run_cli(capsys, url, "predict", "touch-rf", str(arff), "--engine", "native", "--json")
    onnx = run_cli(capsys, url, "predict", "touch-rf", str(arff), "--engine", "onnx", "--json")
    assert native.code == onnx.code == 0, onnx.err
    rows, twin_rows = native.json()["predictions"], onnx.json()["predictions"]
    assert [r["gesture"] for r in twin_rows] == [r["gesture"] for r in rows]
    for row, twin_row in zip(rows, twin_rows, strict=True):
        assert twin_row["probabilities"]["gesture"] == pytest.approx(
            row["probabilities"]["gesture"], abs=1e-5
        )

    assert _example_answer(arff, 0, graph, tmp_path)["label"] == rows[0]["gesture"]
    imports = [line for line in EXAMPLE.read_text().splitlines() if "import " in line]
    assert not [line for line in imports if "app" in line or "benchmark" in line]


def _example_answer(arff: Path, row: int, graph: Path, tmp_path: Path) -> Any:
    """What the example program prints for instance ``row`` of ``arff``, given as a robot's
    program has it: attribute -> number or label."""
    data = read_data_file(arff)
    instance = {
        attribute.name: attribute.label(data.values[row, i])
        if attribute.kind == "nominal"
        else float(data.values[row, i])
        for i, attribute in enumerate(data.schema.attributes)
    }
    (tmp_path / "instance.json").write_text(json.dumps(instance))
    answer = subprocess.run(
        [sys.executable, str(EXAMPLE), str(graph), str(tmp_path / "instance.json")],
        capture_output=True,
        text=True,
        check=True,
        cwd=tmp_path,
        env={"PATH": "/usr/bin:/bin"},  # no PYTHONPATH: touchbench is not importable there
    )
    return json.loads(answer.stdout)


def test_what_has_no_converter_is_refused_in_one_line(
    capsys: pytest.CaptureFixture[str], trained: tuple[str, Path, Path], tmp_path: Path
) -> None:
    url, _, _ = trained
    refused = run_cli(capsys, url, "export-model", "touch-j48", "-o", str(tmp_path / "j.onnx"))
    assert refused.code == 2 and refused.err.count("\n") == 1
    assert "'j48' (C45Classifier) has no ONNX converter; exportable:" in refused.err
    assert not (tmp_path / "j.onnx").exists()
    no_twin = run_cli(
        capsys, url, "predict", "touch-j48", str(tmp_path / "x.arff"), "--engine", "onnx"
    )
    assert no_twin.code == 2 and "has no ONNX twin yet" in no_twin.err
    unknown = run_cli(
        capsys, url, "predict", "touch-rf", str(tmp_path / "x.arff"), "--engine", "fast"
    )
    assert unknown.code == 2 and unknown.err.startswith("touchbench: error: --engine: "), unknown
    listing = run_cli(capsys, url, "classifiers", "--json").json()["classifiers"]
    marks = {entry["id"]: entry["onnx"] for entry in listing}
    assert marks["rf"] and marks["xgb"] and not marks["j48"] and not marks["minirocket"]


def test_live_answers_the_same_with_either_engine(
    capsys: pytest.CaptureFixture[str], trained: tuple[str, Path, Path], tmp_path: Path
) -> None:
    url, _, unseen = trained
    assert (
        run_cli(capsys, url, "export-model", "touch-rf", "-o", str(tmp_path / "m.onnx")).code == 0
    )
    lines = {}
    for engine in ("native", "onnx"):
        result = run_cli(
            capsys,
            url,
            "live",
            "--model",
            "touch-rf",
            "--replay",
            str(unseen),
            "--json",
            "--engine",
            engine,
        )
        assert result.code == 0, result.err
        lines[engine] = [json.loads(line) for line in result.out.splitlines()]
    assert len(lines["onnx"]) == 4
    assert [t["predictions"]["gesture"]["value"] for t in lines["onnx"]] == [
        t["predictions"]["gesture"]["value"] for t in lines["native"]
    ]


def test_the_service_serves_the_graph_and_predicts_with_the_engine_asked(
    trained: tuple[str, Path, Path], make_server_on: Callable[[str], Server], tmp_path: Path
) -> None:
    url, folder, unseen = trained
    url = _without_twins(url, folder, tmp_path)
    server = make_server_on(url)
    missing = server.client.get("/api/models/touch-rf/onnx")  # a GET makes nothing
    assert missing.status_code == 404, missing.text
    assert "POST /api/models/touch-rf/onnx makes it (a job)" in missing.text
    assert count_rows(url, "model_exports") == 0
    started = server.client.post("/api/models/touch-rf/onnx")
    assert started.status_code == 202, started.text
    done = server.wait_for(f"/api/jobs/{started.json()['job']}", finished)
    assert done["status"] == "done" and done["result"]["checked_instances"] == 16, done
    graph = server.client.get("/api/models/touch-rf/onnx")
    assert graph.status_code == 200, graph.text
    assert graph.headers["content-type"] == "application/octet-stream"
    session = onnxruntime.InferenceSession(graph.content)
    features = json.loads(session.get_modelmeta().custom_metadata_map["touchbench.features"])
    instance = {column["name"]: 0.5 for column in features}
    answers = {}
    for engine in ("native", "onnx", "auto"):
        response = server.client.post(
            "/api/models/touch-rf/predict", json={"instances": [instance], "engine": engine}
        )
        assert response.status_code == 200, response.text
        answers[engine] = response.json()["predictions"][0]["gesture"]
    assert answers["onnx"] == answers["native"] == answers["auto"]
    refused = server.client.post("/api/models/touch-j48/onnx")
    assert refused.status_code == 422 and "has no ONNX converter" in refused.text
    assert refused.json()["error"]["where"] == "body.model", refused.text
    assert server.client.get("/api/models/touch-j48/onnx").status_code == 404
    no_twin = server.client.post(
        "/api/models/touch-j48/predict", json={"instances": [instance], "engine": "onnx"}
    )
    assert no_twin.status_code in (400, 422) and "engine" in no_twin.text

    # an uploaded recording, with the engine asked in the form as the CLI's --engine asks it
    files = {}
    for engine in ("native", "onnx"):
        with unseen.open("rb") as upload:
            response = server.client.post(
                "/api/models/touch-rf/predict/file",
                files={"file": (unseen.name, upload)},
                data={"engine": engine},
            )
        assert response.status_code == 200, response.text
        files[engine] = [row["gesture"] for row in response.json()["predictions"]]
    assert len(files["onnx"]) == 4 and files["onnx"] == files["native"]
    for engine, model in (("fast", "touch-rf"), ("onnx", "touch-j48")):  # unknown, no twin
        with unseen.open("rb") as upload:
            refused = server.client.post(
                f"/api/models/{model}/predict/file",
                files={"file": (unseen.name, upload)},
                data={"engine": engine},
            )
        assert refused.status_code == 422, refused.text
        assert refused.json()["error"]["where"] == "body.engine", refused.text
        assert not CLI_WORDS.search(refused.json()["error"]["message"]), refused.text

    # the live WebSocket, with each engine, on the same samples
    rate, channels, blocks = pcm_blocks(unseen)
    labels = {}
    for engine in ("native", "onnx"):
        header = {"samplerate": rate, "channels": channels, "format": "S16LE", "engine": engine}
        messages, code, reason = stream(ws_url(server, "touch-rf"), header, blocks)
        assert (code, reason) == (1000, "stream ended")
        labels[engine] = [m["predictions"]["gesture"]["value"] for m in messages]
    assert len(labels["onnx"]) == 4 and labels["onnx"] == labels["native"]
    header = {"samplerate": rate, "channels": channels, "engine": "fast"}
    _, code, reason = stream(ws_url(server, "touch-rf"), header, [])
    assert (code, reason) == (1007, "header: 'engine' must be auto, onnx or native")


def _without_twins(url: str, folder: Path, tmp_path: Path) -> str:
    """A copy of the store at ``url`` (in ``folder``) in ``tmp_path``, its models' twins
    (made by another test of the module, or not) deleted."""
    copy = tmp_path / "copy.db"
    with (
        contextlib.closing(sqlite3.connect(folder / "touchbench.db")) as source,
        contextlib.closing(sqlite3.connect(copy)) as target,
    ):
        source.backup(target)  # with what the write-ahead log holds
        target.execute("DELETE FROM model_exports")
        target.commit()
    return f"sqlite:///{copy}"


@pytest.fixture
def make_server_on(tmp_path: Path) -> Iterator[Callable[[str], Server]]:
    """Starts (and at the end stops) services on a given store."""
    generators: list[Iterator[Callable[..., Server]]] = []

    def make(url: str) -> Server:
        generator = servers(url, tmp_path)
        generators.append(generator)
        return next(generator)()

    yield make
    for generator in generators:
        next(generator, None)


def test_a_chain_of_two_targets_exports_and_every_engine_gives_both_labels(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    """`export-model` of a classifier chain, `predict --engine onnx` against `native`, and
    the example program's answer for every target."""
    from tests.support.synthetic import touch_arff

    url = f"sqlite:///{tmp_path / 'touchbench.db'}"
    arff = touch_arff(tmp_path / "touch.arff", n=45)
    assert run_cli(capsys, url, "import", str(arff)).code == 0
    trained = run_cli(capsys, url, "train", "touch", "-c", "cc:rf", "--name", "chain")
    assert trained.code == 0, trained.err
    graph = tmp_path / "chain.onnx"
    done = run_cli(capsys, url, "export-model", "chain", "-o", str(graph), "--json")
    assert done.code == 0, done.err
    assert done.json()["checked_instances"] == 45
    native = run_cli(capsys, url, "predict", "chain", str(arff), "--engine", "native", "--json")
    onnx = run_cli(capsys, url, "predict", "chain", str(arff), "--engine", "onnx", "--json")
    assert native.code == onnx.code == 0, onnx.err
    rows, twin_rows = native.json()["predictions"], onnx.json()["predictions"]
    for target in ("gesture", "place"):
        assert [r[target] for r in twin_rows] == [r[target] for r in rows]
        for row, twin_row in zip(rows, twin_rows, strict=True):
            assert twin_row["probabilities"][target] == pytest.approx(
                row["probabilities"][target], abs=1e-5
            )

    printed = _example_answer(arff, 1, graph, tmp_path)
    assert printed["label"] == {"gesture": rows[1]["gesture"], "place": rows[1]["place"]}
    assert set(printed["probabilities"]) == {"gesture", "place"}

    refused = run_cli(capsys, url, "train", "touch", "-c", "pcc:logistic", "--name", "pcc")
    assert refused.code == 0, refused.err
    not_exported = run_cli(capsys, url, "export-model", "pcc", "-o", str(tmp_path / "p.onnx"))
    assert not_exported.code == 2 and not_exported.err.count("\n") == 1
    assert "several targets: cr, cc, bcc, lc, ps and nsr" in not_exported.err
    listing = run_cli(capsys, url, "classifiers", "--multi-target", "--json").json()
    marks = {entry["id"]: entry["onnx"] for entry in listing["classifiers"]}
    assert marks["cc:rf"] and marks["lc:xgb"] and not marks["cc:j48"] and not marks["ecc:rf"]


def test_the_command_line_makes_twins_only_when_asked_and_serves_none_broken(
    capsys: pytest.CaptureFixture[str], store_url: str, tmp_path: Path
) -> None:
    """``train --onnx`` makes the twin (refused up front for a classifier without a
    converter); ``export-model`` into a missing folder stores nothing; a stored twin that
    cannot be loaded is not served: ``auto`` predicts with the model and says so once,
    ``--engine onnx`` exits 2 naming the problem."""
    from tests.support.rows import count_rows
    from tests.support.synthetic import touch_arff

    arff = touch_arff(tmp_path / "touch.arff", n=45, with_place=False)
    assert run_cli(capsys, store_url, "import", str(arff)).code == 0
    made = run_cli(capsys, store_url, "train", "touch", "-c", "rf", "--name", "forest", "--onnx")
    assert made.code == 0 and "its ONNX twin" in made.err, made.err
    refused = run_cli(capsys, store_url, "train", "touch", "-c", "j48", "--onnx")
    assert refused.code == 2 and refused.err.count("\n") == 1, refused.err
    assert "--onnx: classifier 'j48' has no ONNX converter" in refused.err
    plain = run_cli(capsys, store_url, "train", "touch", "-c", "rf", "--name", "plain", "--json")
    assert plain.code == 0 and plain.json()["onnx"] is None
    assert count_rows(store_url, "models") == 2 and count_rows(store_url, "model_exports") == 1
    nowhere = tmp_path / "missing" / "dir" / "x.onnx"
    lost = run_cli(capsys, store_url, "export-model", "plain", "-o", str(nowhere))
    assert lost.code == 2 and lost.err.count("\n") == 1, lost.err
    assert f"--output: folder {nowhere.parent} does not exist" in lost.err
    assert count_rows(store_url, "model_exports") == 1 and not nowhere.parent.exists()

    garbage = b"\x08\x07 not a graph"
    engine = create_engine(store_url.replace("postgresql://", "postgresql+psycopg://", 1))
    with engine.begin() as connection:
        connection.execute(
            text("UPDATE model_exports SET data = :d, sha256 = :s, size_bytes = :n"),
            {"d": garbage, "s": hashlib.sha256(garbage).hexdigest(), "n": len(garbage)},
        )
    engine.dispose()
    native = run_cli(capsys, store_url, "predict", "forest", str(arff), "--engine", "native")
    auto = run_cli(capsys, store_url, "predict", "forest", str(arff), "--json")
    assert auto.code == 0, auto.err
    (warning,) = auto.json()["warnings"]
    assert "model 'forest@1': its ONNX twin cannot be loaded (" in warning
    assert (
        native.code == 0
        and auto.json()["predictions"]
        == run_cli(
            capsys, store_url, "predict", "forest", str(arff), "--engine", "native", "--json"
        ).json()["predictions"]
    )
    onnx = run_cli(capsys, store_url, "predict", "forest", str(arff), "--engine", "onnx")
    assert onnx.code == 2 and onnx.err.count("\n") == 1, onnx.err
    assert "--engine: model 'forest@1': its ONNX twin cannot be loaded (" in onnx.err
