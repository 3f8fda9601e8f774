"""What an extraction answers: the stored data set and what happened to the events."""

from __future__ import annotations

from app.schemas.base import Schema


class ExtractionSummary(Schema):
    """One extraction (``extract --json`` and the API's recording-session upload job).

    ``events_found`` instances were made from the detected events, ``events_labelled``
    were kept, ``events_dropped`` fell outside every labelled interval; ``created`` is
    false when the same features were stored already (then ``id`` is that data set).
    """

    id: int
    name: str
    n_instances: int
    n_features: int
    targets: list[str]
    events_found: int
    events_labelled: int
    events_dropped: int
    warnings: list[str]
    created: bool
