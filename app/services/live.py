"""Live prediction: a stream of samples in, one prediction per detected touch out.

A :class:`LiveSession` runs the model's own extraction recipe (the extractor, its
options and the event detector that made its training data) through the streaming
engine, so live features are computed exactly as the training features were, and
predicts every instance as soon as its event ends.  Its methods are plain synchronous
calls, so that a CLI loop and an async WebSocket handler (in a worker thread) share it.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from app.errors import AppError
from app.schemas.models import Engine
from app.services.export import load_predictor
from app.store.database import Store
from app.store.models import ModelInfo
from benchmark.model import Predictor
from features.errors import FeatureError
from features.extractors import Instances
from features.recipe import Recipe


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
    """

    start: float
    end: float
    predictions: dict[str, tuple[str | float, float | None]]
    latency_ms: float

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
        }


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
    ) -> None:
        name = model_info.name
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
        position = {feature: i for i, feature in enumerate(self.stream.feature_names)}
        missing = [a.name for a in model.schema.features if a.name not in position]
        if missing:
            raise AppError(
                f"model '{name}' needs features its extractor '{recipe.extractor}' does not "
                f"make on {n_channels} channel(s): {', '.join(missing[:5])}"
            )
        self.columns = np.array([position[a.name] for a in model.schema.features], dtype=np.int64)
        self.model = model
        self.recipe = recipe
        self.samplerate = float(samplerate)
        self.n_channels = n_channels
        self.origin: float | None = None
        self.warnings: list[str] = []

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
                )
            )
        return out


def load_live_model(
    store: Store, ref: str | int, engine: Engine = "auto"
) -> tuple[ModelInfo, Predictor]:
    """A stored model (name or id) with its artifact checked, run by ``engine``;
    ``info.extraction`` is the recipe of the data set it was trained on (None for an
    imported one)."""
    return load_predictor(store, ref, engine)


def open_live(
    store: Store, ref: str | int, *, samplerate: float, n_channels: int, engine: Engine = "auto"
) -> LiveSession:
    """A :class:`LiveSession` of the stored model ``ref`` (name or id)."""
    info, model = load_live_model(store, ref, engine)
    return LiveSession(info, model, samplerate=samplerate, n_channels=n_channels)
