"""An ordered multi-class rule list from a binary rule learner (RIPPER, IREP), as JRip orders it.

wittgenstein's RIPPER and IREP learn rules for one positive class.  Like WEKA's JRip, the
classes are taken in order of increasing frequency: rules are learnt for a class against
all the classes after it, that class's instances are then set aside, and the most frequent
class is the default.  A row gets the class of the first rule set that covers it.

Unlike JRip, wittgenstein discretises numeric attributes into equal-frequency bins before
growing conditions, and it cannot take missing values (the pipeline imputes them).
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.utils.multiclass import check_classification_targets
from sklearn.utils.validation import check_is_fitted, validate_data


class OrderedRuleClassifier(ClassifierMixin, BaseEstimator):
    """Multi-class decision list of RIPPER or IREP rule sets (JRip's class order).

    Parameters
    ----------
    algorithm : {"ripper", "irep"}
        wittgenstein's learner.
    k : int
        RIPPER's optimisation passes (ignored by IREP).
    prune_size : float
        Share of each class problem held out to prune rules.
    n_discretize_bins : int
        Equal-frequency bins per numeric feature.
    random_state : int or None

    Attributes
    ----------
    classes_ : ndarray of shape (n_classes,)
    order_ : ndarray of shape (n_classes,)
        Class codes by increasing training frequency (the last is the default).
    learners_ : list
        One fitted wittgenstein learner per class of ``order_[:-1]`` (None when there was
        nothing left to separate).
    """

    def __init__(
        self,
        algorithm: str = "ripper",
        k: int = 2,
        prune_size: float = 0.33,
        n_discretize_bins: int = 10,
        random_state: int | None = None,
    ) -> None:
        self.algorithm = algorithm
        self.k = k
        self.prune_size = prune_size
        self.n_discretize_bins = n_discretize_bins
        self.random_state = random_state

    def fit(self, X: Any, y: Any) -> OrderedRuleClassifier:
        """Learn one rule set per class on ``X`` (n_samples, n_features) and ``y``."""
        import wittgenstein

        if self.algorithm not in ("ripper", "irep"):
            raise ValueError(f"algorithm must be 'ripper' or 'irep', got {self.algorithm!r}")
        X, y = validate_data(self, X, y, dtype=np.float64)
        check_classification_targets(y)
        self.classes_, codes = np.unique(y, return_inverse=True)
        counts = np.bincount(codes)
        self.order_ = np.argsort(counts, kind="stable")
        self.learners_: list[Any] = []
        remaining = np.ones(codes.size, dtype=bool)
        for code in self.order_[:-1]:
            target = (codes[remaining] == code).astype(int)
            learner = None
            if 0 < target.sum() < target.size:
                if self.algorithm == "ripper":
                    learner = wittgenstein.RIPPER(
                        k=self.k,
                        prune_size=self.prune_size,
                        n_discretize_bins=self.n_discretize_bins,
                        random_state=self.random_state,
                    )
                else:
                    learner = wittgenstein.IREP(
                        prune_size=self.prune_size,
                        n_discretize_bins=self.n_discretize_bins,
                        random_state=self.random_state,
                    )
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    learner.fit(X[remaining], target, pos_class=1)
            self.learners_.append(learner)
            remaining &= codes != code
        return self

    def predict(self, X: Any) -> np.ndarray:
        """Labels of shape (n_samples,): the class of the first rule set that fires."""
        check_is_fitted(self)
        X = validate_data(self, X, reset=False, dtype=np.float64)
        out = np.full(X.shape[0], self.order_[-1])
        open_rows = np.ones(X.shape[0], dtype=bool)
        for code, learner in zip(self.order_[:-1], self.learners_, strict=True):
            if learner is None or not open_rows.any():
                continue
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                fires = np.asarray(learner.predict(X[open_rows]), dtype=bool)
            rows = np.flatnonzero(open_rows)[fires]
            out[rows] = code
            open_rows[rows] = False
        return np.asarray(self.classes_[out])
