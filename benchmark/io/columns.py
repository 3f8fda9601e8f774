"""Columns of a data file set aside as it is read: the one that names each instance's
group, and the ones left out.

A table from another lab often holds, beside its features and labels, a column naming
what each row was recorded on (the object grasped, the subject, the session) and columns
that are neither (a trial number, a time stamp).  Read as they stand they would become
features, and a classifier would learn the object's name.  :class:`ColumnChoice` names
them; :func:`plan_columns` checks the choice against a file's columns and targets; the
:class:`ColumnPlan` it returns makes the data set's schema and instances.  The group
column's cells become :attr:`~benchmark.dataset.Dataset.groups` (as text) and its name the
schema's ``group_column``; ignored columns are dropped; neither ever reaches the features.

Targets are chosen among the file's columns as its author sees them (names, the first or
last N, MEKA's ``-C``, the last column by default), before anything is set aside: a column
cannot be both a target and set aside.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np

from touchbench.benchmark.dataset import Attribute, Dataset, InstanceBlock, Schema, shortlist
from touchbench.benchmark.errors import ConfigurationError, DataFormatError
from touchbench.benchmark.io.arff_writer import format_number
from touchbench.benchmark.io.dates import DateFormat

#: The part of a :class:`ColumnChoice` a :class:`ColumnError` refuses.
ColumnField = Literal["groups", "ignore"]


@dataclass(frozen=True)
class ColumnChoice:
    """Which columns of a file are not attributes of the data set.

    Parameters
    ----------
    groups : str or None
        The column that names each instance's group; its cells become the instances'
        groups.
    ignore : tuple of str
        Columns left out (a name given twice counts once).
    """

    groups: str | None = None
    ignore: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "ignore", tuple(dict.fromkeys(self.ignore)))

    def __bool__(self) -> bool:
        """Whether any column is set aside."""
        return self.groups is not None or bool(self.ignore)


class ColumnError(ConfigurationError):
    """A column choice that does not fit the file.

    Parameters
    ----------
    field : {"groups", "ignore"}
        The part of the :class:`ColumnChoice` that is wrong.
    message : str
        What is wrong, naming the column and the file.
    """

    def __init__(self, field: ColumnField, message: str) -> None:
        super().__init__(message)
        self.field = field
        self.message = message


@dataclass(frozen=True)
class ColumnPlan:
    """How the columns of a file become the attributes and groups of a data set.

    Parameters
    ----------
    n_columns : int
        Columns in the file.
    kept : tuple of int
        File positions of the data set's attributes, in file order.
    group : int or None
        File position of the group column.
    target_indices : tuple of int
        Positions of the targets among the kept columns.
    """

    n_columns: int
    kept: tuple[int, ...]
    group: int | None
    target_indices: tuple[int, ...]

    @property
    def keeps_all(self) -> bool:
        """Whether every column stays an attribute (nothing to set aside)."""
        return len(self.kept) == self.n_columns

    def schema(self, relation: str, attributes: Sequence[Attribute]) -> Schema:
        """The data set's schema, from the file's relation and ``attributes`` (all of them)."""
        return Schema(
            relation,
            tuple(attributes[j] for j in self.kept),
            self.target_indices,
            group_column=None if self.group is None else attributes[self.group].name,
        )

    def block(
        self,
        block: InstanceBlock,
        group: Attribute | None,
        *,
        source: str,
        offset: int = 0,
    ) -> InstanceBlock:
        """The data set's instances of a block of the file's.

        Parameters
        ----------
        block : InstanceBlock
            ``values`` of shape (n, n_columns), as the file's reader decodes them.
        group : Attribute or None
            The group column's attribute as read so far (its string table grows as a
            file is read); ``None`` without a group column.
        source : str
            The file's name, for messages.
        offset : int
            Instances before this block, for messages about a block without lines.

        Returns
        -------
        InstanceBlock
            ``values`` of shape (n, len(kept)); ``groups`` the group column's cells as
            text when there is one.

        Raises
        ------
        DataFormatError
            An instance without a group (a missing cell of the group column).
        """
        if self.keeps_all:
            return block
        groups = block.groups
        if self.group is not None:
            assert group is not None
            codes = block.values[:, self.group]
            groups = group_texts(group, codes, source=source, lines=block.lines, offset=offset)
        return InstanceBlock(
            np.ascontiguousarray(block.values[:, list(self.kept)]),
            weights=block.weights,
            groups=groups,
            meta=block.meta,
            lines=block.lines,
        )

    def dataset(self, dataset: Dataset, *, source: str) -> Dataset:
        """``dataset`` (read with every column an attribute) with the columns set aside."""
        attributes = dataset.schema.attributes
        whole = InstanceBlock(
            dataset.values, weights=dataset.weights, groups=dataset.groups, meta=dataset.meta
        )
        group = None if self.group is None else attributes[self.group]
        part = self.block(whole, group, source=source)
        return Dataset(
            self.schema(dataset.schema.relation, attributes),
            part.values,
            weights=part.weights,
            groups=part.groups,
            meta=part.meta,
            sparse=dataset.sparse,
            name=dataset.name,
        )


def plan_columns(
    names: Sequence[str],
    target_indices: Sequence[int],
    choice: ColumnChoice | None,
    *,
    source: str,
    targets_by: str | None = None,
) -> ColumnPlan:
    """Check ``choice`` against a file's columns and targets; the plan that applies it.

    Parameters
    ----------
    names : sequence of str
        The file's column (attribute) names, in order.
    target_indices : sequence of int
        File positions of the targets.
    choice : ColumnChoice or None
        The columns set aside; ``None`` sets none aside.
    source : str
        The file's name, for messages.
    targets_by : str, optional
        How the targets were chosen when the user did not name them (``"the last column,
        by default"``), for messages.

    Returns
    -------
    ColumnPlan

    Raises
    ------
    ColumnError
        A column that does not exist; the group column also ignored or a target; an
        ignored target; every column ignored; no feature left.
    """
    choice = choice or ColumnChoice()
    position = {name: j for j, name in enumerate(names)}
    asked: tuple[tuple[ColumnField, tuple[str, ...]], ...] = (
        ("groups", () if choice.groups is None else (choice.groups,)),
        ("ignore", choice.ignore),
    )
    for field, columns in asked:
        for name in columns:
            if name not in position:
                raise ColumnError(
                    field, f"no column named '{name}' in {source} (columns: {shortlist(names)})"
                )
    ignored = {position[name] for name in choice.ignore}
    group = None if choice.groups is None else position[choice.groups]
    if group is not None and group in ignored:
        raise ColumnError(
            "ignore",
            f"column '{names[group]}' of {source} names the groups; it cannot also be ignored",
        )
    if len(ignored) == len(names):
        raise ColumnError("ignore", f"every column of {source} is ignored: nothing is left")
    targets = set(target_indices)
    how = f" ({targets_by})" if targets_by else ""
    if group is not None and group in targets:
        raise ColumnError(
            "groups",
            f"column '{names[group]}' of {source} is a target{how}; the group column cannot "
            "also be one: choose the targets among the other columns",
        )
    both = sorted(ignored & targets)
    if both:
        raise ColumnError(
            "ignore",
            f"column '{names[both[0]]}' of {source} is a target{how}; a target cannot be ignored",
        )
    kept = tuple(j for j in range(len(names)) if j not in ignored and j != group)
    if choice and not any(j not in targets for j in kept):  # else the caller's own rule
        raise ColumnError(
            "ignore" if ignored else "groups",
            f"no feature is left in {source}: every column is a target, the group column or "
            "ignored",
        )
    return ColumnPlan(
        n_columns=len(names),
        kept=kept,
        group=group,
        target_indices=tuple(kept.index(j) for j in sorted(targets)),
    )


def group_texts(
    attribute: Attribute,
    codes: np.ndarray,
    *,
    source: str,
    lines: np.ndarray | None = None,
    offset: int = 0,
) -> np.ndarray:
    """The group of each instance: the text of its cell in the group column.

    Parameters
    ----------
    attribute : Attribute
        The group column.
    codes : ndarray of shape (n,)
        Its values, encoded as in :class:`~benchmark.dataset.Dataset`.
    source : str
        The file's name, for messages.
    lines : ndarray of shape (n,), optional
        The line each instance was read from, for messages.
    offset : int
        Instances before these, for messages when ``lines`` is not known.

    Returns
    -------
    ndarray of shape (n,), object
        Labels for nominal and string columns, numbers as written back to ARFF (``3``
        for 3.0), dates in the column's format.

    Raises
    ------
    DataFormatError
        A missing value: every instance needs a group.
    """
    missing = np.isnan(codes)
    if missing.any():
        row = int(np.flatnonzero(missing)[0])
        line = None if lines is None else int(lines[row])
        where = "" if line is not None else f" (data row {offset + row + 1})"
        raise DataFormatError(
            f"no group{where}: every instance needs a value in the group column",
            source=source,
            line=line,
            attribute=attribute.name,
        )
    if attribute.kind in ("nominal", "string"):
        return np.array(attribute.values, dtype=object)[codes.astype(np.intp)]
    if attribute.kind == "date":
        dates = DateFormat(attribute.date_format)
        return np.array([dates.format(value) for value in codes.tolist()], dtype=object)
    return np.array([format_number(value) for value in codes.tolist()], dtype=object)
