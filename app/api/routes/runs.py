"""Benchmark runs: start (queued, 202), list, progress, cancel, resume, leaderboard."""

from __future__ import annotations

import io

# Imports inside functions: start-up time: the leaderboard's text formats, the plots and the results
# ARFF writer load when a format other than JSON is first asked for.
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Annotated, Literal

from fastapi import APIRouter, File, Form, Query, Request, Response, UploadFile, status
from fastapi.exceptions import RequestValidationError
from fastapi.responses import PlainTextResponse

from touchbench.app.api.deps import PageDep, ServiceDep, StoreDep, paginate
from touchbench.app.api.uploads import form_request, save_upload
from touchbench.app.errors import FieldError
from touchbench.app.schemas.ablation import AblationResult
from touchbench.app.schemas.certainty import RunCertainty
from touchbench.app.schemas.folds import FoldScoresSchema
from touchbench.app.schemas.imported import ImportResultsRequest
from touchbench.app.schemas.runs import (
    Aggregate,
    BenchRequest,
    LeaderboardSchema,
    RunCreated,
    RunList,
    RunSchema,
)
from touchbench.app.services.answers import latest_ablation
from touchbench.app.services.certainty import run_certainty
from touchbench.app.services.folds import run_fold_scores
from touchbench.app.services.imported import import_results
from touchbench.app.services.lifecycle import (
    cancel_run,
    count_runs,
    get_run,
    list_runs,
    requeue_run,
)
from touchbench.app.services.runs import create_run, run_leaderboard

router = APIRouter(prefix="/api/runs", tags=["runs"])


@router.post("", status_code=status.HTTP_202_ACCEPTED, response_model=RunCreated)
def start_run(body: BenchRequest, service: ServiceDep) -> RunCreated:
    """Check the request, queue the run and answer at once; a worker process carries it out."""
    run = create_run(service.store, body)
    service.dispatcher.wake()
    return RunCreated(id=run.id, status=run.status)


@router.post("/import-results", status_code=status.HTTP_201_CREATED, response_model=RunSchema)
def import_results_file(
    service: ServiceDep,
    file: Annotated[UploadFile, File(description="A WEKA Experimenter results ARFF file.")],
    name: Annotated[str | None, Form(max_length=200)] = None,
    dataset: Annotated[str | None, Form(max_length=200)] = None,
    target: Annotated[str | None, Form(max_length=200)] = None,
) -> RunSchema:
    """Store a WEKA Experimenter results file (InstanceResultListener ARFF: one row per
    run, fold and scheme) as a finished run of its own (``touchbench import-results``)."""
    service.settings.work_dir.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=service.settings.work_dir) as folder:
        fields = {"name": name, "dataset": dataset, "target": target}
        form_request(ImportResultsRequest, file=Path(folder) / "upload", **fields)
        path = save_upload(file, Path(folder), "results.arff")
        request = form_request(ImportResultsRequest, file=path, source_name=path.name, **fields)
        return import_results(service.store, request).schema()


@router.get("", response_model=RunList)
def runs(store: StoreDep, page: PageDep, request: Request, response: Response) -> RunList:
    """The runs, oldest first, a page of at most 1,000 (``X-Total-Count``, ``Link``)."""
    paginate(request, response, page, count_runs(store))
    return RunList(runs=[run.schema() for run in list_runs(store, page=page)])


@router.get("/{run_id}", response_model=RunSchema)
def run(run_id: int, store: StoreDep) -> RunSchema:
    """A run with its status and progress (tasks done, failed, in all)."""
    return get_run(store, run_id).schema()


@router.post("/{run_id}/cancel", response_model=RunSchema)
def cancel(run_id: int, store: StoreDep) -> RunSchema:
    """Cancel a queued run at once; a running one becomes ``cancelling`` and stops within
    about half a second. Finished folds stay."""
    return cancel_run(store, run_id).schema()


@router.post("/{run_id}/resume", status_code=status.HTTP_202_ACCEPTED, response_model=RunSchema)
def resume(run_id: int, service: ServiceDep) -> RunSchema:
    """Queue an interrupted, cancelled or failed run again: only missing tasks are run."""
    run = requeue_run(service.store, run_id)
    service.dispatcher.wake()
    return run.schema()


#: ``aggregate`` of a finished run's views (its leaderboard, folds and classes).
AggregateQuery = Annotated[
    Aggregate | None,
    Query(
        description="`recording`: each recording's windows scored as one prediction; "
        "`window`: each window; from the run's stored test-fold predictions, nothing "
        "fitted again (default: as the run was scored)."
    ),
]


@contextmanager
def _query_fields() -> Iterator[None]:
    """A :class:`~app.errors.FieldError` located in the query, where these routes' fields
    are (the service's handler locates one in the body)."""
    try:
        yield
    except FieldError as error:
        raise RequestValidationError(
            [{"type": "value_error", "loc": ("query", error.field), "msg": error.message}]
        ) from None


LEADERBOARD_FORMATS = {
    "csv": "text/csv; charset=utf-8",
    "markdown": "text/markdown; charset=utf-8",
    "arff": "text/plain; charset=utf-8",
}


@router.get(
    "/{run_id}/leaderboard",
    response_model=LeaderboardSchema,
    responses={200: {"content": {kind: {} for kind in LEADERBOARD_FORMATS.values()}}},
)
def leaderboard(
    run_id: int,
    store: StoreDep,
    metric: Annotated[str | None, Query(max_length=100)] = None,
    baseline: Annotated[str | None, Query(max_length=200)] = None,
    format: Annotated[Literal["json", "csv", "markdown", "arff"], Query()] = "json",
    beside: Annotated[list[int] | None, Query(max_length=20)] = None,
    aggregate: AggregateQuery = None,
) -> LeaderboardSchema | PlainTextResponse:
    """The run's classifiers ranked by ``metric`` with WEKA's marks against ``baseline``
    (JSON: the same rows as ``touchbench leaderboard --json``); ``beside`` adds other runs'
    classifiers (same data set and target: a paper's imported results), t-tested where the
    folds pair and by their means where they do not; ``aggregate`` scores the run's stored
    predictions per recording or per window."""
    with _query_fields():
        ranked = run_leaderboard(
            store,
            run_id,
            metric=metric,
            baseline=baseline,
            beside=beside or (),
            aggregate=aggregate,
        )
    run, board = ranked.run, ranked.board
    if format == "json":
        return ranked.report()
    from touchbench.app.reports.leaderboard import (
        leaderboard_csv,
        leaderboard_markdown,
        metric_columns,
    )

    columns = metric_columns(run, board)
    if format == "csv":
        text = leaderboard_csv(board, columns, ranked.besides, aggregate=ranked.aggregate)
    elif format == "markdown":
        text = leaderboard_markdown(run, board, columns, ranked.besides, ranked.notes())
    else:
        from touchbench.app.reports.results_arff import write_results_arff

        buffer = io.StringIO()
        write_results_arff(ranked, buffer)
        text = buffer.getvalue()
    return PlainTextResponse(text, media_type=LEADERBOARD_FORMATS[format])


ClassifiersQuery = Annotated[
    str | None,
    Query(
        max_length=2000,
        description="Comma-separated classifier ids (default: every one, best first).",
    ),
]


def _classifiers(text: str | None) -> list[str] | None:
    return [c.strip() for c in text.split(",") if c.strip()] if text else None


@router.get("/{run_id}/classes", response_model=RunCertainty)
def classes(
    run_id: int,
    store: StoreDep,
    classifier: ClassifiersQuery = None,
    aggregate: AggregateQuery = None,
) -> RunCertainty:
    """Per-class precision, recall and F1, confusion matrices (summed over folds) per
    target, and out-of-fold calibration of each classifier (``touchbench classes --json``);
    ``aggregate`` counts each recording (or window) as the leaderboard scores them."""
    with _query_fields():
        return run_certainty(
            store, run_id, classifiers=_classifiers(classifier), aggregate=aggregate
        )


@router.get("/{run_id}/folds", response_model=FoldScoresSchema)
def folds(
    run_id: int,
    store: StoreDep,
    metric: Annotated[str | None, Query(max_length=100)] = None,
    alpha: Annotated[float, Query(gt=0, lt=1)] = 0.05,
    aggregate: AggregateQuery = None,
) -> FoldScoresSchema:
    """Every fold's score of every classifier, and their ranks over the folds (Friedman,
    Nemenyi's critical difference): what ``plot --kind folds`` and ``--kind cd`` draw;
    ``aggregate`` scores them per recording or per window as the leaderboard does."""
    with _query_fields():
        return run_fold_scores(store, run_id, metric=metric, alpha=alpha, aggregate=aggregate)


@router.get("/{run_id}/ablation", response_model=AblationResult)
def ablation(run_id: int, store: StoreDep) -> AblationResult:
    """The run's latest finished ablation (``bench --ablate-groups``, or a job of
    ``POST /api/jobs/ablation``)."""
    return latest_ablation(store, run_id)


@router.get(
    "/{run_id}/calibration.svg",
    # Response, not PlainTextResponse: the errors' JSON is documented as JSON then
    response_class=Response,
    responses={200: {"content": {"image/svg+xml": {}}}},
)
def calibration_svg(
    run_id: int,
    store: StoreDep,
    classifier: ClassifiersQuery = None,
    top: Annotated[int, Query(ge=1, le=50)] = 5,
    aggregate: AggregateQuery = None,
) -> Response:
    """The reliability diagram of the run's best ``top`` classifiers with probabilities,
    per recording or per window as ``aggregate`` says."""
    from touchbench.app.reports.figures import reliability_figure
    from touchbench.app.reports.plots import svg_text

    with _query_fields():
        certainty = run_certainty(
            store, run_id, classifiers=_classifiers(classifier), aggregate=aggregate
        )
    svg = svg_text(reliability_figure(certainty, top))
    return Response(svg, media_type="image/svg+xml")
