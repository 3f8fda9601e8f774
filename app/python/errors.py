"""The client's exceptions: what the service answered, or why it could not answer.

Every error the service answers is JSON (``{"error": {"type", "message", "where"}}``,
:mod:`app.api.errors`); :func:`service_error` turns one into the exception of its status,
carrying the status, the service's kind of error, its message and the request's field it
names.  Failures below HTTP (no connection, a timeout) are :class:`ServiceUnreachableError` and
:class:`ServiceTimeoutError`, so that a caller catches the one tree, never httpx's.
"""

from __future__ import annotations

from typing import Any

#: The parts of a request an error's ``where`` may name before the field (FastAPI's
#: locations, and the service's own ``body.FIELD``).
_LOCATIONS = ("body", "query", "path", "form", "header")


class ServiceError(Exception):
    """An error from the service (or on the way to it).

    Attributes
    ----------
    status : int or None
        The HTTP status (``None``: no answer).
    kind : str
        The service's kind of error (``NotFoundError``, ``FieldError``, ``ValidationError``,
        ``Forbidden``...).
    message : str
        What is wrong, in one line, as the CLI would print it.
    where : str or None
        Where, as the service says it: ``body.folds``, a file and line, an attribute.
    field : str or None
        The request's field the error names (``folds``, ``classifiers.0``), when it names one.
    """

    def __init__(
        self, message: str, *, status: int | None = None, kind: str = "", where: str | None = None
    ) -> None:
        self.status = status
        self.kind = kind or type(self).__name__
        self.message = message
        self.where = where
        self.field = field_of(where)
        super().__init__(message)

    def __str__(self) -> str:
        status = f"{self.status} " if self.status is not None else ""
        where = f" [{self.where}]" if self.where else ""
        return f"{status}{self.kind}: {self.message}{where}"

    def __repr__(self) -> str:
        return (
            f"{type(self).__name__}(status={self.status!r}, kind={self.kind!r}, "
            f"message={self.message!r}, where={self.where!r})"
        )


class BadRequestError(ServiceError):
    """400, 413 or 422: the request is wrong; the message and field say how."""


class InvalidRequestError(BadRequestError):
    """422: a field of the request does not validate (``field`` names it)."""


class UnauthorizedError(ServiceError):
    """401: the service needs an API key."""


class ForbiddenError(ServiceError):
    """403: a wrong key, or a key whose role does not allow the request (read-only)."""


class NotFoundError(ServiceError):
    """404: no such data set, run, model or job."""


class ConflictError(ServiceError):
    """409: the request clashes with the store's state (a name taken, a run under way)."""


class ServerError(ServiceError):
    """5xx: the service failed (its log says why)."""


class ServiceUnreachableError(ServiceError):
    """No connection to the service (after the retries)."""


class ServiceTimeoutError(ServiceError):
    """The service did not answer in time."""


class WaitTimeoutError(ServiceError):
    """A run or a job did not finish within the time given to wait for it."""


_BY_STATUS: dict[int, type[ServiceError]] = {
    400: BadRequestError,
    401: UnauthorizedError,
    403: ForbiddenError,
    404: NotFoundError,
    409: ConflictError,
    413: BadRequestError,
    422: InvalidRequestError,
}


def field_of(where: str | None) -> str | None:
    """The request's field in a service's ``where`` (``body.folds`` -> ``folds``)."""
    if not where:
        return None
    head, _, rest = where.partition(".")
    return (rest or None) if head in _LOCATIONS else None


def service_error(status: int, body: Any, text: str = "") -> ServiceError:
    """The exception of an error answer: its status's class, with the JSON error's kind,
    message and where (a body that is not the service's JSON: its first line of text)."""
    kind, message, where = "", "", None
    detail = body.get("error") if isinstance(body, dict) else None
    if isinstance(detail, dict):
        kind = str(detail.get("type") or "")
        message = str(detail.get("message") or "")
        where = detail.get("where") if isinstance(detail.get("where"), str) else None
    if not message:
        first = text.strip().splitlines()[0] if text.strip() else ""
        message = first[:200] or f"HTTP {status}"
    cls = _BY_STATUS.get(status, ServerError if status >= 500 else ServiceError)
    return cls(message, status=status, kind=kind, where=where)
