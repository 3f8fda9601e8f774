"""What the web page's fragments depend on: the store of the service they are part of."""

from __future__ import annotations

from typing import Annotated

from fastapi import Depends, Request

from touchbench.app.store.database import Store


async def get_store(request: Request) -> Store:
    """The service's store (:func:`app.main.create_app` keeps it in the application's
    state); ``async`` so that FastAPI calls it on the event loop, as it does not block."""
    store = request.app.state.service.store
    assert isinstance(store, Store), "create_app sets the service state"
    return store


StoreDep = Annotated[Store, Depends(get_store)]
