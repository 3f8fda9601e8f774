"""Requests built from command-line options name the option of a refused field."""

from __future__ import annotations

import pytest
from pydantic import Field, model_validator

from touchbench.app.cli.requests import build_request, describe
from touchbench.app.errors import FieldError
from touchbench.app.schemas.base import Request


class _Example(Request):
    max_memory_mb: float | None = Field(default=None, gt=0, le=2**20)
    folds: int = Field(default=10, ge=2)
    budget: float | None = None
    tune: bool = False

    @model_validator(mode="after")
    def _budget_needs_tune(self) -> _Example:
        if self.budget is not None and not self.tune:
            raise FieldError("budget", "is only meaningful with `tune`")
        return self


def test_options_left_out_take_the_request_defaults() -> None:
    request = build_request(_Example, max_memory_mb=None, folds=None)
    assert (request.max_memory_mb, request.folds) == (None, 10)


@pytest.mark.parametrize(
    ("values", "shown"),
    [
        ({"max_memory_mb": 1e308}, "--max-memory: Input should be less than or equal to"),
        ({"max_memory_mb": float("inf")}, "--max-memory: Input should be a finite number"),
        ({"folds": 1}, "-k: Input should be greater than or equal to 2"),
        ({"budget": 3.0}, "--budget-minutes... wrong"),
    ],
)
def test_a_refused_field_is_named_by_its_option(values: dict[str, float], shown: str) -> None:
    options = {"max_memory_mb": "--max-memory", "folds": "-k"}
    with pytest.raises(FieldError) as refused:
        build_request(_Example, options, **values)
    if "budget" in values:  # a rule across fields: the other field is named as its option too
        assert refused.value.field == "budget"
        assert describe(refused.value) == "--budget: is only meaningful with --tune"
    else:
        assert describe(refused.value).startswith(shown)
        assert refused.value.field in values
