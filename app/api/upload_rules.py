"""Who reads each file of each upload route, and so how its lines are bounded: the rules of
the service's early refusal of a line too long (:class:`app.api.uploads.BodyLimit`,
:mod:`app.api.multipart_lines`).

Each rule is the reader's own: its limit, what it counts and what ends a line, and its
refusal in its own words (:func:`drivers.limits.LineTooLongError` for a recording,
:func:`benchmark.io.csv.long_line_error` for a data set's CSV...), wrapped as the route
wraps it.  So a line refused early is one the reader would refuse, named as it would name
it, by the name the route saves the file under (:func:`app.api.uploads.safe_name`).  Where
the reader is not known before the file is read (the rest of a CSV file posted to a model
trained on recordings: a recording, unless its first line names the model's features), the
file's lines are left to it.  A data set's ``format`` field counts when it comes before the
file (as our client and a browser's form send it); one sent after it is not seen yet, and
the file's name decides, as when no format is given.

A file posted to a model that is not there is answered 404 before its body is read.

Only a client whose key may call the route has its upload scanned (the others are answered
401 or 403 by the route, as ever), and only a body that may hold a line over the smallest
limit: an upload smaller than that pays nothing.
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Callable
from pathlib import Path

from starlette.concurrency import run_in_threadpool
from starlette.types import Scope

from touchbench.app.api.deps import KeyRefused, Service, key_name, needed_role
from touchbench.app.api.multipart_lines import Chooser, FilePart, LineRule
from touchbench.app.api.uploads import RefusedBeforeBodyError, safe_name
from touchbench.app.errors import AppError, NotFoundError
from touchbench.app.services.datasets import guess_format
from touchbench.app.services.labels import long_line_error as labels_line_error
from touchbench.app.services.limits import read_limits
from touchbench.benchmark.io.csv import MAX_LINE
from touchbench.benchmark.io.csv import long_line_error as csv_line_error
from touchbench.benchmark.io.textfile import MAX_LINE_BYTES
from touchbench.benchmark.io.textfile import long_line_error as arff_line_error
from touchbench.drivers.limits import LINE_CHARS, LineTooLongError, ReadLimits
from touchbench.drivers.replay import CSV_SUFFIXES

_PREDICT_FILE = re.compile(r"/api/models/(?P<ref>[^/]+)/predict/file")
PREDICT_FILE = "/api/models/{model_ref}/predict/file"


def smallest_limit() -> int:
    """The smallest line limit of any rule: a body no larger holds no line over a limit."""
    return min(read_limits().line_chars, LINE_CHARS, MAX_LINE)


async def line_rules(scope: Scope, declared: int | None) -> Chooser | None:
    """The rules of the files of the upload ``scope`` asks for, None when its lines are not
    checked: any request but a ``POST`` to an upload route by a client whose key allows it,
    or a body of ``declared`` bytes too small to hold a line over a limit."""
    if scope.get("method") != "POST" or (declared is not None and declared <= smallest_limit()):
        return None
    path = str(scope.get("path", ""))
    predicted = _PREDICT_FILE.fullmatch(path)
    template = PREDICT_FILE if predicted is not None else path
    service = getattr(getattr(scope.get("app"), "state", None), "service", None)
    if (predicted is None and template not in _ROUTES) or not isinstance(service, Service):
        return None
    try:
        key_name(service.settings, _api_key(scope), needed_role("POST", template))
    except KeyRefused:  # answered by the route, after the body, as ever
        return None
    if predicted is None:
        return _ROUTES[template]
    # start-up time: the services of models load NumPy and the engines
    from touchbench.app.services.models import predicts_recordings

    try:
        # the model decides who reads the file: asked of the store off the event loop
        recordings = await run_in_threadpool(predicts_recordings, service.store, predicted["ref"])
    except NotFoundError as missing:  # no body could make it there: said before it is read
        raise RefusedBeforeBodyError(missing) from None
    except Exception:  # a store away...: the route says it
        return None
    return lambda part: _predicted_file(part, recordings)


def _api_key(scope: Scope) -> str | None:
    """The ``X-API-Key`` header's value, as the route reads it (the first one)."""
    for key, value in scope.get("headers", ()):
        if key == b"x-api-key":
            return bytes(value).decode("latin-1")
    return None


def _dataset_file(part: FilePart) -> LineRule | None:
    """``POST /api/datasets``: an ARFF or CSV file, by its ``format`` field if it came
    first, else by its name (:func:`app.services.datasets.import_file`)."""
    if part.field != "file":
        return None
    name = safe_name(part.filename, "upload.arff")
    given = part.fields.get("format")
    if given is not None and given not in ("arff", "csv"):
        return None  # the route refuses the field
    return _data_file(name, given or guess_format(Path(name)))


def _session_file(part: FilePart) -> LineRule | None:
    """``POST /api/datasets/recordings``: recordings (read by the extraction job, with
    the service's read limits) and a labels CSV (read before the job is queued)."""
    if part.field == "recordings":
        return _recording(safe_name(part.filename, f"recording-{part.index}"))
    if part.field == "labels":
        name = safe_name(part.filename, "labels.csv")
        return LineRule(LINE_CHARS, lambda line: labels_line_error(name, line), utf8=True)
    return None


def _replay_file(part: FilePart) -> LineRule | None:
    """``POST /api/live/recordings``: a recording read with the default read limits,
    whose refusal :func:`app.services.live_sources.save_replay` says as an AppError."""
    if part.field != "recording":
        return None
    return _recording(
        safe_name(part.filename, "recording"),
        ReadLimits().line_chars,
        wrap=lambda error: AppError(str(error)),
    )


def _results_file(part: FilePart) -> LineRule | None:
    """``POST /api/runs/import-results``: a WEKA results ARFF file."""
    if part.field != "file":
        return None
    return _data_file(safe_name(part.filename, "results.arff"), "arff")


def _predicted_file(part: FilePart, recordings: bool) -> LineRule | None:
    """``POST /api/models/{ref}/predict/file``: a data file, or a raw recording when the
    model was trained on extracted features (``recordings``;
    :func:`app.services.models.predict_path`)."""
    if part.field != "file":
        return None
    name = safe_name(part.filename, "upload.arff")
    suffix = Path(name).suffix.lower()
    if not recordings or suffix == ".arff":
        return _data_file(name, guess_format(Path(name)))
    rule = _recording(name)
    if suffix == ".csv" and rule is not None:
        # a recording when its first line is too long to name features
        # (app.services.models.is_recording); the reader of the rest depends on that line
        return dataclasses.replace(rule, lines=1)
    return rule


def _data_file(name: str, file_format: str) -> LineRule:
    """A data set's file: CSV (read whole, ``\\n`` ending a line, UTF-8 else Latin-1) or
    ARFF (read in blocks of bytes)."""
    if file_format == "csv":
        return LineRule(MAX_LINE, lambda line: csv_line_error(name, line), breaks="lf")
    return LineRule(MAX_LINE_BYTES, lambda line: arff_line_error(name, line), unit="bytes")


def _recording(
    name: str,
    limit: int | None = None,
    *,
    wrap: Callable[[Exception], Exception] = lambda error: error,
) -> LineRule | None:
    """A recording: a CSV time series read by :mod:`drivers.csv_series` (strict UTF-8,
    lines bounded by ``limit`` characters, the service's read limits by default); any
    other recording is not text."""
    if Path(name).suffix.lower() not in CSV_SUFFIXES:
        return None
    most = read_limits().line_chars if limit is None else limit
    return LineRule(most, lambda line: wrap(LineTooLongError(name, line, most)), utf8=True)


#: The upload routes by path template, and the rules of their files.
_ROUTES: dict[str, Chooser] = {
    "/api/datasets": _dataset_file,
    "/api/datasets/recordings": _session_file,
    "/api/live/recordings": _replay_file,
    "/api/runs/import-results": _results_file,
}
