"""A scikit-learn VotingClassifier made of members fitted once, not refitted: what a vote
computed from its members' fold predictions must predict, to the last bit."""

from __future__ import annotations

from sklearn.ensemble import VotingClassifier
from sklearn.preprocessing import LabelEncoder

from touchbench.benchmark.catalogue import ClassifierSpec
from touchbench.benchmark.estimators import build_estimator
from touchbench.benchmark.problem import Problem
from touchbench.benchmark.run.folds import Fold


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
