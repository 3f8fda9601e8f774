"""The graph's interface, and the surgery that gives a converter's graph that interface.

The graph has one input, ``features``: a float32 matrix of shape (n_instances,
n_features), its columns the model's usable attributes in the order the metadata key
``touchbench.features`` lists them (nominal attributes as the index of their label in
that list, NaN for a missing value).  One flat tensor rather than one input per
attribute, because that is what a robot's C or C++ program has at hand: it fills one
``float[]`` buffer per instance and creates a single ``Ort::Value``, instead of a
tensor and a name per attribute and the bookkeeping of dozens of inputs.

Outputs of a classifier:

- ``label``: int64 of shape (n_instances,), the index of the predicted label in the
  metadata's ``touchbench.labels``;
- ``probabilities``: float32 of shape (n_instances, n_labels), columns in that order
  (absent when the classifier gives none, as a hinge-loss SVM).

A regressor has one output, ``value``: float32 of shape (n_instances, n_targets).  A model
of several targets names its outputs per target (:func:`output_names`).
"""

from __future__ import annotations

import json
from typing import Any

import numpy as np
from sklearn.base import BaseEstimator

from touchbench.benchmark.model import TrainedModel
from touchbench.benchmark.problem import usable_feature_columns

#: Names of the graph's inputs and outputs.
INPUT, LABEL, PROBABILITIES, VALUE = "features", "label", "probabilities", "value"


def add_metadata(onnx_model: Any, model: TrainedModel) -> None:
    """Write :func:`metadata` into the graph."""
    for key, value in metadata(model).items():
        entry = onnx_model.metadata_props.add()
        entry.key, entry.value = key, value


def metadata(model: TrainedModel) -> dict[str, str]:
    """The graph's metadata: the input's columns (name, kind, labels), the targets and
    their labels, the classifier and library versions (JSON values under ``touchbench.*``).

    ``touchbench.targets`` lists every target as ``{"name", "labels", "label",
    "probabilities"}``, the last two the names of its outputs (a regressor's as ``{"name",
    "value_column"}``, its column of ``value``); a model of one target also has
    ``touchbench.target`` and ``touchbench.labels``, its outputs ``label`` and
    ``probabilities``.
    """
    features = [model.schema.features[i] for i in usable_feature_columns(model.schema)]
    targets = model.schema.targets
    several = len(targets) > 1
    entries = {
        "touchbench.classifier": model.classifier,
        "touchbench.features": json.dumps(
            [
                {"name": a.name, "kind": a.kind, "labels": list(a.values)}
                if a.kind == "nominal"
                else {"name": a.name, "kind": "numeric"}
                for a in features
            ]
        ),
        "touchbench.targets": json.dumps(
            [
                {"name": target.name, "value_column": column}
                if model.regression
                else {
                    "name": target.name,
                    "labels": list(target.values),
                    "label": output_names(target.name, several)[0],
                    "probabilities": output_names(target.name, several)[1],
                }
                for column, target in enumerate(targets)
            ]
        ),
        "touchbench.versions": json.dumps(model.versions),
    }
    if not several:
        entries["touchbench.target"] = targets[0].name
        entries["touchbench.labels"] = json.dumps(
            list(targets[0].values) if not model.regression else []
        )
    return entries


def output_names(target: str, several: bool) -> tuple[str, str]:
    """A target's label and probabilities outputs: ``label`` and ``probabilities`` for a
    model of one target, ``label_<target>`` and ``probabilities_<target>`` otherwise."""
    if not several:
        return LABEL, PROBABILITIES
    return f"{LABEL}_{target}", f"{PROBABILITIES}_{target}"


def route_missing_values(onnx_model: Any, estimator: BaseEstimator) -> None:
    """Send a missing value down the branch scikit-learn's trees send it.

    A scikit-learn tree learns, per split, where NaN goes (``tree_.missing_go_to_left``:
    the side that scored best in training, or the larger side when training saw none);
    skl2onnx writes every split as "NaN is not <= threshold", so it goes right.  The tree
    ensemble's ``nodes_missing_value_tracks_true`` says "NaN takes the true (left)
    branch", node by node, and skl2onnx numbers trees and nodes as scikit-learn does.
    """
    from onnx import helper
    from sklearn.ensemble._forest import BaseForest
    from sklearn.tree import BaseDecisionTree

    if isinstance(estimator, BaseDecisionTree):
        trees = [estimator]
    elif isinstance(estimator, BaseForest):
        trees = list(estimator.estimators_)
    else:
        return  # imputed before it (bagging, boosting, one-vs-one...): it never sees NaN
    for node in onnx_model.graph.node:
        if node.op_type not in ("TreeEnsembleClassifier", "TreeEnsembleRegressor"):
            continue
        attributes = {attribute.name: attribute for attribute in node.attribute}
        tree_ids = attributes["nodes_treeids"].ints
        node_ids = attributes["nodes_nodeids"].ints
        left = [trees[t].tree_.missing_go_to_left for t in range(len(trees))]
        tracks = [int(left[t][n]) for t, n in zip(tree_ids, node_ids, strict=True)]
        if "nodes_missing_value_tracks_true" in attributes:
            node.attribute.remove(attributes["nodes_missing_value_tracks_true"])
        node.attribute.append(helper.make_attribute("nodes_missing_value_tracks_true", tracks))


def finish(
    onnx_model: Any,
    classes: np.ndarray | None,
    n_labels: int,
    *,
    encoded: bool,
    probabilities: bool,
) -> None:
    """Rename a converter's outputs to the graph's, and map labels and probability
    columns to the target's ``n_labels`` codes.

    Parameters
    ----------
    onnx_model : onnx.ModelProto
        A converter's graph: its first output the label (or a regressor's value), its
        second the probabilities.
    classes : ndarray of shape (n_model_classes,) or None
        The label codes, in the order of the converted estimator's probability columns
        (None for a regressor).
    n_labels : int
        Columns of ``probabilities`` (0: a regressor, whose output is ``value``).
    encoded : bool
        Whether the converted estimator predicts positions in ``classes`` rather than
        the codes themselves.
    probabilities : bool
        Whether the graph gives probabilities.
    """
    from onnx import TensorProto, helper, numpy_helper

    graph = onnx_model.graph
    outputs = [output.name for output in graph.output]
    for public in (LABEL, PROBABILITIES, VALUE):
        if public not in outputs:  # a converter's inner result of the name the output takes
            rename(graph, public, f"touchbench_inner_{public}")
    new_outputs = []
    if n_labels == 0:
        rename(graph, outputs[0], VALUE)
        new_outputs.append(helper.make_tensor_value_info(VALUE, TensorProto.FLOAT, [None, None]))
    else:
        assert classes is not None
        codes = classes.astype(np.int64)
        raw_label = "touchbench_raw_label"
        rename(graph, outputs[0], raw_label)
        cast_label = "touchbench_raw_label_int64"
        graph.node.append(helper.make_node("Cast", [raw_label], [cast_label], to=TensorProto.INT64))
        # one label per instance, whatever shape the converter gave (QDA's is (1, n))
        flat = np.array([-1], dtype=np.int64)
        graph.initializer.append(numpy_helper.from_array(flat, "touchbench_flat"))
        flat_label = "touchbench_label_flat"
        graph.node.append(
            helper.make_node("Reshape", [cast_label, "touchbench_flat"], [flat_label])
        )
        if encoded:
            graph.initializer.append(numpy_helper.from_array(codes, "touchbench_classes"))
            graph.node.append(
                helper.make_node("Gather", ["touchbench_classes", flat_label], [LABEL])
            )
        else:
            graph.node.append(helper.make_node("Identity", [flat_label], [LABEL]))
        new_outputs.append(helper.make_tensor_value_info(LABEL, TensorProto.INT64, [None]))
        if probabilities:
            expand = np.zeros((codes.size, n_labels), dtype=np.float32)
            expand[np.arange(codes.size), codes] = 1.0
            rename(graph, outputs[1], "touchbench_raw_probabilities")
            graph.initializer.append(numpy_helper.from_array(expand, "touchbench_columns"))
            as_float = "touchbench_raw_probabilities_f"
            graph.node.append(
                helper.make_node(
                    "Cast", ["touchbench_raw_probabilities"], [as_float], to=TensorProto.FLOAT
                )
            )
            graph.node.append(
                helper.make_node("MatMul", [as_float, "touchbench_columns"], [PROBABILITIES])
            )
            new_outputs.append(
                helper.make_tensor_value_info(PROBABILITIES, TensorProto.FLOAT, [None, n_labels])
            )
    del graph.output[:]
    graph.output.extend(new_outputs)


def rename(graph: Any, old: str, new: str) -> None:
    """Rename the value ``old`` to ``new`` wherever a node reads or writes it."""
    for node in graph.node:
        for i, name in enumerate(node.output):
            if name == old:
                node.output[i] = new
        for i, name in enumerate(node.input):
            if name == old:
                node.input[i] = new
