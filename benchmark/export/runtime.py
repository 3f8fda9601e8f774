"""A model's ONNX twin run by ONNX Runtime, as predictions use a trained model."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.export.graph import INPUT, VALUE, output_names
from touchbench.benchmark.extras import require
from touchbench.benchmark.problem import feature_matrix


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
