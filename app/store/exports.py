"""A model's twins in other formats (``model_exports``): ONNX graphs checked against the
model before they were written, kept with their sha256 and verified on every load; and the
jobs that make them, one per model and format at a time."""

from __future__ import annotations

import hashlib
from dataclasses import dataclass

from sqlalchemy import delete, select
from sqlalchemy.orm import Session

from touchbench.app.errors import AppError
from touchbench.app.schemas.status import FINAL, Status
from touchbench.app.store.database import Store
from touchbench.app.store.models import held_version
from touchbench.app.store.tables import JobRow, ModelExportRow

#: The formats a twin may have.
FORMATS = ("onnx",)
#: The kind of the jobs that make twins (their params: the model's id and the format).
EXPORT_JOB = "export"


@dataclass(frozen=True)
class ExportInfo:
    model_id: int
    format: str
    sha256: str
    size_bytes: int


def save_export(store: Store, model_id: int, format: str, data: bytes) -> ExportInfo:
    """Store (or replace) a model's twin in ``format``."""
    digest = hashlib.sha256(data).hexdigest()
    with store.session() as session:
        session.execute(
            delete(ModelExportRow).where(
                ModelExportRow.model_id == model_id, ModelExportRow.format == format
            )
        )
        session.add(
            ModelExportRow(
                model_id=model_id, format=format, sha256=digest, size_bytes=len(data), data=data
            )
        )
    return ExportInfo(model_id, format, digest, len(data))


def export_digest(store: Store, model_id: int, format: str) -> str | None:
    """The sha256 of a model's twin in ``format``, None without one (the bytes are not
    read)."""
    with store.session() as session:
        return session.scalars(
            select(ModelExportRow.sha256).where(
                ModelExportRow.model_id == model_id, ModelExportRow.format == format
            )
        ).first()


def load_export(store: Store, model_id: int, format: str) -> bytes | None:
    """A model's twin in ``format``, its bytes checked against their sha256; None without
    one.

    Raises
    ------
    AppError
        The bytes differ from their recorded digest (damage in the store).
    """
    with store.session() as session:
        row = session.get(ModelExportRow, (model_id, format))
        if row is None:
            return None
        data, recorded = bytes(row.data), row.sha256
    actual = hashlib.sha256(data).hexdigest()
    if actual != recorded:
        raise AppError(
            f"the stored {format} twin of model {model_id} does not match its recorded sha256 "
            f"({recorded[:12]}..., got {actual[:12]}...); export the model again"
        )
    return data


def queue_export(store: Store, model_id: int, format: str) -> tuple[int, bool]:
    """The job that makes the twin of the model ``model_id`` in ``format``: the one under
    way if there is one, else one queued now; and whether it was queued now.

    The model is held while this looks and queues (:func:`app.store.models.held_version`),
    so that requests at the same moment queue one job between them.

    Raises
    ------
    NotFoundError
        The model was deleted meanwhile.
    """
    with store.session() as session:
        held_version(session, model_id)
        under_way = _under_way(session, model_id, format)
        if under_way is not None:
            return under_way, False
        row = JobRow(
            kind=EXPORT_JOB, status=Status.QUEUED, params={"model": model_id, "format": format}
        )
        session.add(row)
        session.flush()
        return row.id, True


def export_under_way(store: Store, model_id: int, format: str) -> int | None:
    """The id of the job making the model's twin in ``format`` (queued, running or being
    cancelled), None if there is none."""
    with store.session() as session:
        return _under_way(session, model_id, format)


def _under_way(session: Session, model_id: int, format: str) -> int | None:
    unfinished = session.execute(
        select(JobRow.id, JobRow.params)
        .where(JobRow.kind == EXPORT_JOB, JobRow.status.not_in(FINAL))
        .order_by(JobRow.id)
    )
    for job_id, params in unfinished:
        if params.get("model") == model_id and params.get("format", "onnx") == format:
            return int(job_id)
    return None
