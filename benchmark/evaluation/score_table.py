"""Scores of several classifiers on several blocks, with missing cells kept visible.

A *block* is what the statistics across data sets (:mod:`benchmark.evaluation.statistics`)
rank classifiers within: a data set in Demšar's sense (one score per classifier and data
set, the mean over its folds), or a fold when a single run is all there is.  A classifier
that failed on a block leaves a missing cell (NaN); :meth:`ScoreTable.complete` decides,
by an explicit policy, what becomes of it, and says which cells it concerned.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal, cast

import numpy as np

from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.results import TaskResult

#: What to do with a classifier that has no score on a block: leave the classifier out,
#: leave the block out, or rank it last on that block.
MissingPolicy = Literal["drop-classifier", "drop-block", "worst"]
MISSING_POLICIES: tuple[str, ...] = ("drop-classifier", "drop-block", "worst")


@dataclass(frozen=True)
class MissingCell:
    """A classifier without a score on a block."""

    block: str
    classifier: str


@dataclass(frozen=True)
class ScoreTable:
    """One score per block and classifier.

    Parameters
    ----------
    scores : ndarray of shape (n_blocks, n_classifiers)
        NaN marks a missing cell.  With the ``"worst"`` policy applied, a missing cell
        holds -inf (or +inf where lower is better).
    blocks : tuple of str
        Row labels (data sets, or folds), unique.
    classifiers : tuple of str
        Column labels, unique.
    """

    scores: np.ndarray
    blocks: tuple[str, ...]
    classifiers: tuple[str, ...]

    def __post_init__(self) -> None:
        scores = np.asarray(self.scores, dtype=np.float64)
        object.__setattr__(self, "scores", scores)
        object.__setattr__(self, "blocks", tuple(self.blocks))
        object.__setattr__(self, "classifiers", tuple(self.classifiers))
        expected = (len(self.blocks), len(self.classifiers))
        if scores.shape != expected:
            raise ConfigurationError(
                f"scores have shape {scores.shape} but there are {expected[0]} block(s) and "
                f"{expected[1]} classifier(s)"
            )
        for kind, names in (("block", self.blocks), ("classifier", self.classifiers)):
            seen: set[str] = set()
            for name in names:
                if name in seen:
                    raise ConfigurationError(f"{kind} '{name}' appears twice")
                seen.add(name)

    @property
    def shape(self) -> tuple[int, int]:
        return (len(self.blocks), len(self.classifiers))

    def column(self, classifier: str) -> np.ndarray:
        """The scores of one classifier, shape (n_blocks,)."""
        try:
            return self.scores[:, self.classifiers.index(classifier)]
        except ValueError:
            raise ConfigurationError(
                f"classifier '{classifier}' is not in the comparison "
                f"(classifiers: {', '.join(self.classifiers)})"
            ) from None

    def missing_cells(self) -> list[MissingCell]:
        """Every (block, classifier) without a score, block by block."""
        rows, columns = np.nonzero(np.isnan(self.scores))
        return [
            MissingCell(self.blocks[r], self.classifiers[c])
            for r, c in zip(rows, columns, strict=True)
        ]

    def complete(
        self, policy: MissingPolicy = "drop-classifier", *, lower_is_better: bool = False
    ) -> CompletedTable:
        """A table without missing cells, and what was done to get it.

        Parameters
        ----------
        policy : {"drop-classifier", "drop-block", "worst"}
            ``drop-classifier`` leaves out every classifier with a missing cell;
            ``drop-block`` leaves out every block with one; ``worst`` keeps everything and
            gives a missing cell the worst score of its block (several missing cells on a
            block tie for last).
        lower_is_better : bool
            The metric's direction (decides which infinity is the worst score).

        Raises
        ------
        ConfigurationError
            An unknown policy.
        """
        policy = missing_policy(policy)
        missing = self.missing_cells()
        holes = np.isnan(self.scores)
        if policy == "worst":
            filled = np.where(holes, math.inf if lower_is_better else -math.inf, self.scores)
            table = ScoreTable(filled, self.blocks, self.classifiers)
            return CompletedTable(table, policy, missing)
        if policy == "drop-classifier":
            keep = ~holes.any(axis=0)
            table = ScoreTable(
                self.scores[:, keep],
                self.blocks,
                tuple(c for c, k in zip(self.classifiers, keep, strict=True) if k),
            )
            dropped = [c for c, k in zip(self.classifiers, keep, strict=True) if not k]
            return CompletedTable(table, policy, missing, dropped_classifiers=dropped)
        keep = ~holes.any(axis=1)
        table = ScoreTable(
            self.scores[keep],
            tuple(b for b, k in zip(self.blocks, keep, strict=True) if k),
            self.classifiers,
        )
        dropped = [b for b, k in zip(self.blocks, keep, strict=True) if not k]
        return CompletedTable(table, policy, missing, dropped_blocks=dropped)


@dataclass(frozen=True)
class CompletedTable:
    """A table without missing cells and the cells that were missing.

    Attributes
    ----------
    table : ScoreTable
        No NaN left (infinities stand for missing cells under the ``worst`` policy).
    policy : str
        The policy applied.
    missing : list of MissingCell
        Every cell that was missing before.
    dropped_classifiers, dropped_blocks : list of str
        What the policy left out.
    """

    table: ScoreTable
    policy: MissingPolicy
    missing: list[MissingCell]
    dropped_classifiers: list[str] = field(default_factory=list)
    dropped_blocks: list[str] = field(default_factory=list)


def missing_policy(name: str) -> MissingPolicy:
    """``name`` as a :data:`MissingPolicy`; anything else is refused."""
    if name not in MISSING_POLICIES:
        raise ConfigurationError(
            f"unknown missing-cell policy '{name}' (use {', '.join(MISSING_POLICIES)})"
        )
    return cast(MissingPolicy, name)


def fold_label(repeat: int, fold: int) -> str:
    """How a fold is named as a block: ``"fold 3"``, or ``"repeat 2 fold 3"``."""
    return f"repeat {repeat + 1} fold {fold + 1}" if repeat else f"fold {fold + 1}"


def fold_score_table(
    results: Sequence[TaskResult], metric: str, *, classifiers: Sequence[str] | None = None
) -> ScoreTable:
    """A run's per-fold scores: one block per (repeat, fold), one column per classifier.

    Parameters
    ----------
    results : sequence of TaskResult
        The task results of one run (failed ones included).
    metric : str
        The score to tabulate.
    classifiers : sequence of str, optional
        Columns, in this order; default every classifier of ``results`` in order of
        appearance.

    Returns
    -------
    ScoreTable
        Shape (n_folds, n_classifiers); NaN where a task failed, was never run or has no
        value for ``metric``.  Block labels come from :func:`fold_label`.
    """
    names = list(classifiers) if classifiers is not None else _in_order(results)
    folds = sorted({(r.key.repeat, r.key.fold) for r in results})
    row = {key: i for i, key in enumerate(folds)}
    column = {name: j for j, name in enumerate(names)}
    scores = np.full((len(folds), len(names)), math.nan)
    for result in results:
        j = column.get(result.key.classifier)
        if j is None or not result.ok:
            continue
        scores[row[(result.key.repeat, result.key.fold)], j] = result.metrics.get(metric, math.nan)
    return ScoreTable(scores, tuple(fold_label(r, f) for r, f in folds), tuple(names))


def _in_order(results: Sequence[TaskResult]) -> list[str]:
    return list(dict.fromkeys(r.key.classifier for r in results))
