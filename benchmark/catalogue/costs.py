"""Cost hints that account for the data's shape: seconds one fold of an entry may take.

A catalogue entry's ``cost`` (``"fast"``/``"slow"``) is measured on a few thousand instances
and a hundred features; the cost of most families grows with the instances, the features
and the classes at different powers: a gradient-boosted model fits one tree per class per
round (``xgb`` is ``fast`` at the reference shape and among the slowest on thousands of
features and tens of classes), a kernel SVM grows with the square of the instances, a
nearest-neighbour search with the product of training and test rows, naive Bayes barely at
all.  :func:`estimate_seconds` scales the entry's reference seconds by the family's powers;
the engine orders a round cheap first by it and the total budget predicts a task's cost with
it before the entry's first fold has been timed.  The figures are rough on purpose: an
order of magnitude is what ordering and a budget's first guesses need.
"""

from __future__ import annotations

from dataclasses import dataclass

from touchbench.benchmark.catalogue.spec import ClassifierSpec

#: The shape the catalogue's ``cost`` labels describe.
REFERENCE_INSTANCES = 2000
REFERENCE_FEATURES = 100
REFERENCE_CLASSES = 5
#: Seconds of one fold at the reference shape, per ``cost`` label.
REFERENCE_SECONDS = {"fast": 0.5, "slow": 8.0}
#: Seconds of any fold at least: a worker's own overhead (receiving the task, scoring,
#: sending the result) is a few hundredths of a second whatever the data.
MIN_SECONDS = 0.05
#: At or above this many predicted seconds per fold an entry is ``slow`` for the data.
SLOW_SECONDS = 5.0

#: Per family: the powers of (instances, features, classes) its cost grows with, and its
#: seconds at the reference shape relative to its ``cost`` label's (naive Bayes fits in a
#: pass over the data; 300 boosting rounds of a 5-class problem fit 1,500 trees).  Families
#: not listed grow linearly with each, at weight 1.
FAMILY_COSTS: dict[str, tuple[float, float, float, float]] = {
    "majority": (0.3, 0.0, 0.0, 0.1),
    "baseline": (0.3, 0.0, 0.0, 0.1),
    "naive-bayes": (1.0, 1.0, 1.0, 0.1),
    "prototype": (1.0, 1.0, 1.0, 0.1),
    "rules": (1.2, 1.0, 1.0, 0.5),
    # C4.5 sorts every feature at every node and keeps class counts per value
    "trees": (1.2, 1.0, 1.0, 0.5),
    # sqrt(features) per split; classes only change the leaves
    "forests": (1.2, 0.5, 0.3, 1.0),
    "bagging": (1.2, 1.0, 0.3, 1.0),
    # one tree (or stump) per class per round
    "boosting": (1.0, 1.0, 1.0, 2.0),
    # the training rows times the test rows, the whole width
    "nearest-neighbours": (2.0, 1.0, 0.0, 0.3),
    # libsvm: about quadratic in the rows, one model per pair of classes on their rows
    "svm": (2.0, 1.0, 0.5, 1.0),
    "calibration": (2.0, 1.0, 0.5, 1.5),
    "multiclass-wrapper": (1.5, 1.0, 1.0, 1.0),
    # the covariance matrix: the square of the width
    "discriminant-analysis": (1.0, 2.0, 0.5, 0.3),
    "logistic": (1.0, 1.0, 1.0, 1.0),
    "linear": (1.0, 1.0, 0.5, 0.3),
    "linear-sgd": (1.0, 1.0, 1.0, 0.5),
    "neural-network": (1.0, 1.0, 0.2, 2.0),
    "gaussian-process": (3.0, 1.0, 1.0, 1.0),
    "time-series": (1.0, 1.0, 0.2, 1.0),
}


@dataclass(frozen=True)
class Shape:
    """What a fold's cost depends on.

    Parameters
    ----------
    n_instances : int
        Training rows of a fold.
    n_features : int
    n_classes : int
        Classes of the (largest) target; 1 for a regression.
    n_targets : int
        Targets a multi-target configuration fits a model for each (1 otherwise).
    """

    n_instances: int
    n_features: int
    n_classes: int = 2
    n_targets: int = 1


def estimate_seconds(spec: ClassifierSpec, shape: Shape) -> float:
    """Rough wall seconds of one fold (fit and predict) of ``spec`` on data of ``shape``.

    ``REFERENCE_SECONDS[spec.cost] * w`` scaled by ``(n / n0) ** a * (d / d0) ** b *
    (k / k0) ** c`` with the family's powers ``(a, b, c)`` and weight ``w`` of
    :data:`FAMILY_COSTS`, times
    the targets a multi-target configuration fits one model for each; at least
    :data:`MIN_SECONDS`.  A vote costs its members' sum (what it costs on its own; a run
    computes it from the members' folds, which are its only cost there).
    """
    if spec.ensemble is not None and spec.ensemble.combine != "selection":
        return sum(estimate_seconds(member, shape) for member in spec.ensemble.members)
    a, b, c, weight = FAMILY_COSTS.get(spec.family, (1.0, 1.0, 1.0, 1.0))
    scale = (
        (max(shape.n_instances, 1) / REFERENCE_INSTANCES) ** a
        * (max(shape.n_features, 1) / REFERENCE_FEATURES) ** b
        * (max(shape.n_classes, 2) / REFERENCE_CLASSES) ** c
    )
    seconds = REFERENCE_SECONDS.get(spec.cost, REFERENCE_SECONDS["fast"]) * weight * scale
    return max(seconds * shape.n_targets, MIN_SECONDS)


def cost_label(spec: ClassifierSpec, shape: Shape) -> str:
    """``"slow"`` when :func:`estimate_seconds` reaches :data:`SLOW_SECONDS`, else ``"fast"``."""
    return "slow" if estimate_seconds(spec, shape) >= SLOW_SECONDS else "fast"
