"""No error of the API names a CLI flag or command: every operation of the OpenAPI document
that takes a JSON or form body is sent bad bodies (wrong types, numbers out of range,
unknown names, fields missing or unknown), and every message it answers is read.

A service's messages name the request's fields; only the CLI renders a field as its option
(``--max-memory``), so a flag in an API message is a message written for one adapter
below the adapters.
"""

from __future__ import annotations

import json
import re
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx

from tests.support.service import Server, finished
from tests.support.synthetic import touch_arff


def _cli_words() -> re.Pattern[str]:
    """What a CLI flag (``--name``) or command (``touchbench train``) looks like inside a
    message; the commands are the CLI's own, so that "touchbench does not ..." is prose."""
    import typer.main

    from touchbench.app.cli.main import app

    commands = sorted(typer.main.get_command(app).commands, key=len, reverse=True)  # type: ignore[attr-defined]
    return re.compile(r"--[a-z]|touchbench (?:" + "|".join(map(re.escape, commands)) + r")\b")


CLI_WORDS = _cli_words()

#: Values that make a body plausible up to the field being spoiled, by field name (no
#: ``name``: a body that is accepted would take it, and hide the checks behind it after).
PLAUSIBLE: dict[str, Any] = {
    "dataset": "touch",
    "classifier": "nb",
    "classifiers": ["nb"],
    "target": "gesture",
    "targets": ["gesture"],
    "instances": [{"f0": 0.5, "f1": 0.1, "f2": 0.2, "f3": 0.3, "mic": "left"}],
}
#: Path parameters, by name: what the test's store holds (``spare`` is the data set that
#: renames are tried on, renamed back after each that is accepted).
PATH_VALUES = {"dataset": "spare", "model_ref": "touch-nb"}


def _resolve(document: dict[str, Any], schema: dict[str, Any]) -> dict[str, Any]:
    while "$ref" in schema:
        name = schema["$ref"].rsplit("/", 1)[1]
        schema = document["components"]["schemas"][name]
    return schema


def _types(document: dict[str, Any], schema: dict[str, Any]) -> set[str]:
    """The JSON types a property takes (``binary`` for a file part)."""
    schema = _resolve(document, schema)
    if schema.get("format") == "binary" or schema.get("contentMediaType"):
        return {"binary"}
    found: set[str] = set()
    for option in schema.get("anyOf", []) + schema.get("oneOf", []):
        found |= _types(document, option)
    if "type" in schema:
        found.add(schema["type"])
    if "items" in schema and _types(document, schema["items"]) == {"binary"}:
        return {"binary"}
    if "enum" in schema or "const" in schema:
        found.add("string")
    return found - {"null"}


def _bad_values(kinds: set[str]) -> list[Any]:
    """Wrong types, numbers out of range, unknown names, for a property of ``kinds``."""
    values: list[Any] = [{"nested": "object"}]
    if "string" in kinds:
        values += [123, "", "nope-unknown", "x" * 5000, "12", "touch", "touch-nb", "minirocket"]
    if kinds & {"integer", "number"}:
        values += ["abc", -1, 0, 1.5, 2**40, 1e308, -1e308]
    if "boolean" in kinds:
        values += ["maybe", 2]
    if "array" in kinds:
        values += ["not a list", [], [123], ["nope-unknown"], ["minirocket"], [{"nope": 1}]]
        values += [[[1, 2]]]
    if "object" in kinds:
        values += ["not an object", {"nope-unknown": 1}, {"": None}]
    return values


def _form_values(kinds: set[str]) -> list[str]:
    """Bad values of a form field (forms carry text)."""
    values = ["", "nope-unknown", "x" * 5000, "abc", "-1", "0", "1e308", "nan", "12", "touch"]
    return values if kinds != {"binary"} else []


def _plausible(document: dict[str, Any], schema: dict[str, Any]) -> Iterator[dict[str, Any]]:
    """Two bodies to spoil: the required fields only, and every plausible field too."""
    required = {}
    for name in schema.get("required", []):
        kinds = _types(document, schema["properties"][name])
        if name in PLAUSIBLE:
            required[name] = PLAUSIBLE[name]
        elif "string" in kinds:
            required[name] = "touch"
        elif kinds & {"integer", "number"}:
            required[name] = 1
        elif "array" in kinds:
            required[name] = ["touch"]
        else:
            required[name] = {}
    yield required
    yield {**required, **{k: v for k, v in PLAUSIBLE.items() if k in schema["properties"]}}


def _json_bodies(document: dict[str, Any], schema: dict[str, Any]) -> Iterator[Any]:
    yield from ({}, [], "text", None, {"no_such_field": 1})
    for base in _plausible(document, schema):
        yield {**base, "no_such_field": 1}
        for name, prop in schema["properties"].items():
            for value in _bad_values(_types(document, prop)):
                yield {**base, name: value}
            yield {key: value for key, value in base.items() if key != name}


def _form_bodies(
    document: dict[str, Any], schema: dict[str, Any], stored: bytes
) -> Iterator[tuple[list[tuple[str, tuple[str, bytes]]], dict[str, str]]]:
    """(files, fields) pairs: every file part given (a file that is not data, and one
    whose content is stored already), one field spoiled at a time."""
    properties = schema["properties"]
    binary = [name for name, prop in properties.items() if _types(document, prop) == {"binary"}]
    yield [], {}
    for content in (b"not a data file\n", stored):
        files = [(name, (f"{name}.arff", content)) for name in binary]
        yield files, {}
        for name, prop in properties.items():
            for value in _form_values(_types(document, prop)):
                yield files, {name: value}


def _operations(document: dict[str, Any]) -> Iterator[tuple[str, str, str, dict[str, Any]]]:
    """(method, path, media type, body schema) of every operation with a body."""
    for path, operations in document["paths"].items():
        for method, operation in operations.items():
            content = operation.get("requestBody", {}).get("content", {})
            for media, described in content.items():
                if media in ("application/json", "multipart/form-data"):
                    schema = _resolve(document, described["schema"])
                    if "anyOf" in schema:  # an optional body: its object
                        options = [_resolve(document, option) for option in schema["anyOf"]]
                        schema = next(o for o in options if o.get("type") != "null")
                    yield method, path, media, schema


def _prepare(server: Server, tmp_path: Path) -> bytes:
    """A data set ``touch`` and a model ``touch-nb``, so that names resolve and bodies reach
    the rules behind the look-ups."""
    for name, seed in (("spare", 1), ("touch", 0)):
        path = touch_arff(tmp_path / f"{name}.arff", n=60, seed=seed)
        with path.open("rb") as handle:
            sent = server.client.post("/api/datasets", files={"file": (path.name, handle)})
            assert sent.status_code == 201, sent.text
    trained = server.client.post(
        "/api/models",
        json={"dataset": "touch", "classifier": "nb", "target": "gesture", "name": "touch-nb"},
    )
    assert trained.status_code == 202, trained.text
    job = server.wait_for(f"/api/jobs/{trained.json()['job']}", finished)
    assert job["status"] == "done", job
    return path.read_bytes()


def _problem(response: httpx.Response) -> str | None:
    """What is wrong with an answer: a 500, an error that is not the JSON error body, or a
    message with a CLI word; ``None`` when nothing is."""
    if response.status_code < 400:
        return None
    if response.status_code >= 500:
        return f"{response.status_code}: {response.text[:300]}"
    try:
        message = response.json()["error"]["message"]
    except (ValueError, KeyError, TypeError):
        return f"{response.status_code}, not the error body: {response.text[:300]}"
    if CLI_WORDS.search(message):
        return f"{response.status_code}: {message}"
    return None


def test_no_error_names_a_cli_flag_or_command(sqlite_server: Server, tmp_path: Path) -> None:
    stored = _prepare(sqlite_server, tmp_path)
    document = sqlite_server.client.get("/openapi.json").json()
    problems: list[str] = []
    sent = 0
    operations = list(_operations(document))
    assert {(method, path) for method, path, _, _ in operations} >= {
        ("post", "/api/models"),
        ("post", "/api/models/{model_ref}/predict"),
        ("post", "/api/datasets"),
        ("post", "/api/datasets/recordings"),
        ("post", "/api/runs"),
    }
    for method, path, media, schema in operations:
        url = re.sub(r"\{(\w+)\}", lambda match: PATH_VALUES[match.group(1)], path)
        if media == "application/json":
            requests: Iterator[dict[str, Any]] = (
                {"content": json.dumps(body), "headers": {"content-type": "application/json"}}
                for body in _json_bodies(document, schema)
            )
        else:
            requests = (
                {"files": files or None, "data": fields}
                for files, fields in _form_bodies(document, schema, stored)
            )
        for request in requests:
            response = sqlite_server.client.request(method.upper(), url, **request)
            sent += 1
            if path.endswith("/rename") and response.is_success:
                back = {"name": PATH_VALUES["dataset"]}
                renamed = response.json()["name"]
                assert sqlite_server.client.post(
                    f"/api/datasets/{renamed}/rename", json=back
                ).is_success
            problem = _problem(response)
            if problem is not None:
                shown = request.get("content") or request.get("data")
                problems.append(f"{method.upper()} {path} {shown!s:.200}: {problem}")
    assert sent > 200
    assert problems == [], "\n".join(problems)
