"""Tuned twins against their defaults, and what each fold chose.

A run with ``bench --tune`` holds ``rf`` and ``rf+tuned`` (or ``cc:rf`` and
``cc:rf+tuned``) on the same folds: each pair is compared with the corrected resampled
t-test on the folds both completed, the tuned twin as the first of the pair.
"""

from __future__ import annotations

import math
from collections import defaultdict
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from touchbench.benchmark.evaluation.leaderboard import finite, mark_against, scores_by_fold
from touchbench.benchmark.evaluation.metrics import LOWER_IS_BETTER
from touchbench.benchmark.results import TaskResult

#: Suffix of a tuned twin's id (as :data:`benchmark.catalogue.tuning.TUNED_SUFFIX`; the
#: evaluation package does not import the catalogue).
TUNED_SUFFIX = "+tuned"


@dataclass(frozen=True)
class FoldChoice:
    """What one classifier chose on one training fold."""

    classifier: str
    repeat: int
    fold: int
    params: dict[str, Any]

    def to_json(self) -> dict[str, Any]:
        return {
            "classifier": self.classifier,
            "repeat": self.repeat,
            "fold": self.fold,
            "params": self.params,
        }


@dataclass(frozen=True)
class TunedComparison:
    """A tuned twin beside its default on the folds both completed.

    Parameters
    ----------
    tuned, default : str
        Classifier ids (``rf+tuned``, ``rf``).
    metric : str
    tuned_mean, default_mean : float
        Means over the paired folds (NaN with none).
    n_folds : int
        Folds both completed.
    t, p : float
        The corrected resampled t-test of tuned against default (NaN below two folds).
    mark : {"v", "*", ""}
        ``v``: the tuned twin is significantly better, ``*`` worse (in the metric's own
        direction).
    choices : list of FoldChoice
        The tuned twin's chosen parameters per fold.
    """

    tuned: str
    default: str
    metric: str
    tuned_mean: float
    default_mean: float
    n_folds: int
    t: float
    p: float
    mark: str
    choices: list[FoldChoice] = field(default_factory=list)

    def to_json(self) -> dict[str, Any]:
        return {
            "tuned": self.tuned,
            "default": self.default,
            "metric": self.metric,
            "tuned_mean": finite(self.tuned_mean),
            "default_mean": finite(self.default_mean),
            "n_folds": self.n_folds,
            "t": finite(self.t),
            "p": finite(self.p),
            "mark": self.mark,
            "choices": [choice.to_json() for choice in self.choices],
        }


def fold_choices(results: Sequence[TaskResult]) -> list[FoldChoice]:
    """Every successful task's recorded choice, by classifier, repeat and fold."""
    return sorted(
        (
            FoldChoice(r.key.classifier, r.key.repeat, r.key.fold, dict(r.params))
            for r in results
            if r.ok and r.params is not None
        ),
        key=lambda c: (c.classifier, c.repeat, c.fold),
    )


def compare_tuned(
    results: Sequence[TaskResult], *, metric: str = "f1_weighted", alpha: float = 0.05
) -> list[TunedComparison]:
    """Each tuned twin of a run against its default, in the order the twins first appear.

    Parameters
    ----------
    results : sequence of TaskResult
        A run's results (failed ones are left out of the pairs).
    metric : str
        The compared metric (lower is better for :data:`LOWER_IS_BETTER` ones).
    alpha : float
        Significance level of the marks.
    """
    by_classifier: dict[str, list[TaskResult]] = defaultdict(list)
    ratios: dict[str, float] = {}
    for r in results:
        by_classifier[r.key.classifier].append(r)
        if r.n_train > 0:
            ratios[r.key.classifier] = r.n_test / r.n_train
    scores = {c: scores_by_fold(rs, metric) for c, rs in by_classifier.items()}
    choices = fold_choices(results)
    comparisons = []
    for tuned in by_classifier:
        default = tuned.removesuffix(TUNED_SUFFIX)
        if tuned == default or default not in by_classifier:
            continue
        paired = sorted(set(scores[tuned]) & set(scores[default]))
        a = np.array([scores[tuned][k] for k in paired])
        b = np.array([scores[default][k] for k in paired])
        t, p, mark = mark_against(
            a,
            b,
            test_train_ratio=ratios.get(tuned, 0.0),
            alpha=alpha,
            lower_is_better=metric in LOWER_IS_BETTER,
        )
        comparisons.append(
            TunedComparison(
                tuned=tuned,
                default=default,
                metric=metric,
                tuned_mean=float(a.mean()) if paired else math.nan,
                default_mean=float(b.mean()) if paired else math.nan,
                n_folds=len(paired),
                t=t,
                p=p,
                mark=mark,
                choices=[c for c in choices if c.classifier == tuned],
            )
        )
    return comparisons
