"""The app's own errors, and the tuple of every error that means "bad input"."""

from __future__ import annotations

from benchmark.errors import BenchmarkError
from drivers.errors import DriverError
from features.errors import FeatureError


class AppError(Exception):
    """Bad input detected by the app layer (a dataset that does not exist, ...)."""


class NotFoundError(AppError):
    """A dataset, run or model that the store does not have."""


class ConflictError(AppError):
    """The request clashes with the store's state: a name taken, a run already running."""


#: Exceptions that mean the user's input is wrong: exit status 2 on the CLI, 4xx on the API.
USER_ERRORS: tuple[type[Exception], ...] = (AppError, BenchmarkError, FeatureError, DriverError)
