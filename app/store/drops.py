"""The classifiers of a run that stopped before their last fold, and why.

A raced run's engine drops a classifier that is significantly worse than the leader; a run
with a total budget cuts the classifiers whose next task no longer fits.  Each is written
once, when the engine reports it; a race's drop is kept for good (a resumed race replays the
same decisions), a budget's cut is forgotten when the run is resumed with a new budget.
"""

from __future__ import annotations

from sqlalchemy import delete, select

from touchbench.app.store.database import Store
from touchbench.app.store.tables import EntryDropRow
from touchbench.benchmark.results import Drop


def record_drop(store: Store, run_id: int, drop: Drop) -> None:
    """Write ``drop``; an entry already dropped by the race keeps its first record."""
    with store.session() as session:
        row = session.get(EntryDropRow, (run_id, drop.classifier))
        if row is not None and row.reason == "race":
            return
        if row is None:
            row = EntryDropRow(run_id=run_id, classifier=drop.classifier)
            session.add(row)
        row.reason = drop.reason
        row.after_fold = drop.after_fold
        row.p_value = drop.p_value
        row.leader = drop.leader
        row.mean = drop.mean


def load_drops(store: Store, run_id: int) -> dict[str, Drop]:
    """The run's stopped classifiers by id."""
    with store.session() as session:
        rows = session.scalars(select(EntryDropRow).where(EntryDropRow.run_id == run_id))
        return {
            row.classifier: Drop(
                row.classifier,
                "budget" if row.reason == "budget" else "race",
                row.after_fold,
                p_value=row.p_value,
                leader=row.leader,
                mean=row.mean,
            )
            for row in rows
        }


def forget_budget_cuts(store: Store, run_id: int) -> None:
    """A resumed run gets a new budget: its classifiers cut by the old one go on."""
    with store.session() as session:
        session.execute(
            delete(EntryDropRow).where(
                EntryDropRow.run_id == run_id, EntryDropRow.reason == "budget"
            )
        )
