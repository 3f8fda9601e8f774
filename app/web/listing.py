"""The newest rows of a listing, as a fragment shows them: read a page from the store, not
every row (:mod:`app.reports.bounds`)."""

from __future__ import annotations

from typing import Protocol, TypeVar

from touchbench.app.reports.bounds import ROWS, Shown
from touchbench.app.schemas.listing import Page

T = TypeVar("T")


class Lister(Protocol[T]):
    """A store's listing function, reading one page (``list_runs(store, page=...)``)."""

    def __call__(self, *, page: Page) -> list[T]: ...


def newest(total: int, listed: Lister[T], limit: int = ROWS) -> Shown[T]:
    """The last ``limit`` of ``total`` rows, oldest first, and how many came before.

    Parameters
    ----------
    total : int
        The rows of the listing.
    listed : callable
        Reads one page of the listing from the store.
    """
    older = max(total - limit, 0)
    return Shown(listed(page=Page(offset=older, limit=limit)), older)
