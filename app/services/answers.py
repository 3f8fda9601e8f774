"""The answers kept for a run (its finished ablation and importance jobs) and for a data set
(its finished learning curves), for the pages and reports that show them."""

from __future__ import annotations

from dataclasses import dataclass, field

from touchbench.app.errors import NotFoundError
from touchbench.app.schemas.ablation import AblationResult
from touchbench.app.schemas.importance import ImportanceResult
from touchbench.app.schemas.learning import LearningCurveResult
from touchbench.app.store.database import Store
from touchbench.app.store.jobs import done_jobs_naming, done_jobs_of_run
from touchbench.app.store.runs import get_run


@dataclass(frozen=True)
class RunAnswers:
    """A run's latest ablation (``None`` without one) and its latest permutation importance
    per classifier (newest first)."""

    ablation: AblationResult | None = None
    importance: list[ImportanceResult] = field(default_factory=list)

    def __bool__(self) -> bool:
        return self.ablation is not None or bool(self.importance)


def run_answers(store: Store, run_id: int) -> RunAnswers:
    """What the run's finished ablation and importance jobs answered."""
    ablations = done_jobs_of_run(store, "ablation", run_id)
    importance: dict[str, ImportanceResult] = {}
    for job in done_jobs_of_run(store, "importance", run_id):
        if job.result is not None:
            found = ImportanceResult.model_validate(job.result)
            importance.setdefault(found.classifier, found)
    return RunAnswers(
        ablation=AblationResult.model_validate(ablations[0].result)
        if ablations and ablations[0].result is not None
        else None,
        importance=list(importance.values()),
    )


def latest_ablation(store: Store, run_id: int) -> AblationResult:
    """The newest finished ablation of a run.

    Raises
    ------
    NotFoundError
        No such run, or none of its ablations finished.
    """
    run = get_run(store, run_id)
    found = run_answers(store, run.id).ablation
    if found is None:
        raise NotFoundError(
            f"run {run.id} has no finished ablation (`bench --ablate-groups`, or "
            "POST /api/jobs/ablation)"
        )
    return found


def latest_learning_curve(store: Store, dataset_id: int, name: str) -> LearningCurveResult | None:
    """The newest finished learning curve of a data set (asked for by its name or its id),
    or None."""
    for job in done_jobs_naming(store, "learning-curve", "dataset", (name, str(dataset_id))):
        if job.result is not None:
            return LearningCurveResult.model_validate(job.result)
    return None
