"""Rows that users address by name or by numeric id, and names made unique."""

from __future__ import annotations

from typing import Any, Protocol, TypeVar

from sqlalchemy import select
from sqlalchemy.orm import InstrumentedAttribute, Session

from app.errors import NotFoundError


class Named(Protocol):
    id: Any
    name: Any


RowT = TypeVar("RowT", bound=Named)


def find_row(session: Session, model: type[RowT], ref: str | int, *, kind: str, hint: str) -> RowT:
    """The row called ``ref``, else the one with id ``ref``.

    Raises
    ------
    NotFoundError
        Naming the known rows (the first ten), or ``hint`` when there are none.
    """
    text = str(ref)
    name_column: InstrumentedAttribute[str] = model.name
    row = session.scalars(select(model).where(name_column == text)).first()
    if row is None and text.isdigit():
        row = session.get(model, int(text))
    if row is None:
        names = session.scalars(select(name_column).order_by(model.id)).all()
        known = ", ".join(names[:10]) if names else hint
        raise NotFoundError(f"no {kind} '{text}' ({kind}s: {known})")
    return row


def free_name(session: Session, model: type[Named], base: str) -> str:
    """``base``, or ``base-2``, ``base-3``... whichever no row of ``model`` has yet."""
    name_column: InstrumentedAttribute[str] = model.name
    taken = set(session.scalars(select(name_column).where(name_column.startswith(base))))
    if base not in taken:
        return base
    suffix = 2
    while f"{base}-{suffix}" in taken:
        suffix += 1
    return f"{base}-{suffix}"
