"""The cross-validation engine: every classifier on every fold, in parallel, with time limits.

The engine checks the classifier ids, lists the tasks (one classifier on one fold), pickles
what every task needs once, and hands the tasks to a backend
(:class:`~benchmark.run.backend.Backend`): ``jobs`` local worker processes
(:mod:`benchmark.run.local_backend`), or with ``scheduler="tcp://host:port"`` a Dask
distributed cluster (:mod:`benchmark.run.dask_backend`).

Every finished task is reported at once through ``on_result`` (in the calling process),
so that the caller can store it; ``skip`` resumes a run without repeating what is done.
A plain run hands the tasks out classifier-major; a raced run or one with a total budget
runs them fold-major, cheap first (:mod:`benchmark.run.schedule`).

Each task keeps its test fold's predictions (:mod:`benchmark.predictions`).  The run's
ensembles of entries, stacks and ensemble selection have no tasks: their folds are computed
here from their members' predictions as these arrive (:mod:`benchmark.run.members` plans
which entries need which, :mod:`benchmark.run.combine` computes), each member fitted once
per fold whichever ensembles name it.  A run whose stacks or selection read inner
predictions runs fold-major, so that a fold's predictions are let go once its ensembles are
computed.
"""

from __future__ import annotations

import math
import os
import pickle
import time
from collections.abc import Callable, Collection, Mapping, Sequence

from touchbench.benchmark.catalogue import ClassifierSpec
from touchbench.benchmark.catalogue.costs import Shape, estimate_seconds
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.estimators import classifier_spec, is_multitarget_id
from touchbench.benchmark.problem import Problem
from touchbench.benchmark.results import Drop, TaskKey, TaskResult
from touchbench.benchmark.run.backend import Backend, RunStopped, StartCallback, StopCheck
from touchbench.benchmark.run.combine import Combiner
from touchbench.benchmark.run.dask_backend import DaskBackend
from touchbench.benchmark.run.folds import Fold
from touchbench.benchmark.run.local_backend import LocalBackend
from touchbench.benchmark.run.members import RunPlan, plan_run
from touchbench.benchmark.run.racing import RaceRule
from touchbench.benchmark.run.schedule import RoundSchedule, TaskList, TaskSource, test_train_ratio
from touchbench.benchmark.run.task import TaskContext

__all__ = [
    "Problem",
    "RaceRule",
    "RunStopped",
    "TaskKey",
    "TaskResult",
    "available_cores",
    "plan_run",
    "plan_tasks",
    "run_tasks",
]

#: Bytes of ``max_memory`` at most: the kernel's limits are signed 64-bit numbers, and a
#: worker adds what it already uses.
MAX_MEMORY = 2**62


def run_tasks(
    problem: Problem,
    classifiers: Sequence[str],
    folds: Sequence[Fold],
    *,
    jobs: int = 1,
    scheduler: str | None = None,
    timeout: float | None,
    random_state: int = 0,
    skip: Collection[TaskKey] = (),
    on_start: StartCallback | None = None,
    on_result: Callable[[TaskResult], None] | None = None,
    extra_specs: Mapping[str, ClassifierSpec] | None = None,
    max_memory: int | None = None,
    stop: StopCheck | None = None,
    race: RaceRule | None = None,
    budget: float | None = None,
    previous: Sequence[TaskResult] = (),
    on_drop: Callable[[Drop], None] | None = None,
    clock: Callable[[], float] = time.monotonic,
    by_recording: bool = False,
    ensemble: int | None = None,
) -> list[TaskResult]:
    """Cross-validate classifiers on a problem.

    Parameters
    ----------
    problem : Problem
        Features and targets.  One target: catalogue classifiers; several targets:
        multi-target configurations (``META:BASE``) of :mod:`benchmark.multitarget`;
        numeric targets: regressors (:mod:`benchmark.catalogue.regressors`).
    classifiers : sequence of str
        Classifier ids, run in this order (duplicates ignored).
    folds : sequence of Fold
        The folds, shared by every classifier (:func:`benchmark.run.folds.make_folds`).
    jobs : int
        Local worker processes; -1 for one per core.  Ignored with ``scheduler``.
    scheduler : str, optional
        Address of a Dask distributed scheduler (``tcp://host:port``) to run on instead.
    timeout : float or None
        Seconds one task may take before its worker is killed; ``None`` for no limit.
        Required: the caller's request owns its default.
    random_state : int
        Seed of every classifier.
    skip : collection of TaskKey
        Tasks already done (a resumed run); they are neither run nor returned.
    on_start : callable, optional
        Called with each task's key when it starts.
    on_result : callable, optional
        Called in the calling process with each result as soon as it arrives.
    extra_specs : mapping of str to ClassifierSpec, optional
        Multi-class classifiers that are not in the catalogue (they win over catalogue
        entries of the same id).  Their factories must be importable by the workers.
    max_memory : int, optional
        Bytes of memory one task may allocate beyond its worker's copy of the data; a task
        that needs more fails with an ``error`` result saying so.
    stop : callable, optional
        Cheap (such as ``threading.Event().is_set``); checked about ten times a second
        while tasks run.  When it returns true, running tasks are killed, no task starts
        any more and :class:`RunStopped` is raised (the results reported so far stand).
    race : RaceRule, optional
        Race the classifiers: fold-major rounds, and after each round from the third the
        classifiers significantly worse than the leader stop (:mod:`benchmark.run.racing`).
    budget : float, optional
        Wall seconds for the whole call: tasks run fold-major, cheap first, and a task whose
        predicted cost (its classifier's timed folds, else its shape-aware cost hint) does
        not fit the time left is not started, nor are its classifier's later folds.
    previous : sequence of TaskResult
        The stored results of a resumed run (their keys are skipped); a race replays its
        decisions from them and goes on.
    on_drop : callable, optional
        Hears each classifier the race drops (at once) and each one the budget cut short
        (when the tasks are over).
    clock : callable
        Monotonic seconds the budget is measured by (a test's own clock decides when a
        task's cost no longer fits, without waiting).
    by_recording : bool
        Score each test recording (``problem.groups``) as one prediction pooled over its
        windows (:mod:`benchmark.evaluation.recordings`); the caller checks that the
        problem has groups and one label per recording.
    ensemble : int, optional
        Add ``ensemble-N``: in each training fold, N rounds of Caruana's greedy ensemble
        selection over the run's entries, on their inner out-of-fold predictions
        (:mod:`benchmark.catalogue.ensembles`).  Multi-class runs only.

    Returns
    -------
    list of TaskResult
        One per task run and per derived fold computed, classifier-major in the order of
        ``classifiers`` (then the helpers, :attr:`RunPlan.helpers`) and ``folds``, each
        with its fold predictions.  Classifiers that raise, run out of memory, crash or
        time out give results with status ``error`` or ``timeout``; the run goes on.  A
        raced classifier's results stop at the fold after which it was dropped.

    Raises
    ------
    ConfigurationError
        Unknown classifier ids, no folds, impossible ``jobs``, ``timeout`` or
        ``max_memory``, an unreachable scheduler.
    RunStopped
        ``stop`` returned true.
    """
    check_limits(jobs=jobs, timeout=timeout, max_memory=max_memory)
    if budget is not None and not (budget > 0 and math.isfinite(budget)):
        raise ConfigurationError(
            f"budget must be a positive, finite number of seconds, got {budget}"
        )
    skip = set(skip) | {r.key for r in previous}
    plan, tasks = _plan(problem, classifiers, folds, skip, extra_specs, ensemble)
    rounds = [(f.repeat, f.fold) for f in folds]
    rerun = plan.reruns(rounds, skip, {r.key: r for r in previous})
    context = TaskContext(problem, plan.specs, list(folds), random_state, by_recording, plan.inner)
    combiner = Combiner(plan, context, done=skip)
    # derived folds whose members an earlier execution left at hand
    early = [derived for result in previous for derived in combiner.add(result)]
    if not tasks and not rerun and not early:
        return []
    sizes = {(f.repeat, f.fold): (int(f.train.size), int(f.test.size)) for f in folds}
    results: dict[TaskKey, TaskResult] = {}

    def deliver(result: TaskResult) -> None:
        if result.status != "ok":
            result.n_train, result.n_test = sizes[(result.key.repeat, result.key.fold)]
            if max_memory is not None and _looks_out_of_memory(result.error):
                result.error = (
                    f"exceeded the memory limit of {max_memory / 2**20:g} MB per task "
                    f"({result.error})"
                )
        derived = combiner.add(result)
        if result.key not in rerun:  # a task run again for its predictions was stored
            arrive(result)
        for computed in derived:
            arrive(computed)

    def arrive(result: TaskResult) -> None:
        if isinstance(source, RoundSchedule):
            source.arrived(result)  # it hands the result on, or holds it for its race
        else:
            hand_on(result)

    def hand_on(result: TaskResult) -> None:
        results[result.key] = result
        if on_result is not None:
            on_result(result)
        result.inner_predictions = None  # read by the combiner, which keeps its own

    def started(key: TaskKey) -> None:
        if on_start is not None and key not in rerun:
            on_start(key)

    source: TaskSource = TaskList(sorted(rerun) + tasks)
    if race is not None or budget is not None or plan.inner:
        if race is not None and len(folds) < race.first_round:
            raise ConfigurationError(
                f"a race needs at least {race.first_round} folds, got {len(folds)}"
            )
        source = RoundSchedule(
            plan.entries,
            rounds,
            hand_on,
            hints=cost_hints(problem, plan.workers, plan.specs, folds),
            previous=previous,
            done=skip,
            race=race,
            test_train_ratio=test_train_ratio(sizes.values()),
            budget=budget,
            on_drop=on_drop,
            clock=clock,
            derived={entry: plan.uses(entry) for entry in plan.derived},
            helpers=plan.helpers,
            rerun=rerun,
        )
    for computed in early:
        arrive(computed)
    pickled = pickle.dumps(context, protocol=pickle.HIGHEST_PROTOCOL)
    backend: Backend
    if scheduler:
        backend = DaskBackend(scheduler, pickled, timeout=timeout, max_memory=max_memory)
    else:
        workers = available_cores() if jobs == -1 else jobs
        backend = LocalBackend(pickled, workers=workers, timeout=timeout, max_memory=max_memory)
    if not source.exhausted:
        backend.run(source, started, deliver, stop or _never)
    if isinstance(source, RoundSchedule):
        source.finish()
    order = [TaskKey(entry, *round_) for entry in plan.entries for round_ in rounds]
    return [results[key] for key in order if key in results]


def cost_hints(
    problem: Problem,
    classifiers: Sequence[str],
    specs: Mapping[str, ClassifierSpec],
    folds: Sequence[Fold],
) -> dict[str, float]:
    """Predicted seconds of one fold of each classifier on this problem's shape
    (:func:`benchmark.catalogue.costs.estimate_seconds`); a multi-target configuration
    costs its base classifier once per target."""
    from touchbench.benchmark.multitarget import (
        parse_config,  # loads scikit-learn's meta-estimators
    )

    n_train = max(int(f.train.size) for f in folds)
    n_classes = max(problem.n_classes) if problem.kind != "regression" else 1
    hints = {}
    for classifier in dict.fromkeys(classifiers):
        base, n_models = classifier, 1
        if problem.kind != "regression" and is_multitarget_id(classifier):
            base = parse_config(classifier)[1] or "zeror"
            n_models = problem.n_targets
        spec = specs.get(base)
        if spec is None:
            try:
                spec = classifier_spec(base, specs)
            except ConfigurationError:  # a plugin or regressor id: the catalogue's guess
                hints[classifier] = 1.0
                continue
        shape = Shape(n_train, int(problem.X.shape[1]), n_classes, n_models)
        hints[classifier] = estimate_seconds(spec, shape)
    return hints


def check_limits(*, jobs: int, timeout: float | None, max_memory: int | None) -> None:
    """Refuse limits no run can have, naming the parameter.

    Raises
    ------
    ConfigurationError
        ``jobs`` below 1 (other than -1), ``timeout`` not a positive finite number of
        seconds, ``max_memory`` not a positive number of bytes up to :data:`MAX_MEMORY`.
    """
    if jobs != -1 and jobs < 1:
        raise ConfigurationError(f"jobs must be a positive number of processes or -1, got {jobs}")
    if timeout is not None and not (timeout > 0 and math.isfinite(timeout)):
        raise ConfigurationError(
            f"timeout must be a positive, finite number of seconds or None, got {timeout}"
        )
    if max_memory is not None and not 0 < max_memory <= MAX_MEMORY:
        raise ConfigurationError(
            f"max_memory must be a positive number of bytes up to 2**62, got {max_memory}"
        )


def plan_tasks(
    problem: Problem,
    classifiers: Sequence[str],
    folds: Sequence[Fold],
    *,
    skip: Collection[TaskKey] = (),
    extra_specs: Mapping[str, ClassifierSpec] | None = None,
    ensemble: int | None = None,
) -> tuple[dict[str, ClassifierSpec], list[TaskKey]]:
    """Check the classifier ids and list the tasks still to run.

    Returns
    -------
    specs : dict of str to ClassifierSpec
        The multi-class specs the workers need: the run's multi-class classifiers, the
        members of its ensembles and every extra spec.
    tasks : list of TaskKey
        Classifier-major, without the keys in ``skip``: the entries that are fitted (the
        run's, then the helpers; an ensemble of entries has no task).
    """
    plan, tasks = _plan(problem, classifiers, folds, set(skip), extra_specs, ensemble)
    return plan.specs, tasks


def _plan(
    problem: Problem,
    classifiers: Sequence[str],
    folds: Sequence[Fold],
    skip: Collection[TaskKey],
    extra_specs: Mapping[str, ClassifierSpec] | None,
    ensemble: int | None,
) -> tuple[RunPlan, list[TaskKey]]:
    plan = plan_run(problem, classifiers, extra_specs=extra_specs, ensemble=ensemble)
    if not folds:
        raise ConfigurationError("no folds to run the classifiers on")
    tasks = [
        key
        for classifier in plan.workers
        for fold in folds
        if (key := TaskKey(classifier, fold.repeat, fold.fold)) not in skip
    ]
    return plan, tasks


def available_cores() -> int:
    """CPU cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not Linux
        return os.cpu_count() or 1


def _ignore(key: TaskKey) -> None:
    return None


def _never() -> bool:
    return False


def _looks_out_of_memory(error: str | None) -> bool:
    text = error or ""
    return "MemoryError" in text or "SIGSEGV" in text or "SIGABRT" in text or "bad_alloc" in text
