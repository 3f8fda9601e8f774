"""A benchmark request checked against its data set and stored as a ``queued`` run.

:func:`create_run` validates everything that can be validated before any work is done (the
data set, its targets, the classifier ids, the folds) and stores the run with the
configuration that its execution (and any resume) reads back.
"""

from __future__ import annotations

# Imports inside functions: start-up time. The listing commands, the API's routes and the
# job process import this module; the catalogue, the tuning and the recordings' checks load
# scikit-learn and scipy, which only the functions that need them import.
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

from touchbench.app.errors import FieldError
from touchbench.app.schemas.run_config import (
    ExtraSpecsConfig,
    OriginConfig,
    RaceConfig,
    RunConfig,
    TuneConfig,
)
from touchbench.app.schemas.runs import RACE_MIN_FOLDS, BenchRequest
from touchbench.app.services.runs.problem import (
    OneValueError,
    RunOptions,
    fold_plan,
    prepare_problem,
)
from touchbench.app.services.runs.ranking import check_metric
from touchbench.app.services.tuning import run_specs
from touchbench.app.store.database import Store
from touchbench.app.store.datasets import load_dataset, load_schema
from touchbench.app.store.runs import RunInfo
from touchbench.app.store.runs import create_run as store_run
from touchbench.benchmark.dataset import Schema
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.problem import Problem, position_columns

if TYPE_CHECKING:
    from touchbench.benchmark.catalogue import ClassifierSpec


def _check_position(schema: Schema, position: Sequence[str]) -> None:
    """Refuse a position the run's targets (``schema``'s) cannot have, naming the field.

    Raises
    ------
    FieldError
        Not 2 or 3 distinct numeric targets, or targets that are not all numeric (a
        position's run is a regression).
    """
    try:
        position_columns(schema, position)
    except ConfigurationError as error:
        raise FieldError("position", str(error)) from None
    nominal = [t.name for t in schema.targets if t.kind != "numeric"]
    if nominal:
        raise FieldError(
            "position",
            f"coordinates make the run a regression, and the targets include nominal ones "
            f"({', '.join(nominal)}): a position's run takes numeric targets only",
        )


def default_classifiers(
    n_targets: int,
    suite_name: str = "default",
    *,
    sequences: bool = False,
    regression_size: int | None = None,
) -> list[str]:
    """The classifiers a suite means for a data set with ``n_targets`` targets.

    Sequence classifiers are among them only for a sequence data set (``sequences``).
    A regression (``regression_size``: its number of instances) gets the suite's
    regressors (:func:`benchmark.catalogue.regressors.regression_suite`).
    """
    from touchbench.benchmark.estimators import reads_sequences

    if regression_size is not None:
        from touchbench.benchmark.catalogue.regressors import regression_suite

        return regression_suite(
            suite_name, n_targets=n_targets, n_instances=regression_size, sequences=sequences
        )
    if n_targets > 1:
        from touchbench.benchmark.multitarget.suites import multitarget_suite

        ids = multitarget_suite(suite_name)
    else:
        from touchbench.benchmark.catalogue import suite

        ids = suite(suite_name)
    return [i for i in ids if sequences or not reads_sequences(i)]


def check_classifiers(
    problem: Problem,
    classifiers: Sequence[str],
    extra_specs: Mapping[str, ClassifierSpec] | None = None,
    *,
    asked: Sequence[str] = (),
) -> None:
    """Refuse, before a run exists, ids that are unknown or do not fit the problem.

    Raises
    ------
    FieldError
        For ``classifiers``: one of the ids the user asked for (``asked``) is refused.
    ConfigurationError
        No classifiers; an id the run added (a suite's, a twin) does not fit.
    """
    from touchbench.benchmark.estimators import check_classifier

    if not classifiers:
        raise ConfigurationError("no classifiers to run")
    for classifier in classifiers:
        try:
            check_classifier(classifier, problem, extra_specs)
        except ConfigurationError as error:
            if classifier in asked:
                raise FieldError("classifiers", str(error)) from None
            raise


def weka_specs(commands: Sequence[str] | Mapping[str, str | None]) -> dict[str, ClassifierSpec]:
    """The catalogue configurations of WEKA command lines, by id (a run's ``weka``).

    Raises
    ------
    FieldError
        For ``weka``: a command line the catalogue cannot compute.
    """
    from touchbench.benchmark.catalogue import parse_weka_command

    texts = commands.values() if isinstance(commands, Mapping) else commands
    try:
        specs = [parse_weka_command(text) for text in texts if text]
    except ConfigurationError as error:
        raise FieldError("weka", str(error)) from None
    return {spec.id: spec for spec in specs}


@dataclass(frozen=True)
class Plan:
    """A checked run, ready to be stored: what :func:`create_run` stores."""

    dataset_id: int
    kind: str
    targets: list[str]
    classifiers: list[str]
    config: RunConfig
    notes: list[str]


def create_run(
    store: Store, request: BenchRequest, *, on_warning: Callable[[str], None] | None = None
) -> RunInfo:
    """Check a benchmark request against its data set and store it as a ``queued`` run.

    The command line carries the run out at once (:func:`execute_run`), the service's
    workers later; a benchmark of each target on its own is :func:`independent_runs`.

    Parameters
    ----------
    store : Store
    request : BenchRequest
        The run's data set, classifiers and protocol, checked on their own already.
    on_warning : callable, optional
        Hears adjustments made (fewer folds than asked, unstratified folds, ...).

    Raises
    ------
    FieldError
        A field the data set refuses: a target it lacks, a metric of the other kind of
        problem, ``tune``,
        ``stack``, ``ensemble`` or ``weka`` on numeric targets, a stack or an ensemble
        selection on several targets, a baseline
        that is not one of the run's classifiers, impossible folds, ``independent``.
    NotFoundError
        An unknown data set.
    ConfigurationError
        Anything else that would make the run fail at once: a target with one class.
    """
    if request.independent:
        raise FieldError(
            "independent",
            "asks for one run per target, carried out at once rather than queued: "
            "queue a run per `target` instead",
        )
    return store_plan(store, plan_run(store, request), on_warning)


def plan_run(store: Store, request: BenchRequest) -> Plan:
    """Everything :func:`create_run` checks, and the run it would store."""
    options = RunOptions.from_request(request)
    commands = weka_specs(request.weka or ())
    targets = [request.target] if request.target else None
    position = list(request.position or ())
    info, schema, _ = load_schema(store, request.dataset)
    if request.target is not None:
        try:
            schema.index(request.target)
        except ConfigurationError as error:
            raise FieldError("target", str(error)) from None
    if position:
        run_schema = schema if targets is None else schema.with_targets([schema.index(targets[0])])
        _check_position(run_schema, position)
    try:
        prepared = prepare_problem(load_dataset(store, info.id), targets, position)
    except OneValueError as error:
        if error.target not in position:
            raise
        raise FieldError(
            "position", f"'{error.target}' has a single value ({error.value:g}): nothing to predict"
        ) from None
    problem = prepared.problem
    if request.metric is not None:
        try:
            check_metric(problem.kind, request.metric, position=bool(position))
        except ConfigurationError as error:
            raise FieldError("metric", str(error)) from None
    numeric = problem.kind == "regression"
    for name in ("weka", "tune", "stack", "ensemble"):
        if numeric and getattr(request, name):
            raise FieldError(name, "works on classification runs; the targets here are numeric")
    ids = list(dict.fromkeys(request.classifiers or ()))
    if not ids and not commands:
        ids = default_classifiers(
            len(prepared.target_names),
            request.suite or "default",
            sequences=problem.sequence is not None,
            regression_size=problem.n_instances if numeric else None,
        )
    ids = list(dict.fromkeys([*ids, *commands]))
    extras = _extra_specs(commands, request.tune, request.budget, request.stack, request.ensemble)
    if request.tune:
        from touchbench.app.services.tuning import with_tuned_twins

        ids = with_tuned_twins(ids, commands, request.budget)
    if request.stack is not None:
        from touchbench.app.services.tuning import add_stack

        ids = add_stack(ids, request.stack, multitarget=problem.kind == "multitarget")
    if request.ensemble is not None:
        from touchbench.app.services.tuning import add_selection

        ids = add_selection(ids, request.ensemble, kind=problem.kind)
    try:
        specs = run_specs(extras, ids)
        check_classifiers(problem, ids, specs, asked=request.classifiers or ())
        helpers, origins = plan_entries(problem, ids, specs, request.ensemble)
    except ConfigurationError as error:
        if request.ensemble is not None and _about_selection(error):
            raise FieldError("ensemble", str(error)) from None
        raise
    if request.baseline is not None and request.baseline not in ids:
        raise FieldError(
            "baseline",
            f"'{request.baseline}' is not a classifier of this run (classifiers: {', '.join(ids)})",
        )
    if request.aggregate == "recording":
        from touchbench.benchmark.evaluation.recordings import check_one_label

        try:
            check_one_label(problem.Y, problem.groups, prepared.target_names, info.name)
        except ConfigurationError as error:
            raise FieldError("aggregate", str(error)) from None
    plan = fold_plan(prepared, options)
    if request.race and len(plan.folds) < RACE_MIN_FOLDS:
        raise FieldError(
            "race",
            f"needs at least {RACE_MIN_FOLDS} folds in all, and the data allow "
            f"{len(plan.folds)} ({'; '.join(plan.notes)})",
        )
    config = RunConfig(
        folds=max(f.fold for f in plan.folds) + 1,
        repeats=options.repeats,
        seed=options.seed,
        timeout=options.timeout,
        max_memory_mb=options.max_memory_mb,
        folds_requested=options.folds if options.split == "k-fold" else None,
        split=options.split,
        targets_given=targets,
        suite=None if request.classifiers or request.weka else (request.suite or "default"),
        weka=extras.weka,
        tune=extras.tune,
        stack=extras.stack,
        ensemble=extras.ensemble,
        helpers=helpers,
        origins=origins,
        n_tasks=(len(ids) + len(helpers)) * len(plan.folds),
        n_instances=int(problem.X.shape[0]),
        grouped=problem.groups is not None,
        fold_scheme=plan.scheme,
        position=position or None,
        metric=request.metric,
        baseline=request.baseline,
        race=RaceConfig(alpha=request.race_alpha) if request.race else None,
        budget_total=request.budget_total,
        aggregate=request.aggregate,
    )
    return Plan(
        info.id, problem.kind, prepared.target_names, ids, config, prepared.warnings + plan.notes
    )


def store_plan(
    store: Store, plan: Plan, on_warning: Callable[[str], None] | None = None
) -> RunInfo:
    run = store_run(
        store,
        dataset_id=plan.dataset_id,
        kind=plan.kind,
        targets=plan.targets,
        classifiers=plan.classifiers,
        config=plan.config,
    )
    if on_warning is not None:
        for message in plan.notes:
            on_warning(message)
    return run


def _extra_specs(
    commands: Mapping[str, ClassifierSpec],
    tune: bool,
    budget: float | None,
    stack: int | None,
    ensemble: int | None,
) -> ExtraSpecsConfig:
    """The parts of a run's config that say how to build its extra specs again."""
    return ExtraSpecsConfig(
        weka={spec_id: spec.weka_command for spec_id, spec in commands.items()},
        tune=TuneConfig(budget_minutes=budget) if tune else None,
        stack=stack,
        ensemble=ensemble,
    )


def plan_entries(
    problem: Problem,
    ids: Sequence[str],
    specs: Mapping[str, ClassifierSpec],
    ensemble: int | None,
) -> tuple[list[str], dict[str, OriginConfig]]:
    """The helpers of a run (members of its ensembles it did not ask for) and how it comes
    by the folds of its computed entries and helpers (:meth:`RunPlan.origins`).

    Raises
    ------
    ConfigurationError
        Members that the problem refuses, or that make a cycle; an ensemble selection
        without an entry to choose among.
    """
    from touchbench.benchmark.run.members import plan_run as plan_members

    planned = plan_members(problem, ids, extra_specs=specs, ensemble=ensemble)
    origins = {
        entry: OriginConfig(kind=origin.kind, entries=list(origin.entries))
        for entry, origin in planned.origins().items()
    }
    return list(planned.helpers), origins


def _about_selection(error: ConfigurationError) -> bool:
    """Whether the catalogue refused the ensemble selection itself (its rounds, no entry
    to choose among), as its messages say."""
    text = str(error)
    return "ensemble selection" in text or text.startswith("`ensemble`")
