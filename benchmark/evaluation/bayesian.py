"""Bayesian comparison of two classifiers, with a region of practical equivalence.

Instead of a p-value, each test gives the posterior probabilities that classifier A is
better by more than ``rope`` (*left*), that the two are practically equivalent (their
difference lies within ``[-rope, rope]``, *rope*), and that B is better by more than
``rope`` (*right*) (Benavoli, Corani, Demšar and Zaffalon, 2017, "Time for a change: a
tutorial for comparing multiple classifiers through Bayesian analysis", JMLR 18).

- :func:`correlated_ttest`: on one data set, from paired cross-validation folds (Corani and
  Benavoli, 2015): the posterior of the mean difference is a Student t with n - 1 degrees
  of freedom, location the mean difference and scale
  ``sqrt((1/n + n_test/n_train) * var)``, Nadeau and Bengio's correction for the overlap
  of training sets (the same variance WEKA's corrected t-test uses).
- :func:`signed_rank_test`: across data sets, from one mean score per data set (Benavoli et
  al., 2014, "A Bayesian Wilcoxon signed-rank test based on the Dirichlet process"): a
  Dirichlet process posterior (prior strength ``prior`` on a pseudo-observation at 0),
  sampled; the probabilities are how often each region wins a sample.

"Better" follows the metric's direction: pass ``lower_is_better=True`` for losses and times.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from touchbench.benchmark.errors import ConfigurationError

#: Default half-width of the region of practical equivalence, in the metric's units.
DEFAULT_ROPE = 0.01


@dataclass(frozen=True)
class BayesianComparison:
    """Posterior probabilities of A better / practically equivalent / B better.

    Attributes
    ----------
    test : str
        ``"correlated t-test"`` or ``"Bayesian signed-rank test"``.
    p_left : float
        A is better by more than ``rope``.
    p_rope : float
        The difference lies within ``[-rope, rope]``.
    p_right : float
        B is better by more than ``rope``.
    rope : float
        Half-width of the region of practical equivalence.
    mean_difference : float
        Mean of ``a - b`` over the pairs (in the metric's units and sign, whatever its
        direction).
    n : int
        Number of pairs (folds or data sets).
    """

    test: str
    p_left: float
    p_rope: float
    p_right: float
    rope: float
    mean_difference: float
    n: int

    def decision(self, threshold: float = 0.95) -> str:
        """``"left"``, ``"rope"`` or ``"right"`` when one probability reaches
        ``threshold``, else ``"undecided"``."""
        for name, p in (("left", self.p_left), ("rope", self.p_rope), ("right", self.p_right)):
            if p >= threshold:
                return name
        return "undecided"


def correlated_ttest(
    a: np.ndarray,
    b: np.ndarray,
    *,
    test_train_ratio: float,
    rope: float = DEFAULT_ROPE,
    lower_is_better: bool = False,
) -> BayesianComparison:
    """The Bayesian correlated t-test on paired cross-validation scores of one data set.

    Parameters
    ----------
    a, b : ndarray of shape (n,)
        Scores of classifiers A and B on the same n folds (all repeats), same order.
    test_train_ratio : float
        ``n_test / n_train`` of a fold (1/9 for 10-fold cross-validation); the correlation
        ``rho = n_test / n`` of Corani and Benavoli enters as ``rho / (1 - rho)``.
    rope : float
        Half-width of the region of practical equivalence, >= 0.
    lower_is_better : bool
        The metric's direction.

    Returns
    -------
    BayesianComparison
        When every difference is the same the posterior is a point mass there: the
        region holding it has probability 1.

    Raises
    ------
    ConfigurationError
        Unequal lengths, fewer than 2 pairs, NaN scores, a negative rope or ratio.
    """
    a, b = _pairs(a, b, minimum=2)
    _check_rope(rope)
    if not test_train_ratio >= 0:
        raise ConfigurationError(f"test_train_ratio must be >= 0, got {test_train_ratio}")
    better = _advantage(a, b, lower_is_better)
    n = better.size
    mean = float(better.mean())
    variance = float(better.var(ddof=1))
    scale = math.sqrt((1.0 / n + test_train_ratio) * variance)
    if scale > 0:
        # imported here: SciPy's distributions take longer to load than every page that
        # imports this module for its types takes to answer
        from scipy.stats import t as student_t

        p_left = float(student_t.sf(rope, n - 1, loc=mean, scale=scale))
        p_right = float(student_t.cdf(-rope, n - 1, loc=mean, scale=scale))
    else:
        p_left, p_right = float(mean > rope), float(mean < -rope)
    return BayesianComparison(
        "correlated t-test",
        p_left,
        max(0.0, 1.0 - p_left - p_right),
        p_right,
        rope,
        float((a - b).mean()),
        n,
    )


def signed_rank_test(
    a: np.ndarray,
    b: np.ndarray,
    *,
    rope: float = DEFAULT_ROPE,
    lower_is_better: bool = False,
    prior: float = 0.5,
    n_samples: int = 50_000,
    seed: int = 0,
) -> BayesianComparison:
    """The Bayesian signed-rank test on paired mean scores over data sets.

    Parameters
    ----------
    a, b : ndarray of shape (n,)
        Mean scores of classifiers A and B on the same n data sets.
    rope : float
        Half-width of the region of practical equivalence, >= 0.
    lower_is_better : bool
        The metric's direction.
    prior : float
        Strength of the Dirichlet process prior, a pseudo-observation at difference 0.
    n_samples : int
        Posterior samples (Monte Carlo error about ``0.5 / sqrt(n_samples)``).
    seed : int
        Seed of the sampling, for results that repeat.

    Returns
    -------
    BayesianComparison
        Each sample weighs the n differences and the pseudo-observation by Dirichlet
        weights w; the posterior mass of "A better" is the weighted share of Walsh
        averages ``(d_i + d_j) / 2`` above ``rope``, counting ties with the boundary
        half; likewise below ``-rope``; the rest is the rope.  A region's probability is
        the share of samples in which its mass is the largest.

    Raises
    ------
    ConfigurationError
        Unequal lengths, no pair, NaN scores, a negative rope, prior <= 0, n_samples < 1.
    """
    a, b = _pairs(a, b, minimum=1)
    _check_rope(rope)
    if not prior > 0:
        raise ConfigurationError(f"prior must be > 0, got {prior}")
    if n_samples < 1:
        raise ConfigurationError(f"n_samples must be >= 1, got {n_samples}")
    better = np.concatenate(([0.0], _advantage(a, b, lower_is_better)))
    sums = better[:, None] + better[None, :]
    above = _step(sums - 2.0 * rope)
    below = _step(-sums - 2.0 * rope)
    alpha = np.ones(better.size)
    alpha[0] = prior
    weights = np.random.default_rng(seed).dirichlet(alpha, n_samples)
    mass_left = ((weights @ above) * weights).sum(axis=1)
    mass_right = ((weights @ below) * weights).sum(axis=1)
    masses = np.stack([mass_left, 1.0 - mass_left - mass_right, mass_right], axis=1)
    if rope == 0:  # no equivalence region: only "left" and "right" can win
        masses[:, 1] = -1.0
    wins = np.bincount(masses.argmax(axis=1), minlength=3) / n_samples
    return BayesianComparison(
        "Bayesian signed-rank test",
        float(wins[0]),
        float(wins[1]),
        float(wins[2]),
        rope,
        float((a - b).mean()),
        int(a.size),
    )


def _pairs(a: np.ndarray, b: np.ndarray, *, minimum: int) -> tuple[np.ndarray, np.ndarray]:
    a = np.asarray(a, dtype=np.float64).reshape(-1)
    b = np.asarray(b, dtype=np.float64).reshape(-1)
    if a.shape != b.shape:
        raise ConfigurationError(f"paired scores differ in length: {a.size} and {b.size}")
    if a.size < minimum:
        raise ConfigurationError(f"the comparison needs at least {minimum} pair(s), got {a.size}")
    if np.isnan(a).any() or np.isnan(b).any():
        raise ConfigurationError("paired scores contain NaN: leave out the unpaired ones")
    return a, b


def _advantage(a: np.ndarray, b: np.ndarray, lower_is_better: bool) -> np.ndarray:
    """How much better A is than B, pair by pair (positive: A better)."""
    return b - a if lower_is_better else a - b


def _step(x: np.ndarray) -> np.ndarray:
    """Heaviside step with 1/2 at 0."""
    return (x > 0).astype(np.float64) + 0.5 * (x == 0)


def _check_rope(rope: float) -> None:
    if not rope >= 0:
        raise ConfigurationError(f"rope must be >= 0, got {rope}")
