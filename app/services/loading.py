"""Loading a stored model to predict with, and choosing what runs it (the engine): the model's
own artifact, its bytes checked against their sha256 and loaded only in a format that cannot
run code (:mod:`benchmark.artifacts`), or its ONNX twin (:mod:`app.services.export` makes
it), whose bytes are checked the same way and which is a graph of operators, not code.

A twin that cannot be loaded is never served: ``auto`` falls back to the model itself and
says why (once in the log, and in the model's description), ``onnx`` is refused.

Below both the model service (:mod:`app.services.models`, which predicts and trains) and
the export service (:mod:`app.services.export`, which checks a twin against its model):
each needs a loaded model.
"""

from __future__ import annotations

# Imports inside functions: start-up time: numpy, scikit-learn (behind a model's artifact)
# and ONNX Runtime load with the first model loaded, not with the service's routes.
import logging
import threading
from collections.abc import Callable
from dataclasses import replace
from typing import TYPE_CHECKING

from touchbench.app.errors import AppError, FieldError
from touchbench.app.schemas.models import Engine
from touchbench.app.store.database import Store
from touchbench.app.store.exports import load_export
from touchbench.app.store.models import ModelInfo, TwinInfo, get_model, load_artifact
from touchbench.benchmark.extras import MissingExtraError, is_installed

if TYPE_CHECKING:
    from touchbench.benchmark.model import Predictor, TrainedModel

#: What ``auto`` picks when the model has an ONNX twin: ONNX Runtime answers one row sooner
#: than the model's own estimator for every entry measured (``perf/live_latency.py`` part 3:
#: scikit-learn's checks of each call are what a single row pays for).
AUTO_PREFERS_ONNX = True

#: How a stored model is loaded to predict: :func:`load_predictor`'s signature (the service
#: passes its cache of loaded models, :meth:`app.services.model_cache.ModelCache.get`).
PredictorLoader = Callable[[Store, str | int, Engine], "tuple[ModelInfo, Predictor]"]


def load_model(store: Store, ref: str | int) -> tuple[ModelInfo, TrainedModel]:
    """A stored model (an id, ``NAME``: its newest version, ``NAME@VERSION``, ``NAME@ALIAS``);
    its bytes are checked against their sha256 and loaded only as an artifact that cannot
    run code (:mod:`benchmark.artifacts`)."""
    from touchbench.benchmark.model import loads_model

    info, artifact = load_artifact(store, ref)
    return info, loads_model(artifact, sha256=info.sha256)


def load_predictor(
    store: Store, ref: str | int, engine: Engine = "auto"
) -> tuple[ModelInfo, Predictor]:
    """A stored model ready to predict with ``engine``: the model itself, or its ONNX
    twin (:class:`benchmark.export.runtime.OnnxModel`, the same interface; the model's own
    artifact is then not read).

    A twin that cannot be loaded (damaged bytes, a graph ONNX Runtime refuses) is not
    served: ``auto`` falls back to the model itself, says so once in the log and in the
    returned description (``info.twin.problem``, which the model's JSON and the prediction's
    warnings carry); ``onnx`` is refused naming the problem.

    Raises
    ------
    FieldError
        ``engine`` is ``onnx`` and the model has no twin, or one that cannot be loaded
        (for ``engine``).
    MissingExtraError
        ``engine`` is ``onnx`` and ONNX Runtime is not installed.
    """
    if engine == "native" or (
        engine == "auto" and not (AUTO_PREFERS_ONNX and is_installed("onnxruntime"))
    ):
        return load_model(store, ref)
    info = get_model(store, ref)
    if info.twin is None:
        if engine == "onnx":
            raise FieldError(
                "engine",
                f"model '{info.label}' has no ONNX twin yet; export it to ONNX first, or "
                "predict with the native engine",
            )
        return load_model(store, info.id)
    problem = _known_problem(info.twin)
    if problem is None:
        try:
            return info, _twin(info, load_export(store, info.id, info.twin.format))
        except MissingExtraError:
            raise
        except Exception as error:  # whatever the bytes made ONNX Runtime (or the digest) say
            problem = _unusable(info, error)
    if engine == "onnx":
        raise FieldError(
            "engine",
            f"model '{info.label}': its ONNX twin cannot be loaded ({problem}); export it "
            "again, or predict with the native engine",
        )
    described, model = load_model(store, info.id)
    return with_known_problem(described), model


def _twin(info: ModelInfo, graph: bytes | None) -> Predictor:
    if graph is None:  # deleted since the description was read
        raise AppError("the twin was deleted meanwhile")
    from touchbench.benchmark.dataset import Schema
    from touchbench.benchmark.export.runtime import OnnxModel

    return OnnxModel(Schema.from_json(info.schema), info.classifier, graph)


#: Why twins could not be loaded, by their sha256 (a twin is its bytes): what this process
#: learnt, said once in the log and then in descriptions (:func:`with_known_problem`).
_UNUSABLE: dict[str, str] = {}
#: Twins remembered at most (a store cannot make this process hold more).
MAX_UNUSABLE = 1000
_unusable_lock = threading.Lock()
log = logging.getLogger("touchbench.models")


def _unusable(info: ModelInfo, error: Exception) -> str:
    """Note that the twin of ``info`` cannot be loaded because of ``error``; the problem in
    one line (logged the first time)."""
    assert info.twin is not None
    problem = " ".join(str(error).split())[:300] or type(error).__name__
    with _unusable_lock:
        first = info.twin.sha256 not in _UNUSABLE
        if first and len(_UNUSABLE) < MAX_UNUSABLE:
            _UNUSABLE[info.twin.sha256] = problem
    if first:
        log.warning(
            "model %s: its ONNX twin cannot be loaded (%s); predictions with engine auto run "
            "the model itself",
            info.label,
            problem,
        )
    return problem


def with_known_problem(info: ModelInfo) -> ModelInfo:
    """``info`` with the problem this process found loading its twin, if it found one."""
    problem = None if info.twin is None else _known_problem(info.twin)
    if info.twin is None or problem is None:
        return info
    return replace(info, twin=replace(info.twin, problem=problem))


def _known_problem(twin: TwinInfo) -> str | None:
    with _unusable_lock:
        return _UNUSABLE.get(twin.sha256)
