"""The fragment comparing runs: the runs to pick from, and for the picked ones the ranks,
Friedman's and Holm's tests, Nemenyi's groups and the critical-difference diagram."""

from __future__ import annotations

# Imports inside functions: start-up time: matplotlib and the statistics load when a
# comparison is first drawn, not when the service starts.
from functools import partial
from typing import TYPE_CHECKING, Annotated

from fastapi import APIRouter, Query
from fastapi.responses import HTMLResponse

from touchbench.app.errors import AppError
from touchbench.app.reports.bounds import Shown
from touchbench.app.services.lifecycle import count_runs, list_runs
from touchbench.app.web.deps import StoreDep
from touchbench.app.web.listing import newest
from touchbench.app.web.rendering import draw, render
from touchbench.benchmark.errors import BenchmarkError

if TYPE_CHECKING:
    from touchbench.app.store.runs import RunInfo

router = APIRouter(prefix="/fragments/compare", include_in_schema=False)


@router.get("", response_class=HTMLResponse)
def compare(
    store: StoreDep,
    runs: Annotated[list[int], Query()] = [],  # noqa: B006 (FastAPI copies it)
    metric: Annotated[str | None, Query(max_length=100)] = None,
    alpha: Annotated[float, Query(gt=0, lt=1)] = 0.05,
) -> HTMLResponse:
    """One run ranks its classifiers over its folds; several, over their data sets."""
    from touchbench.app.reports.figures import cd_figure
    from touchbench.app.reports.html import comparison_context
    from touchbench.app.services.compare import compare_runs

    context: dict[str, object] = {
        "runs": _with_results(newest(count_runs(store), partial(list_runs, store))),
        "chosen": runs,
        "metric": metric or "",
        "alpha": alpha,
        "comparison": None,
        "plot": None,
        "problem": None,
    }
    if runs:
        try:
            comparison = compare_runs(store, runs, metric=metric or None, alpha=alpha)
        except (AppError, BenchmarkError) as error:  # the form stays, with what is wrong
            context["problem"] = str(error)
        else:
            context["comparison"] = comparison_context(comparison)
            context["plot"] = draw("Critical-difference diagram", partial(cd_figure, comparison))
    return render("fragments/compare.html.j2", **context)


def _with_results(listed: Shown[RunInfo]) -> Shown[RunInfo]:
    """The runs with results among the newest, and how many runs are older."""
    return Shown([run for run in listed.items if run.n_results > 0], listed.more)
