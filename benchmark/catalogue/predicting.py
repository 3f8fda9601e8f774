"""A fitted classifier's labels and probabilities, in one pass where its labels are the
class of highest probability.

Many classifiers predict the class their probabilities rank first: forests, bagging and the
WEKA classifiers of :mod:`benchmark.weka` compute ``predict_proba`` inside ``predict`` and
take its first maximum; trees, logistic regression, Gaussian naive Bayes, k-nearest
neighbours and the neural sequence classifiers rank the classes by a quantity their
probabilities are a monotone map of.  Asking such a model for both runs it twice (a
nearest-neighbour search or a kernel density is most of its cost), so the labels are read off
the probabilities instead.  Other classifiers (an SVM's Platt scaling, calibration, boosting
that votes on decision values) predict in their own way and are asked for both.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["labels_and_probabilities", "predicts_most_probable"]


def predicts_most_probable(estimator: Any) -> bool:
    """Whether ``estimator`` (or a pipeline's last step) predicts the first class of
    highest ``predict_proba``, so that its labels can be read off its probabilities."""
    from sklearn.ensemble import BaggingClassifier
    from sklearn.ensemble._forest import ForestClassifier
    from sklearn.linear_model import LogisticRegression
    from sklearn.naive_bayes import GaussianNB
    from sklearn.neighbors import KNeighborsClassifier
    from sklearn.tree import BaseDecisionTree

    from touchbench.benchmark.catalogue.neural import NeuralSequenceClassifier
    from touchbench.benchmark.weka._data import NanClassifier

    final = estimator[-1] if hasattr(estimator, "steps") else estimator
    # the class whose predict calls predict_proba and takes its argmax: a subclass that
    # predicts in its own way does not count
    for base in (NanClassifier, ForestClassifier, BaggingClassifier):
        if isinstance(final, base):
            return type(final).predict is base.predict
    most_probable = (
        BaseDecisionTree,
        LogisticRegression,
        GaussianNB,
        KNeighborsClassifier,
        NeuralSequenceClassifier,  # argmax of the softmax: one pass of the network
    )
    return isinstance(final, most_probable)


def labels_and_probabilities(
    estimator: Any, X: np.ndarray, *, probabilities: bool
) -> tuple[np.ndarray, np.ndarray | None]:
    """A fitted single-target classifier's predictions of ``X``.

    Parameters
    ----------
    estimator : classifier
        Fitted, with ``classes_``.
    X : ndarray of shape (n, n_features)
    probabilities : bool
        Whether to ask for ``predict_proba`` too.

    Returns
    -------
    labels : ndarray of shape (n,), int64
        What ``estimator.predict(X)`` returns.
    proba : ndarray of shape (n, len(estimator.classes_)), or None
        ``estimator.predict_proba(X)``; None without ``probabilities``.
    """
    if not probabilities:
        return np.asarray(estimator.predict(X), dtype=np.int64), None
    proba = np.asarray(estimator.predict_proba(X))
    if predicts_most_probable(estimator):
        labels = np.asarray(estimator.classes_).take(np.argmax(proba, axis=1))
    else:
        labels = estimator.predict(X)
    return np.asarray(labels, dtype=np.int64), proba
