"""What routes depend on: the service's state (settings, store, dispatcher, the cache of loaded
models), the API key check with the keys' roles, and where a served prediction runs."""

from __future__ import annotations

import asyncio
import hmac
import logging
import threading
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import Annotated, TypeVar

from fastapi import Depends, Header, HTTPException, Query, Request, Response

from touchbench.app.jobs.dispatcher import Dispatcher
from touchbench.app.schemas.listing import Page
from touchbench.app.services.model_cache import ModelCache
from touchbench.app.settings import Role, Settings
from touchbench.app.store.database import Store

log = logging.getLogger("touchbench.api")


#: A prediction expected to take at most this many seconds of CPU time may run on the event
#: loop (see :meth:`PredictionPlacement.run`). Slower ones (large ensembles, many instances)
#: go to a worker thread.
INLINE_SECONDS = 0.005

Result = TypeVar("Result")


def request_size(instances: Sequence[Mapping[str, object]]) -> int:
    """The size of a prediction request, which its cost is taken to grow with: one per
    instance and one per attribute value.  Values count, not only instances: one instance
    carrying a million attributes the model does not know costs as much as thousands of
    ordinary ones."""
    return len(instances) + sum(len(instance) for instance in instances)


class PredictionPlacement:
    """Where a served prediction runs: on the event loop, or in this process's one
    prediction thread; it keeps how long each model's predictions take (:meth:`record`),
    which decides where the next one runs (:meth:`runs_inline`).

    Parameters
    ----------
    known : callable
        ``known(ref)``: the id of the model ``ref`` named last, without asking the store
        (:meth:`app.services.model_cache.ModelCache.known`), None if not loaded.
    """

    def __init__(self, known: Callable[[str], int | None]) -> None:
        self._known = known
        self._seconds: dict[int, float] = {}  # model id -> seconds per unit of size
        self._lock = threading.Lock()
        self._in_flight = 0  # predictions under way in this process (changed on the loop only)
        self._thread = ThreadPoolExecutor(1, thread_name_prefix="predict")

    async def run(self, ref: str, size: int, work: Callable[[], Result]) -> Result:
        """Run a prediction of ``size`` (:func:`request_size`), ``work()``, on the event
        loop or in this process's prediction thread.

        On the loop when the model is known to be quick (:meth:`runs_inline`) and no other
        prediction is under way in this process: a hop to a thread would cost more than the
        prediction (the GIL runs one of them at a time anyway). Otherwise in the one
        prediction thread, first come first served: slow models must not hold the loop up;
        predictions run back to back on the loop leave some clients waiting far longer than
        others; and predictions in many threads at once wait on each other for the GIL at
        every numpy call (``perf/serve.py`` measures both).
        """
        self._in_flight += 1
        try:
            await asyncio.sleep(0)  # requests that arrived with this one count themselves first
            if self._in_flight == 1 and self.runs_inline(ref, size):
                return work()
            return await asyncio.get_running_loop().run_in_executor(self._thread, work)
        finally:
            self._in_flight -= 1

    def close(self) -> None:
        """End the prediction thread (after the prediction it may be running)."""
        self._thread.shutdown(wait=True, cancel_futures=True)

    def runs_inline(self, ref: str, size: int) -> bool:
        """Whether a prediction of ``size`` (:func:`request_size`) with the model ``ref`` is
        known to be quick: the model is loaded and its recent predictions took under
        :data:`INLINE_SECONDS` of CPU time for that size."""
        model_id = self._known(ref)
        with self._lock:
            seconds = None if model_id is None else self._seconds.get(model_id)
        return seconds is not None and seconds * size <= INLINE_SECONDS

    def record(self, model_id: int, seconds: float, size: int) -> None:
        """Note that a prediction of ``size`` (:func:`request_size`) took ``seconds`` of its
        thread's CPU time (not wall time, which waits on other processes and on the GIL, and
        would keep a model measured in a thread looking slow); kept as a moving average."""
        per_unit = seconds / max(1, size)
        with self._lock:
            known = self._seconds.get(model_id)
            self._seconds[model_id] = per_unit if known is None else 0.8 * known + 0.2 * per_unit

    def forget(self, model_id: int) -> None:
        with self._lock:
            self._seconds.pop(model_id, None)


@dataclass
class Service:
    """Everything one service process holds."""

    settings: Settings
    store: Store
    dispatcher: Dispatcher
    models: ModelCache
    placement: PredictionPlacement

    def forget(self, model_id: int) -> None:
        """Drop what this process holds of the model ``model_id`` (deleted)."""
        self.models.forget(model_id)
        self.placement.forget(model_id)


# The dependencies below are ``async`` only so that FastAPI calls them on the event loop
# instead of a thread-pool hop each: none of them blocks.
async def get_service(request: Request) -> Service:
    service = request.app.state.service
    assert isinstance(service, Service), "create_app sets the service state"
    return service


async def get_store(service: Annotated[Service, Depends(get_service)]) -> Store:
    return service.store


async def require_api_key(
    request: Request,
    service: Annotated[Service, Depends(get_service)],
    x_api_key: Annotated[str | None, Header(description="The service's API key.")] = None,
) -> None:
    """401 without a key, 403 with a wrong one or one whose role does not allow the route
    (:func:`needed_role`); a change of state is logged with the key's name."""
    route = request.scope.get("route")
    template = getattr(route, "path", request.url.path)
    check_api_key(
        service.settings,
        x_api_key,
        needed_role(request.method, template),
        action=action_of(request),
    )


def action_of(request: Request) -> str:
    """``METHOD path`` for the log, with the path as sent (still percent-encoded, so that a
    name holding a line break cannot forge a line of the log)."""
    raw = request.scope.get("raw_path")
    path = raw.decode("latin-1") if isinstance(raw, bytes) else request.url.path
    return f"{request.method} {path}"


#: Routes a ``predict`` key may call besides every GET: predictions and uploads (the live
#: WebSocket checks its key itself, with the same role).  Any other change needs ``write``.
PREDICT_ROUTES = frozenset(
    {
        ("POST", "/api/models/{model_ref}/predict"),
        ("POST", "/api/models/{model_ref}/predict/file"),
        ("POST", "/api/datasets"),
        ("POST", "/api/datasets/recordings"),
        ("POST", "/api/live/recordings"),
    }
)


def needed_role(method: str, route: str) -> Role:
    """The role a key needs for ``method`` on the route whose path template is ``route``."""
    if method in ("GET", "HEAD"):
        return "read"
    return "predict" if (method, route) in PREDICT_ROUTES else "write"


class KeyRefused(Exception):  # noqa: N818 (a refusal, answered 401 or 403)
    """The request's key is missing (``status`` 401), wrong, or lacks the role (403)."""

    def __init__(self, status: int, message: str) -> None:
        super().__init__(message)
        self.status = status


def key_name(settings: Settings, given: str | None, role: Role) -> str | None:
    """The name of the key ``given`` when it allows ``role``; None when the service has no
    key.

    Every key is compared, each in constant time, so that the answer's timing does not
    tell how much of a key was right nor which key it was near; an empty key never matches.

    Raises
    ------
    KeyRefused
        401 without a key, 403 with a wrong one or one whose role is below ``role``.
    """
    keys = settings.keyring
    if not keys:
        return None
    if given is None:
        raise KeyRefused(401, "this service needs an API key in the X-API-Key header")
    sent = given.encode()
    found = None
    for key in keys:
        if hmac.compare_digest(sent, key.secret):
            found = key
    if found is None or not given:  # no key is empty (see app.settings.MIN_KEY_LENGTH)
        raise KeyRefused(403, "wrong API key")
    if not found.may(role):
        raise KeyRefused(
            403, f"the API key '{found.name}' is a {found.role} key; this needs a {role} key"
        )
    return found.name


def check_api_key(
    settings: Settings, given: str | None, role: Role, *, action: str | None = None
) -> None:
    """Raise the HTTP error of :func:`key_name`'s refusal; when ``action`` (``METHOD
    path``) changes state, log it with the key's name (never the key)."""
    try:
        name = key_name(settings, given, role)
    except KeyRefused as refused:
        headers = {"WWW-Authenticate": "X-API-Key"} if refused.status == 401 else None
        raise HTTPException(refused.status, str(refused), headers=headers) from None
    if action is not None and not action.startswith(("GET ", "HEAD ", "OPTIONS ")):
        log.info(
            "%s by key %s", action, "(none: the service has no key)" if name is None else repr(name)
        )


ServiceDep = Annotated[Service, Depends(get_service)]
StoreDep = Annotated[Store, Depends(get_store)]
#: Which rows of a listing to answer (``?offset=&limit=``, at most 1,000 rows).
PageDep = Annotated[Page, Query()]


def paginate(request: Request, response: Response, page: Page, total: int) -> None:
    """Say how many rows the listing has (``X-Total-Count``) and, when more follow this
    page, where the next page is (``Link: <...>; rel="next"``)."""
    response.headers["X-Total-Count"] = str(total)
    after = page.offset + page.limit
    if after < total:
        following = request.url.include_query_params(offset=after, limit=page.limit)
        response.headers["Link"] = f'<{following.path}?{following.query}>; rel="next"'
