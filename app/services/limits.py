"""How large a data set may be: at most so many targets and attributes, whatever a file
or an upload declares (``TOUCHBENCH_MAX_TARGETS``, ``TOUCHBENCH_MAX_ATTRIBUTES``).

Everything a data set's size drives (describing it, its pages and plots, a run's per-target
results) is linear in it, but a 170 KB labels file can declare 20,000 targets: the limits
refuse that before anything is read further or stored.
"""

from __future__ import annotations

from dataclasses import dataclass

from touchbench.benchmark.errors import DataFormatError


@dataclass(frozen=True)
class DatasetLimits:
    """The largest data set accepted.

    Attributes
    ----------
    targets : int
    attributes : int
        Targets and features together.
    """

    targets: int
    attributes: int

    @classmethod
    def configured(cls) -> DatasetLimits:
        """The limits of the settings (the environment)."""
        # start-up time: a command that lists or shows reads no settings (pydantic-settings)
        from touchbench.app.settings import get_settings

        settings = get_settings()
        return cls(targets=settings.max_targets, attributes=settings.max_attributes)


def check_dataset_size(
    *,
    n_targets: int,
    n_attributes: int | None = None,
    source: str,
    limits: DatasetLimits | None = None,
) -> None:
    """Refuse a data set with more targets or attributes than the limits allow.

    Parameters
    ----------
    n_targets : int
    n_attributes : int, optional
        Targets and features; unknown yet when not given.
    source : str
        The file the counts come from, as the user knows it.
    limits : DatasetLimits, optional
        By default :meth:`DatasetLimits.configured`.

    Raises
    ------
    DataFormatError
        Over a limit, naming the file, the count and the limit's setting.
    """
    limits = limits or DatasetLimits.configured()
    if n_targets > limits.targets:
        raise DataFormatError(
            f"{n_targets:,} targets, more than the {limits.targets:,} a data set may have "
            "(the setting TOUCHBENCH_MAX_TARGETS raises the limit)",
            source=source,
        )
    if n_attributes is not None and n_attributes > limits.attributes:
        raise DataFormatError(
            f"{n_attributes:,} attributes, more than the {limits.attributes:,} a data set may "
            "have (the setting TOUCHBENCH_MAX_ATTRIBUTES raises the limit)",
            source=source,
        )
