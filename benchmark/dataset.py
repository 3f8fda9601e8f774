"""The in-memory data set: an ARFF schema plus a float matrix, as WEKA keeps it.

Every value is a float64, as in WEKA's ``Instance``: numeric values as they are, nominal
values as the index of the declared label, string values as an index into the
attribute's string table, dates as seconds since the Unix epoch (UTC), and missing
values as NaN.  This keeps a whole data set in one contiguous array that converts to the
engine's ``X`` and ``Y`` without copying the schema around.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import Any, Literal

import numpy as np

from touchbench.benchmark.errors import ConfigurationError

AttributeKind = Literal["numeric", "nominal", "string", "date"]

#: MEKA's ``-C`` option and what follows it (a count, when the relation is valid).
_MEKA_TARGETS = re.compile(r"(?:^|\s)-C(?:\s+(\S+)|\s*$)")
_COUNT = re.compile(r"-?\d+")


@dataclass(frozen=True)
class Attribute:
    """One ARFF attribute.

    Parameters
    ----------
    name : str
        The attribute's name as declared.
    kind : {"numeric", "nominal", "string", "date"}
        How values are encoded in :attr:`Dataset.values`.
    values : tuple of str
        Nominal: the declared labels in order (a value is its index).  String: the
        string table (a value is its index).  Empty otherwise.
    declared_type : str
        The type keyword as written in the file (``"numeric"``, ``"REAL"``,
        ``"integer"``...), kept so that export writes back what was read.
    date_format : str or None
        Date attributes: the Java ``SimpleDateFormat`` pattern, ``None`` for WEKA's
        default ISO-8601 pattern.
    """

    name: str
    kind: AttributeKind
    values: tuple[str, ...] = ()
    declared_type: str = ""
    date_format: str | None = None

    def __post_init__(self) -> None:
        if not self.declared_type:
            object.__setattr__(self, "declared_type", self.kind)

    @property
    def is_nominal(self) -> bool:
        return self.kind == "nominal"

    @property
    def is_numeric(self) -> bool:
        return self.kind == "numeric"

    def label(self, code: float) -> str | None:
        """The text of a nominal or string code, ``None`` for a missing value."""
        if np.isnan(code):
            return None
        return self.values[int(code)]

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {"name": self.name, "kind": self.kind}
        if self.values:
            out["values"] = list(self.values)
        if self.declared_type and self.declared_type != self.kind:
            out["declared_type"] = self.declared_type
        if self.date_format is not None:
            out["date_format"] = self.date_format
        return out

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> Attribute:
        return cls(
            name=data["name"],
            kind=data["kind"],
            values=tuple(data.get("values", ())),
            declared_type=data.get("declared_type", data["kind"]),
            date_format=data.get("date_format"),
        )


@dataclass(frozen=True)
class Schema:
    """Relation name, attributes in file order, and which of them are targets.

    Parameters
    ----------
    relation : str
        The ``@relation`` name as written (MEKA's ``-C`` options included).
    attributes : tuple of Attribute
        All attributes in file order.
    target_indices : tuple of int
        Positions of the target attributes in ``attributes`` (ascending).
    group_column : str or None
        The column of the source file that named each instance's group (the object
        grasped, the subject, the session), set aside as :attr:`Dataset.groups` rather
        than kept as an attribute; ``None`` when no column did (extracted data sets have
        groups all the same: the recording of each instance).
    """

    relation: str
    attributes: tuple[Attribute, ...]
    target_indices: tuple[int, ...]
    group_column: str | None = None

    @property
    def n_attributes(self) -> int:
        return len(self.attributes)

    @cached_property
    def feature_indices(self) -> tuple[int, ...]:
        targets = set(self.target_indices)
        return tuple(i for i in range(len(self.attributes)) if i not in targets)

    @cached_property
    def targets(self) -> tuple[Attribute, ...]:
        return tuple(self.attributes[i] for i in self.target_indices)

    @cached_property
    def features(self) -> tuple[Attribute, ...]:
        return tuple(self.attributes[i] for i in self.feature_indices)

    @cached_property
    def target_names(self) -> tuple[str, ...]:
        return tuple(a.name for a in self.targets)

    @cached_property
    def feature_names(self) -> tuple[str, ...]:
        return tuple(a.name for a in self.features)

    def index(self, name: str) -> int:
        """Position of the attribute called ``name``."""
        for i, attribute in enumerate(self.attributes):
            if attribute.name == name:
                return i
        raise ConfigurationError(
            f"no attribute named '{name}' (attributes: {shortlist(self.attributes)})"
        )

    def with_targets(self, target_indices: Sequence[int]) -> Schema:
        return replace(self, target_indices=tuple(sorted(target_indices)))

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "relation": self.relation,
            "attributes": [a.to_json() for a in self.attributes],
            "target_indices": list(self.target_indices),
        }
        if self.group_column is not None:  # absent otherwise: schemas stored before it read alike
            out["group_column"] = self.group_column
        return out

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> Schema:
        return cls(
            relation=data["relation"],
            attributes=tuple(Attribute.from_json(a) for a in data["attributes"]),
            target_indices=tuple(data["target_indices"]),
            group_column=data.get("group_column"),
        )


@dataclass
class Dataset:
    """A schema and its instances.

    Parameters
    ----------
    schema : Schema
        Attributes and targets.
    values : ndarray of shape (n_instances, n_attributes), float64
        Every value encoded as described in the module docstring; NaN is missing.
    weights : ndarray of shape (n_instances,) or None
        ARFF instance weights (``{w}`` after a row); ``None`` means all 1.
    groups : ndarray of shape (n_instances,) or None
        Recording/session id of each instance, for folds that keep a recording
        on one side; ``None`` when instances are independent.
    meta : list of dict or None
        Per-instance provenance (source file, start and end seconds, frame
        sequences...), kept by the store but not part of the ARFF data.
    sparse : bool
        Whether the source file used ARFF's sparse ``{index value}`` rows, so that an
        export writes the same form back.
    """

    schema: Schema
    values: np.ndarray
    weights: np.ndarray | None = None
    groups: np.ndarray | None = None
    meta: list[dict[str, Any]] | None = None
    sparse: bool = False
    name: str | None = field(default=None, compare=False)

    def __post_init__(self) -> None:
        self.values = np.asarray(self.values, dtype=np.float64)
        if self.values.ndim != 2 or self.values.shape[1] != self.schema.n_attributes:
            raise ValueError(
                f"values must have shape (n_instances, {self.schema.n_attributes}), "
                f"got {self.values.shape}"
            )

    @property
    def n_instances(self) -> int:
        return int(self.values.shape[0])

    @property
    def n_features(self) -> int:
        return len(self.schema.feature_indices)

    @property
    def n_targets(self) -> int:
        return len(self.schema.target_indices)

    @property
    def X(self) -> np.ndarray:  # noqa: N802 (scikit-learn's name)
        """Feature matrix, shape (n_instances, n_features), float64."""
        return self.values[:, list(self.schema.feature_indices)]

    @property
    def Y(self) -> np.ndarray:  # noqa: N802 (scikit-learn's name)
        """Target matrix of codes, shape (n_instances, n_targets), float64 (NaN missing)."""
        return self.values[:, list(self.schema.target_indices)]

    def with_targets(self, target_indices: Sequence[int]) -> Dataset:
        """The same data with other attributes as targets."""
        return replace(self, schema=self.schema.with_targets(target_indices))

    def subset(self, rows: np.ndarray) -> Dataset:
        """The instances at ``rows`` (an index or boolean array), schema unchanged."""
        return replace(
            self,
            values=self.values[rows],
            weights=None if self.weights is None else self.weights[rows],
            groups=None if self.groups is None else self.groups[rows],
            meta=None
            if self.meta is None
            else [self.meta[i] for i in np.arange(self.n_instances)[rows]],
        )

    def equals(self, other: Dataset) -> bool:
        """Same schema, same values (NaN equal to NaN), same weights."""
        if self.schema != other.schema or self.values.shape != other.values.shape:
            return False
        if not np.array_equal(self.values, other.values, equal_nan=True):
            return False
        mine = np.ones(self.n_instances) if self.weights is None else self.weights
        theirs = np.ones(other.n_instances) if other.weights is None else other.weights
        return bool(np.array_equal(mine, theirs))


@dataclass(frozen=True)
class InstanceBlock:
    """Consecutive instances of a data set, as readers and the store hand them on.

    Parameters
    ----------
    values : ndarray of shape (n_instances, n_attributes), float64
        Encoded as in :class:`Dataset`.
    weights : ndarray of shape (n_instances,) or None
        Instance weights; ``None`` means all 1.
    groups : ndarray of shape (n_instances,) or None
        Recording/session ids, as in :class:`Dataset`.
    meta : list of dict or None
        Per-instance provenance, as in :class:`Dataset`.
    lines : ndarray of shape (n_instances,) or None
        The 1-based line of the file each instance was read from, for messages.
    """

    values: np.ndarray
    weights: np.ndarray | None = None
    groups: np.ndarray | None = None
    meta: list[dict[str, Any]] | None = None
    lines: np.ndarray | None = None

    @property
    def n_instances(self) -> int:
        return int(self.values.shape[0])


def dataset_blocks(dataset: Dataset, rows: int) -> Iterator[InstanceBlock]:
    """The instances of ``dataset`` in blocks of at most ``rows``."""
    for start in range(0, dataset.n_instances, rows):
        part = slice(start, start + rows)
        yield InstanceBlock(
            dataset.values[part],
            weights=None if dataset.weights is None else dataset.weights[part],
            groups=None if dataset.groups is None else dataset.groups[part],
            meta=None if dataset.meta is None else dataset.meta[part],
        )


def join_blocks(schema: Schema, blocks: Iterable[InstanceBlock], *, sparse: bool) -> Dataset:
    """One data set of ``blocks`` in order (weights, groups and meta kept where any has them)."""
    parts = list(blocks)
    n = sum(part.n_instances for part in parts)
    values = np.empty((n, schema.n_attributes))
    weights = np.ones(n) if any(part.weights is not None for part in parts) else None
    groups = (
        np.full(n, None, dtype=object) if any(part.groups is not None for part in parts) else None
    )
    meta: list[dict[str, Any]] | None = None
    if any(part.meta is not None for part in parts):
        meta = [{} for _ in range(n)]
    start = 0
    for part in parts:
        stop = start + part.n_instances
        values[start:stop] = part.values
        if weights is not None and part.weights is not None:
            weights[start:stop] = part.weights
        if groups is not None and part.groups is not None:
            groups[start:stop] = part.groups
        if meta is not None and part.meta is not None:
            meta[start:stop] = part.meta
        start = stop
    return Dataset(schema, values, weights=weights, groups=groups, meta=meta, sparse=sparse)


def meka_target_count(relation: str) -> int | None:
    """The ``-C N`` option of a MEKA relation name, ``None`` if it has none.

    ``'Music: -C 6'`` gives 6 (the first six attributes are targets); ``-C -2`` gives
    -2 (the last two).

    Raises
    ------
    ConfigurationError
        The option is there but not followed by a whole number (``-C abc``): a file
        meant for MEKA whose targets cannot be known, rather than WEKA's last attribute.
    """
    match = _MEKA_TARGETS.search(relation.partition(":")[2] if ":" in relation else "")
    if match is None:
        return None
    count = match.group(1) or ""
    if not _COUNT.fullmatch(count):
        shown = f"'{count[:40]}'" if count else "nothing"
        raise ConfigurationError(
            f"MEKA's -C option in the @relation must be a number of targets (-C 2: the first "
            f"two attributes, -C -2: the last two), not {shown}"
        )
    return int(count)


def resolve_targets(
    spec: int | Sequence[str] | None,
    attribute_names: Sequence[str],
    *,
    relation: str = "",
) -> tuple[int, ...]:
    """Positions of the target attributes.

    Parameters
    ----------
    spec : int, sequence of str, or None
        ``N > 0``: the first N attributes; ``N < 0``: the last ``|N|``; names: those
        attributes; ``None``: MEKA's ``-C`` in ``relation`` if present, otherwise the
        last attribute (WEKA's convention).
    attribute_names : sequence of str
        All attribute names in order.
    relation : str
        The relation name, consulted when ``spec`` is ``None``.

    Returns
    -------
    tuple of int
        Ascending positions.
    """
    n = len(attribute_names)
    if spec is None:
        spec = meka_target_count(relation)
        if spec is None:
            return (n - 1,) if n else ()
    if isinstance(spec, int):
        if spec == 0 or abs(spec) >= n:
            raise ConfigurationError(
                f"-C {spec} asks for {abs(spec)} target(s), but there are only {n} "
                "attributes and at least one must remain a feature"
            )
        return tuple(range(spec)) if spec > 0 else tuple(range(n + spec, n))
    positions = []
    for name in spec:
        if name not in attribute_names:
            raise ConfigurationError(
                f"no attribute named '{name}' to use as a target "
                f"(attributes: {shortlist(attribute_names)})"
            )
        positions.append(list(attribute_names).index(name))
    if len(set(positions)) != len(positions):
        raise ConfigurationError("a target is named more than once")
    if len(positions) >= n:
        raise ConfigurationError("every attribute is a target; at least one must be a feature")
    return tuple(sorted(positions))


def shortlist(items: Sequence[Any], limit: int = 8) -> str:
    """The names of ``items`` (attributes, or names themselves) for a message: the first
    ``limit``, and how many there are in all when there are more."""
    names = [getattr(item, "name", item) for item in items]
    shown = ", ".join(str(n) for n in names[:limit])
    return shown + (f", ... ({len(names)} in all)" if len(names) > limit else "")
