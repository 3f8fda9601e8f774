"""The paper's other approach: each target of a multi-target data set benchmarked on its own
with multi-class classifiers, and the product of the best scores.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from touchbench.app.errors import FieldError
from touchbench.app.schemas.runs import BenchRequest
from touchbench.app.services.runs.execute import Callbacks, execute_run
from touchbench.app.services.runs.leaderboard import run_leaderboard
from touchbench.app.services.runs.plan import plan_run, store_plan
from touchbench.app.store.database import Store
from touchbench.app.store.datasets import load_schema
from touchbench.app.store.runs import RunInfo

if TYPE_CHECKING:
    from touchbench.benchmark.evaluation.leaderboard import Leaderboard


@dataclass
class IndependentResult:
    """The paper's other approach: each target's best multi-class classifier, separately.

    Attributes
    ----------
    runs : dict of str to (RunInfo, Leaderboard)
        One multi-class run per target.
    product : dict of str to float
        Product over targets of the best classifiers' mean accuracy and weighted F1: what
        independent classifiers score on all targets at once if their errors are independent.
    """

    runs: dict[str, tuple[RunInfo, Leaderboard]]
    product: dict[str, float]

    def to_json(self) -> dict[str, Any]:
        best = {}
        for target, (run, board) in self.runs.items():
            row = board.rows[0]
            best[target] = {
                "run_id": run.id,
                "classifier": row.classifier,
                "metrics": {
                    name: {"mean": row.metrics[name][0], "std": row.metrics[name][1]}
                    for name in ("accuracy", "f1_weighted")
                    if name in row.metrics
                },
            }
        return {"independent": True, "best": best, "product": self.product}


def independent_runs(
    store: Store,
    request: BenchRequest,
    *,
    jobs: int = 1,
    scheduler: str | None = None,
    callbacks: Callbacks | None = None,
) -> IndependentResult:
    """A multi-class run per target of a multi-target data set, carried out at once, and
    the product of the best scores (the comparison the UC3M paper makes with its
    multi-target results).

    Every target's run is checked before the first one is stored.

    Raises
    ------
    FieldError
        For ``independent``: the data set has one target, or numeric ones.
    """
    callbacks = callbacks or Callbacks()
    info, schema, _ = load_schema(store, request.dataset)
    numeric = [t.name for t in schema.targets if t.kind == "numeric"]
    if numeric:
        raise FieldError(
            "independent",
            f"compares targets classified separately, but {', '.join(numeric)} of "
            f"'{info.name}' are numeric: a regression benchmarks its targets together "
            "(br:ID fits one model per target)",
        )
    if len(info.targets) < 2:
        raise FieldError(
            "independent",
            f"compares targets classified separately, but '{info.name}' has one target "
            f"({', '.join(info.targets)})",
        )
    fields = request.model_dump(exclude={"independent", "target"}, exclude_defaults=True)
    plans = {
        target: plan_run(store, BenchRequest(**fields, target=target)) for target in info.targets
    }
    runs: dict[str, tuple[RunInfo, Leaderboard]] = {}
    for target, plan in plans.items():
        run = store_plan(store, plan, callbacks.on_note)
        execute_run(store, run.id, jobs=jobs, scheduler=scheduler, callbacks=callbacks)
        ranked = run_leaderboard(store, run.id)
        runs[target] = (ranked.run, ranked.board)
    product = {}
    for name in ("accuracy", "f1_weighted"):
        value = 1.0
        for _, board in runs.values():
            value *= board.rows[0].metrics[name][0]
        product[name] = value
    return IndependentResult(runs, product)
