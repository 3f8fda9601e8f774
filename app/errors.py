"""The app's own errors, and the tuple of every error that means "bad input"."""

from __future__ import annotations

import os

from touchbench.benchmark.errors import BenchmarkError
from touchbench.drivers.errors import DriverError
from touchbench.features.errors import FeatureError


class AppError(Exception):
    """Bad input detected by the app layer (a dataset that does not exist, ...)."""


class NotFoundError(AppError):
    """A dataset, run or model that the store does not have."""


class ConflictError(AppError):
    """The request clashes with the store's state: a name taken, a run already running."""


class FieldError(AppError):
    """One field of a request is refused.

    The message says what is wrong in the request's own words and never names an adapter's
    spelling of the field: the CLI shows it as its option (``--max-memory: ...``), the API
    as the field's place in the body (``where: body.max_memory_mb``).  A rule across fields
    raises it for the field it refuses and names the others in backquotes (``only
    meaningful with `tune```), which the CLI shows as their options too.  Raised inside a
    request type's validator, it passes through pydantic unchanged.

    Parameters
    ----------
    field : str
        The field's name in the request type, dotted for a nested one (``instances.3``).
    message : str
        What is wrong with its value, e.g. ``must be at most 1048576 megabytes``.
    """

    def __init__(self, field: str, message: str) -> None:
        super().__init__(message)
        self.field = field
        self.message = message


#: Exceptions that mean the user's input is wrong: exit status 2 on the CLI, 4xx on the API.
USER_ERRORS: tuple[type[Exception], ...] = (AppError, BenchmarkError, FeatureError, DriverError)


def client_words(message: str, folder: str | None) -> str:
    """``message`` with the upload folder left out of its paths: the client knows its files
    by their names, and the service's folders are not its business."""
    if not folder:
        return message
    return message.replace(folder.rstrip(os.sep) + os.sep, "").replace(folder, "the upload")
