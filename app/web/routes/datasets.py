"""Fragments of data sets: the list, and one data set's schema and class distributions."""

from __future__ import annotations

# Imports inside functions: start-up time: matplotlib loads when a class distribution is
# first drawn.
from functools import partial

from fastapi import APIRouter
from fastapi.responses import HTMLResponse

from touchbench.app.schemas.extraction import ExtractionSummary
from touchbench.app.services.answers import latest_learning_curve
from touchbench.app.services.datasets import describe_dataset
from touchbench.app.services.lifecycle import count_runs, get_job, list_runs
from touchbench.app.services.listing import count_datasets, list_datasets
from touchbench.app.store.database import Store
from touchbench.app.web.deps import StoreDep
from touchbench.app.web.listing import newest
from touchbench.app.web.rendering import draw, render
from touchbench.app.web.routes.pages import Ref

router = APIRouter(prefix="/fragments/datasets", include_in_schema=False)


@router.get("", response_class=HTMLResponse)
def datasets(store: StoreDep) -> HTMLResponse:
    """The newest data sets and how many are older."""
    listed = newest(count_datasets(store), partial(list_datasets, store))
    return render("fragments/datasets.html.j2", datasets=listed)


@router.get("/{dataset}", response_class=HTMLResponse)
def dataset(dataset: Ref, store: StoreDep, job: int | None = None) -> HTMLResponse:
    """Attributes, class distribution per target (table and plot), the runs on it, and its
    newest learning curve (table and plot) when one was computed; with ``job``, the
    extraction job that made it: what it found, dropped and noted."""
    from touchbench.app.reports.answer_tables import learning_table
    from touchbench.app.reports.figures import dataset_classes_figure, learning_figure

    description = describe_dataset(store, dataset)
    curve = latest_learning_curve(store, description.id, description.name)
    return render(
        "fragments/dataset.html.j2",
        dataset=description,
        extraction=_extraction(store, job, description.id),
        plot=draw("Instances per class", partial(dataset_classes_figure, description)),
        runs=newest(
            count_runs(store, dataset_id=description.id),
            partial(list_runs, store, dataset_id=description.id),
        ),
        learning=None if curve is None else learning_table(curve),
        learning_plot=None
        if curve is None
        else draw("Score by share of each training fold", partial(learning_figure, curve)),
    )


def _extraction(store: Store, job_id: int | None, dataset_id: int) -> ExtractionSummary | None:
    """The summary of extraction job ``job_id`` when it made data set ``dataset_id``."""
    if job_id is None:
        return None
    found = get_job(store, job_id)
    if found.kind != "extract" or not found.result or found.result.get("id") != dataset_id:
        return None
    fields = ExtractionSummary.model_fields  # the result also holds the job's own keys
    return ExtractionSummary.model_validate(
        {key: value for key, value in found.result.items() if key in fields}
    )
