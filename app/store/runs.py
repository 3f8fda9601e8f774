"""Benchmark runs and their per-fold results in the store.

The engine reports each finished task through a callback; :func:`record_result` writes it
at once in its own transaction, and ignores a task that is already recorded, so a resumed
run never duplicates rows.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from datetime import datetime
from typing import Any

from sqlalchemy import func, insert, select, update
from sqlalchemy.dialects.postgresql import insert as postgresql_insert
from sqlalchemy.dialects.sqlite import insert as sqlite_insert
from sqlalchemy.orm import Session

from app.errors import NotFoundError
from app.store.database import Store
from app.store.tables import DatasetRow, FoldResultRow, RunRow, utcnow
from benchmark.results import TaskKey, TaskResult

#: Multi-target folds keep their per-target scores in the metrics column under this key.
PER_TARGET = "per_target"


@dataclass(frozen=True)
class RunInfo:
    """A run as listings show it."""

    id: int
    dataset_id: int
    dataset_name: str
    kind: str
    targets: list[str]
    classifiers: list[str]
    config: dict[str, Any]
    status: str
    created_at: datetime
    finished_at: datetime | None
    n_results: int

    @property
    def n_tasks(self) -> int:
        return int(self.config.get("n_tasks", 0))

    def to_json(self) -> dict[str, Any]:
        return {
            "id": self.id,
            "dataset": self.dataset_name,
            "dataset_id": self.dataset_id,
            "kind": self.kind,
            "targets": self.targets,
            "classifiers": self.classifiers,
            "config": self.config,
            "status": self.status,
            "created_at": self.created_at.isoformat(),
            "finished_at": self.finished_at.isoformat() if self.finished_at else None,
            "tasks_done": self.n_results,
            "tasks": self.n_tasks,
        }


def create_run(
    store: Store,
    *,
    dataset_id: int,
    kind: str,
    targets: Sequence[str],
    classifiers: Sequence[str],
    config: dict[str, Any],
) -> RunInfo:
    with store.session() as session:
        row = RunRow(
            dataset_id=dataset_id,
            kind=kind,
            targets=list(targets),
            classifiers=list(classifiers),
            config=config,
            status="running",
        )
        session.add(row)
        session.flush()
        return _info(session, row)


def get_run(store: Store, run_id: int | str) -> RunInfo:
    with store.session() as session:
        return _info(session, _row(session, run_id))


def list_runs(store: Store) -> list[RunInfo]:
    with store.session() as session:
        return [_info(session, row) for row in session.scalars(select(RunRow).order_by(RunRow.id))]


def set_status(store: Store, run_id: int, status: str) -> None:
    with store.session() as session:
        finished = utcnow() if status in ("done", "failed", "cancelled") else None
        session.execute(
            update(RunRow).where(RunRow.id == run_id).values(status=status, finished_at=finished)
        )


def record_result(store: Store, run_id: int, result: TaskResult) -> None:
    """Write one finished task; a task already recorded for the run is left as it is."""
    values = {
        "run_id": run_id,
        "classifier": result.key.classifier,
        "repeat": result.key.repeat,
        "fold": result.key.fold,
        "status": result.status,
        "error": result.error,
        "metrics": (
            {**result.metrics, PER_TARGET: result.per_target}
            if result.per_target
            else result.metrics
        ),
        "confusion": result.confusion,
        "n_train": result.n_train,
        "n_test": result.n_test,
        "created_at": utcnow(),
    }
    with store.session() as session:
        dialect = session.bind.dialect.name if session.bind is not None else ""
        if dialect == "postgresql":
            statement: Any = postgresql_insert(FoldResultRow).on_conflict_do_nothing()
        elif dialect == "sqlite":
            statement = sqlite_insert(FoldResultRow).on_conflict_do_nothing()
        else:
            key = (result.key.classifier, result.key.repeat, result.key.fold)
            if key in _keys(session, run_id):
                return
            statement = insert(FoldResultRow)
        session.execute(statement, [values])


def finished_keys(store: Store, run_id: int) -> set[TaskKey]:
    """The tasks of a run that have a recorded result (whatever their status)."""
    with store.session() as session:
        return {TaskKey(*key) for key in _keys(session, run_id)}


def load_results(store: Store, run_id: int) -> list[TaskResult]:
    with store.session() as session:
        rows = session.scalars(
            select(FoldResultRow)
            .where(FoldResultRow.run_id == run_id)
            .order_by(FoldResultRow.classifier, FoldResultRow.repeat, FoldResultRow.fold)
        )
        results = []
        for row in rows:
            metrics = dict(row.metrics)
            per_target = metrics.pop(PER_TARGET, None)
            results.append(
                TaskResult(
                    key=TaskKey(row.classifier, row.repeat, row.fold),
                    status=row.status,  # type: ignore[arg-type]  # a Status literal in the column
                    error=row.error,
                    metrics=metrics,
                    confusion=row.confusion,
                    n_train=row.n_train,
                    n_test=row.n_test,
                    per_target=per_target,
                )
            )
        return results


def _keys(session: Session, run_id: int) -> set[tuple[str, int, int]]:
    rows = session.execute(
        select(FoldResultRow.classifier, FoldResultRow.repeat, FoldResultRow.fold).where(
            FoldResultRow.run_id == run_id
        )
    )
    return {(c, r, f) for c, r, f in rows}


def _row(session: Session, run_id: int | str) -> RunRow:
    text = str(run_id)
    row = session.get(RunRow, int(text)) if text.isdigit() else None
    if row is None:
        last = session.scalar(select(func.max(RunRow.id)))
        known = f"runs are 1..{last}" if last else "the store has no runs yet"
        raise NotFoundError(f"no run '{text}' ({known}; `touchbench runs` lists them)")
    return row


def _info(session: Session, row: RunRow) -> RunInfo:
    dataset_name = session.scalar(select(DatasetRow.name).where(DatasetRow.id == row.dataset_id))
    n_results = session.scalar(
        select(func.count()).select_from(FoldResultRow).where(FoldResultRow.run_id == row.id)
    )
    return RunInfo(
        id=row.id,
        dataset_id=row.dataset_id,
        dataset_name=dataset_name or "?",
        kind=row.kind,
        targets=list(row.targets),
        classifiers=list(row.classifiers),
        config=dict(row.config),
        status=row.status,
        created_at=row.created_at,
        finished_at=row.finished_at,
        n_results=n_results or 0,
    )
