"""CC and PCC: classifier chains over multi-class targets."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from touchbench.benchmark.multitarget._network import TargetNetwork, chain_order
from touchbench.benchmark.targets import one_hot


class ClassifierChain(TargetNetwork):
    """Classifier chain over multi-class targets (MEKA's ``multitarget.CC`` / ``CCp``).

    Targets are ordered in a chain; the classifier of the ``j``-th target sees the
    features plus the one-hot codes of the ``j - 1`` targets before it: their true values
    at training time, the predicted ones (greedy, most probable value) at prediction
    time.  ``predict_proba`` gives each link's distribution given the predicted earlier
    values, like MEKA's ``CCp`` confidences.

    Departures from MEKA: earlier targets enter one-hot encoded (MEKA appends them as
    nominal attributes, which most WEKA learners binarise anyway); without ``order`` the
    chain is a permutation drawn from ``random_state`` with NumPy, not Java's ``Random``.

    Parameters
    ----------
    estimator : classifier
        Base classifier; cloned once per target.
    order : sequence of int, optional
        The chain, a permutation of the target indices; default: random from the seed.
    n_classes : sequence of int, optional
        Classes per target; default ``max(code) + 1`` per target of the training data.
    random_state : int, RandomState or None
        Seed of the random chain order.

    Attributes
    ----------
    order_ : ndarray of shape (n_targets,)
        The chain used.
    parents_ : list of tuple
        ``parents_[t]``: the targets before ``t`` in the chain.
    estimators_ : list of TargetClassifier
        One fitted link per target (indexed by target, not chain position).
    """

    def __init__(
        self,
        estimator: Any,
        *,
        order: Sequence[int] | None = None,
        n_classes: Sequence[int] | None = None,
        random_state: int | np.random.RandomState | None = None,
    ) -> None:
        self.estimator = estimator
        self.order = order
        self.n_classes = n_classes
        self.random_state = random_state

    def _structure(self, X: np.ndarray, Y: np.ndarray) -> tuple[np.ndarray, list[tuple[int, ...]]]:
        order = chain_order(self.order, Y.shape[1], self.random_state)
        parents: list[tuple[int, ...]] = [()] * Y.shape[1]
        for position, target in enumerate(order):
            parents[target] = tuple(int(t) for t in order[:position])
        return order, parents


class ProbabilisticClassifierChain(ClassifierChain):
    """Probabilistic classifier chain: the joint mode instead of greedy decisions.

    Trained exactly as :class:`ClassifierChain`.  At prediction time the chain rule
    ``P(y | x) = prod_j P(y_j | x, y_1 .. y_{j-1})`` is searched for its most probable
    combination: exhaustively when the number of value combinations is at most
    ``exhaustive_limit`` (MEKA's ``multilabel.PCC``, Bayes-optimal for exact match),
    otherwise by beam search keeping the ``beam_width`` most probable partial
    combinations per instance (MEKA's ``MCC``/``PMCC`` use Monte-Carlo search instead).

    ``predict`` gives the joint mode; ``predict_proba`` the per-target marginals of the
    joint distribution over the explored combinations (exact in exhaustive mode), so its
    argmax may differ from the mode.  MEKA's multi-target ``CCp`` is a plain chain with
    confidences; this class follows the issue's definition of PCC.

    Parameters
    ----------
    estimator : classifier
        Base classifier; cloned once per target.
    order : sequence of int, optional
        The chain; default: random permutation from ``random_state``.
    n_classes : sequence of int, optional
        Classes per target.
    exhaustive_limit : int, default 1024
        Largest number of joint combinations searched exhaustively.
    beam_width : int, default 16
        Partial combinations kept per instance beyond that.
    random_state : int, RandomState or None
        Seed of the random chain order.
    """

    def __init__(
        self,
        estimator: Any,
        *,
        order: Sequence[int] | None = None,
        n_classes: Sequence[int] | None = None,
        exhaustive_limit: int = 1024,
        beam_width: int = 16,
        random_state: int | np.random.RandomState | None = None,
    ) -> None:
        super().__init__(estimator, order=order, n_classes=n_classes, random_state=random_state)
        self.exhaustive_limit = exhaustive_limit
        self.beam_width = beam_width

    def _propagate(self, X: np.ndarray) -> tuple[np.ndarray, list[np.ndarray]]:
        paths, log_proba = self._beam_search(X)
        n_samples = X.shape[0]
        weights = _normalised(log_proba)
        predicted = np.zeros((n_samples, self.n_targets_), dtype=np.int64)
        proba: list[np.ndarray] = [np.empty((0, 0))] * self.n_targets_
        for position, target in enumerate(self.order_):
            predicted[:, target] = paths[:, 0, position]
            values = paths[:, :, position]
            proba[target] = np.stack(
                [(weights * (values == v)).sum(axis=1) for v in range(self.n_classes_[target])],
                axis=1,
            )
        return predicted, proba

    def _beam_search(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Most probable combinations per instance, best first.

        Returns
        -------
        paths : ndarray of shape (n_samples, n_kept, n_targets), int64
            Values in chain order.
        log_proba : ndarray of shape (n_samples, n_kept)
            Their log joint probabilities, descending.
        """
        n_samples = X.shape[0]
        n_combinations = math.prod(self.n_classes_)
        width = n_combinations if n_combinations <= self.exhaustive_limit else self.beam_width
        paths = np.zeros((n_samples, 1, 0), dtype=np.int64)
        log_proba = np.zeros((n_samples, 1))
        for position, target in enumerate(self.order_):
            n_values = self.n_classes_[target]
            n_beams = paths.shape[1]
            extended = np.empty((n_samples, n_beams, n_values))
            for beam in range(n_beams):
                design = np.hstack(
                    [X]
                    + [
                        one_hot(paths[:, beam, i], self.n_classes_[self.order_[i]])
                        for i in range(position)
                    ]
                )
                link_proba = self.estimators_[target].predict_proba(design)
                with np.errstate(divide="ignore"):
                    extended[:, beam, :] = log_proba[:, beam, None] + np.log(link_proba)
            flat = extended.reshape(n_samples, n_beams * n_values)
            kept = np.argsort(-flat, axis=1, kind="stable")[:, : min(width, flat.shape[1])]
            beam_of, value_of = np.divmod(kept, n_values)
            paths = np.concatenate(
                [np.take_along_axis(paths, beam_of[:, :, None], axis=1), value_of[:, :, None]],
                axis=2,
            )
            log_proba = np.take_along_axis(flat, kept, axis=1)
        return paths, log_proba


def _normalised(log_proba: np.ndarray) -> np.ndarray:
    """Probabilities proportional to ``exp(log_proba)`` per row, best (first) column as
    reference; a row whose every entry is ``-inf`` (underflow) puts all on the first."""
    best = log_proba[:, :1]
    finite = np.isfinite(best)
    shifted = np.where(
        finite & np.isfinite(log_proba), log_proba - np.where(finite, best, 0), -np.inf
    )
    weights = np.exp(shifted)
    weights[~finite[:, 0], 0] = 1.0
    return weights / weights.sum(axis=1, keepdims=True)
