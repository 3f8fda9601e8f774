"""JSON bodies counted while read (app.api.counting): refused at the item that passes a
limit, whatever the strings inside hold; anything that is not the expected object is left
to the validation."""

from __future__ import annotations

import itertools
import json

import pytest
from fastapi.exceptions import RequestValidationError

from touchbench.app.api.counting import DepthScan, check_counts, depth_problem, limited_lists
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


# -- depth, as the chunks stream in ------------------------------------------------------------

#: Brackets, quotes and backslashes inside strings, wherever a chunk may end.
NESTED = {"a": "[[[[", "b": [[{"c": '"]]]\\'}, "\\"], [[[['x"[', 1]]]]], "d": "{"}
DEEP_WITH_STRINGS = json.dumps(NESTED).encode()


def _depth(value: object) -> int:
    if isinstance(value, dict):
        return 1 + max((_depth(v) for v in value.values()), default=0)
    if isinstance(value, list):
        return 1 + max((_depth(v) for v in value), default=0)
    return 0


def _fed(body: bytes, cuts: list[int], max_depth: int) -> str | None:
    scan = DepthScan(max_depth)
    edges = [0, *cuts, len(body)]
    for i, (start, end) in enumerate(itertools.pairwise(edges)):
        problem = scan.feed(body[start:end], last=i == len(edges) - 2)
        if problem is not None:
            return problem
    return None


@pytest.mark.parametrize("max_depth", [4, 5, 6])
def test_the_depth_is_the_same_however_the_body_is_cut(max_depth: int) -> None:
    deepest = _depth(NESTED)
    assert deepest == 6  # the object, "b"'s list, then [[[[ around 'x"['
    for one in range(len(DEEP_WITH_STRINGS) + 1):
        for two in range(one, len(DEEP_WITH_STRINGS) + 1, 7):
            problem = _fed(DEEP_WITH_STRINGS, [one, two], max_depth)
            assert (problem is not None) == (deepest > max_depth), (one, two, problem)
    assert (depth_problem(DEEP_WITH_STRINGS, max_depth=max_depth) is not None) == (
        deepest > max_depth
    )


def test_a_deep_body_is_refused_at_its_first_chunk() -> None:
    scan = DepthScan()
    problem = scan.feed(b'{"instances": [' + b"[" * 65_536)
    assert problem is not None and "deeper than the 64 levels allowed" in problem
    assert "within its first 4,096 bytes" in problem  # a small piece first


def test_brackets_in_a_string_left_open_by_a_chunk_do_not_count() -> None:
    scan = DepthScan(max_depth=2)
    assert scan.feed(b'{"a": "' + b"[" * 100 + b"\\") is None
    assert scan.feed(b'"' + b"[" * 100 + b'", "b": [1]') is None
    assert scan.feed(b"}") is None
    assert scan.depth == 0
