"""A route FastAPI documents but does not drive, for the one request where FastAPI's own work
costs more than the answer: a prediction of a few instances.

For every request FastAPI solves the route's dependencies (the service, the API key header,
the path), parses the JSON body in Python and validates it again in pydantic; for a
one-instance prediction of a logistic model that is more CPU time than the prediction
(measured with ``perf/serve.py``).  :class:`DirectRoute` keeps the route's OpenAPI
description (its body, response model, path parameters and the API key header) and answers
with a handler that does the same things directly: the API key and role check of every
protected route (:func:`app.api.deps.check_api_key`), the body validated from its bytes in
one pass (``model_validate_json``), errors raised as FastAPI raises them, so the service's
error handlers answer them as for any route.  In front of the validation, the body's
limited lists are counted as they are decoded (:mod:`app.api.counting`): a body over a
limit is refused at the item that passes it, not after all of them are validated.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable, Coroutine
from dataclasses import dataclass
from typing import Any

from fastapi.exceptions import RequestValidationError
from fastapi.routing import APIRoute
from pydantic import BaseModel, ValidationError
from starlette.requests import Request
from starlette.responses import Response

from touchbench.app.api.counting import check_counts, limited_lists
from touchbench.app.api.deps import (
    action_of,
    check_api_key,
    get_service,
    needed_role,
    require_api_key,
)

#: The dependencies a direct route knows how to provide.
_SUPPORTED = {get_service, require_api_key}


@dataclass(frozen=True)
class _Plan:
    """How to call the endpoint: its path parameters (strings), its body parameter and
    model (with its lists' limits), and the parameters that receive the service."""

    path: tuple[str, ...]
    body: str
    model: type[BaseModel]
    service: tuple[str, ...]
    lists: dict[str, int]


class DirectRoute(APIRoute):
    """An ``APIRoute`` whose requests skip FastAPI's per-request machinery.

    The endpoint must be ``async``, return a ``Response`` and take only string path
    parameters, one pydantic body and the service (``ServiceDep``); the handler always
    checks the API key, as every ``/api`` route does (``include_router(...,
    dependencies=[Depends(require_api_key)])``).  Anything else is refused when the route is
    built, so that nothing a later change declares on the route is silently skipped.
    """

    def get_route_handler(self) -> Callable[[Request], Coroutine[Any, Any, Response]]:
        plan = _plan(self)
        endpoint = self.endpoint
        template = self.path

        async def handle(request: Request) -> Response:
            service = await get_service(request)
            check_api_key(
                service.settings,
                request.headers.get("x-api-key"),
                needed_role(request.method, template),
                action=action_of(request),
            )
            arguments: dict[str, Any] = {name: request.path_params[name] for name in plan.path}
            arguments[plan.body] = await _body(
                request, plan, max_keys=service.settings.max_attributes
            )
            arguments.update(dict.fromkeys(plan.service, service))
            response = await endpoint(**arguments)
            if not isinstance(response, Response):
                raise TypeError(f"{endpoint.__name__} must return a Response")
            return response

        return handle


def _plan(route: APIRoute) -> _Plan:
    dependant = route.dependant
    where = f"DirectRoute {sorted(route.methods or ())} {route.path}"
    if not inspect.iscoroutinefunction(route.endpoint):
        raise TypeError(f"{where}: the endpoint must be async")
    if dependant.query_params or dependant.header_params or dependant.cookie_params:
        raise TypeError(f"{where}: query, header and cookie parameters are not supported")
    if len(dependant.body_params) != 1:
        raise TypeError(f"{where}: the endpoint takes exactly one body")
    body = dependant.body_params[0]
    model = body.field_info.annotation
    if not (isinstance(model, type) and issubclass(model, BaseModel)):
        raise TypeError(f"{where}: the body must be a pydantic model")
    for parameter in dependant.path_params:
        if parameter.field_info.annotation is not str:
            raise TypeError(f"{where}: path parameter {parameter.name} must be a str")
    service = []
    for dependency in dependant.dependencies:
        if dependency.call not in _SUPPORTED:
            raise TypeError(f"{where}: cannot provide the dependency {dependency.call}")
        if dependency.name is not None:
            if dependency.call is not get_service:
                raise TypeError(f"{where}: parameter {dependency.name} must be the service")
            service.append(dependency.name)
    return _Plan(
        path=tuple(parameter.name for parameter in dependant.path_params),
        body=body.name,
        model=model,
        service=tuple(service),
        lists=limited_lists(model),
    )


async def _body(request: Request, plan: _Plan, *, max_keys: int) -> BaseModel:
    """The request's JSON body as the plan's model; a ``RequestValidationError`` (located
    under ``body``, as FastAPI locates them) when it is not JSON or not valid, or when a
    list holds more items than the model allows or an object in it more than ``max_keys``
    keys (counted first, so refused before the whole body is validated).

    Validated on the event loop even when large: pydantic holds the GIL throughout, so a
    worker thread would not let the loop run meanwhile (a large body holds other requests up
    as long either way).
    """
    content_type = request.headers.get("content-type", "")
    kind = content_type.split(";", 1)[0].strip().lower()
    if kind != "application/json" and not (
        kind.startswith("application/") and kind.endswith("+json")
    ):
        raise RequestValidationError(
            [
                {
                    "type": "content_type",
                    "loc": ("body",),
                    "msg": f"expected a JSON body (Content-Type: application/json), got "
                    f"{content_type or 'no Content-Type'}",
                }
            ]
        )
    body = await request.body()
    check_counts(body, plan.lists, max_keys=max_keys)
    try:
        return plan.model.model_validate_json(body)
    except ValidationError as error:
        problems = error.errors(include_url=False, include_input=False, include_context=False)
        raise RequestValidationError(
            [{**problem, "loc": ("body", *problem["loc"])} for problem in problems]
        ) from None
