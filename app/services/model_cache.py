"""The one cache of loaded models, shared by the service's predictions and live sessions, and
its one freshness rule.

Loading a model checks and rebuilds its artifact (or its ONNX twin), which costs far more
than a prediction; so loaded models are kept, the least recently used dropped first.  The
freshness rule: a loaded model answers for a reference only while the reference names that
version now, as the store says it with one indexed query
(:func:`app.store.models.model_version`: the id, the artifact's sha256, ``NAME@VERSION``
and the sha256 of its ONNX twin).  A model deleted or renamed by another process, a new
version trained under its name, an alias moved (``NAME@champion``) or a twin made by a job
is never served stale.

How old that answer may be is the caller's choice (``max_age``): the service asks on every
prediction (0 s); a live session between two blocks asks at most once a second, and
sessions on one reference share the answer.
"""

from __future__ import annotations

# Imports inside functions: start-up time: loading a model imports scikit-learn, which the
# service loads in its warm-up thread, not before it answers its first request.
import threading
import time
from collections import OrderedDict
from collections.abc import Callable
from typing import TYPE_CHECKING

from touchbench.app.schemas.references import parse_model_ref
from touchbench.app.store.database import Store
from touchbench.app.store.model_refs import ModelVersion, model_version
from touchbench.app.store.models import ModelInfo

if TYPE_CHECKING:
    from touchbench.app.schemas.models import Engine
    from touchbench.benchmark.model import Predictor


#: A stored model and what runs it (the model itself or its twin).
Loaded = tuple[ModelInfo, "Predictor"]
#: References remembered per cached model (clients choose them: the memory stays bounded).
REFS_PER_MODEL = 64


class ModelCache:
    """Loaded models by (id, sha256, ``NAME@VERSION``, twin's sha256) and engine;
    thread-safe.

    Parameters
    ----------
    size : int
        Model versions kept loaded (each with the engines asked for).
    clock : callable
        Seconds, monotonic (a test's own clock).
    """

    def __init__(self, size: int, *, clock: Callable[[], float] = time.monotonic) -> None:
        self.size = size
        self._clock = clock
        self._models: OrderedDict[ModelVersion, dict[str, tuple[ModelInfo, Predictor]]] = (
            OrderedDict()
        )
        # reference -> the version it named last, and when the store said so
        self._refs: dict[str, tuple[ModelVersion, float]] = {}
        self._lock = threading.Lock()

    def version(self, store: Store, ref: str | int, *, max_age: float = 0.0) -> ModelVersion:
        """The version ``ref`` names now: asked of the store, unless it answered for ``ref``
        less than ``max_age`` seconds ago.

        Raises
        ------
        NotFoundError
            ``ref`` names no model now (deleted, an alias removed).
        """
        text = str(ref)
        if max_age > 0:
            with self._lock:
                known = self._refs.get(text)
            if known is not None and self._clock() - known[1] < max_age:
                return known[0]
        key = model_version(store, text)
        with self._lock:
            if len(self._refs) >= REFS_PER_MODEL * self.size and text not in self._refs:
                self._refs.clear()
            self._refs[text] = (key, self._clock())
        return key

    def get(
        self, store: Store, ref: str | int, engine: Engine = "auto", *, max_age: float = 0.0
    ) -> tuple[ModelInfo, Predictor]:
        """The version ``ref`` names now (:meth:`version`), run by ``engine`` (the model, or
        its ONNX twin: see :func:`app.services.loading.load_predictor`), loaded once."""
        key = self.version(store, ref, max_age=max_age)
        with self._lock:
            cached = self._models.get(key, {}).get(engine)
            if cached is not None:
                self._models.move_to_end(key)
                return cached
        from touchbench.app.services.loading import load_predictor  # start-up time: see above

        info, model = load_predictor(store, key.id, engine)
        with self._lock:
            self._models.setdefault(key, {})[engine] = (info, model)
            self._models.move_to_end(key)
            while len(self._models) > self.size:
                self._models.popitem(last=False)
        return info, model

    def known(self, ref: str) -> int | None:
        """The id of the version ``ref`` named when last asked, or of a loaded model it
        names (its id, ``NAME``, ``NAME@VERSION``), without asking the store; None if
        neither."""
        with self._lock:
            named = self._refs.get(ref)
            if named is not None:
                return named[0].id
            for key in self._models:
                if ref in (key.label, parse_model_ref(key.label).name, str(key.id)):
                    return key.id
        return None

    def forget(self, model_id: int) -> None:
        """Drop every loaded engine of the model ``model_id`` and what references named it."""
        with self._lock:
            for key in [key for key in self._models if key.id == model_id]:
                del self._models[key]
            for ref in [ref for ref, (key, _) in self._refs.items() if key.id == model_id]:
                del self._refs[ref]
