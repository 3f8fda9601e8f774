"""Jobs other than runs (extraction of an uploaded recording session, training a model,
making a model's ONNX twin, the answers after a run: ablation, permutation importance, a
learning curve), as the API answers them."""

from __future__ import annotations

from datetime import datetime
from typing import Any, Literal

from pydantic import Field

from touchbench.app.schemas.ablation import AblationRequest
from touchbench.app.schemas.base import Request, Schema
from touchbench.app.schemas.extraction import ExtractRequest
from touchbench.app.schemas.importance import ImportanceRequest
from touchbench.app.schemas.learning import LearningCurveRequest
from touchbench.app.schemas.models import ExportRequest, TrainRequest
from touchbench.app.schemas.status import Status

JobKind = Literal["extract", "train", "export", "ablation", "importance", "learning-curve"]
#: The request each kind of job carries out (its JSON is the job's ``params``).
JOB_REQUESTS: dict[JobKind, type[Request]] = {
    "extract": ExtractRequest,
    "train": TrainRequest,
    "export": ExportRequest,
    "ablation": AblationRequest,
    "importance": ImportanceRequest,
    "learning-curve": LearningCurveRequest,
}

#: Params that are the service's own business: where an upload was saved, which host's
#: workers may take the job.
_SERVICE_ONLY = frozenset({"folder", "host"})


class JobSchema(Schema):
    id: int
    kind: JobKind
    status: Status  # a run's life without resume (app.store.states)
    params: dict[str, Any] = Field(
        description="What the job was asked to do: its request (TrainRequest, ExtractRequest)."
    )
    result: dict[str, Any] | None = Field(
        default=None,
        description="extract: the new data set; train: the new model; export: the model's "
        "new twin; ablation, importance, "
        "learning-curve: the answer (while running, what is finished so far, `complete` "
        "false).",
    )
    error: str | None = None
    created_at: datetime
    started_at: datetime | None = None
    finished_at: datetime | None = None

    def for_client(self) -> JobSchema:
        """The job as the API shows it: without the service's own folder of an upload (the
        client knows its files by their names) and the host whose workers may take it
        (the service's machine is not the client's business)."""
        params = {key: value for key, value in self.params.items() if key not in _SERVICE_ONLY}
        return self.model_copy(update={"params": params})


class JobList(Schema):
    jobs: list[JobSchema]


class JobCreated(Schema):
    """What a request that starts a job answers at once (status 202)."""

    job: int
    status: Status
    kind: JobKind
