"""Rows that users address by name or by numeric id: lookup, unique names (the rule of a
name itself is :func:`app.schemas.names.check_name`)."""

from __future__ import annotations

import re
from typing import Any, Protocol, TypeVar

from sqlalchemy import func, select
from sqlalchemy.orm import InstrumentedAttribute, Session

from touchbench.app.errors import NotFoundError
from touchbench.app.schemas.names import CONTROL as _CONTROL
from touchbench.app.schemas.names import MAX_NAME
from touchbench.app.schemas.names import shown as shorten

# re-exported: the rule of an id is the schemas' (model references read it too)
from touchbench.app.schemas.references import is_decimal as is_decimal
from touchbench.app.schemas.references import is_row_id as is_row_id

#: Names listed in a "no such ..." message.
_NAMES_SHOWN = 10
_UNSAFE = re.compile(r"[^\w.-]+")


class Named(Protocol):
    id: Any
    name: Any


RowT = TypeVar("RowT", bound=Named)


def may_be_name(text: str) -> bool:
    """Whether some stored row could be called ``text``: names hold no control characters
    and are valid UTF-8 (so a NUL or a lone surrogate, which PostgreSQL refuses in a
    query, is never sent to the database)."""
    if _CONTROL.search(text):
        return False
    try:
        text.encode("utf-8")
    except UnicodeEncodeError:
        return False
    return True


def find_row(session: Session, model: type[RowT], ref: str | int, *, kind: str, hint: str) -> RowT:
    """The row called ``ref``, else the one with id ``ref``.

    Raises
    ------
    NotFoundError
        Naming the known rows (the first ten, each shortened), or ``hint`` when there
        are none.
    """
    text = str(ref)
    name_column: InstrumentedAttribute[str] = model.name
    row = None
    if may_be_name(text):
        row = session.scalars(select(model).where(name_column == text)).first()
    if row is None and is_row_id(text):
        row = session.get(model, int(text))
    if row is None:
        names = session.scalars(select(name_column).order_by(model.id).limit(_NAMES_SHOWN)).all()
        if names:
            total = session.scalar(select(func.count()).select_from(model)) or 0
            known = ", ".join(shorten(name) for name in names)
            if total > len(names):
                known += f", ... ({total} in all)"
        else:
            known = hint
        raise NotFoundError(f"no {kind} '{shorten(text)}' ({kind}s: {known})")
    return row


def default_name(text: str, *, fallback: str = "dataset") -> str:
    """A valid name made from ``text`` (a file stem, a relation): unsafe characters folded
    to ``_``, cut to leave room for a numeric suffix, a number given a ``fallback-`` prefix."""
    base = _UNSAFE.sub("_", text).strip("_")[: MAX_NAME - 10] or fallback
    return f"{fallback}-{base}" if is_decimal(base) else base


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
