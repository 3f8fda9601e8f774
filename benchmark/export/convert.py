"""Converters of a fitted single-target pipeline to an ONNX graph.

The conversion is scikit-learn's ``skl2onnx`` for the pipeline and its estimators,
``onnxmltools`` for XGBoost and LightGBM, CatBoost's own ONNX export for CatBoost; the
graph it gives is then made to read and answer as :mod:`benchmark.export.graph` says.
"""

from __future__ import annotations

import contextlib
import copy
import warnings
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np
from sklearn.base import BaseEstimator

from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.export.graph import INPUT, finish, route_missing_values
from touchbench.benchmark.export.supported import WRAPPED_BOOSTERS, refuse, unsupported

#: Opsets of the graphs written: ONNX Runtime 1.14 (2023) and later run them.
TARGET_OPSET = {"": 17, "ai.onnx.ml": 3}


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
    reason = unsupported(final)
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
    route_missing_values(onnx_model, unwrapped.estimator)
    probabilities = n_labels > 0 and hasattr(estimator, "predict_proba")
    finish(
        onnx_model,
        unwrapped.classes,
        n_labels,
        encoded=unwrapped.encoded,
        probabilities=probabilities,
    )
    onnx_model.graph.name = f"touchbench_{classifier}"
    return onnx_model


def _unwrap(classifier: str, final: BaseEstimator, *, regression: bool) -> Unwrapped:
    name = type(final).__name__
    classes = None if regression else np.asarray(final.classes_)
    if name == "LabelEncodedClassifier" or name in WRAPPED_BOOSTERS:
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
