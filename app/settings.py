"""Settings of touchbench, from ``TOUCHBENCH_*`` environment variables."""

from __future__ import annotations

from functools import lru_cache

from pydantic_settings import BaseSettings, SettingsConfigDict

DEFAULT_DATABASE_URL = "sqlite:///touchbench.db"


class Settings(BaseSettings):
    """Every setting of the CLI and the service.

    Attributes
    ----------
    database_url : str
        SQLAlchemy URL of the store (``TOUCHBENCH_DATABASE_URL``); SQLite in the current
        directory by default.
    """

    model_config = SettingsConfigDict(env_prefix="TOUCHBENCH_", extra="ignore")

    database_url: str = DEFAULT_DATABASE_URL


@lru_cache(maxsize=1)
def get_settings() -> Settings:
    return Settings()
