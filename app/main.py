"""The touchbench service: wiring only (settings, store, dispatcher, the JSON API, the web
page), or, with ``predictions_only``, the prediction routes alone (no dispatcher, no page).

``uvicorn --factory app.main:create_app`` or ``touchbench serve``.
"""

from __future__ import annotations

import logging
import sys
import threading
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from importlib import metadata

from fastapi import Depends, FastAPI

from touchbench.app.api import main as api
from touchbench.app.api.deps import PredictionPlacement, Service, require_api_key
from touchbench.app.api.stopping import CutByStop
from touchbench.app.api.trust import Cors, Trust
from touchbench.app.jobs.dispatcher import Dispatcher
from touchbench.app.redaction import install as hide_keys_in_logs
from touchbench.app.schemas.status import Status
from touchbench.app.services.model_cache import ModelCache
from touchbench.app.settings import Settings, get_settings
from touchbench.app.store.database import Store
from touchbench.app.store.jobs import mark_lost_jobs
from touchbench.app.store.runs import finish_run, get_run, mark_lost_runs
from touchbench.app.web.site import install as install_web_page

#: Seconds a thread holds the GIL while another waits for it (Python's default: 0.005).  A
#: page's rendering runs in a worker thread; a prediction on the event loop waits this long
#: for the GIL at each of its steps (reading the request, predicting, answering) while a
#: client asks for pages back to back.  Shorter, a prediction is barely delayed by them.
SWITCH_INTERVAL = 0.0005

log = logging.getLogger("touchbench.service")


def _warm_up() -> None:
    """Import the machine-learning stack in the background, so that start-up is quick and
    the first prediction does not pay for the imports."""
    import touchbench.app.services.models
    import touchbench.benchmark.model  # noqa: F401


def _recover(store: Store, *, resume: bool) -> None:
    """Mark what a dead process left running (runs, jobs) as lost; with ``resume``, put its
    interrupted runs back in the queue (not those being cancelled)."""
    lost = mark_lost_runs(store)
    mark_lost_jobs(store)
    if resume:
        for run_id in lost:
            if get_run(store, run_id).status == Status.INTERRUPTED:
                finish_run(store, run_id, Status.QUEUED)


def create_app(settings: Settings | None = None) -> FastAPI:
    """The FastAPI application for ``settings`` (default: from the environment).

    Raises
    ------
    app.settings.SettingsError
        A key, allowed host or allowed origin cannot be used.
    """
    settings = settings or get_settings()
    settings.check_trust()
    hide_keys_in_logs(key.secret.decode() for key in settings.keyring)

    @asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        # scikit-learn (and with it scipy.stats and pandas) loads here, in one thread, before
        # the first request: its modules import one another in cycles, and two request
        # threads importing it at once from different modules (a run's plan through the
        # catalogue, a prediction through a model) meet importlib's deadlock detection, which
        # hands one of them a half-initialised module (ImportError, answered 500).
        import sklearn  # noqa: F401

        switch_interval = sys.getswitchinterval()
        sys.setswitchinterval(SWITCH_INTERVAL)
        store = Store(settings.database_url)
        dispatches = not settings.predictions_only  # a predictions-only process never does
        if dispatches:
            _recover(store, resume=settings.resume_on_start)
        settings.work_dir.mkdir(parents=True, exist_ok=True)
        dispatcher = Dispatcher(store, settings)
        models = ModelCache(settings.model_cache)
        placement = PredictionPlacement(models.known)
        app.state.service = Service(settings, store, dispatcher, models, placement)
        if dispatches:
            dispatcher.start()
        else:
            log.info("serving predictions only; a full service on the store answers the rest")
        if settings.warm_up:
            threading.Thread(target=_warm_up, daemon=True, name="warm-up").start()
        try:
            yield
        finally:
            if dispatches:
                dispatcher.stop()
            app.state.service.placement.close()
            store.dispose()
            sys.setswitchinterval(switch_interval)

    app = FastAPI(
        title="touchbench",
        version=metadata.version("touchbench"),
        summary=(
            "Benchmark classifiers for robot touch sensing: data sets, recording-session "
            "uploads, cross-validation runs with WEKA's statistics, models and live "
            "predictions."
        ),
        lifespan=lifespan,
    )
    api.install(app, settings)
    if not settings.predictions_only:
        install_web_page(app, dependencies=[Depends(require_api_key)])
    if settings.origins:  # CORS stays closed unless origins are listed
        app.add_middleware(
            Cors,
            allow_origins=sorted(settings.origins),
            allow_methods=["GET", "POST", "PUT", "PATCH", "DELETE"],
            allow_headers=["X-API-Key", "Content-Type"],
        )
    # a request for another host name or from a foreign page goes no further
    app.add_middleware(Trust, hosts=settings.hosts, origins=settings.origins)
    app.add_middleware(CutByStop)  # outermost: whatever a stop cuts short is answered 503
    return app
