"""Training models on stored data sets and predicting new instances with them.

A model keeps the schema it was trained on; a file to predict is matched to it by
attribute name (order and extra attributes do not matter, nominal labels are matched by
text), so a model trained on a public ARFF file accepts what the extractor produces live.
Whatever had to be changed on the way (a label the model never saw) is reported as a
warning that says where.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from touchbench.app.errors import ConflictError, FieldError
from touchbench.app.schemas.models import (
    AliasDeleted,
    AliasRequest,
    ExportRequest,
    MissingPolicy,
    PredictFileRequest,
    PredictionReport,
    PredictionRow,
    TrainRequest,
)
from touchbench.app.services.alignment import align_features, lacks, quoted
from touchbench.app.services.datasets import read_data_file
from touchbench.app.services.export import export_model, refuse_unexportable
from touchbench.app.services.loading import PredictorLoader, load_model, load_predictor
from touchbench.app.store.aliases import AliasMove, delete_alias, rollback_alias, set_alias
from touchbench.app.store.database import Store
from touchbench.app.store.datasets import find_dataset, load_dataset
from touchbench.app.store.models import ModelInfo, check_model_name, get_model, save_model
from touchbench.app.store.naming import shorten
from touchbench.app.store.runs import RunInfo, get_run, load_results
from touchbench.benchmark.dataset import Attribute, Dataset, Schema
from touchbench.benchmark.errors import ConfigurationError, DataFormatError
from touchbench.benchmark.model import Predictor, dumps_model, fit_model
from touchbench.benchmark.problem import Problem, problem_from_dataset, restrict_targets
from touchbench.drivers.limits import LINE_CHARS, LineTooLongError, bounded_lines


@dataclass(frozen=True)
class Training:
    """What a :class:`TrainRequest` comes to once checked against the store: the data set
    (restricted to the targets), classifier, seed and run to train from."""

    data: Dataset
    dataset_id: int
    classifier: str
    seed: int
    run_id: int | None


def train(store: Store, request: TrainRequest) -> ModelInfo:
    """Fit a classifier on every instance of a data set (or a finished run's best classifier
    on the run's data set and targets) and store the model as the next version of its name
    (``request.name``, else ``DATASET-CLASSIFIER``).

    With ``request.onnx``, the model's ONNX twin is made too, checked on the training
    instances (:func:`app.services.export.export_model`).

    Raises as :func:`check_training` does; a twin whose graph disagrees with the model is
    refused after the model was stored (it stays, without a twin).
    """
    plan = check_training(store, request)
    model = fit_model(plan.data, plan.classifier, random_state=plan.seed)
    info = save_model(
        store,
        classifier=plan.classifier,
        params=_jsonable(model.params),
        schema=plan.data.schema.to_json(),
        targets=list(plan.data.schema.target_names),
        artifact=dumps_model(model),
        dataset_id=plan.dataset_id,
        run_id=plan.run_id,
        name=request.name,
    )
    if not request.onnx:
        return info
    try:
        export_model(store, ExportRequest(model=info.id))
    except FieldError as error:
        raise FieldError(
            "onnx", f"model '{info.label}' was stored without its ONNX twin: {error.message}"
        ) from None
    return get_model(store, info.id)


def check_training(store: Store, request: TrainRequest) -> Training:
    """Refuse at once what training would refuse after the work, before a job is queued.

    Raises
    ------
    NotFoundError
        No such data set or run.
    ConflictError
        The run has no successful classifier.
    FieldError
        An invalid name; an unknown target or one without any known value; an unknown
        classifier or one that cannot learn the targets (a multi-class classifier for
        several targets, or the reverse; a sequence classifier on flat features); an ONNX
        twin asked of a classifier without a converter.
    MissingExtraError
        An ONNX twin asked without the ``onnx`` extra.
    """
    # start-up time: the catalogue is big
    from touchbench.benchmark.estimators import check_classifier

    if request.name is not None:
        check_model_name(request.name)  # a name taken is not refused: it gets a new version
    targets: list[str] | None
    if request.run is not None:
        run, classifier = _best_of_run(store, request.run)
        run_id, dataset_id, seed = run.id, run.dataset_id, run.config.seed
        targets = run.config.targets_given
    else:
        assert request.dataset is not None and request.classifier is not None  # the request's rule
        run_id, classifier, seed = None, request.classifier, request.seed
        targets = [request.target] if request.target else None
        dataset_id = find_dataset(store, str(request.dataset)).id
    data = load_dataset(store, dataset_id)
    if request.target is not None and request.target not in {
        attribute.name for attribute in data.schema.attributes
    }:
        raise FieldError(
            "target",
            f"the data set has no attribute '{shorten(request.target)}' (targets: "
            f"{', '.join(data.schema.target_names) or 'none'})",
        )
    data = restrict_targets(data, targets)
    problem, _ = problem_from_dataset(data)
    _check_learnable(problem, "target" if targets else "dataset")
    try:
        check_classifier(classifier, problem)
    except ConfigurationError as error:
        raise FieldError("run" if request.run is not None else "classifier", str(error)) from None
    if request.onnx:
        refuse_unexportable(classifier, regression=problem.kind == "regression", field="onnx")
    return Training(data, dataset_id, classifier, seed, run_id)


def _check_learnable(problem: Problem, field: str) -> None:
    """Refuse targets without a known value, or with a single class, for ``field``."""
    names = ", ".join(f"'{name}'" for name in problem.target_names)
    if problem.n_instances == 0:
        every = "every target" if problem.n_targets > 1 else "the target"
        raise FieldError(
            field, f"no instance has a known value of {every} ({names}): nothing to train on"
        )
    if problem.kind == "regression":
        return
    for name, column in zip(problem.target_names, problem.Y.T, strict=True):
        if np.unique(column).size < 2:
            raise FieldError(field, f"target '{name}' has a single class: nothing to learn")


def _best_of_run(store: Store, run_ref: int) -> tuple[RunInfo, str]:
    """A finished run and its best classifier.

    Raises
    ------
    ConflictError
        The run has no successful classifier (yet).
    """
    from touchbench.app.services.runs import run_leaderboard  # start-up time: the engine's imports

    run = get_run(store, run_ref)
    if not load_results(store, run.id):
        raise ConflictError(f"run {run.id} has no results yet (it is {run.status})")
    board = run_leaderboard(store, run.id).board
    if board.baseline is None:
        raise ConflictError(f"run {run.id} has no successful classifier to train")
    return run, board.rows[0].classifier


def move_alias(store: Store, request: AliasRequest) -> AliasMove:
    """Point ``NAME@alias`` at the version ``request.model`` names (``promote``: the alias
    ``champion``, which live sessions and services on ``NAME@champion`` follow); the
    version it pointed at before is kept in the alias's history for :func:`roll_back`."""
    return set_alias(store, request.model, request.alias)


def roll_back(store: Store, request: AliasRequest) -> AliasMove:
    """Point ``NAME@alias`` back at the version it pointed at before its last move."""
    return rollback_alias(store, request.model, request.alias)


def remove_alias(store: Store, request: AliasRequest) -> AliasDeleted:
    """Delete ``NAME@alias`` (``alias --delete``, ``DELETE .../aliases/{alias}``): the name
    then names nothing until set again; live sessions following it keep the version they
    hold and say so once (:class:`app.services.live.ModelFollower`).  The one rule: a
    ``request.model`` that names a version (``NAME@3``) deletes the alias only while it
    points there (``ConflictError`` otherwise), as :func:`delete_alias` checks."""
    move = delete_alias(store, request.model, request.alias)
    return AliasDeleted(alias=move.alias, model=move.model.label, version=move.model.version)


@dataclass
class Predictions:
    """Predicted labels and probabilities of each instance, per target.

    Attributes
    ----------
    labels : dict of str to list of str or list of float
        Target name -> predicted label per instance (n_instances,); predicted numbers for a
        regression model.
    probabilities : dict of str to ndarray of shape (n_instances, n_labels) or None
    class_labels : dict of str to list of str
        Target name -> the labels in the column order of ``probabilities``.
    accuracy : dict of str to float
        Per target, where the file carries the true labels.
    warnings : list of str
        What was changed on the way, and where (labels the model never saw).
    mae : dict of str to float
        A regression model's mean absolute error per target, where the file carries the
        true values.
    """

    labels: Mapping[str, Sequence[str | float]]
    probabilities: dict[str, np.ndarray] | None
    class_labels: dict[str, list[str]]
    accuracy: dict[str, float]
    warnings: list[str] = field(default_factory=list)
    mae: dict[str, float] = field(default_factory=dict)

    def report(self, model: ModelInfo) -> PredictionReport:
        """The report ``predict --json`` prints and the API answers (with the problem of a
        twin that could not be loaded, when the model itself answered in its place)."""
        unusable = (
            []
            if model.twin is None or model.twin.problem is None
            else [
                f"model '{model.label}': its ONNX twin cannot be loaded ({model.twin.problem}); "
                "the model itself predicted"
            ]
        )
        return PredictionReport(
            model=model.label,
            targets=model.targets,
            predictions=[PredictionRow(**row) for row in self.to_json()],
            accuracy=self.accuracy,
            mae=self.mae,
            warnings=unusable + self.warnings,
        )

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


def predict(model: Predictor, data: Dataset, *, source: str = "input") -> Predictions:
    """Predict every instance of ``data`` whose attributes match the model's by name."""
    warnings: list[str] = []
    X = align_features(model.schema, data, source=source, warnings=warnings)
    if model.regression:
        return _predict_values(model, X, data, warnings)
    predicted, probas = model.predict_with_proba(X)
    codes = np.asarray(predicted).reshape(X.shape[0], -1)
    targets = model.schema.targets
    labels = {t.name: [t.values[int(c)] for c in codes[:, j]] for j, t in enumerate(targets)}
    probabilities: dict[str, np.ndarray] | None = None
    if probas is not None:
        probabilities = {t.name: np.asarray(p) for t, p in zip(targets, probas, strict=True)}
    accuracy = {}
    for t in targets:
        truth = _true_labels(t, data)
        if truth is None:
            continue
        known = [i for i, label in enumerate(truth) if label is not None]
        if not known:
            continue
        accuracy[t.name] = sum(labels[t.name][i] == truth[i] for i in known) / len(known)
        foreign = [str(truth[i]) for i in known if truth[i] not in t.values]
        if foreign:
            warnings.append(
                f"{source}: target '{t.name}': {len(foreign)} instance(s) carry labels the "
                f"model cannot predict ({quoted(foreign)}); they count as misses in the accuracy"
            )
    return Predictions(
        labels=labels,
        probabilities=probabilities,
        class_labels={t.name: list(t.values) for t in targets},
        accuracy=accuracy,
        warnings=warnings,
    )


def _predict_values(
    model: Predictor, X: np.ndarray, data: Dataset, warnings: list[str]
) -> Predictions:
    """A regression model's predicted numbers, and its error where ``data`` has the truth."""
    values = model.predict_values(X)
    targets = model.schema.targets
    mae = {}
    names = [a.name for a in data.schema.attributes]
    for j, target in enumerate(targets):
        if target.name not in names:
            continue
        if data.schema.attributes[names.index(target.name)].kind != "numeric":
            continue
        truth = data.values[:, names.index(target.name)]
        known = ~np.isnan(truth)
        if known.any():
            mae[target.name] = float(np.abs(values[known, j] - truth[known]).mean())
    return Predictions(
        labels={t.name: values[:, j].tolist() for j, t in enumerate(targets)},
        probabilities=None,
        class_labels={},
        accuracy={},
        warnings=warnings,
        mae=mae,
    )


def predict_file(
    store: Store, request: PredictFileRequest, *, loader: PredictorLoader | None = None
) -> PredictionReport:
    """:func:`predict_path` of the request's file with its model, run by its engine.

    Parameters
    ----------
    loader : callable, optional
        Loads the model (default: :func:`app.services.loading.load_predictor`).
    """
    info, model = (loader or load_predictor)(store, request.model, request.engine)
    return predict_path(info, model, request.file, source=request.source_name)


def predict_path(
    info: ModelInfo, model: Predictor, path: Path, *, source: str | None = None
) -> PredictionReport:
    """Predict every instance of an ARFF or CSV file (attributes matched by name), or of
    a raw recording, when the model was trained on extracted features: the recording's
    instances are then extracted with the model's own recipe (:func:`is_recording`).

    Parameters
    ----------
    source : str, optional
        What messages call the file (an upload's own name); default: its path.

    Raises
    ------
    DataFormatError, DriverError, FeatureError
        A file that is neither, or a recording its recipe cannot read.
    """
    if info.extraction is not None and is_recording(path, model.schema):
        # Imported here: only raw recordings need the extraction stack.
        from touchbench.app.services.extraction import extract_with_recipe

        extracted = extract_with_recipe(path, info.extraction)
        predictions = predict(model, extracted.dataset, source=path.name)
        predictions.warnings[:0] = extracted.notes + extracted.warnings
        return predictions.report(info)
    data = read_data_file(path, source=source)
    return predict(model, data, source=path.name).report(info)


def predicts_recordings(store: Store, ref: str | int) -> bool:
    """Whether a file posted to the model ``ref`` may be a raw recording
    (:func:`predict_path`): the model was trained on extracted features.

    Raises
    ------
    NotFoundError
    """
    return get_model(store, ref).extraction is not None


def is_recording(path: Path, schema: Schema) -> bool:
    """Whether ``path`` is a raw recording rather than a file of instances: anything but
    ARFF and CSV, or a CSV whose header names none of the model's features (a time
    series of channels)."""
    suffix = path.suffix.lower()
    if suffix == ".arff":
        return False
    if suffix != ".csv":
        return True
    try:
        with path.open(newline="", encoding="utf-8-sig") as handle:
            lines = bounded_lines(handle, limit=LINE_CHARS, source=str(path))
            header = {cell.strip() for cell in next(csv.reader(lines), [])}
    except LineTooLongError:
        return True  # no header of features: the recording's reader refuses its line
    except (OSError, UnicodeDecodeError, csv.Error):
        return False  # the data reader says what is wrong with it
    return not header & {attribute.name for attribute in schema.features}


def predict_records(
    store: Store,
    model_ref: str | int,
    records: Sequence[Mapping[str, Any]],
    *,
    missing: MissingPolicy = "refuse",
) -> PredictionReport:
    """Predict instances given as attribute -> value mappings (the API's JSON body).

    Numeric attributes take numbers, nominal ones their labels as text; ``null`` is a
    missing value, and so is a key left out when the request allows it.
    """
    info, model = load_model(store, model_ref)
    return records_report(info, model, records, missing=missing)


def records_report(
    info: ModelInfo,
    model: Predictor,
    records: Sequence[Mapping[str, Any]],
    *,
    missing: MissingPolicy = "refuse",
) -> PredictionReport:
    """The prediction report of a loaded model for JSON-like records (see
    :func:`predict_records`), with the missing values counted per attribute."""
    data = dataset_from_records(model.schema, records, missing=missing)
    report = predict(model, data, source="instances").report(info)
    counts = np.isnan(data.values).sum(axis=0)
    report.missing = {
        attribute.name: int(count)
        for attribute, count in zip(data.schema.attributes, counts, strict=True)
        if count
    }
    return report


def dataset_from_records(
    schema: Schema, records: Sequence[Mapping[str, Any]], *, missing: MissingPolicy = "refuse"
) -> Dataset:
    """A data set with ``schema``'s features (no targets) from JSON-like records.

    Numeric attributes take numbers; nominal ones take their labels as text (a label the
    model never saw is kept, so that :func:`align_features` can say so); ``null`` is a
    missing value, and so is a key left out if ``missing`` is ``"allow"``.

    Raises
    ------
    FieldError
        ``missing`` is ``"refuse"`` and an instance leaves out attributes the model
        needs: the first such instance, naming a few of them.
    DataFormatError
        A value of the wrong kind, naming the instance and attribute; records that share
        no attribute with the model.
    """
    features = schema.features
    if missing == "refuse":
        _refuse_left_out(features, records)
    given = {key for record in records for key in record}
    if given and not given & {a.name for a in features}:
        raise DataFormatError(
            f"none of the attributes given are the model's ({quoted(sorted(given))}); the "
            f"model needs {quoted([a.name for a in features])}",
            source="instances",
        )
    values = np.full((len(records), len(features)), np.nan)
    attributes = []
    for j, attribute in enumerate(features):
        name = attribute.name
        if attribute.kind == "nominal":
            labels = list(attribute.values)
            for i, record in enumerate(records):
                cell = record.get(name)
                if cell is None:
                    continue
                if isinstance(cell, bool) or not isinstance(cell, str | int):
                    raise DataFormatError(
                        f"instance {i + 1}: expects a label ({quoted(labels)}), got {cell!r}",
                        source="instances",
                        attribute=name,
                    )
                if str(cell) not in labels:
                    labels.append(str(cell))
                values[i, j] = labels.index(str(cell))
            attributes.append(Attribute(name, "nominal", values=tuple(labels)))
            continue
        for i, record in enumerate(records):
            cell = record.get(name)
            if cell is None:
                continue
            if not _is_finite_number(cell):
                raise DataFormatError(
                    f"instance {i + 1}: expects a finite number, got {cell!r}",
                    source="instances",
                    attribute=name,
                )
            values[i, j] = cell
        attributes.append(attribute)
    out_schema = Schema(relation="instances", attributes=tuple(attributes), target_indices=())
    return Dataset(schema=out_schema, values=values, name="instances")


def _refuse_left_out(features: Sequence[Attribute], records: Sequence[Mapping[str, Any]]) -> None:
    """Refuse the first record that leaves out attributes of ``features`` (the JSON twin of
    a file without some of the model's columns, which :func:`align_features` refuses)."""
    for i, record in enumerate(records):
        if all(a.name in record for a in features):
            continue
        left_out = [a.name for a in features if a.name not in record]
        if left_out:
            raise FieldError(
                f"instances.{i}",
                f"instance {i + 1} {lacks(left_out)} (give null for a value not known, or "
                'set `missing` to "allow" to read left-out attributes as missing values)',
            )


def _is_finite_number(cell: object) -> bool:
    """A JSON number that fits a float64 and is finite (booleans are not numbers)."""
    if isinstance(cell, bool) or not isinstance(cell, int | float):
        return False
    try:
        return math.isfinite(cell)
    except OverflowError:  # an integer beyond float range
        return False


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
