"""The corrected resampled t-test against a hand-computed example and WEKA's corner cases;
its moderated form's prior against R's limma, and what moderation does to a race's round."""

from __future__ import annotations

import math
import shutil
import subprocess
import warnings

import numpy as np
import pytest
from scipy.stats import t as student

from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.evaluation.significance import (
    VariancePrior,
    corrected_resampled_ttest,
    moderated_corrected_ttests,
    variance_prior,
)


def test_hand_computed_example() -> None:
    a = np.array([0.90, 0.85, 0.88, 0.92, 0.87])
    b = np.array([0.80, 0.82, 0.85, 0.84, 0.83])
    # d = 0.10, 0.03, 0.03, 0.08, 0.04: mean 0.056, sample variance 0.00103
    # t = 0.056 / sqrt((1/5 + 1/4) * 0.00103) = 2.6011...; 4 degrees of freedom
    t, p, sign = corrected_resampled_ttest(a, b, test_train_ratio=0.25)
    assert t == pytest.approx(0.056 / math.sqrt(0.45 * 0.00103))
    assert t == pytest.approx(2.6011, abs=1e-4)
    assert p == pytest.approx(0.06, abs=0.001)  # t(4) two-sided: 0.0600
    assert sign == 0  # not significant at 0.05 ...
    assert corrected_resampled_ttest(a, b, test_train_ratio=0.25, alpha=0.1)[2] == 1
    # ... whereas the uncorrected test (ratio 0) would call it significant
    t0, p0, sign0 = corrected_resampled_ttest(a, b, test_train_ratio=0.0)
    assert t0 == pytest.approx(0.056 / math.sqrt(0.00103 / 5))
    assert p0 < 0.05 and sign0 == 1


def test_sign_follows_the_direction() -> None:
    a = np.array([0.5, 0.52, 0.49, 0.51, 0.5, 0.5, 0.53, 0.48, 0.5, 0.51])
    b = a + 0.2 + np.linspace(-0.01, 0.01, 10)
    assert corrected_resampled_ttest(a, b, test_train_ratio=1 / 9)[2] == -1
    assert corrected_resampled_ttest(b, a, test_train_ratio=1 / 9)[2] == 1


def test_zero_variance_as_weka_does() -> None:
    same = np.array([0.8, 0.7, 0.9])
    assert corrected_resampled_ttest(same, same, test_train_ratio=0.5) == (0.0, 1.0, 0)
    t, p, sign = corrected_resampled_ttest(same + 0.1, same, test_train_ratio=0.5)
    assert (t, p, sign) == (math.inf, 0.0, 1)
    t, p, sign = corrected_resampled_ttest(same - 0.1, same, test_train_ratio=0.5)
    assert (t, p, sign) == (-math.inf, 0.0, -1)


def test_fewer_than_two_pairs_cannot_be_tested() -> None:
    t, p, sign = corrected_resampled_ttest(np.array([0.9]), np.array([0.1]), test_train_ratio=0.1)
    assert math.isnan(t) and math.isnan(p) and sign == 0


def test_bad_arguments() -> None:
    with pytest.raises(ConfigurationError, match="differ in length"):
        corrected_resampled_ttest(np.ones(3), np.ones(4), test_train_ratio=0.1)
    with pytest.raises(ConfigurationError, match="alpha must lie in"):
        corrected_resampled_ttest(np.ones(3), np.ones(3), test_train_ratio=0.1, alpha=0)


# the moderated test -----------------------------------------------------------------

LIMMA = """
suppressMessages(library(limma))
for (line in readLines(file("stdin"))) {
  x <- as.numeric(strsplit(line, " ")[[1]])
  n <- length(x) / 2
  f <- suppressWarnings(fitFDist(x[1:n], x[(n + 1):(2 * n)]))
  cat(format(f$scale, digits = 17), format(f$df2, digits = 17), "\n")
}
"""


def _limma_available() -> bool:
    if shutil.which("Rscript") is None:
        return False
    check = subprocess.run(
        ["Rscript", "-e", "library(limma)"], capture_output=True, text=True, check=False
    )
    return check.returncode == 0


@pytest.mark.skipif(not _limma_available(), reason="needs R's limma (apt-get install r-bioc-limma)")
def test_the_variance_prior_is_limmas_fitfdist() -> None:
    rng = np.random.default_rng(7)
    cases = []
    for n, d0, dof in [(56, 4.0, 2), (56, 12.0, 3), (300, 2.5, 9), (20, 1.0, 1)]:
        # sample variances of a scaled inverse-chi-square prior (Smyth's model)
        prior = 0.0004 * d0 / rng.chisquare(d0, size=n)
        cases.append((prior * rng.chisquare(dof, size=n) / dof, np.full(n, float(dof))))
    # degrees of freedom that differ, a zero variance, and variances alike (d0 infinite)
    mixed = rng.chisquare(3, size=30) / 3 * 1e-3
    mixed[4] = 0.0
    cases.append((mixed, rng.integers(1, 9, size=30).astype(float)))
    cases.append((np.array([0.001, 0.0012, 0.0011, 0.0009]), np.array([2.0, 3.0, 2.0, 4.0])))
    stdin = "\n".join(" ".join(repr(float(v)) for v in (*s2, *df)) for s2, df in cases)
    answer = subprocess.run(
        ["Rscript", "-e", LIMMA], input=stdin, capture_output=True, text=True, check=True
    ).stdout.splitlines()
    for (s2, df), line in zip(cases, answer, strict=True):
        scale, df2 = (float(v) for v in line.split())
        mine = variance_prior(s2, df)
        assert mine is not None
        assert mine.variance == pytest.approx(scale, rel=1e-9)
        assert mine.df == pytest.approx(df2, rel=1e-9) or mine.df == df2 == math.inf
    assert math.isinf(variance_prior(cases[-1][0], cases[-1][1]).df)  # type: ignore[union-attr]


def test_the_variance_prior_recovers_the_prior_that_drew_the_variances() -> None:
    rng = np.random.default_rng(3)
    s0, d0, df = 0.0004, 6.0, 2
    sigma2 = s0 * d0 / rng.chisquare(d0, size=20_000)
    s2 = sigma2 * rng.chisquare(df, size=sigma2.size) / df
    prior = variance_prior(s2, np.full(s2.size, df))
    assert prior is not None
    assert prior.variance == pytest.approx(s0, rel=0.05)
    assert prior.df == pytest.approx(d0, rel=0.15)


def test_no_prior_from_too_few_variances_or_mostly_zeros() -> None:
    assert variance_prior([0.1, 0.2], [2, 2]) is None
    assert variance_prior([0.0, 0.0, 0.1], [2, 2, 2]) is None
    assert variance_prior([0.1, math.nan, 0.2], [2, 2, 2]) is None
    with pytest.raises(ConfigurationError, match="3 variances but 2"):
        variance_prior([0.1, 0.2, 0.3], [2, 2])


def test_without_a_prior_the_moderated_tests_are_the_plain_ones() -> None:
    rows = [np.array([-0.02, -0.01, -0.03]), np.array([0.01, -0.02, 0.0, 0.01])]
    tests = moderated_corrected_ttests(rows, test_train_ratio=0.125)
    for (t, p), d in zip(tests, rows, strict=True):
        plain_t, plain_p, _ = corrected_resampled_ttest(d, np.zeros(d.size), test_train_ratio=0.125)
        assert (t, p) == (plain_t, plain_p)
    [(t, p)] = moderated_corrected_ttests([np.array([0.1])], test_train_ratio=0.125)
    assert math.isnan(t) and math.isnan(p)


def _round_of_a_race(seed: int = 0) -> list[np.ndarray]:
    """A race's third round: 40 entries' per-fold differences from the leader, deficits of
    0.01-0.3 with fold-to-fold deviations about 0.02; the last is close to the leader
    (-0.004) and its three differences happen to agree."""
    rng = np.random.default_rng(seed)
    rows = [rng.normal(-rng.uniform(0.01, 0.3), 0.02, size=3) for _ in range(40)]
    rows.append(np.array([-0.0035, -0.0045, -0.0040]))
    return rows


def test_moderation_keeps_a_close_entry_whose_few_differences_agree_by_chance() -> None:
    rows = _round_of_a_race()
    ratio = 1 / 9
    moderated = moderated_corrected_ttests(rows, test_train_ratio=ratio)
    plain = [corrected_resampled_ttest(d, np.zeros(3), test_train_ratio=ratio)[1] for d in rows]
    # the plain test calls the close entry's 0.004 deficit certain; moderated, it is not
    assert plain[-1] < 0.01 < moderated[-1][1]
    # and the clearly worse are found at least as surely: more degrees of freedom
    far = [i for i, d in enumerate(rows[:-1]) if d.mean() < -0.1]
    assert far and all(moderated[i][1] < 0.01 for i in far)
    assert sum(p < 0.01 for _, p in moderated[:-1]) >= sum(p < 0.01 for p in plain[:-1])


def test_the_moderated_variance_and_degrees_of_freedom_by_hand() -> None:
    rows = _round_of_a_race()
    prior = variance_prior([float(d.var(ddof=1)) for d in rows], [2.0] * len(rows))
    assert isinstance(prior, VariancePrior) and 0 < prior.df < math.inf
    d = rows[-1]
    variance = (prior.df * prior.variance + 2 * d.var(ddof=1)) / (prior.df + 2)
    t = d.mean() / math.sqrt((1 / 3 + 1 / 9) * variance)
    t_mine, p_mine = moderated_corrected_ttests(rows, test_train_ratio=1 / 9)[-1]
    assert t_mine == pytest.approx(t, rel=1e-12)
    assert p_mine == pytest.approx(2 * student.sf(abs(t), prior.df + 2), rel=1e-9)


def test_an_infinite_difference_takes_the_plain_test_and_warns_nothing() -> None:
    """A regressor whose error overflowed on a fold (an infinite MAE) is certainly worse: the
    plain test says p = 0, as for a constant deficit; its variance is no variance, so it
    neither joins the prior nor makes the moderated test's p NaN."""
    rng = np.random.default_rng(3)
    differences = [rng.normal(-0.01, 0.02, 3) for _ in range(10)]
    broken = np.array([-np.inf, -0.1, -0.2])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        out = moderated_corrected_ttests([*differences, broken], test_train_ratio=1 / 9)
        finite = moderated_corrected_ttests(differences, test_train_ratio=1 / 9)
    assert out[-1] == (-math.inf, 0.0)
    assert out[:-1] == finite  # the others' prior as without it
