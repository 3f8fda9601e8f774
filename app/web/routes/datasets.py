"""Fragments of data sets: the list, and one data set's schema and class distributions."""

from __future__ import annotations

# Imports inside functions: start-up time: matplotlib loads when a class distribution is
# first drawn.
from functools import partial

from fastapi import APIRouter
from fastapi.responses import HTMLResponse

from app.services.datasets import describe_dataset
from app.services.listing import list_datasets
from app.store.runs import list_runs
from app.web.deps import StoreDep
from app.web.rendering import draw, render
from app.web.routes.pages import Ref

router = APIRouter(prefix="/fragments/datasets", include_in_schema=False)


@router.get("", response_class=HTMLResponse)
def datasets(store: StoreDep) -> HTMLResponse:
    return render("fragments/datasets.html.j2", datasets=list_datasets(store))


@router.get("/{dataset}", response_class=HTMLResponse)
def dataset(dataset: Ref, store: StoreDep) -> HTMLResponse:
    """Attributes, class distribution per target (table and plot), the runs on it."""
    from app.reports.figures import dataset_classes_figure

    description = describe_dataset(store, dataset)
    return render(
        "fragments/dataset.html.j2",
        dataset=description,
        plot=draw("Instances per class", partial(dataset_classes_figure, description)),
        runs=[run for run in list_runs(store) if run.dataset_id == description.id],
    )
