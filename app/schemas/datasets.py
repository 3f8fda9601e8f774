"""Data sets: the import request, and listings, imports, descriptions, renames."""

from __future__ import annotations

from datetime import datetime
from pathlib import Path
from typing import Any, Literal

from pydantic import Field, field_validator

from touchbench.app.schemas.base import Request, Schema
from touchbench.app.schemas.names import DatasetName

FileFormat = Literal["arff", "csv"]


def parse_targets(text: str | None) -> int | list[str] | None:
    """``"2"`` -> 2 (first two), ``"-2"`` -> -2 (last two), ``"a,b"`` -> names."""
    if text is None or not text.strip():
        return None
    stripped = text.strip()
    digits = stripped.removeprefix("-")
    if digits.isascii() and digits.isdigit():  # not "²", which int() refuses
        return int(stripped)
    return [name.strip() for name in stripped.split(",") if name.strip()]


class ImportRequest(Request):
    """The CLI's ``import`` and ``POST /api/datasets``: an ARFF or CSV file to a data set."""

    file: Path = Field(description="The file to read.")
    name: DatasetName | None = Field(
        default=None, description="Name in the store (default: the file's stem)."
    )
    targets: int | list[str] | None = Field(
        default=None,
        description="N first attributes, -N last ones, or names (default: MEKA's -C header, "
        "else the last attribute).",
    )
    format: FileFormat | None = Field(
        default=None, description="File format (default: by the file's ending)."
    )
    source_name: str | None = Field(
        default=None,
        max_length=255,
        description="The name the user knows the file by (an upload's file name): it names "
        "the data set, is kept as its source and is what messages call the file.",
    )

    @field_validator("targets", mode="before")
    @classmethod
    def _targets_text(cls, value: Any) -> Any:
        """Targets written as text (``"2"``, ``"-2"``, ``"a,b"``), as an option or a form
        field gives them."""
        return parse_targets(value) if isinstance(value, str) else value


class DatasetSummary(Schema):
    """A stored data set as ``touchbench datasets --json`` lists it."""

    id: int
    name: str
    relation: str
    n_instances: int
    n_features: int
    targets: list[str]
    source: str | None
    sha256: str
    created_at: datetime


class DatasetList(Schema):
    """Every stored data set, oldest first."""

    datasets: list[DatasetSummary]


class ImportResult(Schema):
    """What ``touchbench import`` did.

    ``created`` is ``False`` when the file's content was stored before (``action`` is then
    ``"already stored"`` and the fields describe that data set); ``notes`` say what a user
    should know: targets that are numeric (regression), CSV columns typed as nominal
    because of a few words among numbers.
    """

    id: int
    name: str
    n_instances: int
    n_features: int
    targets: list[str]
    created: bool
    action: Literal["imported", "already stored"]
    notes: list[str]


class AttributeDescription(Schema):
    """One attribute: its role, kind, missing values, and labels or range."""

    name: str
    kind: str
    role: Literal["target", "feature"]
    missing: int
    values: list[str] | None = None
    min: float | None = None
    max: float | None = None


class DatasetDescription(Schema):
    """What ``touchbench show --json`` prints: schema, class distributions, missing values."""

    id: int
    name: str
    n_instances: int
    n_features: int
    targets: list[str]
    relation: str
    attributes: list[AttributeDescription]
    #: Instances per label of each nominal target.
    class_distribution: dict[str, dict[str, int]]
    missing_values: int
    notes: list[str]


class RenameRequest(Request):
    """``POST /api/datasets/{id}/rename`` and the CLI's ``rename``: a data set's new name."""

    name: DatasetName = Field(description="The new name.")


class RenameResult(Schema):
    """A data set's new name and the one it had."""

    id: int
    name: str
    previous_name: str
