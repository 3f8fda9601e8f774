"""Listings a page at a time (:class:`app.schemas.listing.Page`), and how many rows a
listing has in all."""

from __future__ import annotations

from typing import Any, TypeVar

from sqlalchemy import ColumnElement, Select, func, select

from touchbench.app.schemas.listing import Page
from touchbench.app.store.database import Store

SelectType = TypeVar("SelectType", bound=Select[Any])


def paged(query: SelectType, page: Page | None) -> SelectType:
    """``query`` (ordered already) limited to ``page``; all of it without one."""
    if page is None:
        return query
    return query.offset(page.offset).limit(page.limit)


def count_rows(store: Store, table: type[Any], *where: ColumnElement[bool]) -> int:
    """How many rows ``table`` has (those matching ``where``)."""
    with store.session() as session:
        query = select(func.count()).select_from(table).where(*where)
        return int(session.scalar(query) or 0)
