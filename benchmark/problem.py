"""The engine's view of a data set: a feature matrix, integer targets, and their shapes."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Literal

import numpy as np

from benchmark.dataset import Dataset, Schema
from benchmark.errors import ConfigurationError
from benchmark.sequence import SequenceLayout, find_sequence


@dataclass(frozen=True, eq=False)
class Problem:
    """What the engine cross-validates.

    Parameters
    ----------
    X : ndarray of shape (n_instances, n_features), float64
        Features; nominal ones as label codes; NaN for missing values.
    Y : ndarray of shape (n_instances, n_targets), int64
        Target label codes ``0..n_classes[t]-1`` (no missing values).
    n_classes : tuple of int
        Number of declared labels per target.
    target_names : tuple of str
        Name per target.
    nominal_features : mapping of int to int
        Nominal feature column index to its number of declared labels.
    groups : ndarray of shape (n_instances,) or None
        Recording/session id per instance, for group-aware folds.
    sequence : SequenceLayout or None
        Where the columns of a sequence data set's windows lie (:mod:`benchmark.sequence`);
        ``None`` for flat features.
    """

    X: np.ndarray
    Y: np.ndarray
    n_classes: tuple[int, ...]
    target_names: tuple[str, ...]
    nominal_features: Mapping[int, int] = field(default_factory=dict)
    groups: np.ndarray | None = None
    sequence: SequenceLayout | None = None

    def __post_init__(self) -> None:
        X = np.asarray(self.X, dtype=np.float64)
        Y = np.asarray(self.Y)
        if Y.ndim == 1:
            Y = Y[:, None]
        if X.ndim != 2 or Y.ndim != 2 or X.shape[0] != Y.shape[0]:
            raise ConfigurationError(
                f"X must be (n_instances, n_features) and Y (n_instances, n_targets); "
                f"got {X.shape} and {Y.shape}"
            )
        if not np.all(np.isfinite(Y)) or not np.array_equal(Y, np.round(Y)):
            raise ConfigurationError("target codes must be whole numbers without missing values")
        Y = Y.astype(np.int64)
        if len(self.n_classes) != Y.shape[1] or len(self.target_names) != Y.shape[1]:
            raise ConfigurationError(
                f"{Y.shape[1]} target column(s) but {len(self.n_classes)} class counts and "
                f"{len(self.target_names)} target names"
            )
        if self.sequence is not None and (
            self.sequence.stop > X.shape[1]
            or any(self.sequence.start <= c < self.sequence.stop for c in self.nominal_features)
        ):
            raise ConfigurationError(
                f"a sequence of {self.sequence.describe()} from column {self.sequence.start} "
                f"does not fit {X.shape[1]} numeric feature columns"
            )
        for t, (name, k) in enumerate(zip(self.target_names, self.n_classes, strict=True)):
            if Y.shape[0] and (Y[:, t].min() < 0 or Y[:, t].max() >= k):
                raise ConfigurationError(f"codes of target '{name}' must lie in 0..{k - 1}")
        object.__setattr__(self, "X", X)
        object.__setattr__(self, "Y", Y)
        object.__setattr__(self, "n_classes", tuple(int(k) for k in self.n_classes))
        object.__setattr__(self, "target_names", tuple(self.target_names))
        object.__setattr__(self, "nominal_features", dict(self.nominal_features))

    @property
    def kind(self) -> Literal["multiclass", "multitarget"]:
        """``"multiclass"`` with one target, ``"multitarget"`` with several."""
        return "multiclass" if self.Y.shape[1] == 1 else "multitarget"

    @property
    def n_instances(self) -> int:
        return int(self.X.shape[0])

    @property
    def n_features(self) -> int:
        return int(self.X.shape[1])

    @property
    def n_targets(self) -> int:
        return int(self.Y.shape[1])


def usable_feature_columns(schema: Schema) -> list[int]:
    """Positions, among the schema's features, of those a classifier can use.

    String attributes are left out: their codes index a per-file string table and carry
    no order or meaning a classifier could learn.  Dates count as numeric (seconds).
    """
    return [i for i, a in enumerate(schema.features) if a.kind != "string"]


def feature_matrix(schema: Schema, X: np.ndarray) -> tuple[np.ndarray, dict[int, int]]:
    """The usable columns of a data set's feature matrix, and which of them are nominal.

    Parameters
    ----------
    schema : Schema
        The data set's schema.
    X : ndarray of shape (n_instances, n_schema_features)
        Features in schema order (:attr:`Dataset.X`).

    Returns
    -------
    X : ndarray of shape (n_instances, n_usable_features)
    nominal_features : dict of int to int
        Column of the returned matrix to its number of declared labels.
    """
    columns = usable_feature_columns(schema)
    features = schema.features
    nominal = {
        position: len(features[column].values)
        for position, column in enumerate(columns)
        if features[column].kind == "nominal"
    }
    return np.asarray(X, dtype=np.float64)[:, columns], nominal


def problem_from_dataset(dataset: Dataset) -> tuple[Problem, list[str]]:
    """Turn a data set with nominal targets into a :class:`Problem`.

    Instances whose target is missing are left out (WEKA does the same when it
    evaluates); string attributes are not used as features; instance weights are not
    used.  Each such adjustment adds a line to the returned warnings.

    Raises
    ------
    ConfigurationError
        A target that is not nominal, no usable feature, or no instance with all targets.
    """
    schema = dataset.schema
    if not schema.target_indices:
        raise ConfigurationError("the data set has no target attribute")
    for target in schema.targets:
        if target.kind != "nominal":
            raise ConfigurationError(
                f"target '{target.name}' is a {target.kind} attribute; classifiers need a "
                "nominal target"
            )
    notes: list[str] = []
    unused = [a.name for a in schema.features if a.kind == "string"]
    if unused:
        notes.append(f"string attribute(s) not used as features: {', '.join(unused)}")
    X, nominal = feature_matrix(schema, dataset.X)
    sequence, note = sequence_layout(schema)
    if note is not None:
        notes.append(note)
    if X.shape[1] == 0:
        raise ConfigurationError(
            "the data set has no numeric, nominal or date feature to learn from"
        )
    Y = dataset.Y
    complete = ~np.isnan(Y).any(axis=1)
    if not complete.all():
        notes.append(f"{int((~complete).sum())} instance(s) with a missing target value left out")
    if dataset.weights is not None and not np.all(dataset.weights == 1):
        notes.append("instance weights are not used: every instance counts once")
    problem = Problem(
        X=X[complete],
        Y=Y[complete].astype(np.int64),
        n_classes=tuple(len(a.values) for a in schema.targets),
        target_names=schema.target_names,
        nominal_features=nominal,
        groups=None if dataset.groups is None else np.asarray(dataset.groups)[complete],
        sequence=sequence,
    )
    return problem, notes


def sequence_layout(schema: Schema) -> tuple[SequenceLayout | None, str | None]:
    """The sequence block among the usable feature columns (:func:`feature_matrix`'s).

    Returns
    -------
    layout : SequenceLayout or None
        ``None`` for flat features.
    note : str or None
        Why attributes named like a sequence were read as flat features.
    """
    features = schema.features
    columns = usable_feature_columns(schema)
    layout, note = find_sequence([features[c].name for c in columns])
    if layout is None:
        return None, note
    kinds = {features[c].kind for c in columns[layout.start : layout.stop]}
    if kinds != {"numeric"}:
        return None, (
            "attributes named like a sequence (CHANNEL[T]) are not all numeric: read as flat"
        )
    return layout, None


def restrict_targets(dataset: Dataset, targets: Sequence[str] | None = None) -> Dataset:
    """The data set with only the chosen targets, ready for :func:`problem_from_dataset`.

    The other declared targets are dropped rather than turned into features (WEKA's
    Experimenter removes them the same way), and so are string attributes, so that a
    model's schema lists exactly the features it uses.

    Parameters
    ----------
    dataset : Dataset
    targets : sequence of str, optional
        Attribute names; the data set's own targets by default.
    """
    schema = dataset.schema
    chosen = [schema.index(n) for n in targets] if targets else list(schema.target_indices)
    keep = [
        i
        for i, attribute in enumerate(schema.attributes)
        if i in chosen or (i not in schema.target_indices and attribute.kind != "string")
    ]
    restricted = Schema(
        relation=schema.relation,
        attributes=tuple(schema.attributes[i] for i in keep),
        target_indices=tuple(keep.index(i) for i in sorted(chosen)),
    )
    return replace(
        dataset,
        schema=restricted,
        values=dataset.values[:, np.asarray(keep, dtype=np.intp)],
    )
