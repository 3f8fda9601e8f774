"""Recordings and a labels file to a data set: drivers -> event detection -> extractor.

:func:`extract_dataset` reads every recording block by block through the streaming
engine (:class:`features.stream.FeatureStream`, so memory follows the longest event, not
the recording), finds its events, turns them into instances with the chosen extractor,
labels each instance from the labels CSV and
returns one :class:`~benchmark.dataset.Dataset` whose targets come first (a MEKA
``-C N`` relation), ready for the store.  Every problem is raised before anything is
returned: :class:`~benchmark.errors.DataFormatError` for the labels file (with its
line), :class:`~drivers.errors.DriverError` for a recording,
:class:`~features.errors.FeatureError` for what the extractor or detector cannot use.

The labels CSV is :mod:`app.services.labels`'s.  The data set's size is bounded
(:mod:`app.services.limits`) before the values are made: its targets when the labels file
is read, its attributes (a sequence counted as its channels) when the first recording
says its channels, and its values as the instances come, each refusal naming the input
that broke the bound.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from touchbench.app.schemas.extraction import ExtractionSummary, ExtractRequest
from touchbench.app.services.labels import (
    count_label_targets,
    few,
    label_instances,
    other_recordings,
    read_labels,
)
from touchbench.app.services.limits import (
    DatasetLimits,
    check_cells,
    check_dataset_size,
    read_limits,
)
from touchbench.app.store.database import Store
from touchbench.app.store.datasets import add_dataset, check_dataset_name, dataset_digest
from touchbench.benchmark.dataset import Attribute, Dataset, Schema
from touchbench.benchmark.errors import DataFormatError
from touchbench.drivers.replay import CSV_SUFFIXES, FileReplaySource
from touchbench.features.errors import FeatureError
from touchbench.features.extractors import Instances
from touchbench.features.recipe import Recipe


@dataclass
class ExtractionResult:
    """A data set extracted from recordings, with the counts the CLI reports.

    Parameters
    ----------
    dataset : Dataset
        Targets first, then features; ``groups`` is each instance's recording file name
        and ``meta`` holds ``source``, ``start``, ``end`` (seconds) and the extractor's
        details.
    n_events : int
        Instances the extractor made from the detected events, before labelling.
    n_labelled : int
        Of those, the instances kept (all of them without a labels file).
    n_dropped : int
        Instances outside every labelled interval, or of a recording without labels.
    warnings : list of str
        What was left out and why, one line each.
    recipe : dict
        How the instances were made (:meth:`features.recipe.Recipe.to_json`) with the
        recordings' ``samplerate``, ``n_channels`` and ``channels`` (their names, or
        None): what a live model repeats.
    notes : list of str
        What was done on the way (resampled stamps, label rows of other recordings).
    """

    dataset: Dataset
    n_events: int
    n_labelled: int
    n_dropped: int
    warnings: list[str] = field(default_factory=list)
    recipe: dict[str, Any] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)


def extract_dataset(
    recordings: Sequence[Path],
    *,
    labels: Path | None,
    extractor: str,
    events: str | None = None,
    name: str | None = None,
    samplerate: float | None = None,
    segment: float | None = None,
    options: Mapping[str, Any] | None = None,
    topic: str | None = None,
    fields: Sequence[str] | None = None,
    channels: int | None = None,
    sample_format: str | None = None,
    max_event: float | None = None,
    time_column: str | None = None,
    time_unit: str = "auto",
    on_progress: Callable[[str, float], None] | None = None,
) -> ExtractionResult:
    """Turn recordings into a labelled data set, each recording read block by block.

    Parameters
    ----------
    recordings : sequence of Path
        WAV/FLAC/... audio, CSV time series, ``.npy`` files or ROS bags; file names must
        differ.
    labels : Path or None
        The labels CSV; ``None`` keeps every instance, without targets.
    extractor : str
        A key of :data:`features.extractors.EXTRACTORS`.
    events : str, optional
        ``snr``, ``dbscan`` or ``none``; the extractor's default if not given.
    name : str, optional
        Data set name (default: the labels file's stem, else the first recording's).
    samplerate : float, optional
        Sample rate for recordings that do not carry one (CSV without time, ``.npy``), and
        the grid of CSV recordings with uneven stamps (default: the first recording's
        rate, else the median rate of its stamps).
    segment : float, optional
        Segment seconds for events ``none`` (default: the extractor's, else whole files).
    options : mapping, optional
        Options of the extractor and of the event detector, in one flat mapping.
    topic : str, optional
        The topic of ROS bags to read: audio, or numeric fields.
    fields : sequence of str, optional
        Numeric fields of ``topic``, or columns of CSV recordings (names or 1-based
        numbers), to read as channels.
    channels, sample_format : optional
        Raw PCM audio in bags without ``AudioInfo``: channels per frame and
        ``S16LE``/``S32LE``/``F32LE``.
    max_event : float, optional
        Longest event in seconds (default 60); longer ones are cut, with a warning.
    time_column : str, optional
        The time column of CSV recordings.
    time_unit : {"auto", "s", "ms", "us", "ns"}
        The unit of that column.
    on_progress : callable, optional
        Called as ``on_progress(file_name, seconds_read)`` after every block.

    Returns
    -------
    ExtractionResult
    """
    if not recordings:
        raise FeatureError("no recording was given")
    recipe = Recipe.resolve(
        extractor, events=events, segment=segment, options=options, max_event=max_event
    )
    paths = [Path(path) for path in recordings]
    by_name = _unique_names(paths)
    table = read_labels(labels) if labels is not None else None
    limits = DatasetLimits.configured()
    n_targets = 0 if table is None else len(table.targets)
    if labels is not None:
        check_dataset_size(n_targets=n_targets, source=labels.name, limits=limits)
    notes: list[str] = []
    if table is not None:
        other = other_recordings(table, by_name)
        if other:
            notes.append(other)
    dataset_name = name or (labels.stem if labels is not None else paths[0].stem)

    features: list[np.ndarray] = []
    spans: list[tuple[str, float, float]] = []
    meta: list[dict[str, Any]] = []
    warnings: list[str] = []
    shape: tuple[float, int] | None = None
    names: tuple[str, ...] | None = None
    grid = samplerate
    reading = read_limits()
    values: _Values | None = None

    def open_source(path: Path) -> FileReplaySource:
        return FileReplaySource(
            path,
            samplerate=grid,
            topic=topic,
            fields=fields,
            channels=channels,
            sample_format=sample_format,
            time_column=time_column,
            time_unit=time_unit,
            limits=reading,
        )

    for index, path in enumerate(paths):
        with open_source(path) as source:
            shape = _same_shape(shape, (source.samplerate, source.n_channels), path)
            names = _same_names(names, source.channel_names, path, first=index == 0)
            if grid is None and source.resampled:
                # Stamped recordings go on the first one's grid: one data set, one rate.
                grid = source.samplerate
            if index == 0:
                longest = None
                if recipe.needs_longest():
                    longest = _longest(paths, open_source)
                recipe, filled = _at_rate(recipe, source.samplerate, longest, path)
                notes += filled
                values = _Values(recipe, n_targets, source.n_channels, path, limits)
            assert values is not None
            parts = _extract_one(recipe, source, path, on_progress, values)
            origin, rate = source.start_time, source.samplerate
        notes += [f"{path.name}: {text}" for text in source.notes]
        # Kept as the parts the stream gave, joined once into the data set itself (which
        # frees them one by one), so that no copy of all the features is ever made.
        while parts:
            warnings += _collect(parts.pop(0), path.name, origin, rate, features, spans, meta)

    assert shape is not None
    feature_names = recipe.make_extractor().feature_names(shape[1], names)
    n_events = sum(part.shape[0] for part in features)
    if table is None:
        if n_events == 0:
            raise FeatureError(
                f"no event was found in {len(paths)} recording(s) with events '{recipe.events}'"
                + (f" ({warnings[0]}{_more(warnings)})" if warnings else "")
            )
        keep = np.ones(n_events, dtype=bool)
        target_attributes: list[Attribute] = []
        codes = np.zeros((n_events, 0))
    else:
        keep, target_attributes, codes, label_warnings = label_instances(table, spans, by_name)
        warnings += label_warnings
        if not keep.any():
            raise DataFormatError(
                f"none of the {n_events} instance(s) found falls inside a labelled interval",
                source=table.source,
            )
    schema = Schema(
        relation=(
            f"{dataset_name}: -C {len(target_attributes)}" if target_attributes else dataset_name
        ),
        attributes=(
            *target_attributes,
            *(Attribute(n, "numeric", declared_type="numeric") for n in feature_names),
        ),
        target_indices=tuple(range(len(target_attributes))),
    )
    rows = np.flatnonzero(keep)
    dataset = Dataset(
        schema=schema,
        values=_assemble(codes[rows], features, keep, len(feature_names)),
        groups=np.array([spans[i][0] for i in rows], dtype=object),
        meta=[meta[i] for i in rows],
        name=dataset_name,
    )
    return ExtractionResult(
        dataset=dataset,
        n_events=n_events,
        n_labelled=int(rows.size),
        n_dropped=n_events - int(rows.size),
        warnings=warnings,
        recipe={
            **recipe.to_json(),
            "samplerate": shape[0],
            "n_channels": shape[1],
            "channels": None if names is None else list(names),
        },
        notes=notes,
    )


def extract_with_recipe(path: Path, recipe: Mapping[str, Any]) -> ExtractionResult:
    """The instances of one recording made as a model's training instances were: its
    stored recipe (:class:`ExtractionResult.recipe`), the same sample rate (the grid of a
    timed CSV, the rate of one without time) and the same channels.

    Raises
    ------
    FeatureError
        A recipe that is not one.
    """
    try:
        options = {**recipe["extractor_options"], **recipe["event_options"]}
        extractor, events = str(recipe["extractor"]), str(recipe["events"])
    except (KeyError, TypeError) as error:
        raise FeatureError(f"not an extraction recipe: {error!r}") from None
    channels = recipe.get("channels")
    return extract_dataset(
        [path],
        labels=None,
        extractor=extractor,
        events=events,
        samplerate=recipe.get("samplerate"),
        segment=recipe.get("segment"),
        options=options,
        max_event=recipe.get("max_event"),
        # A CSV read by name: the columns the model was trained on, in its order.
        fields=channels if channels and path.suffix.lower() in CSV_SUFFIXES else None,
    )


def check_extraction(store: Store, request: ExtractRequest) -> None:
    """Refuse what can be refused before any recording is read: the request checked its
    extractor, event detection and options when it was made; here, the data set's name,
    the number of targets the labels file declares, and then the labels file itself.

    Raises
    ------
    FieldError
        An invalid name.
    ConflictError
        The name is taken.
    DataFormatError
        The labels file declares more targets than :mod:`app.services.limits` allows, or
        :func:`read_labels` refuses it.
    """
    if request.name is not None:
        check_dataset_name(store, request.name)
    labels = request.labels_path()
    if labels is not None and request.labels is not None:
        # the header alone says how many targets: a file declaring thousands is refused
        # before a job reads any recording
        check_dataset_size(n_targets=count_label_targets(labels), source=str(request.labels))
        # the rest is read too (a labels file is small; its time is linear in its size), so
        # that a bad one is refused when uploaded, not by a job that failed meanwhile
        read_labels(labels)


def extract_and_store(
    store: Store,
    request: ExtractRequest,
    *,
    on_progress: Callable[[str, float], None] | None = None,
) -> ExtractionSummary:
    """:func:`extract_dataset`, then store the data set with its extraction recipe in one
    transaction (nothing is stored when anything fails).

    Parameters
    ----------
    store : Store
    request : ExtractRequest
        What to read and how; its ``name``, when given, must be free in the store.
    on_progress : callable, optional
        Called as ``on_progress(file_name, seconds_read)`` after every block.
    """
    check_extraction(store, request)
    recordings = request.recording_paths()
    result = extract_dataset(
        recordings,
        labels=request.labels_path(),
        extractor=request.extractor,
        events=request.events,
        name=request.name,
        samplerate=request.samplerate,
        segment=request.segment,
        options=request.options,
        topic=request.topic,
        fields=request.fields,
        channels=request.channels,
        sample_format=request.sample_format,
        max_event=request.max_event,
        time_column=request.time_column,
        time_unit=request.time_unit,
        on_progress=on_progress,
    )
    data = result.dataset
    shown = ", ".join(path.name for path in recordings[:3])
    info, created = add_dataset(
        store,
        data,
        sha256=dataset_digest(data),
        name=request.name,
        source_name=shown + (f" (+{len(recordings) - 3})" if len(recordings) > 3 else ""),
        extraction=result.recipe,
    )
    return ExtractionSummary(
        id=info.id,
        name=info.name,
        n_instances=info.n_instances,
        n_features=info.n_features,
        targets=info.targets,
        events_found=result.n_events,
        events_labelled=result.n_labelled,
        events_dropped=result.n_dropped,
        warnings=result.warnings,
        notes=result.notes,
        created=created,
    )


def _collect(
    instances: Instances,
    name: str,
    origin: float,
    rate: float,
    features: list[np.ndarray],
    spans: list[tuple[str, float, float]],
    meta: list[dict[str, Any]],
) -> list[str]:
    """Add one part of a recording's instances to the lists; its warnings."""
    features.append(instances.values)
    for (first, last), details in zip(instances.spans, instances.meta, strict=True):
        start, end = origin + first / rate, origin + last / rate
        spans.append((name, start, end))
        meta.append({"source": name, "start": start, "end": end, **details})
    return [f"{name}: {text}" for text in instances.warnings]


def _longest(paths: Sequence[Path], open_source: Callable[[Path], FileReplaySource]) -> int:
    """Samples in the longest of the recordings (each read once, block by block)."""
    longest = 0
    for path in paths:
        with open_source(path) as source:
            longest = max(longest, sum(block.samples.shape[1] for block in source.blocks()))
    return longest


def _at_rate(
    recipe: Recipe, samplerate: float, longest: int | None, path: Path
) -> tuple[Recipe, list[str]]:
    """:meth:`Recipe.at_rate`, its errors naming the first recording."""
    try:
        return recipe.at_rate(samplerate, longest=longest)
    except FeatureError as error:
        raise FeatureError(f"{path}: {error}") from None


def _assemble(
    codes: np.ndarray, parts: list[np.ndarray], keep: np.ndarray, n_features: int
) -> np.ndarray:
    """The data set's values: target ``codes`` of shape (n_kept, n_targets), then the kept
    rows of the feature ``parts`` (one per recording, concatenated they are the
    instances ``keep`` selects from).

    Each part is written into the result and then released (``parts`` is emptied), so
    that memory holds the features about once, not the parts, their concatenation and
    the result.
    """
    values = np.empty((codes.shape[0], codes.shape[1] + n_features))
    values[:, : codes.shape[1]] = codes
    start = row = 0
    while parts:
        part = parts.pop(0)
        kept = keep[start : start + part.shape[0]]
        count = int(kept.sum())
        np.compress(kept, part, axis=0, out=values[row : row + count, codes.shape[1] :])
        start, row = start + part.shape[0], row + count
        del part
    return values


def _extract_one(
    recipe: Recipe,
    source: FileReplaySource,
    path: Path,
    on_progress: Callable[[str, float], None] | None,
    values: _Values,
) -> list[Instances]:
    """The instances of one recording, read block by block, as the stream gave them;
    refused as soon as the data set's values pass the limit."""
    try:
        stream = recipe.open(samplerate=source.samplerate, n_channels=source.n_channels)
        parts = []
        for block in source.blocks():
            parts.append(stream.feed(block.samples))
            values.add(parts[-1].values.shape[0], path)
            if on_progress is not None:
                on_progress(path.name, stream.position / source.samplerate)
        parts.append(stream.finish())
        values.add(parts[-1].values.shape[0], path)
    except FeatureError as error:
        raise FeatureError(f"{path}: {error}") from None
    return parts


@dataclass
class _Values:
    """The data set's size as its instances come: its attributes and one instance's values
    checked when the first recording says its channels (before any value is made), then
    every instance counted.

    Parameters
    ----------
    recipe : Recipe
        With the options that depend on the recordings filled in.
    n_targets, n_channels : int
    path : Path
        The first recording.
    limits : DatasetLimits

    Raises
    ------
    DataFormatError
        Naming the recording and the extractor that make too many.
    """

    recipe: Recipe
    n_targets: int
    n_channels: int
    path: Path
    limits: DatasetLimits
    n_instances: int = 0

    def __post_init__(self) -> None:
        extractor = self.recipe.make_extractor()
        self.width = self.n_targets + extractor.n_features(self.n_channels)
        self.sequence = extractor.sequence_shape(self.n_channels)
        check_dataset_size(
            n_targets=self.n_targets,
            n_attributes=self.width,
            source=f"{self.path.name} ({self.n_channels} channel(s), {self._made_by})",
            limits=self.limits,
            sequence=self.sequence,
        )
        self.add(1, self.path)
        self.n_instances = 0

    @property
    def _made_by(self) -> str:
        return f"extractor '{self.recipe.extractor}'"

    def add(self, count: int, path: Path) -> None:
        """Count ``count`` more instances (of ``path``), refused past the values limit."""
        self.n_instances += count
        check_cells(
            n_instances=self.n_instances,
            n_attributes=self.width,
            source=f"{path.name} ({self._made_by})",
            limits=self.limits,
            sequence=self.sequence,
        )


def _unique_names(paths: Sequence[Path]) -> dict[str, Path]:
    by_name: dict[str, Path] = {}
    for path in paths:
        if path.name in by_name:
            raise FeatureError(
                f"two recordings are named '{path.name}' ({by_name[path.name]} and {path}); "
                "labels name recordings by file name, so names must differ"
            )
        by_name[path.name] = path
    return by_name


def _same_shape(
    expected: tuple[float, int] | None, found: tuple[float, int], path: Path
) -> tuple[float, int]:
    """One sample rate and one channel count for every recording of a data set."""
    if expected is not None and found[1] != expected[1]:
        raise FeatureError(
            f"{path}: has {found[1]} channel(s) but the recordings before it have "
            f"{expected[1]}; one data set needs one channel count"
        )
    if expected is not None and abs(found[0] - expected[0]) > 1e-6:
        raise FeatureError(
            f"{path}: is sampled at {found[0]:g} Hz but the recordings before it at "
            f"{expected[0]:g} Hz; one data set needs one sample rate"
        )
    return found


def _same_names(
    expected: tuple[str, ...] | None, found: Sequence[str] | None, path: Path, *, first: bool
) -> tuple[str, ...] | None:
    """One list of channel names for every recording (the features are named after it)."""
    names = None if found is None else tuple(found)
    if not first and names != expected:
        raise FeatureError(
            f"{path}: has channels {few(names or ('unnamed',))} but the recordings before it "
            f"{few(expected or ('unnamed',))}; one data set needs the same channels"
        )
    return names


def _more(lines: Sequence[str]) -> str:
    """`` and N more`` for the lines after the first ("" for one)."""
    return f" and {len(lines) - 1} more" if len(lines) > 1 else ""
