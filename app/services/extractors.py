"""The extractors and event detectors as data: every option with its type, default and
meaning (``touchbench extractors``, ``GET /api/extractors``)."""

from __future__ import annotations

# Imports inside functions: start-up time: the extractors and detectors import scipy.signal
# and scikit-learn, which the service loads with the first listing, not before it answers.
from typing import Any

from touchbench.app.schemas.extraction import (
    EventsInfo,
    ExtractorInfo,
    ExtractorList,
    ExtractorsRequest,
    OptionInfo,
)
from touchbench.features.options import Option


def list_extractors(request: ExtractorsRequest) -> ExtractorList:
    """Every extractor and event detector with its options; the defaults that depend on
    the sample rate computed at ``request.samplerate`` when it is given."""
    from touchbench.features.events import EVENT_KINDS
    from touchbench.features.extractors import EXTRACTORS

    rate = request.samplerate
    return ExtractorList(
        samplerate=rate,
        extractors=[
            ExtractorInfo(
                name=name,
                description=kind.description,
                default_events=kind.default_events,
                default_segment=kind.default_segment,
                samplerates=None if kind.samplerates is None else list(kind.samplerates),
                min_samplerate=kind.min_samplerate,
                min_channels=kind.min_channels,
                options=[_option(option, rate) for option in kind.options],
            )
            for name, kind in EXTRACTORS.items()
        ],
        events=[
            EventsInfo(
                name=name,
                description=kind.description,
                options=[_option(option, rate) for option in kind.options],
            )
            for name, kind in EVENT_KINDS.items()
        ],
    )


def _option(option: Option, samplerate: float | None) -> OptionInfo:
    computed = None
    if option.at_rate is not None and samplerate is not None:
        computed = _json(option.at_rate(samplerate))
    return OptionInfo(
        name=option.name,
        type=option.kind,
        default=_json(option.default),
        default_text=option.default_text,
        meaning=option.help,
        at_rate=computed,
    )


def _json(value: Any) -> Any:
    """Tuples (frequency bands) as lists."""
    if isinstance(value, tuple | list):
        return [_json(item) for item in value]
    return value
