"""Extraction from recordings: its request, and what it answers (the stored data set and
what happened to the events)."""

from __future__ import annotations

# Imports inside functions: start-up time: the feature stack (numpy, scipy) loads when an
# extraction request is checked, not when a command that never extracts starts.
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, Literal

from pydantic import Field, field_validator, model_validator

from touchbench.app.errors import FieldError
from touchbench.app.schemas.base import Request, Schema
from touchbench.app.schemas.names import DatasetName

if TYPE_CHECKING:
    from touchbench.features.recipe import Recipe

#: Suffixes of CSV time series (their `fields` are columns, not a bag topic's fields).
CSV_SUFFIXES = frozenset({".csv", ".tsv", ".txt"})
#: The extractor used when none is asked for.
DEFAULT_EXTRACTOR = "uc3m-audio"
#: Recordings one extraction may read.
MAX_RECORDINGS = 1000
#: Field paths one bag topic may be read for.
MAX_FIELDS = 100
#: Channels of raw PCM audio (audio_common's AudioInfo holds them in a uint8).
MAX_CHANNELS = 255
#: A day, in seconds: the longest segment or event one may ask for.
MAX_SECONDS = 86400.0

#: A value of an extractor's or event detector's option (text as the CLI gives it).
OptionValue = str | float | int | bool | list[float] | list[list[float]]


class ExtractRequest(Request):
    """The CLI's ``extract`` and ``POST /api/datasets/recordings``: recordings and a labels
    file to a stored data set.

    The extractor, event detection and their options are checked when the request is made
    (:meth:`recipe`), so that nothing is read, queued or stored for a request that cannot
    succeed.  ``folder``, when set, is the folder on the service's host that holds an
    upload; ``recordings`` and ``labels`` are then the uploaded files' names in it.
    """

    recordings: list[Path] = Field(
        min_length=1, max_length=MAX_RECORDINGS, description="Recordings to read."
    )
    labels: Path | None = Field(
        default=None, description="Labels CSV: file,start,end,TARGET... or file,TARGET..."
    )
    extractor: str = Field(default=DEFAULT_EXTRACTOR, max_length=40)
    events: str | None = Field(
        default=None, max_length=20, description="snr, dbscan or none (default: the extractor's)."
    )
    options: dict[str, OptionValue] = Field(
        default_factory=dict,
        max_length=100,
        description="Options of the extractor and of the event detector, in one mapping.",
    )
    name: DatasetName | None = Field(default=None, description="Data set name.")
    samplerate: float | None = Field(
        default=None, gt=0, le=1e9, description="Sample rate (Hz) of files that carry none."
    )
    segment: float | None = Field(
        default=None, gt=0, le=MAX_SECONDS, description="Segment seconds for events 'none'."
    )
    topic: str | None = Field(
        default=None,
        max_length=200,
        description="Topic of ROS bags to read: its audio, or its numeric fields.",
    )
    fields: list[Annotated[str, Field(min_length=1, max_length=200)]] | None = Field(
        default=None,
        min_length=1,
        max_length=MAX_FIELDS,
        description=(
            "Numeric fields of `topic` (pdc, pac, wrench.force), or columns of CSV "
            "recordings (names or 1-based numbers), read as channels."
        ),
    )
    time_column: str | None = Field(
        default=None,
        min_length=1,
        max_length=200,
        description="The time column of CSV recordings, when it has none of the usual names.",
    )
    time_unit: Literal["auto", "s", "ms", "us", "ns"] = Field(
        default="auto",
        description="Unit of the time column of CSV recordings; auto: seconds or "
        "nanoseconds, told apart by magnitude.",
    )
    channels: int | None = Field(
        default=None,
        ge=1,
        le=MAX_CHANNELS,
        description="Channels of raw PCM audio in bags without an AudioInfo topic.",
    )
    sample_format: Literal["S16LE", "S32LE", "F32LE"] | None = Field(
        default=None,
        description="Sample format of raw PCM audio in bags without an AudioInfo topic.",
    )
    max_event: float | None = Field(
        default=None, ge=0.001, le=MAX_SECONDS, description="Longest event in seconds."
    )
    folder: Path | None = Field(
        default=None, description="The service's folder holding an upload's files."
    )

    @field_validator("sample_format", mode="before")
    @classmethod
    def _upper_case(cls, value: object) -> object:
        return value.strip().upper() if isinstance(value, str) else value

    @model_validator(mode="after")
    def _checked_recipe(self) -> ExtractRequest:
        # Fields of a bag belong to a topic; a CSV file's are its columns.
        csv_only = all(path.suffix.lower() in CSV_SUFFIXES for path in self.recordings)
        if self.fields and self.topic is None and not csv_only:
            raise FieldError("fields", "needs `topic`: the bag topic the fields belong to")
        self.recipe()
        return self

    def recipe(self) -> Recipe:
        """How instances are made, defaults filled in.

        Raises
        ------
        FieldError
            An unknown extractor or event detection, a segment length with events other
            than ``none``, an unknown option or a bad option value.
        """
        # Imported here for start-up time: the extractors load scipy and scikit-learn.
        from touchbench.features.errors import FeatureError
        from touchbench.features.events import EVENT_KINDS
        from touchbench.features.extractors import EXTRACTORS
        from touchbench.features.recipe import Recipe

        if self.extractor not in EXTRACTORS:
            raise FieldError(
                "extractor",
                f"unknown extractor '{self.extractor}' (known: {', '.join(EXTRACTORS)})",
            )
        events = self.events or EXTRACTORS[self.extractor].default_events
        if events not in EVENT_KINDS:
            raise FieldError(
                "events", f"unknown event detection '{events}' (known: {', '.join(EVENT_KINDS)})"
            )
        if self.segment is not None and events != "none":
            raise FieldError("segment", f"only applies to `events` 'none', not '{events}'")
        try:
            return Recipe.resolve(
                self.extractor,
                events=events,
                segment=self.segment,
                options=self.options,
                max_event=self.max_event,
            )
        except FeatureError as error:
            raise FieldError("options", str(error)) from None

    def recording_paths(self) -> list[Path]:
        """Where the recordings are read from (in ``folder`` for an upload)."""
        return [self._path(recording) for recording in self.recordings]

    def labels_path(self) -> Path | None:
        """Where the labels file is read from, if there is one."""
        return None if self.labels is None else self._path(self.labels)

    def _path(self, path: Path) -> Path:
        return path if self.folder is None else self.folder / path.name


class ExtractionSummary(Schema):
    """One extraction (``extract --json`` and the API's recording-session upload job).

    ``events_found`` instances were made from the detected events, ``events_labelled``
    were kept, ``events_dropped`` fell outside every labelled interval; ``created`` is
    false when the same features were stored already (then ``id`` is that data set).
    ``warnings`` say what was left out, ``notes`` what was done on the way (resampled
    stamps, defaults computed from the sample rate, label rows of other recordings).
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
    notes: list[str] = Field(default_factory=list)
    created: bool


class ExtractorsRequest(Request):
    """The CLI's ``extractors`` and ``GET /api/extractors``: the extractors and event
    detectors with their options; with a sample rate, the defaults that depend on it."""

    samplerate: float | None = Field(
        default=None, gt=0, le=1e9, description="Show the defaults computed for this rate (Hz)."
    )


class OptionInfo(Schema):
    """One option (``-O name=value``): its type, default and meaning.

    ``default`` is None when it is computed (``default_text`` says how); ``at_rate`` is
    the computed default at the request's sample rate, when it depends on the rate.
    """

    name: str
    type: str
    default: Any
    default_text: str | None
    meaning: str
    at_rate: Any = None


class EventsInfo(Schema):
    """An event detector (``--events NAME``) and its options."""

    name: str
    description: str
    options: list[OptionInfo]


class ExtractorInfo(Schema):
    """An extractor (``--extractor NAME``): what it makes, what it needs, its options."""

    name: str
    description: str
    default_events: str
    default_segment: float | None
    samplerates: list[float] | None
    min_samplerate: float
    min_channels: int
    options: list[OptionInfo]


class ExtractorList(Schema):
    """Every extractor and event detector (``extractors --json``, ``GET /api/extractors``)."""

    samplerate: float | None
    extractors: list[ExtractorInfo]
    events: list[EventsInfo]
