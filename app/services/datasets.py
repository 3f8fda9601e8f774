"""Data-set use cases: import a file, list, describe, export, rename, delete.

The CLI and the API call these and render what they return (:mod:`app.schemas.datasets`).

Importing streams: an ARFF file is checked from its first bytes, scanned once (digest,
encoding), then read block by block straight into the store, so memory stays flat
whatever the file's size.  A file whose content is stored already is not stored again:
importing it answers "already stored", and refuses (saying how to rename) when another
``name`` or other ``targets`` were asked for.  A new data set is named after the file's
stem (``mini.arff`` -> ``mini``); the ARFF relation stays in its metadata and exports.

A table from another lab may name each row's group in a column (the object grasped, the
subject) and hold columns that are neither features nor targets: the request's ``groups``
and ``ignore`` set them aside as the file is read (:mod:`benchmark.io.columns`), the group
column's cells stored as the instances' groups.  The same file read with other columns set
aside is another data set: its key in the store is the file's digest and the columns'.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import queue
import stat
import tempfile
import threading
import warnings
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TextIO

import numpy as np

from touchbench.app.errors import AppError, ConflictError, FieldError
from touchbench.app.schemas.datasets import (
    AttributeDescription,
    DatasetDescription,
    DatasetSummary,
    FileFormat,
    GroupsDescription,
    ImportRequest,
    ImportResult,
    RenameRequest,
    RenameResult,
)
from touchbench.app.services.limits import check_dataset_size, sequence_of
from touchbench.app.services.listing import summary
from touchbench.app.store import datasets as stored
from touchbench.app.store.database import Store
from touchbench.app.store.datasets import DatasetInfo, DatasetInMemory, InstanceSource
from touchbench.app.store.naming import default_name
from touchbench.benchmark.dataset import Dataset, InstanceBlock, Schema
from touchbench.benchmark.errors import DataFormatError, DataWarning
from touchbench.benchmark.io.arff import ArffWriter, open_arff, read_arff
from touchbench.benchmark.io.columns import ColumnChoice, ColumnError
from touchbench.benchmark.io.csv import read_csv
from touchbench.benchmark.io.textfile import FileScan, check_regular_file, open_binary, scan_file

#: Called with (what is being done, bytes done, bytes in all) while a file is imported.
ImportProgress = Callable[[str, int, int], None]


def guess_format(path: Path) -> FileFormat:
    """``csv`` for ``.csv``, ``.tsv`` and ``.txt`` files, else ``arff``."""
    return "csv" if path.suffix.lower() in {".csv", ".tsv", ".txt"} else "arff"


# ---------------------------------------------------------------------------------- import


def import_file(
    store: Store, request: ImportRequest, *, progress: ImportProgress | None = None
) -> ImportResult:
    """Import an ARFF or CSV file as a data set, streaming it into the store.

    Parameters
    ----------
    store : Store
    request : ImportRequest
        The file (a regular file), and optionally the data set's name (by default the stem
        of its ``source_name`` or of the file, made unique with a numeric suffix), its
        targets (by default MEKA's ``-C`` in the relation, else the last attribute), its
        format (by default from the file name's ending), the name the user knows the
        file by (an upload's file name, when ``file`` is a temporary copy: it names the
        data set, is kept as its source, and is what error messages call the file), the
        column that names each instance's group and the columns left out.
    progress : callable, optional
        Called with (what is being done, bytes done, bytes in all).

    Returns
    -------
    ImportResult

    Raises
    ------
    DataFormatError
        If the file is not a regular file, not text, or not valid ARFF/CSV; if it holds
        no instances, infinite values or an instance without a group; if it leaves no
        feature, or has more targets or attributes than :mod:`app.services.limits`
        allows.  Nothing is stored.
    FieldError
        If the name is invalid; if ``groups`` or ``ignore`` name a column the file does
        not have, a target, or each other's column, or leave no feature.  Nothing is
        stored.
    ConflictError
        If the name is taken, or the content is stored already and another name or other
        targets were asked for.
    """
    path, name, targets = request.file, request.name, request.targets
    columns = ColumnChoice(groups=request.groups, ignore=tuple(request.ignore))
    shown = request.source_name or path.name
    if name is not None:  # a name taken by the same content answers "already stored"
        stored.valid_dataset_name(name)
    chosen = request.format or guess_format(Path(shown))
    notes: list[str] = []
    label = request.source_name or str(path)  # what messages call the file
    opened = _open_data(path, label, chosen, targets, columns, Path(shown).stem, progress, notes)
    with opened as data:
        _check_schema(data.schema, label, notes)
        key = import_key(data.scan.sha256, columns)
        existing = stored.stored_digest(store, key)
        if existing is None:
            checked = _CheckedInstances(data, label, progress)
            info, created = stored.add_dataset_stream(
                store,
                checked,
                sha256=key,
                name=name,
                default=default_name(Path(shown).stem),
                source_name=shown,
            )
            if created:
                if columns.ignore:
                    notes.append(f"columns left out: {', '.join(columns.ignore)}")
                return _result(store, info, data.schema, True, notes)
            existing = info  # the same content was stored meanwhile by another process
        return _already_stored(store, existing, shown, name, targets, data.schema, notes)


def import_key(sha256: str, columns: ColumnChoice) -> str:
    """The key that recognises a data set imported before: the file's digest, or with
    columns set aside a digest of it and of them (the order of ignored columns aside)."""
    if not columns:
        return sha256
    chosen = {"file": sha256, "groups": columns.groups, "ignore": sorted(columns.ignore)}
    return hashlib.sha256(json.dumps(chosen, sort_keys=True).encode()).hexdigest()


@dataclass
class _Opened:
    """A data file opened for import: what :func:`import_file` needs of ARFF and CSV alike."""

    scan: FileScan
    source: InstanceSource

    @property
    def schema(self) -> Schema:
        return self.source.schema

    @property
    def sparse(self) -> bool:
        return self.source.sparse

    @property
    def bytes_read(self) -> int:
        return int(getattr(self.source, "bytes_read", self.scan.size))

    def blocks(self) -> Iterator[InstanceBlock]:
        return self.source.blocks()


@contextlib.contextmanager
def _open_data(
    path: Path,
    label: str,
    file_format: FileFormat,
    targets: int | Sequence[str] | None,
    columns: ColumnChoice,
    stem: str,
    progress: ImportProgress | None,
    notes: list[str],
) -> Iterator[_Opened]:
    def scanned(done: int, total: int) -> None:
        if progress is not None:
            progress("checking", done, total)

    with _columns_as_fields():
        if file_format == "arff":
            with open_arff(
                path, targets=targets, progress=scanned, source=label, columns=columns
            ) as reader:
                yield _Opened(reader.scan, reader)
            return
        with open_binary(check_regular_file(path)) as stream:
            scan = scan_file(stream, source=label, size=os.fstat(stream.fileno()).st_size)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", DataWarning)
            dataset = read_csv(path, targets=targets, relation=stem, source=label, columns=columns)
        notes += [str(w.message) for w in caught if issubclass(w.category, DataWarning)]
        yield _Opened(scan, DatasetInMemory(dataset))


@contextlib.contextmanager
def _columns_as_fields() -> Iterator[None]:
    """A column choice the file refuses, as the request's field (``groups``, ``ignore``)."""
    try:
        yield
    except ColumnError as error:
        raise FieldError(error.field, error.message) from None


def _check_schema(schema: Schema, source: str, notes: list[str]) -> None:
    check_dataset_size(
        n_targets=len(schema.target_indices),
        n_attributes=schema.n_attributes,
        source=source,
        sequence=sequence_of(schema.feature_names),
    )
    if not schema.feature_indices:
        raise DataFormatError(
            "no features: every attribute is a target "
            f"({', '.join(schema.target_names)}); a data set needs at least one feature",
            source=source,
        )
    notes += target_notes(schema)


def target_notes(schema: Schema) -> list[str]:
    """What a user should know about the targets: numeric ones are regression targets."""
    return [
        f"target '{target.name}' is numeric: a regression target (a run on it runs regressors "
        "and ranks by mean absolute error; the targets of an import or of a run choose others)"
        for target in schema.targets
        if target.kind == "numeric"
    ]


@dataclass
class _CheckedInstances:
    """The blocks of an opened file, refused where they would fail later: infinite values,
    no instances at all.  Raising inside the store's transaction undoes the import."""

    data: _Opened
    source: str
    progress: ImportProgress | None
    count: int = field(default=0, init=False)

    @property
    def schema(self) -> Schema:
        return self.data.schema

    @property
    def sparse(self) -> bool:
        return self.data.sparse

    def blocks(self) -> Iterator[InstanceBlock]:
        size = self.data.scan.size
        for block in prefetched(self.data.blocks()):
            _refuse_infinite(block, self.schema, self.source, self.count)
            self.count += block.n_instances
            if self.progress is not None:
                self.progress("importing", min(self.data.bytes_read, size), size)
            yield block
        if self.count == 0:
            raise DataFormatError(
                "no instances: the file has a header but no data rows", source=self.source
            )


def prefetched(blocks: Iterator[InstanceBlock], depth: int = 2) -> Iterator[InstanceBlock]:
    """``blocks``, read ahead by a thread while the caller stores the ones before.

    Parsing (Arrow's CSV reader) and inserting (the database driver) both release the GIL
    for most of their work, so on two cores an import takes about the longer of the two
    rather than their sum.  At most ``depth`` blocks wait; what the reader raises is
    raised here, and the reader stops when the caller does.
    """
    ahead: queue.Queue[tuple[str, Any]] = queue.Queue(maxsize=depth)
    stop = threading.Event()

    def offer(kind: str, item: Any) -> bool:
        """Queue an item unless the caller stopped; ``False`` if it did."""
        while not stop.is_set():
            try:
                ahead.put((kind, item), timeout=0.1)
                return True
            except queue.Full:
                continue
        return False

    def read() -> None:
        try:
            for block in blocks:
                if not offer("block", block):
                    return
            offer("end", None)
        except BaseException as error:  # handed to the caller, which raises it
            offer("error", error)

    reader = threading.Thread(target=read, name="import-reader", daemon=True)
    reader.start()
    try:
        while True:
            kind, item = ahead.get()
            if kind == "end":
                return
            if kind == "error":
                raise item
            yield item
    finally:
        stop.set()
        reader.join()


def _refuse_infinite(block: InstanceBlock, schema: Schema, source: str, offset: int) -> None:
    infinite = np.isinf(block.values)
    if not infinite.any():
        return
    row, column = (int(i) for i in np.argwhere(infinite)[0])
    sign = "-" if block.values[row, column] < 0 else ""
    line = None if block.lines is None else int(block.lines[row])
    where = "" if line is not None else f" (data row {offset + row + 1})"
    raise DataFormatError(
        f"{sign}infinity{where} is not a value classifiers can use; write ? for a missing "
        "value, or the finite value meant",
        source=source,
        line=line,
        attribute=schema.attributes[column].name,
    )


def _already_stored(
    store: Store,
    existing: DatasetInfo,
    shown: str,
    name: str | None,
    targets: int | Sequence[str] | None,
    schema: Schema,
    notes: list[str],
) -> ImportResult:
    stored_as = f"{shown} is already stored as dataset {existing.id} '{existing.name}'"
    if name is not None and name != existing.name:
        raise ConflictError(
            f"{stored_as}; nothing imported (renaming dataset {existing.id} gives it that name)"
        )
    if targets is not None and list(schema.target_names) != existing.targets:
        raise ConflictError(
            f"{stored_as} with targets {', '.join(existing.targets)}; nothing imported "
            "(a run chooses its own targets among the attributes)"
        )
    _, stored_schema, _ = stored.load_schema(store, existing.id)
    notes = [*notes, f"{stored_as}; nothing imported"]
    return _result(store, existing, stored_schema, False, notes)


def _result(
    store: Store, info: DatasetInfo, schema: Schema, created: bool, notes: list[str]
) -> ImportResult:
    return ImportResult(
        id=info.id,
        name=info.name,
        n_instances=info.n_instances,
        n_features=info.n_features,
        targets=info.targets,
        created=created,
        action="imported" if created else "already stored",
        notes=notes,
        groups=_groups(store, info.id, schema),
    )


def _groups(store: Store, dataset_id: int, schema: Schema) -> GroupsDescription | None:
    """How many groups a stored data set's instances fall into and what named them."""
    count = stored.count_groups(store, dataset_id)
    return GroupsDescription(count=count, column=schema.group_column) if count else None


# -------------------------------------------------------------------------------- describe


def find_dataset(store: Store, ref: str | int) -> DatasetInfo:
    """The data set ``ref`` names (a name or an id), without reading its instances.

    Raises
    ------
    app.errors.NotFoundError
        No such data set.
    """
    return stored.find_dataset(store, ref)


def add_made_dataset(
    store: Store, dataset: Dataset, *, name: str | None = None
) -> tuple[DatasetInfo, bool]:
    """Store a data set made in memory (a DataFrame's, a pair of arrays'), known by the
    digest of its schema and values, so that storing it again finds the first.

    Returns
    -------
    tuple of (DatasetInfo, bool)
        The stored data set, and whether it was stored now (False: it was there).
    """
    return stored.add_dataset(store, dataset, sha256=stored.dataset_digest(dataset), name=name)


def read_dataset(store: Store, ref: str | int) -> Dataset:
    """A stored data set whole, values as WEKA encodes them.

    Raises
    ------
    app.errors.NotFoundError
        No such data set.
    """
    return stored.load_dataset(store, ref)


def dataset_schema(store: Store, ref: str | int) -> tuple[DatasetInfo, Schema]:
    """The data set ``ref`` names and its attributes, without reading its instances.

    Raises
    ------
    app.errors.NotFoundError
        No such data set.
    """
    info, schema, _ = stored.load_schema(store, ref)
    return info, schema


def describe_dataset(store: Store, ref: str | int) -> DatasetDescription:
    """Schema, per-attribute missing counts and ranges, class distribution per target.

    The instances are read in batches: memory stays flat whatever the data set's size.
    """
    with stored.read_blocks(store, ref) as data:
        schema = data.schema
        n = schema.n_attributes
        missing = np.zeros(n, dtype=np.int64)
        low = np.full(n, np.nan)
        high = np.full(n, np.nan)
        finite = np.zeros(n, dtype=bool)
        counts = {
            j: np.zeros(len(schema.attributes[j].values), dtype=np.int64)
            for j in schema.target_indices
            if schema.attributes[j].kind == "nominal"
        }
        for block in data.blocks():
            values = block.values
            missing += np.isnan(values).sum(axis=0)
            finite |= np.isfinite(values).any(axis=0)
            if values.shape[0]:
                low = np.fmin(low, np.fmin.reduce(values, axis=0))
                high = np.fmax(high, np.fmax.reduce(values, axis=0))
            for j, tally in counts.items():
                codes = values[:, j]
                tally += np.bincount(codes[~np.isnan(codes)].astype(int), minlength=tally.size)
        info = data.info
    targets = set(schema.target_indices)
    attributes = []
    for j, attribute in enumerate(schema.attributes):
        entry = AttributeDescription(
            name=attribute.name,
            kind=attribute.kind,
            role="target" if j in targets else "feature",
            missing=int(missing[j]),
        )
        if attribute.kind == "nominal":
            entry.values = list(attribute.values)
        elif attribute.kind == "numeric" and finite[j]:
            entry.min, entry.max = float(low[j]), float(high[j])
        attributes.append(entry)
    return DatasetDescription(
        id=info.id,
        name=info.name,
        n_instances=info.n_instances,
        n_features=info.n_features,
        targets=info.targets,
        relation=schema.relation,
        attributes=attributes,
        class_distribution={
            schema.attributes[j].name: {
                label: int(c) for label, c in zip(schema.attributes[j].values, tally, strict=True)
            }
            for j, tally in counts.items()
        },
        missing_values=int(missing.sum()),
        notes=target_notes(schema),
        groups=_groups(store, info.id, schema),
    )


# ---------------------------------------------------------------------------------- export


def export_dataset(store: Store, ref: str | int, stream: TextIO) -> int:
    """Write a stored data set as ARFF to ``stream``, reading it in batches.

    The relation keeps MEKA's ``-C`` header for the data set's targets.  Memory stays that
    of one batch, whatever the data set's size.

    Returns
    -------
    int
        The number of instances written.
    """
    with stored.read_blocks(store, ref) as data:
        writer = ArffWriter(stream, data.schema, sparse=data.sparse)
        writer.write_header()
        for block in data.blocks():
            writer.write_block(block.values, block.weights)
        return writer.rows_written


def export_to_file(store: Store, ref: str | int, path: Path, *, force: bool = False) -> int:
    """Write a stored data set as an ARFF file, all or nothing.

    A regular file is written beside ``path`` under a temporary name and renamed over it
    once complete, so that an error or an interruption leaves no half-written file; a
    device or a pipe (``/dev/null``) is written directly.

    Returns
    -------
    int
        The number of instances written.

    Raises
    ------
    FieldError
        For ``force``: ``path`` is a file and ``force`` is not set.
    AppError
        If ``path`` is a folder, its folder does not exist, or it cannot be written (full
        disk, no permission).
    """
    stored.find_dataset(store, ref)  # an unknown data set fails before any file is touched
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        mode = None
    except OSError as error:
        raise AppError(f"cannot write {path}: {error.strerror}") from None
    if mode is not None and stat.S_ISDIR(mode):
        raise AppError(f"cannot write {path}: it is a folder (give a file name)")
    if mode is not None and not stat.S_ISREG(mode):  # a device or a pipe: nothing to replace
        try:
            with open(path, "w", encoding="utf-8", newline="\n") as stream:
                return export_dataset(store, ref, stream)
        except OSError as error:
            raise AppError(f"cannot write {path}: {error.strerror or error}") from None
    if mode is not None and not force:
        raise FieldError("force", f"is needed to replace {path}, which exists")
    folder = path.parent
    if not folder.is_dir():
        raise AppError(f"cannot write {path}: the folder {folder} does not exist")
    try:
        handle, temporary = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=folder)
        os.fchmod(handle, 0o666 & ~_umask())
    except OSError as error:
        raise AppError(f"cannot write {path}: {error.strerror}") from None
    try:
        with os.fdopen(handle, "w", encoding="utf-8", newline="\n") as stream:
            count = export_dataset(store, ref, stream)
        os.replace(temporary, path)
    except BaseException as error:
        with contextlib.suppress(OSError):
            os.unlink(temporary)
        if isinstance(error, OSError):
            raise AppError(f"cannot write {path}: {error.strerror or error}") from None
        raise
    return count


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


# ------------------------------------------------------------------------- rename, delete


def rename_dataset(store: Store, ref: str | int, request: RenameRequest) -> RenameResult:
    """Give a data set another name (unique, see :func:`~app.schemas.names.check_name`)."""
    info, previous = stored.rename_dataset(store, ref, request.name)
    return RenameResult(id=info.id, name=info.name, previous_name=previous)


def delete_dataset(store: Store, ref: str | int) -> DatasetSummary:
    """Delete a data set with its instances, runs and results; refused while a run on it
    is queued or running."""
    return summary(stored.delete_dataset(store, ref))


def read_data_file(
    path: Path, file_format: FileFormat | None = None, *, source: str | None = None
) -> Dataset:
    """An ARFF or CSV file read into memory (to predict it; nothing is stored).

    ``source`` is what messages call the file: an upload's own name, not the service's
    copy of it (``path`` by default).

    Raises
    ------
    DataFormatError
        No such regular file, or a file that is not valid ARFF/CSV (with its line).
    """
    check_regular_file(path)  # an upload is always a regular file: its path is never shown
    if (file_format or guess_format(path)) == "csv":
        return read_csv(path, targets=None, source=source)
    return read_arff(path, source=source)
