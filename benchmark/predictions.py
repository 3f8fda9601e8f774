"""A task's test-fold predictions, kept so that a finished run can be re-scored, combined
and audited without fitting anything again.

:class:`FoldPredictions` holds what a fitted model said about the rows of one test fold (or,
for a stack or an ensemble selection, about the rows of a training fold, out of fold): the
rows, the predicted label codes, the class probabilities where the model has them, the
values of a regression.  :func:`encode` turns it into one compact, versioned bytes blob and
:func:`decode` back, bit for bit; no pickle, so that a blob read from a shared store cannot
run code.

The blob: the 4 bytes ``TBFP``, the length of a JSON header as a little-endian uint32, the
header (``{"version": 1, "n": ..., "arrays": [{"name", "dtype", "shape"}, ...], "raw":
bytes, "compression": "zlib"}``), then the arrays' little-endian bytes, one after the other
in the header's order, compressed with zlib.  Rows and label codes take the smallest integer
type that holds them; probabilities and values stay float64, since re-scoring must give the
stored metrics exactly: the log loss of a probability rounded to float32 differs in its
last digits, and the rounding makes ties that change a fold's ROC AUC.
"""

from __future__ import annotations

import json
import struct
import zlib
from dataclasses import dataclass

import numpy as np

from touchbench.benchmark.errors import DataFormatError

__all__ = ["VERSION", "FoldPredictions", "decode", "encode"]

#: Version of the encoding :func:`encode` writes; :func:`decode` reads it and every older.
VERSION = 1
_MAGIC = b"TBFP"
_HEADER_LENGTH = struct.Struct("<I")
#: Longest header accepted (a header names a few arrays per target).
_MAX_HEADER = 1 << 20
#: The types an array may be stored as: integers of rows and codes, float64 numbers.
_INTEGERS = ("<i1", "<i2", "<i4", "<i8")
_FLOAT = "<f8"
_SOURCE = "fold predictions"


@dataclass(frozen=True, eq=False)
class FoldPredictions:
    """What a fitted model predicted for some rows of a problem.

    Parameters
    ----------
    indices : ndarray of shape (n,), int64
        The rows (positions in the problem's ``X``), in the order of the other arrays:
        the test fold's, or a training fold's for out-of-fold predictions.
    labels : ndarray of shape (n, n_targets), int64, or None
        Predicted label codes per target; ``None`` for a regression.
    proba : tuple of ndarray, or None
        Classes only: one (n, n_classes[t]) float64 matrix of class probabilities per target,
        columns the declared label codes; ``None`` for a model without probabilities.
    values : ndarray of shape (n, n_targets), float64, or None
        A regression's predicted values; ``None`` for classes.
    """

    indices: np.ndarray
    labels: np.ndarray | None = None
    proba: tuple[np.ndarray, ...] | None = None
    values: np.ndarray | None = None

    def __post_init__(self) -> None:
        indices = np.asarray(self.indices, dtype=np.int64).reshape(-1)
        n = indices.size
        labels = None if self.labels is None else _two_d(self.labels, np.int64, n, "labels")
        values = None if self.values is None else _two_d(self.values, np.float64, n, "values")
        if (labels is None) == (values is None):
            raise ValueError("fold predictions hold either labels or values")
        proba = None
        if self.proba is not None:
            if labels is None:
                raise ValueError("probabilities come with labels")
            proba = tuple(_two_d(p, np.float64, n, "proba") for p in self.proba)
            if len(proba) != labels.shape[1]:
                raise ValueError(f"{len(proba)} probability matrices for {labels.shape[1]} targets")
        object.__setattr__(self, "indices", indices)
        object.__setattr__(self, "labels", labels)
        object.__setattr__(self, "values", values)
        object.__setattr__(self, "proba", proba)

    @classmethod
    def of_classes(
        cls, indices: np.ndarray, labels: np.ndarray, proba: np.ndarray | None
    ) -> FoldPredictions:
        """One target's predictions: ``labels`` of shape (n,), ``proba`` (n, n_classes)."""
        column = np.asarray(labels, dtype=np.int64).reshape(-1, 1)
        return cls(indices, column, None if proba is None else (proba,))

    @property
    def n(self) -> int:
        """Rows predicted."""
        return int(self.indices.size)

    @property
    def label(self) -> np.ndarray:
        """The first (a multi-class problem's only) target's codes, shape (n,)."""
        if self.labels is None:
            raise ValueError("a regression's predictions have no labels")
        return self.labels[:, 0]

    @property
    def probabilities(self) -> np.ndarray | None:
        """The first target's class probabilities, shape (n, n_classes), if any."""
        return None if self.proba is None else self.proba[0]

    def same_as(self, other: FoldPredictions) -> bool:
        """Whether both hold the same rows and the same numbers, bit for bit."""
        mine, theirs = self._arrays(), other._arrays()
        return [name for name, _ in mine] == [name for name, _ in theirs] and all(
            a.shape == b.shape and a.dtype == b.dtype and a.tobytes() == b.tobytes()
            for (_, a), (_, b) in zip(mine, theirs, strict=True)
        )

    def _arrays(self) -> list[tuple[str, np.ndarray]]:
        arrays = [("indices", self.indices)]
        if self.labels is not None:
            arrays.append(("labels", self.labels))
        for t, matrix in enumerate(self.proba or ()):
            arrays.append((f"proba/{t}", matrix))
        if self.values is not None:
            arrays.append(("values", self.values))
        return arrays


def encode(predictions: FoldPredictions) -> bytes:
    """The predictions as one versioned bytes blob (see the module's notes)."""
    entries = []
    body = []
    for name, array in predictions._arrays():
        dtype = _FLOAT if array.dtype == np.float64 else _smallest_integer(array)
        data = np.ascontiguousarray(array, dtype=np.dtype(dtype))
        entries.append({"name": name, "dtype": dtype, "shape": list(data.shape)})
        body.append(data.tobytes())
    raw = b"".join(body)
    header = json.dumps(
        {
            "version": VERSION,
            "n": predictions.n,
            "arrays": entries,
            "raw": len(raw),
            "compression": "zlib",
        },
        separators=(",", ":"),
    ).encode()
    return _MAGIC + _HEADER_LENGTH.pack(len(header)) + header + zlib.compress(raw, 6)


def decode(blob: bytes) -> FoldPredictions:
    """The predictions :func:`encode` wrote, bit for bit.

    Raises
    ------
    DataFormatError
        Not such a blob, a newer version, or a header that does not agree with its arrays.
    """
    view = memoryview(blob)
    if bytes(view[:4]) != _MAGIC or len(view) < 4 + _HEADER_LENGTH.size:
        raise DataFormatError("not an encoding of fold predictions", source=_SOURCE)
    (length,) = _HEADER_LENGTH.unpack_from(view, 4)
    start = 4 + _HEADER_LENGTH.size
    if length > _MAX_HEADER or start + length > len(view):
        raise DataFormatError("a header longer than the blob", source=_SOURCE)
    try:
        header = json.loads(bytes(view[start : start + length]))
        version, n, entries, size = (
            int(header["version"]),
            int(header["n"]),
            list(header["arrays"]),
            int(header["raw"]),
        )
        compression = header["compression"]
    except (ValueError, KeyError, TypeError) as error:
        raise DataFormatError(f"an unreadable header ({error})", source=_SOURCE) from None
    if version > VERSION:
        raise DataFormatError(
            f"version {version}; this touchbench reads up to {VERSION}", source=_SOURCE
        )
    if compression != "zlib":
        raise DataFormatError(f"unknown compression '{compression}'", source=_SOURCE)
    expected = sum(_size(entry, n) for entry in entries)
    if expected != size:
        raise DataFormatError("the header's arrays do not add up to its size", source=_SOURCE)
    inflater = zlib.decompressobj()
    try:
        raw = inflater.decompress(bytes(view[start + length :]), size + 1)
    except zlib.error as error:
        raise DataFormatError(f"damaged arrays ({error})", source=_SOURCE) from None
    if len(raw) != size or not inflater.eof:
        raise DataFormatError("arrays of another size than the header says", source=_SOURCE)
    arrays: dict[str, np.ndarray] = {}
    offset = 0
    for entry in entries:
        dtype = np.dtype(entry["dtype"])
        shape = tuple(int(s) for s in entry["shape"])
        count = int(np.prod(shape))
        array = np.frombuffer(raw, dtype=dtype, count=count, offset=offset).reshape(shape)
        offset += count * dtype.itemsize
        wanted = np.float64 if entry["dtype"] == _FLOAT else np.int64
        arrays[str(entry["name"])] = array.astype(wanted)
    return _assemble(arrays)


def _assemble(arrays: dict[str, np.ndarray]) -> FoldPredictions:
    names = set(arrays)
    probas = sorted((name for name in names if name.startswith("proba/")), key=_target_of)
    known = {"indices", "labels", "values", *probas}
    if "indices" not in names or names - known:
        raise DataFormatError(f"unexpected arrays {sorted(names - known)}", source=_SOURCE)
    if [_target_of(name) for name in probas] != list(range(len(probas))):
        raise DataFormatError("probabilities of missing targets", source=_SOURCE)
    try:
        return FoldPredictions(
            arrays["indices"],
            arrays.get("labels"),
            tuple(arrays[name] for name in probas) if probas else None,
            arrays.get("values"),
        )
    except ValueError as error:
        raise DataFormatError(str(error), source=_SOURCE) from None


def _size(entry: object, n: int) -> int:
    """Bytes of one array the header describes, after checking its name, type and rows."""
    if not isinstance(entry, dict) or not {"name", "dtype", "shape"} <= set(entry):
        raise DataFormatError("an array without name, dtype and shape", source=_SOURCE)
    name, dtype, shape = entry["name"], entry["dtype"], entry["shape"]
    allowed = (_FLOAT,) if name == "values" or str(name).startswith("proba/") else _INTEGERS
    if dtype not in allowed:
        raise DataFormatError(f"array '{name}' of type {dtype}", source=_SOURCE)
    if (
        not isinstance(shape, list)
        or not 1 <= len(shape) <= 2
        or not all(isinstance(s, int) and s >= 0 for s in shape)
        or shape[0] != n
    ):
        raise DataFormatError(f"array '{name}' of shape {shape} for {n} rows", source=_SOURCE)
    return int(np.prod(shape)) * np.dtype(dtype).itemsize


def _target_of(name: str) -> int:
    suffix = name.partition("/")[2]
    if not suffix.isdigit():
        raise DataFormatError(f"array '{name}'", source=_SOURCE)
    return int(suffix)


def _smallest_integer(array: np.ndarray) -> str:
    if array.size == 0:
        return "<i1"
    low, high = int(array.min()), int(array.max())
    for dtype in _INTEGERS:
        info = np.iinfo(np.dtype(dtype))
        if info.min <= low and high <= info.max:
            return dtype
    raise ValueError("integers beyond int64")  # cannot happen: the arrays are int64


def _two_d(values: object, dtype: type, n: int, name: str) -> np.ndarray:
    array: np.ndarray = np.asarray(values, dtype=dtype)
    if array.ndim == 1:
        array = array[:, None]
    if array.ndim != 2 or array.shape[0] != n:
        raise ValueError(f"{name} of shape {array.shape} for {n} rows")
    return array
