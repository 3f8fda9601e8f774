"""ONNX export: every catalogue entry said to export does, and its graph predicts as the
model does; every other entry is refused in one line naming what exports."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from sklearn.pipeline import Pipeline

from tests.support.synthetic import nominal_dataset
from touchbench.benchmark.catalogue import SPECS
from touchbench.benchmark.dataset import Attribute, Dataset, Schema
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.estimators import build_estimator
from touchbench.benchmark.export.graph import LABEL, PROBABILITIES
from touchbench.benchmark.export.onnx import TOLERANCE, OnnxModel, export_onnx, exports_onnx
from touchbench.benchmark.model import TrainedModel, fit_model
from touchbench.benchmark.problem import problem_from_dataset

EXPORTABLE = [spec.id for spec in SPECS if exports_onnx(spec)]
REFUSED = [spec.id for spec in SPECS if not exports_onnx(spec)]

#: Parameters that make ensembles small, so that the whole catalogue fits in seconds.
SMALL = {"n_estimators": 4, "iterations": 4, "max_iter": 30, "cv": 2}


def numeric_dataset(n: int = 36) -> Dataset:
    """Three numeric features that separate three classes, one noise feature."""
    rng = np.random.default_rng(1)
    gesture = np.arange(n) % 3
    values = np.column_stack(
        [
            0.5 * rng.normal(size=n) + 2.0 * gesture,
            rng.normal(size=n) - gesture,
            rng.normal(size=n),
            gesture,
        ]
    ).astype(np.float64)
    attributes = (
        Attribute("f0", "numeric"),
        Attribute("f1", "numeric"),
        Attribute("noise", "numeric"),
        Attribute("gesture", "nominal", ("tap", "slap", "stroke")),
    )
    return Dataset(Schema("touch", attributes, (3,)), values)


def small_model(classifier: str, data: Dataset) -> TrainedModel:
    """The entry's pipeline with few trees (iterations, folds), fitted on ``data``."""
    problem, _ = problem_from_dataset(data)
    estimator = build_estimator(classifier, problem, random_state=0)
    names = estimator.get_params(deep=True)
    estimator.set_params(
        **{
            name: SMALL[name.rsplit("__", 1)[-1]]
            for name in names
            if name.rsplit("__", 1)[-1] in SMALL
        }
    )
    estimator.fit(problem.X, problem.Y[:, 0])
    return TrainedModel(classifier, {}, data.schema, estimator)


@pytest.mark.filterwarnings("ignore")
@pytest.mark.parametrize("classifier", EXPORTABLE)
def test_every_exportable_entry_exports_and_predicts_as_the_model(classifier: str) -> None:
    data = numeric_dataset()
    model = small_model(classifier, data)
    graph = export_onnx(model, data.X)  # checked inside: it raises on any difference
    twin = OnnxModel(model.schema, classifier, graph)
    codes, probabilities = model.predict_with_proba(data.X)
    twin_codes, twin_probabilities = twin.predict_with_proba(data.X)
    np.testing.assert_array_equal(twin_codes, codes)
    if probabilities is None:
        assert twin_probabilities is None
    else:
        assert twin_probabilities is not None
        np.testing.assert_allclose(twin_probabilities[0], probabilities[0], atol=TOLERANCE)


@pytest.mark.parametrize("classifier", REFUSED)
def test_every_other_entry_is_refused_in_one_line(classifier: str) -> None:
    spec = next(spec for spec in SPECS if spec.id == classifier)
    pipeline = Pipeline([("preprocess", "passthrough"), ("classifier", spec.make_estimator())])
    model = TrainedModel(classifier, {}, numeric_dataset().schema, pipeline)
    with pytest.raises(ConfigurationError) as refused:
        export_onnx(model, numeric_dataset().X)
    message = str(refused.value)
    assert "\n" not in message and f"'{classifier}'" in message
    assert "has no ONNX converter; exportable: scikit-learn's trees" in message


def test_the_weka_reimplementations_and_sequence_classifiers_do_not_export() -> None:
    assert {"j48", "nb", "ibk", "part", "minirocket", "bilstm"} <= set(REFUSED)
    assert {"rf", "xgb", "logistic", "svm-rbf", "lgbm", "catboost"} <= set(EXPORTABLE)


def test_nominal_attributes_and_missing_values_take_the_graph_path_of_the_model() -> None:
    """One-hot encoding, imputation, and a forest's own route for NaN, in one graph; the
    string attribute is not an input; metadata names the input's columns and the labels."""
    import json

    import onnx

    data = nominal_dataset()  # nominal features, a string attribute, NaN in `level`
    for classifier in ("rf", "logistic"):
        model = fit_model(data, classifier)
        graph = export_onnx(model, data.X)
        proto = onnx.load_model_from_string(graph)
        assert [i.name for i in proto.graph.input] == ["features"]
        assert [o.name for o in proto.graph.output] == [LABEL, PROBABILITIES]
        meta = {entry.key: entry.value for entry in proto.metadata_props}
        columns = json.loads(meta["touchbench.features"])
        assert [c["name"] for c in columns] == ["place", "colour", "level"]
        assert columns[0]["labels"] == ["head", "arm"]
        assert json.loads(meta["touchbench.labels"]) == ["tap", "slap", "stroke"]


def test_a_graph_that_predicts_otherwise_is_refused_naming_the_difference() -> None:
    data = numeric_dataset()
    model = fit_model(data, "logistic")
    graph = export_onnx(model, data.X)
    other = fit_model(numeric_dataset(12), "logistic")  # another fit: other probabilities
    from touchbench.benchmark.export.onnx import check_twin

    with pytest.raises(
        ConfigurationError, match=r"(another label for|differs from the model.s by)"
    ):
        check_twin(other, graph, data.X)


@pytest.mark.filterwarnings("ignore")
@pytest.mark.parametrize("regressor", ["linear", "rf", "xgb"])
def test_a_regressor_exports_its_values(regressor: str) -> None:
    rng = np.random.default_rng(0)
    a, b = rng.normal(size=30), rng.normal(size=30)
    values = np.column_stack([a, b, 2 * a - b + 0.1 * rng.normal(size=30)])
    attributes = (Attribute("a", "numeric"), Attribute("b", "numeric"), Attribute("y", "numeric"))
    data = Dataset(Schema("r", attributes, (2,)), values)
    model = fit_model(data, regressor)
    twin = OnnxModel(data.schema, regressor, export_onnx(model, data.X))
    np.testing.assert_allclose(
        twin.predict_values(data.X), model.predict_values(data.X), rtol=1e-5, atol=1e-5
    )


def test_exporting_an_svm_with_probabilities_warns_of_nothing() -> None:
    """skl2onnx reads SVC's Platt attributes, which scikit-learn deprecates: the user
    exporting a model could do nothing about that warning."""
    data = numeric_dataset()
    model = small_model("svm-rbf", data)
    with warnings.catch_warnings(record=True) as heard:
        warnings.simplefilter("always")
        export_onnx(model, data.X)
    assert [str(warning.message) for warning in heard] == []
