"""scikit-multilearn's multi-label methods behind the multi-target estimator interface.

Only for binary targets (multi-label data such as MEKA's Music.arff).  The package
``scikit-multilearn-ng`` provides ``skmultilearn``; the original ``scikit-multilearn``
0.2.0 fails with scikit-learn >= 1.2 and NumPy 2 (its MLkNN and BRkNN pass
``NearestNeighbors`` a positional argument, its random label-space clusterer builds a
ragged NumPy array, its MLARAM calls ``scipy.ones``).
"""

from __future__ import annotations

import warnings
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from types import ModuleType
from typing import Any

import numpy as np
from scipy import sparse
from sklearn.base import clone
from sklearn.utils import check_random_state

from touchbench.benchmark.multitarget._base import MultiTargetClassifier
from touchbench.benchmark.multitarget._target_classifier import TargetClassifier
from touchbench.benchmark.targets import (
    TargetError,
    all_binary,
    one_hot,
    random_partition,
)

#: Methods that need a base classifier, and those that have none.
METHODS_WITH_BASE = ("br", "cc", "lp", "rakeld", "rakelo")
METHODS_WITHOUT_BASE = ("mlknn", "brknn", "mlaram")
#: Methods whose scikit-multilearn class has no ``predict_proba``.
METHODS_WITHOUT_PROBABILITIES = ("rakelo", "brknn")


class MultiLabelAdapter(MultiTargetClassifier):
    """A scikit-multilearn method for binary targets, as a multi-target estimator.

    ``method`` is one of

    - ``"br"``: binary relevance; ``"cc"``: classifier chain (seeded random order);
      ``"lp"``: label powerset (each with ``estimator`` as base);
    - ``"rakeld"``: label powerset on random disjoint label subsets of
      ``labelset_size`` (seeded, unlike scikit-multilearn's ``RakelD``);
    - ``"rakelo"``: majority vote of ``n_models`` label powersets on random overlapping
      subsets (seeded; scikit-multilearn gives no probabilities for it);
    - ``"mlknn"``: ML-kNN; ``"brknn"``: BRkNN-a (no probabilities); ``"mlaram"``:
      ML-ARAM (these three have no base).

    Every base is wrapped in :class:`TargetClassifier`, so a label with one value in a
    training fold works.  Where a method gives no probabilities, ``predict_proba`` is the
    one-hot encoding of ``predict``.  ``preprocessor`` (e.g. the imputation, encoding and
    scaling steps of a catalogue pipeline) transforms ``X`` first, which the methods
    without a base need for missing values and nominal inputs.

    Parameters
    ----------
    method : str
        See above.
    estimator : classifier, optional
        Base classifier for the methods that take one.
    preprocessor : transformer, optional
        Fitted on the training features and applied before the method.
    n_neighbors : int, default 10
        ``k`` of ML-kNN and BRkNN.
    labelset_size : int, default 3
        Labels per subset for RAkEL.
    n_models : int, optional
        Subsets for RAkELo; default twice the number of labels.
    n_classes : sequence of int, optional
        Classes per target, each at most 2.
    random_state : int, RandomState or None
        Seed of chain orders and label subsets.

    Attributes
    ----------
    model_ : scikit-multilearn classifier
        The fitted method.
    preprocessor_ : transformer or None
    """

    def __init__(
        self,
        method: str,
        estimator: Any = None,
        *,
        preprocessor: Any = None,
        n_neighbors: int = 10,
        labelset_size: int = 3,
        n_models: int | None = None,
        n_classes: Sequence[int] | None = None,
        random_state: int | np.random.RandomState | None = None,
    ) -> None:
        self.method = method
        self.estimator = estimator
        self.preprocessor = preprocessor
        self.n_neighbors = n_neighbors
        self.labelset_size = labelset_size
        self.n_models = n_models
        self.n_classes = n_classes
        self.random_state = random_state

    def fit(self, X: object, Y: object) -> MultiLabelAdapter:
        """Fit the method on binary targets.

        Parameters
        ----------
        X : array-like of shape (n_samples, n_features)
        Y : array-like of shape (n_samples, n_targets), codes 0 or 1

        Returns
        -------
        self

        Raises
        ------
        TargetError
            A target has more than two classes, or ``method`` is unknown or lacks its
            base classifier.
        """
        X_checked, codes = self._validate_training_data(X, Y)
        if self.method not in METHODS_WITH_BASE + METHODS_WITHOUT_BASE:
            raise TargetError(
                f"unknown multi-label method '{self.method}' (known: "
                f"{', '.join(METHODS_WITH_BASE + METHODS_WITHOUT_BASE)})"
            )
        if self.n_classes is None and all_binary(self.n_classes_):
            # Multi-label data: a label that is 0 throughout training still has two values.
            self.n_classes_ = (2,) * self.n_targets_
            self.classes_ = [np.arange(2) for _ in range(self.n_targets_)]
        if not all_binary(self.n_classes_):
            wide = [t for t, k in enumerate(self.n_classes_) if k > 2]
            raise TargetError(
                f"multi-label method '{self.method}' needs binary targets, but target(s) "
                f"{wide} have {[self.n_classes_[t] for t in wide]} classes; use a "
                "multi-target method (cr, cc, bcc, ...) instead"
            )
        if self.method in METHODS_WITH_BASE and self.estimator is None:
            raise TargetError(f"multi-label method '{self.method}' needs a base classifier")
        self.preprocessor_ = None if self.preprocessor is None else clone(self.preprocessor)
        features = self._features(X_checked, fit=True)
        self.model_ = self._build(check_random_state(self.random_state))
        with _quiet_skmultilearn():
            self.model_.fit(features, codes)
        return self

    def _features(self, X: np.ndarray, *, fit: bool = False) -> np.ndarray:
        if self.preprocessor_ is None:
            return X
        transformed = (
            self.preprocessor_.fit_transform(X) if fit else self.preprocessor_.transform(X)
        )
        if sparse.issparse(transformed):
            transformed = transformed.toarray()
        return np.asarray(transformed, dtype=np.float64)

    def _build(self, rng: np.random.RandomState) -> Any:
        skml = _skmultilearn()
        dense = [True, True]
        n_labels = self.n_targets_
        if self.method == "mlknn":
            return skml.adapt.MLkNN(k=self.n_neighbors)
        if self.method == "brknn":
            return skml.adapt.BRkNNaClassifier(k=self.n_neighbors)
        if self.method == "mlaram":
            return skml.adapt.MLARAM()
        # The methods with a base remain: br, cc, lp, rakeld, rakelo.
        binary = TargetClassifier(self.estimator, 2)
        if self.method == "br":
            return skml.problem_transform.BinaryRelevance(classifier=binary, require_dense=dense)
        if self.method == "cc":
            return skml.problem_transform.ClassifierChain(
                classifier=binary, require_dense=dense, order=rng.permutation(n_labels).tolist()
            )
        powerset = skml.problem_transform.LabelPowerset(
            classifier=TargetClassifier(self.estimator), require_dense=dense
        )
        if self.method == "lp":
            return powerset
        if self.method == "rakeld":
            subsets = [
                part.tolist()
                for part in random_partition(n_labels, max(self.labelset_size, 1), rng)
            ]
            return skml.ensemble.LabelSpacePartitioningClassifier(
                classifier=powerset,
                clusterer=skml.cluster.FixedLabelSpaceClusterer(clusters=subsets),
                require_dense=dense,
            )
        return skml.ensemble.MajorityVotingClassifier(
            classifier=powerset,
            clusterer=skml.cluster.FixedLabelSpaceClusterer(
                clusters=self._overlapping_subsets(rng)
            ),
            require_dense=dense,
        )

    def _overlapping_subsets(self, rng: np.random.RandomState) -> list[list[int]]:
        """Random label subsets for RAkELo, every label in at least one."""
        n_labels = self.n_targets_
        size = min(max(self.labelset_size, 1), n_labels)
        n_models = 2 * n_labels if self.n_models is None else self.n_models
        subsets = [
            sorted(rng.choice(n_labels, size, replace=False).tolist()) for _ in range(n_models)
        ]
        covered = {label for subset in subsets for label in subset}
        for label in range(n_labels):
            if label not in covered:
                others = rng.permutation([t for t in range(n_labels) if t != label])[: size - 1]
                subsets.append(sorted([label, *others.tolist()]))
        return subsets

    def predict(self, X: object) -> np.ndarray:
        """Predicted label indicators.

        Parameters
        ----------
        X : array-like of shape (n_samples, n_features)

        Returns
        -------
        ndarray of shape (n_samples, n_targets), int64
        """
        X_checked = self._validate_prediction_data(X)
        with _quiet_skmultilearn():
            predicted = self.model_.predict(self._features(X_checked))
        return _dense(predicted).astype(np.int64)

    def predict_proba(self, X: object) -> list[np.ndarray]:
        """Per-label probabilities ``[P(0), P(1)]`` (one-hot of ``predict`` where the
        method has none).

        Parameters
        ----------
        X : array-like of shape (n_samples, n_features)

        Returns
        -------
        list of ndarray
            One (n_samples, n_classes_[t]) matrix per target.
        """
        X_checked = self._validate_prediction_data(X)
        features = self._features(X_checked)
        if self.method in METHODS_WITHOUT_PROBABILITIES:
            with _quiet_skmultilearn():
                predicted = _dense(self.model_.predict(features)).astype(np.int64)
            return [
                one_hot(np.minimum(predicted[:, t], k - 1), k)
                for t, k in enumerate(self.n_classes_)
            ]
        with _quiet_skmultilearn():
            positive = np.clip(_dense(self.model_.predict_proba(features)), 0.0, 1.0)
        return [
            np.stack([1.0 - positive[:, t], positive[:, t]], axis=1)
            if k == 2
            else np.ones((features.shape[0], 1))
            for t, k in enumerate(self.n_classes_)
        ]


@contextmanager
def _quiet_skmultilearn() -> Iterator[None]:
    """Silence scikit-multilearn's own deprecation warnings (MLARAM's ``numpy.core``)."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", category=DeprecationWarning, module="skmultilearn")
        yield


def _dense(matrix: Any) -> np.ndarray:
    if sparse.issparse(matrix):
        return np.asarray(matrix.toarray())
    return np.asarray(matrix)


def _skmultilearn() -> ModuleType:
    """The ``skmultilearn`` package with the submodules used here."""
    try:
        import skmultilearn.adapt
        import skmultilearn.cluster
        import skmultilearn.ensemble
        import skmultilearn.problem_transform
    except ImportError as error:
        raise TargetError(
            "multi-label methods need scikit-multilearn-ng (pip install scikit-multilearn-ng)"
        ) from error
    return skmultilearn
