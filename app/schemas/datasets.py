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


def parse_names(text: str) -> list[str]:
    """``"trial, time"`` -> ``["trial", "time"]``: comma-separated column names (a name of
    digits stays a name)."""
    return [name.strip() for name in text.split(",") if name.strip()]


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
    groups: str | None = Field(
        default=None,
        min_length=1,
        max_length=200,
        description="The column that names each instance's group (the object grasped, the "
        "subject, the session): kept as the instances' groups, never as a feature.",
    )
    ignore: list[str] = Field(
        default_factory=list,
        max_length=10_000,
        description="Columns left out of the data set (comma-separated as text).",
    )

    @field_validator("targets", mode="before")
    @classmethod
    def _targets_text(cls, value: Any) -> Any:
        """Targets written as text (``"2"``, ``"-2"``, ``"a,b"``), as an option or a form
        field gives them."""
        return parse_targets(value) if isinstance(value, str) else value

    @field_validator("ignore", mode="before")
    @classmethod
    def _ignore_text(cls, value: Any) -> Any:
        """Ignored columns written as text (``"trial,time"``), as an option or a form field
        gives them."""
        return parse_names(value) if isinstance(value, str) else value


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


class GroupsDescription(Schema):
    """The groups of a data set's instances: folds grouped by them keep each group on one
    side, and leave-one-group-out tests one group at a time."""

    count: int = Field(description="How many distinct groups the instances fall into.")
    column: str | None = Field(
        description="The column of the imported file that named them; null for an extracted "
        "data set, whose groups are the recordings its instances come from."
    )


class ImportResult(Schema):
    """What ``touchbench import`` did.

    ``created`` is ``False`` when the file's content was stored before (``action`` is then
    ``"already stored"`` and the fields describe that data set); ``notes`` say what a user
    should know: targets that are numeric (regression), CSV columns typed as nominal
    because of a few words among numbers, columns left out.
    """

    id: int
    name: str
    n_instances: int
    n_features: int
    targets: list[str]
    created: bool
    action: Literal["imported", "already stored"]
    notes: list[str]
    groups: GroupsDescription | None = None


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
    groups: GroupsDescription | None = None


class RenameRequest(Request):
    """``POST /api/datasets/{id}/rename`` and the CLI's ``rename``: a data set's new name."""

    name: DatasetName = Field(description="The new name.")


class RenameResult(Schema):
    """A data set's new name and the one it had."""

    id: int
    name: str
    previous_name: str
