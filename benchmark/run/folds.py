"""Cross-validation folds, computed once per run so that every classifier sees the same ones.

One target: stratified k-fold per repeat (seed ``seed + repeat``).  Several targets:
stratified on the joint label combination when every combination is common enough, plain
shuffled k-fold otherwise.  Numeric targets (a regression): shuffled k-fold.  With
recording/session groups, a group never straddles training and test (group k-fold).  The
scheme used is named in :attr:`FoldPlan.scheme`, for leaderboards to say.  When the data
cannot support the requested number of folds, the largest feasible number is used and a
warning line says so.

Leave-one-group-out (``split="leave-one-group-out"``) asks how a classifier does on a group
it never saw (an object never grasped, a subject never recorded): as many folds as groups,
each group the test side of one fold, in the groups' sorted order; it is deterministic, so
it is made once, whatever the seed.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from sklearn.model_selection import GroupKFold, KFold, StratifiedGroupKFold, StratifiedKFold

from touchbench.benchmark.errors import ConfigurationError

#: How the instances are split: ``k-fold`` (stratified and group-aware where it can be) or
#: one fold per group.
Split = Literal["k-fold", "leave-one-group-out"]
LEAVE_ONE_GROUP_OUT: Split = "leave-one-group-out"


@dataclass(frozen=True)
class Fold:
    """One train/test split.

    Parameters
    ----------
    repeat : int
        0-based repetition of the whole k-fold partition.
    fold : int
        0-based fold within the repetition.
    train, test : ndarray of shape (n_train,) and (n_test,), int64
        Instance indices, sorted.
    """

    repeat: int
    fold: int
    train: np.ndarray
    test: np.ndarray


@dataclass(frozen=True)
class FoldPlan:
    """The folds of a run and how they were made.

    Parameters
    ----------
    folds : list of Fold
        ``n_repeats * k`` folds, repeat-major.
    notes : list of str
        One line per adjustment made (fewer folds, unstratified splits...).
    scheme : str
        ``"stratified k-fold"``, ``"k-fold"`` (shuffled), ``"stratified group k-fold"``,
        ``"group k-fold"`` or ``"leave-one-group-out over N groups"``.
    test_groups : tuple of str or None
        Leave-one-group-out: the group each fold tests (fold ``k`` tests
        ``test_groups[k]``); ``None`` for k-fold.
    """

    folds: list[Fold]
    notes: list[str]
    scheme: str
    test_groups: tuple[str, ...] | None = None


def make_folds(
    Y: np.ndarray,
    *,
    n_folds: int = 10,
    n_repeats: int = 1,
    seed: int = 0,
    groups: np.ndarray | None = None,
    target_names: Sequence[str] | None = None,
    regression: bool = False,
    split: Split = "k-fold",
) -> tuple[list[Fold], list[str]]:
    """Repeated (stratified, group-aware) k-fold splits, or leave-one-group-out:
    :func:`make_fold_plan`'s folds and notes."""
    plan = make_fold_plan(
        Y,
        n_folds=n_folds,
        n_repeats=n_repeats,
        seed=seed,
        groups=groups,
        target_names=target_names,
        regression=regression,
        split=split,
    )
    return plan.folds, plan.notes


def make_fold_plan(
    Y: np.ndarray,
    *,
    n_folds: int = 10,
    n_repeats: int = 1,
    seed: int = 0,
    groups: np.ndarray | None = None,
    target_names: Sequence[str] | None = None,
    regression: bool = False,
    split: Split = "k-fold",
) -> FoldPlan:
    """Repeated (stratified, group-aware) k-fold splits, or leave-one-group-out.

    Parameters
    ----------
    Y : ndarray of shape (n_instances, n_targets) or (n_instances,)
        Integer target codes, or target values with ``regression``.
    n_folds : int
        Requested number of folds (at least 2); leave-one-group-out makes one per group.
    n_repeats : int
        Number of repetitions, each shuffled with seed ``seed + repeat``; leave-one-group-out
        makes one partition only.
    seed : int
        Base random seed.
    groups : ndarray of shape (n_instances,), optional
        Group per instance (its recording, session, object or subject); instances of a
        group stay together.  Leave-one-group-out needs them.
    target_names : sequence of str, optional
        Names used in messages (default ``target 1``, ``target 2``...).
    regression : bool
        Numeric targets: shuffled (group) k-fold, never stratified.
    split : {"k-fold", "leave-one-group-out"}
        k-fold, or one fold per group with that group on the test side.

    Returns
    -------
    FoldPlan

    Raises
    ------
    ConfigurationError
        Empty data, a target with a single class, fewer than two instances or groups,
        instances without a group, or impossible parameters.
    """
    Y = np.asarray(Y)
    if Y.ndim == 1:
        Y = Y[:, None]
    if Y.ndim != 2:
        raise ConfigurationError(f"targets must be a 2-D array, got shape {Y.shape}")
    n_instances, n_targets = Y.shape
    names = list(target_names or [f"target {t + 1}" for t in range(n_targets)])
    if split == LEAVE_ONE_GROUP_OUT:
        return _leave_one_group_out(Y, n_repeats, groups, names, regression=regression)
    _check_parameters(n_folds, n_repeats, n_instances, n_targets)
    groups = _checked_groups(groups, n_instances)
    notes: list[str] = []
    if regression:
        strata, stratified = np.zeros(n_instances, dtype=np.int64), False
        k = _feasible_folds(min(n_folds, n_instances), None, groups, notes)
        if k < n_folds and groups is None:
            notes.append(f"only {n_instances} instances: using {k} folds instead of {n_folds}")
    else:
        _check_classes(Y, names)
        strata, stratified = _strata(Y, n_folds, names, notes, grouped=groups is not None)
        k = _feasible_folds(n_folds, strata if stratified else None, groups, notes)
    folds = [
        Fold(repeat, fold, np.sort(train).astype(np.int64), np.sort(test).astype(np.int64))
        for repeat in range(n_repeats)
        for fold, (train, test) in enumerate(
            _splits(k, strata, stratified, groups, seed + repeat, n_instances)
        )
    ]
    scheme = ("stratified " if stratified else "") + ("group " if groups is not None else "")
    return FoldPlan(folds, notes, scheme + "k-fold")


def _leave_one_group_out(
    Y: np.ndarray,
    n_repeats: int,
    groups: np.ndarray | None,
    names: Sequence[str],
    *,
    regression: bool,
) -> FoldPlan:
    """One fold per group, that group on its test side, groups in sorted order."""
    n_instances, n_targets = Y.shape
    if groups is None:
        raise ConfigurationError(
            "leave-one-group-out needs groups, and the data set has none (a group column "
            "named on import, or the recordings of an extracted data set, give them)"
        )
    _check_parameters(2, 1, n_instances, n_targets)  # the folds and repeats are checked below
    if n_repeats != 1:
        raise ConfigurationError(
            "leave-one-group-out makes one partition, the same every time: the number of "
            f"repeats must be 1, got {n_repeats}"
        )
    groups = _checked_groups(groups, n_instances)
    assert groups is not None
    if not regression:
        _check_classes(Y, names)
    labels, which = np.unique(groups, return_inverse=True)
    if labels.size < 2:
        raise ConfigurationError(
            f"leave-one-group-out needs at least 2 groups; every instance is in group '{labels[0]}'"
        )
    everything = np.arange(n_instances, dtype=np.int64)
    folds = [Fold(0, k, everything[which != k], everything[which == k]) for k in range(labels.size)]
    return FoldPlan(
        folds,
        [],
        f"leave-one-group-out over {labels.size} groups",
        test_groups=tuple(str(label) for label in labels),
    )


def _checked_groups(groups: np.ndarray | None, n_instances: int) -> np.ndarray | None:
    """``groups`` as an array of one group per instance, each instance with one."""
    if groups is None:
        return None
    groups = np.asarray(groups)
    if groups.shape != (n_instances,):
        raise ConfigurationError(
            f"groups must have one entry per instance ({n_instances}), got {groups.shape}"
        )
    if groups.dtype == object:
        without = np.flatnonzero(np.array([group is None for group in groups.tolist()]))
        if without.size:
            raise ConfigurationError(
                f"{without.size} instance(s) have no group (the first: instance "
                f"{int(without[0]) + 1}); group-aware folds need one for every instance"
            )
    return groups


def _check_classes(Y: np.ndarray, names: Sequence[str]) -> None:
    for t in range(Y.shape[1]):
        values = np.unique(Y[:, t])
        if values.size < 2:
            raise ConfigurationError(
                f"target '{names[t]}' has a single class (code {int(values[0])}) among the "
                f"{Y.shape[0]} instances; classification needs at least two"
            )


def _check_parameters(n_folds: int, n_repeats: int, n_instances: int, n_targets: int) -> None:
    if n_instances == 0:
        raise ConfigurationError("the data set is empty: there is nothing to cross-validate")
    if n_targets == 0:
        raise ConfigurationError("no target attribute to predict")
    if n_folds < 2:
        raise ConfigurationError(f"the number of folds must be at least 2, got {n_folds}")
    if n_repeats < 1:
        raise ConfigurationError(f"the number of repeats must be at least 1, got {n_repeats}")
    if n_instances < 2:
        raise ConfigurationError("cross-validation needs at least 2 instances, got 1")


def _strata(
    Y: np.ndarray, n_folds: int, names: Sequence[str], notes: list[str], *, grouped: bool
) -> tuple[np.ndarray, bool]:
    """The labels to stratify on and whether stratification is used."""
    if Y.shape[1] == 1:
        return Y[:, 0], True
    _, joint, counts = np.unique(Y, axis=0, return_inverse=True, return_counts=True)
    joint = joint.reshape(-1)
    if counts.min() >= n_folds:
        notes.append(f"folds stratified on the {counts.size} combinations of {', '.join(names)}")
        return joint, True
    notes.append(
        f"folds not stratified: {int((counts < n_folds).sum())} of the {counts.size} "
        f"combinations of {', '.join(names)} have fewer than {n_folds} instances "
        + ("(group k-fold)" if grouped else "(plain shuffled k-fold)")
    )
    return joint, False


def _feasible_folds(
    n_folds: int, strata: np.ndarray | None, groups: np.ndarray | None, notes: list[str]
) -> int:
    """The largest number of folds, at most ``n_folds``, that the data supports."""
    if groups is not None:
        n_groups = np.unique(groups).size
        if n_groups < 2:
            raise ConfigurationError(
                "all instances belong to one recording/session group; group-aware folds "
                "need at least 2 groups"
            )
        if n_groups < n_folds:
            notes.append(f"only {n_groups} groups: using {n_groups} folds instead of {n_folds}")
            return n_groups
        return n_folds
    if strata is None:
        return n_folds
    smallest = int(np.bincount(np.unique(strata, return_inverse=True)[1]).min())
    k = max(2, min(n_folds, smallest))
    if k < n_folds:
        notes.append(
            f"the smallest class has only {smallest} instance(s): using {k} folds instead "
            f"of {n_folds}"
        )
    if smallest < 2:
        notes.append(
            "a class has a single instance: it is tested in one fold without ever being trained on"
        )
    return k


def _splits(
    k: int,
    strata: np.ndarray,
    stratified: bool,
    groups: np.ndarray | None,
    seed: int,
    n_instances: int,
) -> list[tuple[np.ndarray, np.ndarray]]:
    placeholder = np.zeros((n_instances, 1))
    splitter: StratifiedKFold | KFold | StratifiedGroupKFold | GroupKFold
    if groups is None and stratified:
        splitter = StratifiedKFold(n_splits=k, shuffle=True, random_state=seed)
    elif groups is None:
        splitter = KFold(n_splits=k, shuffle=True, random_state=seed)
    elif stratified:
        splitter = StratifiedGroupKFold(n_splits=k, shuffle=True, random_state=seed)
    else:
        splitter = GroupKFold(n_splits=k, shuffle=True, random_state=seed)
    with warnings.catch_warnings():
        # scikit-learn warns about classes smaller than k; _feasible_folds reported it.
        warnings.simplefilter("ignore", UserWarning)
        return list(splitter.split(placeholder, strata, groups))
