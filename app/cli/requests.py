"""Requests from command-line options, and their field errors in the options' words.

A command builds its use case's request type (:class:`app.schemas.base.Request`) from its
options with :func:`build_request`, naming the option that sets each field.  A field the
request refuses, when it is built or later in the service (:class:`app.errors.FieldError`),
is shown as that option: ``touchbench: error: --max-memory: must be ...``.

The options named by the last request built belong to the command being run: they are kept
in a context variable, which :func:`app.cli.main.main` gives each call of the CLI afresh,
so that nothing of one call reaches the next (tests run many in one process).
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from contextvars import ContextVar
from types import MappingProxyType
from typing import Any, TypeVar

from pydantic import ValidationError

from touchbench.app.errors import FieldError
from touchbench.app.schemas.base import Request, field_error

RequestType = TypeVar("RequestType", bound=Request)

#: A field named inside a message: `tune` (see :class:`app.errors.FieldError`).
_NAMED_FIELD = re.compile(r"`([a-z][a-z0-9_.]*)`")

#: The options of the command being run, by the field each sets (see :func:`option_of`).
_options: ContextVar[Mapping[str, str]] = ContextVar("options", default=MappingProxyType({}))


def build_request(
    kind: type[RequestType], options: Mapping[str, str] | None = None, /, **values: Any
) -> RequestType:
    """The request ``kind`` made of ``values``; ``options`` names the option of each field.

    ``kind`` and ``options`` are positional only, so that a request may have a field called
    ``options``.  Values that are ``None`` are left out, so that the request's own defaults apply to
    options the user did not give.  A field without an entry in ``options`` is shown as
    ``--`` and its name with dashes (``max_memory_mb`` as ``--max-memory-mb``); a field an
    argument sets is named in ``options`` by the argument's metavar (``DATASET``).

    Raises
    ------
    FieldError
        The first field the request refuses.
    """
    _options.set(MappingProxyType(dict(options or {})))
    try:
        return kind(**{field: value for field, value in values.items() if value is not None})
    except ValidationError as error:
        raise field_error(error) from None


def option_of(field: str) -> str:
    """How the command line spells a request's field: its option or argument."""
    top = field.split(".", 1)[0]
    options = _options.get()
    return options.get(field) or options.get(top) or "--" + top.replace("_", "-")


def describe(error: FieldError) -> str:
    """``--max-memory: must be ...``, the line the CLI prints for a refused field; other
    fields the message names in backquotes are shown as their options too."""
    message = _NAMED_FIELD.sub(lambda named: option_of(named.group(1)), error.message)
    return f"{option_of(error.field)}: {message}"
