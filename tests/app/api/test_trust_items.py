"""Issue 21, items 4 to 9 and the CORS preflight, tried on a real ``touchbench serve`` as a
hostile client would: each answer is one 4xx JSON error naming the client's own file or
field, and nothing is half-written in the store. The subject is what a client is told, not
the store: the tests run on SQLite only.

One service serves every test of the module (each test uses names of its own), so that the
cases cost one start-up, not one each.
"""

from __future__ import annotations

import socket
from collections.abc import Callable, Iterator
from email.message import Message
from pathlib import Path
from typing import Any
from urllib.parse import unquote

import httpx
import pytest

from tests.support.service import Server, finished, servers

#: One more than ``csv.field_size_limit()``'s default.
LONG_FIELD = "x" * 131_073
#: Features of the wide model (item 6: 98 of 99 left out).
N_WIDE = 99


@pytest.fixture(scope="module")
def served(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    """A service on SQLite only (the subject is not the store) with a data set ``wide`` (99
    numeric features, a class) and its model ``wide-nb``."""
    folder = tmp_path_factory.mktemp("served-sqlite")
    builder = servers(f"sqlite:///{folder / 'touchbench.db'}", folder)
    build = next(builder)
    server = build()
    wide = _wide_arff(folder / "wide.arff")
    assert _upload(server, wide).status_code == 201
    trained = server.client.post(
        "/api/models", json={"dataset": "wide", "classifier": "nb", "name": "wide-nb"}
    )
    assert trained.status_code == 202, trained.text
    assert server.wait_for(f"/api/jobs/{trained.json()['job']}", finished)["status"] == "done"
    yield server
    for _ in builder:  # stops the service
        pass


def _wide_arff(path: Path) -> Path:
    lines = ["@relation wide", *(f"@attribute a{i} numeric" for i in range(N_WIDE))]
    lines += ["@attribute cls {u, v}", "@data"]
    for row in range(20):
        cells = [str((row * 7 + i) % 11 + (row % 2) * 5) for i in range(N_WIDE)]
        lines.append(",".join([*cells, "uv"[row % 2]]))
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def _upload(server: Server, path: Path, **form: str) -> httpx.Response:
    with path.open("rb") as handle:
        return server.client.post(
            "/api/datasets", files={"file": (path.name, handle)}, data=form or None
        )


def _refusal(response: httpx.Response, status: int, *words: str) -> dict[str, Any]:
    """The JSON error of a refused request: its status, one line, the words expected."""
    assert response.status_code == status, (response.status_code, response.text)
    error: dict[str, Any] = response.json()["error"]
    assert "\n" not in error["message"], error
    for word in words:
        assert word in error["message"], error
    return error


def _dataset_names(server: Server) -> set[str]:
    return {d["name"] for d in server.client.get("/api/datasets").json()["datasets"]}


def _model_names(server: Server) -> set[str]:
    return {m["name"] for m in server.client.get("/api/models").json()["models"]}


# -- 4. a CSV field over 131,072 characters ------------------------------------------------


def test_a_csv_field_over_the_limit_is_refused_at_upload_and_prediction(
    served: Server, tmp_path: Path
) -> None:
    long_csv = tmp_path / "long-field.csv"
    long_csv.write_text(f"a0,a1,cls\n1,2,u\n{LONG_FIELD},3,v\n", encoding="utf-8")
    before = _dataset_names(served)

    error = _refusal(_upload(served, long_csv), 400, "long-field.csv:3", "131,072 characters")
    assert error["type"] == "DataFormatError"
    assert _dataset_names(served) == before

    with long_csv.open("rb") as handle:
        answer = served.client.post(
            "/api/models/wide-nb/predict/file", files={"file": (long_csv.name, handle)}
        )
    _refusal(answer, 400, "long-field.csv:3", "131,072 characters")


def test_a_labels_field_over_the_limit_is_refused_before_any_job(
    served: Server, tmp_path: Path
) -> None:
    labels = tmp_path / "long-labels.csv"
    labels.write_text(f"file,gesture\ntake.wav,{LONG_FIELD}\n", encoding="utf-8")
    jobs = served.client.get("/api/jobs").json()["jobs"]
    uploads = set((served.work_dir / "uploads").glob("*"))
    with labels.open("rb") as handle:
        refused = served.client.post(
            "/api/datasets/recordings",
            files=[
                ("recordings", ("take.wav", b"RIFF not really")),
                ("labels", (labels.name, handle)),
            ],
        )
    error = _refusal(refused, 400, "long-labels.csv:2: a field is longer than 131,072 characters")
    assert error["type"] == "DataFormatError"
    assert served.client.get("/api/jobs").json()["jobs"] == jobs
    assert set((served.work_dir / "uploads").glob("*")) == uploads, "an upload was kept"


# -- 5. a data set name beyond Latin-1, a quote in a file name --------------------------


@pytest.mark.parametrize("name", ["Ω-touch", 'q"uote'])
def test_a_download_keeps_a_name_in_any_script(served: Server, tmp_path: Path, name: str) -> None:
    path = tmp_path / "named.arff"
    path.write_text(
        f"@relation r{len(name)}\n@attribute a numeric\n@attribute cls {{u,v}}\n@data\n"
        f"{len(name)},u\n2,v\n",
        encoding="utf-8",
    )
    assert _upload(served, path, name=name).status_code == 201
    answer = served.client.get(f"/api/datasets/{name}/arff")
    assert answer.status_code == 200, answer.text
    assert answer.text.startswith("@relation")
    header = answer.headers["content-disposition"]
    assert header.isascii()
    parsed = Message()
    parsed["content-disposition"] = header
    assert parsed.get_content_disposition() == "attachment"
    # RFC 6266: the exact name in filename*, an ASCII fallback with nothing unescaped
    assert unquote(header.split("filename*=UTF-8''", 1)[1]) == f"{name}.arff"
    fallback = parsed.get_param("filename", header="content-disposition")
    assert isinstance(fallback, str) and fallback.endswith(".arff")
    assert '"' not in fallback and fallback.isascii()


# -- 6. JSON instances that leave out the model's attributes ------------------------------


def _predict(server: Server, body: dict[str, Any]) -> httpx.Response:
    return server.client.post("/api/models/wide-nb/predict", json=body)


def test_json_instances_that_leave_out_attributes_are_refused_as_a_file_is(
    served: Server,
) -> None:
    error = _refusal(
        _predict(served, {"instances": [{}]}),
        422,
        f"instance 1 lacks {N_WIDE} attribute(s) the model needs: a0, a1, a2, a3, a4, ...",
    )
    assert error["where"] == "body.instances.0"
    one_given = {"a0": 1.0}
    second = {f"a{i}": 1.0 for i in range(N_WIDE)}
    _refusal(
        _predict(served, {"instances": [second, {"a0": 1.0, "a7": 2.0}]}),
        422,
        f"instance 2 lacks {N_WIDE - 2} attribute(s) the model needs: a1, a2, a3, a4, a5, ...",
    )
    _refusal(_predict(served, {"instances": [one_given]}), 422, "lacks 98 attribute(s)")


def test_missing_values_asked_for_are_predicted_and_counted(served: Server) -> None:
    allowed = _predict(served, {"instances": [{"a0": 1.0}, {"a0": 2.0}], "missing": "allow"})
    assert allowed.status_code == 200, allowed.text
    report = allowed.json()
    assert len(report["predictions"]) == 2
    assert report["missing"] == {f"a{i}": 2 for i in range(1, N_WIDE)}

    nulls = {f"a{i}": (None if i < 3 else 1.0) for i in range(N_WIDE)}
    explicit = _predict(served, {"instances": [nulls]})
    assert explicit.status_code == 200, explicit.text
    assert explicit.json()["missing"] == {"a0": 1, "a1": 1, "a2": 1}

    _refusal(_predict(served, {"instances": [nulls], "missing": "maybe"}), 422, "missing")


# -- 7. no server path or host name reaches a client ---------------------------------------


def _strings(value: Any) -> Iterator[str]:
    if isinstance(value, str):
        yield value
    elif isinstance(value, dict):
        for key, item in value.items():
            yield str(key)
            yield from _strings(item)
    elif isinstance(value, list):
        for item in value:
            yield from _strings(item)


def test_job_listings_and_errors_speak_of_the_clients_own_files(
    served: Server, tmp_path: Path
) -> None:
    for recording in ("broken.wav", "broken.csv"):
        queued = served.client.post(
            "/api/datasets/recordings",
            files=[
                ("recordings", (recording, b"\x00\x01 not a recording")),
                ("labels", ("labels.csv", f"file,gesture\n{recording},tap\n".encode())),
            ],
            data={"name": f"from-{recording.replace('.', '-')}"},
        )
        assert queued.status_code == 202, queued.text
        job = served.wait_for(f"/api/jobs/{queued.json()['job']}", finished)
        assert job["status"] == "failed" and recording in job["error"], job
    bad = tmp_path / "bad-values.arff"
    bad.write_text("@relation r\n@attribute a0 numeric\n@data\nfoo\n", encoding="utf-8")
    with bad.open("rb") as handle:
        predicted = served.client.post(
            "/api/models/wide-nb/predict/file", files={"file": (bad.name, handle)}
        )
    error = _refusal(predicted, 400, "bad-values.arff:4")

    listing = served.client.get("/api/jobs").json()
    seen = [listing, error]
    for job in listing["jobs"]:
        assert set(job["params"]) & {"host", "folder"} == set(), job
        seen.append(served.client.get(f"/api/jobs/{job['id']}").json())
    host = socket.gethostname()
    secrets = ("/tmp", str(served.work_dir), "uploads")
    leaks = [
        text
        for text in _strings(seen)
        if text == host or f"{host}:" in text or any(secret in text for secret in secrets)
    ]
    assert leaks == []
    assert len(listing["jobs"]) >= 2


def test_a_running_run_shows_no_host_to_any_client(served: Server) -> None:
    """The process executing a run (host:pid) stays the service's business: the run and the
    listing show its status, never the machine's name."""
    gate = served.gate
    assert gate is not None
    request = {"dataset": "wide", "classifiers": ["gate"], "folds": 2}
    run_id = served.client.post("/api/runs", json=request).json()["id"]
    gate.wait_started(1)  # a worker holds the run: its owner is set in the store
    seen = [served.client.get(f"/api/runs/{run_id}").json(), served.client.get("/api/runs").json()]
    assert seen[0]["status"] == "running", seen[0]
    host = socket.gethostname()
    leaks = [text for text in _strings(seen) if text in (host, "owner") or f"{host}:" in text]
    gate.open()
    assert served.wait_for(f"/api/runs/{run_id}", finished)["status"] == "done"
    assert leaks == []


# -- 8. names are checked once, wherever one is given ---------------------------------------

BAD_NAMES = ["a/b", "../../etc/passwd", "tab\there", " padded", "x" * 201]


@pytest.mark.parametrize("name", BAD_NAMES)
def test_a_name_that_cannot_be_reached_again_is_refused_everywhere(
    served: Server, tmp_path: Path, name: str
) -> None:
    path = tmp_path / "fine.arff"
    path.write_text(
        "@relation fine\n@attribute a numeric\n@attribute cls {u,v}\n@data\n9,u\n8,v\n",
        encoding="utf-8",
    )
    datasets, models = _dataset_names(served), _model_names(served)
    assert _refusal(_upload(served, path, name=name), 422)["where"] == "body.name"
    renamed = served.client.post("/api/datasets/wide/rename", json={"name": name})
    assert _refusal(renamed, 422, "dataset name")["where"] == "body.name"
    trained = served.client.post(
        "/api/models", json={"dataset": "wide", "classifier": "nb", "name": name}
    )
    assert _refusal(trained, 422, "model name")["where"] == "body.name"
    extracted = served.client.post(
        "/api/datasets/recordings",
        files=[("recordings", ("take.wav", b"RIFF"))],
        data={"name": name},
    )
    assert _refusal(extracted, 422, "dataset name")["where"] == "body.name"
    assert (_dataset_names(served), _model_names(served)) == (datasets, models)


# -- 9. MEKA's -C that is not a number --------------------------------------------------


def test_a_meka_option_that_is_not_a_number_is_refused_at_the_header(
    served: Server, tmp_path: Path
) -> None:
    path = tmp_path / "meka-abc.arff"
    path.write_text(
        "@relation 'r: -C abc'\n@attribute a numeric\n@attribute cls {u,v}\n@data\n1,u\n2,v\n",
        encoding="utf-8",
    )
    before = _dataset_names(served)
    error = _refusal(_upload(served, path), 400, "meka-abc.arff:1", "-C", "'abc'")
    assert error["where"] == "meka-abc.arff:1"
    assert _dataset_names(served) == before


# -- CORS preflight ------------------------------------------------------------------------


def test_a_cors_preflight_from_an_unlisted_origin_is_a_json_error(
    make_sqlite_server: Callable[..., Server],
) -> None:
    listed = "http://robot-console.example:3000"
    server = make_sqlite_server(allowed_origins=listed)

    def preflight(origin: str) -> httpx.Response:
        return server.client.options(
            "/api/datasets",
            headers={"Origin": origin, "Access-Control-Request-Method": "POST"},
        )

    error = _refusal(preflight("http://evil.example"), 400, "'http://evil.example'")
    assert error["where"] == "headers.Origin"
    assert "access-control-allow-origin" not in preflight("http://evil.example").headers
    allowed = preflight(listed)
    assert allowed.status_code == 200
    assert allowed.headers["access-control-allow-origin"] == listed
