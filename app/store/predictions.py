"""The fold predictions of a run's tasks (:mod:`benchmark.predictions`), one encoded blob
per task and part: ``test`` (the test fold's rows) and ``inner`` (the training fold's, out
of fold, kept for a run whose stacks or ensemble selection read them).

A resumed run gets them back with its stored results (:func:`attach_predictions`), so that
its ensembles are computed without fitting their members again.  The blobs are decoded by
:func:`benchmark.predictions.decode`, which reads arrays and a JSON header, never a pickle.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from sqlalchemy import delete, select
from sqlalchemy.dialects.postgresql import insert as postgresql_insert
from sqlalchemy.dialects.sqlite import insert as sqlite_insert
from sqlalchemy.orm import Session

from touchbench.app.store.database import Store
from touchbench.app.store.tables import FoldPredictionsRow
from touchbench.benchmark.predictions import FoldPredictions, decode, encode
from touchbench.benchmark.results import TaskKey, TaskResult

#: The parts of a task's predictions, and the attribute of :class:`TaskResult` of each.
PARTS = {"test": "predictions", "inner": "inner_predictions"}


def record_predictions(store: Store, run_id: int, result: TaskResult) -> None:
    """Write a finished task's fold predictions (nothing for a task without them); parts
    already recorded for the task are left as they are."""
    with store.session() as session:
        insert_predictions(session, run_id, result)


def insert_predictions(session: Session, run_id: int, result: TaskResult) -> None:
    """:func:`record_predictions` inside the caller's transaction (with the task's result,
    so that a run killed between the two never keeps one without the other)."""
    rows = [
        {
            "run_id": run_id,
            "classifier": result.key.classifier,
            "repeat": result.key.repeat,
            "fold": result.key.fold,
            "part": part,
            "data": encode(predictions),
        }
        for part, attribute in PARTS.items()
        if (predictions := getattr(result, attribute)) is not None
    ]
    if not rows:
        return
    dialect = session.bind.dialect.name if session.bind is not None else ""
    statement: Any
    if dialect == "postgresql":
        statement = postgresql_insert(FoldPredictionsRow).on_conflict_do_nothing()
    else:
        statement = sqlite_insert(FoldPredictionsRow).on_conflict_do_nothing()
    session.execute(statement, rows)


def load_predictions(
    store: Store, run_id: int, *, part: str = "test"
) -> dict[TaskKey, FoldPredictions]:
    """The run's fold predictions of one part, by task.

    Raises
    ------
    DataFormatError
        A stored blob that is not an encoding of fold predictions.
    """
    with store.session() as session:
        rows = session.execute(
            select(
                FoldPredictionsRow.classifier,
                FoldPredictionsRow.repeat,
                FoldPredictionsRow.fold,
                FoldPredictionsRow.data,
            ).where(FoldPredictionsRow.run_id == run_id, FoldPredictionsRow.part == part)
        ).all()
    return {TaskKey(c, r, f): decode(data) for c, r, f, data in rows}


def attach_predictions(store: Store, run_id: int, results: Sequence[TaskResult]) -> None:
    """Give each of the run's stored ``results`` its stored fold predictions, if any."""
    for part, attribute in PARTS.items():
        stored = load_predictions(store, run_id, part=part)
        for result in results:
            if result.key in stored:
                setattr(result, attribute, stored[result.key])


def forget_inner_predictions(store: Store, run_id: int) -> None:
    """Delete a run's inner predictions once every entry made of them is computed (a
    finished run): they are about as large as the training folds, and only a stack or a
    selection still to compute reads them; the test folds' stay."""
    with store.session() as session:
        session.execute(
            delete(FoldPredictionsRow).where(
                FoldPredictionsRow.run_id == run_id, FoldPredictionsRow.part == "inner"
            )
        )
