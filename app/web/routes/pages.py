"""The pages: frames that hold no data, only the layout and the addresses of the fragments
that the script loads into them with the API key (see :mod:`app.web.site`).

So these answer without the key, and never read the store: an unknown run or data set is
said by its fragment, as the JSON API says it.
"""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Path, Query
from fastapi.responses import HTMLResponse

from touchbench.app.web.rendering import render

router = APIRouter(include_in_schema=False)

Ref = Annotated[str, Path(max_length=200)]


@router.get("/", response_class=HTMLResponse)
def home() -> HTMLResponse:
    """Data sets (with the upload form), runs and models."""
    return render("home.html.j2", title="touchbench")


@router.get("/datasets/{dataset}", response_class=HTMLResponse)
def dataset(dataset: Ref) -> HTMLResponse:
    return render("dataset.html.j2", title=f"data set {dataset}", dataset=dataset)


@router.get("/recordings/new", response_class=HTMLResponse)
def new_session() -> HTMLResponse:
    """The form that uploads a recording session and extracts a data set from it."""
    return render("new_session.html.j2", title="upload a recording session")


@router.get("/runs/new", response_class=HTMLResponse)
def new_run(dataset: Annotated[str | None, Query(max_length=200)] = None) -> HTMLResponse:
    return render("new_run.html.j2", title="new run", dataset=dataset)


@router.get("/runs/{run_id}", response_class=HTMLResponse)
def run(run_id: int) -> HTMLResponse:
    """Progress, leaderboard (sorted and marked as the query says) and plots."""
    return render("run.html.j2", title=f"run {run_id}", run_id=run_id)


@router.get("/runs/{run_id}/classifiers/{classifier}", response_class=HTMLResponse)
def classifier(run_id: int, classifier: Ref) -> HTMLResponse:
    """One classifier of a run: confusion matrix and per-fold scores."""
    return render(
        "classifier.html.j2",
        title=f"{classifier} in run {run_id}",
        run_id=run_id,
        classifier=classifier,
    )


@router.get("/compare", response_class=HTMLResponse)
def compare() -> HTMLResponse:
    """Ranks, Friedman, Nemenyi and Holm across runs, with the CD diagram."""
    return render("compare.html.j2", title="compare runs")


@router.get("/models/{model}", response_class=HTMLResponse)
def model(model: Ref) -> HTMLResponse:
    """A model and the form that predicts with it."""
    return render("model.html.j2", title=f"model {model}", model=model)
