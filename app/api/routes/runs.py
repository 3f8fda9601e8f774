"""Benchmark runs: start (queued, 202), list, progress, cancel, resume, leaderboard."""

from __future__ import annotations

from typing import Annotated, Literal

from fastapi import APIRouter, Query, status
from fastapi.responses import PlainTextResponse
from pydantic import Field

from app.api.deps import ServiceDep, StoreDep
from app.schemas.base import Schema
from app.schemas.runs import LeaderboardSchema, RunCreated, RunList, RunSchema
from app.services.runs import RunOptions, create_run, leaderboard_schema
from app.store.runs import get_run, list_runs, request_cancel, requeue_run

router = APIRouter(prefix="/api/runs", tags=["runs"])


class RunRequest(Schema):
    """What to cross-validate: a data set, its target(s), classifiers or a suite, protocol."""

    dataset: str | int = Field(description="Data set name or id.")
    target: str | None = Field(
        default=None, description="One target for the multi-class catalogue."
    )
    classifiers: list[str] | None = Field(default=None, min_length=1, max_length=500)
    weka: list[str] | None = Field(
        default=None,
        max_length=50,
        description='WEKA command lines, e.g. "weka.classifiers.trees.J48 -C 0.1 -M 5".',
    )
    suite: Literal["fast", "default", "all"] | None = None
    position: list[str] | None = Field(
        default=None,
        min_length=2,
        max_length=3,
        description="Numeric targets that are a position's coordinates (mean Euclidean error).",
    )
    folds: int = Field(default=10, ge=2, le=100)
    repeats: int = Field(default=1, ge=1, le=100)
    seed: int = Field(default=0, ge=0, le=2**31 - 1)
    timeout: float | None = Field(default=600.0, gt=0, le=7 * 24 * 3600)
    max_memory_mb: float | None = Field(default=None, gt=0)
    tune: bool = Field(
        default=False, description="Add tuned twins (ID+tuned), searched inside each fold."
    )
    budget: float | None = Field(
        default=None, description="With tune: minutes per tuned twin and outer fold."
    )
    stack: int | None = Field(
        default=None, description="Add stack-topN over the run's N best by inner CV."
    )


@router.post("", status_code=status.HTTP_202_ACCEPTED, response_model=RunCreated)
def start_run(body: RunRequest, service: ServiceDep) -> RunCreated:
    """Check the request, queue the run and answer at once; a worker process carries it out."""
    run = create_run(
        service.store,
        str(body.dataset),
        body.classifiers,
        suite=body.suite,
        targets=[body.target] if body.target else None,
        options=RunOptions(
            folds=body.folds,
            repeats=body.repeats,
            seed=body.seed,
            timeout=body.timeout,
            max_memory_mb=body.max_memory_mb,
        ),
        weka=body.weka or (),
        position=body.position or (),
        tune=body.tune,
        budget=body.budget,
        stack=body.stack,
    )
    service.dispatcher.wake()
    return RunCreated(id=run.id, status=run.status)


@router.get("", response_model=RunList)
def runs(store: StoreDep) -> RunList:
    return RunList(runs=[run.schema() for run in list_runs(store)])


@router.get("/{run_id}", response_model=RunSchema)
def run(run_id: int, store: StoreDep) -> RunSchema:
    """A run with its status and progress (tasks done, failed, in all)."""
    return get_run(store, run_id).schema()


@router.post("/{run_id}/cancel", response_model=RunSchema)
def cancel(run_id: int, store: StoreDep) -> RunSchema:
    """Cancel a queued run at once; a running one becomes ``cancelling`` and stops within
    about half a second. Finished folds stay."""
    return request_cancel(store, run_id).schema()


@router.post("/{run_id}/resume", status_code=status.HTTP_202_ACCEPTED, response_model=RunSchema)
def resume(run_id: int, service: ServiceDep) -> RunSchema:
    """Queue an interrupted, cancelled or failed run again: only missing tasks are run."""
    run = requeue_run(service.store, run_id)
    service.dispatcher.wake()
    return run.schema()


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
) -> LeaderboardSchema | PlainTextResponse:
    """The run's classifiers ranked by ``metric`` with WEKA's marks against ``baseline``
    (JSON: the same rows as ``touchbench leaderboard --json``)."""
    run, board, report = leaderboard_schema(store, run_id, metric=metric, baseline=baseline)
    if format == "json":
        return report
    from app.reports.leaderboard import leaderboard_csv, leaderboard_markdown, metric_columns

    columns = metric_columns(run, board)
    if format == "csv":
        text = leaderboard_csv(board, columns)
    elif format == "markdown":
        text = leaderboard_markdown(run, board, columns)
    else:
        import io

        from app.reports.results_arff import write_results_arff

        buffer = io.StringIO()
        write_results_arff(store, run, buffer)
        text = buffer.getvalue()
    return PlainTextResponse(text, media_type=LEADERBOARD_FORMATS[format])
