"""Training models on stored data sets and predicting new instances with them.

A model keeps the schema it was trained on; a file to predict is matched to it by
attribute name (order and extra attributes do not matter, nominal labels are matched by
text), so a model trained on a public ARFF file accepts what the extractor produces live.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from app.store.database import Store
from app.store.datasets import find_dataset, load_dataset
from app.store.models import ModelInfo, load_artifact, save_model
from benchmark.dataset import Attribute, Dataset, Schema
from benchmark.errors import DataFormatError
from benchmark.model import TrainedModel, dumps_model, fit_model, loads_model
from benchmark.problem import restrict_targets


def train(
    store: Store,
    dataset_ref: str,
    classifier: str,
    *,
    targets: Sequence[str] | None = None,
    name: str | None = None,
    seed: int = 0,
    run_id: int | None = None,
) -> ModelInfo:
    """Fit a classifier on every instance of a data set and store the model."""
    info = find_dataset(store, dataset_ref)
    data = restrict_targets(load_dataset(store, info.id), targets)
    model = fit_model(data, classifier, random_state=seed)
    return save_model(
        store,
        classifier=classifier,
        params=_jsonable(model.params),
        schema=data.schema.to_json(),
        targets=list(data.schema.target_names),
        artifact=dumps_model(model),
        dataset_id=info.id,
        run_id=run_id,
        name=name,
    )


def load_model(store: Store, ref: str | int) -> tuple[ModelInfo, TrainedModel]:
    """A stored model, its bytes checked against their sha256 before they are unpickled."""
    info, artifact = load_artifact(store, ref)
    return info, loads_model(artifact, sha256=info.sha256)


@dataclass
class Predictions:
    """Predicted labels and probabilities of each instance, per target.

    Attributes
    ----------
    labels : dict of str to list of str
        Target name -> predicted label per instance (n_instances,).
    probabilities : dict of str to ndarray of shape (n_instances, n_labels) or None
    class_labels : dict of str to list of str
        Target name -> the labels in the column order of ``probabilities``.
    accuracy : dict of str to float
        Per target, where the file carries the true labels.
    """

    labels: dict[str, list[str]]
    probabilities: dict[str, np.ndarray] | None
    class_labels: dict[str, list[str]]
    accuracy: dict[str, float]

    def to_json(self) -> list[dict[str, Any]]:
        n = len(next(iter(self.labels.values()))) if self.labels else 0
        rows = []
        for i in range(n):
            row: dict[str, Any] = {"instance": i + 1}
            for target, labels in self.labels.items():
                row[target] = labels[i]
            if self.probabilities is not None:
                row["probabilities"] = {
                    target: {
                        label: float(p)
                        for label, p in zip(self.class_labels[target], matrix[i], strict=True)
                    }
                    for target, matrix in self.probabilities.items()
                }
            rows.append(row)
        return rows


def predict(model: TrainedModel, data: Dataset, *, source: str = "input") -> Predictions:
    """Predict every instance of ``data`` whose attributes match the model's by name."""
    X = align_features(model.schema, data, source=source)
    codes = np.asarray(model.predict(X)).reshape(X.shape[0], -1)
    targets = model.schema.targets
    labels = {t.name: [t.values[int(c)] for c in codes[:, j]] for j, t in enumerate(targets)}
    try:
        probas = model.predict_proba(X)
        probabilities: dict[str, np.ndarray] | None = {
            t.name: np.asarray(p) for t, p in zip(targets, probas, strict=True)
        }
    except (AttributeError, NotImplementedError):
        probabilities = None
    accuracy = {}
    for t in targets:
        truth = _true_labels(t, data)
        if truth is not None:
            known = [i for i, label in enumerate(truth) if label is not None]
            if known:
                hits = sum(labels[t.name][i] == truth[i] for i in known)
                accuracy[t.name] = hits / len(known)
    return Predictions(
        labels=labels,
        probabilities=probabilities,
        class_labels={t.name: list(t.values) for t in targets},
        accuracy=accuracy,
    )


def align_features(schema: Schema, data: Dataset, *, source: str = "input") -> np.ndarray:
    """The model's feature matrix from ``data``, shape (n_instances, n_model_features).

    Columns are found by name; nominal codes are translated label by label; a label the
    model never saw becomes missing (NaN), which every pipeline imputes.
    """
    by_name = {a.name: i for i, a in enumerate(data.schema.attributes)}
    missing = [a.name for a in schema.features if a.name not in by_name]
    if missing:
        shown = ", ".join(missing[:5]) + (
            f", ... ({len(missing)} in all)" if len(missing) > 5 else ""
        )
        raise DataFormatError(
            f"lacks {len(missing)} attribute(s) the model needs: {shown}", source=source
        )
    columns = []
    for attribute in schema.features:
        theirs = data.schema.attributes[by_name[attribute.name]]
        column = data.values[:, by_name[attribute.name]]
        columns.append(_translate(attribute, theirs, column, source))
    return np.column_stack(columns) if columns else np.empty((data.n_instances, 0))


def _translate(mine: Attribute, theirs: Attribute, column: np.ndarray, source: str) -> np.ndarray:
    if mine.kind == "nominal":
        if theirs.kind != "nominal":
            raise DataFormatError(
                f"is {theirs.kind} here but nominal in the model",
                source=source,
                attribute=mine.name,
            )
        lookup = np.array(
            [mine.values.index(v) if v in mine.values else np.nan for v in theirs.values]
            or [np.nan]
        )
        out = np.full(column.shape, np.nan)
        known = ~np.isnan(column)
        out[known] = lookup[column[known].astype(int)]
        return out
    if theirs.kind not in ("numeric", "date") and mine.kind == "numeric":
        raise DataFormatError(
            f"is {theirs.kind} here but numeric in the model", source=source, attribute=mine.name
        )
    return column


def _true_labels(target: Attribute, data: Dataset) -> list[str | None] | None:
    names = [a.name for a in data.schema.attributes]
    if target.name not in names:
        return None
    theirs = data.schema.attributes[names.index(target.name)]
    if theirs.kind != "nominal":
        return None
    column = data.values[:, names.index(target.name)]
    return [theirs.label(v) for v in column]


def _jsonable(params: dict[str, Any]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in params.items():
        out[key] = (
            value if isinstance(value, str | int | float | bool | type(None)) else repr(value)
        )
    return out
