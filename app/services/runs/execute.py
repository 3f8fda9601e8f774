"""A stored run carried out: claimed, its tasks without a result run by the engine while a
heartbeat tells other processes this one is alive (and hears a cancel), its final status
written.  The command line carries a run out at once, a service worker later.
"""

from __future__ import annotations

# Imports inside functions: start-up time: the job process and the API import this module;
# the engine (scikit-learn, Dask) loads when a run is carried out.
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from touchbench.app.errors import AppError
from touchbench.app.schemas.status import Status
from touchbench.app.services.runs.memory import task_memory
from touchbench.app.services.runs.problem import RunOptions, fold_plan, prepare_problem
from touchbench.app.services.runs.stopping import budget_left, race_rule
from touchbench.app.services.tuning import run_specs
from touchbench.app.store.database import Store
from touchbench.app.store.datasets import load_dataset
from touchbench.app.store.drops import forget_budget_cuts, record_drop
from touchbench.app.store.ownership import process_owner
from touchbench.app.store.predictions import attach_predictions, forget_inner_predictions
from touchbench.app.store.runs import (
    RunInfo,
    add_spent,
    claim_run,
    finish_run,
    finished_keys,
    get_run,
    load_results,
    record_result,
    run_heartbeat,
    update_config,
)
from touchbench.benchmark.errors import ConfigurationError
from touchbench.benchmark.results import Drop, TaskKey, TaskResult


@dataclass
class Callbacks:
    """What the caller hears while a run goes on (progress bars, logs)."""

    on_plan: Callable[[int, int], None] = lambda total, done: None
    on_start: Callable[[TaskKey], None] = lambda key: None
    on_result: Callable[[TaskResult], None] = lambda result: None
    on_warning: Callable[[str], None] = lambda message: None
    on_note: Callable[[str], None] = lambda message: None
    #: The run's end is recorded (a progress bar stops before what comes after the run).
    on_end: Callable[[RunInfo], None] = lambda run: None


class RunCancelled(Exception):  # noqa: N818 (an outcome, not an error)
    """The run was cancelled while it executed; its finished tasks are kept."""

    def __init__(self, run: RunInfo) -> None:
        super().__init__(f"run {run.id} was cancelled")
        self.run = run


def execute_run(
    store: Store,
    run_id: int | str,
    *,
    jobs: int = 1,
    scheduler: str | None = None,
    callbacks: Callbacks | None = None,
) -> RunInfo:
    """Carry out every task of a run that has no result yet, then record how it ended.

    The run is claimed first (another live process executing it is refused); a heartbeat
    thread tells other processes this one is alive and stops the engine when a cancel is
    requested.

    Returns
    -------
    RunInfo
        Status ``done``, or ``failed`` when every task failed.

    Raises
    ------
    RunCancelled
        A cancel request stopped the run (status ``cancelled``).
    KeyboardInterrupt
        Passed on after the run is marked ``interrupted``.
    AppError
        Another process executes the run.
    """
    callbacks = callbacks or Callbacks()
    run = get_run(store, run_id)
    if run.status == Status.DONE and run.n_results >= run.n_tasks:
        callbacks.on_end(run)
        return run
    owner = process_owner()
    run = claim_run(store, run.id, owner=owner)
    stop = threading.Event()
    beat = run_heartbeat(store, run.id, owner, stop.set)
    try:
        options = RunOptions.from_config(run.config)
        prepared = prepare_problem(
            load_dataset(store, run.dataset_id),
            run.config.targets_given,
            run.config.position or (),
        )
        folds = fold_plan(prepared, options).folds
        race = race_rule(run)
        extra_specs = run_specs(run.config, run.classifiers)
        # a race replays its decisions from the stored scores, and the ensembles computed
        # from fold predictions read their members' stored ones; a plain run needs the keys
        computes = bool(run.config.origins) or run.config.ensemble is not None
        previous = load_results(store, run.id) if race is not None or computes else []
        if computes:
            attach_predictions(store, run.id, previous)
        done = {r.key for r in previous} if previous else finished_keys(store, run.id)
        # tasks in all and done, for the caller's progress: a drop takes its entry's later
        # folds off the total
        counts = [(len(run.classifiers) + len(run.config.helpers)) * len(folds), len(done)]
        callbacks.on_plan(*counts)
        forget_budget_cuts(store, run.id)
        budget = budget_left(run)
        max_memory, memory_from = task_memory(
            options.max_memory_mb,
            jobs=jobs,
            scheduler=scheduler,
            data_bytes=int(prepared.problem.X.nbytes),
        )
        update_config(
            store,
            run.id,
            task_memory_mb=None if max_memory is None else round(max_memory / 2**20),
            task_memory_from=memory_from,
        )

        def persist(result: TaskResult) -> None:
            record_result(store, run.id, result)
            counts[1] += 1
            callbacks.on_result(result)

        def dropped(drop: Drop) -> None:
            record_drop(store, run.id, drop)
            counts[0] -= len(folds) - drop.after_fold
            callbacks.on_plan(*counts)
            callbacks.on_note(f"{drop.classifier}: {drop.describe()}")

        from touchbench.benchmark.run.engine import RunStopped, run_tasks

        beat.start()
        began = time.monotonic()
        try:
            run_tasks(
                prepared.problem,
                run.classifiers,
                folds,
                jobs=jobs,
                scheduler=scheduler,
                timeout=options.timeout,
                random_state=options.seed,
                skip=done,
                on_start=callbacks.on_start,
                on_result=persist,
                max_memory=max_memory,
                stop=stop.is_set,
                extra_specs=extra_specs,
                race=race,
                budget=budget,
                previous=previous,
                on_drop=dropped,
                by_recording=run.config.by_recording,
                ensemble=run.config.ensemble,
            )
        except RunStopped:
            finish_run(store, run.id, Status.CANCELLED)
            raise RunCancelled(get_run(store, run.id)) from None
        finally:
            add_spent(store, run.id, time.monotonic() - began)
    except (KeyboardInterrupt, SystemExit):
        finish_run(store, run.id, Status.INTERRUPTED)
        raise
    except RunCancelled:
        raise
    except (ConfigurationError, AppError) as error:
        finish_run(store, run.id, Status.FAILED, error=str(error))
        raise
    except BaseException as error:
        finish_run(store, run.id, Status.INTERRUPTED, error=f"{type(error).__name__}: {error}")
        raise
    finally:
        beat.stop()
    status, error_text = _outcome(load_results(store, run.id))
    finish_run(store, run.id, status, error=error_text)
    forget_inner_predictions(store, run.id)  # every fold ran: nothing left reads them
    ended = get_run(store, run.id)
    callbacks.on_end(ended)
    return ended


def _outcome(results: Sequence[TaskResult]) -> tuple[Status, str | None]:
    """``done``, or ``failed`` with a one-line reason when no task succeeded."""
    if any(result.ok for result in results):
        return Status.DONE, None
    if not results:
        return Status.FAILED, "no task was carried out"
    reasons: dict[str, int] = {}
    for result in results:
        reason = (result.error or result.status).split(" (at ", 1)[0]
        reasons[reason] = reasons.get(reason, 0) + 1
    common = max(reasons, key=lambda reason: reasons[reason])
    return Status.FAILED, (
        f"all {len(results)} tasks failed; most often ({reasons[common]}x): {common}"
    )
