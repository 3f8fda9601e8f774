"""A trained model as one ONNX graph: preprocessing, then the classifier or regressor.

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

A regressor has one output, ``value``: float32 of shape (n_instances, n_targets).

The conversion is scikit-learn's ``skl2onnx`` for the pipeline and its estimators,
``onnxmltools`` for XGBoost and LightGBM, CatBoost's own ONNX export for CatBoost.  Each
graph is checked against the model it came from before it is returned
(:func:`check_twin`).
"""

from __future__ import annotations

import contextlib
import copy
import json
import warnings
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Any, NoReturn

import numpy as np
from sklearn.base import BaseEstimator

from touchbench.benchmark.catalogue.spec import ClassifierSpec
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.extras import EXTRAS, require
from touchbench.benchmark.model import TrainedModel
from touchbench.benchmark.problem import feature_matrix, usable_feature_columns

#: Opsets of the graphs written: ONNX Runtime 1.14 (2023) and later run them.
TARGET_OPSET = {"": 17, "ai.onnx.ml": 3}

#: Largest difference of a probability from the model's own allowed in :func:`check_twin`.
TOLERANCE = 1e-5

#: Names of the graph's inputs and outputs.
INPUT, LABEL, PROBABILITIES, VALUE = "features", "label", "probabilities", "value"

#: What the refusal says is supported.
SUPPORTED = (
    "scikit-learn's trees, forests, bagged trees, boosting, linear models, SVMs, "
    "naive Bayes, discriminant analysis, k-NN, MLPs, XGBoost, LightGBM and CatBoost, "
    "flat features; several targets: cr, cc, bcc, lc, ps and nsr over one of those"
)


@dataclass(frozen=True)
class Unwrapped:
    """The estimator a converter knows, and how its labels map to the model's.

    Attributes
    ----------
    estimator : BaseEstimator
        What is converted (the catalogue's wrapper's inner model, or the estimator).
    classes : ndarray of shape (n_model_classes,) or None
        The model's label codes, in the order of ``estimator``'s probability columns.
    encoded : bool
        Whether ``estimator`` predicts positions in ``classes`` (a wrapper that encoded
        the labels) rather than the codes themselves.
    """

    estimator: BaseEstimator
    classes: np.ndarray | None
    encoded: bool


def exports_onnx(spec: ClassifierSpec) -> bool:
    """Whether models of this catalogue entry export to ONNX (without fitting one)."""
    if spec.min_sequence is not None or spec.tuning is not None or spec.stacking is not None:
        return False
    try:
        estimator = spec.make_estimator()
    except Exception:  # an entry that cannot even be built does not export
        return False
    return _unsupported(estimator) is None


def _unsupported(estimator: BaseEstimator, *, nested: bool = False) -> str | None:
    """Why ``estimator`` (fitted or not) has no converter that matches it, or None.

    ``nested``: inside another estimator, where the catalogue's wrappers of XGBoost,
    LightGBM and CatBoost are not unwrapped.
    """
    name = type(estimator).__name__
    inner = getattr(estimator, "estimator", None)
    if name == "LabelEncodedClassifier" and not nested:
        return None if type(inner).__name__ in ("XGBClassifier", "XGBRegressor") else name
    if name in _WRAPPED_BOOSTERS and not nested:
        # onnxmltools writes a LightGBM random forest's probabilities with the wrong width
        return name if getattr(estimator, "boosting_type", "") == "rf" else None
    module = type(estimator).__module__
    if not module.startswith(("sklearn.", "xgboost.")) or name in _NO_CONVERTER:
        return name
    reason = _differs(estimator)
    if reason is not None:
        return reason
    if name == "Pipeline":
        steps = (_unsupported(step, nested=True) for _, step in estimator.steps)
        return next(filter(None, steps), None)
    if inner is not None and not isinstance(inner, str):
        return _unsupported(inner, nested=True)
    for _, member in getattr(estimator, "estimators", None) or ():
        reason = _unsupported(member, nested=True)
        if reason is not None:
            return reason
    return None


def _differs(estimator: BaseEstimator) -> str | None:
    """Where skl2onnx converts the estimator but the graph predicts otherwise (found by
    checking every catalogue entry), what it is; else None."""
    name = type(estimator).__name__
    params = estimator.get_params(deep=False)
    inner = params.get("estimator")
    if params.get("weights") == "distance":
        # an instance at distance 0 (a training instance) weighs infinitely: scikit-learn
        # takes its label, the graph's 1/0 gives NaN
        return f"{name} weighted by distance"
    if name == "SGDClassifier" and params.get("loss") in ("log_loss", "modified_huber"):
        # scikit-learn's label is the decision function's, the graph's the probabilities'
        return f"{name} with probabilities"
    if name == "VotingClassifier" and params.get("voting") == "hard":
        return "hard VotingClassifier"
    if name == "OneVsRestClassifier" and not hasattr(inner, "predict_proba"):
        return "OneVsRestClassifier of a classifier without probabilities"
    if name == "CalibratedClassifierCV" and type(inner).__name__ == "GaussianNB":
        return "CalibratedClassifierCV of GaussianNB"
    return None


#: scikit-learn estimators skl2onnx has no converter for (or none that matches ours).
_NO_CONVERTER = frozenset(
    {
        "OutputCodeClassifier",
        "GaussianProcessClassifier",
        "GaussianProcessRegressor",
        "TransformedTargetRegressor",
        "RegressorChain",
        "KBinsDiscretizer",
        "CategoricalNB",
        "DummyRegressor",
        "NearestCentroid",
    }
)

#: The catalogue's wrappers of LightGBM and CatBoost (:mod:`benchmark.catalogue.boosters`).
_WRAPPED_BOOSTERS = frozenset({"LightGBMClassifier", "CatBoostNominalClassifier"})


def export_onnx(model: TrainedModel, X: np.ndarray) -> bytes:
    """The model as ONNX bytes, checked on ``X`` against the model itself.

    Parameters
    ----------
    model : TrainedModel
        A fitted model of one target (classifier or regressor).
    X : ndarray of shape (n_instances, n_schema_features)
        Instances to check the graph on (the training instances), in the model's schema
        order as :meth:`TrainedModel.predict` takes them.

    Returns
    -------
    bytes
        A serialised ``onnx.ModelProto``.

    Raises
    ------
    ConfigurationError
        No converter for the model (one line naming what is supported), or the graph
        disagrees with the model on ``X`` (naming the largest difference).
    MissingExtraError
        The ``onnx`` extra is not installed.
    """
    require(EXTRAS["onnx"].modules, "exporting a model to ONNX")
    onnx_model = convert(model)
    data = onnx_model.SerializeToString()
    check_twin(model, data, X)
    return data


def convert(model: TrainedModel) -> Any:
    """The model's ONNX graph (an ``onnx.ModelProto``), unchecked.

    Raises
    ------
    ConfigurationError
        No converter for the model.
    """
    if len(model.schema.target_indices) != 1:
        # a cycle at import time: the multi-target graphs are built of this module's
        from touchbench.benchmark.export.multitarget import convert_multitarget

        return convert_multitarget(model)
    n_labels = 0 if model.regression else model.n_classes[0]
    onnx_model = convert_pipeline(
        model.classifier,
        model.estimator,
        n_inputs=len(usable_feature_columns(model.schema)),
        n_labels=n_labels,
    )
    add_metadata(onnx_model, model)
    return onnx_model


def convert_pipeline(
    classifier: str,
    estimator: BaseEstimator,
    *,
    n_inputs: int,
    n_labels: int,
    codes: np.ndarray | None = None,
) -> Any:
    """The graph of a fitted ``[preprocess, final]`` pipeline, without metadata.

    Parameters
    ----------
    classifier : str
        The catalogue id (or configuration), for messages.
    estimator : Pipeline
        Fitted; its preprocessing takes ``n_inputs`` float columns.
    n_inputs : int
        Width of the input ``features``.
    n_labels : int
        Columns of ``probabilities`` (0: a regressor, whose output is ``value``).
    codes : ndarray of shape (n_final_classes,), optional
        The label code each of the final estimator's classes stands for (a multi-target
        link trained on re-coded classes); default: its classes are the codes.

    Raises
    ------
    ConfigurationError
        No converter for the estimator.
    """
    if not hasattr(estimator, "steps") or len(estimator.steps) != 2:
        refuse(classifier, type(estimator).__name__)
    preprocess, final = estimator.steps[0][1], estimator.steps[1][1]
    reason = _unsupported(final)
    if reason is not None or isinstance(preprocess, str):
        refuse(classifier, reason or type(final).__name__)
    unwrapped = _unwrap(classifier, final, regression=n_labels == 0)
    if codes is not None and unwrapped.classes is not None:
        # a link trained on classes re-coded 0 .. m - 1: what it predicts is a position
        # in ``codes`` (its own classes are those positions, all present)
        own = unwrapped.classes.astype(np.int64)
        if not np.array_equal(own, np.arange(own.size)) and not unwrapped.encoded:
            refuse(classifier, "classes other than the positions of its codes")
        unwrapped = Unwrapped(unwrapped.estimator, np.asarray(codes)[own], encoded=True)
    onnx_model = _convert_pipeline(classifier, preprocess, unwrapped, n_inputs, n_labels == 0)
    _route_missing_values(onnx_model, unwrapped.estimator)
    probabilities = n_labels > 0 and hasattr(estimator, "predict_proba")
    _finish(onnx_model, unwrapped, n_labels, probabilities=probabilities)
    onnx_model.graph.name = f"touchbench_{classifier}"
    return onnx_model


def refuse(classifier: str, what: str) -> NoReturn:
    """Refuse ``classifier`` (``what`` of it has no converter), naming what exports."""
    raise ConfigurationError(
        f"classifier '{classifier}' ({what}) has no ONNX converter; exportable: {SUPPORTED}"
    )


def _unwrap(classifier: str, final: BaseEstimator, *, regression: bool) -> Unwrapped:
    name = type(final).__name__
    classes = None if regression else np.asarray(final.classes_)
    if name == "LabelEncodedClassifier" or name in _WRAPPED_BOOSTERS:
        inner = final.estimator_ if name == "LabelEncodedClassifier" else final.model_
        if inner is None:
            refuse(classifier, "a single class in training: nothing to convert")
        return Unwrapped(inner, classes, encoded=True)
    return Unwrapped(final, classes, encoded=False)


def _listed_columns(preprocess: BaseEstimator) -> BaseEstimator:
    """A shallow copy of a fitted column transformer whose columns are lists of ints.

    The model selects its columns by int64 arrays (:func:`benchmark.preprocessing.
    make_preprocessor`: fast on one row), which skl2onnx takes for column names.
    """
    fitted = getattr(preprocess, "transformers_", None)
    if fitted is None:
        return preprocess
    listed = copy.copy(preprocess)
    listed.transformers_ = [
        (
            name,
            transformer,
            [int(c) for c in columns] if isinstance(columns, np.ndarray) else columns,
        )
        for name, transformer, columns in fitted
    ]
    return listed


def _convert_pipeline(
    classifier: str,
    preprocess: BaseEstimator,
    unwrapped: Unwrapped,
    n_inputs: int,
    regression: bool,
) -> Any:
    """skl2onnx's graph of ``[preprocess, estimator]`` with its default output names."""
    from skl2onnx import convert_sklearn
    from skl2onnx.common.data_types import FloatTensorType
    from sklearn.pipeline import Pipeline

    _register_boosters()
    estimator = unwrapped.estimator
    pipeline = Pipeline([("preprocess", _listed_columns(preprocess)), ("model", estimator)])
    options: dict[int, dict[str, Any]] = {}
    if not regression:
        # given for every classifier: skl2onnx would give a ZipMap option to those without
        # probabilities, which refuse it
        options[id(estimator)] = {"zipmap": False} if hasattr(estimator, "predict_proba") else {}
        if type(estimator).__name__ in ("SVC", "NuSVC"):
            options[id(estimator)]["raw_scores"] = False
    try:
        with _plain_missing_flags(), warnings.catch_warnings():
            # skl2onnx reads SVC's Platt attributes, which scikit-learn 1.9 deprecates:
            # the user exporting a model can do nothing about it
            warnings.filterwarnings("ignore", r"Attribute `prob[AB]_`", FutureWarning)
            return convert_sklearn(
                pipeline,
                initial_types=[(INPUT, FloatTensorType([None, n_inputs]))],
                options=options,
                target_opset=TARGET_OPSET,
            )
    except (RuntimeError, NotImplementedError, ValueError, TypeError, KeyError) as error:
        first = str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__
        raise ConfigurationError(
            f"classifier '{classifier}': the ONNX converter refused it ({first[:200]})"
        ) from None


@contextlib.contextmanager
def _plain_missing_flags() -> Iterator[None]:
    """skl2onnx 1.20 passes HistGradientBoosting's missing-value flags on as numpy
    integers, which ONNX's attribute builder refuses beside Python ones: hand it ints."""
    from skl2onnx.common import tree_ensemble

    add_node = tree_ensemble.add_node

    def plain(*args: Any, nodes_missing_value_tracks_true: Any = 0, **kwargs: Any) -> Any:
        flag = int(nodes_missing_value_tracks_true)
        return add_node(*args, nodes_missing_value_tracks_true=flag, **kwargs)

    tree_ensemble.add_node = plain
    try:
        yield
    finally:
        tree_ensemble.add_node = add_node


_registered = False


def _register_boosters() -> None:
    """Tell skl2onnx how to convert XGBoost, LightGBM and CatBoost (once per process)."""
    global _registered
    if _registered:
        return
    from catboost import CatBoostClassifier
    from lightgbm import LGBMClassifier
    from onnxmltools.convert.lightgbm.operator_converters.LightGbm import convert_lightgbm
    from onnxmltools.convert.xgboost.operator_converters.XGBoost import convert_xgboost
    from skl2onnx import update_registered_converter
    from skl2onnx.common.shape_calculator import (
        calculate_linear_classifier_output_shapes,
        calculate_linear_regressor_output_shapes,
    )
    from xgboost import XGBClassifier, XGBRegressor

    classifier_options = {"nocl": [True, False], "zipmap": [True, False, "columns"]}
    update_registered_converter(
        XGBClassifier,
        "XGBoostXGBClassifier",
        calculate_linear_classifier_output_shapes,
        convert_xgboost,
        options=classifier_options,
    )
    update_registered_converter(
        XGBRegressor,
        "XGBoostXGBRegressor",
        calculate_linear_regressor_output_shapes,
        convert_xgboost,
    )
    update_registered_converter(
        LGBMClassifier,
        "LightGbmLGBMClassifier",
        calculate_linear_classifier_output_shapes,
        convert_lightgbm,
        options=classifier_options,
    )
    update_registered_converter(
        CatBoostClassifier,
        "CatBoostCatBoostClassifier",
        calculate_linear_classifier_output_shapes,
        _convert_catboost,
        options=classifier_options,
        parser=_parse_catboost,
    )
    _registered = True


def _parse_catboost(scope: Any, model: Any, inputs: Any, custom_parsers: Any = None) -> Any:
    """A CatBoost classifier's two outputs, label and probabilities (CatBoost declares no
    scikit-learn tags, so skl2onnx's own parser takes it for a one-output transformer)."""
    from skl2onnx.common.data_types import FloatTensorType, Int64TensorType

    operator = scope.declare_local_operator("CatBoostCatBoostClassifier", model)
    operator.inputs = inputs
    operator.outputs.append(scope.declare_local_variable("label", Int64TensorType()))
    operator.outputs.append(scope.declare_local_variable("probabilities", FloatTensorType()))
    return operator.outputs


def _convert_catboost(scope: Any, operator: Any, container: Any) -> None:
    """CatBoost's own ONNX export, as one node of skl2onnx's graph (skl2onnx's recipe)."""
    from catboost.utils import convert_to_onnx_object
    from onnx.helper import get_attribute_value

    booster = operator.raw_operator
    if booster.get_cat_feature_indices():
        raise NotImplementedError("CatBoost exports no model with nominal features to ONNX")
    exported = convert_to_onnx_object(booster)
    opsets = {d.domain: d.version for d in exported.opset_import}
    node = exported.graph.node[0]
    container.add_node(
        node.op_type,
        [operator.inputs[0].full_name],
        [operator.outputs[0].full_name, operator.outputs[1].full_name],
        op_domain=node.domain,
        op_version=opsets.get(node.domain),
        **{attribute.name: get_attribute_value(attribute) for attribute in node.attribute},
    )


def _route_missing_values(onnx_model: Any, estimator: BaseEstimator) -> None:
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


def _finish(onnx_model: Any, unwrapped: Unwrapped, n_labels: int, *, probabilities: bool) -> None:
    """Rename the outputs, and map labels and probability columns to the target's
    ``n_labels`` codes (0: a regressor's ``value``)."""
    from onnx import TensorProto, helper, numpy_helper

    graph = onnx_model.graph
    outputs = [output.name for output in graph.output]
    for public in (LABEL, PROBABILITIES, VALUE):
        if public not in outputs:  # a converter's inner result of the name the output takes
            _rename(graph, public, f"touchbench_inner_{public}")
    new_outputs = []
    if n_labels == 0:
        _rename(graph, outputs[0], VALUE)
        new_outputs.append(helper.make_tensor_value_info(VALUE, TensorProto.FLOAT, [None, None]))
    else:
        assert unwrapped.classes is not None
        classes = unwrapped.classes.astype(np.int64)
        raw_label = "touchbench_raw_label"
        _rename(graph, outputs[0], raw_label)
        cast_label = "touchbench_raw_label_int64"
        graph.node.append(helper.make_node("Cast", [raw_label], [cast_label], to=TensorProto.INT64))
        # one label per instance, whatever shape the converter gave (QDA's is (1, n))
        flat = np.array([-1], dtype=np.int64)
        graph.initializer.append(numpy_helper.from_array(flat, "touchbench_flat"))
        flat_label = "touchbench_label_flat"
        graph.node.append(
            helper.make_node("Reshape", [cast_label, "touchbench_flat"], [flat_label])
        )
        if unwrapped.encoded:
            graph.initializer.append(numpy_helper.from_array(classes, "touchbench_classes"))
            graph.node.append(
                helper.make_node("Gather", ["touchbench_classes", flat_label], [LABEL])
            )
        else:
            graph.node.append(helper.make_node("Identity", [flat_label], [LABEL]))
        new_outputs.append(helper.make_tensor_value_info(LABEL, TensorProto.INT64, [None]))
        if probabilities:
            expand = np.zeros((classes.size, n_labels), dtype=np.float32)
            expand[np.arange(classes.size), classes] = 1.0
            _rename(graph, outputs[1], "touchbench_raw_probabilities")
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


def _rename(graph: Any, old: str, new: str) -> None:
    for node in graph.node:
        for i, name in enumerate(node.output):
            if name == old:
                node.output[i] = new
        for i, name in enumerate(node.input):
            if name == old:
                node.input[i] = new


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


#: Training instances checked per ONNX Runtime call in :func:`check_twin`: both sides'
#: intermediate arrays (a forest's per-tree probabilities) grow with the rows of one call.
CHECK_ROWS = 4096


def check_twin(model: TrainedModel, data: bytes, X: np.ndarray) -> None:
    """Refuse a graph whose labels differ from the model's on ``X``, or whose
    probabilities (values of a regressor) differ by more than :data:`TOLERANCE`.

    Raises
    ------
    ConfigurationError
        Naming the largest difference and where.
    """
    try:
        twin = OnnxModel(model.schema, model.classifier, data)
        for start in range(0, max(len(X), 1), CHECK_ROWS):
            _check_twin(model, twin, X[start : start + CHECK_ROWS], start)
    except ConfigurationError:
        raise
    except Exception as error:  # ONNX Runtime's own errors, said in one line
        first = (str(error).strip().splitlines() or [type(error).__name__])[0]
        raise ConfigurationError(
            f"classifier '{model.classifier}': ONNX Runtime cannot run the exported graph "
            f"({first[:200]}); not exported"
        ) from None


def _check_twin(model: TrainedModel, twin: OnnxModel, X: np.ndarray, start: int) -> None:
    """Check rows ``start ..`` of the training instances (``X`` holds them)."""
    if model.regression:
        native = model.predict_values(X)
        mine = twin.predict_values(X)
        _check_close(model, "value", native, mine, start)
        return
    codes, probabilities = model.predict_with_proba(X)
    twin_codes, twin_probabilities = twin.predict_with_proba(X)
    differ = np.flatnonzero((codes != twin_codes).any(axis=1))
    if differ.size:
        i = int(differ[0])
        t = int(np.flatnonzero(codes[i] != twin_codes[i])[0])
        of_target = f" of '{model.schema.targets[t].name}'" if codes.shape[1] > 1 else ""
        raise ConfigurationError(
            f"classifier '{model.classifier}': the ONNX graph predicts another label{of_target} "
            f"for {differ.size} training instance(s) from instance {start + 1} on (first: "
            f"instance {start + i + 1}, {codes[i, t]} vs {twin_codes[i, t]}); not exported"
        )
    if probabilities is not None:
        if twin_probabilities is None:
            raise ConfigurationError(
                f"classifier '{model.classifier}': the ONNX graph gives no probabilities"
            )
        several = len(probabilities) > 1
        for target, native, mine in zip(
            model.schema.targets, probabilities, twin_probabilities, strict=True
        ):
            what = f"probability of '{target.name}'" if several else "probability"
            _check_close(model, what, native, mine, start)


def _check_close(
    model: TrainedModel, what: str, native: np.ndarray, mine: np.ndarray, start: int
) -> None:
    """Refuse a difference over :data:`TOLERANCE`: absolute for probabilities, relative to
    the value (at least 1) for a regressor's values, which float32 holds to ~1e-7 of
    their size."""
    native = np.asarray(native, dtype=np.float64)
    difference = np.abs(native - mine)
    if what == "value":
        difference = difference / np.maximum(1.0, np.abs(native))
    if difference.size == 0 or not np.nanmax(difference) > TOLERANCE:
        return
    i, j = np.unravel_index(int(np.nanargmax(difference)), difference.shape)
    relative = " (relative)" if what == "value" else ""
    raise ConfigurationError(
        f"classifier '{model.classifier}': the ONNX graph's {what} differs from the model's "
        f"by {difference[i, j]:.3g}{relative} (instance {start + i + 1}, column {j + 1}; at "
        f"most {TOLERANCE:g} allowed); not exported"
    )


class OnnxModel:
    """A model's ONNX twin, run by ONNX Runtime, with the interface of
    :class:`TrainedModel` that predictions use (``schema``, ``regression``,
    ``predict_with_proba``, ``predict_values``).

    Parameters
    ----------
    schema : Schema
        The model's schema (its features in the order :meth:`predict_with_proba` takes).
    classifier : str
        The catalogue id, for messages.
    data : bytes
        The ONNX graph :func:`export_onnx` wrote.
    """

    def __init__(self, schema: Any, classifier: str, data: bytes) -> None:
        require(("onnxruntime",), "predicting with ONNX Runtime")
        import onnxruntime

        options = onnxruntime.SessionOptions()
        # One row at a time is the usual call: threads cost more than they save, and the
        # service and live loop run several sessions side by side.
        options.intra_op_num_threads = 1
        options.inter_op_num_threads = 1
        options.log_severity_level = 4  # errors come back as exceptions, said once by us
        self.schema = schema
        self.classifier = classifier
        self.engine = "onnx"
        self._session = onnxruntime.InferenceSession(
            data, options, providers=["CPUExecutionProvider"]
        )
        self._outputs = [output.name for output in self._session.get_outputs()]

    @property
    def regression(self) -> bool:
        """Whether it predicts numbers (its targets are numeric)."""
        return all(target.kind == "numeric" for target in self.schema.targets)

    @property
    def n_classes(self) -> tuple[int, ...]:
        return tuple(len(target.values) for target in self.schema.targets)

    def _run(self, X: np.ndarray, names: Sequence[str]) -> list[np.ndarray]:
        X = np.asarray(X, dtype=np.float64)
        expected = len(self.schema.feature_indices)
        if X.ndim != 2 or X.shape[1] != expected:
            raise ConfigurationError(
                f"the model expects {expected} feature columns, got an array of shape {X.shape}"
            )
        features = feature_matrix(self.schema, X)[0].astype(np.float32)
        return list(self._session.run(list(names), {INPUT: features}))

    def predict_with_proba(self, X: np.ndarray) -> tuple[np.ndarray, list[np.ndarray] | None]:
        """Codes of shape (n_instances, n_targets) and the probabilities (a list of one
        matrix of shape (n_instances, n_labels[t]) per target, float64) or None, as
        :meth:`TrainedModel.predict_with_proba`."""
        names = [output_names(t.name, len(self.schema.targets) > 1) for t in self.schema.targets]
        labels = [label for label, _ in names]
        if any(proba not in self._outputs for _, proba in names):
            answers = self._run(X, labels)
            return np.column_stack([a.astype(np.int64).reshape(-1) for a in answers]), None
        answers = self._run(X, labels + [proba for _, proba in names])
        codes = np.column_stack([a.astype(np.int64).reshape(-1) for a in answers[: len(labels)]])
        return codes, [a.astype(np.float64) for a in answers[len(labels) :]]

    def predict(self, X: np.ndarray) -> np.ndarray:
        """Predicted codes of shape (n_instances, n_targets)."""
        return self.predict_with_proba(X)[0]

    def predict_values(self, X: np.ndarray) -> np.ndarray:
        """A regressor's values, float64 of shape (n_instances, n_targets)."""
        [value] = self._run(X, [VALUE])
        return value.astype(np.float64).reshape(value.shape[0], -1)
