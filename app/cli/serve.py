"""``touchbench serve``: the REST service (uvicorn) on this machine."""

from __future__ import annotations

# Imports inside functions: start-up time: uvicorn, the settings and threadpoolctl load
# when the service starts, not when another command of the CLI runs.
import copy
import os
import socket
from typing import Annotated, Any

import typer

from touchbench.app.cli.state import get_state
from touchbench.app.environment import put_setting
from touchbench.app.trust import is_loopback


def register(app: typer.Typer) -> None:
    app.command("serve")(serve_command)


def serve_command(
    ctx: typer.Context,
    host: Annotated[
        str, typer.Option("--host", metavar="ADDRESS", help="Address to listen on.")
    ] = "127.0.0.1",
    port: Annotated[
        int, typer.Option("--port", metavar="PORT", min=1, max=65535, help="Port to listen on.")
    ] = 8000,
    workers: Annotated[
        int,
        typer.Option(
            "--workers", metavar="N", min=1, help="Service processes (each dispatches jobs)."
        ),
    ] = 1,
    insecure: Annotated[
        bool,
        typer.Option(
            "--insecure",
            help="Listen beyond loopback without an API key (anyone who reaches the port "
            "can read and change the store).",
        ),
    ] = False,
    predictions_only: Annotated[
        bool,
        typer.Option(
            "--predictions-only",
            help="Serve the robots' side only, beside a full service on the same store: "
            "models listed and described, their ONNX twins, predictions over REST and the live "
            "WebSocket, /healthz; no other route, no web page, no jobs.  A client flooding the "
            "full service with changes then does not slow the predictions.",
        ),
    ] = False,
    log_level: Annotated[
        str, typer.Option("--log-level", metavar="LEVEL", help="debug, info, warning, error.")
    ] = "info",
) -> None:
    """Serve the REST API (data sets, recording uploads, runs, leaderboards, models,
    predictions) at http://HOST:PORT/api, its documentation at /docs.

    Settings come from TOUCHBENCH_* variables: TOUCHBENCH_API_KEY or TOUCHBENCH_API_KEYS
    (required beyond loopback), TOUCHBENCH_ALLOWED_HOSTS (required beyond loopback),
    TOUCHBENCH_ALLOWED_ORIGINS, TOUCHBENCH_JOB_WORKERS, TOUCHBENCH_RUN_JOBS,
    TOUCHBENCH_DASK_SCHEDULER, TOUCHBENCH_MAX_UPLOAD_MB, TOUCHBENCH_MAX_TARGETS,
    TOUCHBENCH_MAX_ATTRIBUTES, TOUCHBENCH_RESUME_ON_START, TOUCHBENCH_PREDICTIONS_ONLY.
    Ctrl-C or SIGTERM stops it within a few seconds (exit 130 or 143), whatever it is
    computing.
    """
    import uvicorn

    from touchbench.app.cli.stopping import GRACE, serve
    from touchbench.app.settings import get_settings

    state = get_state(ctx)
    # The service's processes (uvicorn's workers, the job processes) read their settings
    # from the environment: the store the CLI was given goes there.
    put_setting("database_url", state.database_url)
    if predictions_only:
        put_setting("predictions_only", "1")
    get_settings.cache_clear()
    settings = get_settings()  # a value a setting refuses: one line, exit 2
    settings.check_trust()  # a bad key, host or origin: one line, exit 2
    if not settings.keyring and not is_loopback(host) and not insecure:
        raise typer.BadParameter(
            f"{host} is reachable from other machines and TOUCHBENCH_API_KEY is not set: set "
            "a key, listen on 127.0.0.1, or pass --insecure",
            param_hint="--host",
        )
    if not settings.allowed_hosts.strip() and not is_loopback(host):
        raise typer.BadParameter(
            f"{host} is reachable from other machines and TOUCHBENCH_ALLOWED_HOSTS is not set: "
            "name the host names or addresses clients reach the service by "
            "(comma-separated), or listen on 127.0.0.1",
            param_hint="--host",
        )
    _check_port(host, port)
    state.store  # noqa: B018 (open and migrate the store once, before the workers start)
    pin_native_threads()
    options: dict[str, Any] = {
        "factory": True,
        "host": host,
        "port": port,
        "workers": workers,
        "log_level": log_level,
        "log_config": _log_config(log_level),
        "proxy_headers": False,
        "server_header": False,
        "timeout_graceful_shutdown": GRACE,  # a request computing does not hold a stop
    }
    serve(uvicorn.Config("touchbench.app.main:create_app", **options))


#: Variables that set the thread count of numpy's BLAS and of OpenMP (scikit-learn, xgboost).
NATIVE_THREADS = ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "BLIS_NUM_THREADS", "OMP_NUM_THREADS")


def pin_native_threads() -> None:
    """One BLAS and OpenMP thread in this process and the workers it starts, unless one of
    :data:`NATIVE_THREADS` is set (then the environment decides).

    A service worker answers one prediction at a time: a team of native threads in each
    would only contend for the cores the other workers and the job processes use.
    Libraries loaded from now on read the variables; those loaded already (numpy's BLAS)
    are limited through threadpoolctl.
    """
    if any(name in os.environ for name in NATIVE_THREADS):
        return
    for name in NATIVE_THREADS:
        os.environ[name] = "1"
    from threadpoolctl import threadpool_limits

    threadpool_limits(1)


def _log_config(level: str) -> dict[str, Any]:
    """uvicorn's logging, and the service's own log (``touchbench.*``: which key made each
    change of state, unexpected errors) through uvicorn's handler at ``level``; without
    the traceback of a request cancelled to stop (:class:`app.cli.stopping.CancelledByStop`)."""
    from uvicorn.config import LOGGING_CONFIG

    config = copy.deepcopy(LOGGING_CONFIG)
    config.setdefault("filters", {})["cancelled_by_stop"] = {
        "()": "touchbench.app.cli.stopping.CancelledByStop"
    }
    config["loggers"]["uvicorn.error"]["filters"] = ["cancelled_by_stop"]
    config["loggers"]["touchbench"] = {
        "handlers": ["default"],
        "level": level.upper(),
        "propagate": False,
    }
    return config


def _check_port(host: str, port: int) -> None:
    """Refuse, in one line, an address the service could not listen on (a port another
    process holds), before uvicorn starts and answers it with its log and exit status 3.

    The probe binds as uvicorn does (``SO_REUSEADDR``), so a port left in TIME_WAIT by a
    service that just stopped is not refused.
    """
    try:
        addresses = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM, flags=socket.AI_PASSIVE)
    except socket.gaierror as error:
        raise typer.BadParameter(f"{host}: {error.strerror}", param_hint="--host") from None
    family, kind, protocol, _, address = addresses[0]
    with socket.socket(family, kind, protocol) as probe:
        probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            probe.bind(address)
        except OSError as error:
            raise typer.BadParameter(
                f"cannot listen on {host}:{port}: {error.strerror} (another process listens "
                "there: stop it or choose another port)",
                param_hint="--port",
            ) from None
