"""Benchmark runs: start (queued, 202), list, progress, cancel, resume, leaderboard."""

from __future__ import annotations

import io

# Imports inside functions: start-up time: the leaderboard's text formats and the results
# ARFF writer load when a format other than JSON is first asked for.
from typing import Annotated, Literal

from fastapi import APIRouter, Query, status
from fastapi.responses import PlainTextResponse

from app.api.deps import ServiceDep, StoreDep
from app.schemas.runs import BenchRequest, LeaderboardSchema, RunCreated, RunList, RunSchema
from app.services.runs import create_run, run_leaderboard
from app.store.runs import get_run, list_runs, request_cancel, requeue_run

router = APIRouter(prefix="/api/runs", tags=["runs"])


@router.post("", status_code=status.HTTP_202_ACCEPTED, response_model=RunCreated)
def start_run(body: BenchRequest, service: ServiceDep) -> RunCreated:
    """Check the request, queue the run and answer at once; a worker process carries it out."""
    run = create_run(service.store, body)
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
    ranked = run_leaderboard(store, run_id, metric=metric, baseline=baseline)
    run, board = ranked.run, ranked.board
    if format == "json":
        return ranked.report()
    from app.reports.leaderboard import leaderboard_csv, leaderboard_markdown, metric_columns

    columns = metric_columns(run, board)
    if format == "csv":
        text = leaderboard_csv(board, columns)
    elif format == "markdown":
        text = leaderboard_markdown(run, board, columns, ranked.notes())
    else:
        from app.reports.results_arff import write_results_arff

        buffer = io.StringIO()
        write_results_arff(ranked, buffer)
        text = buffer.getvalue()
    return PlainTextResponse(text, media_type=LEADERBOARD_FORMATS[format])
