"""The fragment with the form that uploads a recording session: the extractors and event
detectors from the service's own listing (:func:`app.services.extractors.list_extractors`,
what ``GET /api/extractors`` answers), each option an input with its type, default and
meaning; the fields of :class:`ExtractRequest` that an upload takes, from its schema."""

from __future__ import annotations

from fastapi import APIRouter
from fastapi.responses import HTMLResponse

from touchbench.app.schemas.extraction import DEFAULT_EXTRACTOR, ExtractorsRequest, ExtractRequest
from touchbench.app.services.extractors import list_extractors
from touchbench.app.web.rendering import render
from touchbench.app.web.request_form import form_fields

router = APIRouter(prefix="/fragments/recordings", include_in_schema=False)

#: The fields of :class:`ExtractRequest` that ``POST /api/datasets/recordings`` takes as
#: form fields besides the files, the extractor, the events and the options.
UPLOAD_FIELDS = (
    "name",
    "samplerate",
    "time_column",
    "time_unit",
    "fields",
    "segment",
    "topic",
    "channels",
    "sample_format",
)


@router.get("/form", response_class=HTMLResponse)
def recording_form() -> HTMLResponse:
    """Files, extractor and event detection with their options, and how to read the files."""
    fields = form_fields(ExtractRequest)
    return render(
        "fragments/recording_form.html.j2",
        listing=list_extractors(ExtractorsRequest()),
        default_extractor=DEFAULT_EXTRACTOR,
        extractor_help=fields["extractor"].help,
        events_help=fields["events"].help,
        reading=[fields[name] for name in UPLOAD_FIELDS if name in fields],
    )
