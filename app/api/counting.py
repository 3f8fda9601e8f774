"""A JSON body's lists counted while they are read, before the body is validated: a list
longer than its request type allows (``max_length``), or an object in it with more keys
than the service takes, is refused at the item that passes the limit.

Validating 50,000 prediction instances to refuse them for being over 10,000 took 6.4 s of
the event loop; here the scan steps over one item at a time and stops at item 10,001.  An
item that is a flat object (a prediction instance) is stepped over by one regular
expression, and its colons bound its keys; only an object with more colons than the keys
allowed, or another kind of item, is decoded (the standard library's C decoder) to count
exactly.  A body too short to pass any limit is not scanned at all (a one-instance
prediction pays nothing).  Anything else (a body that is not JSON, a field of the wrong
type) is left to the validation that follows, which says what is wrong where.

Before any of that, :func:`depth_problem` finds a JSON body nested deeper than
:data:`MAX_DEPTH` (a parser recurses once per level: 100,000 ``[`` are 200 KB that no
parser should follow); the service's body limit refuses such a body (422) before any
route parses it.
"""

from __future__ import annotations

import json
import re
from typing import Any

import numpy as np
from annotated_types import MaxLen
from fastapi.exceptions import RequestValidationError
from pydantic import BaseModel

_SPACE = re.compile(r"[ \t\n\r]*")
_DECODER = json.JSONDecoder()
#: An object whose values are strings, numbers, booleans or null (no nested object or list).
_FLAT_OBJECT = re.compile(r'\{(?:[^"{}\[\]]++|"(?:[^"\\]++|\\.)*+")*+\}')


#: The deepest nesting of objects and lists a JSON body may have.
MAX_DEPTH = 64
#: A JSON string, escapes included (possessive: a long string is one step of the engine).
_STRING = re.compile(rb'"(?:[^"\\]++|\\.)*+"')
_OPENING = np.frombuffer(b"[{", dtype=np.uint8)
_CLOSING = np.frombuffer(b"]}", dtype=np.uint8)


def depth_problem(body: bytes, *, max_depth: int = MAX_DEPTH) -> str | None:
    """What is wrong with a JSON body whose objects and lists nest deeper than
    ``max_depth``; None when they do not.

    Brackets inside strings do not count; the scan is a regular expression and array
    operations over the body's brackets, so its cost follows the body's size, and a body
    with fewer brackets than the limit is not scanned at all.
    """
    if body.count(b"[") + body.count(b"{") <= max_depth:
        return None
    bare = np.frombuffer(_STRING.sub(b'""', body), dtype=np.uint8)
    brackets = np.flatnonzero(np.isin(bare, _OPENING) | np.isin(bare, _CLOSING))
    steps = np.where(np.isin(bare[brackets], _OPENING), 1, -1).astype(np.int32)
    deepest = int(np.cumsum(steps, dtype=np.int32).max())
    if deepest <= max_depth:
        return None
    return (
        f"JSON nested {deepest:,} levels deep, deeper than the {max_depth} allowed (objects "
        "and lists in one another)"
    )


class _NotCountedError(Exception):
    """The body is not the JSON object the scan expects: validation says why."""


def limited_lists(model: type[BaseModel]) -> dict[str, int]:
    """The fields of ``model`` that are lists with a ``max_length``, and that length."""
    limits = {}
    for name, field in model.model_fields.items():
        for constraint in field.metadata:
            if isinstance(constraint, MaxLen):
                limits[field.alias or name] = constraint.max_length
    return limits


def check_counts(body: bytes, lists: dict[str, int], *, max_keys: int) -> None:
    """Count the items of the top-level ``lists`` of a JSON object, and the keys of each
    object among them, refusing the body as soon as one passes its limit.

    Parameters
    ----------
    body : bytes
        The request's body.
    lists : dict of str to int
        Field name -> most items (:func:`limited_lists`).
    max_keys : int
        Most keys of an object inside one of those lists.

    Raises
    ------
    RequestValidationError
        Located at ``body.FIELD`` (too many items) or ``body.FIELD.INDEX`` (too many
        keys), as FastAPI locates a validation error.
    """
    # n items take at least 2n bytes ("0,"), k keys at least 4k ('"":0,' less one)
    if not lists or (len(body) < 2 * min(lists.values()) and len(body) < 4 * max_keys):
        return
    try:
        _scan(body.decode("utf-8"), lists, max_keys)
    except (
        _NotCountedError,
        UnicodeDecodeError,
        json.JSONDecodeError,
        IndexError,
        RecursionError,
    ):
        return  # not the object expected: the validation says what is wrong


def _scan(text: str, lists: dict[str, int], max_keys: int) -> None:
    at = _skip(text, 0)
    _expect(text, at, "{")
    at = _skip(text, at + 1)
    if text[at] == "}":
        return
    while True:
        key, at = _DECODER.raw_decode(text, at)
        at = _skip(text, at)
        _expect(text, at, ":")
        at = _skip(text, at + 1)
        if key in lists and text[at] == "[":
            at = _count_items(text, at + 1, key, lists[key], max_keys)
        else:
            _, at = _DECODER.raw_decode(text, at)
        at = _skip(text, at)
        if text[at] == "}":
            return
        _expect(text, at, ",")
        at = _skip(text, at + 1)


def _count_items(text: str, at: int, field: str, most: int, max_keys: int) -> int:
    """Decode the items of a list one at a time from ``at`` (just after its ``[``);
    where the list ends."""
    at = _skip(text, at)
    if text[at] == "]":
        return at + 1
    count = 0
    while True:
        flat = _FLAT_OBJECT.match(text, at)
        if flat is not None and text.count(":", at, flat.end()) <= max_keys:
            item, at = None, flat.end()  # no more keys than colons: within the limit
        else:
            item, at = _DECODER.raw_decode(text, at)
        count += 1
        if count > most:
            _refuse(
                ("body", field),
                "too_long",
                f"List should have at most {most} items after validation, not more (counting "
                f"stopped at item {count})",
            )
        if isinstance(item, dict) and len(item) > max_keys:
            _refuse(
                ("body", field, count - 1),
                "too_many_keys",
                f"an item has at most {max_keys} keys (the service's limit on attributes), "
                f"not {len(item)}",
            )
        at = _skip(text, at)
        if text[at] == "]":
            return at + 1
        _expect(text, at, ",")
        at = _skip(text, at + 1)


def _skip(text: str, at: int) -> int:
    match = _SPACE.match(text, at)
    return match.end() if match else at


def _expect(text: str, at: int, character: str) -> None:
    if text[at] != character:
        raise _NotCountedError


def _refuse(location: tuple[Any, ...], kind: str, message: str) -> None:
    raise RequestValidationError([{"type": kind, "loc": location, "msg": message}])
