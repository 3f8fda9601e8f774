"""Matching a data set's attributes to a model's, by name: the feature matrix a model takes
from a file or a stream whose attributes come in another order, with extra ones, or with
nominal labels in another order.

Below both predicting (:mod:`app.services.models`) and checking an export against its
model (:mod:`app.services.export`), which each need the model's matrix.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from touchbench.app.store.naming import shorten
from touchbench.benchmark.dataset import Attribute, Dataset, Schema
from touchbench.benchmark.errors import DataFormatError

#: Labels quoted in one warning at most.
MAX_QUOTED = 5


def lacks(names: Sequence[str]) -> str:
    """``lacks N attribute(s) the model needs: a, b, ...``, naming the first five."""
    shown = ", ".join(shorten(name) for name in names[:5])
    more = f", ... ({len(names)} in all)" if len(names) > 5 else ""
    return f"lacks {len(names)} attribute(s) the model needs: {shown}{more}"


def align_features(
    schema: Schema,
    data: Dataset,
    *,
    source: str = "input",
    warnings: list[str] | None = None,
) -> np.ndarray:
    """The model's feature matrix from ``data``, shape (n_instances, n_model_features).

    Columns are found by name; nominal codes are translated label by label; a label the
    model never saw becomes missing (NaN), which every pipeline imputes, and is reported
    in ``warnings``.
    """
    given, wanted = data.schema.attributes, schema.features
    if len(given) == len(wanted) and all(a is b for a, b in zip(given, wanted, strict=True)):
        return data.values  # built from the model's own attributes (dataset_from_records)
    by_name = {a.name: i for i, a in enumerate(given)}
    missing = [a.name for a in schema.features if a.name not in by_name]
    if missing:
        raise DataFormatError(lacks(missing), source=source)
    X = np.empty((data.n_instances, len(schema.features)))
    for j, attribute in enumerate(schema.features):
        theirs = data.schema.attributes[by_name[attribute.name]]
        column = data.values[:, by_name[attribute.name]]
        X[:, j] = _translate(attribute, theirs, column, source, warnings)
    return X


def _translate(
    mine: Attribute,
    theirs: Attribute,
    column: np.ndarray,
    source: str,
    warnings: list[str] | None,
) -> np.ndarray:
    if mine.kind == "nominal":
        if theirs.kind != "nominal":
            raise DataFormatError(
                f"is {theirs.kind} here but nominal in the model",
                source=source,
                attribute=mine.name,
            )
        lookup = np.array(
            [mine.values.index(v) if v in mine.values else -1.0 for v in theirs.values] or [-1.0]
        )
        out = np.full(column.shape, np.nan)
        known = ~np.isnan(column)
        out[known] = lookup[column[known].astype(int)]
        unseen = out < 0
        if unseen.any():
            labels = [theirs.values[int(code)] for code in column[unseen]]
            if warnings is not None:
                warnings.append(
                    f"{source}: attribute '{mine.name}': {int(unseen.sum())} instance(s) have "
                    f"labels the model never saw ({quoted(labels)}); treated as missing values"
                )
            out[unseen] = np.nan
        return out
    if theirs.kind not in ("numeric", "date") and mine.kind == "numeric":
        raise DataFormatError(
            f"is {theirs.kind} here but numeric in the model", source=source, attribute=mine.name
        )
    return column


def quoted(labels: Sequence[str]) -> str:
    distinct = list(dict.fromkeys(labels))
    shown = ", ".join(f"'{label}'" for label in distinct[:MAX_QUOTED])
    return shown + (f", ... ({len(distinct)} in all)" if len(distinct) > MAX_QUOTED else "")
