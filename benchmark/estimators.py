"""From a classifier id and a problem to an estimator: the one place that decides.

A problem with one target takes a catalogue id (``rf``, ``j48``...); one with several
targets takes a multi-target configuration (``META:BASE``, e.g. ``bcc:rf``); a regression
(numeric targets) takes a regressor id (``ridge``, ``rf``, ``rc:xgb``...,
:mod:`benchmark.catalogue.regressors`).  The engine,
its tasks, model training and the app's checks all ask here, so the rule lives once.
"""

from __future__ import annotations

import inspect
from collections.abc import Mapping
from typing import Any

import numpy as np

from touchbench.benchmark.catalogue import (
    CATALOGUE,
    ClassifierSpec,
    build_pipeline,
    check_sequence_input,
    get_spec,
)
from touchbench.benchmark.catalogue import unknown_classifier_message as _unknown_message
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.extras import require
from touchbench.benchmark.problem import Problem

__all__ = [
    "build_estimator",
    "check_classifier",
    "classifier_spec",
    "is_multitarget_id",
    "reads_sequences",
]


def is_multitarget_id(classifier_id: str) -> bool:
    """Whether ``classifier_id`` names a multi-target configuration (``META:BASE`` or a META)."""
    from touchbench.benchmark.multitarget import META_METHODS

    return ":" in classifier_id or classifier_id.lower() in META_METHODS


def reads_sequences(classifier_id: str) -> bool:
    """Whether a catalogue id or ``META:BASE`` configuration needs a sequence data set."""
    if is_multitarget_id(classifier_id):
        from touchbench.benchmark.multitarget import parse_config

        _, base = parse_config(classifier_id)
        return bool(base) and get_spec(base).needs_sequence
    return classifier_spec(classifier_id).needs_sequence


def classifier_spec(
    classifier_id: str, extra_specs: Mapping[str, ClassifierSpec] | None = None
) -> ClassifierSpec:
    """The multi-class spec of ``classifier_id``: an extra spec first, else the catalogue's.

    Raises
    ------
    ConfigurationError
        Unknown id, naming the closest known one.
    """
    from touchbench.benchmark.catalogue.tuning import is_tuned_id

    if extra_specs and classifier_id in extra_specs:
        return extra_specs[classifier_id]
    if classifier_id in CATALOGUE or is_tuned_id(classifier_id):
        return get_spec(classifier_id)
    raise ConfigurationError(_unknown_message(classifier_id, {**CATALOGUE, **(extra_specs or {})}))


def check_classifier(
    classifier_id: str,
    problem: Problem,
    extra_specs: Mapping[str, ClassifierSpec] | None = None,
) -> ClassifierSpec | None:
    """Refuse an id that is unknown or does not fit the problem's targets.

    Parameters
    ----------
    classifier_id : str
    problem : Problem
        Only its shape is used (targets, classes).
    extra_specs : mapping of str to ClassifierSpec, optional
        Multi-class specs outside the catalogue.

    Returns
    -------
    ClassifierSpec or None
        The multi-class spec or the regressor's; ``None`` for a multi-target configuration.

    Raises
    ------
    ConfigurationError
        Unknown id; a multi-class id for several targets (or the reverse); a binary-only
        multi-label method on targets with more than two classes; a sequence classifier
        (as the classifier or as a base) on flat features; an id with no regressor on
        numeric targets.
    """
    from touchbench.benchmark.multitarget import check_targets, parse_config

    if problem.kind == "regression":
        from touchbench.benchmark.catalogue.regressors import regressor_spec

        regressor = regressor_spec(
            classifier_id, n_targets=problem.n_targets, n_instances=problem.n_instances
        )
        require(regressor.requires, f"regressor '{classifier_id}'")
        check_sequence_input(regressor, problem.sequence)
        return regressor
    names = ", ".join(problem.target_names)
    if is_multitarget_id(classifier_id):
        _, base = parse_config(classifier_id)
        check_targets(classifier_id, problem.n_classes, problem.target_names)
        if base:
            base_spec = classifier_spec(base, extra_specs)
            require(base_spec.requires, f"classifier '{classifier_id}'")
            check_sequence_input(base_spec, problem.sequence)
        return None
    spec = classifier_spec(classifier_id, extra_specs)
    require(spec.requires, f"classifier '{classifier_id}'")
    check_sequence_input(spec, problem.sequence)
    if problem.kind == "multitarget":
        raise ConfigurationError(
            f"'{classifier_id}' is a multi-class classifier and the data set has "
            f"{len(problem.target_names)} targets ({names}): choose one of them as `target`, "
            f"or a multi-target configuration such as bcc:{classifier_id}"
        )
    return spec


def build_estimator(
    classifier_id: str,
    problem: Problem,
    *,
    random_state: int | None = 0,
    extra_specs: Mapping[str, ClassifierSpec] | None = None,
) -> Any:
    """A fresh, unfitted estimator for ``classifier_id`` on ``problem``.

    Parameters
    ----------
    classifier_id : str
        A catalogue id (one target) or a ``META:BASE`` configuration (several targets).
    problem : Problem
        Decides the kind, the nominal feature columns, the feature count and the declared
        classes per target.
    random_state : int or None
        Seed of the estimator.
    extra_specs : mapping of str to ClassifierSpec, optional
        Multi-class specs outside the catalogue.

    Returns
    -------
    estimator
        A scikit-learn pipeline (``fit(X, y)`` with ``y`` of shape (n_instances,)) for one
        target, or a regression's (``y`` of shape (n_instances,) for one target, (n_instances,
        n_targets) for several); a multi-target classifier (``fit(X, Y)`` with ``Y`` of shape
        (n_instances, n_targets)) for several.
    """
    spec = check_classifier(classifier_id, problem, extra_specs)
    if spec is not None:
        return build_pipeline(
            spec,
            nominal_features=problem.nominal_features,
            n_features=problem.n_features,
            random_state=random_state,
            sequence=problem.sequence,
        )
    from touchbench.benchmark.multitarget import build_multitarget

    return build_multitarget(
        classifier_id,
        nominal_features=problem.nominal_features,
        n_features=problem.n_features,
        random_state=random_state,
        n_classes=problem.n_classes,
        sequence=problem.sequence,
        extra_specs=extra_specs,
    )


def group_fit_params(estimator: Any, groups: np.ndarray | None) -> dict[str, np.ndarray]:
    """Fit parameters that hand ``groups`` to a pipeline's last step if its ``fit`` takes
    them, else none.

    The neural networks hold out part of the training fold for early stopping; with the
    groups (a window's recording) they hold out whole recordings, so that a recording's
    sister windows on both sides cannot hide overfitting from the validation loss.

    Parameters
    ----------
    estimator : Any
        What :func:`build_estimator` returned.
    groups : ndarray of shape (n_instances,) or None
        The group of each training instance, rows as the ``X`` given to ``fit``.
    """
    if groups is None or not hasattr(estimator, "steps"):
        return {}
    name, last = estimator.steps[-1]
    if "groups" not in inspect.signature(last.fit).parameters:
        return {}
    return {f"{name}__groups": np.asarray(groups)}
