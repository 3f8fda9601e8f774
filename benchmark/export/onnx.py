"""A trained model as one ONNX graph: preprocessing, then the classifier or regressor.

The entry of the export: :func:`export_onnx` converts a model and checks the graph against
it before returning it.  The parts, each below this module:

- :mod:`~benchmark.export.supported`: what exports, and the refusal of what does not;
- :mod:`~benchmark.export.graph`: the graph's input, outputs and metadata, and the
  surgery that gives a converter's graph them;
- :mod:`~benchmark.export.convert`: the converters of a single-target pipeline;
- :mod:`~benchmark.export.multitarget`: multi-target models, built of those;
- :mod:`~benchmark.export.check`: the check of a graph against its model;
- :mod:`~benchmark.export.runtime`: :class:`OnnxModel`, a graph run by ONNX Runtime.

The names callers use (export, check, run, ask what exports) are importable from here.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from touchbench.benchmark.export.check import TOLERANCE, check_twin
from touchbench.benchmark.export.convert import convert_pipeline
from touchbench.benchmark.export.graph import add_metadata
from touchbench.benchmark.export.multitarget import convert_multitarget, exports_multitarget
from touchbench.benchmark.export.runtime import OnnxModel
from touchbench.benchmark.export.supported import exports_onnx
from touchbench.benchmark.extras import EXTRAS, require
from touchbench.benchmark.model import TrainedModel
from touchbench.benchmark.problem import usable_feature_columns

__all__ = [
    "TOLERANCE",
    "OnnxModel",
    "check_twin",
    "convert",
    "export_onnx",
    "exports_multitarget",
    "exports_onnx",
]


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
