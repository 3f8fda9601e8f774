"""Live prediction: a stream of samples in, one prediction per detected touch out.

A :class:`LiveSession` runs the model's own extraction recipe (the extractor, its
options and the event detector that made its training data) through the streaming
engine, so live features are computed exactly as the training features were, and
predicts every instance as soon as its event ends.  Its methods are plain synchronous
calls, so that a CLI loop and an async WebSocket handler (in a worker thread) share it.

A session opened on a reference that can name another version later (``NAME``: the
newest version; ``NAME@champion``) follows it (:class:`ModelFollower`): between two blocks
it asks the model cache (:mod:`app.services.model_cache`, whose freshness rule asks the
store at most once per second) which version the reference names, and switches to a new
one without dropping the stream when that version extracts its features the same way
(same recipe, sample rate and channels); otherwise it keeps the model it has and says why
once.  Each prediction names the version that made it.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from touchbench.app.errors import AppError
from touchbench.app.schemas.models import Engine
from touchbench.app.schemas.references import parse_model_ref
from touchbench.app.services.loading import load_predictor
from touchbench.app.services.model_cache import ModelCache
from touchbench.app.store.database import Store
from touchbench.app.store.models import ModelInfo
from touchbench.benchmark.model import Predictor
from touchbench.features.errors import FeatureError
from touchbench.features.extractors import Instances
from touchbench.features.recipe import Recipe


@dataclass(frozen=True)
class TouchPrediction:
    """One detected touch and what the model says of it.

    Attributes
    ----------
    start, end : float
        Seconds from the start of the stream (the source's time origin).
    predictions : dict of str to (str or float, float or None)
        Per target, the predicted label (a number from a regression model) and its
        probability (None when the model gives none).
    latency_ms : float
        From the end of the event to the prediction: how long after its last sample
        the block holding it arrived, plus the time to extract and predict.
    model : str
        ``NAME@VERSION`` of the model version that made the prediction.
    """

    start: float
    end: float
    predictions: dict[str, tuple[str | float, float | None]]
    latency_ms: float
    model: str = ""

    def to_json(self) -> dict[str, Any]:
        """One line of ``live --json`` (and one WebSocket message)."""
        return {
            "start": round(self.start, 6),
            "end": round(self.end, 6),
            "predictions": {
                target: {"value": value, "probability": probability}
                for target, (value, probability) in self.predictions.items()
            },
            "latency_ms": round(self.latency_ms, 3),
            "model": self.model,
        }


#: Seconds between two checks of which version a followed reference names.
FOLLOW_SECONDS = 1.0
#: Model versions a session's own cache keeps loaded (the one held, the one switched to).
FOLLOWED_MODELS = 2


class ModelFollower:
    """Which version a model reference (``NAME@champion``) names now, by the freshness rule
    of the model cache (:class:`app.services.model_cache.ModelCache`).

    Parameters
    ----------
    store : Store
    ref : str or int
        The reference the session was opened with.
    current : ModelInfo
        The version the session holds.
    cache : ModelCache
        Where versions are loaded, and what ``ref`` named last (the service's own cache,
        shared with its predictions and other sessions; the command line's, the session's).
    engine : {"auto", "onnx", "native"}
        What runs the versions switched to.
    interval : float
        Seconds an answer of the store on what ``ref`` names stays good: a check is one
        indexed query, a change a model load.
    """

    def __init__(
        self,
        store: Store,
        ref: str | int,
        current: ModelInfo,
        *,
        cache: ModelCache,
        engine: Engine = "auto",
        interval: float = FOLLOW_SECONDS,
    ) -> None:
        self.store = store
        self.ref = ref
        self.cache = cache
        self.engine: Engine = engine
        self.interval = interval
        self.held = (current.id, current.sha256)
        self.refused: tuple[int, str] | None = None  # a version already found unfit

    def check(self) -> tuple[ModelInfo, Predictor] | str | None:
        """A version to switch to, a message when the reference names nothing now, or None
        (no change, or a version refused before)."""
        try:
            key = self.cache.version(self.store, self.ref, max_age=self.interval)
        except AppError as error:  # the version deleted, the alias removed: keep ours
            return self._once(("gone", str(self.ref)), f"{error}; the session keeps its model")
        if (key.id, key.sha256) in (self.held, self.refused):
            return None
        return self.cache.get(self.store, key.id, self.engine)

    def _once(self, key: tuple[Any, str], message: str) -> str | None:
        if self.refused == key:
            return None
        self.refused = key
        return message


def follower(
    store: Store,
    ref: str | int,
    current: ModelInfo,
    *,
    cache: ModelCache | None = None,
    engine: Engine = "auto",
    interval: float = FOLLOW_SECONDS,
) -> ModelFollower | None:
    """A :class:`ModelFollower` of ``ref`` (with a cache of its own if none is given), or
    None when it names one version for good (an id, ``NAME@VERSION``)."""
    if parse_model_ref(ref).pinned:
        return None
    return ModelFollower(
        store,
        ref,
        current,
        cache=cache or ModelCache(FOLLOWED_MODELS),
        engine=engine,
        interval=interval,
    )


class LiveSession:
    """Predictions of a model on a live stream.

    Parameters
    ----------
    model_info : ModelInfo
        The stored model's description: its ``name`` for messages, its ``extraction``
        for the recipe.
    model : Predictor
        The fitted model, or its ONNX twin.
    samplerate : float
        Of the stream, Hz; must be the training recordings'.
    n_channels : int
        Of the stream; must be the training recordings'.
    extraction : mapping, optional
        The recipe, when ``model_info`` does not carry it.
    follow : ModelFollower, optional
        Switch to the version it names when that changes (see the module's description).

    Attributes
    ----------
    events : list of dict
        What happened to the session's model since the adapter last took them
        (:meth:`take_events`): ``{"switched": "NAME@3", "from": "NAME@2"}`` or
        ``{"warning": "..."}``.

    Raises
    ------
    AppError
        A model without a recipe (built from an imported data set), or a stream whose
        sample rate or channel count is not the training recordings'.
    """

    def __init__(
        self,
        model_info: ModelInfo,
        model: Predictor,
        *,
        samplerate: float,
        n_channels: int,
        extraction: Mapping[str, Any] | None = None,
        follow: ModelFollower | None = None,
    ) -> None:
        name = model_info.label
        recipe_json = extraction if extraction is not None else model_info.extraction
        if not recipe_json:
            raise AppError(
                f"model '{name}' was trained on a data set imported from a file, not extracted "
                "from recordings, so touchbench does not know how to compute its features "
                "live; train it on a data set extracted from recordings"
            )
        recipe = Recipe.from_json(recipe_json)
        trained_rate = recipe_json.get("samplerate")
        trained_channels = recipe_json.get("n_channels")
        if trained_channels is not None and int(trained_channels) != n_channels:
            raise AppError(
                f"model '{name}' was trained on {trained_channels}-channel recordings "
                f"({recipe.extractor} features per channel), but the source has {n_channels}"
            )
        if trained_rate is not None and abs(float(trained_rate) - samplerate) > 1e-6:
            raise AppError(
                f"model '{name}' was trained on recordings at {float(trained_rate):g} Hz, "
                f"but the source runs at {samplerate:g} Hz"
            )
        try:
            # The features are named after the training recordings' channels (a CSV
            # header's), which the live source, of the same channel count, stands for.
            self.stream = recipe.open(
                samplerate=samplerate,
                n_channels=n_channels,
                channels=recipe_json.get("channels"),
            )
        except FeatureError as error:
            raise AppError(f"model '{name}': {error}") from None
        self.recipe = recipe
        self.recipe_json = dict(recipe_json)
        self.samplerate = float(samplerate)
        self.n_channels = n_channels
        self.columns = self._columns(name, model)
        self.model = model
        self.label = name
        self.origin: float | None = None
        self.warnings: list[str] = []
        self.follow = follow
        self.events: list[dict[str, str]] = []

    def _columns(self, name: str, model: Predictor) -> np.ndarray:
        """Where each feature ``model`` needs is among the stream's, shape (n_features,)."""
        position = {feature: i for i, feature in enumerate(self.stream.feature_names)}
        missing = [a.name for a in model.schema.features if a.name not in position]
        if missing:
            raise AppError(
                f"model '{name}' needs features its extractor '{self.recipe.extractor}' does "
                f"not make on {self.n_channels} channel(s): {', '.join(missing[:5])}"
            )
        return np.array([position[a.name] for a in model.schema.features], dtype=np.int64)

    def switch(self, model_info: ModelInfo, model: Predictor) -> None:
        """Predict with another model from the next touch on, keeping the stream (its
        extraction state, its time origin).

        Raises
        ------
        AppError
            The model extracts its features otherwise (recipe, sample rate, channels) or
            needs features the stream does not make.
        """
        if model_info.extraction != self.recipe_json:
            raise AppError(
                f"model '{model_info.label}' extracts its features otherwise than "
                f"'{self.label}' (recipe, sample rate or channels): the session keeps "
                f"'{self.label}'"
            )
        self.columns = self._columns(model_info.label, model)
        self.model = model
        self.label = model_info.label

    def take_events(self) -> list[dict[str, str]]:
        """The events since the last call (see the class's ``events``), oldest first."""
        events, self.events = self.events, []
        return events

    def _follow(self) -> None:
        """Switch to the version the followed reference names now, if it changed."""
        if self.follow is None:
            return
        found = self.follow.check()
        if found is None:
            return
        if isinstance(found, str):
            self.events.append({"warning": found})
            return
        info, model = found
        before = self.label
        try:
            self.switch(info, model)
        except AppError as error:
            self.follow.refused = (info.id, info.sha256)
            self.events.append({"warning": str(error)})
            return
        self.follow.held, self.follow.refused = (info.id, info.sha256), None
        self.events.append({"switched": info.label, "from": before})

    def feed(
        self, block: np.ndarray, t0: float | None = None, *, arrived: float | None = None
    ) -> list[TouchPrediction]:
        """Take the next samples; predictions of the touches that ended in them.

        Parameters
        ----------
        block : ndarray of shape (n_channels, n_samples)
            Samples following the previous block.
        t0 : float, optional
            Time of the block's first sample (the first block's sets the origin of
            ``start``/``end``; 0 if never given).
        arrived : float, optional
            ``time.perf_counter()`` when the block was complete (now if not given).
        """
        arrived = time.perf_counter() if arrived is None else arrived
        if self.origin is None:
            self.origin = t0 or 0.0
        self._follow()
        try:
            instances = self.stream.feed(block)
        except FeatureError as error:
            raise AppError(f"live stream: {error}") from None
        return self._predict(instances, arrived)

    def finish(self) -> list[TouchPrediction]:
        """The end of the stream: predictions of the touches still open."""
        arrived = time.perf_counter()
        if self.stream.position == 0:
            return []
        try:
            instances = self.stream.finish()
        except FeatureError:
            return []  # a stream shorter than one analysis window holds no touch
        return self._predict(instances, arrived)

    def _predict(self, instances: Instances, arrived: float) -> list[TouchPrediction]:
        self.warnings += instances.warnings
        if instances.values.shape[0] == 0:
            return []
        X = instances.values[:, self.columns]
        if self.model.regression:
            values, probabilities = self.model.predict_values(X), None
        else:
            values, probabilities = self.model.predict_with_proba(X)
        values = np.asarray(values).reshape(X.shape[0], -1)
        targets = self.model.schema.targets
        done = time.perf_counter()
        origin = self.origin or 0.0
        out = []
        for i, (first, last) in enumerate(instances.spans):
            behind = (self.stream.position - last) / self.samplerate
            predictions: dict[str, tuple[str | float, float | None]] = {}
            for j, target in enumerate(targets):
                if self.model.regression:
                    predictions[target.name] = (float(values[i, j]), None)
                    continue
                code = int(values[i, j])
                chance = None if probabilities is None else float(probabilities[j][i, code])
                predictions[target.name] = (target.values[code], chance)
            out.append(
                TouchPrediction(
                    start=origin + first / self.samplerate,
                    end=origin + last / self.samplerate,
                    predictions=predictions,
                    latency_ms=1000.0 * (behind + done - arrived),
                    model=self.label,
                )
            )
        return out


def load_live_model(
    store: Store, ref: str | int, engine: Engine = "auto"
) -> tuple[ModelInfo, Predictor]:
    """A stored model (any reference: id, ``NAME``, ``NAME@VERSION``, ``NAME@ALIAS``) with
    its artifact checked, run by ``engine``; ``info.extraction`` is the recipe of the data
    set it was trained on (None for an imported one)."""
    return load_predictor(store, ref, engine)


def open_live(
    store: Store,
    ref: str | int,
    *,
    samplerate: float,
    n_channels: int,
    engine: Engine = "auto",
    cache: ModelCache | None = None,
    follow_seconds: float = FOLLOW_SECONDS,
) -> LiveSession:
    """A :class:`LiveSession` of the stored model ``ref`` (id, ``NAME``, ``NAME@VERSION``,
    ``NAME@ALIAS``), following ``ref`` when it can name another version later.

    Parameters
    ----------
    engine : {"auto", "onnx", "native"}
        What runs the predictions (see :func:`app.services.loading.load_predictor`), of
        this version and of those the session switches to.
    cache : ModelCache, optional
        Where the versions are loaded (the service passes its own); default: one of the
        session's own.
    follow_seconds : float
        Seconds between two checks of the version ``ref`` names.
    """
    cache = cache or ModelCache(FOLLOWED_MODELS)
    info, model = cache.get(store, ref, engine)
    return LiveSession(
        info,
        model,
        samplerate=samplerate,
        n_channels=n_channels,
        follow=follower(store, ref, info, cache=cache, engine=engine, interval=follow_seconds),
    )
