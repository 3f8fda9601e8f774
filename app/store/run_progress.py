"""A run's progress read light: what its progress fragment shows, polled every second while
the run is unfinished.

:func:`~app.store.runs.get_run` reads a run whole: its classifiers and its configuration,
which for an imported run lists every scheme (thousands), validated at each read.  A poll
needs none of that: :func:`run_progress` reads the run's scalar columns, the few keys of its
configuration that describe its folds, its classifiers counted by the database, and its
tasks counted by state with SQL aggregates; what it reads does not grow with the run.
"""

from __future__ import annotations

from dataclasses import dataclass
from datetime import datetime
from typing import Any

from sqlalchemy import JSON, ColumnElement, case, func, select
from sqlalchemy.orm import Session

from touchbench.app.schemas.run_config import RunConfig, entry_tasks
from touchbench.app.schemas.status import Status
from touchbench.app.store.database import Store
from touchbench.app.store.naming import is_row_id
from touchbench.app.store.runs import folds_text, no_run
from touchbench.app.store.tables import DatasetRow, EntryDropRow, FoldResultRow, RunRow

#: Keys of a run's configuration that its progress shows or counts with: how its folds were
#: made, its seed or origin, its tasks in all, and its helpers (members of its ensembles:
#: a few catalogue entries).
_KEYS = ("folds", "repeats", "seed", "n_tasks", "split", "fold_scheme", "origin", "grouped")
_HELPERS = "helpers"


@dataclass(frozen=True)
class RunProgress:
    """A run's status and its tasks counted by state.

    Attributes
    ----------
    n_results : int
        Tasks with a result (failed ones included).
    n_failed : int
        Of those, tasks that failed.
    n_dropped : int
        Tasks that will not run: the later folds of entries a race dropped or a total
        budget cut.
    n_tasks : int
        Tasks in all.
    seed, origin : int or str, optional
        The run's seed (a run carried out here) or origin (an imported run), when stored.
    """

    id: int
    dataset_id: int
    dataset_name: str
    kind: str
    targets: list[str]
    status: Status
    created_at: datetime
    started_at: datetime | None
    finished_at: datetime | None
    error: str | None
    n_classifiers: int
    n_tasks: int
    n_results: int
    n_failed: int
    n_dropped: int
    folds_text: str
    seed: int | None
    origin: str | None


def run_progress(store: Store, run_id: int | str) -> RunProgress:
    """The progress of ``run_id`` with three light queries (bounded whatever the run's size).

    Raises
    ------
    NotFoundError
        No such run.
    """
    text = str(run_id)
    with store.session() as session:
        found = _run(session, int(text)) if is_row_id(text) else None
        if found is None:
            raise no_run(session, run_id)
        values = dict(zip((*_KEYS, _HELPERS), found["config"] or (), strict=False))
        helpers = values.pop(_HELPERS, None) or []
        stored = {key: value for key, value in values.items() if value is not None}
        config = RunConfig.load(stored)  # a handful of scalars: no scheme, no classifier
        per_entry = entry_tasks(config.n_tasks, found["n_classifiers"] + len(helpers))
        after = EntryDropRow.after_fold
        dropped = session.scalar(
            select(func.sum(case((after < per_entry, per_entry - after), else_=0))).where(
                EntryDropRow.run_id == found["id"]
            )
        )
        return RunProgress(
            id=found["id"],
            dataset_id=found["dataset_id"],
            dataset_name=found["dataset_name"] or "?",
            kind=found["kind"],
            targets=list(found["targets"]),
            status=Status(found["status"]),
            created_at=found["created_at"],
            started_at=found["started_at"],
            finished_at=found["finished_at"],
            error=found["error"],
            n_classifiers=found["n_classifiers"],
            n_tasks=config.n_tasks,
            n_results=found["n_results"],
            n_failed=found["n_failed"],
            n_dropped=int(dropped or 0),
            folds_text=folds_text(found["kind"], config),
            seed=stored.get("seed"),
            origin=stored.get("origin"),
        )


def _run(session: Session, run_id: int) -> dict[str, Any] | None:
    """The run's scalar columns, the values of :data:`_KEYS` and its helpers in its
    configuration (one array), its classifiers counted; and its results and failures counted."""
    row = session.execute(
        select(
            RunRow.id,
            RunRow.dataset_id,
            DatasetRow.name.label("dataset_name"),
            RunRow.kind,
            RunRow.targets,
            RunRow.status,
            RunRow.created_at,
            RunRow.started_at,
            RunRow.finished_at,
            RunRow.error,
            func.coalesce(func.json_array_length(RunRow.classifiers), 0).label("n_classifiers"),
            _values(session, RunRow.config, (*_KEYS, _HELPERS)).label("config"),
        )
        .outerjoin(DatasetRow, DatasetRow.id == RunRow.dataset_id)
        .where(RunRow.id == run_id)
    ).one_or_none()
    if row is None:
        return None
    total, failed = session.execute(
        select(func.count(), func.sum(case((FoldResultRow.status != "ok", 1), else_=0))).where(
            FoldResultRow.run_id == run_id
        )
    ).one()
    return {**row._mapping, "n_results": int(total), "n_failed": int(failed or 0)}


def _values(session: Session, column: Any, keys: tuple[str, ...]) -> ColumnElement[Any]:
    """The values under ``keys`` of a JSON column as one JSON array, the column parsed once
    (an imported run's configuration lists its thousands of schemes)."""
    if session.get_bind().dialect.name == "sqlite":
        return func.json_extract(column, *(f"$.{key}" for key in keys), type_=JSON)
    return func.json_build_array(*(column[key] for key in keys), type_=JSON)
