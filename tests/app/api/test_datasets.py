"""Data sets over HTTP: upload, describe, download, rename, delete; recording sessions that
end in a data set; bad uploads answered with a 4xx JSON error and nothing stored."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from tests.support.cli_runner import run_cli
from tests.support.service import Server, finished, upload
from tests.support.synthetic import touch_arff
from touchbench.app.services.simulation import write_labels, write_session


def test_upload_describe_download_rename_delete(
    capsys: pytest.CaptureFixture[str], server: Server, tmp_path: Path
) -> None:
    path = touch_arff(tmp_path / "touch.arff", n=60)
    response = upload(server, path)
    assert response.status_code == 201, response.text
    created = response.json()
    assert (created["name"], created["n_instances"], created["n_features"]) == ("touch", 60, 5)
    assert created["targets"] == ["gesture", "place"] and created["created"] is True

    again = upload(server, path)
    assert again.status_code == 200
    assert again.json()["id"] == created["id"] and again.json()["created"] is False

    api = server.client
    listed = api.get("/api/datasets").json()["datasets"]
    cli_listed = run_cli(capsys, server.database_url, "datasets", "--json").json()["datasets"]
    assert listed == cli_listed and [d["name"] for d in listed] == ["touch"]

    described = api.get("/api/datasets/touch").json()
    assert described == run_cli(capsys, server.database_url, "show", "touch", "--json").json()
    assert described["class_distribution"]["gesture"] == {"tap": 20, "slap": 20, "stroke": 20}

    downloaded = api.get(f"/api/datasets/{created['id']}/arff")
    assert downloaded.status_code == 200
    exported = tmp_path / "exported.arff"
    assert run_cli(capsys, server.database_url, "export", "touch", "-o", str(exported)).code == 0
    assert downloaded.text == exported.read_text(encoding="utf-8")

    renamed = api.post("/api/datasets/touch/rename", json={"name": "robot"})
    assert renamed.status_code == 200 and renamed.json()["previous_name"] == "touch"
    assert api.get("/api/datasets/touch").status_code == 404
    gone = api.delete("/api/datasets/robot")
    assert gone.status_code == 200
    assert api.get("/api/datasets").json() == {"datasets": []}


def test_bad_uploads_are_4xx_json_and_store_nothing(server: Server, tmp_path: Path) -> None:
    broken = tmp_path / "broken.arff"
    broken.write_text("@relation r\n@attribute a numeric\n@attribute c {x,y}\n@data\n1,x\n2,z\n")
    response = upload(server, broken)
    assert response.status_code == 400
    error = response.json()["error"]
    assert error["type"] == "DataFormatError" and "broken.arff:6" in error["where"]
    assert "'z'" in error["message"]

    binary = tmp_path / "noise.wav"
    binary.write_bytes(bytes(range(256)) * 64)
    assert upload(server, binary).status_code == 400

    api = server.client
    assert api.post("/api/datasets").status_code == 422
    missing = api.get("/api/datasets/nothing-here")
    assert missing.status_code == 404 and missing.json()["error"]["type"] == "NotFoundError"
    assert api.get("/api/datasets").json() == {"datasets": []}
    assert not list((server.work_dir).glob("**/*.arff"))


def test_a_recording_session_upload_becomes_a_data_set(server: Server, tmp_path: Path) -> None:
    rows = []
    recordings = []
    for i in range(2):
        path, touches = write_session(tmp_path, f"s{i}", n_touches=6, seed=i)
        recordings.append(path)
        rows += [(path.name, start, end, gesture, place) for start, end, gesture, place in touches]
    labels = write_labels(tmp_path / "labels.csv", rows)
    files = [("recordings", (p.name, p.open("rb"))) for p in recordings]
    files.append(("labels", (labels.name, labels.open("rb"))))
    try:
        response = server.client.post(
            "/api/datasets/recordings",
            files=files,
            data={"extractor": "uc3m-audio", "name": "robot-session"},
        )
    finally:
        for _, (_, handle) in files:
            handle.close()
    assert response.status_code == 202, response.text
    job = server.wait_for(f"/api/jobs/{response.json()['job']}", finished)
    assert job["status"] == "done", job
    assert job["result"]["name"] == "robot-session" and job["result"]["n_instances"] >= 10
    assert job["params"]["recordings"] == [p.name for p in recordings]
    assert (job["params"]["labels"], job["params"]["extractor"]) == ("labels.csv", "uc3m-audio")
    assert str(server.work_dir) not in response.text + str(server.client.get("/api/jobs").json())
    described = server.client.get("/api/datasets/robot-session").json()
    assert described["targets"] == ["gesture", "place"]
    assert not list((server.work_dir / "uploads").glob("*/*")), "the upload folder is left"

    refused = server.client.post(
        "/api/datasets/recordings",
        files=[("recordings", ("x.wav", b"not audio"))],
        data={"extractor": "uc3m-audio"},
    )
    assert refused.status_code == 202
    failed = server.wait_for(f"/api/jobs/{refused.json()['job']}", finished)
    assert failed["status"] == "failed" and failed["error"].startswith("x.wav: ")
    assert str(server.work_dir) not in failed["error"], "a server path in the job's error"
    unknown = server.client.post(
        "/api/datasets/recordings",
        files=[("recordings", ("x.wav", b"x"))],
        data={"extractor": "nope"},
    )
    assert unknown.status_code == 422 and "unknown extractor 'nope'" in unknown.text
    assert unknown.json()["error"]["where"] == "body.extractor"


def test_uploads_over_the_limit_are_refused_while_streaming(
    make_server: Callable[..., Server], tmp_path: Path
) -> None:
    server = make_server(max_upload_mb="1")
    big = touch_arff(tmp_path / "big.arff", n=40000)
    assert big.stat().st_size > 2**20
    response = upload(server, big)
    assert response.status_code == 413
    assert response.json()["error"]["type"] == "UploadTooLarge"

    def chunks() -> Iterator[bytes]:  # a valid multipart body, sent without a length
        yield (
            b'--x\r\nContent-Disposition: form-data; name="recordings"; filename="big.wav"'
            b"\r\nContent-Type: application/octet-stream\r\n\r\n"
        )
        with big.open("rb") as handle:
            while block := handle.read(65536):
                yield block
        yield b"\r\n--x--\r\n"

    streamed = server.client.post(
        "/api/datasets/recordings",
        content=chunks(),
        headers={"content-type": "multipart/form-data; boundary=x"},
    )
    assert streamed.status_code == 413
    assert server.client.get("/api/datasets").json() == {"datasets": []}
