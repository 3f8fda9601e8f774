"""Every setting of touchbench, each an environment variable ``TOUCHBENCH_`` + its name:
where it is declared, with its default and its help.

The CLI, the service and its processes receive their settings from :class:`Settings`.
Two readers stand beside it, each for a reason and each held equal to it by a test:
:mod:`app.environment` reads the store's URL and the debug switch for the CLI without
pydantic-settings (start-up time), and :mod:`benchmark.catalogue.plugins` reads
``TOUCHBENCH_PLUGINS`` where the catalogue is built, in every process that runs
classifiers (``benchmark`` knows nothing of ``app``).  The keys, host names and origins
are read by :mod:`app.trust`, whose rules the trust boundary applies.
"""

from __future__ import annotations

import tempfile
from collections.abc import Callable
from functools import cached_property, lru_cache
from pathlib import Path
from typing import Any, TypeVar

from pydantic import Field, SecretStr, ValidationError, field_validator
from pydantic_settings import BaseSettings, SettingsConfigDict

from touchbench.app.environment import DEFAULT_DATABASE_URL, ENV_PREFIX, FALSE_WORDS
from touchbench.app.errors import AppError
from touchbench.app.trust import (
    ApiKey,
    Role,
    TrustSettingError,
    read_hosts,
    read_keys,
    read_origins,
)
from touchbench.drivers.limits import CELLS, GAP_SAMPLES

__all__ = ["ApiKey", "Role", "Settings", "SettingsError", "get_settings", "variable"]


class SettingsError(AppError):
    """A setting that touchbench cannot work with (one line naming the variable)."""


class Settings(BaseSettings):
    """Every setting of the CLI and the service.

    Each field is read from the environment variable ``TOUCHBENCH_`` + its name in upper
    case (any case matches); its description is its help.
    """

    model_config = SettingsConfigDict(env_prefix=ENV_PREFIX, extra="ignore")

    database_url: str = Field(
        default=DEFAULT_DATABASE_URL,
        description="SQLAlchemy URL of the store (the CLI's --db overrides it); SQLite in "
        "the current directory by default.",
    )
    debug: bool = Field(
        default=False,
        description="Print the traceback of an unexpected error of the CLI.",
    )
    plugins: str = Field(
        default="",
        description="Modules (comma-separated) whose CLASSIFIERS join the catalogue in every "
        "run, listing and service (see benchmark.catalogue.plugins).",
    )
    api_key: SecretStr | None = Field(
        default=None,
        description="A write key named 'default'.  With any key, every request but "
        "GET /healthz and the OpenAPI document needs one in the X-API-Key header; without "
        "any, the service listens on loopback only.  At least 16 characters.",
    )
    api_keys: SecretStr | None = Field(
        default=None,
        description="More keys with names and roles: name:role:key entries separated by "
        "commas, or the path of a file readable by its owner alone with one 'name role key' "
        "a line ('#' starts a comment).  Roles: read, predict, write.",
    )
    allowed_hosts: str = Field(
        default="",
        description="Host names or addresses (comma-separated) the service answers besides "
        "the loopback ones; the Host header of every request must name one.  Required when "
        "the service listens beyond loopback.",
    )
    allowed_origins: str = Field(
        default="",
        description="Web origins (scheme://host:port, comma-separated) whose pages may "
        "change the store and call the API from a browser (CORS); the service's own origin "
        "always may.",
    )
    max_upload_mb: float = Field(
        default=200.0,
        gt=0,
        description="Largest upload (data set, recording session, file to predict), "
        "enforced while the body streams in.",
    )
    max_targets: int = Field(
        default=1000,
        ge=1,
        description="Most targets a data set may have, at import, upload and extraction "
        "(MEKA's largest benchmark data sets have fewer than the default).",
    )
    max_attributes: int = Field(
        default=20000,
        ge=2,
        description="Most attributes (targets and features) a data set may have; a sequence "
        "among them counts as its channels.",
    )
    max_cells: int = Field(
        default=CELLS,
        ge=1000,
        description="Most values a data set (instances x attributes) or one recording "
        "(samples x channels, as read, resampled or padded) may hold.",
    )
    max_gap_samples: int = Field(
        default=GAP_SAMPLES,
        ge=1,
        description="Most samples resampling may put between two consecutive time stamps.",
    )
    max_label_rows: int = Field(default=100_000, ge=1, description="Most rows of a labels file.")
    max_json_mb: float = Field(
        default=16.0,
        gt=0,
        description="Largest JSON body, enforced while it streams in.",
    )
    job_workers: int = Field(
        default=1,
        ge=1,
        description="Jobs (runs, extractions, trainings) carried out at once on this host "
        "for the store, each in a worker process of its own (one service process dispatches "
        "them, however many `touchbench serve --workers` starts).",
    )
    run_jobs: int = Field(default=1, ge=1, description="Engine worker processes per run.")
    job_nice: int = Field(
        default=10,
        ge=0,
        le=19,
        description="How much lower than the service's the CPU priority of a job's worker "
        "process is (its niceness raised by this much; its engine processes inherit it), so "
        "that heavy runs and jobs do not starve the service's predictions; 0: the same.",
    )
    dask_scheduler: str | None = Field(
        default=None,
        description="tcp://host:port of a Dask scheduler: runs' tasks go there instead.",
    )
    predictions_only: bool = Field(
        default=False,
        description="Serve predictions only (models listed and described, predictions over "
        "REST and the live WebSocket, /healthz), beside a full service on the same store: "
        "no other route, no web page, no jobs dispatched, so that clients managing the store "
        "do not share a process with the robots' predictions.",
    )
    resume_on_start: bool = Field(
        default=False,
        description="Put runs interrupted by a crash back in the queue when the service starts.",
    )
    warm_up: bool = Field(
        default=True,
        description="Import the machine-learning stack in the background at start-up, so "
        "that the first prediction does not wait for it.",
    )
    work_dir: Path = Field(
        default_factory=lambda: Path(tempfile.gettempdir()) / "touchbench",
        description="Where uploaded recording sessions wait for their extraction job.",
    )
    model_cache: int = Field(
        default=8,
        ge=1,
        description="Loaded models kept in memory per service process for predictions.",
    )
    ranking_cache: int = Field(
        default=8,
        ge=1,
        description="Run leaderboards kept ranked in memory per service process for the web "
        "page (each version of a run's results is ranked once).",
    )
    live_follow_seconds: float = Field(
        default=1.0,
        ge=0,
        le=3600,
        description="How often a live WebSocket session on NAME@ALIAS (or NAME) asks the "
        "store which version its reference names now (one indexed query); 0: before every "
        "block.",
    )
    live_source_seconds: float = Field(
        default=600.0,
        gt=0,
        le=86400,
        description="Longest source the service reads itself for a live session (the live "
        "view's): a recording uploaded for replay, a simulated sensor's take.",
    )
    live_sources: int = Field(
        default=4,
        ge=1,
        description="Live sessions per service process reading a source of the service's at "
        "once (one source per connection).",
    )
    live_replays: int = Field(
        default=20,
        ge=1,
        description="Recordings uploaded for replay that are kept (the oldest go first).",
    )

    @field_validator("debug", mode="before")
    @classmethod
    def _unset_when_empty(cls, value: Any) -> Any:
        """``TOUCHBENCH_DEBUG=`` (empty) and the words of false are off, as the CLI reads
        them (:func:`app.environment.debug`)."""
        if isinstance(value, str) and value.lower() in FALSE_WORDS:
            return False
        return value

    @property
    def max_upload_bytes(self) -> int:
        return int(self.max_upload_mb * 2**20)

    @property
    def max_json_bytes(self) -> int:
        return int(self.max_json_mb * 2**20)

    @cached_property
    def keyring(self) -> tuple[ApiKey, ...]:
        """Every key the service knows (none: the service needs no key).

        Raises
        ------
        SettingsError
            See :func:`app.trust.read_keys`.
        """
        return _trusted(
            read_keys,
            None if self.api_key is None else self.api_key.get_secret_value(),
            None if self.api_keys is None else self.api_keys.get_secret_value(),
        )

    @cached_property
    def hosts(self) -> frozenset[str]:
        """The host names the service answers (:func:`app.trust.read_hosts`)."""
        return _trusted(read_hosts, self.allowed_hosts)

    @cached_property
    def origins(self) -> frozenset[str]:
        """The other origins that may change the store (:func:`app.trust.read_origins`)."""
        return _trusted(read_origins, self.allowed_origins)

    def check_trust(self) -> None:
        """Read the keys, hosts and origins once, so that a bad one stops the service
        before it starts.

        Raises
        ------
        SettingsError
            One of them cannot be used (see :attr:`keyring`, :attr:`hosts`,
            :attr:`origins`).
        """
        self.keyring  # noqa: B018
        self.hosts  # noqa: B018
        self.origins  # noqa: B018


def variable(field: str) -> str:
    """The environment variable of the setting ``field``: ``TOUCHBENCH_DATABASE_URL``."""
    return f"{ENV_PREFIX}{field.upper()}"


_Read = TypeVar("_Read")


def _trusted(read: Callable[..., _Read], *values: str | None) -> _Read:
    """What ``read`` makes of ``values``; its refusal as a :class:`SettingsError`."""
    try:
        return read(*values)
    except TrustSettingError as error:
        raise SettingsError(str(error)) from None


@lru_cache(maxsize=1)
def get_settings() -> Settings:
    """The settings of the environment, read once per process.

    Raises
    ------
    SettingsError
        A variable holds a value its setting refuses (naming the variable).
    """
    try:
        return Settings()
    except ValidationError as error:
        problem = error.errors()[0]
        field = str(problem["loc"][0]) if problem.get("loc") else "?"
        raise SettingsError(f"{variable(field)}: {problem['msg']}") from None
