"""``GET /api/extractors``: the extractors and event detectors with their options."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Query

from touchbench.app.schemas.extraction import ExtractorList, ExtractorsRequest

router = APIRouter(prefix="/api/extractors", tags=["extraction"])


@router.get("", response_model=ExtractorList)
def extractors(
    samplerate: Annotated[float | None, Query(gt=0, le=1e9)] = None,
) -> ExtractorList:
    """Every extractor and event detector with each option's type, default and meaning
    (the same object as ``touchbench extractors --json``); with ``samplerate``, the
    defaults that depend on the sample rate computed for it."""
    # imported on first use: the extractors' modules load SciPy's signal tools and
    # scikit-learn, which the service's start-up does not otherwise need
    from touchbench.app.services.extractors import list_extractors

    return list_extractors(ExtractorsRequest(samplerate=samplerate))
