"""Benchmark runs and their per-fold results in the store.

A run is created ``queued``; the process that executes it *claims* it (status ``running``,
its ``host:pid`` as owner) and keeps a heartbeat while it works, so that any other process
(a second service, the CLI) can tell a live run from one whose process died, and refuse to
execute a run twice.  The engine reports each finished task through a callback;
:func:`record_result` writes it at once in its own transaction and ignores a task that is
already recorded, so a resumed run never duplicates rows.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from datetime import datetime
from typing import Any

from sqlalchemy import Text, case, cast, func, insert, null, select, update
from sqlalchemy.dialects.postgresql import insert as postgresql_insert
from sqlalchemy.dialects.sqlite import insert as sqlite_insert
from sqlalchemy.orm import Session

from touchbench.app.errors import ConflictError, NotFoundError
from touchbench.app.schemas.base import finite
from touchbench.app.schemas.listing import Page
from touchbench.app.schemas.run_config import LEAVE_ONE_GROUP_OUT, RunConfig
from touchbench.app.schemas.runs import RunSchema
from touchbench.app.schemas.status import FINAL, Status
from touchbench.app.store import queue
from touchbench.app.store.database import Store
from touchbench.app.store.naming import is_row_id
from touchbench.app.store.ownership import aware, mark_lost, owner_alive, process_owner
from touchbench.app.store.paging import count_rows, paged
from touchbench.app.store.predictions import insert_predictions
from touchbench.app.store.states import LOST_AS, check_claim, check_resume, is_active
from touchbench.app.store.tables import DatasetRow, EntryDropRow, FoldResultRow, RunRow, utcnow
from touchbench.benchmark.results import TaskKey, TaskResult

#: Multi-target folds keep their per-target scores in the metrics column under this key.
PER_TARGET = "per_target"
#: Key of a result's chosen parameters inside its stored metrics (absent before tuning).
PARAMS = "params"
#: Key of a fold's reliability bins inside its stored metrics (absent before they were kept).
CALIBRATION = "calibration"


@dataclass(frozen=True)
class RunInfo:
    """A run as listings show it."""

    id: int
    dataset_id: int
    dataset_name: str
    kind: str
    targets: list[str]
    classifiers: list[str]
    config: RunConfig
    status: Status
    created_at: datetime
    finished_at: datetime | None
    n_results: int
    n_failed: int = 0
    started_at: datetime | None = None
    owner: str | None = None
    heartbeat_at: datetime | None = None
    error: str | None = None
    cancel_requested: bool = False
    #: Tasks that will not run: the later folds of entries a race dropped or a total
    #: budget cut (not counted in ``n_results``).
    n_dropped: int = 0
    #: Wall seconds the engine has run for this run, over all its executions.
    seconds_spent: float = 0.0

    @property
    def n_tasks(self) -> int:
        return self.config.n_tasks

    def tasks_text(self) -> str:
        """Progress as listings say it: ``done/total``, and with drops ``done done,
        dropped dropped / total`` (a raced run ends with fewer results than tasks)."""
        failed = f" ({self.n_failed} failed)" if self.n_failed else ""
        if not self.n_dropped:
            return f"{self.n_results}/{self.n_tasks}{failed}"
        return f"{self.n_results} done{failed}, {self.n_dropped} dropped / {self.n_tasks}"

    @property
    def fold_scheme(self) -> str:
        """How the folds were made (``stratified k-fold``, ``group k-fold``...)."""
        return fold_scheme(self.kind, self.config)

    @property
    def folds_text(self) -> str:
        """How the folds were made, as every view says it (:func:`folds_text`)."""
        return folds_text(self.kind, self.config)

    def is_alive(self) -> bool:
        """Whether a live process is executing the run (``running`` or ``cancelling``)."""
        return is_active(self)

    def owner_alive(self) -> bool:
        """Whether the process named as the run's owner still runs."""
        return owner_alive(self.owner, self.heartbeat_at)

    def seconds_since_heartbeat(self) -> float:
        """Seconds since the owner's last heartbeat (0 without one)."""
        if self.heartbeat_at is None:
            return 0.0
        return (utcnow() - aware(self.heartbeat_at)).total_seconds()

    def schema(self) -> RunSchema:
        return RunSchema(
            id=self.id,
            dataset=self.dataset_name,
            dataset_id=self.dataset_id,
            kind=self.kind,
            targets=self.targets,
            classifiers=self.classifiers,
            config=self.config.to_json(),
            folds=self.folds_text,
            status=self.status,
            created_at=self.created_at,
            started_at=self.started_at,
            finished_at=self.finished_at,
            tasks_done=self.n_results,
            tasks=self.n_tasks,
            tasks_failed=self.n_failed,
            tasks_dropped=self.n_dropped,
            error=self.error,
        )

    def to_json(self) -> dict[str, Any]:
        return self.schema().to_json()


def fold_scheme(kind: str, config: RunConfig) -> str:
    """How a run's folds were made (``stratified k-fold``, ``group k-fold``...); runs stored
    before it was recorded are described from their kind and whether they had groups."""
    if config.fold_scheme:
        return config.fold_scheme
    stratified = "stratified " if kind == "multiclass" else ""
    return stratified + ("group " if config.grouped else "") + "k-fold"


def folds_text(kind: str, config: RunConfig) -> str:
    """How a run's folds were made, as every view says it: ``stratified 10-fold``,
    ``group 5-fold x 3 repeats``, ``leave-one-group-out, 7 groups``."""
    if config.split == LEAVE_ONE_GROUP_OUT:
        return f"leave-one-group-out, {config.folds} groups"
    scheme = fold_scheme(kind, config)
    if config.folds is None or "k-fold" not in scheme:  # an imported run's
        return scheme
    repeats = f" x {config.repeats} repeats" if config.repeats and config.repeats > 1 else ""
    return scheme.replace("k-fold", f"{config.folds}-fold") + repeats


def create_run(
    store: Store,
    *,
    dataset_id: int,
    kind: str,
    targets: Sequence[str],
    classifiers: Sequence[str],
    config: RunConfig,
) -> RunInfo:
    """A new run, ``queued``."""
    with store.session() as session:
        row = _new_run(session, dataset_id, kind, targets, classifiers, config, Status.QUEUED)
        return _infos(session, [row])[0]


def _new_run(
    session: Session,
    dataset_id: int,
    kind: str,
    targets: Sequence[str],
    classifiers: Sequence[str],
    config: RunConfig,
    status: Status,
    **times: datetime,
) -> RunRow:
    """A run's row, added and flushed (so that it has its id)."""
    row = RunRow(
        dataset_id=dataset_id,
        kind=kind,
        targets=list(targets),
        classifiers=list(classifiers),
        config=config.to_json(),
        status=status,
        **times,
    )
    session.add(row)
    session.flush()
    return row


def add_finished_run(
    store: Store,
    *,
    dataset_id: int,
    kind: str,
    targets: Sequence[str],
    classifiers: Sequence[str],
    config: RunConfig,
    results: Sequence[TaskResult],
) -> RunInfo:
    """A run that is ``done`` on arrival, stored with its results in one transaction (an
    imported one: nothing executes it, and a failure stores nothing)."""
    now = utcnow()
    with store.session() as session:
        row = _new_run(
            session,
            dataset_id,
            kind,
            targets,
            classifiers,
            config,
            Status.DONE,
            started_at=now,
            finished_at=now,
        )
        if results:
            session.execute(
                insert(FoldResultRow),
                [
                    {
                        "run_id": row.id,
                        "classifier": r.key.classifier,
                        "repeat": r.key.repeat,
                        "fold": r.key.fold,
                        "status": r.status,
                        "error": r.error,
                        "metrics": _stored_metrics(r),
                        "confusion": r.confusion,
                        "n_train": r.n_train,
                        "n_test": r.n_test,
                        "created_at": now,
                    }
                    for r in results
                ],
            )
        return _infos(session, [row])[0]


def get_run(store: Store, run_id: int | str) -> RunInfo:
    with store.session() as session:
        return _infos(session, [_row(session, run_id)])[0]


def results_version(store: Store, run_id: int | str) -> tuple[Any, ...]:
    """What tells one state of a run's results from another, read without the run's
    configuration or classifiers (light for a run of thousands): its id and creation time
    (a run stored anew under a freed id differs), its status and end, its results and
    failures counted, and its dropped entries with their folds.

    Raises
    ------
    NotFoundError
        No such run.
    """
    text = str(run_id)
    with store.session() as session:
        found = None
        if is_row_id(text):
            found = session.execute(
                select(RunRow.id, RunRow.created_at, RunRow.status, RunRow.finished_at).where(
                    RunRow.id == int(text)
                )
            ).one_or_none()
        if found is None:
            _row(session, run_id)  # says which runs there are
            raise NotFoundError(f"no run '{text}'")
        results = session.execute(
            select(func.count(), func.sum(case((FoldResultRow.status != "ok", 1), else_=0))).where(
                FoldResultRow.run_id == found.id
            )
        ).one()
        drops = session.execute(
            select(func.count(), func.sum(EntryDropRow.after_fold)).where(
                EntryDropRow.run_id == found.id
            )
        ).one()
        return (*found, results[0], results[1] or 0, drops[0], drops[1] or 0)


def list_runs(
    store: Store,
    *,
    status: str | None = None,
    dataset_id: int | None = None,
    page: Page | None = None,
) -> list[RunInfo]:
    """The runs, oldest first: those with ``status``, on ``dataset_id``, of ``page``."""
    with store.session() as session:
        query = select(RunRow).order_by(RunRow.id)
        if status is not None:
            query = query.where(RunRow.status == status)
        if dataset_id is not None:
            query = query.where(RunRow.dataset_id == dataset_id)
        return _infos(session, list(session.scalars(paged(query, page))))


def count_runs(store: Store, *, dataset_id: int | None = None) -> int:
    """How many runs there are (on ``dataset_id``)."""
    where = () if dataset_id is None else (RunRow.dataset_id == dataset_id,)
    return count_rows(store, RunRow, *where)


def claim_run(store: Store, run_id: int, *, owner: str | None = None) -> RunInfo:
    """Make this process the one executing ``run_id``: status ``running``, owner, heartbeat.

    A run that another live process executes, or that is being cancelled, is refused
    (:func:`app.store.states.check_claim`); an active run whose process died (kill -9, a
    crash, a lost machine) is taken over.

    Raises
    ------
    ConflictError
        Another process is executing the run, or just took it.
    """
    owner = owner or process_owner()
    now = utcnow()
    check_claim(get_run(store, run_id), owner)
    with store.session() as session:
        row = _row(session, run_id)
        same_owner = RunRow.owner.is_(None) if row.owner is None else RunRow.owner == row.owner
        claimed = session.execute(
            update(RunRow)
            .where(RunRow.id == row.id, RunRow.status == row.status, same_owner)
            .values(
                status=Status.RUNNING,
                owner=owner,
                heartbeat_at=now,
                started_at=func.coalesce(RunRow.started_at, now),
                finished_at=None,
                error=None,
                cancel_requested=False,
            )
            .execution_options(synchronize_session=False)
        ).rowcount  # type: ignore[attr-defined]  # an UPDATE gives a CursorResult
        if not claimed:
            raise ConflictError(f"run {row.id} was just taken up by another process; try again")
    return get_run(store, run_id)


def heartbeat(store: Store, run_id: int, owner: str) -> bool:
    """Say that ``owner`` still executes the run; returns whether it should stop."""
    return queue.beat(store, RunRow, run_id, owner)


def run_heartbeat(
    store: Store, run_id: int, owner: str, on_stop: Callable[[], None]
) -> queue.Heartbeat:
    """The thread that keeps the run's heartbeat for ``owner`` and calls ``on_stop`` once
    when the run should stop (a cancel, the run taken away)."""
    return queue.Heartbeat(store, RunRow, run_id, owner, on_stop)


def should_stop(store: Store, run_id: int, owner: str) -> bool:
    """Whether the process ``owner`` executing the run should stop: a cancel was requested,
    or the run was taken away from it (deleted, claimed by another process)."""
    return queue.should_stop(store, RunRow, run_id, owner)


def update_config(store: Store, run_id: int, **values: Any) -> None:
    """Set ``values`` in a run's stored config (what its executing process decided when it
    started, such as the memory cap it derived)."""
    with store.session() as session:
        row = _row(session, run_id)
        row.config = RunConfig.load(row.config).updated(**values).to_json()


def finish_run(store: Store, run_id: int, status: Status, *, error: str | None = None) -> None:
    """Leave a run in ``status`` (``finished_at`` set for final ones), its owner released."""
    with store.session() as session:
        session.execute(
            update(RunRow)
            .where(RunRow.id == run_id)
            .values(
                status=status,
                error=error,
                finished_at=utcnow() if status in FINAL else None,
                heartbeat_at=None,
                owner=None,
            )
        )


def add_spent(store: Store, run_id: int, seconds: float) -> None:
    """Add ``seconds`` of an execution to the run's spent time."""
    with store.session() as session:
        session.execute(
            update(RunRow)
            .where(RunRow.id == run_id)
            .values(seconds_spent=RunRow.seconds_spent + max(seconds, 0.0))
        )


def request_cancel(store: Store, run_id: int | str) -> RunInfo:
    """Cancel a run: at once if nobody executes it, else by asking its process to stop
    (status ``cancelling`` until it has; see :mod:`app.store.states`).

    Raises
    ------
    ConflictError
        The run is already over.
    """
    run = get_run(store, run_id)
    outcome = queue.request_cancel(store, RunRow, run, "run")
    if outcome == "changed":  # the run changed meanwhile: judge it again
        return request_cancel(store, run.id)
    if outcome == Status.CANCELLING:  # what this request did, whatever the run's process does
        return replace(run, status=Status.CANCELLING, cancel_requested=True)
    return get_run(store, run.id)


def requeue_run(store: Store, run_id: int | str) -> RunInfo:
    """Put an interrupted, cancelled or failed run back in the queue, to be resumed (only
    its tasks without a result are carried out).

    Raises
    ------
    ConflictError
        The run is queued, executing, being cancelled or done.
    """
    check_resume(get_run(store, run_id))
    finish_run(store, int(str(run_id)), Status.QUEUED)
    return get_run(store, run_id)


def mark_lost_runs(store: Store) -> list[int]:
    """Runs left active by a process that died become ``interrupted`` (or ``cancelled``,
    when they were being cancelled); their ids."""
    lost: list[int] = []
    with store.session() as session:
        for status, becomes in LOST_AS.items():
            values = {"finished_at": utcnow()} if becomes in FINAL else {}
            lost += mark_lost(
                session, RunRow, of=status, status=becomes, owner=None, heartbeat_at=None, **values
            )
    return sorted(lost)


def record_result(store: Store, run_id: int, result: TaskResult) -> None:
    """Write one finished task with its fold predictions, in one transaction; a task
    already recorded for the run is left as it is."""
    values = {
        "run_id": run_id,
        "classifier": result.key.classifier,
        "repeat": result.key.repeat,
        "fold": result.key.fold,
        "status": result.status,
        "error": result.error,
        "metrics": _stored_metrics(result),
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
        insert_predictions(session, run_id, result)


def finished_keys(store: Store, run_id: int) -> set[TaskKey]:
    """The tasks of a run that have a recorded result (whatever their status)."""
    with store.session() as session:
        return {TaskKey(*key) for key in _keys(session, run_id)}


def load_results(
    store: Store,
    run_id: int,
    *,
    classifiers: Sequence[str] | None = None,
    confusion: bool = True,
) -> list[TaskResult]:
    """The run's fold results, by classifier, repeat and fold; of ``classifiers`` only when
    given (a page that draws a few of a run's thousands); without their confusion matrices
    (``None``) unless ``confusion``: what a ranking reads, which never looks at them."""
    metrics_column = cast(FoldResultRow.metrics, Text)
    confusion_column = cast(FoldResultRow.confusion, Text) if confusion else null()
    query = select(
        FoldResultRow.classifier,
        FoldResultRow.repeat,
        FoldResultRow.fold,
        FoldResultRow.status,
        FoldResultRow.error,
        metrics_column,
        confusion_column,
        FoldResultRow.n_train,
        FoldResultRow.n_test,
    ).where(FoldResultRow.run_id == run_id)
    if classifiers is not None:
        query = query.where(FoldResultRow.classifier.in_(list(classifiers)))
    with store.session() as session:
        # columns, not ORM objects, and the JSON columns as their text: a large run loads
        # several times faster
        read = session.connection().execute(query).all()
    # sorted here, not by SQL: SQLite would walk the unique key's index and look each row
    # up in the table (a run of 30,000 results: 4 times the cost of reading them in the
    # table's order); and classifiers sort by code point on every store, as SQLite's
    # binary collation sorts them, whatever a PostgreSQL database's collation
    rows: list[Any] = sorted(read, key=lambda row: (row[0], row[1], row[2]))
    stored_metrics = _json_cells([row[5] for row in rows])
    confusions = _json_cells([row[6] for row in rows]) if confusion else [None] * len(rows)
    results = []
    for row, metrics, matrix in zip(rows, stored_metrics, confusions, strict=True):
        classifier, repeat, fold, status, error, _, _, n_train, n_test = row
        per_target = metrics.pop(PER_TARGET, None)
        params = metrics.pop(PARAMS, None)
        calibration = metrics.pop(CALIBRATION, None)
        metrics = _undefined_as_nan(metrics)
        if per_target is not None:
            per_target = {t: _undefined_as_nan(scores) for t, scores in per_target.items()}
        results.append(
            TaskResult(
                key=TaskKey(classifier, repeat, fold),
                status=status,
                error=error,
                metrics=metrics,
                confusion=matrix,
                n_train=n_train,
                n_test=n_test,
                per_target=per_target,
                params=params,
                calibration=calibration,
            )
        )
    return results


def _json_cells(texts: Sequence[str | None]) -> list[Any]:
    """JSON cells read as text (``None``: SQL NULL), decoded as one JSON array: the same
    values as a :func:`json.loads` per cell (the column's own decoding), without the cost
    of a call per cell, which for a run of 30,000 fold results is most of reading them."""
    decoded: list[Any] = json.loads(
        "[" + ",".join("null" if text is None else text for text in texts) + "]"
    )
    return decoded


def _stored_metrics(result: TaskResult) -> dict[str, Any]:
    """The metrics column: scores, and per-target scores and chosen parameters when any.
    An undefined score (NaN: ROC AUC of a classifier without probabilities) is stored as
    null, which PostgreSQL's JSON accepts and NaN it refuses."""
    stored: dict[str, Any] = finite(dict(result.metrics))
    if result.per_target:
        stored[PER_TARGET] = finite(result.per_target)
    if result.params is not None:
        stored[PARAMS] = result.params
    if result.calibration is not None:
        stored[CALIBRATION] = result.calibration
    return stored


def _undefined_as_nan(scores: dict[str, Any]) -> dict[str, Any]:
    """Scores as read: null (an undefined score) back to NaN."""
    if None not in scores.values():  # most rows: no copy
        return scores
    return {name: math.nan if value is None else value for name, value in scores.items()}


def _keys(session: Session, run_id: int) -> set[tuple[str, int, int]]:
    rows = session.execute(
        select(FoldResultRow.classifier, FoldResultRow.repeat, FoldResultRow.fold).where(
            FoldResultRow.run_id == run_id
        )
    )
    return {(c, r, f) for c, r, f in rows}


def _row(session: Session, run_id: int | str) -> RunRow:
    text = str(run_id)
    row = session.get(RunRow, int(text)) if is_row_id(text) else None
    if row is None:
        raise no_run(session, run_id)
    return row


def no_run(session: Session, run_id: int | str) -> NotFoundError:
    """The error that says ``run_id`` is no run, and which runs there are."""
    text = str(run_id)
    last = session.scalar(select(func.max(RunRow.id)))
    known = f"runs are 1..{last}" if last else "the store has no runs yet"
    shown = text if len(text) <= 40 else text[:39] + "…"
    return NotFoundError(f"no run '{shown}' ({known})")


def _infos(session: Session, rows: Sequence[RunRow]) -> list[RunInfo]:
    """Descriptions of ``rows`` with three queries in all (names, result counts, drops)."""
    if not rows:
        return []
    ids = [row.id for row in rows]
    names = dict(
        session.execute(
            select(DatasetRow.id, DatasetRow.name).where(
                DatasetRow.id.in_({row.dataset_id for row in rows})
            )
        ).all()
    )
    counts = {
        run_id: (int(total), int(failed or 0))
        for run_id, total, failed in session.execute(
            select(
                FoldResultRow.run_id,
                func.count(),
                func.sum(case((FoldResultRow.status != "ok", 1), else_=0)),
            )
            .where(FoldResultRow.run_id.in_(ids))
            .group_by(FoldResultRow.run_id)
        ).all()
    }
    stopped: dict[int, list[int]] = {}  # run -> folds run by each of its dropped entries
    for run_id, after_fold in session.execute(
        select(EntryDropRow.run_id, EntryDropRow.after_fold).where(EntryDropRow.run_id.in_(ids))
    ).all():
        stopped.setdefault(run_id, []).append(int(after_fold))
    configs = {row.id: RunConfig.load(row.config) for row in rows}
    return [
        RunInfo(
            id=row.id,
            dataset_id=row.dataset_id,
            dataset_name=names.get(row.dataset_id, "?"),
            kind=row.kind,
            targets=list(row.targets),
            classifiers=list(row.classifiers),
            config=configs[row.id],
            status=Status(row.status),
            created_at=row.created_at,
            finished_at=row.finished_at,
            n_results=counts.get(row.id, (0, 0))[0],
            n_failed=counts.get(row.id, (0, 0))[1],
            started_at=row.started_at,
            owner=row.owner,
            heartbeat_at=row.heartbeat_at,
            error=row.error,
            cancel_requested=bool(row.cancel_requested),
            n_dropped=_skipped(row, configs[row.id], stopped.get(row.id, [])),
            seconds_spent=float(row.seconds_spent or 0.0),
        )
        for row in rows
    ]


def _skipped(row: RunRow, config: RunConfig, folds_run: Sequence[int]) -> int:
    """Tasks a run's dropped entries will not run: each entry's folds after its last."""
    per_entry = config.tasks_per_entry(len(row.classifiers))
    return sum(max(per_entry - folds, 0) for folds in folds_run)
