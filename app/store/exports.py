"""A model's twins in other formats (``model_exports``): ONNX graphs checked against the
model before they were written, kept with their sha256 and verified on every load."""

from __future__ import annotations

import hashlib
from dataclasses import dataclass

from sqlalchemy import delete, select

from touchbench.app.errors import AppError
from touchbench.app.store.database import Store
from touchbench.app.store.tables import ModelExportRow

#: The formats a twin may have.
FORMATS = ("onnx",)


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
