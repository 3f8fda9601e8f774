"""Fragments of models: the list, and one model with the form that predicts with it."""

from __future__ import annotations

from functools import partial

from fastapi import APIRouter
from fastapi.responses import HTMLResponse

from touchbench.app.schemas.status import FINAL
from touchbench.app.services.lifecycle import count_jobs, list_jobs
from touchbench.app.services.registry import count_models, find_model, list_models
from touchbench.app.web.deps import StoreDep
from touchbench.app.web.listing import newest
from touchbench.app.web.rendering import render
from touchbench.app.web.routes.pages import Ref
from touchbench.benchmark.dataset import Schema

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
    """What the model classifies, and one input per feature it needs (a number, or a
    choice of the labels it was trained with)."""
    info = find_model(store, model)
    return render(
        "fragments/model.html.j2",
        model=info.to_schema(),
        features=Schema.from_json(info.schema).features,
    )
