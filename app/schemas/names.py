"""What a name of a data set or a model may be: the rule, once, for every request that gives
one (import, extraction, training, rename) and for the store that keeps it.

A name is how a user finds a row again, on the command line and in a URL path
(``/api/datasets/{name}``), so it must survive both: not empty, at most :data:`MAX_NAME`
characters, no control characters nor bidirectional formatting ones (a right-to-left
override makes ``abc\u202edcba`` list as another name), no spaces at its ends, no ``/``
(a path segment cannot hold one: ``a/b`` would be stored and never reached by name
again), and not a number (a number is read as an id).  A model's name holds no ``@``
either: ``NAME@VERSION`` and ``NAME@ALIAS`` name one of its versions.

An alias (``champion``) starts with a letter, so that it is never read as a version number.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from typing import Annotated

from pydantic import AfterValidator, ValidationInfo

from touchbench.app.errors import AppError, FieldError
from touchbench.app.schemas.references import LATEST, SEPARATOR

#: The longest name the store keeps (the ``name`` columns are ``String(200)``).
MAX_NAME = 200
#: Control characters (C0, DEL and C1).
CONTROL = re.compile(r"[\x00-\x1f\x7f-\x9f]")
#: Characters that change how the text around them is shown rather than being shown:
#: control characters, the bidirectional marks, embeddings, overrides and isolates, and
#: the line and paragraph separators.
INVISIBLE = re.compile(r"[\x00-\x1f\x7f-\x9f\u061c\u200e\u200f\u2028-\u202e\u2066-\u2069]")
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
    control = INVISIBLE.search(name)
    if control is not None:
        raise AppError(
            f"a {kind} name cannot hold control characters, nor bidirectional formatting ones: "
            f"'{shown(name)}' has U+{ord(control.group()):04X} at position {control.start() + 1}"
        )
    if name != name.strip():
        raise AppError(f"a {kind} name cannot start or end with spaces: '{shown(name)}'")
    if "/" in name:
        raise AppError(
            f"a {kind} name cannot hold '/' (it could not be reached in a URL): '{shown(name)}'"
        )
    if name.isascii() and name.isdigit():
        raise AppError(f"a {kind} name cannot be a number ('{name}' would read as an id)")
    if kind == "model" and SEPARATOR in name:
        raise AppError(
            f"a model name cannot hold '@' (NAME@VERSION and NAME@ALIAS name a version of "
            f"model NAME): '{shown(name)}'"
        )
    return name


#: The longest alias the store keeps (``model_aliases.alias`` is ``String(100)``).
MAX_ALIAS = 100
_ALIAS = re.compile(r"[A-Za-z][A-Za-z0-9_.-]*")


def check_alias(alias: str) -> str:
    """``alias`` if it can name a version of a model (``champion``, ``staging``).

    Raises
    ------
    AppError
        Saying which rule the alias breaks.
    """
    if len(alias) > MAX_ALIAS:
        raise AppError(f"an alias has at most {MAX_ALIAS} characters, got {len(alias)}")
    if not _ALIAS.fullmatch(alias):
        raise AppError(
            f"an alias starts with a letter and holds only letters, digits, '_', '.' and '-' "
            f"(a number would read as a version): '{shown(alias)}'"
        )
    if alias == LATEST:
        raise AppError(f"'{LATEST}' is not an alias: NAME@{LATEST} is always the newest version")
    return alias


def shown(text: str, limit: int = _SHOWN) -> str:
    """``text`` for a message: control and bidirectional formatting characters as ``?``,
    cut to ``limit`` characters."""
    text = INVISIBLE.sub("?", text)
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


def _alias_rule(alias: str, info: ValidationInfo) -> str:
    try:
        return check_alias(alias)
    except AppError as error:
        raise FieldError(info.field_name or "alias", str(error)) from None


#: A request's field that names an alias of a model's version.
AliasName = Annotated[str, AfterValidator(_alias_rule)]
