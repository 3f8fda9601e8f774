"""The check of an ONNX graph against the model it came from."""

from __future__ import annotations

import numpy as np

from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.export.runtime import OnnxModel
from touchbench.benchmark.model import TrainedModel

#: Largest difference of a probability from the model's own allowed in :func:`check_twin`.
TOLERANCE = 1e-5

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
