"""How large a data set or a recording may be, whatever a file or an upload declares or
its values say (``TOUCHBENCH_MAX_TARGETS``, ``_MAX_ATTRIBUTES``, ``_MAX_CELLS``,
``_MAX_GAP_SAMPLES``).

Everything a data set's size drives (describing it, its pages and plots, a run's per-target
results) is linear in it, but a 170 KB labels file can declare 20,000 targets: the limits
refuse that before anything is read further or stored.  They count what costs: targets
and attributes, where a sequence (a window of ``channels x steps`` values per instance)
counts as its channels, and the values held (instances x attributes; a recording's
samples x channels), so that a tactile array's whole recordings extract as sequences while
a file that would make millions of values from a few bytes is refused.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from touchbench.benchmark.errors import DataFormatError
from touchbench.drivers.limits import ReadLimits

#: The settings that raise each limit, as a refusal names them.
SETTINGS = {
    "targets": "TOUCHBENCH_MAX_TARGETS",
    "attributes": "TOUCHBENCH_MAX_ATTRIBUTES",
    "cells": "TOUCHBENCH_MAX_CELLS",
    "gap_samples": "TOUCHBENCH_MAX_GAP_SAMPLES",
    "label_rows": "TOUCHBENCH_MAX_LABEL_ROWS",
}


@dataclass(frozen=True)
class DatasetLimits:
    """The largest data set accepted.

    Attributes
    ----------
    targets : int
    attributes : int
        Targets and features together, a sequence counted as its channels.
    cells : int
        Values: instances x attributes (a sequence's every value counted).
    """

    targets: int
    attributes: int
    cells: int

    @classmethod
    def configured(cls) -> DatasetLimits:
        """The limits of the settings (the environment)."""
        # start-up time: a command that lists or shows reads no settings (pydantic-settings)
        from touchbench.app.settings import get_settings

        settings = get_settings()
        return cls(
            targets=settings.max_targets,
            attributes=settings.max_attributes,
            cells=settings.max_cells,
        )


def read_limits() -> ReadLimits:
    """The bounds of reading one recording (:class:`drivers.limits.ReadLimits`), from the
    settings."""
    # start-up time: a command that lists or shows reads no settings (pydantic-settings)
    from touchbench.app.settings import get_settings

    settings = get_settings()
    return ReadLimits(
        cells=settings.max_cells, gap_samples=settings.max_gap_samples, settings=SETTINGS
    )


def raised_by(limit: str) -> str:
    """`` (the setting X raises the limit)``."""
    return f" (the setting {SETTINGS[limit]} raises the limit)"


def sequence_of(names: Sequence[str]) -> tuple[int, int] | None:
    """``(channels, steps)`` of the sequence among attribute ``names``
    (:func:`benchmark.sequence.find_sequence`), None for a flat data set."""
    from touchbench.benchmark.sequence import find_sequence  # start-up time: NumPy

    layout, _ = find_sequence(names)
    return None if layout is None else (layout.n_channels, layout.length)


def check_dataset_size(
    *,
    n_targets: int,
    n_attributes: int | None = None,
    source: str,
    limits: DatasetLimits | None = None,
    sequence: tuple[int, int] | None = None,
) -> None:
    """Refuse a data set with more targets or attributes than the limits allow.

    Parameters
    ----------
    n_targets : int
    n_attributes : int, optional
        Targets and features, every value of a sequence counted; unknown yet when not given.
    source : str
        The input the counts come from, as the user knows it.
    limits : DatasetLimits, optional
        By default :meth:`DatasetLimits.configured`.
    sequence : (int, int), optional
        ``(channels, steps)`` of a sequence among the attributes: it counts as its
        channels.

    Raises
    ------
    DataFormatError
        Over a limit, naming the input, the count and the limit's setting.
    """
    limits = limits or DatasetLimits.configured()
    if n_targets > limits.targets:
        raise DataFormatError(
            f"{n_targets:,} targets, more than the {limits.targets:,} a data set may have"
            + raised_by("targets"),
            source=source,
        )
    if n_attributes is None:
        return
    counted, told = n_attributes, ""
    if sequence is not None:
        channels, steps = sequence
        counted = n_attributes - channels * steps + channels
        told = f" ({_described(sequence)} counted as its {channels:,} channels)"
    if counted > limits.attributes:
        raise DataFormatError(
            f"{counted:,} attributes{told}, more than the {limits.attributes:,} a data set may "
            "have" + raised_by("attributes"),
            source=source,
        )


def check_cells(
    *,
    n_instances: int,
    n_attributes: int,
    source: str,
    limits: DatasetLimits | None = None,
    sequence: tuple[int, int] | None = None,
) -> None:
    """Refuse a data set of more values (instances x attributes) than the limits allow.

    Parameters
    ----------
    n_instances, n_attributes : int
        Every value of a sequence counted.
    source : str
        The input the values come from, as the user knows it.
    limits : DatasetLimits, optional
    sequence : (int, int), optional
        ``(channels, steps)`` of a sequence among the attributes, said in the message.

    Raises
    ------
    DataFormatError
    """
    limits = limits or DatasetLimits.configured()
    if n_instances * n_attributes > limits.cells:
        told = f" ({_described(sequence)})" if sequence is not None else ""
        raise DataFormatError(
            f"{n_instances:,} instance(s) x {n_attributes:,} attributes{told}, more than the "
            f"{limits.cells:,} values a data set may hold" + raised_by("cells"),
            source=source,
        )


def _described(sequence: tuple[int, int]) -> str:
    channels, steps = sequence
    return f"a sequence of {channels:,} channel(s) x {steps:,} steps"
