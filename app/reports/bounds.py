"""How much a page, a fragment or a plot shows: the first items of a long list and a count
of the others ("and 19,980 more").

A data set may have hundreds of targets and thousands of attributes, a target thousands of
classes, a run thousands of classifiers (an imported results file), and the store
thousands of runs.  Whatever it holds, a fragment or a plot shows at
most these many of each, so that drawing and rendering cost a bounded time and memory (a
plot with a panel per target grew faster than the square of the targets); the JSON API and
the CLI give everything.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Generic, TypeVar

T = TypeVar("T")
K = TypeVar("K")
V = TypeVar("V")

#: Names in one line of text (the targets of a data set, a run, a model).
NAMES = 10
#: Targets drawn in a plot (one panel each) or tabled in a fragment (one table each).
PANELS = 6
#: Classes of one target in a table or a plot.
CLASSES = 30
#: Attributes in a data set's schema table, or inputs in a model's form.
ATTRIBUTES = 200
#: Rows of a listing (data sets, runs, models).
ROWS = 500
#: Classifiers in a run's leaderboard fragment (rows of its table and of each table below).
CLASSIFIERS = 100
#: Classifiers drawn in a plot (one row or one dot each), the best first.
DRAWN = 30


@dataclass(frozen=True)
class Shown(Generic[T]):
    """The first items of a list and how many others there are.

    Attributes
    ----------
    items : list
        At most the limit asked for.
    more : int
        Items left out (0 when all are shown).
    """

    items: list[T]
    more: int

    @property
    def total(self) -> int:
        return len(self.items) + self.more


def first(items: Iterable[T], limit: int) -> Shown[T]:
    """The first ``limit`` of ``items`` (a sequence, a mapping's keys, any iterable)."""
    listed = items if isinstance(items, Sequence) else list(items)
    return Shown(list(listed[:limit]), max(len(listed) - limit, 0))


def first_entries(mapping: Mapping[K, V], limit: int) -> dict[K, V]:
    """The first ``limit`` entries of ``mapping``, in its order."""
    return {key: mapping[key] for key in first(mapping.keys(), limit).items}


def count(number: int) -> str:
    """A count as text, with thousands separated (``19,980``)."""
    return f"{number:,}"


def and_more(more: int, noun: str = "") -> str:
    """``" and 19,980 more"`` (with ``noun`` after it), or nothing when ``more`` is 0."""
    if not more:
        return ""
    return f" and {count(more)} more" + (f" {noun}" if noun else "")


def names(items: Iterable[object], limit: int = NAMES) -> str:
    """Names joined by commas, the first ``limit`` of them and a count of the others:
    ``"y0, y1, y2 and 19,997 more"``."""
    shown = first([str(item) for item in items], limit)
    return ", ".join(shown.items) + and_more(shown.more)


def of_all(shown: Shown[Any], noun: str) -> str:
    """``"first 6 of 800 targets"`` when some are left out, else ``""``."""
    return f"first {count(len(shown.items))} of {count(shown.total)} {noun}" if shown.more else ""
