"""The engine's view of a data set: a feature matrix, its targets (integer codes of nominal
targets, or numbers for a regression), and their shapes."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Literal

import numpy as np

from touchbench.benchmark.dataset import Dataset, Schema
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.sequence import SequenceLayout, find_sequence

Task = Literal["classification", "regression"]
Kind = Literal["multiclass", "multitarget", "regression"]


@dataclass(frozen=True, eq=False)
class Problem:
    """What the engine cross-validates.

    Parameters
    ----------
    X : ndarray of shape (n_instances, n_features), float64
        Features; nominal ones as label codes; NaN for missing values.
    Y : ndarray of shape (n_instances, n_targets)
        Classification: int64 target label codes ``0..n_classes[t]-1``; regression: float64
        target values.  No missing values.
    n_classes : tuple of int
        Number of declared labels per target; empty for a regression.
    target_names : tuple of str
        Name per target.
    nominal_features : mapping of int to int
        Nominal feature column index to its number of declared labels.
    groups : ndarray of shape (n_instances,) or None
        Recording/session id per instance, for group-aware folds.
    sequence : SequenceLayout or None
        Where the columns of a sequence data set's windows lie (:mod:`benchmark.sequence`);
        ``None`` for flat features.
    task : {"classification", "regression"}
        Whether the targets are nominal codes or numbers.
    coordinates : tuple of int
        Regression only: the 2 or 3 target columns that are a position's coordinates
        (scored by the mean Euclidean error too); empty otherwise.
    """

    X: np.ndarray
    Y: np.ndarray
    n_classes: tuple[int, ...]
    target_names: tuple[str, ...]
    nominal_features: Mapping[int, int] = field(default_factory=dict)
    groups: np.ndarray | None = None
    sequence: SequenceLayout | None = None
    task: Task = "classification"
    coordinates: tuple[int, ...] = ()

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
        Y = self._regression_targets(Y) if self.task == "regression" else self._class_codes(Y)
        if self.sequence is not None and (
            self.sequence.stop > X.shape[1]
            or any(self.sequence.start <= c < self.sequence.stop for c in self.nominal_features)
        ):
            raise ConfigurationError(
                f"a sequence of {self.sequence.describe()} from column {self.sequence.start} "
                f"does not fit {X.shape[1]} numeric feature columns"
            )
        object.__setattr__(self, "X", X)
        object.__setattr__(self, "Y", Y)
        object.__setattr__(self, "n_classes", tuple(int(k) for k in self.n_classes))
        object.__setattr__(self, "target_names", tuple(self.target_names))
        object.__setattr__(self, "nominal_features", dict(self.nominal_features))
        object.__setattr__(self, "coordinates", tuple(int(c) for c in self.coordinates))

    def _class_codes(self, Y: np.ndarray) -> np.ndarray:
        if not np.all(np.isfinite(Y)) or not np.array_equal(Y, np.round(Y)):
            raise ConfigurationError("target codes must be whole numbers without missing values")
        Y = Y.astype(np.int64)
        if len(self.n_classes) != Y.shape[1] or len(self.target_names) != Y.shape[1]:
            raise ConfigurationError(
                f"{Y.shape[1]} target column(s) but {len(self.n_classes)} class counts and "
                f"{len(self.target_names)} target names"
            )
        if self.coordinates:
            raise ConfigurationError("only numeric targets can be a position's coordinates")
        for t, (name, k) in enumerate(zip(self.target_names, self.n_classes, strict=True)):
            if Y.shape[0] and (Y[:, t].min() < 0 or Y[:, t].max() >= k):
                raise ConfigurationError(f"codes of target '{name}' must lie in 0..{k - 1}")
        return Y

    def _regression_targets(self, Y: np.ndarray) -> np.ndarray:
        Y = Y.astype(np.float64)
        if not np.all(np.isfinite(Y)):
            raise ConfigurationError("regression targets must be finite numbers")
        if self.n_classes or len(self.target_names) != Y.shape[1]:
            raise ConfigurationError(
                f"{Y.shape[1]} regression target column(s) take {Y.shape[1]} target names and "
                f"no class counts; got {len(self.target_names)} and {len(self.n_classes)}"
            )
        coordinates = list(self.coordinates)
        if coordinates and (
            not 2 <= len(coordinates) <= 3
            or len(set(coordinates)) != len(coordinates)
            or not all(0 <= c < Y.shape[1] for c in coordinates)
        ):
            raise ConfigurationError(
                f"a position takes 2 or 3 distinct target columns, got {coordinates}"
            )
        return Y

    @property
    def kind(self) -> Kind:
        """``"multiclass"`` with one nominal target, ``"multitarget"`` with several, and
        ``"regression"`` with numeric targets (one or several)."""
        if self.task == "regression":
            return "regression"
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


def problem_from_dataset(
    dataset: Dataset, *, position: Sequence[str] = ()
) -> tuple[Problem, list[str]]:
    """Turn a data set with nominal targets, or with numeric ones, into a :class:`Problem`.

    Nominal targets make a classification (one target: multi-class; several:
    multi-target); numeric ones a regression (one or several outputs).

    Instances whose target is missing are left out (WEKA does the same when it
    evaluates); string attributes are not used as features; instance weights are not
    used.  Each such adjustment adds a line to the returned warnings.

    Parameters
    ----------
    dataset : Dataset
    position : sequence of str
        Names of 2 or 3 numeric targets that are a position's coordinates (x, y[, z]).

    Raises
    ------
    ConfigurationError
        Targets neither all nominal nor all numeric, a position that is not 2 or 3 numeric
        targets, no usable feature.
    """
    schema = dataset.schema
    coordinates = position_columns(schema, position)
    task = target_task(schema)
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
    regression = task == "regression"
    problem = Problem(
        X=X[complete],
        Y=Y[complete] if regression else Y[complete].astype(np.int64),
        n_classes=() if regression else tuple(len(a.values) for a in schema.targets),
        target_names=schema.target_names,
        nominal_features=nominal,
        groups=None if dataset.groups is None else np.asarray(dataset.groups)[complete],
        sequence=sequence,
        task=task,
        coordinates=coordinates,
    )
    return problem, notes


def target_task(schema: Schema) -> Task:
    """``"classification"`` for nominal targets, ``"regression"`` for numeric ones.

    Raises
    ------
    ConfigurationError
        No target, a target of another kind, or nominal and numeric targets mixed.
    """
    if not schema.target_indices:
        raise ConfigurationError("the data set has no target attribute")
    kinds = {target.kind for target in schema.targets}
    for target in schema.targets:
        if target.kind not in ("nominal", "numeric"):
            raise ConfigurationError(
                f"target '{target.name}' is a {target.kind} attribute; targets must be nominal "
                "(classification) or numeric (regression)"
            )
    if kinds == {"nominal", "numeric"}:
        described = ", ".join(f"{t.name} ({t.kind})" for t in schema.targets)
        raise ConfigurationError(
            f"targets mix nominal and numeric attributes ({described}): choose nominal ones "
            "to classify or numeric ones to regress (`target` or `targets`)"
        )
    return "regression" if kinds == {"numeric"} else "classification"


def position_columns(schema: Schema, position: Sequence[str]) -> tuple[int, ...]:
    """Target columns of the coordinates named by ``position`` (2 or 3 numeric targets).

    Raises
    ------
    ConfigurationError
        Not 2 or 3 distinct names, or a name that is not a numeric target.
    """
    names = list(position)
    if not names:
        return ()
    targets = {t.name: (column, t.kind) for column, t in enumerate(schema.targets)}
    numeric = [name for name, (_, kind) in targets.items() if kind == "numeric"]
    for name in names:
        if name not in targets or targets[name][1] != "numeric":
            what = "not a target" if name not in targets else f"a {targets[name][1]} target"
            choice = ", ".join(numeric) if numeric else "none"
            raise ConfigurationError(
                f"'{name}' is {what}; a position's coordinates must be numeric targets "
                f"(numeric targets here: {choice})"
            )
    if not 2 <= len(names) <= 3 or len(set(names)) != len(names):
        raise ConfigurationError(
            f"a position takes 2 or 3 distinct numeric targets (x,y or x,y,z), got "
            f"{','.join(names)}"
        )
    return tuple(targets[name][0] for name in names)


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
