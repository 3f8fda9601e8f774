"""Response models of data sets: listings, imports, descriptions, renames."""

from __future__ import annotations

from datetime import datetime
from typing import Literal

from app.schemas.base import Schema


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


class RenameResult(Schema):
    """A data set's new name and the one it had."""

    id: int
    name: str
    previous_name: str
