"""Long work the service queues instead of doing in a request: benchmark runs (the runs table
is their queue), extraction of an uploaded recording session, training a model.

The request stores what is asked (``queued``) and answers at once; a dispatcher
(:mod:`app.jobs.dispatcher`) hands each queued item to a worker process, which claims it
and calls :func:`execute_job` or :func:`app.services.runs.execute_run`.
"""

from __future__ import annotations

import shutil
import socket
from pathlib import Path
from typing import Any

from app.errors import USER_ERRORS, AppError
from app.schemas.jobs import JobSchema
from app.store.database import Store
from app.store.jobs import claim_job, create_job, finish_job, get_job

#: Statuses from which a run can be put back in the queue.


def submit_extraction(
    store: Store,
    folder: Path,
    recordings: list[str],
    *,
    labels: str | None,
    options: dict[str, Any],
) -> JobSchema:
    """Queue the extraction of recordings saved in ``folder`` (deleted when the job ends).

    Parameters
    ----------
    folder : Path
        Holds the uploaded files; only a worker on this host can reach it.
    recordings : list of str
        File names in ``folder``.
    labels : str or None
        The labels CSV's file name in ``folder``.
    options : dict
        ``extractor``, ``events``, ``name``, ``samplerate``, ``segment``.
    """
    return create_job(
        store,
        "extract",
        {
            "host": socket.gethostname(),
            "folder": str(folder),
            "recordings": recordings,
            "labels": labels,
            **options,
        },
    )


def submit_training(store: Store, params: dict[str, Any]) -> JobSchema:
    """Queue training: ``{"dataset", "classifier", "target", "name", "seed"}`` or
    ``{"run", "name"}`` (the run's best classifier)."""
    return create_job(store, "train", {**params, "host": socket.gethostname()})


def execute_job(store: Store, job_id: int) -> JobSchema | None:
    """Claim and carry out a queued job; ``None`` if another process claimed it first.

    Bad input (a recording that cannot be read, an unknown classifier) ends the job
    ``failed`` with the same one-line message the CLI prints; the job's upload folder is
    removed either way.
    """
    job = get_job(store, job_id)
    if not claim_job(store, job.id):
        return None
    try:
        if job.kind == "extract":
            result = _extract(store, job.params)
        elif job.kind == "train":
            result = _train(store, job.params)
        else:
            raise AppError(f"unknown job kind '{job.kind}'")
    except USER_ERRORS as error:
        finish_job(store, job.id, "failed", error=str(error))
    except KeyboardInterrupt:
        finish_job(store, job.id, "interrupted", error="interrupted")
        raise
    except Exception as error:
        finish_job(store, job.id, "failed", error=f"unexpected {type(error).__name__}: {error}")
    else:
        finish_job(store, job.id, "done", result=result)
    finally:
        if job.kind == "extract":
            shutil.rmtree(job.params.get("folder", ""), ignore_errors=True)
    return get_job(store, job.id)


def _extract(store: Store, params: dict[str, Any]) -> dict[str, Any]:
    from app.services.extraction import extract_and_store

    folder = Path(params["folder"])
    summary = extract_and_store(
        store,
        [folder / name for name in params["recordings"]],
        labels=folder / params["labels"] if params.get("labels") else None,
        extractor=params.get("extractor") or "uc3m-audio",
        events=params.get("events"),
        name=params.get("name"),
        samplerate=params.get("samplerate"),
        segment=params.get("segment"),
        topic=params.get("topic"),
    )
    result = summary.to_json()
    return {"dataset_id": result["id"], **result}


def _train(store: Store, params: dict[str, Any]) -> dict[str, Any]:
    from app.services.models import train, train_best

    if params.get("run") is not None:
        model = train_best(store, params["run"], name=params.get("name"))
    else:
        model = train(
            store,
            str(params["dataset"]),
            str(params["classifier"]),
            targets=[params["target"]] if params.get("target") else None,
            name=params.get("name"),
            seed=int(params.get("seed") or 0),
        )
    return {"model_id": model.id, **model.to_json()}
