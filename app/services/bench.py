"""A benchmark carried out at once by the process that asks (``touchbench bench``): a new run
or one to finish, each target on its own (``independent``), then the run's ablation.

A service's workers carry queued runs out instead (:mod:`app.services.runs`); the ablation
after a run is a job the store keeps, as one queued through the API would be
(:func:`app.services.jobs.carry_out_here`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from touchbench.app.errors import FieldError
from touchbench.app.schemas.ablation import AblationRequest, AblationResult
from touchbench.app.schemas.base import Schema
from touchbench.app.schemas.runs import BenchHereRequest
from touchbench.app.schemas.status import Status
from touchbench.app.services.ablation import check_grouping
from touchbench.app.services.jobs import carry_out_here
from touchbench.app.services.runs import (
    Callbacks,
    IndependentResult,
    create_run,
    execute_run,
    independent_runs,
)
from touchbench.app.store.database import Store
from touchbench.app.store.runs import RunInfo


class RunInterrupted(KeyboardInterrupt):
    """This process was interrupted (Ctrl-C, SIGTERM) while it carried the run out; the run
    is ``interrupted``, its finished tasks kept.  A KeyboardInterrupt still, raised from
    the interrupt itself (its ``__cause__``, which says how the process was stopped)."""

    def __init__(self, run_id: int) -> None:
        super().__init__(f"run {run_id} was interrupted")
        self.run_id = run_id


@dataclass(frozen=True)
class Benched:
    """What :func:`bench_here` carried out.

    Attributes
    ----------
    run : RunInfo or None
        The run, ended (``done`` or ``failed``); ``None`` for targets benchmarked each on
        its own.
    independent : IndependentResult or None
        Each target's run and best scores, for a request with ``independent``.
    ablation_job : int or None
        The job that keeps the run's ablation, when one was asked and the run did not fail.
    ablation : AblationResult or None
        That ablation's answer.
    """

    run: RunInfo | None = None
    independent: IndependentResult | None = None
    ablation_job: int | None = None
    ablation: AblationResult | None = None


def bench_here(
    store: Store,
    request: BenchHereRequest,
    *,
    jobs: int = 1,
    scheduler: str | None = None,
    callbacks: Callbacks | None = None,
    on_ablation: Callable[[Schema], None] = lambda partial: None,
) -> Benched:
    """Carry out a new run (checked and stored first) or the rest of a stored one, in this
    process; then its ablation, unless the run failed.

    Everything that can be refused is refused before the run exists: the request, the
    ablation's grouping against the data set's feature names.

    Parameters
    ----------
    jobs : int
        Local worker processes of the engine.
    scheduler : str, optional
        A Dask scheduler to run the tasks on.
    callbacks : Callbacks, optional
        Hear the run's progress; adjustments made when it is planned are notes.
    on_ablation : callable
        Hears the ablation's answer so far (an :class:`AblationResult`, ``complete``
        false) while it goes on.

    Raises
    ------
    FieldError, NotFoundError, ConfigurationError
        As :func:`app.services.runs.create_run` does; for ``ablate_groups``: a grouping the
        data set's features do not give.
    RunBusy
        Another live process executes the run.
    RunCancelled, RunInterrupted
        The run was cancelled or interrupted (its finished tasks are kept); an interrupt
        while the targets are benchmarked each on its own, or while the request is
        checked or the ablation carried out, is passed on as it came.
    """
    callbacks = callbacks or Callbacks()
    if request.ablate_groups is not None:
        try:
            check_grouping(store, request.ablate_groups, bench=request.bench, run=request.resume)
        except FieldError as error:
            raise FieldError("ablate_groups", error.message) from None
    if request.bench is not None and request.bench.independent:
        return Benched(
            independent=independent_runs(
                store, request.bench, jobs=jobs, scheduler=scheduler, callbacks=callbacks
            )
        )
    if request.bench is not None:
        run_id = create_run(store, request.bench, on_warning=callbacks.on_note).id
    else:
        assert request.resume is not None  # the request's rule: one of the two
        run_id = request.resume
    try:
        run = execute_run(store, run_id, jobs=jobs, scheduler=scheduler, callbacks=callbacks)
    except KeyboardInterrupt as interrupt:  # recorded: the run is interrupted
        raise RunInterrupted(run_id) from interrupt
    if request.ablate_groups is None or run.status == Status.FAILED:
        return Benched(run=run)
    ablation = AblationRequest(run=run.id, grouping=request.ablate_groups)
    job_id, result = carry_out_here(store, ablation, jobs=jobs, on_progress=on_ablation)
    return Benched(run=run, ablation_job=job_id, ablation=AblationResult.model_validate(result))
