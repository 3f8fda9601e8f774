"""Work under way on the service, as the client hands it back: a :class:`Run` or a
:class:`Job`, each its response model (``schema``) and what can be done with it, and the
wait for it to finish with a progress bar (tqdm: in Jupyter and in a terminal)."""

from __future__ import annotations

import time
from typing import TYPE_CHECKING, Any, Generic, Protocol, Self, TypeVar

from touchbench.app.python.errors import ServiceError, WaitTimeoutError
from touchbench.app.schemas.jobs import JobSchema
from touchbench.app.schemas.models import ModelSchema
from touchbench.app.schemas.runs import Aggregate, RunSchema
from touchbench.app.schemas.status import FINAL, Status

if TYPE_CHECKING:
    from touchbench.app.python.leaderboard import Leaderboard

#: Longest pause between two polls, in seconds (the first ones are shorter: quick work
#: is seen finished at once).
MAX_POLL = 1.0
_FIRST_POLL = 0.05

S = TypeVar("S", RunSchema, JobSchema)


class Service(Protocol):
    """What a run or a job asks of the client that made it (:class:`app.python.client.Client`,
    which imports this module)."""

    def run(self, run: int, /) -> Run: ...

    def job(self, job: int, /) -> Job: ...

    def cancel(self, run: int, /) -> Run: ...

    def cancel_job(self, job: int, /) -> Job: ...

    def model(self, model: str | int, /) -> ModelSchema: ...

    def leaderboard(
        self,
        run: int,
        /,
        *,
        metric: str | None = None,
        baseline: str | None = None,
        aggregate: Aggregate | None = None,
    ) -> Leaderboard: ...


class Work(Generic[S]):
    """A run or a job: its response model, refreshed from the service on request."""

    #: What the progress bar counts.
    unit = "task"

    def __init__(self, client: Service, schema: S) -> None:
        self._client = client
        self.schema: S = schema

    @property
    def id(self) -> int:
        return self.schema.id

    @property
    def status(self) -> Status:
        return self.schema.status

    @property
    def finished(self) -> bool:
        """Whether nothing more happens (done, failed, cancelled, interrupted)."""
        return self.schema.status in FINAL

    def refresh(self) -> Self:
        """Read the status and progress again (this object, updated)."""
        self.schema = self._read()
        return self

    def wait(self, *, progress: bool = True, timeout: float | None = None) -> Self:
        """Poll until it has finished, showing a progress bar.

        Interrupting the wait (Ctrl-C, the notebook's stop) stops waiting, not the work on
        the service: ``cancel()`` stops that.

        Raises
        ------
        WaitTimeoutError
            Still under way after ``timeout`` seconds.
        """
        from tqdm.auto import tqdm  # start-up time: only a wait shows a bar

        deadline = None if timeout is None else time.monotonic() + timeout
        pause = _FIRST_POLL
        label = f"{type(self).__name__.lower()} {self.id}"
        done, total = self._progress()
        with tqdm(
            total=total, initial=done, desc=label, unit=self.unit, disable=not progress
        ) as bar:
            while not self.finished:
                if deadline is not None and time.monotonic() >= deadline:
                    raise WaitTimeoutError(f"{label} is still {self.status} after {timeout:g} s")
                time.sleep(pause)
                pause = min(pause * 2, MAX_POLL)
                self.refresh()
                done, total = self._progress()
                bar.total = total
                bar.set_postfix_str(str(self.status), refresh=False)
                bar.update(done - bar.n)
                bar.refresh()
        return self

    def _read(self) -> S:
        raise NotImplementedError

    def _progress(self) -> tuple[int, int]:
        """Steps done and in all."""
        return (1, 1) if self.finished else (0, 1)


class Run(Work[RunSchema]):
    """A run on the service: its :class:`~app.schemas.runs.RunSchema` (``schema``)."""

    def leaderboard(
        self,
        *,
        metric: str | None = None,
        baseline: str | None = None,
        aggregate: Aggregate | None = None,
    ) -> Leaderboard:
        """The run's leaderboard (:meth:`Client.leaderboard`), re-scored per ``aggregate``
        when given."""
        return self._client.leaderboard(
            self.id, metric=metric, baseline=baseline, aggregate=aggregate
        )

    def cancel(self) -> Run:
        """Cancel the run (finished folds stay)."""
        self.schema = self._client.cancel(self.id).schema
        return self

    def _read(self) -> RunSchema:
        return self._client.run(self.id).schema

    def _progress(self) -> tuple[int, int]:
        return self.schema.tasks_done + self.schema.tasks_dropped, self.schema.tasks

    def __repr__(self) -> str:
        s = self.schema
        return (
            f"<Run {s.id} on {s.dataset} ({', '.join(s.targets)}): {s.status}, "
            f"{s.tasks_done}/{s.tasks} tasks>"
        )


class Job(Work[JobSchema]):
    """A job on the service (extraction, training, ...): its
    :class:`~app.schemas.jobs.JobSchema` (``schema``)."""

    unit = "job"

    @property
    def result(self) -> dict[str, Any] | None:
        """Once done: the new data set (extraction), the new model (training), the answer."""
        return self.schema.result

    def model(self) -> ModelSchema:
        """The model a finished training job made."""
        if self.schema.kind != "train":
            raise ServiceError(f"job {self.id} is a {self.schema.kind} job, not training")
        if self.schema.status != Status.DONE or not self.result:
            error = f": {self.schema.error}" if self.schema.error else ""
            raise ServiceError(f"job {self.id} is {self.schema.status}{error}")
        return self._client.model(int(self.result["model_id"]))

    def cancel(self) -> Job:
        """Cancel the job."""
        self.schema = self._client.cancel_job(self.id).schema
        return self

    def _read(self) -> JobSchema:
        return self._client.job(self.id).schema

    def __repr__(self) -> str:
        return f"<Job {self.id} ({self.schema.kind}): {self.schema.status}>"
