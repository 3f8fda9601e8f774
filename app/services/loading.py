"""Loading a stored model to predict with, and choosing what runs it (the engine): the model's
own artifact, its bytes checked against their sha256 and loaded only in a format that cannot
run code (:mod:`benchmark.artifacts`), or its ONNX twin (:mod:`app.services.export` makes
it), whose bytes are checked the same way and which is a graph of operators, not code.

Below both the model service (:mod:`app.services.models`, which predicts) and the export
service (:mod:`app.services.export`, which checks a twin against its model): each needs a
loaded model, and neither needs the other to get one.
"""

from __future__ import annotations

from collections.abc import Callable

from touchbench.app.errors import FieldError
from touchbench.app.schemas.models import Engine
from touchbench.app.store.database import Store
from touchbench.app.store.exports import load_export
from touchbench.app.store.models import ModelInfo, get_model, load_artifact
from touchbench.benchmark.dataset import Schema
from touchbench.benchmark.extras import is_installed
from touchbench.benchmark.model import Predictor, TrainedModel, loads_model

#: What ``auto`` picks when the model has an ONNX twin: ONNX Runtime answers one row sooner
#: than the model's own estimator for every entry measured (``perf/live_latency.py`` part 3:
#: scikit-learn's checks of each call are what a single row pays for).
AUTO_PREFERS_ONNX = True

#: How a stored model is loaded to predict: :func:`load_predictor`'s signature (the service
#: passes its cache of loaded models, :meth:`app.services.model_cache.ModelCache.get`).
PredictorLoader = Callable[[Store, str | int, Engine], tuple[ModelInfo, Predictor]]


def load_model(store: Store, ref: str | int) -> tuple[ModelInfo, TrainedModel]:
    """A stored model (an id, ``NAME``: its newest version, ``NAME@VERSION``, ``NAME@ALIAS``);
    its bytes are checked against their sha256 and loaded only as an artifact that cannot
    run code (:mod:`benchmark.artifacts`)."""
    info, artifact = load_artifact(store, ref)
    return info, loads_model(artifact, sha256=info.sha256)


def load_predictor(
    store: Store, ref: str | int, engine: Engine = "auto"
) -> tuple[ModelInfo, Predictor]:
    """A stored model ready to predict with ``engine``: the model itself, or its ONNX
    twin (:class:`benchmark.export.onnx.OnnxModel`, the same interface; the model's own
    artifact is then not read).

    Raises
    ------
    FieldError
        ``engine`` is ``onnx`` and the model has no twin (for ``engine``).
    MissingExtraError
        ``engine`` is ``onnx`` and ONNX Runtime is not installed.
    """
    if engine == "native" or (
        engine == "auto" and not (AUTO_PREFERS_ONNX and is_installed("onnxruntime"))
    ):
        return load_model(store, ref)
    info = get_model(store, ref)
    graph = load_export(store, info.id, "onnx")
    if graph is None:
        if engine == "onnx":
            raise FieldError(
                "engine",
                f"model '{info.name}' has no ONNX twin yet; export it to ONNX first, or "
                "predict with the native engine",
            )
        return load_model(store, info.id)
    from touchbench.benchmark.export.onnx import OnnxModel  # start-up time: onnxruntime

    return info, OnnxModel(Schema.from_json(info.schema), info.classifier, graph)
