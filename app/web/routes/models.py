"""Fragments of models: the list, and one model with the form that predicts with it."""

from __future__ import annotations

from fastapi import APIRouter
from fastapi.responses import HTMLResponse

from app.schemas.runs import FINAL_STATUSES
from app.store.jobs import list_jobs
from app.store.models import get_model, list_models
from app.web.deps import StoreDep
from app.web.rendering import render
from app.web.routes.pages import Ref
from benchmark.dataset import Schema

router = APIRouter(prefix="/fragments/models", include_in_schema=False)


@router.get("", response_class=HTMLResponse)
def models(store: StoreDep) -> HTMLResponse:
    """Every model; polled while a training job is queued or running."""
    training = [
        job for job in list_jobs(store) if job.kind == "train" and job.status not in FINAL_STATUSES
    ]
    return render("fragments/models.html.j2", models=list_models(store), training=training)


@router.get("/{model}", response_class=HTMLResponse)
def model(model: Ref, store: StoreDep) -> HTMLResponse:
    """What the model classifies, and one input per feature it needs (a number, or a
    choice of the labels it was trained with)."""
    info = get_model(store, model)
    return render(
        "fragments/model.html.j2",
        model=info.to_schema(),
        features=Schema.from_json(info.schema).features,
    )
