"""``touchbench.Client``: the service's verbs from Python, over HTTP.

The client speaks the service's REST API (the same request bodies as the CLI's requests,
the same response models), with the API key in the ``X-API-Key`` header the service reads
(:mod:`app.api.deps`).  Errors are exceptions of :mod:`app.python.errors` carrying the
service's status, kind, message and field.  A request is retried only when it never
reached the service (the connection could not be made), or, for a request that changes
nothing (GET), when the connection broke; a POST the service may have received is never
sent again, and an error answer (4xx, 5xx) is never retried.
"""

from __future__ import annotations

import contextlib
import json as jsonlib
import math
import os
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from pathlib import Path
from types import TracebackType
from typing import TYPE_CHECKING, Any, Self

import httpx

from touchbench.app.python.errors import (
    ServiceError,
    ServiceTimeoutError,
    ServiceUnreachableError,
    service_error,
)
from touchbench.app.python.leaderboard import Leaderboard
from touchbench.app.python.work import Job, Run
from touchbench.app.schemas.certainty import RunCertainty
from touchbench.app.schemas.datasets import DatasetDescription, ImportResult
from touchbench.app.schemas.folds import FoldScoresSchema
from touchbench.app.schemas.jobs import JobSchema
from touchbench.app.schemas.models import ModelSchema, PredictionReport
from touchbench.app.schemas.runs import Aggregate, LeaderboardSchema, RunSchema

if TYPE_CHECKING:
    import pandas as pd

#: Methods whose request may be sent again after a broken connection: they change nothing
#: (the service's GETs), so a second delivery does no harm.
SAFE_METHODS = frozenset({"GET", "HEAD", "OPTIONS"})
#: Seconds one request may take unless the client is told otherwise.
DEFAULT_TIMEOUT = 60.0
#: Attempts after the first on a connection error.
DEFAULT_RETRIES = 3
#: Suites a benchmark may name instead of classifier ids (:data:`app.schemas.runs.Suite`).
_SUITES = ("fast", "default", "all")

Files = list[tuple[str, tuple[str, Any, str]]]


class Client:
    """A touchbench service, from Python.

    Parameters
    ----------
    url : str
        The service, e.g. ``http://127.0.0.1:8000``.
    api_key : str, optional
        The service's key; default the environment's ``TOUCHBENCH_API_KEY`` (none without
        it).  Sent in the ``X-API-Key`` header, never shown (not in ``repr``, not in an
        exception, not logged).
    timeout : float
        Seconds a request may take (uploads and predictions included) before
        :class:`~app.python.errors.ServiceTimeoutError`.
    retries : int
        Attempts after the first when the connection cannot be made (and, for GETs, when
        it breaks); pauses of 0.2, 0.4, 0.8... seconds between them.
    transport : httpx.BaseTransport, optional
        httpx's transport (tests, proxies, a mounted ASGI app).

    Examples
    --------
    >>> with touchbench.Client("http://127.0.0.1:8000", api_key="...") as service:
    ...     run = service.bench(dataset="touch", target="gesture", wait=True)
    ...     run.leaderboard().to_pandas()
    """

    def __init__(
        self,
        url: str,
        api_key: str | None = None,
        *,
        timeout: float = DEFAULT_TIMEOUT,
        retries: int = DEFAULT_RETRIES,
        transport: httpx.BaseTransport | None = None,
    ) -> None:
        if retries < 0:
            raise ValueError(f"retries must be at least 0, got {retries}")
        key = api_key if api_key is not None else os.environ.get("TOUCHBENCH_API_KEY")
        headers = {"X-API-Key": key} if key else {}
        self.url = url.rstrip("/")
        self.timeout = timeout
        self.retries = retries
        self._http = httpx.Client(
            base_url=self.url,
            headers=headers,
            timeout=httpx.Timeout(timeout, connect=min(timeout, 10.0)),
            transport=transport,
        )

    def __repr__(self) -> str:
        return f"Client({self.url!r})"  # never the key

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        self.close()

    def close(self) -> None:
        """Close the connections (the context manager does it on leaving)."""
        self._http.close()

    # --- data sets ------------------------------------------------------------------

    def upload(
        self,
        path: str | os.PathLike[str],
        *,
        name: str | None = None,
        targets: str | Sequence[str] | None = None,
        format: str | None = None,
        groups: str | None = None,
        ignore: str | Sequence[str] | None = None,
    ) -> ImportResult:
        """Import an ARFF or CSV file as a data set (``touchbench import``).

        Parameters
        ----------
        path : path-like
        name : str, optional
            Default: the file's name.
        targets : str or sequence of str, optional
            ``N`` first attributes, ``-N`` last ones, or names.
        format : {"arff", "csv"}, optional
            Default: by the file's ending.
        groups : str, optional
            The column naming each instance's group (never a feature).
        ignore : str or sequence of str, optional
            Columns to leave out.
        """
        file = Path(path)
        fields = {
            "name": name,
            "targets": _joined(targets),
            "format": format,
            "groups": groups,
            "ignore": _joined(ignore),
        }
        response = self._send(
            "POST",
            "/api/datasets",
            data=_form(fields),
            files=lambda stack: [("file", _opened(stack, file))],
        )
        return ImportResult.model_validate(response.json())

    def upload_recordings(
        self,
        paths: Iterable[str | os.PathLike[str]],
        *,
        labels: str | os.PathLike[str] | None = None,
        wait: bool = False,
        progress: bool = True,
        **options: Any,
    ) -> Job:
        """Upload a recording session; its extraction is a job whose result is the new data
        set (``POST /api/datasets/recordings``).

        Parameters
        ----------
        paths : iterable of path-like
            Recordings (WAV, FLAC, CSV time series, bags).
        labels : path-like, optional
            Labels CSV: ``file,start,end,TARGET...`` or ``file,TARGET...``.
        wait : bool
            Return once the extraction has finished (``job.result`` names the data set).
        progress : bool
            With ``wait``: show a progress bar.
        **options
            The upload form's fields: ``extractor``, ``events``, ``name``, ``samplerate``,
            ``segment``, ``topic``, ``fields`` (a list), ``time_column``, ``time_unit``,
            ``channels``, ``sample_format``.
        """
        files = [Path(p) for p in paths]
        if not files:
            raise ValueError("recordings: give at least one recording")
        label_file = None if labels is None else Path(labels)

        def opened(stack: contextlib.ExitStack) -> Files:
            parts = [("recordings", _opened(stack, f)) for f in files]
            if label_file is not None:
                parts.append(("labels", _opened(stack, label_file)))
            return parts

        response = self._send("POST", "/api/datasets/recordings", data=_form(options), files=opened)
        job = self.job(response.json()["job"])
        return job.wait(progress=progress) if wait else job

    def datasets(self) -> list[dict[str, Any]]:
        """The data sets (their summaries, oldest first; the first 1,000)."""
        return list(self._get("/api/datasets", params={"limit": 1000})["datasets"])

    def dataset(self, dataset: str | int) -> DatasetDescription:
        """A data set's schema, class distribution and missing values (``touchbench show``)."""
        return DatasetDescription.model_validate(self._get(f"/api/datasets/{dataset}"))

    # --- runs -----------------------------------------------------------------------

    def bench(
        self,
        dataset: str | int,
        *,
        target: str | None = None,
        classifiers: str | Sequence[str] | None = None,
        folds: int | None = None,
        repeats: int | None = None,
        seed: int | None = None,
        wait: bool = False,
        progress: bool = True,
        timeout: float | None = None,
        **options: Any,
    ) -> Run:
        """Start a benchmark run (``touchbench bench``; the service queues it).

        Parameters
        ----------
        dataset : str or int
            Data set name or id.
        target : str, optional
            Benchmark this one target; default the data set's own targets.
        classifiers : str or sequence of str, optional
            A suite (``fast``, ``default``, ``all``) or classifier ids (``rf``,
            ``bcc:rf``...); default the service's (``default``).
        folds, repeats, seed : int, optional
            k of k-fold, repeats of it, the seed; default the service's (10, 1, 0).
        wait : bool
            Return once the run has finished, showing its progress.
        progress : bool
            With ``wait``: show a progress bar (tqdm: in Jupyter, in a terminal).
        timeout : float, optional
            With ``wait``: seconds to wait at most (:class:`~app.python.errors.WaitTimeoutError`).
        **options
            Any other field of the run's request (:class:`app.schemas.runs.BenchRequest`):
            ``metric``, ``baseline``, ``race``, ``tune``, ``aggregate``...; the service
            checks them and refuses a wrong one naming it.
        """
        body: dict[str, Any] = {"dataset": dataset, **options}
        if isinstance(classifiers, str):
            key = "suite" if classifiers in _SUITES else "classifiers"
            body[key] = classifiers if key == "suite" else [classifiers]
        elif classifiers is not None:
            body["classifiers"] = list(classifiers)
        for field, value in (("target", target), ("folds", folds), ("repeats", repeats)):
            if value is not None:
                body[field] = value
        if seed is not None:
            body["seed"] = seed
        created = self._send("POST", "/api/runs", json=body).json()
        run = self.run(created["id"])
        return run.wait(progress=progress, timeout=timeout) if wait else run

    def run(self, run: Run | int) -> Run:
        """A run with its status and progress."""
        return Run(self, RunSchema.model_validate(self._get(f"/api/runs/{_run_id(run)}")))

    def runs(self) -> list[Run]:
        """The runs, oldest first (the first 1,000)."""
        listed = self._get("/api/runs", params={"limit": 1000})["runs"]
        return [Run(self, RunSchema.model_validate(item)) for item in listed]

    def leaderboard(
        self,
        run: Run | int,
        *,
        metric: str | None = None,
        baseline: str | None = None,
        aggregate: Aggregate | None = None,
    ) -> Leaderboard:
        """A run's leaderboard (``touchbench leaderboard --json``'s rows), its plots drawn
        from the service's per-fold scores and confusion matrices.

        Parameters
        ----------
        run : Run or int
        metric, baseline : str, optional
            Rank by this metric, mark against this classifier; default the run's.
        aggregate : {"window", "recording"}, optional
            Score each window, or each recording's windows as one prediction, from the
            run's stored test-fold predictions, nothing fitted again (``leaderboard
            --aggregate``); default as the run scored.  The service refuses a run it cannot
            re-score (an imported one, data without recordings) naming ``aggregate``.
        """
        asked = (("metric", metric), ("baseline", baseline), ("aggregate", aggregate))
        params = {k: v for k, v in asked if v is not None}
        data = self._get(f"/api/runs/{_run_id(run)}/leaderboard", params=params)
        return Leaderboard(LeaderboardSchema.model_validate(data), _HttpSource(self))

    def cancel(self, run: Run | int) -> Run:
        """Cancel a run: a queued one at once, a running one within about half a second
        (finished folds stay)."""
        data = self._send("POST", f"/api/runs/{_run_id(run)}/cancel").json()
        return Run(self, RunSchema.model_validate(data))

    def resume(self, run: Run | int) -> Run:
        """Queue an interrupted, cancelled or failed run again (only missing tasks run)."""
        data = self._send("POST", f"/api/runs/{_run_id(run)}/resume").json()
        return Run(self, RunSchema.model_validate(data))

    # --- models ---------------------------------------------------------------------

    def train(
        self,
        dataset: str | int | None = None,
        classifier: str | None = None,
        *,
        run: Run | int | None = None,
        wait: bool = False,
        progress: bool = True,
        **options: Any,
    ) -> Job:
        """Train a model as a job (``touchbench train``): ``classifier`` on ``dataset``, or
        a run's best classifier (``run``); ``job.model()`` is the model once done.

        Parameters
        ----------
        dataset : str or int, optional
        classifier : str, optional
        run : Run or int, optional
        wait : bool
            Return once training has finished.
        **options
            Other fields of :class:`app.schemas.models.TrainRequest`: ``target``,
            ``name``, ``seed``, ``onnx``.
        """
        body = {
            k: v
            for k, v in (
                ("dataset", dataset),
                ("classifier", classifier),
                ("run", None if run is None else _run_id(run)),
            )
            if v is not None
        }
        created = self._send("POST", "/api/models", json={**body, **options}).json()
        job = self.job(created["job"])
        return job.wait(progress=progress) if wait else job

    def models(self) -> list[ModelSchema]:
        """The models, oldest first (the first 1,000)."""
        listed = self._get("/api/models", params={"limit": 1000})["models"]
        return [ModelSchema.model_validate(item) for item in listed]

    def model(self, model: str | int) -> ModelSchema:
        """A model by id, ``NAME``, ``NAME@VERSION`` or ``NAME@ALIAS``."""
        return ModelSchema.model_validate(self._get(f"/api/models/{model}"))

    def predict(
        self,
        model: str | int | ModelSchema,
        instances: pd.DataFrame
        | Sequence[Mapping[str, Any]]
        | Mapping[str, Any]
        | str
        | os.PathLike[str],
        *,
        missing: str | None = None,
        engine: str | None = None,
    ) -> PredictionReport:
        """Predict instances with a model.

        Parameters
        ----------
        model : str, int or ModelSchema
            Id, ``NAME``, ``NAME@VERSION`` or ``NAME@ALIAS``.
        instances : DataFrame, dict, sequence of dicts, or path-like
            ``{attribute: value}`` rows (a DataFrame's rows; NaN as missing), or a file:
            ARFF or CSV with the model's attributes, or a raw recording of a model trained
            on extracted features.
        missing : {"refuse", "allow"}, optional
            Rows: what to do with an instance without some of the model's attributes.
        engine : {"auto", "onnx", "native"}, optional
        """
        ref = model.id if isinstance(model, ModelSchema) else model
        if isinstance(instances, str | os.PathLike):
            file = Path(instances)
            response = self._send(
                "POST",
                f"/api/models/{ref}/predict/file",
                data=_form({"engine": engine}),
                files=lambda stack: [("file", _opened(stack, file))],
            )
        else:
            options = {k: v for k, v in (("missing", missing), ("engine", engine)) if v is not None}
            body = _instances_json(instances, options)
            response = self._send("POST", f"/api/models/{ref}/predict", content=body)
        return PredictionReport.model_validate(response.json())

    # --- jobs -----------------------------------------------------------------------

    def job(self, job: Job | int) -> Job:
        """A job (extraction, training, ...) with its status and, once done, its result."""
        job_id = job.id if isinstance(job, Job) else job
        return Job(self, JobSchema.model_validate(self._get(f"/api/jobs/{job_id}")))

    def cancel_job(self, job: Job | int) -> Job:
        """Cancel a job: a queued one at once, a running one within about half a second."""
        job_id = job.id if isinstance(job, Job) else job
        data = self._send("POST", f"/api/jobs/{job_id}/cancel").json()
        return Job(self, JobSchema.model_validate(data))

    # --- HTTP -----------------------------------------------------------------------

    def _get(self, path: str, *, params: Mapping[str, Any] | None = None) -> Any:
        return self._send("GET", path, params=params).json()

    def _send(
        self,
        method: str,
        path: str,
        *,
        params: Mapping[str, Any] | None = None,
        json: Any = None,
        content: bytes | None = None,
        data: Mapping[str, Any] | None = None,
        files: Callable[[contextlib.ExitStack], Files] | None = None,
    ) -> httpx.Response:
        """One request, retried as the module says; an error answer raised as its
        :class:`~app.python.errors.ServiceError`.  ``content`` is a JSON body already
        encoded; ``files`` opens the uploads afresh for each attempt (an attempt may have
        read them)."""
        headers = {"content-type": "application/json"} if content is not None else None
        attempt = 0
        while True:
            try:
                with contextlib.ExitStack() as stack:
                    response = self._http.request(
                        method,
                        path,
                        params=params,
                        json=json,
                        content=content,
                        headers=headers,
                        data=data,
                        files=files(stack) if files is not None else None,
                    )
                break
            except (httpx.ConnectError, httpx.ConnectTimeout) as error:
                # the service never got the request: sending it again is safe for any method
                problem: ServiceError = ServiceUnreachableError(
                    f"cannot connect to {self.url}: {_reason(error)}"
                )
                again = True
            except httpx.TimeoutException:
                raise ServiceTimeoutError(
                    f"{method} {path}: no answer from {self.url} within {self.timeout:g} s"
                ) from None
            except (httpx.ReadError, httpx.WriteError, httpx.RemoteProtocolError) as error:
                # the service may have got it: only a request that changes nothing goes again
                problem = ServiceUnreachableError(
                    f"{method} {path}: the connection to {self.url} broke: {_reason(error)}"
                )
                again = method in SAFE_METHODS
            except httpx.HTTPError as error:
                raise ServiceUnreachableError(f"{method} {path}: {_reason(error)}") from None
            if not again or attempt >= self.retries:
                raise problem from None
            time.sleep(0.2 * 2**attempt)
            attempt += 1
        if response.status_code >= 400:
            raise service_error(response.status_code, _json_or_none(response), response.text)
        return response


class _HttpSource:
    """What a leaderboard's plots read, fetched from the service."""

    def __init__(self, client: Client) -> None:
        self._client = client

    def fold_scores(self, run_id: int, *, metric: str, aggregate: Aggregate) -> FoldScoresSchema:
        params = {"metric": metric, "aggregate": aggregate}
        data = self._client._get(f"/api/runs/{run_id}/folds", params=params)
        return FoldScoresSchema.model_validate(data)

    def classes(self, run_id: int, *, classifier: str, aggregate: Aggregate) -> RunCertainty:
        params = {"classifier": classifier, "aggregate": aggregate}
        data = self._client._get(f"/api/runs/{run_id}/classes", params=params)
        return RunCertainty.model_validate(data)


def _run_id(run: Run | int) -> int:
    return run.id if isinstance(run, Run) else int(run)


def _joined(value: str | Sequence[str] | None) -> str | None:
    if value is None or isinstance(value, str):
        return value
    return ",".join(value)


def _form(fields: Mapping[str, Any]) -> dict[str, Any]:
    """A form's fields without the absent ones (lists stay lists: repeated fields)."""
    return {
        key: [str(v) for v in value] if isinstance(value, list | tuple) else str(value)
        for key, value in fields.items()
        if value is not None
    }


def _opened(stack: contextlib.ExitStack, path: Path) -> tuple[str, Any, str]:
    """The upload of ``path`` under its own name (a missing file: FileNotFoundError, before
    anything is sent)."""
    return (path.name, stack.enter_context(path.open("rb")), "application/octet-stream")


def _instances_json(
    instances: pd.DataFrame | Sequence[Mapping[str, Any]] | Mapping[str, Any],
    options: Mapping[str, Any],
) -> bytes:
    """A prediction's JSON body.  Rows of plain values are encoded as they are, by the
    json module's C encoder in one call; anything else (a DataFrame, NaN, numpy scalars)
    goes through :func:`_records` first."""
    if isinstance(instances, list | tuple):
        try:
            return _dumps({"instances": instances, **options})
        except (TypeError, ValueError):  # NaN or values JSON lacks: converted below
            pass
    return _dumps({"instances": _records(instances), **options})


def _dumps(body: Any) -> bytes:
    return jsonlib.dumps(body, allow_nan=False, separators=(",", ":")).encode()


def _records(
    instances: pd.DataFrame | Sequence[Mapping[str, Any]] | Mapping[str, Any],
) -> list[dict[str, Any]]:
    """Rows as ``{attribute: value}`` dicts, NaN as a missing value (JSON null)."""
    if isinstance(instances, Mapping):
        rows: Iterable[Mapping[str, Any]] = [instances]
    elif hasattr(instances, "to_dict"):
        rows = instances.to_dict(orient="records")
    else:
        rows = instances
    return [
        {key if type(key) is str else str(key): _plain(value) for key, value in row.items()}
        for row in rows
    ]


#: Values sent as they are (the usual case, checked by exact type: the quickest test).
_PLAIN = frozenset({str, int, bool, type(None)})


def _plain(value: Any) -> Any:
    """A value as JSON takes it: NaN as null (a missing value), numpy scalars as Python's."""
    kind = type(value)
    if kind in _PLAIN:
        return value
    if kind is float:
        return None if math.isnan(value) else value
    if hasattr(value, "item"):  # numpy scalars
        value = value.item()
    if isinstance(value, float) and math.isnan(value):
        return None
    return value


def _json_or_none(response: httpx.Response) -> Any:
    try:
        return response.json()
    except ValueError:
        return None


def _reason(error: httpx.HTTPError) -> str:
    return str(error) or type(error).__name__
