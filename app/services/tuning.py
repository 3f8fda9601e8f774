"""A run's tuned twins (its request's ``tune``), stack (``stack``) and ensemble selection
(``ensemble``): which ids they add,
and the specs the engine needs to build them again from the run's stored config.
"""

from __future__ import annotations

# Imports inside functions: start-up time: the catalogue loads scikit-learn, which only
# a run with tuned twins or a stack needs.
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

from touchbench.app.errors import FieldError
from touchbench.app.schemas.run_config import ExtraSpecsConfig
from touchbench.app.services.own_specs import own_specs

if TYPE_CHECKING:
    from touchbench.benchmark.catalogue import ClassifierSpec


def with_tuned_twins(
    ids: Sequence[str], extra_specs: Mapping[str, ClassifierSpec], budget_minutes: float | None
) -> list[str]:
    """``ids`` with each tunable one followed by its tuned twin (``rf``, ``rf+tuned``).

    A multi-target configuration ``META:BASE`` is tunable when its base is.

    Raises
    ------
    FieldError
        For ``tune``: no id of the run declares a search space.
    ConfigurationError
        A search space that its estimator refuses; a budget out of the engine's range.
    """
    from touchbench.benchmark.catalogue import SEARCH_SPACES
    from touchbench.benchmark.catalogue.tuning import (
        check_budget,
        is_tuned_id,
        tuned_id,
        tuned_spec,
    )
    from touchbench.benchmark.estimators import classifier_spec, is_multitarget_id

    check_budget(budget_minutes)
    out: list[str] = []
    for classifier in ids:
        out.append(classifier)
        if is_tuned_id(classifier):
            continue
        meta, _, base = classifier.rpartition(":")
        if is_multitarget_id(classifier) and not meta:
            continue  # a META without a base (``lc``): nothing to tune
        spec = classifier_spec(base, extra_specs)
        if spec.search_space:
            tuned_spec(spec, budget_minutes)  # a space its estimator refuses fails here
            out.append(f"{meta}:{tuned_id(base)}" if meta else tuned_id(base))
    if len(out) == len(ids):
        raise FieldError(
            "tune",
            "no classifier of this run declares a search space (those that do: "
            f"{', '.join(SEARCH_SPACES)})",
        )
    return list(dict.fromkeys(out))


def run_specs(config: ExtraSpecsConfig, classifiers: Sequence[str]) -> dict[str, ClassifierSpec]:
    """Every spec outside the catalogue that a run's classifiers need, by id.

    Parameters
    ----------
    config : ExtraSpecsConfig
        What the run adds (its stored config, a :class:`app.schemas.run_config.RunConfig`):
        ``weka`` (id -> WEKA command), ``tune``, ``stack`` and ``ensemble``.
    classifiers : sequence of str
        The run's classifier ids (its stack and ensemble selection among them).

    The specs the caller brought (:mod:`app.services.own_specs`) are among them.
    """
    from touchbench.benchmark.catalogue import parse_weka_command
    from touchbench.benchmark.catalogue.ensembles import selection_id, selection_spec
    from touchbench.benchmark.catalogue.stacking import stack_id, stacked_spec
    from touchbench.benchmark.catalogue.tuning import TUNED_SUFFIX, is_tuned_id, tuned_spec
    from touchbench.benchmark.estimators import classifier_spec
    from touchbench.benchmark.run.members import VOTES

    specs: dict[str, ClassifierSpec] = dict(own_specs())
    for text in config.weka.values():
        if text:
            spec = parse_weka_command(text)
            specs[spec.id] = spec
    tune = config.tune
    if tune is not None:
        for classifier in classifiers:
            base = classifier.rpartition(":")[2]
            if is_tuned_id(base):
                untuned = classifier_spec(base.removesuffix(TUNED_SUFFIX), specs)
                specs[base] = tuned_spec(untuned, tune.budget_minutes)
    added = {selection_id(config.ensemble)} if config.ensemble is not None else set()
    top_n = config.stack
    if top_n:
        added.add(stack_id(top_n))
    # the stack and the selection choose among the run's other entries, never each other:
    # neither has inner predictions to be chosen by (the engine leaves them out too)
    members = [classifier_spec(c, specs) for c in classifiers if c not in added] if added else []
    if top_n:
        specs[stack_id(top_n)] = stacked_spec(members, top_n)
    if config.ensemble is not None:
        candidates = [m for m in members if m.combine is None or m.combine in VOTES]
        specs[selection_id(config.ensemble)] = selection_spec(candidates, config.ensemble)
    return specs


def add_selection(ids: Sequence[str], rounds: int, *, kind: str) -> list[str]:
    """``ids`` and the ensemble selection of ``rounds`` rounds over them (``ensemble-N``).

    Raises
    ------
    FieldError
        For ``ensemble``: a run that is not multi-class.
    """
    from touchbench.benchmark.catalogue.ensembles import selection_id

    if kind != "multiclass":
        raise FieldError(
            "ensemble", "selects among multi-class classifiers: pick one nominal `target`"
        )
    return [*ids, selection_id(rounds)]


def add_stack(ids: Sequence[str], top_n: int, *, multitarget: bool) -> list[str]:
    """``ids`` and the stack over them.

    Raises
    ------
    FieldError
        For ``stack``: a multi-target run, or more members than the run has classifiers.
    """
    from touchbench.benchmark.catalogue.stacking import check_top_n, stack_id

    if multitarget:
        raise FieldError("stack", "stacks multi-class classifiers: pick one `target`")
    if top_n > len(ids):
        raise FieldError(
            "stack",
            f"needs at least {top_n} classifiers in the run to choose from; the run has {len(ids)}",
        )
    check_top_n(top_n, len(ids))  # the engine's own bounds, which the request's keep
    return [*ids, stack_id(top_n)]
