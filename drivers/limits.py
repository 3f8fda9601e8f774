"""How much work reading one recording may cost, whatever its values say.

A CSV file's size bounds the work of parsing it, but not what its values make of it: time
stamps that jump by an hour make resampling fill the hour on an even grid, and a file of
one line (no line break) is one row as long as the file.  :class:`ReadLimits` bounds both,
so that the work and the memory of reading a recording follow its size:

* a line longer than :attr:`ReadLimits.line_chars` is refused as it streams in, never
  read whole (:func:`bounded_lines`);
* a recording holds at most :attr:`ReadLimits.cells` values (samples x channels) as read,
  resampled or padded;
* resampling puts at most :attr:`ReadLimits.gap_samples` grid samples into the gap
  between two consecutive time stamps (a longer gap is a recording that stopped, not
  jitter: split it there).

Each refusal is one line naming the file, the line and what broke the bound.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from typing import TextIO

from touchbench.drivers.errors import DriverError

#: The longest line of a CSV file (characters), by default.
LINE_CHARS = 1 << 20
#: The most values (samples x channels) of one recording, by default.
CELLS = 1 << 25
#: The most grid samples resampling puts into the gap between two stamps, by default.
GAP_SAMPLES = 100_000


@dataclass(frozen=True)
class ReadLimits:
    """The bounds of reading one recording (see the module docstring).

    Attributes
    ----------
    line_chars : int
        Longest line of a text file.
    cells : int
        Most values (samples x channels) a recording may hold, as read or after
        resampling or padding.
    gap_samples : int
        Most grid samples resampling may put between two consecutive stamps.
    settings : mapping of str to str
        The name of the setting that raises each limit (``"cells"`` ->
        ``"TOUCHBENCH_MAX_CELLS"``), said in a refusal; none by default.
    """

    line_chars: int = LINE_CHARS
    cells: int = CELLS
    gap_samples: int = GAP_SAMPLES
    settings: Mapping[str, str] = field(default_factory=dict)

    def raised_by(self, limit: str) -> str:
        """`` (the setting X raises the limit)`` for ``limit``, or nothing."""
        setting = self.settings.get(limit)
        return f" (the setting {setting} raises the limit)" if setting else ""

    def check_cells(self, n_samples: int, n_channels: int, *, what: str) -> None:
        """Refuse ``n_samples`` x ``n_channels`` values over :attr:`cells`.

        Raises
        ------
        DriverError
            ``what`` (the file, and the line or the gap) followed by the counts.
        """
        if n_samples * n_channels > self.cells:
            raise DriverError(
                f"{what}: {n_samples:,} samples x {n_channels:,} channel(s), more than the "
                f"{self.cells:,} values a recording may hold{self.raised_by('cells')}"
            )


class LineTooLongError(DriverError):
    """A line of a text file longer than the limit.

    Attributes
    ----------
    line : int
        Its 1-based number.
    limit : int
        The longest line allowed, in characters.
    """

    def __init__(self, source: str, line: int, limit: int) -> None:
        super().__init__(
            f"{source}:{line}: a line longer than {limit:,} characters (a file of one line, "
            "or not a CSV file?)"
        )
        self.line = line
        self.limit = limit


def bounded_lines(handle: TextIO, *, limit: int, source: str) -> Iterator[str]:
    """The lines of ``handle``, each read up to ``limit`` characters and refused past them,
    so that no more than ``limit + 2`` characters of one line are ever held.

    A line is read with its line break (two characters for ``\\r\\n``), so that a line of
    exactly ``limit`` characters comes whole and the lines keep the numbers of the file's
    own lines (the service's early refusal of an upload names the same line).

    Raises
    ------
    LineTooLongError
        At the first line longer than ``limit`` characters (its line break not counted).
    """
    number = 0
    while True:
        line = handle.readline(limit + 2)
        if not line:
            return
        number += 1
        if len(line) > limit and len(line.rstrip("\r\n")) > limit:
            raise LineTooLongError(source, number, limit)
        yield line
