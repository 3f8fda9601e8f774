"""Statistics across data sets against Demšar's worked example (JMLR 7, 2006, section 3.2.4),
autorank, scikit-posthocs, statsmodels and scipy (test-only oracles)."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
import scikit_posthocs
from autorank import autorank
from autorank._util import get_sorted_rank_groups
from scipy.stats import friedmanchisquare
from statsmodels.stats.multitest import multipletests

from tests.support.demsar import DEMSAR_AUC, DEMSAR_NAMES
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.evaluation.score_table import ScoreTable
from touchbench.benchmark.evaluation.statistics import (
    compare_classifiers,
    friedman_test,
    nemenyi_critical_difference,
    rank_scores,
    studentized_range_q,
)

DEMSAR_DATASETS = (
    "adult (sample)",
    "breast cancer",
    "breast cancer wisconsin",
    "cmc",
    "ionosphere",
    "iris",
    "liver disorders",
    "lung cancer",
    "lymphography",
    "mushroom",
    "primary tumor",
    "rheum",
    "voting",
    "wine",
)


def demsar_table() -> ScoreTable:
    return ScoreTable(DEMSAR_AUC, DEMSAR_DATASETS, DEMSAR_NAMES)


def test_demsar_worked_example() -> None:
    result = compare_classifiers(demsar_table(), control="C4.5")
    ranks = {name: result.average_rank(name) for name in DEMSAR_NAMES}
    assert ranks == pytest.approx(
        {"C4.5": 3.143, "C4.5+m": 2.000, "C4.5+cf": 2.893, "C4.5+m+cf": 1.964}, abs=5e-4
    )
    assert result.classifiers == ("C4.5+m+cf", "C4.5+m", "C4.5+cf", "C4.5")
    # "chi2_F = 9.28", "F_F = 3.69", F(3, 39)
    assert result.friedman.statistic == pytest.approx(9.28, abs=5e-3)
    assert result.friedman.iman_davenport == pytest.approx(3.69, abs=5e-3)
    assert (result.friedman.df, result.friedman.df_denominator) == (3, 39)
    assert result.friedman.iman_davenport_p_value < 0.05
    # Table 5a: q_0.05 = 2.569 for k = 4; "CD = 2.569 sqrt(4 * 5 / (6 * 14)) = 1.25"
    assert result.q_alpha == pytest.approx(2.569, abs=5e-4)
    assert result.critical_difference == pytest.approx(1.25, abs=5e-3)
    # "at alpha = 0.10 ... CD = 1.12"
    assert nemenyi_critical_difference(4, 14, 0.10) == pytest.approx(1.12, abs=5e-3)
    assert studentized_range_q(4, 0.10) == pytest.approx(2.291, abs=5e-4)
    # Holm against C4.5: p = 0.016, 0.019, 0.607; the first two rejected at alpha 0.05
    holm = {h.classifier: h for h in result.holm}
    assert [h.classifier for h in result.holm] == ["C4.5+m+cf", "C4.5+m", "C4.5+cf"]
    assert holm["C4.5+m+cf"].p_value == pytest.approx(0.016, abs=1e-3)
    assert holm["C4.5+m"].p_value == pytest.approx(0.019, abs=1e-3)
    assert holm["C4.5+cf"].p_value == pytest.approx(0.607, abs=2e-3)
    assert [h.significant for h in result.holm] == [True, True, False]
    assert holm["C4.5+m+cf"].z > 0  # the control ranks worse
    # The Nemenyi test cannot tell any pair apart (the largest difference is 1.18 < 1.25).
    assert result.groups == (("C4.5+m+cf", "C4.5+m", "C4.5+cf", "C4.5"),)
    assert not result.different("C4.5", "C4.5+m+cf")


def test_scipy_friedman_with_tie_correction() -> None:
    table = ScoreTable(DEMSAR_AUC[:12], DEMSAR_DATASETS[:12], DEMSAR_NAMES)  # "mushroom" ties
    ranks = rank_scores(table.scores)
    expected = friedmanchisquare(*table.scores.T)
    corrected = friedman_test(ranks, correct_ties=True)
    assert corrected.tie_corrected
    assert corrected.statistic == pytest.approx(expected.statistic, rel=1e-12)
    assert corrected.p_value == pytest.approx(expected.pvalue, rel=1e-10)
    assert friedman_test(ranks).statistic < corrected.statistic


def random_scores(seed: int, n_blocks: int = 12, k: int = 6) -> pd.DataFrame:
    rng = np.random.default_rng(seed)
    values = rng.normal(0.7, 0.05, size=(n_blocks, k)) + np.linspace(0, 0.06, k)
    return pd.DataFrame(values, columns=[f"c{j}" for j in range(k)])


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_against_autorank(seed: int) -> None:
    data = random_scores(seed)
    oracle = autorank(data, alpha=0.05, order="descending", force_mode="nonparametric")
    assert (oracle.omnibus, oracle.posthoc) == ("friedman", "nemenyi")
    table = ScoreTable(data.to_numpy(), [f"d{i}" for i in range(len(data))], data.columns)
    result = compare_classifiers(table)
    for name, rank in oracle.rankdf.meanrank.items():
        assert result.average_rank(str(name)) == pytest.approx(rank, rel=1e-12)
    assert result.friedman.p_value == pytest.approx(oracle.pvalue, rel=1e-9)  # no ties here
    # autorank takes q from statsmodels' qsturng, an interpolated table good to about 1e-5;
    # scipy's studentized_range, which we use, is exact (and matches Demšar's Table 5a).
    assert result.critical_difference == pytest.approx(oracle.cd, rel=1e-4)
    _, names, groups = get_sorted_rank_groups(oracle, reverse=False)
    expected = {frozenset(names[i : j + 1]) for i, j in groups}
    assert {frozenset(group) for group in result.groups} == expected
    assert result.groups  # the data are close enough to leave some classifiers together


def test_lower_is_better_reverses_the_ranks() -> None:
    data = random_scores(3)
    table = ScoreTable(data.to_numpy(), [f"d{i}" for i in range(len(data))], data.columns)
    losses = ScoreTable(-table.scores, table.blocks, table.classifiers)
    higher = compare_classifiers(table)
    lower = compare_classifiers(losses, lower_is_better=True)
    assert lower.classifiers == higher.classifiers
    np.testing.assert_allclose(lower.average_ranks, higher.average_ranks)
    oracle = autorank(
        pd.DataFrame(losses.scores, columns=data.columns),
        order="ascending",
        force_mode="nonparametric",
    )
    for name, rank in oracle.rankdf.meanrank.items():
        assert lower.average_rank(str(name)) == pytest.approx(rank)


@pytest.mark.parametrize("seed", [0, 4])
def test_nemenyi_and_holm_against_scikit_posthocs(seed: int) -> None:
    data = random_scores(seed, n_blocks=15, k=5)
    table = ScoreTable(data.to_numpy(), [f"d{i}" for i in range(len(data))], data.columns)
    result = compare_classifiers(table, alpha=0.05)
    order = list(result.classifiers)
    nemenyi = scikit_posthocs.posthoc_nemenyi_friedman(data.to_numpy())
    nemenyi.index = nemenyi.columns = list(data.columns)
    np.testing.assert_allclose(
        result.nemenyi_p_values, nemenyi.loc[order, order].to_numpy(), rtol=1e-6, atol=1e-12
    )
    # Holm against the best: Siegel and Castellan's unadjusted z-test p-values, adjusted by
    # statsmodels' Holm procedure.
    pairwise = scikit_posthocs.posthoc_siegel_friedman(data.to_numpy())
    pairwise.index = pairwise.columns = list(data.columns)
    others = [h.classifier for h in result.holm]
    raw = pairwise.loc[result.control, others].to_numpy()
    reject, adjusted, _, _ = multipletests(raw, alpha=0.05, method="holm")
    np.testing.assert_allclose([h.p_value for h in result.holm], raw, rtol=1e-9)
    np.testing.assert_allclose([h.adjusted_p_value for h in result.holm], adjusted, rtol=1e-9)
    assert [h.significant for h in result.holm] == list(reject)
    # The Nemenyi p-values and the CD agree on every pair.
    for i, a in enumerate(order):
        for j, b in enumerate(order):
            if i != j:
                assert result.different(a, b) == (result.nemenyi_p_values[i, j] < 0.05)


def test_identical_classifiers_and_perfect_agreement() -> None:
    same = ScoreTable(np.full((5, 3), 0.8), [f"d{i}" for i in range(5)], ["a", "b", "c"])
    tied = compare_classifiers(same)
    assert tied.friedman.statistic == 0.0
    assert tied.friedman.p_value == 1.0
    assert compare_classifiers(same, correct_ties=True).friedman.p_value == 1.0
    assert all(not h.significant for h in tied.holm)
    ladder = np.tile([0.9, 0.8, 0.7], (6, 1))
    ordered = compare_classifiers(ScoreTable(ladder, [f"d{i}" for i in range(6)], ["a", "b", "c"]))
    assert ordered.friedman.statistic == pytest.approx(12.0)  # N (k - 1): ranks never vary
    assert math.isinf(ordered.friedman.iman_davenport)
    assert ordered.friedman.iman_davenport_p_value == 0.0
    assert ordered.average_ranks.tolist() == [1.0, 2.0, 3.0]


def test_bad_input_is_refused_with_a_reason() -> None:
    table = demsar_table()
    with pytest.raises(ConfigurationError, match="alpha"):
        compare_classifiers(table, alpha=1.5)
    with pytest.raises(ConfigurationError, match="control 'J48'"):
        compare_classifiers(table, control="J48")
    with pytest.raises(ConfigurationError, match="at least 2 data sets"):
        compare_classifiers(ScoreTable(DEMSAR_AUC[:1], DEMSAR_DATASETS[:1], DEMSAR_NAMES))
    with pytest.raises(ConfigurationError, match="at least 2 of them"):
        compare_classifiers(ScoreTable(DEMSAR_AUC[:, :1], DEMSAR_DATASETS, DEMSAR_NAMES[:1]))
    holes = DEMSAR_AUC.copy()
    holes[2, 1] = np.nan
    with pytest.raises(ConfigurationError, match=r"'C4.5\+m' on 'breast cancer wisconsin'"):
        compare_classifiers(ScoreTable(holes, DEMSAR_DATASETS, DEMSAR_NAMES))
