"""The fragment of one job (an extraction, a training, an ONNX twin, an ablation, a
permutation importance, a learning curve): its progress, polled until it ends, then what
it made: the new data set and the extraction's notes, the model, the twin to download,
or the answer's table and plot (drawn from what is finished while it runs)."""

from __future__ import annotations

# Imports inside functions: start-up time: matplotlib loads when a job's plot is first drawn.
from functools import partial
from typing import Any

from fastapi import APIRouter
from fastapi.responses import HTMLResponse

from touchbench.app.schemas.status import FINAL, Status
from touchbench.app.services.lifecycle import get_job
from touchbench.app.web.deps import StoreDep
from touchbench.app.web.rendering import Plot, draw, render

router = APIRouter(prefix="/fragments/jobs", include_in_schema=False)


@router.get("/{job_id}", response_class=HTMLResponse)
def job(job_id: int, store: StoreDep) -> HTMLResponse:
    """Status and what the job made (or has made so far)."""
    found = get_job(store, job_id).for_client()
    final = found.status in FINAL
    tables, plot = _answer(found.kind, found.result)
    return render(
        "fragments/job.html.j2",
        job=found,
        final=final,
        done=found.status == Status.DONE,
        tables=tables,
        plot=plot,
    )


def _answer(kind: str, result: dict[str, Any] | None) -> tuple[list[Any], Plot | None]:
    """The tables and the plot of an answer's result (none for other kinds)."""
    from touchbench.app.reports import answer_tables, figures
    from touchbench.app.schemas.ablation import AblationResult
    from touchbench.app.schemas.importance import ImportanceResult
    from touchbench.app.schemas.learning import LearningCurveResult

    if not result:
        return [], None
    if kind == "ablation":
        ablation = AblationResult.model_validate(result)
        if not ablation.entries:
            return [], None
        caption = "Change of the score without each group (the full set at 0)"
        return [answer_tables.ablation_table(ablation)], draw(
            caption, partial(figures.ablation_figure, ablation)
        )
    if kind == "importance":
        importance = ImportanceResult.model_validate(result)
        if not importance.features:
            return [], None
        return answer_tables.importance_tables(importance, answer_tables.TOP_FEATURES), draw(
            "Drop of the score when shuffled", partial(figures.importance_figure, importance)
        )
    if kind == "learning-curve":
        curve = LearningCurveResult.model_validate(result)
        if not curve.curves:
            return [], None
        return [answer_tables.learning_table(curve)], draw(
            "Score by share of each training fold", partial(figures.learning_figure, curve)
        )
    return [], None
