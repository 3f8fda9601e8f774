"""Comparing classifiers over several data sets (Demšar, 2006).

Demšar, J. (2006), "Statistical Comparisons of Classifiers over Multiple Data Sets",
JMLR 7:1-30.  Each classifier gets one score per data set (a *block*); within each
block the classifiers are ranked (1 = best, ties share the average rank), and:

- Friedman's test asks whether the average ranks differ more than chance allows, as a
  chi-square statistic and as Iman and Davenport's F statistic;
- the Nemenyi test calls two classifiers different when their average ranks differ by
  more than the critical difference ``CD = q_alpha * sqrt(k (k + 1) / (6 N))``, with
  ``q_alpha`` the studentised range statistic (k groups, infinite degrees of freedom)
  divided by sqrt(2);
- Holm's step-down procedure tests every classifier against one control (the best by
  default) with ``z = (R_control - R_i) / sqrt(k (k + 1) / (6 N))``.

The direction of the metric decides the ranks: for
:data:`~benchmark.evaluation.metrics.LOWER_IS_BETTER` metrics the smallest score ranks 1.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.evaluation.score_table import ScoreTable

# Imports inside functions: start-up time: the service's run, fold and compare routes name
# these tests, and scipy.stats, the largest import of a service's start, would load unused


@dataclass(frozen=True)
class FriedmanResult:
    """Friedman's test on ranks of k classifiers over N blocks.

    Attributes
    ----------
    statistic : float
        Friedman's chi-square, ``12 N / (k (k + 1)) * (sum_j R_j^2 - k (k + 1)^2 / 4)``
        (divided by the tie correction when it was asked for).
    p_value : float
        Chi-square with k - 1 degrees of freedom.
    iman_davenport : float
        ``(N - 1) chi2 / (N (k - 1) - chi2)``; infinite when every block ranks the
        classifiers the same way.
    iman_davenport_p_value : float
        F with k - 1 and (k - 1)(N - 1) degrees of freedom.
    df, df_denominator : int
        k - 1 and (k - 1)(N - 1).
    tie_corrected : bool
        Whether the chi-square was divided by ``1 - sum(t^3 - t) / (N k (k^2 - 1))``
        (as :func:`scipy.stats.friedmanchisquare` does); Demšar's formulas are not.
    """

    statistic: float
    p_value: float
    iman_davenport: float
    iman_davenport_p_value: float
    df: int
    df_denominator: int
    tie_corrected: bool


@dataclass(frozen=True)
class HolmComparison:
    """One classifier against the control in Holm's step-down procedure.

    Attributes
    ----------
    classifier : str
    z : float
        ``(R_control - R_classifier) / SE``: negative when the classifier ranks worse.
    p_value : float
        Two-sided, unadjusted.
    adjusted_p_value : float
        Holm's adjusted p-value (comparable with alpha).
    significant : bool
        Rejected by the step-down procedure at the comparison's alpha.
    """

    classifier: str
    z: float
    p_value: float
    adjusted_p_value: float
    significant: bool


@dataclass(frozen=True)
class RankComparison:
    """Everything Demšar's procedure says about k classifiers over N blocks.

    Attributes
    ----------
    classifiers : tuple of str
        Best first (by average rank; equal ranks in the input's order).
    average_ranks : ndarray of shape (k,)
        In the order of ``classifiers``.
    mean_scores : ndarray of shape (k,)
        Mean score over the blocks (infinite where a missing cell was ranked worst).
    ranks : ndarray of shape (N, k)
        Per-block ranks, columns in the order of ``classifiers``.
    blocks : tuple of str
    friedman : FriedmanResult
    q_alpha : float
        The studentised range quantile divided by sqrt(2) (Demšar's Table 5a).
    critical_difference : float
        Nemenyi's CD at ``alpha``.
    nemenyi_p_values : ndarray of shape (k, k)
        Pairwise p-values of the Nemenyi test (1 on the diagonal).
    control : str
        The classifier of Holm's procedure.
    holm : tuple of HolmComparison
        Every other classifier, in increasing order of p-value.
    groups : tuple of tuple of str
        Maximal runs of consecutive classifiers (best first) whose average ranks lie
        within the critical difference of each other: the bars of a CD diagram.  Groups
        of one are left out.
    alpha : float
    lower_is_better : bool
    """

    classifiers: tuple[str, ...]
    average_ranks: np.ndarray
    mean_scores: np.ndarray
    ranks: np.ndarray
    blocks: tuple[str, ...]
    friedman: FriedmanResult
    q_alpha: float
    critical_difference: float
    nemenyi_p_values: np.ndarray
    control: str
    holm: tuple[HolmComparison, ...]
    groups: tuple[tuple[str, ...], ...]
    alpha: float
    lower_is_better: bool

    @property
    def n_blocks(self) -> int:
        return len(self.blocks)

    def average_rank(self, classifier: str) -> float:
        return float(self.average_ranks[self.classifiers.index(classifier)])

    def different(self, a: str, b: str) -> bool:
        """Whether the Nemenyi test tells ``a`` and ``b`` apart at ``alpha``."""
        return abs(self.average_rank(a) - self.average_rank(b)) > self.critical_difference


def rank_scores(scores: np.ndarray, *, lower_is_better: bool = False) -> np.ndarray:
    """Ranks within each block: 1 for the best score, ties share their average rank.

    Parameters
    ----------
    scores : ndarray of shape (n_blocks, k)
        No NaN (see :meth:`ScoreTable.complete`); infinities rank as the extremes.
    lower_is_better : bool

    Returns
    -------
    ndarray of shape (n_blocks, k)
    """
    scores = np.asarray(scores, dtype=np.float64)
    if scores.ndim != 2:
        raise ConfigurationError(
            f"scores must be a (blocks, classifiers) matrix, got shape {scores.shape}"
        )
    if np.isnan(scores).any():
        raise ConfigurationError("scores have missing cells: complete the table first")
    from scipy.stats import rankdata

    return np.asarray(rankdata(scores if lower_is_better else -scores, axis=1), dtype=np.float64)


def friedman_test(ranks: np.ndarray, *, correct_ties: bool = False) -> FriedmanResult:
    """Friedman's test and Iman and Davenport's F on per-block ranks.

    Parameters
    ----------
    ranks : ndarray of shape (N, k)
        Per-block ranks (:func:`rank_scores`), N >= 2 blocks, k >= 2 classifiers.
    correct_ties : bool
        Divide the chi-square by the tie correction (scipy's ``friedmanchisquare``);
        Demšar's formula, the default, does not.
    """
    ranks = np.asarray(ranks, dtype=np.float64)
    n, k = _check_size(ranks.shape)
    average = ranks.mean(axis=0)
    statistic = 12.0 * n / (k * (k + 1)) * float((average**2).sum() - k * (k + 1) ** 2 / 4.0)
    statistic = max(statistic, 0.0)  # rounding can leave -1e-15 when every rank ties
    if correct_ties:
        ties = sum(
            float((counts**3 - counts).sum())
            for counts in (np.unique(row, return_counts=True)[1] for row in ranks)
        )
        correction = 1.0 - ties / (n * k * (k * k - 1))
        statistic = statistic / correction if correction > 0 else 0.0
    df, df_denominator = k - 1, (k - 1) * (n - 1)
    from scipy.stats import chi2
    from scipy.stats import f as f_distribution

    p_value = float(chi2.sf(statistic, df))
    denominator = n * (k - 1) - statistic
    if denominator <= 1e-12 * n * k:
        iman_davenport, id_p_value = math.inf, 0.0
    else:
        iman_davenport = (n - 1) * statistic / denominator
        id_p_value = float(f_distribution.sf(iman_davenport, df, df_denominator))
    return FriedmanResult(
        statistic, p_value, iman_davenport, id_p_value, df, df_denominator, correct_ties
    )


def studentized_range_q(k: int, alpha: float) -> float:
    """Demšar's ``q_alpha``: the studentised range quantile over sqrt(2) (Table 5a)."""
    _check_alpha(alpha)
    if k < 2:
        raise ConfigurationError(f"the Nemenyi test needs at least 2 classifiers, got {k}")
    from scipy.stats import studentized_range

    return float(studentized_range.ppf(1.0 - alpha, k, math.inf) / math.sqrt(2.0))


def nemenyi_critical_difference(k: int, n_blocks: int, alpha: float = 0.05) -> float:
    """The average-rank difference beyond which the Nemenyi test finds two of k
    classifiers different over ``n_blocks`` blocks."""
    _check_size((n_blocks, k))
    return studentized_range_q(k, alpha) * _rank_standard_error(k, n_blocks)


def nemenyi_p_values(average_ranks: np.ndarray, n_blocks: int) -> np.ndarray:
    """Pairwise p-values of the Nemenyi test.

    Parameters
    ----------
    average_ranks : ndarray of shape (k,)
    n_blocks : int

    Returns
    -------
    ndarray of shape (k, k)
        ``P(studentised range >= sqrt(2) |R_i - R_j| / SE)``; 1 on the diagonal.
    """
    average_ranks = np.asarray(average_ranks, dtype=np.float64)
    k = average_ranks.size
    _check_size((n_blocks, k))
    q = np.abs(average_ranks[:, None] - average_ranks[None, :]) / _rank_standard_error(k, n_blocks)
    from scipy.stats import studentized_range

    p_values = np.asarray(studentized_range.sf(q * math.sqrt(2.0), k, math.inf))
    np.fill_diagonal(p_values, 1.0)
    return np.minimum(p_values, 1.0)


def holm_test(
    average_ranks: np.ndarray,
    n_blocks: int,
    *,
    control: int,
    names: tuple[str, ...],
    alpha: float = 0.05,
) -> tuple[HolmComparison, ...]:
    """Holm's step-down test of every classifier against a control.

    Parameters
    ----------
    average_ranks : ndarray of shape (k,)
    n_blocks : int
    control : int
        Index of the control classifier in ``average_ranks``.
    names : tuple of str
        Classifier names, in the order of ``average_ranks``.
    alpha : float
        Family-wise significance level.

    Returns
    -------
    tuple of HolmComparison
        The k - 1 comparisons in increasing order of p-value.  The i-th (1-based) is
        rejected when it and every one before it have ``p <= alpha / (k - i)``; its
        adjusted p-value is ``max_{j <= i} min(1, (k - j) p_j)``.
    """
    _check_alpha(alpha)
    average_ranks = np.asarray(average_ranks, dtype=np.float64)
    k = average_ranks.size
    _check_size((n_blocks, k))
    others = [i for i in range(k) if i != control]
    z = (average_ranks[control] - average_ranks[others]) / _rank_standard_error(k, n_blocks)
    from scipy.stats import norm

    p = 2.0 * norm.sf(np.abs(z))
    order = np.argsort(p, kind="stable")
    m = len(others)
    comparisons = []
    adjusted = 0.0
    rejecting = True
    for step, i in enumerate(order):
        adjusted = max(adjusted, min(1.0, (m - step) * float(p[i])))
        rejecting = rejecting and float(p[i]) <= alpha / (m - step)
        comparisons.append(
            HolmComparison(names[others[i]], float(z[i]), float(p[i]), adjusted, rejecting)
        )
    return tuple(comparisons)


def nemenyi_groups(sorted_ranks: np.ndarray, critical_difference: float) -> list[tuple[int, int]]:
    """Maximal runs of classifiers that the Nemenyi test does not tell apart.

    Parameters
    ----------
    sorted_ranks : ndarray of shape (k,)
        Average ranks in increasing order.
    critical_difference : float

    Returns
    -------
    list of (int, int)
        ``(first, last)`` index pairs, ``first < last``: every classifier from ``first`` to
        ``last`` lies within the critical difference of ``first``; no pair is contained in
        another.
    """
    groups: list[tuple[int, int]] = []
    reach = -1
    for first in range(sorted_ranks.size):
        last = first
        while last + 1 < sorted_ranks.size and (
            sorted_ranks[last + 1] - sorted_ranks[first] <= critical_difference
        ):
            last += 1
        if last > first and last > reach:
            groups.append((first, last))
            reach = last
    return groups


def compare_classifiers(
    table: ScoreTable,
    *,
    lower_is_better: bool = False,
    alpha: float = 0.05,
    control: str | None = None,
    correct_ties: bool = False,
) -> RankComparison:
    """Demšar's procedure on a complete score table.

    Parameters
    ----------
    table : ScoreTable
        Shape (N, k) with N >= 2 blocks and k >= 2 classifiers, no missing cell (use
        :meth:`ScoreTable.complete` first).
    lower_is_better : bool
        The metric's direction.
    alpha : float
        Significance level of the Nemenyi CD and of Holm's procedure.
    control : str, optional
        Holm's control classifier; default the best ranked.
    correct_ties : bool
        Tie-correct Friedman's chi-square (see :func:`friedman_test`).

    Raises
    ------
    ConfigurationError
        Missing cells, fewer than 2 blocks or classifiers, alpha outside (0, 1), an
        unknown control.
    """
    _check_alpha(alpha)
    missing = table.missing_cells()
    if missing:
        cells = ", ".join(f"'{m.classifier}' on '{m.block}'" for m in missing[:3])
        raise ConfigurationError(f"{len(missing)} missing score(s) ({cells}): complete the table")
    ranks = rank_scores(table.scores, lower_is_better=lower_is_better)
    n, k = _check_size(ranks.shape)
    average = ranks.mean(axis=0)
    order = np.argsort(average, kind="stable")
    names = tuple(table.classifiers[i] for i in order)
    average = average[order]
    ranks = ranks[:, order]
    if control is None:
        control = names[0]
    elif control not in names:
        raise ConfigurationError(
            f"control '{control}' is not in the comparison (classifiers: {', '.join(names)})"
        )
    cd = nemenyi_critical_difference(k, n, alpha)
    groups = nemenyi_groups(average, cd)
    return RankComparison(
        classifiers=names,
        average_ranks=average,
        mean_scores=table.scores[:, order].mean(axis=0),
        ranks=ranks,
        blocks=table.blocks,
        friedman=friedman_test(ranks, correct_ties=correct_ties),
        q_alpha=studentized_range_q(k, alpha),
        critical_difference=cd,
        nemenyi_p_values=nemenyi_p_values(average, n),
        control=control,
        holm=holm_test(average, n, control=names.index(control), names=names, alpha=alpha),
        groups=tuple(names[first : last + 1] for first, last in groups),
        alpha=alpha,
        lower_is_better=lower_is_better,
    )


def _rank_standard_error(k: int, n_blocks: int) -> float:
    return math.sqrt(k * (k + 1) / (6.0 * n_blocks))


def _check_size(shape: tuple[int, ...]) -> tuple[int, int]:
    n, k = int(shape[0]), int(shape[1])
    if k < 2:
        raise ConfigurationError(f"comparing classifiers needs at least 2 of them, got {k}")
    if n < 2:
        raise ConfigurationError(
            f"ranking classifiers needs at least 2 data sets (blocks), got {n}"
        )
    return n, k


def _check_alpha(alpha: float) -> None:
    if not 0 < alpha < 1:
        raise ConfigurationError(f"alpha must lie in (0, 1), got {alpha}")
