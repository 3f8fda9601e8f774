"""Leaderboards: per-classifier means and standard deviations, ranks, and WEKA's marks.

Like WEKA's Experimenter, every classifier is compared with a baseline on the folds both
completed, with the corrected resampled t-test: ``v`` marks a classifier significantly
better than the baseline, ``*`` significantly worse (in the metric's own direction: a lower
log loss is better).
"""

from __future__ import annotations

import math
from collections import defaultdict
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.evaluation.metrics import LOWER_IS_BETTER
from touchbench.benchmark.evaluation.significance import corrected_resampled_ttest
from touchbench.benchmark.results import Drop, Origin, TaskResult

Mark = Literal["v", "*", ""]

#: Distinct error messages kept per classifier.
MAX_ERRORS = 3


@dataclass
class LeaderboardRow:
    """One classifier's line.

    Parameters
    ----------
    rank : int
        1 for the best; ties share a rank; classifiers that stopped early (dropped by a
        race, cut by a budget) come after those that ran every fold, whatever the mean of
        their fewer folds; classifiers without a score come last.
    classifier : str
    metrics : dict of str to (float, float)
        Mean and sample standard deviation over the successful folds (NaN where no fold
        has the metric; standard deviation 0 for a single fold).
    mark : {"v", "*", ""}
        Significantly better / worse than the baseline on the ranking metric.
    n_ok, n_failed : int
        Successful and failed (error or timeout) tasks.
    errors : list of str
        Distinct failure messages, at most three.
    tested : bool
        Whether the t-test compared it with the baseline: ``False`` for the baseline and
        for a classifier whose folds cannot be paired with the baseline's (another
        comparison group: only the means compare).
    p_value : float
        The t-test's p-value against the baseline (NaN for the baseline itself and below
        two paired folds).
    dropped : Drop or None
        Why the classifier stopped before its last fold (a raced or budgeted run).
    origin : Origin or None
        An ensemble computed from its members' fold predictions, or a helper (a member
        the run did not ask for); ``None`` for an entry fitted as asked.
    """

    rank: int
    classifier: str
    metrics: dict[str, tuple[float, float]]
    mark: Mark = ""
    n_ok: int = 0
    n_failed: int = 0
    errors: list[str] = field(default_factory=list)
    tested: bool = False
    p_value: float = math.nan
    dropped: Drop | None = None
    origin: Origin | None = None

    def to_json(self) -> dict[str, Any]:
        """JSON-ready data; ``origin`` only for a row that has one (a computed ensemble,
        a helper)."""
        data = {
            "rank": self.rank,
            "classifier": self.classifier,
            "mark": self.mark,
            "metrics": {
                name: {"mean": finite(mean), "std": finite(std)}
                for name, (mean, std) in self.metrics.items()
            },
            "n_ok": self.n_ok,
            "n_failed": self.n_failed,
            "errors": list(self.errors),
            "tested": self.tested,
            "p_value": finite(self.p_value),
            "dropped": None if self.dropped is None else self.dropped.to_json(),
        }
        if self.origin is not None:
            data["origin"] = self.origin.to_json()
        return data


@dataclass
class Leaderboard:
    """A ranked comparison of classifiers on one run.

    Parameters
    ----------
    metric : str
        The ranking metric.
    baseline : str or None
        The classifier the marks compare against; ``None`` when no task succeeded.
    rows : list of LeaderboardRow
        Best first.
    summary : (int, int, int)
        WEKA's (v/ /*): classifiers significantly better than, not different from, and
        significantly worse than the baseline (the baseline and classifiers without a
        comparable fold are not counted).
    alpha : float
        Significance level of the marks.
    """

    metric: str
    baseline: str | None
    rows: list[LeaderboardRow]
    summary: tuple[int, int, int]
    alpha: float = 0.05

    @property
    def lower_is_better(self) -> bool:
        """Whether the ranking metric is better when smaller (errors, costs)."""
        return self.metric in LOWER_IS_BETTER

    def row(self, classifier: str) -> LeaderboardRow:
        """The row of ``classifier``."""
        for row in self.rows:
            if row.classifier == classifier:
                return row
        raise KeyError(classifier)

    def to_json(self) -> dict[str, Any]:
        """JSON-ready data; NaN becomes ``null``."""
        better, same, worse = self.summary
        return {
            "metric": self.metric,
            "lower_is_better": self.lower_is_better,
            "baseline": self.baseline,
            "alpha": self.alpha,
            "test": "corrected resampled t-test (Nadeau and Bengio; WEKA PairedCorrectedTTester)",
            "summary": {"better": better, "same": same, "worse": worse},
            "leaderboard": [row.to_json() for row in self.rows],
        }


def build_leaderboard(
    results: Sequence[TaskResult],
    *,
    metric: str = "f1_weighted",
    baseline: str | None = None,
    alpha: float = 0.05,
    groups: Mapping[str, str] | None = None,
    drops: Mapping[str, Drop] | None = None,
    origins: Mapping[str, Origin] | None = None,
) -> Leaderboard:
    """Rank the classifiers of a run and mark significant differences from a baseline.

    Parameters
    ----------
    results : sequence of TaskResult
        Every task result of the run (failed ones included).
    metric : str
        The ranking metric; descending, or ascending for :data:`LOWER_IS_BETTER` ones.
    baseline : str, optional
        The classifier to compare against; default the best ranked.
    alpha : float
        Significance level.
    groups : mapping of str to str, optional
        Comparison group of each classifier (default: one for all).  Only classifiers in
        the baseline's group are t-tested against it, fold by fold; the others are
        ranked by their means alone (results from runs whose folds do not pair).
    drops : mapping of str to Drop, optional
        Classifiers that stopped early (a raced or budgeted run) or never started (a
        cancelled run): their rows say so, and the default baseline is the best classifier
        that did not stop.
    origins : mapping of str to Origin, optional
        Entries computed from fold predictions and helpers (the engine's
        :meth:`~benchmark.run.members.RunPlan.origins`): their rows say so.

    Raises
    ------
    ConfigurationError
        No results, a metric no result has, a baseline not in the run or without a
        successful fold.

    Notes
    -----
    When no task succeeded, every classifier is listed unranked with its failures and the
    leaderboard has no baseline: a failed run still says why it failed.
    """
    if not results:
        raise ConfigurationError("no results to rank")
    by_classifier: dict[str, list[TaskResult]] = defaultdict(list)
    for result in results:
        by_classifier[result.key.classifier].append(result)
    if not any(result.ok for result in results):
        failed = [_summarise(c, rs, []) for c, rs in sorted(by_classifier.items())]
        failed += [_summarise(c, [], []) for c in drops or {} if c not in by_classifier]
        for position, row in enumerate(failed, start=1):
            row.rank = position
            row.dropped = (drops or {}).get(row.classifier)
            row.origin = (origins or {}).get(row.classifier)
        return Leaderboard(metric, None, failed, (0, 0, 0), alpha)
    available = sorted({name for r in results if r.ok for name in r.metrics})
    if metric not in available:
        raise ConfigurationError(
            f"unknown metric '{metric}' for this run (metrics: {', '.join(available) or 'none'})"
        )
    lower = metric in LOWER_IS_BETTER
    rows = [_summarise(classifier, rs, available) for classifier, rs in by_classifier.items()]
    # a classifier the budget cut, or a stopped run left, before its first fold is listed
    # too, without scores
    rows += [_summarise(c, [], available) for c in drops or {} if c not in by_classifier]
    for row in rows:
        row.dropped = (drops or {}).get(row.classifier)
        row.origin = (origins or {}).get(row.classifier)
    rows.sort(key=lambda row: _sort_key(row, metric, lower))
    _assign_ranks(rows, metric)
    if baseline is None:
        # the first row with a score: one that ran every fold, when there is one
        ranked = [row for row in rows if not math.isnan(row.metrics[metric][0])]
        if not ranked:
            raise ConfigurationError(f"no classifier has a {metric} score: every task failed")
        baseline = ranked[0].classifier
    elif baseline not in by_classifier:
        raise ConfigurationError(
            f"baseline '{baseline}' is not in this run (classifiers: {', '.join(by_classifier)})"
        )
    base_scores = scores_by_fold(by_classifier[baseline], metric)
    if not base_scores:
        raise ConfigurationError(f"baseline '{baseline}' has no successful fold with {metric}")
    counts = {"v": 0, "": 0, "*": 0}
    ratio = _test_train_ratio(results)
    group = (groups or {}).get(baseline, "")
    for row in rows:
        if row.classifier == baseline or (groups or {}).get(row.classifier, "") != group:
            continue
        scores = scores_by_fold(by_classifier[row.classifier], metric)
        paired = sorted(set(scores) & set(base_scores))
        if len(paired) < 2:
            continue
        _, row.p_value, row.mark = mark_against(
            np.array([scores[k] for k in paired]),
            np.array([base_scores[k] for k in paired]),
            test_train_ratio=ratio,
            alpha=alpha,
            lower_is_better=lower,
        )
        row.tested = True
        counts[row.mark] += 1
    return Leaderboard(metric, baseline, rows, (counts["v"], counts[""], counts["*"]), alpha)


def mark_against(
    scores: np.ndarray,
    others: np.ndarray,
    *,
    test_train_ratio: float,
    alpha: float,
    lower_is_better: bool,
) -> tuple[float, float, Mark]:
    """The corrected resampled t-test of paired per-fold ``scores`` against ``others``
    (both of shape (n_folds,)), and WEKA's mark: ``v`` significantly better, ``*`` worse,
    in the metric's own direction.

    Returns
    -------
    t, p : float
        NaN below two folds.
    mark : {"v", "*", ""}
    """
    t, p, sign = corrected_resampled_ttest(
        scores, others, test_train_ratio=test_train_ratio, alpha=alpha
    )
    if lower_is_better:
        sign = -sign
    return t, p, "v" if sign > 0 else "*" if sign < 0 else ""


def _summarise(classifier: str, results: list[TaskResult], names: list[str]) -> LeaderboardRow:
    ok = [r for r in results if r.ok]
    failed = [r for r in results if not r.ok]
    # one (n_metrics, n_ok) table and one mean and deviation per row: the same numbers as
    # per metric (each row is reduced as its own array), without a numpy call per metric
    table = np.array(
        [[r.metrics.get(name, math.nan) for r in ok] for name in names], dtype=np.float64
    ).reshape(len(names), len(ok))
    complete = np.isnan(table).sum(axis=1) == 0
    means = table.mean(axis=1) if ok else np.full(len(names), math.nan)
    stds = table.std(axis=1, ddof=1) if len(ok) > 1 else np.zeros(len(names))
    metrics = {}
    for i, name in enumerate(names):
        if complete[i] and ok:
            metrics[name] = (float(means[i]), float(stds[i]))
            continue
        values = table[i][~np.isnan(table[i])]
        if values.size == 0:
            metrics[name] = (math.nan, math.nan)
        else:
            std = float(values.std(ddof=1)) if values.size > 1 else 0.0
            metrics[name] = (float(values.mean()), std)
    errors: list[str] = []
    for r in failed:
        message = r.error or r.status
        if message not in errors and len(errors) < MAX_ERRORS:
            errors.append(message)
    return LeaderboardRow(0, classifier, metrics, "", len(ok), len(failed), errors)


def _sort_key(row: LeaderboardRow, metric: str, lower: bool) -> tuple[int, float, str]:
    """Where ``row`` ranks: by tier, then by its mean in the metric's direction, then by name.

    Tiers: 0 a score over every fold it was to run; 1 a score over the folds it ran before
    it stopped (a race dropped it, a budget cut it): a mean over fewer folds, not comparable
    with the others', so after them however high; 2 no score but a successful fold (another
    metric); 3 nothing.
    """
    mean = row.metrics[metric][0]
    if math.isnan(mean):
        return (2 if row.n_ok else 3, 0.0, row.classifier)
    return (0 if row.dropped is None else 1, mean if lower else -mean, row.classifier)


def _assign_ranks(rows: list[LeaderboardRow], metric: str) -> None:
    """Competition ranking (1, 2, 2, 4): equal means share a rank, among the rows that ran
    every fold and among those that stopped early, never across the two."""
    previous: tuple[bool, float] | None = None
    for position, row in enumerate(rows, start=1):
        now = (row.dropped is None, row.metrics[metric][0])
        # NaN == NaN is false: rows without a score never share a rank
        if previous is not None and now[0] == previous[0] and now[1] == previous[1]:
            row.rank = rows[position - 2].rank
        else:
            row.rank = position
        previous = now


def scores_by_fold(results: Sequence[TaskResult], metric: str) -> dict[tuple[int, int], float]:
    """Metric per (repeat, fold) of the successful tasks that have it."""
    return {
        (r.key.repeat, r.key.fold): r.metrics[metric]
        for r in results
        if r.ok and not math.isnan(r.metrics.get(metric, math.nan))
    }


def _test_train_ratio(results: Sequence[TaskResult]) -> float:
    """Mean ``n_test / n_train`` over the run's folds (1/9 for 10-fold CV)."""
    ratios = [r.n_test / r.n_train for r in results if r.n_train > 0]
    return float(np.mean(ratios)) if ratios else 0.0


def finite(value: float) -> float | None:
    """``value``, or ``None`` for NaN (JSON has none)."""
    return None if math.isnan(value) else value
