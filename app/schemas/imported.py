"""Importing WEKA Experimenter's results as a run: the request."""

from __future__ import annotations

from pathlib import Path

from pydantic import Field

from touchbench.app.schemas.base import Request


class ImportResultsRequest(Request):
    """The CLI's ``import-results`` and ``POST /api/runs/import-results``: a WEKA
    Experimenter results file (InstanceResultListener ARFF) stored as a finished run."""

    file: Path = Field(description="The results ARFF file to read.")
    name: str | None = Field(
        default=None,
        min_length=1,
        max_length=200,
        description="What the run is called in listings (default: 'WEKA' and the file's name).",
    )
    dataset: str | None = Field(
        default=None,
        min_length=1,
        max_length=200,
        description="The stored data set the results are of, by name or id (default: the one "
        "whose relation the file's Key_Dataset names, when exactly one has it).",
    )
    target: str | None = Field(
        default=None,
        min_length=1,
        max_length=200,
        description="The target the schemes predicted (default: the data set's only target, "
        "or the one WEKA's Remove filter in Key_Dataset left).",
    )
    source_name: str | None = Field(
        default=None,
        max_length=255,
        description="The name the user knows the file by (an upload's file name): what "
        "messages call the file.",
    )
