"""Stand-in catalogue entries for the ensemble tests: slow or counting members, votes
over them, and a small problem whose run can be resumed; and a scikit-learn
VotingClassifier of members fitted once, not refitted (what a vote computed from its
members' fold predictions must predict, to the last bit)."""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np
from sklearn.ensemble import VotingClassifier
from sklearn.naive_bayes import GaussianNB
from sklearn.preprocessing import LabelEncoder

from touchbench.benchmark.catalogue import ClassifierSpec, get_spec
from touchbench.benchmark.catalogue.spec import Ensemble
from touchbench.benchmark.catalogue.stacking import stacked_spec
from touchbench.benchmark.estimators import build_estimator
from touchbench.benchmark.run.engine import Problem
from touchbench.benchmark.run.folds import Fold


def small_problem(n: int = 150, seed: int = 0) -> Problem:
    rng = np.random.default_rng(seed)
    y = np.arange(n) % 3
    X = rng.normal(size=(n, 5)) + 1.0 * y[:, None] * np.array([1.0, 0.5, 0.0, -0.5, 0.2])
    X[::13, 1] = np.nan
    return Problem(X=X, Y=y[:, None], n_classes=(3,), target_names=("gesture",))


def resumable(seconds: float) -> tuple[list[str], dict[str, ClassifierSpec]]:
    """A run with a vote, a stack and a selection over a slow member."""
    slow = stand_in("slow", SlowNB, True, seconds=seconds)
    members = [slow, get_spec("logistic"), get_spec("ibk")]
    extra = {
        "slow": slow,
        "vote": vote("vote", "soft", slow, get_spec("logistic"), get_spec("calibrated-nb")),
        "stack-top2": stacked_spec(members, 2),
    }
    return ["slow", "logistic", "ibk", "vote", "stack-top2"], extra


class SlowNB(GaussianNB):
    """Gaussian naive Bayes that takes ``seconds`` longer to fit (a run to kill midway)."""

    def __init__(self, seconds: float = 0.0, priors: object = None, var_smoothing: float = 1e-9):
        super().__init__(priors=priors, var_smoothing=var_smoothing)
        self.seconds = seconds

    def fit(self, X: np.ndarray, y: np.ndarray, sample_weight: object = None) -> SlowNB:
        time.sleep(self.seconds)
        return super().fit(X, y)


def stand_in(classifier_id: str, factory: type, probabilities: bool, **params: object):
    return replace(
        get_spec("nb-gaussian"),
        id=classifier_id,
        factory=factory,
        params=params,
        probabilities=probabilities,
        handles_missing=False,  # imputed first, as the estimators here want
        description=classifier_id,
    )


def vote(classifier_id: str, combine: str, *members: ClassifierSpec) -> ClassifierSpec:
    return replace(
        get_spec("voting"),
        id=classifier_id,
        params={"voting": combine},
        probabilities=combine == "soft",
        ensemble=Ensemble(tuple(members), combine),  # type: ignore[arg-type]
    )


def prefit_vote(spec: ClassifierSpec, problem: Problem, fold: Fold) -> VotingClassifier:
    """``spec``'s vote (soft or hard) of its members, each fitted on ``fold``'s training
    rows as the engine fits it; call under ``threadpool_limits(limits=1)`` as its workers
    run."""
    X, y = problem.X[fold.train], problem.Y[fold.train, 0]
    fitted = [(m.id, build_estimator(m.id, problem).fit(X, y)) for m in spec.members]
    vote = VotingClassifier(fitted, voting=spec.combine)  # type: ignore[arg-type]
    vote.estimators_ = [model for _, model in fitted]
    vote.le_ = LabelEncoder().fit(y)
    vote.classes_ = vote.le_.classes_
    return vote
