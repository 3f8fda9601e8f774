"""The corrected resampled t-test that WEKA's Experimenter uses to compare two schemes,
and its moderated form for many comparisons on few folds.

Nadeau and Bengio (2003), "Inference for the Generalization Error", as implemented by
WEKA's ``PairedCorrectedTTester``: the variance of the paired differences is inflated by
the test/train size ratio, because cross-validation training sets overlap.

Smyth (2004), "Linear models and empirical Bayes methods for assessing differential
expression in microarray experiments" (limma's moderated t): when many pairs are compared
on the same few folds, each pair's sample variance of the differences is shrunk towards a
prior fitted to all of them.  On two or three folds a sample variance is often far too
small by chance (two near-equal entries whose differences happen to agree), which makes
the plain test declare a small difference significant; the moderated variance cannot be
much smaller than the others', and its extra degrees of freedom keep the test's power
for the large differences.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from scipy.special import digamma, polygamma, stdtr

from touchbench.benchmark.errors import ConfigurationError


def corrected_resampled_ttest(
    a: np.ndarray,
    b: np.ndarray,
    *,
    test_train_ratio: float,
    alpha: float = 0.05,
) -> tuple[float, float, int]:
    """Compare paired per-fold scores of two classifiers.

    Parameters
    ----------
    a, b : ndarray of shape (k,)
        Scores of the two classifiers on the same k folds (same order).
    test_train_ratio : float
        ``n_test / n_train`` of a fold (1/9 for 10-fold cross-validation).
    alpha : float
        Two-sided significance level.

    Returns
    -------
    t : float
        ``mean(d) / sqrt((1/k + test_train_ratio) * var(d))`` with ``d = a - b`` and the
        sample variance (ddof 1); 0 when all differences are 0, +-inf when they are all
        the same non-zero value, NaN when k < 2.
    p : float
        Two-sided p-value with k - 1 degrees of freedom.  As in WEKA, zero variance gives
        p = 1 when all differences are 0 and p = 0 when they are all the same non-zero
        value.  NaN when k < 2.
    sign : int
        +1 if ``a`` is significantly higher than ``b`` (p <= alpha), -1 if significantly
        lower, 0 otherwise.
    """
    a = np.asarray(a, dtype=np.float64).reshape(-1)
    b = np.asarray(b, dtype=np.float64).reshape(-1)
    if a.shape != b.shape:
        raise ConfigurationError(f"paired scores differ in length: {a.size} and {b.size}")
    if not test_train_ratio >= 0:
        raise ConfigurationError(f"test_train_ratio must be >= 0, got {test_train_ratio}")
    if not 0 < alpha < 1:
        raise ConfigurationError(f"alpha must lie in (0, 1), got {alpha}")
    k = a.size
    if k < 2:
        return math.nan, math.nan, 0
    with np.errstate(invalid="ignore", over="ignore"):  # an infinite score: see below
        d = a - b
        mean = float(d.mean())
        variance = float(d.var(ddof=1))
    if variance > 0:
        t, p = _corrected_t(mean, variance, k, test_train_ratio, df=k - 1)
    elif mean == 0:
        t, p = 0.0, 1.0
    else:
        t, p = math.copysign(math.inf, mean), 0.0
    sign = 0
    if p <= alpha:
        sign = 1 if a.mean() > b.mean() else -1
    return t, p, sign


def _corrected_t(
    mean: float, variance: float, k: int, test_train_ratio: float, *, df: float
) -> tuple[float, float]:
    """Nadeau and Bengio's t of ``k`` paired differences of ``mean`` and ``variance`` (> 0),
    and its two-sided p-value with ``df`` degrees of freedom (``inf``: the normal's)."""
    t = mean / math.sqrt((1.0 / k + test_train_ratio) * variance)
    return t, float(2.0 * stdtr(df, -abs(t)))  # Student's t survival function, as a ufunc


@dataclass(frozen=True)
class VariancePrior:
    """The scaled inverse-chi-square prior of many comparisons' variances.

    Attributes
    ----------
    variance : float
        The prior's location ``s0^2``.
    df : float
        Its degrees of freedom ``d0`` (how much a comparison's own variance is shrunk
        towards ``variance``); ``inf`` when the variances differ no more than chance says.
    """

    variance: float
    df: float


#: Fewer positive variances than this say too little about their spread: no prior.
MIN_PRIOR_VARIANCES = 3


def variance_prior(variances: npt.ArrayLike, dfs: npt.ArrayLike) -> VariancePrior | None:
    """Fit the prior of sample variances by the moments of their logarithms (Smyth 2004,
    limma's ``fitFDist`` without covariates).

    Parameters
    ----------
    variances : array-like of shape (n,)
        Sample variances (>= 0); NaN ones are left out.  Zeros (identical differences)
        count, raised to 1e-5 of the median as limma does.
    dfs : array-like of shape (n,)
        Their degrees of freedom, each > 0.

    Returns
    -------
    VariancePrior or None
        None with fewer than :data:`MIN_PRIOR_VARIANCES` variances, or when more than half
        are zero (nothing to scale the prior by).
    """
    s2 = np.asarray(variances, dtype=np.float64).reshape(-1)
    df = np.asarray(dfs, dtype=np.float64).reshape(-1)
    if s2.shape != df.shape:
        raise ConfigurationError(f"{s2.size} variances but {df.size} degrees of freedom")
    kept = np.isfinite(s2) & (s2 >= 0) & np.isfinite(df) & (df > 0)
    s2, df = s2[kept], df[kept]
    if s2.size < MIN_PRIOR_VARIANCES or (median := float(np.median(s2))) == 0:
        return None
    s2 = np.maximum(s2, 1e-5 * median)
    # log s^2 = log s0^2 + log F(d, d0): its mean and variance give d0 and s0^2
    e = np.log(s2) - digamma(df / 2) + np.log(df / 2)
    mean = float(e.mean())
    spread = float(e.var(ddof=1)) - float(polygamma(1, df / 2).mean())
    if spread <= 0:  # no more spread than chance gives: one variance for all
        return VariancePrior(float(s2.mean()), math.inf)
    d0 = 2.0 * _trigamma_inverse(spread)
    return VariancePrior(math.exp(mean + float(digamma(d0 / 2)) - math.log(d0 / 2)), d0)


def _trigamma_inverse(x: float) -> float:
    """``y`` with ``trigamma(y) = x`` (Smyth's Newton iteration, monotone from below)."""
    if x > 1e7:
        return 1.0 / math.sqrt(x)
    if x < 1e-6:
        return 1.0 / x
    y = 0.5 + 1.0 / x
    for _ in range(50):
        trigamma = float(polygamma(1, y))
        step = trigamma * (1.0 - trigamma / x) / float(polygamma(2, y))
        y += step
        if -step / y < 1e-8:
            break
    return y


def moderated_corrected_ttests(
    differences: Sequence[np.ndarray], *, test_train_ratio: float
) -> list[tuple[float, float]]:
    """Corrected resampled t-tests of many paired comparisons at once, their variances
    moderated by a prior fitted to all of them (:func:`variance_prior`).

    Parameters
    ----------
    differences : sequence of ndarray, each of shape (k_i,)
        Per-fold differences ``a - b`` of each comparison (its own folds, k_i >= 2).
    test_train_ratio : float
        ``n_test / n_train`` of a fold.

    Returns
    -------
    list of (t, p)
        For each comparison: ``mean / sqrt((1/k + ratio) * v)`` with the moderated variance
        ``v = (d0 s0^2 + (k - 1) s^2) / (d0 + k - 1)`` and the two-sided p-value with
        ``d0 + k - 1`` degrees of freedom.  Without a prior (too few comparisons) each is
        :func:`corrected_resampled_ttest`'s, and so is a comparison with an infinite
        difference (an infinite deficit is a certain one); NaN for a comparison of fewer
        than 2 folds.
    """
    if not test_train_ratio >= 0:
        raise ConfigurationError(f"test_train_ratio must be >= 0, got {test_train_ratio}")
    rows = [np.asarray(d, dtype=np.float64).reshape(-1) for d in differences]
    # NaN for fewer than 2 folds, which the prior leaves out (no degrees of freedom); an
    # infinite difference (a regressor's error that overflowed) has no finite variance
    with np.errstate(invalid="ignore", over="ignore"):
        variances = [float(d.var(ddof=1)) if d.size >= 2 else math.nan for d in rows]
    prior = variance_prior(variances, [max(d.size - 1, 0) for d in rows])
    out = []
    for d, own in zip(rows, variances, strict=True):
        k = d.size
        if k < 2:
            out.append((math.nan, math.nan))
            continue
        if prior is None or not np.isfinite(d).all():
            # the plain test: as WEKA's, an infinite deficit is a certain one
            t, p, _ = corrected_resampled_ttest(d, np.zeros(k), test_train_ratio=test_train_ratio)
            out.append((t, p))
            continue
        df = k - 1.0
        if math.isinf(prior.df):
            variance, df = prior.variance, math.inf
        else:
            variance = (prior.df * prior.variance + df * own) / (prior.df + df)
            df += prior.df
        out.append(_corrected_t(float(d.mean()), variance, k, test_train_ratio, df=df))
    return out
