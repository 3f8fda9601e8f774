"""Racing: after each round of folds from the third on, drop the entries that are
significantly worse than the current leader.

The test is the leaderboard's, WEKA's corrected resampled t-test (Nadeau and Bengio), of an
entry's per-fold scores against the leader's on the folds both ran, at a stricter level
than the leaderboard's (``alpha`` 0.01 by default), with one change for a race's few folds:
the variances of the differences are moderated, shrunk towards a prior fitted to all the
entries compared in the round (Smyth's empirical Bayes t, limma's), see
:func:`benchmark.evaluation.significance.moderated_corrected_ttests`.  On three folds the
plain test takes an entry whose differences from the leader happen to agree for one whose
small deficit is certain, and drops entries that ten folds find no worse; the moderated
variance is rarely that small, and its extra degrees of freedom let the clearly worse go
sooner.  A single comparison, or two, has no prior to fit and is the plain test.

Why not Friedman's test with Nemenyi's post-hoc comparisons (F-race): with the 57 entries of
the default suite, Nemenyi's critical difference of mean ranks at 0.01 is 60 after 3 folds
and 33 after 10, while mean ranks can differ by 56 at most, so it drops nothing in the early
rounds where racing saves time (``perf/racing.py`` prints both rules' drops on the full
run's scores).  The moderated test borrows from the other entries only the spread of their
variances, not their ranks: an entry's fate does not hinge on who else is ahead of it.

A decision depends only on the scores of the rounds up to it, never on timing, so a raced
run gives the same drops however many workers it has and however often it is resumed.
"""

from __future__ import annotations

import math
from collections.abc import Collection, Mapping
from dataclasses import dataclass

import numpy as np

from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.evaluation.metrics import LOWER_IS_BETTER
from touchbench.benchmark.evaluation.significance import moderated_corrected_ttests
from touchbench.benchmark.results import Drop

#: The first round after which entries may be dropped: fewer folds say too little.
FIRST_ROUND = 3


@dataclass(frozen=True)
class RaceRule:
    """How a run races.

    Parameters
    ----------
    metric : str
        The leaderboard's ranking metric (lower is better for :data:`LOWER_IS_BETTER`).
    alpha : float
        Two-sided level of the t-test against the leader, in (0, 0.5).
    protected : collection of str
        Entries never dropped besides the leader (the run's chosen baseline).
    first_round : int
        Rounds (folds) every entry runs before the first decision; at least 2.
    """

    metric: str
    alpha: float = 0.01
    protected: frozenset[str] = frozenset()
    first_round: int = FIRST_ROUND

    def __post_init__(self) -> None:
        if not 0 < self.alpha < 0.5:
            raise ConfigurationError(f"race alpha must lie in (0, 0.5), got {self.alpha}")
        if self.first_round < 2:
            raise ConfigurationError(f"a race needs 2 folds before a test, not {self.first_round}")

    @property
    def lower_is_better(self) -> bool:
        return self.metric in LOWER_IS_BETTER


def leader(scores: Mapping[str, Mapping[int, float]], *, lower_is_better: bool) -> str | None:
    """The entry with the best mean score (ties: the first id in sorted order)."""
    means = {entry: float(np.mean(list(s.values()))) for entry, s in scores.items() if s}
    if not means:
        return None
    sign = 1.0 if lower_is_better else -1.0
    return min(sorted(means), key=lambda entry: sign * means[entry])


@dataclass(frozen=True)
class RoundOutcome:
    """What one decision of a race found.

    Attributes
    ----------
    drops : list of Drop
        The entries dropped, in the order of the live entries.
    p_values : dict of str to float
        Each compared entry's p-value against the leader (the survivors' included; NaN for
        an undefined test): how close each is to a drop, which the schedule uses to decide
        which entries may run ahead of the next decision.
    leader : str or None
    """

    drops: list[Drop]
    p_values: dict[str, float]
    leader: str | None


def decide(
    rule: RaceRule,
    scores: Mapping[str, Mapping[int, float]],
    live: Collection[str],
    round_index: int,
    *,
    test_train_ratio: float,
) -> list[Drop]:
    """The entries to drop after round ``round_index`` (0-based); see :func:`race_round`."""
    return race_round(rule, scores, live, round_index, test_train_ratio=test_train_ratio).drops


def race_round(
    rule: RaceRule,
    scores: Mapping[str, Mapping[int, float]],
    live: Collection[str],
    round_index: int,
    *,
    test_train_ratio: float,
) -> RoundOutcome:
    """The decision after round ``round_index`` (0-based).

    Parameters
    ----------
    rule : RaceRule
    scores : mapping of str to mapping of int to float
        Entry -> round -> score of its successful folds on the race's metric, rounds up
        to ``round_index`` only.
    live : collection of str
        The entries still racing (dropped ones are not compared again).
    round_index : int
    test_train_ratio : float
        ``n_test / n_train`` of the folds (1/9 for 10-fold cross-validation).

    Returns
    -------
    RoundOutcome
        No drops before ``rule.first_round`` rounds.
    """
    lower = rule.lower_is_better
    racing = {entry: scores.get(entry, {}) for entry in live}
    best = leader(racing, lower_is_better=lower)
    outcome = RoundOutcome([], {}, best)
    if best is None:
        return outcome
    # each entry's per-fold advantage over the leader, on the folds both ran
    compared: dict[str, np.ndarray] = {}
    for entry, own in racing.items():
        paired = sorted(set(own) & set(racing[best]))
        if entry != best and len(paired) >= 2:
            advantage = np.array([own[r] - racing[best][r] for r in paired])
            compared[entry] = -advantage if lower else advantage
    tests = moderated_corrected_ttests(list(compared.values()), test_train_ratio=test_train_ratio)
    for (entry, advantage), (_, p) in zip(compared.items(), tests, strict=True):
        outcome.p_values[entry] = p
        worse = advantage.mean() < 0 and p <= rule.alpha
        if worse and entry not in rule.protected and round_index + 1 >= rule.first_round:
            mean = float(np.mean(list(racing[entry].values())))
            outcome.drops.append(
                Drop(
                    entry,
                    "race",
                    round_index + 1,
                    p_value=None if math.isnan(p) else p,
                    leader=best,
                    mean=mean,
                )
            )
    return outcome
