"""ONNX export of multi-target models: target networks (cr, cc, bcc) and label
combinations (lc, ps, nsr) give every target's label and probabilities as the model does;
other meta-classifiers are refused in one line naming what exports."""

from __future__ import annotations

import json

import numpy as np
import pytest

from tests.support.synthetic import nominal_dataset
from touchbench.benchmark.dataset import Dataset
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.estimators import build_estimator
from touchbench.benchmark.export import check
from touchbench.benchmark.export.onnx import TOLERANCE, OnnxModel, check_twin, export_onnx
from touchbench.benchmark.model import TrainedModel, fit_model
from touchbench.benchmark.problem import problem_from_dataset


def two_targets() -> Dataset:
    """Gesture (3 labels) and place (2) from a nominal feature, a string attribute that is
    not an input, and a numeric one with missing values."""
    return nominal_dataset(targets=2)


@pytest.mark.filterwarnings("ignore")
@pytest.mark.parametrize(
    "config", ["cr:xgb", "cc:rf", "cc:logistic", "bcc:logistic", "lc:rf", "nsr:svm-rbf"]
)
def test_a_multi_target_model_exports_every_targets_label_and_probabilities(
    config: str,
) -> None:
    import onnx

    data = two_targets()
    model = fit_model(data, config)
    graph = export_onnx(model, data.X)  # checked inside: it raises on any difference
    proto = onnx.load_model_from_string(graph)
    assert [o.name for o in proto.graph.output] == [
        "label_gesture",
        "probabilities_gesture",
        "label_place",
        "probabilities_place",
    ]
    meta = {entry.key: entry.value for entry in proto.metadata_props}
    targets = json.loads(meta["touchbench.targets"])
    assert [(t["name"], t["labels"], t["label"]) for t in targets] == [
        ("gesture", ["tap", "slap", "stroke"], "label_gesture"),
        ("place", ["head", "arm"], "label_place"),
    ]
    twin = OnnxModel(model.schema, config, graph)
    codes, probabilities = model.predict_with_proba(data.X)
    twin_codes, twin_probabilities = twin.predict_with_proba(data.X)
    assert codes.shape == twin_codes.shape == (len(data.X), 2)
    np.testing.assert_array_equal(twin_codes, codes)
    assert probabilities is not None and twin_probabilities is not None
    for native, mine in zip(probabilities, twin_probabilities, strict=True):
        np.testing.assert_allclose(mine, native, atol=TOLERANCE)


def test_the_chain_feeds_each_link_the_labels_the_graph_predicted() -> None:
    """The second link of a chain reads the features followed by the one-hot code of the
    label the graph predicted for the first (not, say, the features alone)."""
    import onnx

    data = two_targets()
    model = fit_model(data, "cc:logistic")
    graph = onnx.load_model_from_string(export_onnx(model, data.X))
    first, second = (int(t) for t in model.estimator.order_)
    design = next(n for n in graph.graph.node if n.output[0] == f"touchbench_t{second}_features")
    assert design.op_type == "Concat"
    assert list(design.input) == ["features", f"touchbench_t{first}_label_one_hot"]


def test_other_meta_classifiers_are_refused_in_one_line() -> None:
    data = two_targets()
    problem, _ = problem_from_dataset(data)
    for config in ("ecc:logistic", "eps:logistic", "pcc:logistic", "rakeld:logistic", "cc:j48"):
        if config.startswith("e"):  # refused by its kind: no need to fit ten chains
            estimator = build_estimator(config, problem, random_state=0)
            model = TrainedModel(config, {}, data.schema, estimator)
        else:
            model = fit_model(data, config)
        with pytest.raises(ConfigurationError) as refused:
            export_onnx(model, data.X)
        message = str(refused.value)
        assert "\n" not in message and f"'{config}'" in message
        assert "several targets: cr, cc, bcc, lc, ps and nsr over one of those" in message


def test_a_target_that_differs_is_named_with_its_instance_beyond_the_first_chunk(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A graph whose place differs on instance 10 only is refused naming that target and
    instance, counted from the first training instance although the check runs in
    chunks of 4 rows."""
    data = two_targets()
    model = fit_model(data, "lc:logistic")
    graph = export_onnx(model, data.X)
    odd = data.X[9]
    predict = model.predict_with_proba

    def one_place_flipped(X: np.ndarray) -> tuple[np.ndarray, list[np.ndarray] | None]:
        codes, probabilities = predict(X)
        rows = np.array([np.array_equal(row, odd, equal_nan=True) for row in X])
        codes[rows, 1] = 1 - codes[rows, 1]
        return codes, probabilities

    monkeypatch.setattr(model, "predict_with_proba", one_place_flipped)
    monkeypatch.setattr(check, "CHECK_ROWS", 4)
    with pytest.raises(ConfigurationError) as refused:
        check_twin(model, graph, data.X)
    message = str(refused.value)
    assert "predicts another label of 'place' for 1 training instance(s)" in message
    assert "(first: instance 10," in message and "from instance 9 on" in message
