"""What routes depend on: the service's state (settings, store, dispatcher, model cache), the
API key check, and a cache of loaded models for fast predictions."""

from __future__ import annotations

import hmac
import threading
from collections import OrderedDict
from dataclasses import dataclass
from typing import TYPE_CHECKING, Annotated

from fastapi import Depends, Header, HTTPException, Request

from app.jobs.dispatcher import Dispatcher
from app.settings import Settings
from app.store.database import Store
from app.store.models import ModelInfo, get_model

if TYPE_CHECKING:  # scikit-learn loads on the first prediction, not at start-up
    from benchmark.model import TrainedModel


class ModelCache:
    """Loaded models by (id, sha256), least recently used dropped first; thread-safe.

    Loading a model checks and rebuilds its artifact (tens to hundreds of milliseconds);
    a prediction on a cached model costs one small query for the model's row.
    """

    def __init__(self, size: int) -> None:
        self.size = size
        self._models: OrderedDict[tuple[int, str], TrainedModel] = OrderedDict()
        self._lock = threading.Lock()

    def get(self, store: Store, ref: str | int) -> tuple[ModelInfo, TrainedModel]:
        info = get_model(store, ref)
        key = (info.id, info.sha256)
        with self._lock:
            model = self._models.get(key)
            if model is not None:
                self._models.move_to_end(key)
                return info, model
        from app.services.models import load_model

        info, model = load_model(store, info.id)
        with self._lock:
            self._models[(info.id, info.sha256)] = model
            while len(self._models) > self.size:
                self._models.popitem(last=False)
        return info, model

    def forget(self, model_id: int) -> None:
        with self._lock:
            for key in [key for key in self._models if key[0] == model_id]:
                del self._models[key]


@dataclass
class Service:
    """Everything one service process holds."""

    settings: Settings
    store: Store
    dispatcher: Dispatcher
    models: ModelCache


def get_service(request: Request) -> Service:
    service = request.app.state.service
    assert isinstance(service, Service), "create_app sets the service state"
    return service


def get_store(service: Annotated[Service, Depends(get_service)]) -> Store:
    return service.store


def require_api_key(
    service: Annotated[Service, Depends(get_service)],
    x_api_key: Annotated[str | None, Header(description="The service's API key.")] = None,
) -> None:
    """401 without the key, 403 with a wrong one (compared in constant time)."""
    expected = service.settings.api_key
    if expected is None:
        return
    if x_api_key is None:
        raise HTTPException(
            401, "this service needs an API key in the X-API-Key header",
            headers={"WWW-Authenticate": "X-API-Key"},
        )  # fmt: skip
    if not hmac.compare_digest(x_api_key.encode(), expected.get_secret_value().encode()):
        raise HTTPException(403, "wrong API key")


ServiceDep = Annotated[Service, Depends(get_service)]
StoreDep = Annotated[Store, Depends(get_store)]
