"""How many touches: learning curves inside each fold.

Each outer fold's training instances are cut to a fraction (the test instances stay as they
are, so every point of a curve is scored on the same instances); the classifier is fitted on
the cut and scored on the fold's test instances.  The cut is stratified (each class keeps
its share, at least one instance) and group-aware (a recording/session is kept or left out
whole, as the folds keep them), and nested: a smaller fraction's instances are among a
larger one's, so a curve shows more data, not other data.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.run.folds import Fold


def training_order(
    train: np.ndarray, strata: np.ndarray | None, groups: np.ndarray | None, seed: int
) -> list[np.ndarray]:
    """Blocks of ``train`` in the order a growing training set takes them.

    Parameters
    ----------
    train : ndarray of shape (n_train,), int
        A fold's training indices.
    strata : ndarray of shape (n_instances,), optional
        The label to stratify on, per instance of the whole data set.
    groups : ndarray of shape (n_instances,), optional
        Recording/session per instance: a block is one group.
    seed : int

    Returns
    -------
    list of ndarray
        Without groups, one instance per block, interleaved across classes so that any
        prefix keeps the classes' shares (every class first once); with groups, one group
        per block, in random order.
    """
    rng = np.random.default_rng(seed)
    if groups is not None:
        names = np.unique(groups[train])
        return [train[groups[train] == g] for g in rng.permutation(names)]
    if strata is None:
        return [np.array([i]) for i in rng.permutation(train)]
    labels = strata[train]
    classes = np.unique(labels)
    shuffled = {c: rng.permutation(train[labels == c]) for c in classes}
    # an instance's place in the order: its rank within its class, scaled to the class size
    # (a class with a tenth of the instances comes a tenth as often); each class once first
    keys, members = [], []
    for c in classes:
        size = shuffled[c].size
        keys.append((np.arange(size) + rng.random()) / size)
        members.append(shuffled[c])
    key = np.concatenate(keys)
    order = np.concatenate(members)[np.argsort(key, kind="stable")]
    firsts = [shuffled[c][0] for c in classes]
    rest = order[~np.isin(order, firsts)]
    return [np.array([i]) for i in [*firsts, *rest.tolist()]]


def training_subset(blocks: Sequence[np.ndarray], fraction: float) -> np.ndarray:
    """The first blocks of :func:`training_order` holding at least ``fraction`` of its
    instances (at least one block), sorted."""
    if not 0.0 < fraction <= 1.0:
        raise ConfigurationError(f"a training fraction lies in (0, 1], got {fraction}")
    total = sum(b.size for b in blocks)
    wanted = int(np.ceil(fraction * total - 1e-9))
    taken: list[np.ndarray] = []
    count = 0
    for block in blocks:
        if count >= wanted and taken:
            break
        taken.append(block)
        count += block.size
    return np.sort(np.concatenate(taken)).astype(np.int64)


def learning_folds(
    folds: Sequence[Fold],
    fractions: Sequence[float],
    *,
    strata: np.ndarray | None = None,
    groups: np.ndarray | None = None,
    seed: int = 0,
) -> dict[float, list[Fold]]:
    """Per fraction, the folds with their training instances cut to it (same test sets).

    Raises
    ------
    ConfigurationError
        No fraction, or a fraction outside (0, 1].
    """
    if not fractions:
        raise ConfigurationError("a learning curve needs at least one training fraction")
    orders = [
        training_order(f.train, strata, groups, seed + 7919 * f.repeat + f.fold) for f in folds
    ]
    return {
        float(fraction): [
            Fold(f.repeat, f.fold, training_subset(order, fraction), f.test)
            for f, order in zip(folds, orders, strict=True)
        ]
        for fraction in sorted(set(fractions))
    }


def enough_fraction(
    means: Mapping[float, float], *, tolerance: float = 0.01, lower_is_better: bool = False
) -> float | None:
    """The smallest fraction whose mean score is within ``tolerance`` of the largest
    fraction's (``None`` if a mean is missing at the largest fraction).

    Parameters
    ----------
    means : mapping of float to float
        Fraction -> mean score over the folds (NaN for a fraction whose folds failed).
    """
    if not means:
        return None
    full = means[max(means)]
    if np.isnan(full):
        return None
    for fraction in sorted(means):
        score = means[fraction]
        gap = (score - full) if lower_is_better else (full - score)
        if not np.isnan(score) and gap <= tolerance:
            return fraction
    return max(means)
