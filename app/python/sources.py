"""Where a leaderboard made in this process reads what its plots draw: the store, through
the services (the client's counterpart fetches the same answers over HTTP)."""

from __future__ import annotations

from touchbench.app.python.leaderboard import Leaderboard
from touchbench.app.schemas.certainty import RunCertainty
from touchbench.app.schemas.folds import FoldScoresSchema
from touchbench.app.schemas.runs import Aggregate
from touchbench.app.services.certainty import run_certainty
from touchbench.app.services.folds import run_fold_scores
from touchbench.app.services.runs import run_leaderboard
from touchbench.app.store.database import Store


class StoreSource:
    """A :class:`~app.python.leaderboard.ResultSource` reading a store."""

    def __init__(self, store: Store) -> None:
        self.store = store

    def fold_scores(self, run_id: int, *, metric: str, aggregate: Aggregate) -> FoldScoresSchema:
        return run_fold_scores(self.store, run_id, metric=metric, aggregate=aggregate)

    def classes(self, run_id: int, *, classifier: str, aggregate: Aggregate) -> RunCertainty:
        return run_certainty(self.store, run_id, classifiers=[classifier], aggregate=aggregate)


def stored_leaderboard(
    store: Store,
    run_ref: int | str,
    *,
    metric: str | None = None,
    baseline: str | None = None,
    aggregate: Aggregate | None = None,
) -> Leaderboard:
    """A stored run's leaderboard (what ``touchbench leaderboard RUN --json`` prints), its
    plots reading the same store, scored per ``aggregate`` as the rows (default: as the
    run scored; see :func:`~app.services.runs.run_leaderboard`)."""
    ranked = run_leaderboard(store, run_ref, metric=metric, baseline=baseline, aggregate=aggregate)
    return Leaderboard(ranked.report(), StoreSource(store))
