"""Which features and which sensor: permutation importance on each outer test fold.

The classifier is fitted on each fold's training instances as the run fitted it, and scored
(weighted F1) on the fold's test instances as they are and with one feature (or one group of
features: a channel, a feature family) shuffled across the test instances.  The drop is that
feature's importance on that fold; the test instances never took part in the fit, so the
importance is as honest as the fold's score (Breiman 2001; scikit-learn's
``permutation_importance``, computed here per outer fold and per group as well).
"""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from touchbench.benchmark.catalogue import ClassifierSpec
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.estimators import build_estimator
from touchbench.benchmark.evaluation.metrics import confusion_matrix, confusion_scores
from touchbench.benchmark.problem import Problem
from touchbench.benchmark.run.folds import Fold

#: ``CHANNEL[T]``: a sample of a window (sequence data sets).
_WINDOW = re.compile(r"^(?P<channel>.+)\[(?P<t>\d+)\]$")
#: ``feature_N``: a statistic of microphone/channel N (the UC3M attributes).
_SUFFIX = re.compile(r"^(?P<family>.+)_(?P<channel>\d+)$")


@dataclass(frozen=True)
class Importance:
    """Score drops per fold.

    Attributes
    ----------
    baseline : ndarray of shape (n_folds,)
        Weighted F1 of each fold with nothing shuffled.
    features : dict of str to ndarray of shape (n_folds,)
        Per feature, the mean drop over the shuffles of each fold.
    groups : dict of str to dict of str to ndarray of shape (n_folds,)
        Per grouping (``channel``, ``family``), per group: the drop with the whole group
        shuffled together (the same permutation of the test instances for its columns).
    """

    baseline: np.ndarray
    features: dict[str, np.ndarray]
    groups: dict[str, dict[str, np.ndarray]]


def feature_groups(names: Sequence[str]) -> dict[str, dict[str, list[int]]]:
    """Groupings of the feature columns: by ``channel`` (``CHANNEL[T]`` windows, or the
    ``_1``, ``_2``... suffixes of per-microphone statistics) and by ``family`` (a suffixed
    statistic across channels).  A grouping with fewer than two groups is left out.

    Returns
    -------
    dict
        grouping -> group name -> column indices.
    """
    channel: dict[str, list[int]] = {}
    family: dict[str, list[int]] = {}
    for i, name in enumerate(names):
        window = _WINDOW.match(name)
        suffix = _SUFFIX.match(name)
        if window is not None:
            channel.setdefault(window["channel"], []).append(i)
        elif suffix is not None:
            channel.setdefault(f"channel {suffix['channel']}", []).append(i)
            family.setdefault(suffix["family"], []).append(i)
    out = {}
    if len(channel) >= 2:
        out["channel"] = channel
    if len(family) >= 2 and any(len(columns) > 1 for columns in family.values()):
        out["family"] = family
    return out


def permutation_importance(
    problem: Problem,
    classifier: str,
    folds: Sequence[Fold],
    feature_names: Sequence[str],
    *,
    n_repeats: int = 3,
    random_state: int = 0,
    extra_specs: Mapping[str, ClassifierSpec] | None = None,
    on_fold: Callable[[int, int, Importance], None] = lambda done, total, so_far: None,
) -> Importance:
    """Permutation importance of every feature and feature group on each test fold.

    Parameters
    ----------
    problem : Problem
        A multi-class problem (one nominal target).
    classifier : str
        Catalogue id (or one of ``extra_specs``).
    folds : sequence of Fold
        The run's folds.
    feature_names : sequence of str
        One per column of ``problem.X``.
    n_repeats : int
        Shuffles per feature and fold (their mean drop is kept).
    random_state : int
        Seed of the classifier (as the run's) and of the shuffles.
    on_fold : callable
        Called with (folds done, folds in all, the drops of the folds done) after each fold.

    Raises
    ------
    ConfigurationError
        Not a multi-class problem, names that do not match the columns, no folds.
    """
    if problem.kind != "multiclass":
        raise ConfigurationError(
            f"permutation importance scores one nominal target; this problem is {problem.kind}"
        )
    if len(feature_names) != problem.X.shape[1]:
        raise ConfigurationError(
            f"{len(feature_names)} feature names for {problem.X.shape[1]} columns"
        )
    if not folds or n_repeats < 1:
        raise ConfigurationError("permutation importance needs folds and at least one shuffle")
    groupings = feature_groups(feature_names)
    n_classes = problem.n_classes[0]
    y = problem.Y[:, 0]
    rng = np.random.default_rng(random_state)
    baseline = np.empty(len(folds))
    features = {name: np.empty(len(folds)) for name in feature_names}
    groups = {g: {n: np.empty(len(folds)) for n in members} for g, members in groupings.items()}
    for k, fold in enumerate(folds):
        model = build_estimator(
            classifier, problem, random_state=random_state, extra_specs=extra_specs
        )
        model.fit(problem.X[fold.train], y[fold.train])
        test = _TestFold(model, problem.X[fold.test], y[fold.test], n_classes)
        baseline[k] = test.base
        for i, name in enumerate(feature_names):
            features[name][k] = test.drop([i], n_repeats, rng)
        for grouping, members in groupings.items():
            for name, columns in members.items():
                groups[grouping][name][k] = test.drop(columns, n_repeats, rng)
        on_fold(k + 1, len(folds), _first(Importance(baseline, features, groups), k + 1))
    return Importance(baseline, features, groups)


def _first(found: Importance, n: int) -> Importance:
    """The drops of the first ``n`` folds."""
    return Importance(
        found.baseline[:n].copy(),
        {name: drops[:n].copy() for name, drops in found.features.items()},
        {g: {name: d[:n].copy() for name, d in m.items()} for g, m in found.groups.items()},
    )


class _TestFold:
    """A fitted model and its test fold: the score as it is and with columns shuffled."""

    def __init__(self, model: Any, X: np.ndarray, y: np.ndarray, n_classes: int) -> None:
        self.model, self.X, self.y, self.n_classes = model, X, y, n_classes
        self.base = self.score(X)

    def score(self, X: np.ndarray) -> float:
        predicted = np.asarray(self.model.predict(X), dtype=np.int64)
        confusion = confusion_matrix(self.y, predicted, n_classes=self.n_classes)
        return confusion_scores(confusion)["f1_weighted"]

    def drop(self, columns: Sequence[int], n_repeats: int, rng: np.random.Generator) -> float:
        """Mean drop of the score over ``n_repeats`` shuffles of the test rows of
        ``columns`` (one permutation for all of them, so a group moves together)."""
        shuffled = self.X.copy()
        losses = []
        for _ in range(n_repeats):
            order = rng.permutation(len(self.X))
            shuffled[:, columns] = self.X[order][:, columns]
            losses.append(self.base - self.score(shuffled))
        return float(np.mean(losses))
