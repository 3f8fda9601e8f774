"""What a researcher's ``data`` is to the Python API: a pandas DataFrame, an ``(X, y)`` pair of
arrays, an ARFF or CSV file, or the name of a stored data set; and a stored data set back
as a DataFrame.

A DataFrame becomes a :class:`~benchmark.dataset.Dataset` column by column (numbers stay
numbers; text, categories and booleans become nominal attributes; an integer target is a
class label, a float one a number to predict), then its ``groups`` and ``ignore`` columns
are set aside by the same rule an imported file's are
(:func:`benchmark.io.columns.plan_columns`).  A file is imported by
:func:`app.services.datasets.import_file`, as ``touchbench import`` does.
"""

from __future__ import annotations

# Imports inside functions: start-up time: pandas loads when a DataFrame is read or made.
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from touchbench.app.errors import FieldError, NotFoundError
from touchbench.app.schemas.datasets import ImportRequest
from touchbench.app.services.datasets import add_made_dataset, dataset_schema, import_file
from touchbench.app.store.database import Store
from touchbench.benchmark.dataset import Attribute, Dataset, Schema, shortlist
from touchbench.benchmark.io.columns import ColumnChoice, ColumnError, plan_columns

if TYPE_CHECKING:
    import pandas as pd

#: What messages call a DataFrame the caller gave.
FRAME = "the DataFrame"
#: The target column of an ``(X, y)`` pair, and the prefix of its features' names.
PAIR_TARGET, PAIR_FEATURE = "y", "x"


def stored_data(
    store: Store,
    data: Any,
    *,
    target: str | None,
    groups: str | None = None,
    ignore: Sequence[str] = (),
    name: str | None = None,
) -> tuple[str, bool]:
    """Store ``data`` (unless it is a stored name): its data set's name, and whether this
    call created it (rather than found it stored).

    Parameters
    ----------
    store : Store
    data : DataFrame, (X, y), str or Path
        A DataFrame (``target``, ``groups`` and ``ignore`` name its columns); arrays ``X``
        of shape (n_instances, n_features) and ``y`` of shape (n_instances,); a path to an
        ARFF or CSV file; the name of a data set in ``store``.
    target : str or None
        The column to predict; ``None`` for a file's own (MEKA's ``-C``, else the last).
    groups, ignore
        The column that names each instance's group, and columns left out.
    name : str, optional
        The data set's name in the store.

    Raises
    ------
    FieldError
        Naming ``target``, ``groups``, ``ignore`` or ``data``: an unknown column, a column
        of mixed types, a target with one value, data of another kind.  Nothing is stored.
    NotFoundError
        A name that is neither a file nor a stored data set.
    """
    if _is_frame(data):
        return _store_frame(store, data, target, groups, ignore, name)
    if isinstance(data, tuple) and len(data) == 2:
        if groups is not None or ignore:
            raise FieldError("groups" if groups else "ignore", "names a column of a DataFrame")
        pair = pair_frame(*data)
        return _store_frame(store, pair, target or PAIR_TARGET, None, (), name)
    if isinstance(data, str | Path):
        path = Path(data).expanduser()
        if path.is_file():
            request = ImportRequest(
                file=path,
                name=name,
                targets=None if target is None else [target],
                groups=groups,
                ignore=list(ignore),
            )
            result = import_file(store, request)
            return result.name, result.created
        if isinstance(data, Path) or any(sep in str(data) for sep in ("/", "\\", ".arff", ".csv")):
            raise NotFoundError(f"data: no file '{data}'")
        info, schema = dataset_schema(store, str(data))  # a stored data set: NotFoundError
        if groups is not None or ignore:
            raise FieldError(
                "groups" if groups else "ignore",
                f"data set '{info.name}' is stored already: its columns were chosen on import",
            )
        if target is not None:
            _known_column(target, [a.name for a in schema.attributes], "target", info.name)
        return info.name, False
    raise FieldError(
        "data",
        "must be a pandas DataFrame, an (X, y) pair of arrays, a path to an ARFF or CSV "
        f"file, or a stored data set's name; got {type(data).__name__}",
    )


def pair_frame(X: Any, y: Any) -> pd.DataFrame:
    """``X`` and ``y`` as one DataFrame: columns ``x0``, ``x1``... and ``y``."""
    import pandas as pd

    X = np.asarray(X)
    y = np.asarray(y)
    if X.ndim != 2 or y.ndim != 1 or X.shape[0] != y.shape[0]:
        raise FieldError(
            "data",
            f"(X, y) must be X of shape (n, n_features) and y of shape (n,); got X {X.shape} "
            f"and y {y.shape}",
        )
    frame = pd.DataFrame(X, columns=[f"{PAIR_FEATURE}{j}" for j in range(X.shape[1])])
    frame[PAIR_TARGET] = y
    return frame


def frame_dataset(
    frame: pd.DataFrame,
    target: str,
    groups: str | None = None,
    ignore: Sequence[str] = (),
    *,
    relation: str = "dataframe",
) -> Dataset:
    """A DataFrame as a data set, its ``groups`` and ``ignore`` columns set aside.

    Returns
    -------
    Dataset
        ``values`` of shape (n_rows, n_kept_columns); ``groups`` the group column's cells
        as text.

    Raises
    ------
    FieldError
        Naming the field and the column: unknown, of mixed types, a target with one value.
    """
    names = [str(column) for column in frame.columns]
    if len(set(names)) != len(names):
        twice = next(n for n in names if names.count(n) > 1)
        raise FieldError("data", f"{FRAME} has two columns named '{twice}'")
    _known_column(target, names, "target", FRAME)
    attributes, columns = [], []
    for name, column in zip(names, frame.columns, strict=True):
        attribute, values = _column(name, frame[column], is_target=name == target)
        attributes.append(attribute)
        columns.append(values)
    values = np.column_stack(columns) if columns else np.empty((len(frame), 0))
    position = names.index(target)
    try:
        plan = plan_columns(names, [position], ColumnChoice(groups, tuple(ignore)), source=FRAME)
    except ColumnError as error:
        raise FieldError(error.field, error.message) from None
    whole = Dataset(Schema(relation, tuple(attributes), (position,)), values)
    dataset = plan.dataset(whole, source=FRAME)
    _has_two_values(dataset, target)
    return dataset


def frame_of(dataset: Dataset) -> pd.DataFrame:
    """A data set as a DataFrame: numbers as floats, nominal values as their labels
    (missing ones as None), the groups (if any) in a column ``group``."""
    import pandas as pd

    data: dict[str, Any] = {}
    for j, attribute in enumerate(dataset.schema.attributes):
        column = dataset.values[:, j]
        if attribute.kind in ("nominal", "string"):
            data[attribute.name] = pd.Categorical(
                [attribute.label(code) for code in column],
                categories=list(dict.fromkeys(attribute.values)),
            )
        else:
            data[attribute.name] = column
    frame = pd.DataFrame(data)
    if dataset.groups is not None and "group" not in frame.columns:
        frame["group"] = [str(g) for g in dataset.groups]
    return frame


def features_of(frame: pd.DataFrame, schema: Schema, *, source: str = FRAME) -> Dataset:
    """Rows to predict: the columns of ``frame`` named as ``schema``'s features, encoded as
    ``schema`` encodes them (targets, when present, kept for an accuracy).

    Raises
    ------
    FieldError
        For ``data``: a feature the frame lacks.
    """
    names = [str(c) for c in frame.columns]
    missing = [a.name for a in schema.features if a.name not in names]
    if missing:
        raise FieldError(
            "data", f"{source} lacks the model's feature column(s) {shortlist(missing)}"
        )
    attributes = [a for a in schema.attributes if a.name in names]
    values = np.column_stack([_encoded(frame[a.name], a) for a in attributes])
    targets = tuple(i for i, a in enumerate(attributes) if a in schema.targets)
    return Dataset(Schema(schema.relation, tuple(attributes), targets), values)


# ----------------------------------------------------------------------------- inside


def _is_frame(data: Any) -> bool:
    import sys

    pandas = sys.modules.get("pandas")
    return pandas is not None and isinstance(data, pandas.DataFrame)


def _store_frame(
    store: Store,
    frame: pd.DataFrame,
    target: str | None,
    groups: str | None,
    ignore: Sequence[str],
    name: str | None,
) -> tuple[str, bool]:
    if target is None:
        raise FieldError("target", "is required with a DataFrame: name the column to predict")
    dataset = frame_dataset(frame, target, groups, ignore, relation=name or "dataframe")
    info, created = add_made_dataset(store, dataset, name=name)
    return info.name, created


def _known_column(column: str, names: Sequence[str], field: str, source: str) -> None:
    if column not in names:
        raise FieldError(
            field, f"no column named '{column}' in {source} (columns: {shortlist(names)})"
        )


def _column(name: str, series: pd.Series, *, is_target: bool) -> tuple[Attribute, np.ndarray]:
    """The attribute of one column and its values as :class:`Dataset` encodes them."""
    import pandas as pd
    from pandas.api import types

    if isinstance(series.dtype, pd.CategoricalDtype):
        labels = [str(c) for c in series.cat.categories]
        codes = series.cat.codes.to_numpy().astype(float)
        codes[codes < 0] = np.nan
        return Attribute(name, "nominal", tuple(labels)), codes
    if types.is_bool_dtype(series.dtype):
        return _nominal(name, series.map(str))
    if types.is_float_dtype(series.dtype):
        values = series.to_numpy(dtype=float)
        if not np.isfinite(values[~np.isnan(values)]).all():
            raise FieldError("data", f"column '{name}' of {FRAME} holds an infinite value")
        return Attribute(name, "numeric"), values
    if types.is_integer_dtype(series.dtype):
        if is_target:  # class labels: 0, 1, 2...
            return _nominal(name, series.map(str))
        return Attribute(name, "numeric"), series.to_numpy(dtype=float)
    if types.is_object_dtype(series.dtype) or types.is_string_dtype(series.dtype):
        kinds = {type(v) for v in series if v is not None and not _is_nan(v)}
        if kinds - {str}:
            shown = ", ".join(sorted(k.__name__ for k in kinds))
            raise FieldError(
                "data",
                f"column '{name}' of {FRAME} mixes types ({shown}): give it one type "
                "(text labels or numbers)",
            )
        return _nominal(name, series)
    raise FieldError(
        "data", f"column '{name}' of {FRAME} has type {series.dtype}, which touchbench cannot use"
    )


def _nominal(name: str, series: pd.Series) -> tuple[Attribute, np.ndarray]:
    present = [v for v in series if v is not None and not _is_nan(v)]
    labels = sorted(set(map(str, present)))
    index = {label: float(i) for i, label in enumerate(labels)}
    values = np.array(
        [np.nan if v is None or _is_nan(v) else index[str(v)] for v in series], dtype=float
    )
    return Attribute(name, "nominal", tuple(labels)), values


def _encoded(series: pd.Series, attribute: Attribute) -> np.ndarray:
    """One column as ``attribute`` encodes it (labels it lacks as missing)."""
    if attribute.kind == "numeric":
        return series.to_numpy(dtype=float)
    index = {label: float(i) for i, label in enumerate(attribute.values)}
    return np.array([index.get(str(v), np.nan) for v in series], dtype=float)


def _is_nan(value: Any) -> bool:
    return isinstance(value, float) and value != value


def _has_two_values(dataset: Dataset, target: str) -> None:
    index = dataset.schema.index(target)
    column = dataset.values[:, index]
    present = np.unique(column[~np.isnan(column)])
    if present.size < 2:
        only = "none" if not present.size else dataset.schema.attributes[index].label(present[0])
        if dataset.schema.attributes[index].kind == "numeric" and present.size:
            only = f"{present[0]:g}"
        raise FieldError(
            "target",
            f"column '{target}' of {FRAME} has a single value ('{only}'): nothing to predict",
        )
