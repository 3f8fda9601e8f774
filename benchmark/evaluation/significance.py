"""The corrected resampled t-test that WEKA's Experimenter uses to compare two schemes.

Nadeau and Bengio (2003), "Inference for the Generalization Error", as implemented by
WEKA's ``PairedCorrectedTTester``: the variance of the paired differences is inflated by
the test/train size ratio, because cross-validation training sets overlap.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.special import stdtr

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
    d = a - b
    mean = float(d.mean())
    variance = float(d.var(ddof=1))
    if variance > 0:
        t = mean / math.sqrt((1.0 / k + test_train_ratio) * variance)
        p = float(2.0 * stdtr(k - 1, -abs(t)))  # Student's t survival function, as a ufunc
    elif mean == 0:
        t, p = 0.0, 1.0
    else:
        t, p = math.copysign(math.inf, mean), 0.0
    sign = 0
    if p <= alpha:
        sign = 1 if a.mean() > b.mean() else -1
    return t, p, sign
