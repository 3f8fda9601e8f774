"""The base of every response model."""

from __future__ import annotations

import math
from datetime import UTC, datetime
from typing import Any

from pydantic import BaseModel, ConfigDict, ValidationError, field_validator

from touchbench.app.errors import FieldError


class Schema(BaseModel):
    """A response model: JSON-ready (``to_json``), NaN and infinities as ``null``, every
    time with its zone (the store keeps UTC; SQLite hands it back without the zone)."""

    model_config = ConfigDict(extra="forbid", ser_json_inf_nan="null")

    @field_validator("*", mode="after")
    @classmethod
    def _utc(cls, value: Any) -> Any:
        if isinstance(value, datetime) and value.tzinfo is None:
            return value.replace(tzinfo=UTC)
        return value

    def to_json(self) -> dict[str, Any]:
        """The plain JSON object (what ``--json`` prints and the API answers)."""
        return finite(self.model_dump(mode="json"))


class Request(BaseModel):
    """The base of every request type: one use case's input, its defaults, bounds and rules
    across fields said once.  The API takes it as its body, the CLI builds it from its
    options (:func:`app.cli.requests.build_request`), the service takes nothing else.

    Unknown fields are refused and numbers must be finite.
    """

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True)


def field_error(error: ValidationError) -> FieldError:
    """The first problem of a request's validation error, as a :class:`FieldError` (what
    the CLI and the Python API raise for a refused field)."""
    problem = error.errors()[0]
    field = ".".join(str(part) for part in problem.get("loc", ())) or "request"
    message = str(problem.get("msg", "invalid value"))
    return FieldError(field, message.removeprefix("Value error, "))


def finite(data: Any) -> Any:
    """``data`` with every NaN or infinite float replaced by ``None``, recursively."""
    if isinstance(data, float) and not math.isfinite(data):
        return None
    if isinstance(data, dict):
        return {key: finite(value) for key, value in data.items()}
    if isinstance(data, list | tuple):
        return [finite(value) for value in data]
    return data
