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

Before any of that, :class:`DepthScan` finds a JSON body nested deeper than
:data:`MAX_DEPTH` (a parser recurses once per level: 100,000 ``[`` are 200 KB that no
parser should follow); the service's body limit refuses such a body (422) at the chunk
where it passes the limit, before the rest is read and before any route parses it.
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
#: What follows a string's opening quote up to its closing quote (or the data's end).
_STRING_BODY = re.compile(rb'(?:[^"\\]++|\\.)*+')
#: Bytes of a chunk scanned before the rest of it.
_FIRST_PIECE = 4096


class DepthScan:
    """The nesting of a JSON body followed chunk by chunk as it streams in, so that a body
    nested deeper than ``max_depth`` is refused at the chunk where it passes the limit,
    before the rest is read and before any parser sees it.

    Each chunk costs a regular expression (strings stepped over, brackets inside them do
    not count) and array operations over its brackets: linear in its bytes, whatever it
    holds.  A string that a chunk leaves open is carried to the next (with a backslash
    that ends the chunk).  The last chunk of a body with too few brackets to pass the limit
    is not scanned at all (a one-instance prediction pays nothing).
    """

    def __init__(self, max_depth: int = MAX_DEPTH) -> None:
        self.max_depth = max_depth
        self.depth = 0
        self.seen = 0
        self._in_string = False
        self._escaped = False

    def feed(self, chunk: bytes, *, last: bool = False) -> str | None:
        """What is wrong once ``chunk`` is read (the body nests too deep), else None."""
        if last and not self._in_string and self.depth + _openings(chunk) <= self.max_depth:
            self.seen += len(chunk)
            return None
        # a small piece first: a body deep from its first bytes is refused after them
        for piece in (chunk[:_FIRST_PIECE], chunk[_FIRST_PIECE:]):
            self.seen += len(piece)
            problem = self._scan(piece) if piece else None
            if problem is not None:
                return problem
        return None

    def _scan(self, chunk: bytes) -> str | None:
        at = 0
        if self._in_string:
            at = self._string_rest(chunk, 1 if self._escaped else 0)
            if at < 0:
                return None
        bare = _STRING.sub(b"", chunk[at:])
        opened = bare.find(b'"')  # the whole strings are gone: this one stays open
        if opened >= 0:
            self._string_rest(bare, opened + 1)  # carried to the next chunk
            bare = bare[:opened]
        if not bare:
            return None
        codes = np.frombuffer(bare, dtype=np.uint8)
        opening = (codes == ord("[")) | (codes == ord("{"))
        closing = (codes == ord("]")) | (codes == ord("}"))
        steps = opening.astype(np.int32) - closing
        depths = self.depth + np.cumsum(steps, dtype=np.int64)
        deepest = int(depths.max())
        self.depth = int(depths[-1])
        if deepest <= self.max_depth:
            return None
        return (
            f"JSON nested deeper than the {self.max_depth} levels allowed (objects and lists "
            f"in one another; refused within its first {self.seen:,} bytes)"
        )

    def _string_rest(self, data: bytes, at: int) -> int:
        """Where the string open at ``at`` of ``data`` closes (the index after its quote),
        or -1 when it runs to the end (then still open, escaped if a backslash ends it)."""
        match = _STRING_BODY.match(data, at)
        end = match.end() if match is not None else at  # it always matches (maybe empty)
        if end < len(data) and data[end : end + 1] == b'"':
            self._in_string = self._escaped = False
            return end + 1
        self._in_string = True
        self._escaped = end < len(data)  # stopped before a lone backslash, the last byte
        return -1


def depth_problem(body: bytes, *, max_depth: int = MAX_DEPTH) -> str | None:
    """What is wrong with a whole JSON body whose objects and lists nest deeper than
    ``max_depth`` (:class:`DepthScan` over one chunk); None when they do not."""
    return DepthScan(max_depth).feed(body, last=True)


def _openings(data: bytes) -> int:
    return data.count(b"[") + data.count(b"{")


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
