"""Settings of touchbench, from ``TOUCHBENCH_*`` environment variables."""

from __future__ import annotations

import tempfile
from functools import lru_cache
from pathlib import Path

from pydantic import Field, SecretStr
from pydantic_settings import BaseSettings, SettingsConfigDict

from app.environment import DEFAULT_DATABASE_URL, ENV_PREFIX


class Settings(BaseSettings):
    """Every setting of the CLI and the service (``TOUCHBENCH_`` + the name, upper case).

    Attributes
    ----------
    database_url : str
        SQLAlchemy URL of the store; SQLite in the current directory by default.
    api_key : SecretStr or None
        When set, every request but ``GET /healthz`` and the OpenAPI document needs it in
        the ``X-API-Key`` header. Unset, the service listens on loopback only.
    max_upload_mb : float
        Largest upload (data set, recording session, file to predict), enforced while the
        body streams in.
    job_workers : int
        Jobs (runs, extractions, trainings) carried out at once on this host for the store,
        each in a worker process of its own (one service process dispatches them, however
        many ``touchbench serve --workers`` starts).
    run_jobs : int
        Engine worker processes per run.
    dask_scheduler : str or None
        ``tcp://host:port`` of a Dask scheduler: runs' tasks go there instead.
    resume_on_start : bool
        Put runs interrupted by a crash back in the queue when the service starts.
    work_dir : Path
        Where uploaded recording sessions wait for their extraction job.
    model_cache : int
        Loaded models kept in memory per service process for predictions.
    """

    model_config = SettingsConfigDict(env_prefix=ENV_PREFIX, extra="ignore")

    database_url: str = DEFAULT_DATABASE_URL
    api_key: SecretStr | None = None
    max_upload_mb: float = Field(default=200.0, gt=0)
    job_workers: int = Field(default=1, ge=1)
    run_jobs: int = Field(default=1, ge=1)
    dask_scheduler: str | None = None
    resume_on_start: bool = False
    work_dir: Path = Field(default_factory=lambda: Path(tempfile.gettempdir()) / "touchbench")
    model_cache: int = Field(default=8, ge=1)

    @property
    def max_upload_bytes(self) -> int:
        return int(self.max_upload_mb * 2**20)


@lru_cache(maxsize=1)
def get_settings() -> Settings:
    return Settings()
