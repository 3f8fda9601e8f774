"""The registry's read and delete use cases: model versions listed, found and deleted.

Every adapter (the CLI, the API, the web page) reads the registry here, so that each shows
a model the same way: with the problem this process found loading its ONNX twin, where it
found one (:func:`app.services.loading.with_known_problem`).
"""

from __future__ import annotations

from touchbench.app.schemas.listing import Page
from touchbench.app.services.loading import with_known_problem
from touchbench.app.store import models as stored
from touchbench.app.store.database import Store
from touchbench.app.store.models import ModelInfo


def count_models(store: Store) -> int:
    """How many model versions the store holds."""
    return stored.count_models(store)


def list_models(store: Store, *, page: Page | None = None) -> list[ModelInfo]:
    """Every model version (those of ``page``), oldest first, with their aliases."""
    return [with_known_problem(info) for info in stored.list_models(store, page=page)]


def find_model(store: Store, ref: str | int) -> ModelInfo:
    """The version ``ref`` names (``NAME``, ``NAME@VERSION``, ``NAME@alias`` or an id).

    Raises
    ------
    app.errors.NotFoundError
        No such model, version or alias.
    """
    return with_known_problem(stored.get_model(store, ref))


def delete_model(store: Store, ref: str | int) -> ModelInfo:
    """Delete the version ``ref`` names (``NAME``: the newest), its artifact, twins and
    the aliases that pointed at it; its number and id are never given again."""
    return stored.delete_model(store, ref)
