"""JSON bodies counted while read (app.api.counting): refused at the item that passes a
limit, whatever the strings inside hold; anything that is not the expected object is left
to the validation."""

from __future__ import annotations

import json

import pytest
from fastapi.exceptions import RequestValidationError

from touchbench.app.api.counting import check_counts, limited_lists
from touchbench.app.schemas.models import PredictRequest

LISTS = {"instances": 5}


def _refusal(body: object, *, max_keys: int = 3) -> dict[str, object]:
    with pytest.raises(RequestValidationError) as refused:
        check_counts(json.dumps(body).encode(), LISTS, max_keys=max_keys)
    (problem,) = refused.value.errors()
    return dict(problem)


def _accepted(body: bytes | object, *, max_keys: int = 3) -> None:
    raw = body if isinstance(body, bytes) else json.dumps(body).encode()
    check_counts(raw, LISTS, max_keys=max_keys)


def test_the_limits_come_from_the_request_type() -> None:
    assert limited_lists(PredictRequest) == {"instances": 10000}


def test_too_many_items_or_keys_are_refused_where_they_pass_the_limit() -> None:
    tricky = {"a": 'x":1,"y":{"z":[', "b": 1}  # colons, braces and brackets in a string
    problem = _refusal({"other": [1] * 9, "instances": [tricky] * 6})
    assert problem["loc"] == ("body", "instances") and problem["type"] == "too_long"
    assert str(problem["msg"]).endswith("(counting stopped at item 6)")
    problem = _refusal({"instances": [{"a": 1}, {"a": 1, "b": 2, "c": 3, "d": 4}]})
    assert problem["loc"] == ("body", "instances", 1)
    assert problem["msg"] == "an item has at most 3 keys (the service's limit on attributes), not 4"
    nested = {"instances": [{"a": [1, 2]}, [1, {"b": 2}], "x", None, 1, {"c": {"d": 1}}]}
    assert _refusal(nested)["type"] == "too_long"


def test_bodies_within_the_limits_or_not_the_object_expected_pass_through() -> None:
    _accepted({"instances": [{"a": 'x":1,"y":2,"z":3', "b": None}] * 5})  # 4 colons, 2 keys
    _accepted({"instances": []})
    _accepted({"instances": "not a list", "other": [1] * 100})
    for broken in (b"", b"[1, 2]", b'{"instances": [1, 2', b'{"instances" [1]}', b"\xff\xfe"):
        _accepted(broken + b" " * 100)  # long enough to be scanned
