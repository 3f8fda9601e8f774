"""touchbench.Client against a real ``touchbench serve`` on loopback with keys (a write key
and a read-only one): every verb, the service's errors as exceptions with their field, the
leaderboard equal to the CLI's, retries only where the service never got the request."""

from __future__ import annotations

import contextlib
import math
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
import numpy as np
import pandas as pd
import pytest
from matplotlib.figure import Figure

import touchbench
from tests.support.cli_runner import run_cli
from tests.support.recordings import PER_RECORDING, recorded_windows, store_dataset
from tests.support.service import Server, servers
from tests.support.synthetic import touch_arff
from touchbench.app.errors import FieldError
from touchbench.app.python import errors
from touchbench.app.python.client import Client, _HttpSource
from touchbench.app.python.sources import stored_leaderboard
from touchbench.app.python.work import Run
from touchbench.app.services.simulation import write_labels, write_session
from touchbench.app.store.database import Store

WRITE = "client-test-write-key-0123456789"
READ = "client-test-read-key-0123456789"


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    """One service for the module (SQLite), a write and a read-only key."""
    folder = tmp_path_factory.mktemp("client")
    builds = servers(f"sqlite:///{folder / 'touchbench.db'}", folder)
    build = next(builds)
    yield build(api_keys=f"lab:write:{WRITE},robot:read:{READ}")
    next(builds, None)  # stops it


@pytest.fixture(scope="module")
def service(server: Server) -> Iterator[Client]:
    with Client(server.url, api_key=WRITE) as client:
        yield client


@pytest.fixture(scope="module")
def touch(service: Client, tmp_path_factory: pytest.TempPathFactory) -> str:
    """A data set uploaded through the client."""
    path = touch_arff(tmp_path_factory.mktemp("data") / "touch.arff", n=120)
    imported = service.upload(path, name="touch")
    assert (imported.name, imported.created, imported.targets) == (
        "touch",
        True,
        ["gesture", "place"],
    )
    return imported.name


@pytest.fixture(scope="module")
def done_run(service: Client, touch: str) -> Run:
    run = service.bench(
        touch, target="gesture", classifiers=["nb", "zeror", "j48"], folds=3, seed=1, wait=True
    )
    return run


def test_bench_waits_and_the_leaderboard_is_the_clis(
    server: Server,
    service: Client,
    done_run: Run,
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert done_run.finished and done_run.status == "done"
    assert (done_run.schema.tasks_done, done_run.schema.tasks) == (9, 9)
    assert service.run(done_run.id).schema == done_run.schema
    assert any(r.id == done_run.id for r in service.runs())

    board = service.leaderboard(done_run)
    cli = run_cli(capsys, server.database_url, "leaderboard", str(done_run.id), "--json")
    assert cli.code == 0, cli.err
    assert board.schema.to_json() == cli.json()
    assert board.best == cli.json()["leaderboard"][0]["classifier"] == "nb"
    assert done_run.leaderboard().schema == board.schema

    frame = board.to_pandas()
    assert list(frame.index) == ["nb", "j48", "zeror"]
    assert list(frame["mark"]) == ["(base)", "", "*"]
    assert list(frame["folds"]) == [3, 3, 3]
    first = cli.json()["leaderboard"][0]["metrics"]["f1_weighted"]
    assert frame.loc["nb", "f1_weighted_mean"] == pytest.approx(first["mean"])
    assert frame.loc["nb", "f1_weighted_std"] == pytest.approx(first["std"])
    assert math.isnan(frame.loc["nb", "p_value"]) and frame.loc["zeror", "p_value"] < 0.05

    # the plots read the same numbers over HTTP as from the store
    stored = stored_leaderboard(Store(server.database_url), done_run.id)
    pd.testing.assert_frame_equal(board.fold_scores(), stored.fold_scores())
    assert board.fold_scores().shape == (3, 3)
    for kind in ("cd", "folds", "confusion"):
        figure = board.plot(kind)
        assert isinstance(figure, Figure) and figure.axes
    confusion = board.plot("confusion", classifier="j48")
    assert "j48, summed over 3 folds" in " ".join(confusion.get_suptitle().split())
    with pytest.raises(errors.NotFoundError) as unknown:
        service.leaderboard(done_run.id + 1000)
    assert unknown.value.status == 404 and "run" in unknown.value.message

    text = repr(board)
    assert "(base)" in text and "nb" in text and "marks against nb" in text
    html = board._repr_html_()
    assert "<table>" in html and "(base)" in html


def test_a_refused_request_raises_with_the_services_field(
    service: Client, touch: str, done_run: Run
) -> None:
    with pytest.raises(errors.InvalidRequestError) as few:
        service.bench(touch, target="gesture", classifiers=["nb"], folds=1)
    assert (few.value.status, few.value.field, few.value.where) == (422, "folds", "body.folds")
    assert "greater than or equal to 2" in few.value.message
    assert isinstance(few.value, errors.BadRequestError | errors.ServiceError)

    with pytest.raises(errors.InvalidRequestError) as rule:  # a rule across fields (FieldError)
        service.bench(touch, classifiers=["nb"], budget=5)
    assert (rule.value.field, rule.value.kind) == ("budget", "FieldError")
    assert "only meaningful with `tune`" in str(rule.value)

    with pytest.raises(errors.ServiceError) as unknown_classifier:
        service.bench(touch, target="gesture", classifiers=["no-such-classifier"], folds=2)
    assert unknown_classifier.value.status in (400, 422)
    assert "no-such-classifier" in unknown_classifier.value.message

    with pytest.raises(errors.NotFoundError) as missing:
        service.dataset("no-such-data-set")
    assert missing.value.kind == "NotFoundError" and missing.value.field is None

    with pytest.raises(errors.ConflictError):  # a finished run cannot be cancelled
        service.cancel(done_run)

    with pytest.raises(errors.BadRequestError) as metric:  # the plots' numbers, refused
        _HttpSource(service).fold_scores(done_run.id, metric="no-such-metric", aggregate="window")
    assert metric.value.status == 400 and "no-such-metric" in metric.value.message


def test_leaderboard_rescored_per_recording_is_the_clis(
    server: Server,
    service: Client,
    done_run: Run,
    capsys: pytest.CaptureFixture[str],
    tmp_path: Path,
) -> None:
    """``aggregate=`` re-scores the run's stored fold predictions as ``leaderboard
    --aggregate`` does, and the leaderboard's plots and fold scores follow it (over HTTP and
    from the store); a run on data without recordings, or an imported one, is refused
    naming the field."""
    store_dataset(server.database_url, recorded_windows(), "takes")
    run = service.bench("takes", classifiers=["nb", "ridge"], folds=4, seed=3, wait=True)
    assert run.status == "done"
    board = service.leaderboard(run, aggregate="recording")
    asked = ("leaderboard", str(run.id), "--aggregate", "recording", "--json")
    cli = run_cli(capsys, server.database_url, *asked)
    assert cli.code == 0, cli.err
    assert board.schema.to_json() == cli.json()
    assert board.schema.aggregate == "recording"
    assert board.schema.notes[0].startswith(PER_RECORDING)
    assert run.leaderboard(aggregate="recording").schema == board.schema
    plain = service.leaderboard(run, aggregate="window")
    assert plain.schema == service.leaderboard(run).schema and plain.schema.aggregate == "window"
    assert (
        plain.to_pandas()["f1_weighted_mean"].tolist()
        != board.to_pandas()["f1_weighted_mean"].tolist()
    )

    # its plots draw the folds and classes scored per recording, over HTTP and from the store
    folds = board.fold_scores()
    means = board.to_pandas()["f1_weighted_mean"]
    assert folds.mean().to_dict() == pytest.approx(means.to_dict(), abs=1e-12)
    assert not folds.equals(plain.fold_scores())
    store = Store(server.database_url)
    stored = stored_leaderboard(store, run.id, aggregate="recording")
    assert stored.schema == board.schema
    pd.testing.assert_frame_equal(folds, stored.fold_scores())
    pd.testing.assert_frame_equal(
        plain.fold_scores(), stored_leaderboard(store, run.id).fold_scores()
    )
    for kind in ("cd", "folds"):
        assert board.plot(kind).axes and stored.plot(kind).axes
    for made in (board, stored):
        confusion = made.plot("confusion", classifier="nb")
        assert "nb, summed over 4 folds" in " ".join(confusion.get_suptitle().split())
        # 16 recordings of 16 windows: per recording, each cell counts recordings
        counts = [text.get_text() for text in confusion.axes[0].texts]
        assert sum(int(c.rsplit("\n", 1)[-1]) for c in counts) == 16, counts
    window_counts = plain.plot("confusion", classifier="nb").axes[0].texts
    assert sum(int(t.get_text().rsplit("\n", 1)[-1]) for t in window_counts) == 256

    # an imported run (scores, not predictions): its plots as it scored; per recording refused
    exported = tmp_path / "results.arff"
    exported.write_text(
        run_cli(capsys, server.database_url, "leaderboard", str(run.id), "-f", "arff").out
    )
    imported = run_cli(
        capsys, server.database_url, "import-results", str(exported), "--dataset", "takes", "--json"
    )
    assert imported.code == 0, imported.err
    paper = int(imported.json()["id"])
    as_scored = service.leaderboard(paper)
    assert as_scored.schema.aggregate == "window" and as_scored.plot("folds").axes
    # the same folds as the run's per window (exported under WEKA's names)
    np.testing.assert_allclose(
        sorted(as_scored.fold_scores().T.to_numpy().tolist()),
        sorted(plain.fold_scores().T.to_numpy().tolist()),
    )
    for refused in (
        lambda: service.leaderboard(paper, aggregate="recording"),
        lambda: _HttpSource(service).fold_scores(
            paper, metric="f1_weighted", aggregate="recording"
        ),
        lambda: _HttpSource(service).classes(paper, classifier="nb", aggregate="recording"),
        lambda: stored_leaderboard(store, paper, aggregate="recording"),
    ):
        with pytest.raises((errors.InvalidRequestError, FieldError)) as imported_refused:
            refused()
        assert imported_refused.value.field == "aggregate"
        assert f"run {paper} was imported" in str(imported_refused.value)
    store.dispose()

    with pytest.raises(errors.InvalidRequestError) as ungrouped:
        service.leaderboard(done_run, aggregate="recording")
    assert (ungrouped.value.status, ungrouped.value.field) == (422, "aggregate")
    assert "grouped by recording" in ungrouped.value.message
    with pytest.raises(errors.InvalidRequestError) as bad:
        service.leaderboard(run, aggregate="take")  # type: ignore[arg-type]
    assert bad.value.field == "aggregate"


def test_keys_read_only_refused_on_write_and_never_shown(
    server: Server, touch: str, done_run: Run
) -> None:
    with Client(server.url, api_key=READ) as reader:
        assert reader.leaderboard(done_run.id).best == "nb"  # reading is allowed
        with pytest.raises(errors.ForbiddenError) as refused:
            reader.bench(touch, target="gesture", classifiers=["nb"], folds=2)
        assert refused.value.status == 403
        assert "'robot' is a read key; this needs a write key" in refused.value.message
        assert READ not in repr(reader) + str(refused.value) + repr(refused.value)
    with Client(server.url, api_key="") as nobody, pytest.raises(errors.UnauthorizedError) as no:
        nobody.runs()
    assert no.value.status == 401 and "X-API-Key" in no.value.message
    with (
        Client(server.url, api_key="wrong-key-but-long-enough") as wrong,
        pytest.raises(errors.ForbiddenError),
    ):
        wrong.models()
    assert WRITE not in repr(Client(server.url, api_key=WRITE))


def test_train_models_predict(service: Client, done_run: Run, tmp_path: Path) -> None:
    job = service.train(run=done_run, name="client-best", wait=True)
    assert job.finished and job.status == "done", job.schema.error
    model = job.model()
    assert (model.name, model.run_id, model.classifier) == ("client-best", done_run.id, "nb")
    assert model in service.models()
    assert service.model("client-best") == model

    rows = pd.DataFrame(
        [
            {"f0": 0.0, "f1": 0.0, "f2": 0, "f3": 0, "mic": "left"},
            {"f0": 4.0, "f1": 2.0, "f2": float("nan"), "f3": 1, "mic": "elbow"},
        ]
    )
    report = service.predict("client-best", rows, missing="allow")
    assert report.model == "client-best@1" and len(report.predictions) == 2
    assert [p.instance for p in service.predict(model, rows.iloc[0].to_dict()).predictions] == [1]

    file = touch_arff(tmp_path / "test.arff", n=30, seed=5)
    from_file = service.predict(model.id, file)
    assert len(from_file.predictions) == 30 and "gesture" in from_file.accuracy

    with pytest.raises(errors.InvalidRequestError) as bad:
        service.predict(model, [])
    assert bad.value.field == "instances"
    with pytest.raises(FileNotFoundError):
        service.predict(model, tmp_path / "absent.arff")


def test_cancel_a_run_under_way(server: Server, service: Client, touch: str) -> None:
    gate = server.gate
    assert gate is not None
    run = service.bench(touch, target="gesture", classifiers=["gate"], folds=5)
    assert isinstance(run, Run) and not run.finished
    gate.let_through(1)
    gate.wait_started(2)  # the second task waits at the gate while the cancel comes
    cancelling = run.cancel()
    assert cancelling.status in ("cancelling", "cancelled")
    finished = run.wait(progress=False, timeout=120)
    assert finished.status == "cancelled" and finished.schema.tasks_done >= 1
    with pytest.raises(errors.ConflictError):
        service.cancel(run.id)


def test_recordings_upload_becomes_a_data_set(service: Client, tmp_path: Path) -> None:
    rows, recordings = [], []
    for i in range(2):
        path, touches = write_session(tmp_path, f"s{i}", n_touches=6, seed=i)
        recordings.append(path)
        rows += [(path.name, start, end, gesture, place) for start, end, gesture, place in touches]
    labels = write_labels(tmp_path / "labels.csv", rows)
    job = service.upload_recordings(
        recordings, labels=labels, extractor="uc3m-audio", name="client-session", wait=True
    )
    assert job.status == "done", job.schema.error
    assert job.result is not None and job.result["name"] == "client-session"
    assert service.dataset("client-session").targets == ["gesture", "place"]
    with pytest.raises(errors.InvalidRequestError) as unknown:
        service.upload_recordings(recordings, extractor="nope")
    assert unknown.value.field == "extractor"


class _Flaky(httpx.BaseTransport):
    """The real transport, but the first ``refuse`` requests fail to connect, and with
    ``break_after`` the answer to a request the service got is lost on the way back."""

    def __init__(self, refuse: int = 0, break_after: bool = False, timeout: bool = False) -> None:
        self.real = httpx.HTTPTransport()
        self.refuse, self.break_after, self.timeout = refuse, break_after, timeout
        self.sent: list[str] = []  # the requests that reached the service

    def handle_request(self, request: httpx.Request) -> httpx.Response:
        if self.refuse:
            self.refuse -= 1
            raise httpx.ConnectError("connection refused", request=request)
        if self.timeout:
            raise httpx.ReadTimeout("timed out", request=request)
        response = self.real.handle_request(request)
        response.read()
        self.sent.append(request.method)
        if self.break_after:
            raise httpx.RemoteProtocolError("the server closed the connection", request=request)
        return response

    def close(self) -> None:
        self.real.close()


def _stop(service: Client, run: Run) -> None:
    """Cancel a run the test no longer needs (the module's service stays free)."""
    with contextlib.suppress(errors.ConflictError):  # finished already
        service.cancel(run)


def _client(server: Server, transport: _Flaky, **options: Any) -> Client:
    return Client(server.url, api_key=WRITE, transport=transport, **options)


def test_retries_only_where_the_service_never_got_the_request(
    server: Server, service: Client, touch: str
) -> None:
    flaky = _Flaky(refuse=2)
    with _client(server, flaky, retries=2) as client:  # a POST never sent: sent again
        run = client.bench(touch, target="gesture", classifiers=["zeror"], folds=2)
    assert flaky.sent[0] == "POST" and flaky.sent.count("POST") == 1
    _stop(service, run)

    with (
        _client(server, _Flaky(refuse=3), retries=2) as client,
        pytest.raises(errors.ServiceUnreachableError) as unreachable,
    ):
        client.runs()
    assert unreachable.value.status is None and "cannot connect" in unreachable.value.message

    before = len(service.runs())
    broken = _Flaky(break_after=True)
    with _client(server, broken, retries=3) as client:
        with pytest.raises(errors.ServiceUnreachableError):  # the service got it: not again
            client.bench(touch, target="gesture", classifiers=["zeror"], folds=2)
        assert broken.sent == ["POST"]
        with pytest.raises(errors.ServiceUnreachableError):  # a GET goes again, then gives up
            client.runs()
        assert broken.sent == ["POST", "GET", "GET", "GET", "GET"]
    after = service.runs()
    assert len(after) == before + 1  # one run, not four
    _stop(service, after[-1])

    slow = _Flaky(timeout=True)
    with (
        _client(server, slow, retries=3, timeout=5) as client,
        pytest.raises(errors.ServiceTimeoutError) as late,
    ):
        client.runs()
    assert "within 5 s" in late.value.message and slow.sent == []

    refused = _Flaky()
    with (  # an error answer is never retried
        _client(server, refused, retries=3) as client,
        pytest.raises(errors.InvalidRequestError),
    ):
        client.bench(touch, folds=0)
    assert refused.sent == ["POST"]


def test_touchbench_exports_the_client() -> None:
    assert touchbench.Client is Client
    assert touchbench.ServiceError is errors.ServiceError
    with pytest.raises(AttributeError):
        _ = touchbench.no_such_name
