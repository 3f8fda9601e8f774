"""Data sets in the store: add (one transaction, streamed, deduplicated by content), look
up by name or id, load whole or in blocks, rename and delete.

Instances are stored in blocks of consecutive instances, about :data:`STORED_BLOCK_BYTES`
of values each (see :mod:`app.store.tables`): an import of 235 000 instances writes a few
hundred rows, so its cost is that of writing its bytes, not of 235 000 inserts, and
reading back one block at a time keeps memory flat whatever the data set's size.  An import
is one transaction: interrupted (Ctrl-C, ``kill -9``) or failed, it leaves nothing behind.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any, Protocol, cast

import numpy as np
from sqlalchemy import Table, delete, distinct, func, insert, select, update
from sqlalchemy.exc import IntegrityError, OperationalError
from sqlalchemy.orm import Session

from touchbench.app.errors import AppError, ConflictError, FieldError
from touchbench.app.schemas.names import check_name
from touchbench.app.schemas.status import UNFINISHED, Status
from touchbench.app.store.database import Store
from touchbench.app.store.listing import DatasetInfo
from touchbench.app.store.naming import default_name, find_row, free_name, shorten
from touchbench.app.store.ownership import owner_alive
from touchbench.app.store.tables import DatasetRow, InstanceBlockRow, InstanceRow, RunRow
from touchbench.benchmark.dataset import Dataset, InstanceBlock, Schema, dataset_blocks

_LITTLE_F8 = np.dtype("<f8")
#: Instances per block when a data set held in memory is stored.
_INSERT_BATCH = 5000
#: At most this many instances are handed on at a time when instances are read back.
READ_BATCH = 5000
#: About how many bytes of values one stored block holds.
STORED_BLOCK_BYTES = 1 << 20


class InstanceSource(Protocol):
    """Instances that come block by block, such as an :class:`~benchmark.io.arff.ArffReader`.

    ``schema`` and ``sparse`` are final once ``blocks()`` is exhausted (a reader's string
    tables grow as it reads).
    """

    @property
    def schema(self) -> Schema: ...

    @property
    def sparse(self) -> bool: ...

    def blocks(self) -> Iterator[InstanceBlock]: ...


@dataclass
class DatasetInMemory:
    """A :class:`~benchmark.dataset.Dataset` as an :class:`InstanceSource`."""

    dataset: Dataset
    rows: int | None = None  # instances per block; default _INSERT_BATCH

    @property
    def schema(self) -> Schema:
        return self.dataset.schema

    @property
    def sparse(self) -> bool:
        return self.dataset.sparse

    def blocks(self) -> Iterator[InstanceBlock]:
        return dataset_blocks(self.dataset, self.rows or _INSERT_BATCH)


def content_digest(content: bytes) -> str:
    """sha256 of a file's bytes, the key that recognises a file imported before."""
    return hashlib.sha256(content).hexdigest()


def dataset_digest(dataset: Dataset) -> str:
    """sha256 of a data set made in memory (schema and values), for data without a file."""
    digest = hashlib.sha256(json.dumps(dataset.schema.to_json(), sort_keys=True).encode())
    digest.update(np.ascontiguousarray(dataset.values, dtype=_LITTLE_F8).tobytes())
    return digest.hexdigest()


def add_dataset(
    store: Store,
    dataset: Dataset,
    *,
    sha256: str,
    name: str | None = None,
    source_name: str | None = None,
    extraction: dict[str, Any] | None = None,
) -> tuple[DatasetInfo, bool]:
    """Store a data set held in memory (see :func:`add_dataset_stream`).

    By default it is named after its relation (MEKA's options dropped), made unique with a
    numeric suffix.
    """
    return add_dataset_stream(
        store,
        DatasetInMemory(dataset),
        sha256=sha256,
        name=name,
        default=default_name(dataset.schema.relation.split(":", 1)[0].strip()),
        source_name=source_name,
        extraction=extraction,
    )


def add_dataset_stream(
    store: Store,
    source: InstanceSource,
    *,
    sha256: str,
    name: str | None = None,
    default: str = "dataset",
    source_name: str | None = None,
    extraction: dict[str, Any] | None = None,
    on_block: Callable[[InstanceBlock], None] | None = None,
) -> tuple[DatasetInfo, bool]:
    """Store instances as they come, in one transaction, unless the same content is stored.

    The data set's row is written first (so that a name taken meanwhile by another
    process shows at once), then each block of instances as ``source`` yields it, then
    the final schema and count.

    Parameters
    ----------
    store : Store
    source : InstanceSource
        The schema and the blocks of instances; blocks are read only if the content is new.
    sha256 : str
        Digest of the content (of the file's bytes for an import).
    name : str, optional
        The name; it must be free (see :func:`~app.store.naming.check_name`).
    default : str
        The name when ``name`` is not given, made unique with a numeric suffix.
    source_name : str, optional
        File name the data came from.
    extraction : dict, optional
        How the data set was extracted from recordings (JSON), kept so that models trained
        on it can extract live features the same way.
    on_block : callable, optional
        Called with each block before it is stored; what it raises undoes the import.

    Returns
    -------
    info : DatasetInfo
    created : bool
        ``False`` when the content was already stored and ``info`` is that data set.

    Raises
    ------
    AppError
        If ``name`` is invalid or taken (also by an import that committed meanwhile), or
        the store stayed locked by another writer.
    """
    if name is not None:
        check_name(name, kind="dataset")
    for _attempt in range(3):
        try:
            with store.session() as session:
                existing = find_by_digest(session, sha256)
                if existing is not None:
                    return existing, False
                chosen = name if name is not None else free_name(session, DatasetRow, default)
                if name is not None:
                    _refuse_taken(session, name)
                row = _insert_row(session, source.schema, chosen, sha256, source_name, extraction)
                count = _insert_blocks(session, row.id, source.blocks(), on_block)
                schema = source.schema
                session.execute(
                    update(DatasetRow)
                    .where(DatasetRow.id == row.id)
                    .values(
                        schema=schema.to_json(),
                        n_instances=count,
                        sparse=source.sparse,
                    )
                )
                session.refresh(row)
                return DatasetInfo.of(row), True
        except _NameTakenError as taken:
            if name is not None:
                raise ConflictError(_taken_message(store, taken.name)) from None
            # Another process took the default name meanwhile: choose again.
        except OperationalError as error:
            raise _busy_or_raise(error) from None
    raise AppError(f"could not find a free name for the dataset after '{default}' (busy store)")


class _NameTakenError(Exception):
    def __init__(self, name: str) -> None:
        self.name = name


def _insert_row(
    session: Session,
    schema: Schema,
    name: str,
    sha256: str,
    source_name: str | None,
    extraction: dict[str, Any] | None,
) -> DatasetRow:
    row = DatasetRow(
        name=name,
        relation=schema.relation,
        schema=schema.to_json(),
        target_names=list(schema.target_names),
        n_instances=0,
        n_attributes=schema.n_attributes,
        sparse=False,
        source_name=source_name,
        sha256=sha256,
        extraction=extraction,
    )
    session.add(row)
    try:
        session.flush()  # waits for a concurrent import of the same name to end
    except IntegrityError:
        raise _NameTakenError(name) from None
    return row


def valid_dataset_name(name: str) -> str:
    """``name`` if it can name a data set (see :func:`check_name`).

    Raises
    ------
    FieldError
        For the request's ``name``: the rule it breaks.
    """
    try:
        return check_name(name, kind="dataset")
    except AppError as error:
        raise FieldError("name", str(error)) from None


def check_dataset_name(store: Store, name: str) -> None:
    """Refuse a name no new data set can take: invalid, or another data set's.

    Raises
    ------
    FieldError
        For the request's ``name``: the rule it breaks.
    ConflictError
        Another data set has it.
    """
    valid_dataset_name(name)
    with store.session() as session:
        _refuse_taken(session, name)


def _refuse_taken(session: Session, name: str) -> None:
    clash = session.scalars(select(DatasetRow).where(DatasetRow.name == name)).first()
    if clash is not None:
        raise ConflictError(
            f"a dataset named '{shorten(name)}' already exists (id {clash.id}); choose another name"
        )


def _taken_message(store: Store, name: str) -> str:
    with store.session() as session:
        clash = session.scalars(select(DatasetRow).where(DatasetRow.name == name)).first()
    where = f" (id {clash.id})" if clash is not None else ""
    return f"a dataset named '{shorten(name)}' already exists{where}; choose another name"


def _busy_or_raise(error: OperationalError) -> Exception:
    if "locked" in str(error.orig):
        return AppError(
            "the store is busy: another process kept it locked for writing (an import?); "
            "try again when it is done"
        )
    return error


def find_by_digest(session: Session, sha256: str) -> DatasetInfo | None:
    """The first data set stored with content digest ``sha256``, if any."""
    row = session.scalars(
        select(DatasetRow).where(DatasetRow.sha256 == sha256).order_by(DatasetRow.id)
    ).first()
    return None if row is None else DatasetInfo.of(row)


def stored_digest(store: Store, sha256: str) -> DatasetInfo | None:
    """The first data set stored with content digest ``sha256``, if any."""
    with store.session() as session:
        return find_by_digest(session, sha256)


def _insert_blocks(
    session: Session,
    dataset_id: int,
    blocks: Iterable[InstanceBlock],
    on_block: Callable[[InstanceBlock], None] | None,
) -> int:
    """Insert every block's instances; the number inserted."""
    position = 0
    for block in blocks:
        if on_block is not None:
            on_block(block)
        _write_block(session, dataset_id, position, block)
        position += block.n_instances
    return position


def _write_block(session: Session, dataset_id: int, start: int, block: InstanceBlock) -> None:
    """Insert one block: its values and weights as stored blocks, then the groups and
    metadata of the instances that have any."""
    values = np.ascontiguousarray(block.values, dtype=_LITTLE_F8)
    weights = None if block.weights is None else np.asarray(block.weights, dtype=_LITTLE_F8)
    rows = stored_rows(values.shape[1])
    stored = [
        {
            "dataset_id": dataset_id,
            "start": start + first,
            "n_rows": min(rows, block.n_instances - first),
            "data": _bytes_of(values[first : first + rows]),
            "weights": None if weights is None else _bytes_of(weights[first : first + rows]),
        }
        for first in range(0, block.n_instances, rows)
    ]
    if stored:
        session.execute(insert(InstanceBlockRow), stored)
    extras = _extras(dataset_id, start, block)
    if extras:
        _insert_extras(session, extras)


def _insert_extras(session: Session, rows: list[dict[str, Any]]) -> None:
    """Insert rows of ``instances``.  An imported table's groups are a row per instance:
    PostgreSQL copies groups alone in (a statement per row costs a round trip each), and
    SQLite takes them through the table rather than the ORM class (whose bulk insert
    spends several times the driver's own time on each row)."""
    if "meta" not in rows[0] and session.connection().dialect.driver == "psycopg":
        columns = ("dataset_id", "position", "group_id")
        statement = f"COPY instances ({', '.join(columns)}) FROM STDIN"
        with _dbapi(session).cursor() as cursor, cursor.copy(statement) as copy:
            for row in rows:
                copy.write_row([row[column] for column in columns])
        return
    session.execute(insert(cast(Table, InstanceRow.__table__)), rows)


def _bytes_of(array: np.ndarray) -> memoryview:
    """The bytes of a C-contiguous array, not copied (both drivers take any bytes-like)."""
    return array.data.cast("B")


def stored_rows(n_attributes: int) -> int:
    """Instances per stored block of a data set with ``n_attributes`` attributes."""
    return max(1, STORED_BLOCK_BYTES // (_LITTLE_F8.itemsize * max(1, n_attributes)))


def _extras(dataset_id: int, start: int, block: InstanceBlock) -> list[dict[str, Any]]:
    """Rows of ``instances`` for the instances of ``block`` with a group or metadata."""
    groups, metas = block.groups, block.meta
    if groups is None and metas is None:
        return []
    if metas is None:  # groups alone (an imported table's group column)
        assert groups is not None
        return [
            {"dataset_id": dataset_id, "position": start + i, "group_id": str(group)}
            for i, group in enumerate(groups.tolist())
            if group is not None
        ]
    rows = []
    for i in range(block.n_instances):
        group = None if groups is None or groups[i] is None else str(groups[i])
        meta = None if metas is None else metas[i]
        if group is not None or meta is not None:
            rows.append(
                {"dataset_id": dataset_id, "position": start + i, "group_id": group, "meta": meta}
            )
    return rows


def _dbapi(session: Session) -> Any:
    dbapi = session.connection().connection.dbapi_connection
    assert dbapi is not None
    return dbapi


def find_dataset(store: Store, ref: str | int) -> DatasetInfo:
    """The data set called ``ref``, or with id ``ref``."""
    with store.session() as session:
        return DatasetInfo.of(_row(session, ref))


def load_schema(store: Store, ref: str | int) -> tuple[DatasetInfo, Schema, bool]:
    """A stored data set's listing, schema and whether it was read from sparse rows."""
    with store.session() as session:
        row = _row(session, ref)
        return DatasetInfo.of(row), Schema.from_json(row.schema), row.sparse


def load_dataset(store: Store, ref: str | int) -> Dataset:
    """The stored data set, values as WEKA encodes them (see :mod:`benchmark.dataset`)."""
    with store.session() as session:
        row = _row(session, ref)
        schema = Schema.from_json(row.schema)
        n = row.n_instances
        values = np.empty((n, schema.n_attributes))
        weights: np.ndarray | None = None
        count = 0
        for block in _value_batches(session, row.id, schema.n_attributes):
            stop = count + block.n_instances
            values[count:stop] = block.values
            if block.weights is not None:
                if weights is None:
                    weights = np.ones(n)
                weights[count:stop] = block.weights
            count = stop
        groups, meta = _instance_extras(session, row.id, count)
        return Dataset(
            schema=schema,
            values=values[:count],
            weights=None if weights is None else weights[:count],
            groups=groups,
            meta=meta,
            sparse=row.sparse,
            name=row.name,
        )


@dataclass
class StoredInstances:
    """A stored data set read back in blocks (an :class:`InstanceSource`).

    Made by :func:`read_blocks`; the blocks come from one query, so they are consistent
    with each other even if the data set changes meanwhile.
    """

    info: DatasetInfo
    schema: Schema
    sparse: bool
    _blocks: Iterator[InstanceBlock]

    def blocks(self) -> Iterator[InstanceBlock]:
        return self._blocks


@contextmanager
def read_blocks(
    store: Store, ref: str | int, *, rows: int | None = None
) -> Iterator[StoredInstances]:
    """A stored data set's values and weights, to read in blocks of ``rows`` instances
    (:data:`READ_BATCH` by default)::

    with read_blocks(store, "mini") as stored:
        for block in stored.blocks(): ...
    """
    with store.session() as session:
        row = _row(session, ref)
        schema = Schema.from_json(row.schema)
        batches = _value_batches(session, row.id, schema.n_attributes, rows=rows)
        yield StoredInstances(DatasetInfo.of(row), schema, row.sparse, batches)


def _value_batches(
    session: Session,
    dataset_id: int,
    n_attributes: int,
    *,
    rows: int | None = None,
) -> Iterator[InstanceBlock]:
    """Instances in order, at most ``rows`` at a time, one stored block fetched at a time,
    through the driver's own cursor (PostgreSQL's in binary: the text form of ``bytea``
    doubles what crosses the wire and costs its decoding)."""
    connection = session.connection()
    dbapi = _dbapi(session)
    style = connection.dialect.paramstyle
    marker = {"qmark": "?", "numeric": ":1", "named": ":id"}.get(style, "%s")
    postgresql = connection.dialect.driver == "psycopg"
    cursor = (
        dbapi.cursor(name=f"instances_{dataset_id}", binary=True) if postgresql else dbapi.cursor()
    )
    limit = rows or READ_BATCH
    try:
        cursor.execute(
            "SELECT n_rows, data, weights FROM instance_blocks "
            f"WHERE dataset_id = {marker} ORDER BY start",
            {"id": dataset_id} if style == "named" else (dataset_id,),
        )
        while stored := cursor.fetchone():
            n_rows, data, weights = stored
            _check_block(dataset_id, n_rows, n_attributes, data, weights)
            values = np.frombuffer(data, dtype=_LITTLE_F8).reshape(n_rows, n_attributes)
            scale = None if weights is None else np.frombuffer(weights, dtype=_LITTLE_F8)
            for first in range(0, n_rows, limit):
                part = slice(first, first + limit)
                yield InstanceBlock(values[part], weights=None if scale is None else scale[part])
    finally:
        cursor.close()


def _check_block(
    dataset_id: int, n_rows: int, n_attributes: int, data: bytes, weights: bytes | None
) -> None:
    """A stored block whose bytes do not fit its shape was written by someone else."""
    expected = n_rows * n_attributes * 8
    if len(data) != expected or (weights is not None and len(weights) != n_rows * 8):
        raise AppError(
            f"data set {dataset_id}: a stored block of {n_rows} instances holds {len(data)} "
            f"bytes where {n_attributes} attributes need {expected}; the store was changed "
            "outside touchbench: import the data set again"
        )


def _instance_extras(
    session: Session, dataset_id: int, n: int
) -> tuple[np.ndarray | None, list[dict[str, Any]] | None]:
    """Group ids and metadata, from the instances that have any."""
    rows = session.execute(
        select(InstanceRow.position, InstanceRow.group_id, InstanceRow.meta).where(
            InstanceRow.dataset_id == dataset_id
        )
    ).all()
    groups: np.ndarray | None = None
    meta: list[dict[str, Any]] | None = None
    for position, group, extra in rows:
        if group is not None:
            if groups is None:
                groups = np.full(n, None, dtype=object)
            groups[position] = group
        if extra is not None:
            if meta is None:
                meta = [{} for _ in range(n)]
            meta[position] = extra
    return groups, meta


def count_groups(store: Store, dataset_id: int) -> int:
    """How many distinct groups the instances of a stored data set fall into (0: none)."""
    with store.session() as session:
        count = session.scalar(
            select(func.count(distinct(InstanceRow.group_id))).where(
                InstanceRow.dataset_id == dataset_id
            )
        )
    return int(count or 0)


def rename_dataset(store: Store, ref: str | int, new_name: str) -> tuple[DatasetInfo, str]:
    """Give a data set another name; returns its listing and the name it had.

    Raises
    ------
    AppError
        If the name is invalid or another data set has it.
    """
    check_name(new_name, kind="dataset")
    try:
        with store.session() as session:
            row = _row(session, ref)
            old = row.name
            if new_name != old:
                _refuse_taken(session, new_name)
                row.name = new_name
                try:
                    session.flush()
                except IntegrityError:
                    raise _NameTakenError(new_name) from None
            return DatasetInfo.of(row), old
    except _NameTakenError as taken:
        raise ConflictError(_taken_message(store, taken.name)) from None


def delete_dataset(store: Store, ref: str | int) -> DatasetInfo:
    """Remove a data set with its instances (and, by cascade, its runs).

    Raises
    ------
    ConflictError
        If a run on it is queued, or running in a process that is alive: the run must be
        cancelled first.
    """
    with store.session() as session:
        row = _row(session, ref, lock=True)
        info = DatasetInfo.of(row)
        live = _live_run(session, row.id)
        if live is not None:
            run_id, status = live
            raise ConflictError(
                f"dataset '{shorten(info.name)}' is in use by run {run_id} ({status}); "
                f"cancel run {run_id} first or wait for it to end"
            )
        session.execute(delete(InstanceRow).where(InstanceRow.dataset_id == row.id))
        session.execute(delete(InstanceBlockRow).where(InstanceBlockRow.dataset_id == row.id))
        session.delete(row)
        return info


def _live_run(session: Session, dataset_id: int) -> tuple[int, str] | None:
    """A queued run on the data set, or a running one whose process is alive, if any."""
    runs = session.execute(
        select(RunRow.id, RunRow.status, RunRow.owner, RunRow.heartbeat_at)
        .where(RunRow.dataset_id == dataset_id)
        .where(RunRow.status.in_(UNFINISHED))
        .order_by(RunRow.id)
    ).all()
    for run_id, status, owner, heartbeat in runs:
        if status == Status.QUEUED or owner_alive(owner, heartbeat):
            return run_id, status
    return None


def _row(session: Session, ref: str | int, *, lock: bool = False) -> DatasetRow:
    row = find_row(
        session, DatasetRow, ref, kind="dataset", hint="the store has none; import one first"
    )
    if lock:
        session.refresh(row, with_for_update=True)
    return row
