"""Fragments of models: the list, and one model: its versions and aliases with the actions
that move them, its ONNX twin, and the forms that predict with it."""

from __future__ import annotations

# Imports inside functions: start-up time: the leaderboards' statistics load with the first
# model page that shows a score.
from functools import partial

from fastapi import APIRouter
from fastapi.responses import HTMLResponse

from touchbench.app.errors import AppError
from touchbench.app.schemas.models import AliasBody
from touchbench.app.schemas.status import FINAL
from touchbench.app.services.lifecycle import count_jobs, list_jobs
from touchbench.app.services.registry import count_models, find_model, list_models
from touchbench.app.store.database import Store
from touchbench.app.store.models import ModelInfo
from touchbench.app.web.deps import StoreDep
from touchbench.app.web.listing import newest
from touchbench.app.web.rendering import render
from touchbench.app.web.request_form import form_fields
from touchbench.app.web.routes.pages import Ref
from touchbench.benchmark.dataset import Schema
from touchbench.benchmark.errors import BenchmarkError

router = APIRouter(prefix="/fragments/models", include_in_schema=False)


@router.get("", response_class=HTMLResponse)
def models(store: StoreDep) -> HTMLResponse:
    """Every model; polled while a training job is queued or running."""
    recent = newest(count_jobs(store), partial(list_jobs, store)).items
    training = [job for job in recent if job.kind == "train" and job.status not in FINAL]
    listed = newest(count_models(store), partial(list_models, store))
    return render("fragments/models.html.j2", models=listed, training=training)


@router.get("/{model}", response_class=HTMLResponse)
def model(model: Ref, store: StoreDep) -> HTMLResponse:
    """What the model classifies, its name's versions (score in the run each came from,
    aliases, the actions that move them), its ONNX twin, and the forms that predict: one
    input per feature it needs, or a file (instances, or a raw recording)."""
    info = find_model(store, model)
    listed = newest(count_models(store), partial(list_models, store))
    versions = [found for found in listed.items if found.name == info.name]
    return render(
        "fragments/model.html.j2",
        model=info.to_schema(),
        features=Schema.from_json(info.schema).features,
        versions=[(found.to_schema(), _score(store, found)) for found in reversed(versions)],
        older=bool(listed.more),
        alias_field=form_fields(AliasBody)["alias"],
    )


def _score(store: Store, found: ModelInfo) -> str:
    """The version's classifier's mean score in the run it came from (``-``: none)."""
    from touchbench.app.services.runs import NoResultsError, ranked_run

    if found.run_id is None:
        return "-"
    try:
        board = ranked_run(store, found.run_id).board
        mean = board.row(found.classifier).metrics[board.metric][0]
    except (AppError, BenchmarkError, NoResultsError, KeyError):
        return "-"
    return f"{board.metric} {mean:.4f}"
