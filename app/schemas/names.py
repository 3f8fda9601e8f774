"""What a name of a data set or a model may be: the rule, once, for every request that gives
one (import, extraction, training, rename) and for the store that keeps it.

A name is how a user finds a row again, on the command line and in a URL path
(``/api/datasets/{name}``), so it must survive both: not empty, at most :data:`MAX_NAME`
characters, no control characters, no spaces at its ends, no ``/`` (a path segment
cannot hold one: ``a/b`` would be stored and never reached by name again), and not a
number (a number is read as an id).
"""

from __future__ import annotations

import re
from collections.abc import Callable
from typing import Annotated

from pydantic import AfterValidator, ValidationInfo

from app.errors import AppError, FieldError

#: The longest name the store keeps (the ``name`` columns are ``String(200)``).
MAX_NAME = 200
#: Control characters (C0, DEL and C1).
CONTROL = re.compile(r"[\x00-\x1f\x7f-\x9f]")
#: Characters of a name a message shows.
_SHOWN = 40


def check_name(name: str, *, kind: str) -> str:
    """``name`` if it can name a ``kind`` (a new one, or a renamed one).

    Parameters
    ----------
    name : str
        The name asked for.
    kind : str
        What it names, for the message: ``dataset``, ``model``.

    Raises
    ------
    AppError
        Saying which rule the name breaks.
    """
    if not name.strip():
        raise AppError(f"a {kind} name cannot be empty")
    if len(name) > MAX_NAME:
        raise AppError(
            f"a {kind} name has at most {MAX_NAME} characters; '{shown(name)}' has {len(name)}"
        )
    control = CONTROL.search(name)
    if control is not None:
        raise AppError(
            f"a {kind} name cannot hold control characters: '{shown(name)}' has "
            f"{control.group()!r} at position {control.start() + 1}"
        )
    if name != name.strip():
        raise AppError(f"a {kind} name cannot start or end with spaces: '{shown(name)}'")
    if "/" in name:
        raise AppError(
            f"a {kind} name cannot hold '/' (it could not be reached in a URL): '{shown(name)}'"
        )
    if name.isascii() and name.isdigit():
        raise AppError(f"a {kind} name cannot be a number ('{name}' would read as an id)")
    return name


def shown(text: str, limit: int = _SHOWN) -> str:
    """``text`` for a message: control characters as ``?``, cut to ``limit`` characters."""
    text = CONTROL.sub("?", text)
    return text if len(text) <= limit else text[: limit - 1] + "…"


def _field_rule(kind: str) -> Callable[[str, ValidationInfo], str]:
    def valid(name: str, info: ValidationInfo) -> str:
        try:
            return check_name(name, kind=kind)
        except AppError as error:
            raise FieldError(info.field_name or "name", str(error)) from None

    return valid


#: A request's field that names a new or renamed data set.
DatasetName = Annotated[str, AfterValidator(_field_rule("dataset"))]
#: A request's field that names a new model.
ModelName = Annotated[str, AfterValidator(_field_rule("model"))]
